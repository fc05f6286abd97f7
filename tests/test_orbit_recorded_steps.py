"""Measures of a continuation's orbits taken on the steps of the flow that converged.

The strain check and the whirling measures of every orbit used to integrate it once more
without the variational equations; the dense shooting now records the orbit at its steps while
it integrates them. The claim that makes this exact: the state's arithmetic in the flow kernel
does not depend on whether the variational equations are carried, so the recorded steps are the
steps of a separate integration bit for bit, and so are the measures taken on them. Checked
here against that separate integration (:meth:`Shooting.steps`, no variational equations), and
the strains against the node positions' segment lengths written out in the test.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablesim import api
from cablesim.analyses.continuation import prepare_continuation, trace
from cablesim.analyses.orbit_strain import orbit_strains
from cablesim.orbits import Shooting, cable_system, linear_response_state, solve_orbit
from cablesim.orbits.symmetry import orbit_whirling

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"


def _case(spatial: bool, start: float, stop: float):
    over = [f"continuation={{omega: {{start: {start}, stop: {stop}}}, channels: [node1.v, node2.v], max_points: 40}}"]
    return api.load_case(CONFIG, overrides=over + (["spatial=true"] if spatial else []))


@pytest.mark.parametrize("spatial", [False, True])
def test_recorded_steps_are_the_flow_without_variational_equations(spatial):
    start = prepare_continuation(_case(spatial, 2.0, 2.4))
    eom = start.eom
    system = cable_system(eom)
    sh = Shooting(system, period=1, segments=2, parameter="omega")
    u0 = linear_response_state(eom, 2.2, 1.0, 1.0)
    sol = solve_orbit(sh, u0, 2.2)
    assert sol.converged
    # a start slightly off the orbit, out of the plane too for the spatial cable
    u = sol.u + 1e-4 * np.abs(sol.u).max() * np.cos(np.arange(sol.u.size))
    ev = sh.evaluate(u, 2.2, record=True)
    again = sh.steps(u, 2.2)
    assert ev.steps is not None and len(ev.steps) == 2
    for (t, rec), (t2, rec2) in zip(ev.steps, again):
        assert np.array_equal(t, t2) and np.array_equal(rec, rec2)
    assert np.array_equal(ev.steps[0][1][-1, : system.dim], ev.ends[0])  # the segment's end state
    assert sh.evaluate(u, 2.2).steps is None


def test_strains_of_the_traced_orbits_are_those_of_a_new_integration():
    start = prepare_continuation(_case(True, 4.8, 5.3))
    eom, spec = start.eom, start.spec
    diagram = trace(start, None, switch_branches=False)
    br = diagram.branches[0]
    assert len(br.points) > 10 and all(p.measure is not None for p in br.points)
    taken = orbit_strains(eom, br, spec.parameter, spec.fixed_gamma, spec.fixed_support)
    for p in br.points:
        p.measure = None
    anew = orbit_strains(eom, br, spec.parameter, spec.fixed_gamma, spec.fixed_support)
    assert np.array_equal(taken, anew)
    # the strain written out: segment lengths between the supports and the nodes over the steps
    cable, nd = eom.cable, eom.n_dof
    sh = Shooting(cable_system(eom), period=br.period, segments=br.points[0].u.size // (2 * nd))
    for k in (0, len(br.points) // 2, len(br.points) - 1):
        p = br.points[k]
        y = eom.y0 + np.concatenate([rec[:, :nd] for _, rec in sh.steps(p.u, p.parameter)])
        pts = y.reshape(len(y), -1, 3)
        A = np.broadcast_to(cable.support_A, (len(y), 1, 3))
        B = np.broadcast_to(cable.support_B, (len(y), 1, 3))
        chain = np.concatenate([A, pts, B], axis=1)
        lengths = np.sqrt(((chain[:, 1:] - chain[:, :-1]) ** 2).sum(axis=2))
        assert taken[k] == pytest.approx(float(np.max(lengths / np.asarray(cable.S) - 1.0)), rel=1e-12, abs=1e-15)


def test_whirling_from_recorded_steps_is_that_of_a_new_integration():
    start = prepare_continuation(_case(True, 2.0, 2.4))
    eom = start.eom
    system = cable_system(eom)
    sh = Shooting(system, period=1, segments=1, parameter="omega")
    u = linear_response_state(eom, 2.2, 1.0, 1.0)
    u = u + 1e-3 * np.abs(u).max() * np.sin(np.arange(u.size) + 0.3)  # off the plane
    ev = sh.evaluate(u, 2.2, record=True)
    a = orbit_whirling(system.frame, sh, u, 2.2, 64, steps=ev.steps)
    b = orbit_whirling(system.frame, sh, u, 2.2, 64)
    assert np.abs(b.max_w).max() > 0
    assert np.array_equal(a.area, b.area) and a.tilt == b.tilt and np.array_equal(a.max_w, b.max_w)
