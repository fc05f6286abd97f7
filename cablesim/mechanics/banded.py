"""Banded storage: the stiffness, damping and Newton matrices of a finely divided cable.

The tangent stiffness couples each node to its neighbours only, so it is block-tridiagonal with
``DIM x DIM`` blocks (half bandwidth ``2 DIM - 1``: 3 for a planar cable, 5 for a spatial one),
and so are the Rayleigh damping ``C = a0 M + a1 K0`` and the Newton matrices of the implicit
schemes. Stored as LAPACK's general band layout, ``A_band[h + i - j, j] = A[i, j]`` with ``h``
the half bandwidth (shape ``(2 h + 1, n_dof)``, :func:`band_rows`), their products and solves
cost O(n) instead of O(n^2) and O(n^3). The half bandwidth is read from the array's shape
(:func:`half_band`). The compiled kernels take either a dense or a banded matrix
(:func:`damping_row`); :func:`is_band` tells them apart (a dense matrix is square; a band never
is, since its row count ``4 DIM - 1`` is not a multiple of ``DIM``).
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

def band_half(dim: int) -> int:
    """Half bandwidth of a block-tridiagonal matrix of ``dim x dim`` blocks: ``2 dim - 1``."""
    return 2 * dim - 1


def band_rows(dim: int) -> int:
    """Rows of its general band storage, ``2 band_half(dim) + 1``."""
    return 2 * band_half(dim) + 1


@njit(inline="always")
def half_band(A):
    """The half bandwidth of a matrix in general band storage (``(A.shape[0] - 1) / 2``)."""
    return (A.shape[0] - 1) // 2


@njit
def is_band(A):
    """Whether ``A`` is in banded storage, shape ``(2 h + 1, nd)``, rather than dense (nd, nd)."""
    return A.shape[0] != A.shape[1]


@njit
def damping_row(C, s, off, i):
    """Row ``i`` of ``C`` times ``s[off:off + nd]``: C dense (nd, nd), O(n), or banded
    (2 h + 1, nd), O(h)."""
    nd = C.shape[1]
    acc = 0.0
    if is_band(C):
        hb = half_band(C)
        for j in range(max(0, i - hb), min(nd, i + hb + 1)):
            acc += C[hb + i - j, j] * s[off + j]
    else:
        for j in range(nd):
            acc += C[i, j] * s[off + j]
    return acc


def band_storage(lower: np.ndarray) -> np.ndarray:
    """The ``(2 h + 1, nd)`` general band storage of a symmetric matrix given in lower band form
    (``lower[d, j] = A[j + d, j]``, ``d = 0 .. h``)."""
    hb = lower.shape[0] - 1
    nd = lower.shape[1]
    C = np.zeros((2 * hb + 1, nd))
    for d in range(min(lower.shape[0], nd)):
        C[hb + d, : nd - d] = lower[d, : nd - d]  # below the diagonal: A[j + d, j]
        C[hb - d, d:] = lower[d, : nd - d]  # above: A[j, j + d]
    return C


def band_product(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``A x`` for ``A`` in banded storage (as :func:`damping_row`), O(n), vectorised."""
    nd = x.size
    hb = (A.shape[0] - 1) // 2
    y = np.zeros(nd)
    for r in range(A.shape[0]):
        d = r - hb  # row index minus column index of this diagonal
        if abs(d) >= nd:  # a diagonal outside a small matrix (one node: 2 DOF)
            continue
        if d >= 0:
            y[d:] += A[r, : nd - d] * x[: nd - d]
        else:
            y[: nd + d] += A[r, -d:] * x[-d:]
    return y


@njit
def band_row(A, x, i):
    """Row ``i`` of the banded ``A`` (storage as :func:`damping_row`) times ``x``."""
    nd = A.shape[1]
    hb = half_band(A)
    acc = 0.0
    for j in range(max(0, i - hb), min(nd, i + hb + 1)):
        acc += A[hb + i - j, j] * x[j]
    return acc


@njit
def factor_band(A, LU):
    """LU factors of a banded ``A`` (storage as :func:`damping_row`) into ``LU`` by Gaussian
    elimination without pivoting, O(n): the multipliers below the diagonal, U on and above.

    For the symmetric positive definite Newton matrices of the implicit schemes
    (``c_m M + c_c C + K`` of a taut cable). Returns False on a zero or non-finite pivot.
    """
    nd = A.shape[1]
    hb = half_band(A)
    LU[:, :] = A
    for k in range(nd):
        piv = LU[hb, k]
        if piv == 0.0 or not np.isfinite(piv):
            return False
        for i in range(k + 1, min(nd, k + hb + 1)):
            f = LU[hb + i - k, k] / piv
            LU[hb + i - k, k] = f
            if f != 0.0:
                for j in range(k + 1, min(nd, k + hb + 1)):
                    LU[hb + i - j, j] -= f * LU[hb + k - j, j]
    return True


@njit
def solve_factored(LU, b, out):
    """Solve ``A out = b`` with the factors of :func:`factor_band`, O(n)."""
    nd = b.size
    hb = half_band(LU)
    out[:] = b
    for k in range(nd):
        for i in range(k + 1, min(nd, k + hb + 1)):
            out[i] -= LU[hb + i - k, k] * out[k]
    for i in range(nd - 1, -1, -1):
        acc = out[i]
        for j in range(i + 1, min(nd, i + hb + 1)):
            acc -= LU[hb + i - j, j] * out[j]
        out[i] = acc / LU[hb, i]


@njit
def solve_band(A, b, out, LU):
    """Solve ``A out = b`` for a banded ``A`` (:func:`factor_band`, then :func:`solve_factored`);
    False on a zero or non-finite pivot."""
    if not factor_band(A, LU):
        return False
    solve_factored(LU, b, out)
    return True


@njit
def damping_product(C, Cr, x, off, out):
    """``out = (C - U G U^T) x[off:off + nd]``: ``C`` dense or banded (:func:`damping_row`) and
    ``Cr = [U; G]`` (nd + r, r) its low-rank part (r = 0, or 2 for the approximate analysis,
    whose ``K0`` is banded minus rank 2); O(n) when ``C`` is banded."""
    nd = out.size
    r = Cr.shape[1]
    for i in range(nd):
        out[i] = damping_row(C, x, off, i)
    if r == 0:  # no low-rank part (exact analysis): no scratch either, this is the time loop
        return
    w = np.zeros(r)
    for c in range(r):
        for j in range(nd):
            w[c] += Cr[j, c] * x[off + j]
    for c in range(r):
        g = 0.0
        for d in range(r):
            g += Cr[nd + c, d] * w[d]
        for i in range(nd):
            out[i] -= Cr[i, c] * g
