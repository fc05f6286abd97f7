"""The approximate analysis' stiffness K = N(P)^-1 in O(n) (block-tridiagonal minus rank 2)
against the inverse of the full flexibility N = D + f, and its natural and elastic states."""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics import flexibility as fx
from cablesim.dynamics import kernels as kn

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
    kn.cumulative_loads(P, Q)
    assert kn.closure_solve(c.S, Q, 0.0, c.L, c.H, F, 1e-13 * c.total_length, 60) >= 0
    return np.asarray(c.S, float), float(c.EA), Q, F


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("n", [1, 2, 7, 30])
def test_product_is_the_inverse_of_the_full_flexibility(name, n):
    S, EA, Q, F = solved(CASES[name], n, seed=n)
    x, u, T, N = np.empty(2 * n), np.empty(2 * n), np.empty(n + 1), np.empty((2 * n, 2 * n))
    kn.approximate_flexibility(S, EA, Q, F, x, u, T, N, kn.flexibility_workspace(n))  # the full N = D + f
    K_ref = np.linalg.inv(N)
    fac, gi, Fd = fx.factor_workspace(n)
    T2 = np.empty(n + 1)
    assert fx.segment_factors(S, EA, Q, F, T2, fac, gi)
    np.testing.assert_allclose(T2, T, rtol=1e-14)
    rng = np.random.default_rng(7)
    scale = np.abs(K_ref).max()
    for _ in range(3):
        v = rng.standard_normal(2 * n)
        out = np.empty(2 * n)
        fx.stiffness_product(fac, gi, v, out, Fd)
        # N is ill-conditioned (cond ~ EA / T), so compare within its conditioning
        np.testing.assert_allclose(out, K_ref @ v, rtol=0, atol=1e-7 * scale * np.abs(v).max())
        np.testing.assert_allclose(N @ out, v, rtol=0, atol=1e-9 * np.abs(v).max())
    K = np.empty((2 * n, 2 * n))
    fx.stiffness_dense(fac, gi, K)
    np.testing.assert_allclose(K, K.T, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(N @ K, np.eye(2 * n), rtol=0, atol=1e-9)
    assert np.linalg.eigvalsh(K).min() > 0.0  # a taut cable's stiffness is positive definite
    x2, u2 = np.empty(2 * n), np.empty(2 * n)
    fx.natural_and_elastic(S, EA, fac, T2, x2, u2)
    np.testing.assert_allclose(x2, x, rtol=0, atol=1e-12 * S.sum())
    np.testing.assert_allclose(u2, u, rtol=0, atol=1e-12 * np.abs(u).max())
