"""The segment law: geometry, tension and tangent block of one straight segment.

A cable of ``n`` interior nodes has ``n + 1`` segments. Nodes are numbered ``0 .. n-1`` (their
coordinates are ``y[DIM j : DIM (j + 1)]``), node ``-1`` is support A and node ``n`` support B;
segment ``k`` (``0 .. n``) joins node ``k - 1`` to node ``k``. With ``d`` the segment's vector,
``l = |d|`` its length, ``e = d / l`` its unit vector and ``S`` its natural length:

- tension (paper eq. 1 with Hooke's law): ``T = EA (l - S) / S``, negative when the segment is
  shorter than ``S``; the cable is tension-only, so a segment is *taut* (carries ``T``) or
  *slack* (carries nothing), as its mode says (:data:`taut`, 1 or 0);
- tangent block (``DIM x DIM``, N/m): ``k = (EA/S) e e^T + (T/l) (I - e e^T)``, here written
  ``k = kg I + (ka - kg) e e^T`` with ``ka = EA/S`` (axial) and ``kg = T/l`` (geometric).

This module is the only place where these laws are written; every assembly (forces, stiffness
products, dense and banded tangents, the orbits' Jacobians, slack events) calls it. Vectors are
tuples of ``DIM`` components (:mod:`cablesim.mechanics.vectors`): ``DIM = len(A)``.
"""

from __future__ import annotations

import math

from ..jit import njit
from .vectors import vcombo, vdiv, vdot, vload, vsub, vzero


@njit(inline="always")
def node(y, j, n, A, B):
    """Coordinates of node ``j`` (``-1``: support A, ``n``: support B), m."""
    if j < 0:
        return A
    if j >= n:
        return B
    return vload(y, len(A) * j, A)


@njit(inline="always")
def node_rate(v, j, n, vA, vB):
    """Velocity (or any rate) of node ``j``, with the supports' ``vA`` and ``vB``."""
    if j < 0:
        return vA
    if j >= n:
        return vB
    return vload(v, len(vA) * j, vA)


@njit(inline="always")
def segment_vector(y, k, n, A, B):
    """``d = node k - node (k - 1)``, m."""
    return vsub(node(y, k, n, A, B), node(y, k - 1, n, A, B))


@njit(inline="always")
def length(d):
    """``l = |d|``, m."""
    return math.sqrt(vdot(d, d))


@njit(inline="always")
def tension_of_stretch(stretch, S, EA):
    """The constitutive law: ``T = EA (l - S) / S`` from the stretch ``l - S``, N (negative for
    a segment shorter than its natural length)."""
    return EA * stretch / S


@njit(inline="always")
def tension(l, S, EA):
    """``T = EA (l - S) / S`` of a segment of length ``l``, N."""
    return tension_of_stretch(l - S, S, EA)


@njit(inline="always")
def displaced_stretch(d0, dd, l, S):
    """``l - S`` of a segment whose vector ``d0`` (at a reference state) changed by ``dd``:
    ``(|d0|^2 - S^2 + 2 d0.dd + dd.dd) / (l + S)``. A small change then keeps its full relative
    precision instead of the round-off of ``|d0 + dd| - S`` (about 1e-14 of the coordinates)."""
    num = (vdot(d0, d0) - S * S) + 2.0 * vdot(d0, dd) + vdot(dd, dd)
    return num / (l + S)


@njit(inline="always")
def block_coefficients(l, T, S, EA, taut):
    """``(ka, kg)`` of the tangent block ``kg I + (ka - kg) e e^T`` of a segment in mode ``taut``
    (1 taut, 0 slack; ``T`` already multiplied by it), N/m."""
    return taut * EA / S, T / l


@njit(inline="always")
def block_times(ka, kg, e, dv):
    """``k dv = kg dv + (ka - kg) (e . dv) e`` (the tangent block times a relative rate)."""
    return vcombo(dv, e, kg, (ka - kg) * vdot(e, dv))


@njit(inline="always")
def block_entry(ka, kg, e, r, c):
    """Entry ``(r, c)`` of the tangent block ``kg I + (ka - kg) e e^T``, N/m (the same rounding
    for ``(r, c)`` and ``(c, r)``: the block is exactly symmetric)."""
    if r == c:
        return kg + (ka - kg) * e[r] * e[r]
    lo, hi = min(r, c), max(r, c)
    return (ka - kg) * e[lo] * e[hi]


@njit
def gaps(y, S, A, B, g):
    """``g[k] = l_k - S_k`` of every segment of configuration ``y`` (negative: shorter than its
    natural length), m."""
    n = S.size - 1
    for k in range(n + 1):
        g[k] = length(segment_vector(y, k, n, A, B)) - S[k]


@njit
def gap(y, k, S, A, B):
    """``l_k - S_k`` of segment ``k``, m."""
    return length(segment_vector(y, k, S.size - 1, A, B)) - S[k]


@njit
def taut_modes(y, S, A, B, taut):
    """``taut[k] = 1`` where segment ``k`` is longer than its natural length, else 0 (slack)."""
    n = S.size - 1
    for k in range(n + 1):
        taut[k] = 1.0 if length(segment_vector(y, k, n, A, B)) > S[k] else 0.0


@njit
def tensions(y, S, EA, A, B, T):
    """``T[k] = EA (l_k - S_k) / S_k`` (signed); returns the first segment not longer than its
    natural length, or -1."""
    n = S.size - 1
    slack = -1
    for k in range(n + 1):
        T[k] = tension(length(segment_vector(y, k, n, A, B)), S[k], EA)
        if T[k] <= 0.0 and slack < 0:
            slack = k
    return slack


@njit
def zero_rate(A):
    """The rate of a fixed support: zero, with ``len(A)`` components."""
    return vzero(A)


@njit
def segment_states(y, S, EA, A, B, lengths, e, T):
    """Lengths ``l_k`` (m), unit vectors ``e_k`` (rows of ``e``, (n + 1, DIM)) and signed
    tensions ``T_k = EA (l_k - S_k) / S_k`` (N) of every segment of configuration ``y``."""
    dim = len(A)
    n = S.size - 1
    for k in range(n + 1):
        d = segment_vector(y, k, n, A, B)
        l = length(d)
        lengths[k] = l
        T[k] = tension(l, S[k], EA)
        for c in range(dim):
            e[k, c] = d[c] / l


@njit
def segment_block(y, k, S, EA, A, B, out):
    """Segment ``k``'s tangent block ``(EA/S) e e^T + (T/l)(I - e e^T)`` in configuration ``y``
    (taut) into ``out`` (DIM x DIM), N/m."""
    dim = len(A)
    n = S.size - 1
    d = segment_vector(y, k, n, A, B)
    l = length(d)
    e = vdiv(d, l)
    ka, kg = block_coefficients(l, tension(l, S[k], EA), S[k], EA, 1.0)
    for r in range(dim):
        for c in range(dim):
            out[r, c] = block_entry(ka, kg, e, r, c)
