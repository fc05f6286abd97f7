"""The approximate analysis' stiffness K = N(P)^-1 in O(n) (block-tridiagonal minus rank 2)
against the inverse of the full flexibility N = D + f written out here in closed form (the
derivatives of eq. 8 by implicit differentiation of the closure, as matrices), and its natural
and elastic states."""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics.integrators.newmark import solve_band_low_rank
from cablesim.mechanics import banded as bd
from cablesim.mechanics import closure as cl
from cablesim.mechanics import flexibility as fx

LIKE = (0.0, 0.0)  # planar: two components per node

CASES = {
    "level-heavy": "cable: {L: 100.0, H: 0.0, length: 102.5, nodes: %d, EA: 2.0e8, mass_per_length: 10.0}\n"
    "loads: {gravity: 9.81, point: [{node: 1, F: [3.0e3, 5.0e3]}]}\n",
    "inclined-soft": "cable: {L: 80.0, H: 30.0, length: 95.0, nodes: %d, EA: 2.0e5, mass_per_length: 3.0}\n"
    "loads: {gravity: 9.81, point: [{node: 1, F: [-2.0e3, 1.0e3]}]}\n",
}


def solved(text: str, n: int, seed: int):
    """(S, EA, Q, F) of the inextensible closure at loads near the case's F0."""
    case = parse_case(text % n + "analysis: approximate\n")
    eom = build_equations(case, run_static(case, all_models=False))
    rng = np.random.default_rng(seed)
    P = eom.F0 * (1.0 + 0.2 * rng.standard_normal(eom.n_dof))
    c = eom.cable
    Q, F = np.empty((n + 1, 2)), np.array(eom.F1, float)
    cl.cumulative_loads(P, Q, LIKE)
    assert cl.minimise(np.asarray(c.S, float), Q, 0.0, (c.L, c.H), F, 1e-13 * c.total_length, 60) >= 0
    return np.asarray(c.S, float), float(c.EA), Q, F


def reference(S, EA, Q, F):
    """``x, u, T`` and the full ``N = D + f`` of the inextensible closure at segment-1 force F,
    as dense matrices: ``dF_k/dP = W - E_k`` with ``W = H^-1 [sum_{k>j} G_k]_j`` (implicit
    differentiation of the closure), ``D = dx/dP``, ``B = dT/dP`` and eq. 8's ``f`` with the
    second derivatives of T contracted through ``v = H^-1 sum_k S_k T_k e_k``."""
    n = S.size - 1
    Fk = F[None, :] - Q
    T = np.hypot(Fk[:, 0], Fk[:, 1])
    e = Fk / T[:, None]
    t = np.column_stack([-e[:, 1], e[:, 0]])
    G = (S / T)[:, None, None] * t[:, :, None] * t[:, None, :]
    H = G.sum(axis=0)
    suffix = np.cumsum(G[::-1], axis=0)[::-1]
    W = np.linalg.solve(H, np.concatenate(list(suffix[1 : n + 1]), axis=1))
    below = np.tri(n + 1, n, k=-1, dtype=bool)
    a = t @ W - (below[:, :, None] * t[:, None, :]).reshape(n + 1, 2 * n)
    b = e @ W - (below[:, :, None] * e[:, None, :]).reshape(n + 1, 2 * n)
    contrib = (S / T)[:, None, None] * t[:, :, None] * a[:, None, :]
    D = np.cumsum(contrib, axis=0)[:n].reshape(2 * n, 2 * n)
    v = np.linalg.solve(H, (S * T) @ e)
    c1, c2 = S * (t @ v) / T**2, S * (e @ v) / T**2
    f = b.T @ (S[:, None] * b) + a.T @ ((S + c2)[:, None] * a)
    cross = a.T @ (c1[:, None] * b)
    f = (f + cross + cross.T) / EA
    x = np.cumsum(S[:, None] * e, axis=0)[:n].reshape(-1)
    u = b.T @ (S * T) / EA
    return x, u, T, 0.5 * (D + D.T) + 0.5 * (f + f.T)


def general_band_to_dense(A: np.ndarray) -> np.ndarray:
    """The full matrix of LAPACK's general band storage ``A[3 + i - j, j] = M[i, j]``."""
    nd = A.shape[1]
    M = np.zeros((nd, nd))
    for i in range(nd):
        for j in range(max(0, i - 3), min(nd, i + 4)):
            M[i, j] = A[3 + i - j, j]
    return M


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("n", [1, 2, 7, 30])
def test_product_is_the_inverse_of_the_full_flexibility(name, n):
    S, EA, Q, F = solved(CASES[name], n, seed=n)
    x, u, T, N = reference(S, EA, Q, F)  # the full N = D + f
    K_ref = np.linalg.inv(N)
    fac, gi, Fd = fx.factor_workspace(n)
    T2 = np.empty(n + 1)
    assert fx.segment_factors(S, EA, Q, F, T2, fac, gi, LIKE)
    np.testing.assert_allclose(T2, T, rtol=1e-14)
    rng = np.random.default_rng(7)
    scale = np.abs(K_ref).max()
    for _ in range(3):
        v = rng.standard_normal(2 * n)
        out = np.empty(2 * n)
        fx.stiffness_product(fac, gi, v, out, Fd, LIKE)
        # N is ill-conditioned (cond ~ EA / T), so compare within its conditioning
        np.testing.assert_allclose(out, K_ref @ v, rtol=0, atol=1e-7 * scale * np.abs(v).max())
        np.testing.assert_allclose(N @ out, v, rtol=0, atol=1e-9 * np.abs(v).max())
    Nw = np.empty(2 * n)
    fx.flexibility_product(fac, gi, v, Nw, Fd[0], LIKE, 0)
    np.testing.assert_allclose(Nw, N @ v, rtol=0, atol=1e-12 * np.abs(N @ v).max())
    Kb, U = np.empty((bd.band_rows(2), 2 * n)), np.empty((2 * n, 2))
    fx.stiffness_band(fac, gi, Kb, U, LIKE)
    Gi = gi[:4].reshape(2, 2)
    K = general_band_to_dense(Kb) - U @ Gi @ U.T
    np.testing.assert_allclose(K @ v, out, rtol=0, atol=1e-10 * np.abs(out).max())
    np.testing.assert_allclose(K, K.T, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(N @ K, np.eye(2 * n), rtol=0, atol=1e-9)
    assert np.linalg.eigvalsh(K).min() > 0.0  # a taut cable's stiffness is positive definite
    x2, u2 = np.empty(2 * n), np.empty(2 * n)
    fx.natural_and_elastic(S, EA, fac, gi, T2, x2, u2, LIKE)
    np.testing.assert_allclose(x2, x, rtol=0, atol=1e-12 * S.sum())
    np.testing.assert_allclose(u2, u, rtol=0, atol=1e-12 * np.abs(u).max())


def test_damping_of_the_approximate_analysis_is_banded_minus_rank_2():
    """C = a0 M + a1 K0 with K0 the static tangent (dense N(F0)^-1) equals the banded part minus
    U G U^T that the kernels use, and every damping product agrees."""
    case = parse_case(CASES["inclined-soft"] % 12 + "analysis: approximate\n")
    eom = build_equations(case, run_static(case, all_models=False))
    Cr = eom.damping_low_rank
    assert eom.C_band.shape == (bd.band_rows(2), 24) and Cr.shape == (26, 2)
    C_ref = eom.a0 * np.diag(eom.mass) + eom.a1 * np.asarray(eom.K0_dense)
    C_kernel = general_band_to_dense(eom.C_band) - Cr[:24] @ Cr[24:] @ Cr[:24].T
    np.testing.assert_allclose(C_kernel, C_ref, rtol=0, atol=1e-9 * np.abs(C_ref).max())
    v = np.random.default_rng(4).standard_normal(24)
    np.testing.assert_allclose(eom.damping_force(v), C_ref @ v, rtol=0, atol=1e-9 * np.abs(C_ref @ v).max())
    out = np.empty(24)
    bd.damping_product(eom.C_band, Cr, np.concatenate([np.zeros(5), v]), 5, out)
    np.testing.assert_allclose(out, C_ref @ v, rtol=0, atol=1e-9 * np.abs(C_ref @ v).max())


def test_banded_lu_with_several_right_hand_sides_and_woodbury():
    """factor_band + solve_factored solve a banded SPD system; the rank-k correction of the
    approximate analysis' Newton matrices (Woodbury) gives the dense solution."""
    rng = np.random.default_rng(9)
    nd = 30
    A = np.zeros((nd, nd))
    for i in range(nd):
        for j in range(max(0, i - 3), min(nd, i + 4)):
            A[i, j] = A[j, i] = rng.standard_normal()
    A += 12.0 * np.eye(nd)
    band = np.zeros((bd.band_rows(2), nd))
    for i in range(nd):
        for j in range(max(0, i - 3), min(nd, i + 4)):
            band[3 + i - j, j] = A[i, j]
    LU, x, b = np.empty_like(band), np.empty(nd), rng.standard_normal(nd)
    assert bd.factor_band(band, LU)
    bd.solve_factored(LU, b, x)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-12, atol=1e-14)
    V = rng.standard_normal((4, nd))
    for damping in (0.3, 0.0):  # no stiffness-proportional damping: D is singular
        D = np.diag([damping, 0.6 * damping, 0.0, 0.0])
        D[2:, 2:] = [[0.4, 0.1], [0.1, -0.25]]  # Gamma^-1 need not be definite
        out, Z = np.empty(nd), np.empty((4, nd))
        assert solve_band_low_rank(band, V, D, b, out, LU, Z, (np.empty((4, 4)), np.empty((4, 4))))
        np.testing.assert_allclose(out, np.linalg.solve(A - V.T @ D @ V, b), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("ratio", [0.02, 0.0])
def test_implicit_history_of_the_approximate_analysis_matches_an_explicit_one(ratio):
    """The O(n) Newton matrices (banded minus rank 4) give the same history as dopri5 on the
    third-order form, with and without damping (without, the damping's low-rank part is zero)."""
    from cablesim.dynamics.integrators import DOPRI5, GeneralizedAlpha
    from cablesim.dynamics.simulate import simulate

    case = parse_case(
        "cable: {L: 80.0, H: 30.0, length: 95.0, nodes: 12, EA: 2.0e7, mass_per_length: 3.0}\n"
        "loads: {gravity: 9.81, point: [{node: 4, FL: [200.0, 800.0]}]}\n"
        f"analysis: approximate\ndamping: {{ratio: {ratio}, modes: [1, 2]}}\n"
    )
    eom = build_equations(case, run_static(case, all_models=False), omega=3.0)
    assert eom.damping_low_rank.shape == (26, 2)
    ref = simulate(eom, DOPRI5(rtol=1e-10, atol=1e-12 * eom.cable.chord_length), 1.0, 0.05, split=False)
    got = simulate(eom, GeneralizedAlpha(dt=2e-4), 1.0, 0.05, split=False)
    assert ref.completed and got.completed
    scale = np.abs(ref.z).max()
    assert scale > 1e-3
    assert np.abs(got.z - ref.z).max() < 1e-4 * scale


def test_nearly_taut_cable_runs_to_the_end():
    """The paper's cable at 1.0001 times its chord (its segment flexibilities then span a wide
    range and Gamma is not definite): the factored product alone left |N (K v) - v| at up to
    6e-11 of |v| along the run, noise that stalled dopri5 at rtol 1e-8 at t = 5.09 s (step
    underflow); with one refinement step against the forward product the 300 s run ends, as it
    did with the full flexibility."""
    from cablesim.stress.cases import build_cases
    from cablesim.stress.run import OK, run_one

    case = next(c for c in build_cases() if c.label == "sag=1.0001")
    scheme = next(sc for an, sc in case.runs if an == "approximate")
    row = run_one(case, "approximate", scheme)
    assert row["outcome"] == OK, row.get("message")
