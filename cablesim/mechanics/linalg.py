"""Small dense linear systems inside compiled loops, where a LAPACK call costs more than the
arithmetic (the Newton systems of a few-node cable, the inner solves of the orbits)."""

from __future__ import annotations

from ..jit import njit


@njit
def solve_small(A, b, out, LU):
    """Solve ``A out = b`` by Gaussian elimination with partial pivoting into scratch ``LU``.

    For the small dense systems of the time loop, where a LAPACK call costs more than the
    arithmetic. Returns False if ``A`` is singular.
    """
    m = b.size
    LU[:, :] = A
    out[:] = b
    for k in range(m):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, m):
            if abs(LU[i, k]) > big:
                big = abs(LU[i, k])
                p = i
        if big == 0.0:
            return False
        if p != k:
            for j in range(m):
                tmp = LU[k, j]
                LU[k, j] = LU[p, j]
                LU[p, j] = tmp
            tmp = out[k]
            out[k] = out[p]
            out[p] = tmp
        piv = LU[k, k]
        for i in range(k + 1, m):
            f = LU[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, m):
                    LU[i, j] -= f * LU[k, j]
                out[i] -= f * out[k]
    for i in range(m - 1, -1, -1):
        acc = out[i]
        for j in range(i + 1, m):
            acc -= LU[i, j] * out[j]
        out[i] = acc / LU[i, i]
    return True
