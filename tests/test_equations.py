"""The equations of motion (docs/theory.md, sections 1 and 5) against independent expectations.

Every expected value here is computed from the physics (the independent second-order reference
of ``helpers_dynamics``, own geometry, own eigenproblems), never taken from an earlier cablesim
run:

1. the reference's own resisting force and tangent are the model's (``cablesim.statics``);
2. the initial state (eq. 19): ``y''(0)`` from ``P(y0 + z0)`` for a displaced start, and the
   mode-shaped initial velocity of free vibration; Rayleigh damping C;
3. the drift of the dynamic equilibrium (eq. 15) and the split ``z = zc + ze`` (eq. 22) along
   tight solutions, exact and approximate analysis;
4. free vibration along mode 1: damped modal frequency and logarithmic decrement.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cablesim.analyses.dynamic import run_free_vibration
from cablesim.analyses.setup import build_equations, mode_velocity
from cablesim.case import IntegratorSpec
from cablesim.dynamics.integrators import DOPRI5, RK4
from cablesim.dynamics.simulate import simulate
from cablesim.statics import resisting_force, tangent_stiffness
from helpers_dynamics import (
    APPROX_DURATION,
    DURATION,
    OUT_STEP,
    _own_stiffness,
    forced_run,
    own_force,
    reference_history,
    rel_error,
)


# ----------------------------------------------------------------------------------------------
# 1. The independent reference is the model: P(y) and K(y) equal cablesim.statics
# ----------------------------------------------------------------------------------------------
def test_reference_force_is_the_code_statics_force(exact_static):
    """Sanity of the reference itself: own P equals statics.resisting_force, and P(y0) = F0."""
    cable = exact_static.cable
    y0 = exact_static.y0
    assert np.allclose(own_force(cable, y0), exact_static.P, rtol=0, atol=1e-8 * np.abs(exact_static.P).max())
    rng = np.random.default_rng(1)
    for _ in range(5):
        y = y0 + rng.normal(scale=0.5, size=y0.size)
        assert np.allclose(own_force(cable, y), resisting_force(cable, y), rtol=1e-12, atol=1e-6)
        K = _own_stiffness(y, np.asarray(cable.S, dtype=float), cable.EA, cable.L, cable.H)
        assert np.allclose(K, tangent_stiffness(cable, y), rtol=1e-12, atol=1e-9 * np.abs(K).max())
        # and K is the derivative of the own force (central differences)
        eps = 1e-6
        Kfd = np.column_stack([(own_force(cable, y + eps * e) - own_force(cable, y - eps * e)) / (2 * eps) for e in np.eye(y.size)])
        assert np.allclose(K, Kfd, rtol=0, atol=1e-6 * np.abs(K).max())


# ----------------------------------------------------------------------------------------------
# 2. Initial state (eq. 19)
# ----------------------------------------------------------------------------------------------
def test_displaced_start_matches_reference(paper, exact_static):
    """Exact analysis started away from equilibrium (z0, v0): y''(0) from eq. 19 with P(y0 + z0);
    undamped free motion compared with the independent reference."""
    eom = build_equations(paper, exact_static, omega=0.0, load_scale=0.0, damping_ratio=0.0)
    z0 = np.array([0.4, -0.3, 0.2, 0.6])
    v0 = np.array([0.0, 0.5, -0.2, 0.0])
    s0 = eom.initial_state(z0, v0)
    t = np.arange(0, 201) * 0.1
    zref, vref = reference_history(eom, t, s0=s0)
    hist = simulate(eom, DOPRI5(rtol=1e-10, atol=1e-12), t[-1], 0.1, s0=s0)
    assert hist.completed, hist.message
    assert np.allclose(hist.z[0], z0) and np.allclose(hist.v[0], v0)
    err = rel_error(hist.z, zref)
    print(f"displaced start, dopri5 1e-10 vs reference: {err:.3g}")
    assert err < 1e-7
    assert rel_error(hist.v, vref) < 1e-7


def test_mode_velocity_and_initial_acceleration(paper, exact_static):
    """mode_velocity: largest component V > 0 along the mode; a(0) from eq. 19."""
    st = exact_static
    for mode in range(1, 5):
        v0 = mode_velocity(st, mode, 1.5)
        k = int(np.argmax(np.abs(v0)))
        assert v0[k] == pytest.approx(1.5, rel=1e-14)
        # v0 is an eigenvector of M^-1 K0 for omega_mode
        Mv = st.cable.mass_diagonal
        lhs = st.K0 @ v0
        rhs = st.modes.omega[mode - 1] ** 2 * Mv * v0
        assert np.allclose(lhs, rhs, rtol=0, atol=1e-8 * np.abs(lhs).max())
    eom = build_equations(paper, st, omega=0.0, load_scale=0.0, damping_ratio=0.2)
    v0 = mode_velocity(st, 3, 1.0)
    s0 = eom.initial_state(None, v0)
    nd = eom.n_dof
    a_expected = -(eom.C @ v0) / eom.mass
    assert np.allclose(s0[:nd], 0.0)
    assert np.allclose(s0[nd : 2 * nd], v0)
    assert np.allclose(s0[2 * nd :], a_expected, rtol=0, atol=1e-6 * np.abs(a_expected).max())
    # C is Rayleigh: a0 M + a1 K0 with the formulas of docs/theory.md for xi = 0.2 in modes 1 and 2
    w1, w2 = st.modes.omega[:2]
    C = 2 * 0.2 * w1 * w2 / (w1 + w2) * np.diag(st.cable.mass_diagonal) + 2 * 0.2 / (w1 + w2) * st.K0
    assert np.allclose(eom.C, C, rtol=1e-12, atol=1e-9 * np.abs(C).max())
    # displaced start (exact analysis): a(0) = M^-1 (F0 - P(y0 + z0) - C v0), own P
    z0 = np.array([0.3, -0.2, 0.1, 0.4])
    s0 = eom.initial_state(z0, v0)
    a_expected = (eom.F0 - own_force(st.cable, eom.y0 + z0) - eom.C @ v0) / eom.mass
    assert np.allclose(s0[2 * nd :], a_expected, rtol=1e-9, atol=1e-9)


# ----------------------------------------------------------------------------------------------
# 3. Eq. 15 residual and the split z = zc + ze (eq. 22)
# ----------------------------------------------------------------------------------------------
def test_exact_analysis_residual_and_split(forced_eom):
    """Exact analysis: eq. 15 residual small along a tight solution; z = zc + ze by definition;
    the elastic part equals the independent y - x(P(y)) computed from own statics here."""
    hist = forced_run(forced_eom, DOPRI5(rtol=1e-10, atol=1e-12), DURATION)
    assert hist.residual.max() < 1e-7
    assert np.max(np.abs(hist.z - hist.zc - hist.ze)) < 1e-9 * np.max(np.abs(hist.z))
    # tensions from own geometry
    c = forced_eom.cable
    y = forced_eom.y0 + hist.z
    pts = np.zeros((y.shape[0], c.n_nodes + 2, 2))
    pts[:, 1:-1] = y.reshape(y.shape[0], -1, 2)
    pts[:, -1] = [c.L, c.H]
    d = np.diff(pts, axis=1)
    T = c.EA * (np.hypot(d[..., 0], d[..., 1]) - c.S) / c.S
    assert np.allclose(hist.T, T, rtol=1e-9, atol=1e-6)


def test_approximate_analysis_drift_is_small(approx_eom, approx_tight):
    """The third-order integration keeps y = x(P) + u(P) (eq. 15 defines P): tiny drift."""
    rk = simulate(approx_eom, RK4(dt=0.005), APPROX_DURATION, OUT_STEP)
    for hist in (approx_tight, rk):
        zmax = np.max(np.abs(hist.z))
        split_gap = np.max(np.abs(hist.z - hist.zc - hist.ze))
        print(f"{hist.integrator}: residual {hist.residual.max():.3g}, |z - zc - ze| / max|z| {split_gap / zmax:.3g}")
        assert np.all(np.isfinite(hist.residual))
        assert hist.residual.max() < 1e-6
        assert split_gap < 1e-6 * zmax
        # both parts are present: configurational dominates, elastic is not zero
        assert np.max(np.abs(hist.ze)) > 1e-4 * zmax


# ----------------------------------------------------------------------------------------------
# 4. Free vibration along mode 1
# ----------------------------------------------------------------------------------------------
def _zero_crossings(t, x):
    """Times where x changes sign (linear interpolation)."""
    i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def _peaks(t, x):
    """Interpolated positive local maxima (parabola through three samples)."""
    i = np.nonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]) & (x[1:-1] > 0))[0] + 1
    a, b, c = x[i - 1], x[i], x[i + 1]
    denom = a - 2 * b + c
    off = 0.5 * (a - c) / denom
    return t[i] + off * (t[1] - t[0]), b - 0.25 * (a - c) * off


@pytest.mark.parametrize("analysis", ["exact", "approximate"])
def test_free_vibration_mode1_frequency_and_decrement(paper, analysis):
    xi = 0.05
    V = 1e-3  # about 0.4 mm of motion: linear to ~1e-5
    tight = paper.model_copy(update={"integrator": IntegratorSpec(name="dopri5", rtol=1e-10, atol=1e-14)})
    static, hist, _ = run_free_vibration(
        tight, mode=1, peak_velocity=V, damping_ratio=xi, duration=25.0, output_step=0.01,
        analysis=analysis,
    )
    assert hist.completed, hist.message
    M = static.cable.mass_diagonal
    lam, phi = np.linalg.eig(np.linalg.solve(np.diag(M), static.K0))
    order = np.argsort(lam.real)
    w1 = math.sqrt(lam.real[order[0]])
    phi1 = phi[:, order[0]].real
    # initial velocity: along mode 1, largest component V and positive
    v0 = hist.v[0]
    k = int(np.argmax(np.abs(v0)))
    assert v0[k] == pytest.approx(V, rel=1e-12)
    assert abs(np.dot(v0, phi1)) / (np.linalg.norm(v0) * np.linalg.norm(phi1)) == pytest.approx(1, abs=1e-10)
    # response frequency from zero crossings of the largest component
    x = hist.z[:, k]
    tc = _zero_crossings(hist.t, x)
    tc = tc[tc > 0.05]
    wd = math.pi * (tc.size - 1) / (tc[-1] - tc[0])
    expected = w1 * math.sqrt(1 - xi**2)
    print(f"{analysis}: damped frequency {wd:.6f} vs {expected:.6f}")
    assert wd == pytest.approx(expected, rel=1e-3)
    # logarithmic decrement of successive positive peaks
    tp, xp = _peaks(hist.t, x)
    delta = np.log(xp[:-1] / xp[1:]).mean()
    xi_obs = delta / math.sqrt(4 * math.pi**2 + delta**2)
    print(f"{analysis}: xi from log decrement {xi_obs:.5f}")
    assert xi_obs == pytest.approx(xi, rel=0.02)
    # and the motion stays in mode 1 (Rayleigh damping is classical)
    q = hist.z @ np.diag(M) @ phi / np.sum(phi * (M[:, None] * phi), axis=0)
    assert np.max(np.abs(np.delete(q, order[0], axis=1))) < 1e-3 * np.max(np.abs(q[:, order[0]]))
