"""Branch switching at period doublings when the fixed-size perturbation is out of reach.

The state scale of the orbit problem is a property of the case (for a cable, the linear
response at its primary resonance); a period-doubled orbit born far from that resonance can be
much smaller. A perturbation of ``switch_size`` times the scale then leaves the region where the
flow can be evaluated (a stiff cable goes slack), and the switch must shrink it.

References (independent of the orbit code under test):

1. Mathieu-Duffing oscillator ``x'' + c x' + (1 + eps cos(w t)) x + alpha x^3 = 0`` whose field
   refuses states with ``|x| > 1.2`` (as a cable refuses a slack segment), traced with a state
   scale of 100: the period-2 branches at both edges of the instability tongue are still
   started, and their orbits return to themselves over two forcing periods under scipy's DOP853
   (and not over one).
2. The stiff cable of ``configs/paper/fig8a.yaml`` (EA = 1e12 N) near ``2 w1``: the period-2
   branch between the period-doubling pair passes through the brute-force steady state of the
   package's time integration from rest (generalized-alpha, the case's integrator) at 1.63 rad/s.
3. The paper's example: the switch there is unchanged (the period-doubling pair and the period-2
   fold at the values recorded before the change).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp

import cablesim
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.dynamics.steady import SteadyCriterion, steady_response
from cablesim.orbits import OdeSystem, Shooting, cable_system, continue_branches, solve_orbit, trace_branches
from cablesim.orbits.kernels import SLACK
from cablesim.orbits.switching import doubling_direction, start_factor

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
RTOL = dict(rtol=1e-12, atol=1e-13, method="DOP853")
MC, MEPS, MALPHA, XMAX = 0.05, 0.4, 1.0, 1.2


# ----------------------------------------------------------------------------------------------
# 1. Mathieu-Duffing with a state limit and an oversized scale
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def limited_mathieu_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    c, eps, alpha, xmax = prm[0], prm[1], prm[2], prm[3]
    if abs(x[0]) > xmax:
        return SLACK
    k = 1.0 + eps * np.cos(theta)
    dx[0] = x[1]
    dx[1] = -c * x[1] - k * x[0] - alpha * x[0] ** 3
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -k - 3.0 * alpha * x[0] ** 2
    J[1, 1] = -c
    if ipar >= 0:
        dp[0] = 0.0
        dp[1] = 0.0
    return 0


def mathieu_rhs(t, y, w):
    return [y[1], -MC * y[1] - (1 + MEPS * np.cos(w * t)) * y[0] - MALPHA * y[0] ** 3]


def limited_system():
    return OdeSystem(field=limited_mathieu_field, dim=2, prm=np.array([MC, MEPS, MALPHA, XMAX]), work=np.zeros(1),
                     omega=1.5, parameters={}, fastest_rate=3.0, displacements=np.array([0]), divergence=-MC)


def test_start_factor_shrinks_only_when_needed():
    sysm = limited_system()
    d = trace_branches(sysm, np.zeros(2), "omega", 1.5, 2.6, state_scale=np.array([0.5, 0.5]), switch_branches=False)
    pd = next(p for p in d.branches[0].points if p.special == "period-doubling")
    ev = Shooting(sysm).evaluate(pd.u, pd.parameter)
    sh2 = Shooting(sysm, period=2, segments=2)
    base = np.concatenate([pd.u, pd.u])
    for scale, expect_full in ((0.5, True), (100.0, False)):
        sc = np.array([scale, scale])
        dirn, eps = doubling_direction(ev, 1, sc, 0.02)
        f = start_factor(sh2, base, dirn, eps, pd.parameter, np.tile(sc, 2))
        assert f is not None and (f == 1.0) == expect_full
        # the accepted perturbation can be integrated from both signs
        for sign in (1.0, -1.0):
            assert sh2.evaluate(base + sign * f * eps * dirn, pd.parameter, jac=False).status == 0


def test_switch_with_oversized_scale():
    d = trace_branches(limited_system(), np.zeros(2), "omega", 1.5, 2.6, state_scale=np.array([100.0, 100.0]))
    pds = [b for b in d.of_kind("period-doubling") if b.period == 1]
    assert len(pds) == 2 and all(b.child is not None for b in pds)
    for b in pds:
        br = d.branches[b.child]
        assert br.period == 2 and br.end.name == "BOUND_REACHED"
        pts = [p for p in br.points[1:] if p.amplitude[0] > 1e-3]
        assert len(pts) > 5
        for p in pts[:: max(1, len(pts) // 6)]:
            T2 = 4 * np.pi / p.omega
            sol = solve_ivp(mathieu_rhs, (0, T2), p.state, args=(p.omega,), t_eval=[T2 / 2, T2], **RTOL)
            # to the continuation's tolerance, 1e-9 of the (oversized) scale
            assert np.abs(sol.y[:, 1] - p.state).max() < 1e-8 * 100.0
            assert np.abs(sol.y[:, 0] - p.state).max() > 1e-4


# ----------------------------------------------------------------------------------------------
# 2. The stiff cable near 2 w1
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def stiff():
    case = cablesim.load_case(CONFIGS / "paper" / "fig8a.yaml")
    static = run_static(case)
    eom = build_equations(case, static, omega=1.58)
    return case, static, continue_branches(eom, "omega", 1.58, 1.68)


@pytest.mark.slow  # the paper example's switch (below, and tests/test_orbits_cable.py) in `make test`
def test_stiff_cable_period_two_branch(stiff):
    case, static, d = stiff
    pds = sorted((b for b in d.of_kind("period-doubling") if b.branch == 0), key=lambda b: b.parameter)
    assert [round(b.parameter, 5) for b in pds] == [1.60328, 1.65721]
    doubled = [b for b in d.branches if b.period == 2]
    assert len(doubled) == 1  # one branch joins the pair
    br = doubled[0]
    assert br.end.name == "MERGED"
    assert {round(br.values[0], 9), round(br.values[-1], 9)} == {round(b.parameter, 9) for b in pds}
    assert max(p.residual for p in br.points) < 1e-8
    # the period-2 orbits between the pair are stable and much larger than the period-1 orbit
    inner = [p for p in br.points if 1.61 < p.parameter < 1.65]
    assert inner and all(p.stable for p in inner)
    assert min(p.amplitude[1] for p in inner) > 5 * max(p.amplitude[1] for p in d.branches[0].points)


@pytest.mark.slow  # the paper example's switch (below, and tests/test_orbits_cable.py) in `make test`
def test_stiff_cable_brute_force_on_period_two_branch(stiff):
    case, static, d = stiff
    w = 1.63
    eom = build_equations(case, static, omega=w)
    brute = steady_response(eom, make_integrator(case.integrator, eom, w), np.arange(eom.n_dof),
                            SteadyCriterion(cap=6000.0, window=300.0))
    assert brute.steady and brute.period == 2
    br = next(b for b in d.branches if b.period == 2)
    guess = min(br.points, key=lambda p: abs(p.parameter - w))
    assert abs(guess.parameter - w) < 5e-3
    sysm = cable_system(eom)
    sol = solve_orbit(Shooting(sysm, period=2), guess.state, w)
    assert sol.converged
    ev = sol.evaluation
    d_ = sysm.displacements
    amp = np.maximum(np.abs(ev.xmax[d_]), np.abs(ev.xmin[d_]))
    rel = np.abs(amp - brute.amplitude) / amp
    assert rel[[1, 3]].max() < 1e-3  # z2, z4: measured 2.7e-5, 1.9e-6
    assert np.abs(amp - brute.amplitude).max() < 1e-3 * amp.max()
    assert np.abs(ev.multipliers).max() < 1
    # the branch itself passes through it
    pts = sorted(br.points, key=lambda p: p.parameter)
    vals = np.array([p.parameter for p in pts])
    j = int(np.searchsorted(vals, w))
    a, b = pts[j - 1], pts[j]
    f = (w - a.parameter) / (b.parameter - a.parameter)
    assert np.abs(a.amplitude + f * (b.amplitude - a.amplitude) - amp).max() < 1e-2 * amp.max()


# ----------------------------------------------------------------------------------------------
# 3. The paper's example is switched as before
# ----------------------------------------------------------------------------------------------
def test_paper_example_switch_unchanged():
    case = cablesim.load_case(CONFIGS / "paper-example.yaml")
    eom = build_equations(case, run_static(case), omega=4.9)
    d = continue_branches(eom, "omega", 4.9, 5.2)
    pds = sorted(b.parameter for b in d.of_kind("period-doubling") if b.branch == 0)
    assert [round(x, 5) for x in pds] == [5.02116, 5.07439]
    doubled = [b for b in d.branches if b.period == 2]
    assert len(doubled) == 1 and doubled[0].end.name == "MERGED"
    folds = [b.parameter for b in d.of_kind("fold") if b.branch == doubled[0].index]
    assert [round(x, 5) for x in folds] == [4.98694]
