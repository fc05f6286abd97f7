"""The approximate analysis' orbit field on a lightly loaded, low-sag cable.

``configs/paper/fig6.yaml``: sum S only 0.32 % over the chord, and loads a thirteenth of the
paper example's at the same EA. The inner solve of the field for the loads (``y = x(P) + u(P)``)
resolves them only to some EA machine epsilons, 1e-11 of ``|P|`` here (6e-13 on the paper's
example), which a stopping test relative to ``|P|`` alone cannot meet
(:mod:`cablesim.orbits.cablefield`).

References (none from the orbit code under test): the static equilibrium (``z = 0`` is a rest
point of the field), the field itself from other warm starts, the package's time integration
(:func:`~cablesim.dynamics.steady.steady_response`) and the linear frequencies of the
approximate analysis (the resonance peaks of the continued branch).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.api import load_case
from cablesim.dynamics.steady import SteadyCriterion, steady_response
from cablesim.orbits import BranchEnd, Shooting, cable_system, continue_branches, linear_response_state, solve_orbit
from cablesim.orbits.kernels import OK, copy_work

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
FIG6 = CONFIGS / "paper" / "fig6.yaml"
EXAMPLE = CONFIGS / "paper-example.yaml"


def _approximate(path: Path):
    case = load_case(path)
    return case, run_static(case, analysis="approximate")


@pytest.fixture(scope="module")
def fig6():
    return _approximate(FIG6)


@pytest.fixture(scope="module")
def example():
    return _approximate(EXAMPLE)


def _call(sysm, work, x, theta=0.0, model=None):
    n = x.size
    dx, J, dp = np.empty(n), np.zeros((n, n)), np.zeros(n)
    model = sysm.model if model is None else model
    code = sysm.field(theta, sysm.omega, np.ascontiguousarray(x, dtype=float), model, sysm.prm, work, dx, J, dp, -1)
    return code, dx, J


@pytest.mark.parametrize("which", [
    pytest.param("fig6", marks=pytest.mark.slow(reason="about 10 s; the example is the fast check")), "example"])
def test_equilibrium_is_a_rest_point(which, request):
    case, static = request.getfixturevalue(which)
    eom = build_equations(case, static, omega=1.0)
    sysm = cable_system(eom)
    nd = eom.n_dof
    z0 = np.zeros(sysm.dim)
    # the field with the static loads as they are: y'' = 0 up to the statics' tolerance
    code, dx, _ = _call(sysm, copy_work(sysm.work), z0, model=eom.model(dense_damping=True))
    assert code == OK
    assert np.abs(eom.mass * dx[nd:]).max() < 1e-9 * np.abs(eom.F0).max()  # measured 2.6e-11, 1.4e-12
    # the orbit system (F0 taken as P(y0)): exactly at rest, also after a warm start elsewhere
    work = copy_work(sysm.work)
    away = np.concatenate([0.02 * linear_response_state(eom, 1.0)[:nd], np.zeros(nd)])
    assert _call(sysm, work, away)[0] == OK
    code, dx, J = _call(sysm, work, z0)
    assert code == OK
    assert np.abs(eom.mass * dx[nd:]).max() < 1e-10 * np.abs(eom.F0).max()  # measured 1.8e-12
    # tangent stiffness = K0 of the equilibrium
    K = -J[nd:, :nd] * eom.mass[:, None]
    assert np.abs(K - eom.K0).max() < 1e-10 * np.abs(eom.K0).max()  # measured 2e-14
    # the failure this file is about: one forcing period from the equilibrium
    assert Shooting(sysm).evaluate(z0, 1.0).status == OK


@pytest.mark.parametrize("which", ["fig6", "example"])
def test_field_does_not_depend_on_the_warm_start(which, request):
    """Loads at a state from a cold start (walk from F0) and from warm starts at nearby and
    farther states agree to round-off."""
    case, static = request.getfixturevalue(which)
    w = 1.84
    eom = build_equations(case, static, omega=w)
    sysm = cable_system(eom)
    n, nd = sysm.dim, eom.n_dof
    x0 = linear_response_state(eom, w)
    rng = np.random.default_rng(7)
    worst_f = worst_j = 0.0
    for _ in range(10):
        x = x0 * rng.uniform(-1.0, 1.0) + 1e-3 * rng.normal(size=n)
        code, dx_ref, J_ref = _call(sysm, copy_work(sysm.work), x, 0.7)
        assert code == OK
        for spread in (1e-6, 1e-3, 1e-2):
            work = copy_work(sysm.work)
            assert _call(sysm, work, x + spread * rng.normal(size=n), 0.7)[0] == OK
            code, dx, J = _call(sysm, work, x, 0.7)
            assert code == OK
            worst_f = max(worst_f, np.abs(eom.mass * (dx - dx_ref)[nd:]).max())
            worst_j = max(worst_j, np.abs(J - J_ref).max() / np.abs(J_ref).max())
    assert worst_f < 1e-10 * np.abs(eom.F0).max()  # measured 5.5e-12 (fig6), 4e-13
    assert worst_j < 1e-11  # measured 1e-13


def test_orbit_matches_brute_force_steady_state(fig6):
    case, static = fig6
    w = 1.84  # near the fundamental
    eom = build_equations(case, static, omega=w)
    sol = solve_orbit(Shooting(cable_system(eom)), linear_response_state(eom, w), w)
    assert sol.converged
    ev = sol.evaluation
    assert np.abs(ev.multipliers).max() < 1.0
    amp = np.maximum(np.abs(ev.xmax[: eom.n_dof]), np.abs(ev.xmin[: eom.n_dof]))
    pr = steady_response(eom, make_integrator(case.integrator, eom, w), np.arange(eom.n_dof), SteadyCriterion())
    assert pr.steady and pr.period == 1
    # measured 1.7e-4, the steady criterion's periodicity tolerance over 1 - |mu| (3e-6 with
    # 1024 samples per period)
    assert np.abs(amp - pr.amplitude).max() < 1e-3 * np.abs(pr.amplitude).max()
    assert np.all(np.abs(amp - pr.amplitude) < 1e-3 * np.abs(pr.amplitude))


def test_continuation_covers_the_frequency_range(fig6):
    case, static = fig6
    eom = build_equations(case, static, omega=1.0)
    d = continue_branches(eom, "omega", 1.0, 4.0)
    main = d.branches[0]
    assert main.period == 1 and main.end == BranchEnd.BOUND_REACHED
    assert main.values.min() == pytest.approx(1.0) and main.values.max() == pytest.approx(4.0)
    assert main.trusted.all() and main.stable.all()
    # the resonance peaks of z2 lie just above the approximate analysis' first two linear
    # frequencies (1.811, 2.340 rad/s; measured peaks 1.828, 2.338)
    w, a = main.values, main.amplitude[:, 1]
    for lo, hi in ((1.0, 2.1), (2.1, 4.0)):
        sel = (w > lo) & (w < hi)
        peak = w[sel][np.argmax(a[sel])]
        f = eom.frequencies[0] if lo < 2.0 else eom.frequencies[1]
        assert abs(peak - f) < 0.03
