"""cablesim's out-of-plane bifurcations against the independent reference (``helpers_whirl.py``,
``helpers_whirl_cases.py``: its own lumped model, shooting and Hill monodromy, written without
cablesim's code) and against the damped Mathieu closed form of a taut string.

- The whirling pitchfork of one mass on two segments (:data:`helpers_whirl_cases.WHIRL_CASE`):
  located in omega to 1e-6, and the nonplanar branch born there against the reference's own
  nonplanar orbits (full spatial shooting) and the normal form's square-root law.
- The parametric tongue of a taut stay excited along its chord at its anchorage: the threshold
  amplitude and the tongue's edges against the reference to 1e-6, and against the closed form to
  within its neglected terms, which the tests state: O(eps^2) w1 in the edges (eps the relative
  tension modulation), O(strain) and O(zeta^3) in the threshold, and the lumping's O(1/n^2) in
  the natural frequency (lumped ``2 sqrt(T/(m h)) sin(pi/(2(n+1)))`` against ``pi sqrt(T/mu)/L``).
"""

from __future__ import annotations

import math

import numpy as np
import yaml
from scipy.optimize import brentq

from cablesim.analyses.continuation import run_continuation
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict
from cablesim.orbits import continue_branches
from helpers_whirl import cable_from_case
from helpers_whirl_cases import (
    STAY_CASE,
    PlanarBranch,
    pitchfork_omega,
    stay_case,
    stay_mathieu,
    tongue_edges,
    whirl_case,
    whirling_orbit,
)


def stay_continuation(nodes: int, **continuation):
    data = yaml.safe_load(STAY_CASE.format(nodes=nodes, omega=12.0))
    data["continuation"] = {"switch_branches": False, **continuation}
    return run_continuation(case_from_dict(data))


def out_of_plane_doublings(result):
    found = [b for b in result.bifurcations if b.kind == "period-doubling" and b.plane == "out-of-plane"]
    assert all(b.located for b in found)
    return sorted(b.parameter for b in found)


def test_whirling_pitchfork_and_its_branch_against_the_reference():
    """The out-of-plane multiplier of the planar response passes +1 where the reference's does
    (to 1e-6 rad/s; measured 8e-10), and the nonplanar branch cablesim switches onto there is the
    reference's: at the frequencies of two of the reference's nonplanar orbits (branch parameter
    h = 0.01 and 0.005 m), max|w| interpolated along cablesim's branch agrees to 1e-3, and so does
    the square-root law's coefficient max|w|^2 / (omega - omega_c)."""
    case = whirl_case()
    ref = pitchfork_omega(case)
    eom = build_equations(case, run_static(case), omega=4.5)
    diagram = continue_branches(eom, "omega", 4.5, 4.7)
    pitchforks = [b for b in diagram.bifurcations if b.kind == "pitchfork"]
    assert len(pitchforks) == 1 and pitchforks[0].plane == "out-of-plane"
    pf = pitchforks[0]
    assert abs(pf.parameter - ref.value) < 1e-6, (pf.parameter, ref.value)
    whirl = diagram.branches[pf.child]
    assert whirl.mirror_image and not whirl.planar
    omega = np.array([p.parameter for p in whirl.points])
    w2 = np.array([p.amplitude[2] ** 2 for p in whirl.points])  # node 1's w, m
    assert np.all(np.diff(omega[:6]) > 0)  # it leaves on the side where the planar orbit is unstable
    for h in (0.01, 0.005):
        orbit = whirling_orbit(case, ref, h)
        here = math.sqrt(np.interp(orbit.value, omega[:6], w2[:6]))
        assert abs(here / orbit.max_w - 1) < 1e-3, (h, here, orbit.max_w)
        c_ref = orbit.max_w**2 / (orbit.value - ref.value)
        c = np.interp(orbit.value, omega[1:6], w2[1:6] / (omega[1:6] - pf.parameter))
        assert abs(c / c_ref - 1) < 1e-3, (c, c_ref)


def test_parametric_threshold_of_a_stay_against_the_reference_and_mathieu():
    """One node of a taut stay whose anchorage moves along the chord, forced at twice its first
    transverse frequency: continued in the amplitude's multiplier gamma, the planar response loses
    stability out of its plane (multiplier -1) at the reference's gamma to 1e-6 (measured 2e-13),
    and at the Mathieu closed form's ``4 zeta sqrt(1 - zeta^2) / eps_per_gamma`` to within its
    neglected terms: O(strain) (1.5e-3 here, the change of T/l with the chord) and O(zeta^3).
    Without sag the in-plane transverse mode has the same frequency and its tongue too: an
    in-plane period doubling at the same gamma."""
    case = stay_case(1)
    cf = stay_mathieu(case)
    omega, gc = 2 * cf.w1, cf.threshold_gamma()
    result = stay_continuation(1, parameter="gamma", omega=omega, gamma={"start": 0.5 * gc, "stop": 2 * gc})
    (found,) = out_of_plane_doublings(result)
    branch = PlanarBranch(cable_from_case(case))
    ref = brentq(lambda g: abs(branch.out_of_plane(omega, g)[0]) - 1.0, 0.5 * gc, 2 * gc, xtol=1e-12)
    assert abs(found - ref) < 1e-6, (found, ref)
    strain = 1 - 99.85 / 100.0  # of the stay at rest: natural length 99.85 m, chord 100 m (STAY_CASE)
    assert abs(found / gc - 1) < 2 * strain + 10 * cf.zeta**3, (found, gc)
    in_plane = [b.parameter for b in result.bifurcations if b.kind == "period-doubling" and b.plane == "in-plane"]
    assert len(in_plane) == 1 and abs(in_plane[0] - found) < 1e-6


def test_tongue_edges_of_a_stay_against_the_reference_and_mathieu():
    """Three nodes: the edges of the tongue in omega (at the case's 5 mm anchorage amplitude)
    against the reference to 1e-6 rad/s (measured 2e-11) and against the lumped closed form to
    within its O(eps^2) w1 (eps = 0.033, about eps^2/32 * 2 w1 = 4e-4 rad/s: bound 1e-4 of 2 w1);
    the lumped frequency itself is the continuous string's to O(1/(n+1)^2) (here 0.3 %, the
    ``pi^2 / (24 (n+1)^2)`` of the sine's expansion)."""
    case = stay_case(3)
    cf = stay_mathieu(case)
    lo, hi = cf.edges()
    result = stay_continuation(3, omega={"start": lo - 0.3 * (hi - lo), "stop": hi + 0.3 * (hi - lo)})
    edges = out_of_plane_doublings(result)
    ref = tongue_edges(case)
    assert len(edges) == 2
    for found, located, closed in zip(edges, (ref.lower, ref.upper), (lo, hi)):
        assert abs(found - located.value) < 1e-6, (found, located.value)
        assert abs(found - closed) < 1e-4 * 2 * cf.w1, (found, closed)
    lumping = 1 - cf.w1 / cf.w1_continuous
    assert abs(lumping / (math.pi**2 / (24 * (cf.n + 1) ** 2)) - 1) < 0.01
