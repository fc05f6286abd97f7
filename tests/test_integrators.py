"""The integrators (rk4, dopri5, newmark, generalized-alpha) against independent references
(docs/theory.md, section 5).

Every expected value here is computed from the physics, never taken from an earlier cablesim
run:

1. exact analysis vs the independent second-order formulation ``M y'' + C y' + P(y) = F(t)`` of
   ``helpers_dynamics`` (own P from the segment geometry, scipy's DOP853 at rtol 1e-11) from
   the static equilibrium at rest; also output instants between steps;
2. observed convergence orders of rk4, newmark and generalized-alpha against that reference;
3. approximate analysis: the schemes agree with each other;
4. linear limit: tiny harmonic loads give the linear frequency response of (K0, M, C);
5. undamped free vibration: the total energy is conserved; newmark and generalized-alpha follow
   the published (Chung-Hulbert) amplification matrix on a badly resolved high mode;
6. a stiff (EA = 1e12) cable: generalized-alpha vs newmark, and vs scipy's Radau on the same
   independent second-order form.

Measured errors (paper example, forcing 2.45 rad/s, 200 s, max|z| about 4.7 m) are quoted next to
each bound; the bounds leave a margin of roughly 5-20x.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations, mode_velocity
from cablesim.analyses.static import run_static
from cablesim.case import example_text, parse_case
from cablesim.dynamics.integrators import DOPRI5, RK4, GeneralizedAlpha, Newmark
from cablesim.dynamics.simulate import simulate
from helpers_dynamics import (
    APPROX_DURATION,
    DURATION,
    OUT_STEP,
    SHORT,
    _all_finite,
    forced_run,
    own_energy,
    reference_history,
    rel_error,
    stiff_reference,
)


# ----------------------------------------------------------------------------------------------
# 1. Exact analysis against the independent second-order reference
# ----------------------------------------------------------------------------------------------
# (integrator, bound on max|z - z_ref| / max|z_ref| over 200 s near resonance, observed)
ACCURACY_CASES = [
    # adaptive 5(4), rtol 1e-10: global error a few rtol x the ~80 periods (observed ~4e-11)
    pytest.param(DOPRI5(rtol=1e-10, atol=1e-12), 1e-7, id="dopri5-1e-10"),
    # 4th order: (w h)^4-type error with h = 0.005, w = 2.45 -> ~1e-9 per period (observed ~5e-8)
    pytest.param(RK4(dt=0.005), 1e-6, id="rk4-0.005"),
    # 2nd order: period error (w h)^2 / 12 = 2e-6, amplified near resonance (observed ~1.5e-4)
    pytest.param(Newmark(dt=0.002), 1e-3, id="newmark-0.002"),
    pytest.param(GeneralizedAlpha(dt=0.002, rho_inf=1.0), 1e-3, id="galpha1-0.002"),
    pytest.param(GeneralizedAlpha(dt=0.002, rho_inf=0.8), 1e-3, id="galpha0.8-0.002"),
]


@pytest.mark.parametrize("integ, bound", ACCURACY_CASES)
def test_exact_analysis_matches_second_order_reference(forced_eom, reference, integ, bound):
    t, zref, vref = reference
    hist = forced_run(forced_eom, integ, DURATION)
    assert hist.completed, hist.message
    assert np.allclose(hist.t, t, rtol=0, atol=1e-9)
    assert np.max(np.abs(zref)) > 2.0  # near resonance: metres of response, a nonlinear regime
    err = rel_error(hist.z, zref)
    print(f"{integ}: max|z - z_ref| / max|z_ref| = {err:.3g}")
    assert err < bound
    # the velocities too (the third-order state carries y' explicitly)
    assert rel_error(hist.v, vref) < 2 * bound


def test_saved_instants_between_steps_are_accurate(forced_eom):
    """Output instants that do not fall on a step are interpolated (cubic Hermite): the
    interpolation keeps the schemes' accuracy."""
    step = 0.0731
    t = np.arange(0, round(SHORT / step) + 1) * step
    zref, _ = reference_history(forced_eom, t)
    for integ, bound in [(RK4(dt=0.005), 1e-7), (Newmark(dt=0.002), 5e-4), (DOPRI5(rtol=1e-10, atol=1e-12), 1e-8)]:
        hist = simulate(forced_eom, integ, t[-1], step)
        assert hist.completed, hist.message
        assert np.allclose(hist.t, t, rtol=0, atol=1e-9)
        err = rel_error(hist.z, zref)
        print(f"off-grid outputs, {integ}: {err:.3g}")
        assert err < bound


# ----------------------------------------------------------------------------------------------
# 2. Observed convergence orders (first 30 s, same reference)
# ----------------------------------------------------------------------------------------------
ORDER_CASES = [
    pytest.param(RK4, {}, (0.04, 0.02, 0.01), 4, id="rk4"),
    pytest.param(Newmark, {}, (0.02, 0.01, 0.005), 2, id="newmark"),
    pytest.param(GeneralizedAlpha, {"rho_inf": 0.8}, (0.02, 0.01, 0.005), 2, id="galpha0.8"),
]


@pytest.mark.parametrize("cls, kw, steps, order", ORDER_CASES)
def test_observed_convergence_order(forced_eom, reference, cls, kw, steps, order):
    t, zref, _ = reference
    k = round(SHORT / OUT_STEP) + 1
    errs = []
    for dt in steps:
        hist = forced_run(forced_eom, cls(dt=dt, **kw), SHORT)
        assert hist.completed, hist.message
        errs.append(rel_error(hist.z, zref[:k]))
    orders = [math.log2(errs[i] / errs[i + 1]) for i in range(len(errs) - 1)]
    print(f"{cls.name}: errors {errs}, observed orders {orders}")
    assert errs[-1] > 1e-9  # still far above the reference's own error
    for p in orders:
        assert abs(p - order) < 0.5


# ----------------------------------------------------------------------------------------------
# 3. Approximate analysis: the schemes agree
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "integ, bound",
    [
        pytest.param(RK4(dt=0.005), 1e-6, id="rk4-0.005"),
        pytest.param(Newmark(dt=0.002), 1e-3, id="newmark-0.002"),
        pytest.param(GeneralizedAlpha(dt=0.002, rho_inf=0.8), 1e-3, id="galpha0.8-0.002"),
    ],
)
def test_approximate_analysis_schemes_agree(approx_eom, approx_tight, integ, bound):
    hist = simulate(approx_eom, integ, APPROX_DURATION, OUT_STEP)
    assert hist.completed, hist.message
    assert np.max(np.abs(approx_tight.z)) > 1.0
    err = rel_error(hist.z, approx_tight.z)
    print(f"approximate, {integ} vs dopri5 1e-10: {err:.3g}")
    assert err < bound


# ----------------------------------------------------------------------------------------------
# 4. Linear limit: frequency response of (K0, M, C)
# ----------------------------------------------------------------------------------------------
LIN_XI = 0.1  # transients (slowest rate xi w1 = 0.25/s) die out within the run
LIN_DURATION = 70.0


def _harmonic_fit(t, z, w):
    """Complex amplitude X with z ~ a + Im(X e^{i w t}) (least squares), per column."""
    A = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    coef, *_ = np.linalg.lstsq(A, z, rcond=None)
    return coef[1] + 1j * coef[2], coef[0]


@pytest.mark.parametrize(
    "analysis, w",
    [("exact", 1.3), ("exact", 2.5), ("exact", 8.0), ("exact", 20.0), ("approximate", 2.5)],
)
def test_linear_limit_frequency_response(paper, exact_static, approx_static, analysis, w):
    static = exact_static if analysis == "exact" else approx_static
    scale = 1e-4
    eom = build_equations(paper, static, omega=w, load_scale=scale, damping_ratio=LIN_XI)
    step = 2 * np.pi / w / 40
    hist = simulate(eom, DOPRI5(rtol=1e-10, atol=1e-14), LIN_DURATION, step, split=False)
    assert hist.completed, hist.message
    M = np.diag(eom.mass)
    # C built independently: Rayleigh coefficients for xi in modes 1 and 2 of (K0, M)
    w12 = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, static.K0)).real))[:2]
    a0 = 2 * LIN_XI * w12[0] * w12[1] / (w12[0] + w12[1])
    a1 = 2 * LIN_XI / (w12[0] + w12[1])
    C = a0 * M + a1 * static.K0
    X = np.linalg.solve(static.K0 - w**2 * M + 1j * w * C, paper.FL * scale)
    # last 5 periods
    T = 2 * np.pi / w
    sel = hist.t >= hist.t[-1] - 5 * T - 1e-9
    Xfit, mean = _harmonic_fit(hist.t[sel], hist.z[sel], w)
    err = np.abs(Xfit - X) / np.abs(X)
    print(f"{analysis} w={w}: |X| = {np.abs(X)}, rel err {err}")
    assert np.all(err < 1e-3)
    assert np.all(np.abs(mean) < 1e-3 * np.abs(X).max())


# ----------------------------------------------------------------------------------------------
# 5. Energy conservation, undamped exact analysis, large amplitude
# ----------------------------------------------------------------------------------------------
ENERGY_V = 3.0  # m/s along mode 1: about 1.2 m of motion, strongly nonlinear
ENERGY_DURATION = 50.0


def _energy_run(paper, exact_static, integ):
    eom = build_equations(paper, exact_static, omega=0.0, load_scale=0.0, damping_ratio=0.0)
    assert np.all(eom.C == 0)
    v0 = mode_velocity(exact_static, 1, ENERGY_V)
    hist = simulate(eom, integ, ENERGY_DURATION, 0.02, s0=eom.initial_state(None, v0), split=False)
    assert hist.completed, hist.message
    E = own_energy(eom.cable, eom.F0, eom.y0, hist.z, hist.v)
    ke0 = 0.5 * np.sum(eom.mass * v0 * v0)
    return hist, (E - E[0]) / ke0


def test_energy_conserved_dopri5(paper, exact_static):
    hist, drift = _energy_run(paper, exact_static, DOPRI5(rtol=1e-11, atol=1e-13))
    assert np.max(np.abs(hist.z)) > 0.5
    print(f"dopri5: max |E - E0| / KE0 = {np.abs(drift).max():.3g}")
    assert np.abs(drift).max() < 1e-6


def test_energy_bounded_newmark(paper, exact_static):
    hist, drift = _energy_run(paper, exact_static, Newmark(dt=0.01))
    half = drift.size // 2
    first, second = np.abs(drift[:half]).max(), np.abs(drift[half:]).max()
    print(f"newmark: max |E - E0| / KE0 first half {first:.3g}, second half {second:.3g}")
    assert max(first, second) < 1e-3
    # no secular growth: the second half is not systematically worse than the first
    assert second < 2.0 * first + 1e-9


# ----------------------------------------------------------------------------------------------
# 5b. Newmark / generalized-alpha on a high mode: the published amplification matrix
# ----------------------------------------------------------------------------------------------
def chung_hulbert_amplification(Omega, rho_inf):
    """G with (x, h v, h^2 a)_{n+1} = G (x, h v, h^2 a)_n for x'' + w^2 x = 0, Omega = w h
    (Chung and Hulbert 1993; rho_inf = None gives Newmark's average acceleration)."""
    if rho_inf is None:
        am, af, beta, gamma = 0.0, 0.0, 0.25, 0.5
    else:
        am = (2 * rho_inf - 1) / (rho_inf + 1)
        af = rho_inf / (rho_inf + 1)
        gamma = 0.5 - am + af
        beta = 0.25 * (1 - am + af) ** 2
    O2 = Omega**2
    # unknowns X1 = (x, v, a)_{n+1} scaled by (1, h, h^2); A X1 = B X0
    A = np.array([[O2 * (1 - af), 0.0, 1 - am], [1.0, 0.0, -beta], [0.0, 1.0, -gamma]])
    B = np.array([[-O2 * af, 0.0, -am], [1.0, 1.0, 0.5 - beta], [0.0, 1.0, 1 - gamma]])
    return np.linalg.solve(A, B)


@pytest.mark.parametrize(
    "integ, rho",
    [
        (Newmark(dt=0.5), None),
        (GeneralizedAlpha(dt=0.5, rho_inf=1.0), 1.0),
        (GeneralizedAlpha(dt=0.5, rho_inf=0.8), 0.8),
        (GeneralizedAlpha(dt=0.5, rho_inf=0.5), 0.5),
        (GeneralizedAlpha(dt=0.5, rho_inf=0.0), 0.0),
    ],
    ids=["newmark", "galpha1", "galpha0.8", "galpha0.5", "galpha0"],
)
def test_implicit_schemes_follow_their_amplification_matrix(paper, exact_static, integ, rho):
    """Undamped, tiny motion along mode 4 with omega_4 dt = 26: the modal coordinate must follow
    G^n of the published scheme (energy kept by newmark, dissipated at rate ~rho_inf otherwise)."""
    # sanity of G itself: spectral radius 1 (newmark) or rho_inf as Omega -> infinity
    G_inf = chung_hulbert_amplification(1e7, rho)
    assert np.max(np.abs(np.linalg.eigvals(G_inf))) == pytest.approx(1.0 if rho is None else rho, abs=1e-3)
    st = exact_static
    eom = build_equations(paper, st, omega=0.0, load_scale=0.0, damping_ratio=0.0)
    M = eom.mass
    lam, Phi = np.linalg.eigh(st.K0 / np.sqrt(np.outer(M, M)))
    Phi = Phi / np.sqrt(M)[:, None]  # M-orthonormal modes of (K0, M), computed here
    w4 = math.sqrt(lam[3])
    v0 = 1e-3 * Phi[:, 3] / np.abs(Phi[:, 3]).max()
    s0 = eom.initial_state(None, v0)
    h = integ.dt
    n_steps = 30
    hist = simulate(eom, integ, n_steps * h, h, s0=s0, split=False)
    assert hist.completed, hist.message
    q = hist.z @ (M[:, None] * Phi)
    qd = hist.v @ (M[:, None] * Phi)
    G = chung_hulbert_amplification(w4 * h, rho)
    X = np.array([0.0, h * qd[0, 3], h * h * (s0[2 * eom.n_dof :] @ (M * Phi[:, 3]))])
    pred = [X]
    for _ in range(n_steps):
        pred.append(G @ pred[-1])
    pred = np.array(pred)
    scale = np.abs(pred[:, 0]).max()
    err = np.abs(q[:, 3] - pred[:, 0]).max() / scale
    err_v = np.abs(h * qd[:, 3] - pred[:, 1]).max() / np.abs(pred[:, 1]).max()
    decay = math.hypot(w4 * q[-1, 3], qd[-1, 3]) / abs(qd[0, 3])  # sqrt of modal energy ratio
    print(f"{integ}: modal error {err:.3g} (velocity {err_v:.3g}), amplitude ratio after {n_steps} steps {decay:.3g}")
    assert err < 1e-4 and err_v < 1e-4
    # the other modes stay at rest
    assert np.abs(np.delete(q, 3, axis=1)).max() < 1e-4 * scale
    if rho is None or rho == 1.0:
        assert decay == pytest.approx(1.0, abs=1e-5)
    else:
        assert decay < 0.1


# ----------------------------------------------------------------------------------------------
# 6. A stiff cable (EA = 1e12)
# ----------------------------------------------------------------------------------------------
STIFF_EA = 1e12


@pytest.fixture(scope="module")
def stiff():
    text = example_text()
    text = re.sub(r"^\s*E:.*\n", "", text, flags=re.M)
    text = re.sub(r"^(\s*)A:.*\n", rf"\1EA: {STIFF_EA:.1e}\n", text, flags=re.M)
    case = parse_case(text)
    assert case.cable.axial_rigidity == STIFF_EA
    static = run_static(case, "exact", all_models=False)
    w = static.modes.omega
    assert w[-1] / w[0] > 200  # genuinely stiff
    return case, static


def test_stiff_cable_generalized_alpha(stiff):
    case, static = stiff
    w1 = static.modes.omega[0]
    w = 0.97 * w1
    eom = build_equations(case, static, omega=w)
    dt = 2 * np.pi / w1 / 100
    out = 50 * dt
    ga = simulate(eom, GeneralizedAlpha(dt=dt, rho_inf=0.8), 200.0, out)
    nm = simulate(eom, Newmark(dt=dt), 200.0, out)
    for hist in (ga, nm):
        assert hist.completed, hist.message
        assert _all_finite(hist)
    zmax = np.max(np.abs(ga.z))
    print(f"stiff: w1 = {w1:.4f}, w_max = {static.modes.omega[-1]:.4g}, max|z| = {zmax:.3g}, "
          f"galpha vs newmark {rel_error(ga.z, nm.z):.3g}")
    assert 0.5 < zmax < 20.0  # responds near resonance, but bounded
    assert np.all(ga.T > 0)
    assert rel_error(ga.z, nm.z) < 1e-2  # observed ~1e-3 (both 2nd order, same dt)


def test_stiff_cable_against_implicit_reference(stiff):
    """First 40 s against scipy's Radau on the independent second-order form: generalized-alpha
    at T/100 is within its 2nd-order error (observed ~1.5e-2), and 4x smaller steps give ~16x
    less error."""
    case, static = stiff
    w1 = static.modes.omega[0]
    eom = build_equations(case, static, omega=0.97 * w1)
    dt = 2 * np.pi / w1 / 100
    out = 50 * dt
    t = np.arange(0, int(40.0 / out) + 1) * out
    zref = stiff_reference(eom, t)
    errs = []
    for h in (dt, dt / 4):
        hist = simulate(eom, GeneralizedAlpha(dt=h, rho_inf=0.8), t[-1], out)
        assert hist.completed, hist.message
        errs.append(rel_error(hist.z, zref))
    print(f"stiff vs Radau: errors {errs}, order {math.log(errs[0] / errs[1]) / math.log(4):.3f}")
    assert errs[0] < 5e-2
    assert math.log(errs[0] / errs[1]) / math.log(4) == pytest.approx(2.0, abs=0.5)
