"""Banded LU factorization with partial pivoting (LAPACK's ``dgbtf2`` / ``dgbtrs``), compiled.

For the implicit Runge-Kutta stages of :mod:`cablesim.orbits.radau`, whose Newton matrix couples
the stages of each node: banded (half bandwidth ``kl = ku``) but not symmetric, so rows are
exchanged for stability. Storage is LAPACK's band layout transposed, so that a column's band is
contiguous in numpy's row-major order: ``AB[j, kl + ku + i - j] = A[i, j]``, with ``kl`` extra
places for the fill-in of the pivoting (shape ``(N, 2 kl + ku + 1)``); the factors overwrite
``AB`` and the row interchanges go to ``piv``. Cost O(N kl (kl + ku)) to factor and
O(N (2 kl + ku)) per right-hand side; :func:`solve_many` solves for several right-hand sides at
once (each factor entry read once for all of them).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit

__all__ = ["band_rows", "factor", "solve", "solve_many"]


@njit
def band_rows(kl, ku):
    """Entries per column of the storage of an ``(kl, ku)`` band matrix with room for the
    pivoting."""
    return 2 * kl + ku + 1


@njit
def factor(AB, kl, ku, piv):
    """LU factors of the band matrix in ``AB`` in place, ``piv[j]`` the row exchanged with row
    ``j``; False on a zero or non-finite pivot."""
    N = AB.shape[0]
    kv = kl + ku
    ju = 0
    for j in range(N):
        km = min(kl, N - 1 - j)
        col = AB[j]
        p = 0
        big = abs(col[kv])
        for d in range(1, km + 1):
            a = abs(col[kv + d])
            if a > big:
                big = a
                p = d
        piv[j] = j + p
        if big == 0.0 or not np.isfinite(big):
            return False
        ju = max(ju, min(j + p + ku, N - 1))
        if p != 0:
            for c in range(j, ju + 1):
                cc = AB[c]
                tmp = cc[kv + j - c]
                cc[kv + j - c] = cc[kv + j + p - c]
                cc[kv + j + p - c] = tmp
        rp = 1.0 / col[kv]
        lower = col[kv + 1 : kv + km + 1]
        for d in range(km):
            lower[d] *= rp
        for c in range(j + 1, ju + 1):
            off = kv + j - c
            ajc = AB[c, off]
            target = AB[c, off + 1 : off + km + 1]
            for d in range(km):
                target[d] -= lower[d] * ajc
    return True


@njit
def solve(AB, kl, ku, piv, b):
    """Solve ``A x = b`` in place with the factors of :func:`factor`."""
    N = AB.shape[0]
    kv = kl + ku
    # Plain loops without tests for zero entries: these short loops run faster unbranched.
    for j in range(N - 1):
        p = piv[j]
        if p != j:
            tmp = b[j]
            b[j] = b[p]
            b[p] = tmp
        bj = b[j]
        col = AB[j]
        for d in range(1, min(kl, N - 1 - j) + 1):
            b[j + d] -= col[kv + d] * bj
    for c in range(N - 1, -1, -1):
        col = AB[c]
        bc = b[c] / col[kv]
        b[c] = bc
        lo = max(0, c - kv)
        seg = b[lo:c]
        band = col[kv + lo - c : kv]
        for i in range(c - lo):
            seg[i] -= band[i] * bc


@njit
def solve_many(AB, kl, ku, piv, B):
    """Solve ``A X = B`` in place for the columns of ``B`` (N, q), C-contiguous."""
    N = AB.shape[0]
    kv = kl + ku
    q = B.shape[1]
    if q == 1:  # one right-hand side: the vector's loops run about twice as fast as q-loops of one
        solve(AB, kl, ku, piv, B.reshape(N))
        return
    for j in range(N - 1):
        p = piv[j]
        if p != j:
            for r in range(q):
                tmp = B[j, r]
                B[j, r] = B[p, r]
                B[p, r] = tmp
        col = AB[j]
        for d in range(1, min(kl, N - 1 - j) + 1):
            l = col[kv + d]
            if l != 0.0:
                for r in range(q):
                    B[j + d, r] -= l * B[j, r]
    for c in range(N - 1, -1, -1):
        col = AB[c]
        rd = 1.0 / col[kv]
        for r in range(q):
            B[c, r] *= rd
        for i in range(max(0, c - kv), c):
            u = col[kv + i - c]
            if u != 0.0:
                for r in range(q):
                    B[i, r] -= u * B[c, r]
