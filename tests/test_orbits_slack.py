"""Periodic orbits through slack (the dense shooting, :mod:`cablesim.orbits.slackflow`) against
an independent event-driven shooting written here: scipy's DOP853 (rtol 1e-12) on the
second-order equations with own geometry and tension-only segments by modes, the gaps as
terminal events, restarted in the new modes at each event; Newton's method on its period map
with a central finite-difference monodromy across the events.

The orbit: the paper's cable with the harmonic load scaled by 13.5 at 2.45 rad/s. Its slack
pattern: segment 3 (support B's) goes slack once a period, from 1.777 s to 1.834 s of the
2.565 s period (phase 0 at the forcing's zero crossing); segments 1 and 2 stay taut.
"""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.orbits.shooting import Shooting, solve_orbit
from cablesim.orbits.slackpattern import slack_pattern
from cablesim.orbits.systems import cable_system

from helpers_slack import Reference

OMEGA, SCALE = 2.45, 13.5
#: A state near the orbit (displacements from the equilibrium, m, and velocities, m/s, at phase 0,
#: to 3 digits, from a time history after 60 periods): the start of both Newton iterations.
START = np.array([-4.334, 7.088, -2.68, -3.665, -18.247, 26.177, -14.215, -21.179])


# ----------------------------------------------------------------------------------------------
# The orbits, once per module
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def snap_eom(paper, exact_static):
    return build_equations(paper, exact_static, omega=OMEGA, load_scale=SCALE)


@pytest.fixture(scope="module")
def snap_orbit(snap_eom):
    sh = Shooting(cable_system(snap_eom), through_slack=True)
    sol = solve_orbit(sh, START)
    assert sol.converged, sol.status
    return sh, sol


@pytest.fixture(scope="module")
def reference_orbit(snap_eom):
    ref = Reference(snap_eom)
    x, Mo = ref.orbit(START.copy())
    return ref, x, Mo


def _matched(a, b):
    """Largest distance from each of ``a`` to the nearest of ``b`` (and back)."""
    d = np.abs(a[:, None] - b[None, :])
    return max(d.min(axis=1).max(), d.min(axis=0).max())


# ----------------------------------------------------------------------------------------------
# Tests
# ----------------------------------------------------------------------------------------------
def test_orbit_through_slack_agrees_with_an_event_driven_shooting(snap_orbit, reference_orbit):
    sh, sol = snap_orbit
    ref, x_ref, M_ref = reference_orbit
    ev = sol.evaluation
    nd = ref.nd
    # the slack pattern: segment 3 slack once a period, the others taut throughout
    _, events = ref.flow(x_ref)
    assert [(k, m) for _, k, m in events] == [(2, 0.0), (2, 1.0)]
    assert ev.events[:, 1:].tolist() == [[2.0, 0.0], [2.0, 1.0]]
    assert np.abs(ev.events[:, 0] - [t for t, _, _ in events]).max() < 1e-8  # s
    # the state to 1e-7 of each half's largest component (m, m/s)
    for part in (slice(0, nd), slice(nd, 2 * nd)):
        assert np.abs(sol.u[part] - x_ref[part]).max() < 1e-7 * np.abs(x_ref[part]).max()
    # the multipliers to 1e-5; Liouville's formula det = exp(-tr(M^-1 C) T) holds through the
    # kinks for both (the saltation matrices are the identity): the reference's to its finite
    # differences, cablesim's to the rk8 error on the axial modes it has without slack (1.6e-5)
    assert _matched(ev.multipliers, np.linalg.eigvals(M_ref)) < 1e-5
    assert abs(np.log(abs(np.linalg.det(M_ref))) - ev.divergence) < 5e-5
    assert ev.liouville < 5e-5


def test_monodromy_through_slack_is_the_derivative_of_the_flow_map(snap_orbit):
    """The product of the smooth pieces' variational flows (saltation = identity) against
    central differences of cablesim's own period map, whose events move with the state."""
    sh, sol = snap_orbit
    u = sol.u
    n = u.size
    nd = n // 2
    scale = np.concatenate([np.full(nd, np.abs(u[:nd]).max()), np.full(nd, np.abs(u[nd:]).max())])
    fd = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-6 * scale[i]
        plus, minus = sh.evaluate(u + e, sh.default_lam(), jac=False), sh.evaluate(u - e, sh.default_lam(), jac=False)
        assert plus.events.shape == minus.events.shape == (2, 3)
        fd[:, i] = (plus.ends[0] - minus.ends[0]) / (2.0 * e[i])
    mono = sol.evaluation.monodromy
    # relative to the largest entry of each block row (displacements, velocities) and column
    w = scale[:, None] / scale[None, :]
    assert np.abs((mono - fd) / w).max() < 1e-6 * np.abs(mono / w).max()


def test_slack_intervals_and_snap_loads_of_the_orbit(snap_orbit, reference_orbit):
    sh, sol = snap_orbit
    ref, x_ref, _ = reference_orbit
    pat = slack_pattern(sh, sol.u, sh.default_lam(), sol.evaluation)
    peaks = np.zeros(3)
    _, events = ref.flow(x_ref, peaks=peaks)
    assert pat.episodes.tolist() == [0, 0, 1]
    assert np.abs(pat.intervals[2] - [[events[0][0], events[1][0]]]).max() < 1e-8  # s
    assert np.abs(pat.peak_tension - peaks).max() < 1e-7 * peaks.max()  # N


def test_flow_without_slack_is_the_plain_kernels_bit_for_bit(forced_eom):
    """Where no segment goes slack the kernel with modes takes the plain kernel's steps: the
    same end state, Jacobian and extremes to the bit (a taut orbit of the paper's cable)."""
    from cablesim.orbits import kernels as ok
    from cablesim.orbits import slackflow as sf

    sh = Shooting(cable_system(forced_eom))
    system = sh.system
    x0 = np.array([0.01, -0.02, 0.005, 0.03, 0.0, 0.01, -0.02, 0.0])
    outs = []
    for kernel in ("plain", "modes"):
        n = x0.size
        ns = sh.segment_steps(sh.default_lam())
        res = [np.empty(n), np.empty((n, n)), np.zeros(n), np.empty(n), np.empty(n), np.empty((ns + 1, 2 * n)),
               np.zeros(4)]
        args = (system.model, system.prm, ok.copy_work(system.work), x0, 0.0, sh.default_lam(),
                2 * np.pi / sh.default_lam(), ns, sh.tableau.A, sh.tableau.b, sh.tableau.c, -1, ok.PARAM_OMEGA, True,
                np.arange(n), np.array([0, n]), *res)
        if kernel == "plain":
            code = ok.EntryPoint(ok.flow_segment)(system.field, *args)
        else:
            ev, nev = np.zeros((64 * 3, 3)), np.zeros(1, dtype=np.int64)
            code = ok.EntryPoint(sf.flow_segment_modes)(system.field, *system.slack, *args, ev, nev)
            assert nev[0] == 0
        assert code == ok.OK
        outs.append(res)
    for a, b in zip(*outs):
        assert np.array_equal(a, b)


def test_approximate_analysis_still_stops_where_a_segment_goes_slack(paper, approx_static):
    """Only the exact analysis' dense shooting follows slack segments; the approximate
    analysis has no state with a slack segment (x(P) undetermined) and stops there as before."""
    from cablesim.orbits.shooting import FlowStatus

    eom = build_equations(paper, approx_static, omega=OMEGA, load_scale=SCALE)
    system = cable_system(eom)
    assert system.slack is None
    ev = Shooting(system).evaluate(START, OMEGA, jac=False)
    # (from this far out the inner solve of x(P) may fail first: the same stop, named so)
    assert ev.status in (FlowStatus.SLACK, FlowStatus.INNER_SOLVE) and ev.events.size == 0
