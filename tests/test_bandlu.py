"""The compiled banded LU (``cablesim.orbits.bandlu``) against numpy's dense solve.

Random band matrices whose diagonal is not dominant, so that rows are exchanged, in the
transposed band layout of the module; one right-hand side (``solve``, and ``solve_many`` with a
single column, which takes the vector's loops) and several (``solve_many``).
"""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.orbits import bandlu


def band_matrix(N: int, kl: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A dense ``(N, N)`` band matrix of half bandwidth ``kl`` and its band storage."""
    rng = np.random.default_rng(seed)
    A = np.zeros((N, N))
    for i in range(N):
        lo, hi = max(0, i - kl), min(N, i + kl + 1)
        A[i, lo:hi] = rng.standard_normal(hi - lo)
    kv = 2 * kl
    AB = np.zeros((N, bandlu.band_rows(kl, kl)))
    for j in range(N):
        for i in range(max(0, j - kl), min(N, j + kl + 1)):
            AB[j, kv + i - j] = A[i, j]
    return A, AB


@pytest.mark.parametrize("N, kl, seed", [(1, 0, 0), (7, 1, 1), (40, 3, 2), (300, 11, 3), (12, 11, 4)])
def test_band_solves_match_the_dense_solve(N, kl, seed):
    A, AB = band_matrix(N, kl, seed)
    piv = np.zeros(N, dtype=np.int64)
    assert bandlu.factor(AB, kl, kl, piv)
    if N > 1:
        assert np.any(piv != np.arange(N))  # the test exercises the row exchanges
    rng = np.random.default_rng(seed + 100)
    B = rng.standard_normal((N, 5))
    X = np.linalg.solve(A, B)
    tol = 1e-10 * np.linalg.cond(A)
    one = B[:, 0].copy()
    bandlu.solve(AB, kl, kl, piv, one)
    assert np.abs(one - X[:, 0]).max() <= tol * np.abs(X[:, 0]).max()
    single = B[:, :1].copy()
    bandlu.solve_many(AB, kl, kl, piv, single)
    assert np.abs(single[:, 0] - X[:, 0]).max() <= tol * np.abs(X[:, 0]).max()
    many = B.copy()
    bandlu.solve_many(AB, kl, kl, piv, many)
    assert np.abs(many - X).max() <= tol * np.abs(X).max()
