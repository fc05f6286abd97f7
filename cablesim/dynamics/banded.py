"""Banded storage for heavy cables: the damping and Newton matrices of a finely divided cable.

The tangent stiffness of the exact analysis couples each node to its neighbours only, so it
is block-tridiagonal with 2x2 blocks (bandwidth 3), and so are the Rayleigh damping
``C = a0 M + a1 K0`` and the Newton matrices of the implicit schemes. Stored as LAPACK's general
band layout, ``A_band[BAND_HALF + i - j, j] = A[i, j]`` (shape (:data:`BAND_ROWS`, 2n)), their
products and solves cost O(n) instead of O(n^2) and O(n^3). The compiled kernels take either a
dense or a banded damping matrix (:func:`damping_row`); :func:`is_band` tells them apart.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

#: Rows of a damping matrix in banded storage (bandwidth 3: block-tridiagonal 2x2 blocks):
#: ``C_band[3 + i - j, j] = C[i, j]`` (LAPACK's general band layout). The DOF count is even, so a
#: (7, 2n) band is never mistaken for a square dense matrix.
BAND_ROWS = 7
BAND_HALF = 3


@njit
def is_band(A):
    """Whether ``A`` is in banded storage (shape (BAND_ROWS, nd)) rather than dense (nd, nd)."""
    return A.shape[0] == BAND_ROWS and A.shape[1] != BAND_ROWS


@njit
def damping_row(C, s, off, i):
    """Row ``i`` of ``C`` times ``s[off:off + nd]``: C dense (nd, nd), O(n), or banded
    (:data:`BAND_ROWS`, nd), O(1)."""
    nd = C.shape[1]
    acc = 0.0
    if is_band(C):
        for j in range(max(0, i - BAND_HALF), min(nd, i + BAND_HALF + 1)):
            acc += C[BAND_HALF + i - j, j] * s[off + j]
    else:
        for j in range(nd):
            acc += C[i, j] * s[off + j]
    return acc


def band_storage(lower: np.ndarray) -> np.ndarray:
    """The (:data:`BAND_ROWS`, nd) banded storage of a symmetric matrix given in lower band form
    (``lower[d, j] = A[j + d, j]``, d = 0..3)."""
    nd = lower.shape[1]
    C = np.zeros((BAND_ROWS, nd))
    for d in range(min(lower.shape[0], nd)):
        C[BAND_HALF + d, : nd - d] = lower[d, : nd - d]  # below the diagonal: A[j + d, j]
        C[BAND_HALF - d, d:] = lower[d, : nd - d]  # above: A[j, j + d]
    return C


def band_product(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``A x`` for ``A`` in banded storage (as :func:`damping_row`), O(n), vectorised."""
    nd = x.size
    y = np.zeros(nd)
    for r in range(BAND_ROWS):
        d = r - BAND_HALF  # row index minus column index of this diagonal
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
    acc = 0.0
    for j in range(max(0, i - BAND_HALF), min(nd, i + BAND_HALF + 1)):
        acc += A[BAND_HALF + i - j, j] * x[j]
    return acc


@njit
def factor_band(A, LU):
    """LU factors of a banded ``A`` (storage as :func:`damping_row`) into ``LU`` by Gaussian
    elimination without pivoting, O(n): the multipliers below the diagonal, U on and above.

    For the symmetric positive definite Newton matrices of the implicit schemes
    (``c_m M + c_c C + K`` of a taut cable). Returns False on a zero or non-finite pivot.
    """
    nd = A.shape[1]
    hb = BAND_HALF
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
    hb = BAND_HALF
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
