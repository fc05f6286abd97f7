"""Small vectors and matrices of ``DIM`` components as tuples, for the compiled mechanics.

A node's position, a segment's unit vector or a support's displacement is a tuple of ``DIM``
floats (``DIM = 2`` for a planar cable, 3 for a spatial one); a ``DIM x DIM`` block is a flat
tuple of ``DIM * DIM`` floats, row-major. The number of components is part of the tuple's type,
so numba compiles each function once per ``DIM``, with every loop over components unrolled and
every component in a register: the mechanics is written once, for any ``DIM``, at the speed of
code written out by hand for two components (the arithmetic, and so every rounding, is the same).

The operations are implemented for 2 and 3 components (:func:`numba.extending.overload` picks
the implementation from the tuple's length at compile time); ``len(v)`` of such a tuple is a
compile-time constant. Called from Python they are plain functions on tuples (the tests use them).
"""

from __future__ import annotations

import math

from numba.extending import overload

#: Numbers of components the operations are written for.
SUPPORTED_DIMS = (2, 3)


def _count(typ) -> int:
    n = getattr(typ, "count", None)
    if n not in SUPPORTED_DIMS and n not in tuple(d * d for d in SUPPORTED_DIMS):
        raise TypeError(f"cablesim vectors have 2 or 3 components (blocks 4 or 9), not {n}")
    return n


# ----------------------------------------------------------------------------------------------
# Vectors. The Python definitions serve calls from Python; inside compiled code each name is
# replaced by its overload for the tuple's length.
# ----------------------------------------------------------------------------------------------
def vload(a, i, like):
    """``(a[i], ..., a[i + DIM - 1])``, ``DIM = len(like)``."""
    return tuple(float(a[i + d]) for d in range(len(like)))


def vrow(Q, k, like):
    """Row ``k`` of the 2-D array ``Q`` as a vector of ``len(like)`` components."""
    return tuple(float(Q[k, d]) for d in range(len(like)))


def vstore(a, i, v):
    """``a[i + d] = v[d]``."""
    for d in range(len(v)):
        a[i + d] = v[d]


def vadd_to(a, i, v, s):
    """``a[i + d] += s * v[d]``."""
    for d in range(len(v)):
        a[i + d] += s * v[d]


def vzero(like):
    """The zero vector of ``len(like)`` components."""
    return tuple(0.0 for _ in like)


def vadd(a, b):
    """``a + b``."""
    return tuple(x + y for x, y in zip(a, b))


def vsub(a, b):
    """``a - b``."""
    return tuple(x - y for x, y in zip(a, b))


def vscale(a, s):
    """``a * s`` (each component times ``s``)."""
    return tuple(x * s for x in a)


def vdiv(a, s):
    """``a / s`` (each component divided by ``s``: not the same rounding as ``a * (1/s)``)."""
    return tuple(x / s for x in a)


def vcombo(a, b, sa, sb):
    """``sa a + sb b``."""
    return tuple(sa * x + sb * y for x, y in zip(a, b))


def vdot(a, b):
    """``a . b``, summed in component order."""
    acc = 0.0
    for x, y in zip(a, b):
        acc += x * y
    return acc


def vnorm(a):
    """``|a|``."""
    return math.sqrt(vdot(a, a))


def vmaxabs(a):
    """``max_d |a_d|``."""
    return max(abs(x) for x in a)


def vnormal(a, e):
    """``a - e (e . a)``: the part of ``a`` normal to the unit vector ``e``."""
    c = vdot(e, a)
    return tuple(x - u * c for x, u in zip(a, e))


# ----------------------------------------------------------------------------------------------
# DIM x DIM blocks (flat, row-major)
# ----------------------------------------------------------------------------------------------
def mzero(like):
    """The zero block of ``len(like)`` x ``len(like)``."""
    return tuple(0.0 for _ in range(len(like) ** 2))


def madd_outer(m, a, b, s):
    """``m + s a b^T``."""
    n = len(a)
    return tuple(m[r * n + c] + s * a[r] * b[c] for r in range(n) for c in range(n))


def madd_diag(m, s):
    """``m + s I``."""
    n = int(round(math.sqrt(len(m))))
    return tuple(m[k] + (s if k % (n + 1) == 0 else 0.0) for k in range(len(m)))


def vunit(like, c):
    """The unit vector along axis ``c``, with ``len(like)`` components."""
    return tuple(1.0 if d == c else 0.0 for d in range(len(like)))


def mload(a, i, like):
    """The flat ``DIM x DIM`` block stored in ``a[i : i + DIM^2]``."""
    return tuple(float(a[i + k]) for k in range(len(like) ** 2))


def mstore(a, i, m):
    """``a[i + k] = m[k]`` for the entries of a block."""
    for k in range(len(m)):
        a[i + k] = m[k]


def madd(a, b):
    """``a + b`` (blocks)."""
    return tuple(x + y for x, y in zip(a, b))


def mblock(wt, we, e):
    """``wt (I - e e^T) + we e e^T`` for the unit vector ``e``: a segment's block with weight
    ``wt`` across it and ``we`` along it. The diagonal of ``I - e e^T`` is taken as the sum of
    the other components squared (``1 - e_r^2`` would cancel for a segment along an axis)."""
    n = len(e)
    out = []
    for r in range(n):
        for c in range(n):
            if r == c:
                out.append(sum(wt * e[s] * e[s] for s in range(n) if s != r) + we * e[r] * e[r])
            else:
                lo, hi = min(r, c), max(r, c)
                out.append((we - wt) * e[lo] * e[hi])
    return tuple(out)


def mvec(m, v):
    """``m v``."""
    n = len(v)
    return tuple(sum(m[r * n + c] * v[c] for c in range(n)) for r in range(n))


def mtrace(m):
    """``tr m``."""
    n = int(round(math.sqrt(len(m))))
    return sum(m[k * (n + 1)] for k in range(n))


def mdet(m):
    """``det m``."""
    if len(m) == 4:
        return m[0] * m[3] - m[1] * m[2]
    return (m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
            + m[2] * (m[3] * m[7] - m[4] * m[6]))


def msym_inverse(m):
    """The inverse of the symmetric block ``m`` (cofactors over the determinant)."""
    if len(m) == 4:
        det = m[0] * m[3] - m[1] * m[1]
        return (m[3] / det, -m[1] / det, -m[1] / det, m[0] / det)
    a, b, c, d, e, f = m[0], m[1], m[2], m[4], m[5], m[8]
    c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
    c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * c00 + b * c01 + c * c02
    return (c00 / det, c01 / det, c02 / det, c01 / det, c11 / det, c12 / det, c02 / det, c12 / det, c22 / det)


def msym_solve(m, v):
    """``m^-1 v`` for the symmetric block ``m``."""
    if len(m) == 4:
        det = m[0] * m[3] - m[1] * m[1]
        return ((m[3] * v[0] - m[1] * v[1]) / det, (m[0] * v[1] - m[1] * v[0]) / det)
    return mvec(msym_inverse(m), v)


# ----------------------------------------------------------------------------------------------
# The compiled implementations
# ----------------------------------------------------------------------------------------------
@overload(vload)
def _vload(a, i, like):
    if _count(like) == 2:
        return lambda a, i, like: (a[i], a[i + 1])
    return lambda a, i, like: (a[i], a[i + 1], a[i + 2])


@overload(vrow)
def _vrow(Q, k, like):
    if _count(like) == 2:
        return lambda Q, k, like: (Q[k, 0], Q[k, 1])
    return lambda Q, k, like: (Q[k, 0], Q[k, 1], Q[k, 2])


@overload(vstore)
def _vstore(a, i, v):
    if _count(v) == 2:
        def impl2(a, i, v):
            a[i] = v[0]
            a[i + 1] = v[1]
        return impl2

    def impl3(a, i, v):
        a[i] = v[0]
        a[i + 1] = v[1]
        a[i + 2] = v[2]
    return impl3


@overload(vadd_to)
def _vadd_to(a, i, v, s):
    if _count(v) == 2:
        def impl2(a, i, v, s):
            a[i] += s * v[0]
            a[i + 1] += s * v[1]
        return impl2

    def impl3(a, i, v, s):
        a[i] += s * v[0]
        a[i + 1] += s * v[1]
        a[i + 2] += s * v[2]
    return impl3


@overload(vzero)
def _vzero(like):
    if _count(like) == 2:
        return lambda like: (0.0, 0.0)
    return lambda like: (0.0, 0.0, 0.0)


@overload(vadd)
def _vadd(a, b):
    if _count(a) == 2:
        return lambda a, b: (a[0] + b[0], a[1] + b[1])
    return lambda a, b: (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@overload(vsub)
def _vsub(a, b):
    if _count(a) == 2:
        return lambda a, b: (a[0] - b[0], a[1] - b[1])
    return lambda a, b: (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@overload(vscale)
def _vscale(a, s):
    if _count(a) == 2:
        return lambda a, s: (a[0] * s, a[1] * s)
    return lambda a, s: (a[0] * s, a[1] * s, a[2] * s)


@overload(vdiv)
def _vdiv(a, s):
    if _count(a) == 2:
        return lambda a, s: (a[0] / s, a[1] / s)
    return lambda a, s: (a[0] / s, a[1] / s, a[2] / s)


@overload(vcombo)
def _vcombo(a, b, sa, sb):
    if _count(a) == 2:
        return lambda a, b, sa, sb: (sa * a[0] + sb * b[0], sa * a[1] + sb * b[1])
    return lambda a, b, sa, sb: (sa * a[0] + sb * b[0], sa * a[1] + sb * b[1], sa * a[2] + sb * b[2])


@overload(vdot)
def _vdot(a, b):
    if _count(a) == 2:
        return lambda a, b: a[0] * b[0] + a[1] * b[1]
    return lambda a, b: a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@overload(vnorm)
def _vnorm(a):
    if _count(a) == 2:
        return lambda a: math.sqrt(a[0] * a[0] + a[1] * a[1])
    return lambda a: math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@overload(vmaxabs)
def _vmaxabs(a):
    if _count(a) == 2:
        return lambda a: max(abs(a[0]), abs(a[1]))
    return lambda a: max(abs(a[0]), abs(a[1]), abs(a[2]))


@overload(vnormal)
def _vnormal(a, e):
    if _count(a) == 2:
        def impl2(a, e):
            c = e[0] * a[0] + e[1] * a[1]
            return (a[0] - e[0] * c, a[1] - e[1] * c)
        return impl2

    def impl3(a, e):
        c = e[0] * a[0] + e[1] * a[1] + e[2] * a[2]
        return (a[0] - e[0] * c, a[1] - e[1] * c, a[2] - e[2] * c)
    return impl3


@overload(mzero)
def _mzero(like):
    if _count(like) == 2:
        return lambda like: (0.0, 0.0, 0.0, 0.0)
    return lambda like: (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@overload(madd_outer)
def _madd_outer(m, a, b, s):
    if _count(a) == 2:
        return lambda m, a, b, s: (m[0] + s * a[0] * b[0], m[1] + s * a[0] * b[1],
                                   m[2] + s * a[1] * b[0], m[3] + s * a[1] * b[1])
    return lambda m, a, b, s: (m[0] + s * a[0] * b[0], m[1] + s * a[0] * b[1], m[2] + s * a[0] * b[2],
                               m[3] + s * a[1] * b[0], m[4] + s * a[1] * b[1], m[5] + s * a[1] * b[2],
                               m[6] + s * a[2] * b[0], m[7] + s * a[2] * b[1], m[8] + s * a[2] * b[2])


@overload(madd_diag)
def _madd_diag(m, s):
    if _count(m) == 4:
        return lambda m, s: (m[0] + s, m[1], m[2], m[3] + s)
    return lambda m, s: (m[0] + s, m[1], m[2], m[3], m[4] + s, m[5], m[6], m[7], m[8] + s)


@overload(vunit)
def _vunit(like, c):
    if _count(like) == 2:
        return lambda like, c: (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0)
    return lambda like, c: (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0, 1.0 if c == 2 else 0.0)


@overload(mload)
def _mload(a, i, like):
    if _count(like) == 2:
        return lambda a, i, like: (a[i], a[i + 1], a[i + 2], a[i + 3])
    return lambda a, i, like: (a[i], a[i + 1], a[i + 2], a[i + 3], a[i + 4], a[i + 5], a[i + 6], a[i + 7], a[i + 8])


@overload(mstore)
def _mstore(a, i, m):
    n = _count(m)

    def impl(a, i, m):
        for k in range(n):
            a[i + k] = m[k]
    return impl


@overload(madd)
def _madd(a, b):
    if _count(a) == 4:
        return lambda a, b: (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3])
    return lambda a, b: (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5],
                         a[6] + b[6], a[7] + b[7], a[8] + b[8])


@overload(mblock)
def _mblock(wt, we, e):
    if _count(e) == 2:
        def impl2(wt, we, e):
            c = (we - wt) * e[0] * e[1]
            return (wt * e[1] * e[1] + we * e[0] * e[0], c, c, wt * e[0] * e[0] + we * e[1] * e[1])
        return impl2

    def impl3(wt, we, e):
        c01 = (we - wt) * e[0] * e[1]
        c02 = (we - wt) * e[0] * e[2]
        c12 = (we - wt) * e[1] * e[2]
        return (wt * e[1] * e[1] + wt * e[2] * e[2] + we * e[0] * e[0], c01, c02,
                c01, wt * e[0] * e[0] + wt * e[2] * e[2] + we * e[1] * e[1], c12,
                c02, c12, wt * e[0] * e[0] + wt * e[1] * e[1] + we * e[2] * e[2])
    return impl3


@overload(mvec)
def _mvec(m, v):
    if _count(v) == 2:
        return lambda m, v: (m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1])
    return lambda m, v: (m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
                         m[6] * v[0] + m[7] * v[1] + m[8] * v[2])


@overload(mtrace)
def _mtrace(m):
    if _count(m) == 4:
        return lambda m: m[0] + m[3]
    return lambda m: m[0] + m[4] + m[8]


@overload(mdet)
def _mdet(m):
    if _count(m) == 4:
        return lambda m: m[0] * m[3] - m[1] * m[2]
    return lambda m: (m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
                      + m[2] * (m[3] * m[7] - m[4] * m[6]))


@overload(msym_inverse)
def _msym_inverse(m):
    if _count(m) == 4:
        def impl2(m):
            det = m[0] * m[3] - m[1] * m[1]
            return (m[3] / det, -m[1] / det, -m[1] / det, m[0] / det)
        return impl2

    def impl3(m):
        a, b, c, d, e, f = m[0], m[1], m[2], m[4], m[5], m[8]
        c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
        c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
        det = a * c00 + b * c01 + c * c02
        return (c00 / det, c01 / det, c02 / det, c01 / det, c11 / det, c12 / det, c02 / det, c12 / det, c22 / det)
    return impl3


@overload(msym_solve)
def _msym_solve(m, v):
    if _count(m) == 4:
        def impl2(m, v):
            det = m[0] * m[3] - m[1] * m[1]
            return ((m[3] * v[0] - m[1] * v[1]) / det, (m[0] * v[1] - m[1] * v[0]) / det)
        return impl2

    def impl3(m, v):
        return mvec(msym_inverse(m), v)
    return impl3
