"""Assembly of the segments into the cable's resisting force and tangent stiffness.

The resisting force at interior node ``j`` is ``P_j = T_j e_j - T_(j+1) e_(j+1)`` (paper eqs.
2-3: segment ``j`` ends at node ``j``, segment ``j + 1`` starts there), and the tangent stiffness
``K = dP/dy`` is block-tridiagonal: segment ``k``'s block (:mod:`cablesim.mechanics.segments`)
is added to the diagonal blocks of its two end nodes and subtracted from their coupling; the
blocks of the supports are dropped. Each segment counts as its mode says (``taut[k]`` = 1 taut,
0 slack): a slack segment contributes neither force nor stiffness, a taut one acts as a linear
spring even if (within a step, before its event is located) it is a little shorter than ``S``.

Forms, all O(n) but the dense one:

- :func:`force_and_rate`: ``P(y)`` and the product ``K(y) v`` without a matrix, where ``v``
  holds the node velocities and ``vA``, ``vB`` the supports' (so that with moving supports the
  product is the whole rate ``dP/dt``);
- :func:`force_and_stiffness`: ``P(y)`` and the dense ``K(y)``;
- :func:`force_and_stiffness_band`: ``P(y)`` and ``K(y)`` in general band storage
  (:mod:`cablesim.mechanics.banded`, half bandwidth ``2 DIM - 1``);
- :func:`displaced_force_and_stiffness`: the same for a displacement ``z`` from a reference
  configuration ``y0``, with each stretch computed from the change of its segment vector
  (:func:`~cablesim.mechanics.segments.displaced_stretch`): the orbits' vector field, whose small
  orbits need the force to full relative precision; ``K`` goes into a block of a Jacobian.

Every function returns the first segment not longer than its natural length, or -1. Vectors are
tuples of ``DIM = len(A)`` components.
"""

from __future__ import annotations

from ..jit import njit
from .segments import (block_coefficients, block_entry, block_times, displaced_stretch, length, node,
                       node_rate, segment_vector, tension, tension_of_stretch)
from .vectors import madd_diag, madd_outer, mzero, vadd, vadd_to, vdiv, vsub


@njit
def force_and_rate(y, v, S, EA, A, B, vA, vB, taut, P, Kv):
    """Resisting force ``P(y)`` and the product ``K(y) v`` of the segments in their modes ``taut``.

    Parameters
    ----------
    y, v : ndarray (n DIM,)
        Node coordinates (m) and velocities (m/s, or any rate).
    S : ndarray (n + 1,)
        Natural segment lengths, m.
    EA : float
        Axial rigidity, N.
    A, B : tuple of DIM floats
        Support positions, m.
    vA, vB : tuple of DIM floats
        Support velocities (zero for fixed supports).
    taut : ndarray (n + 1,)
        Segment modes, 1 (taut) or 0 (slack).
    P, Kv : ndarray (n DIM,)
        Receive the force (N) and the product (N/s for velocities).
    """
    dim = len(A)
    n = S.size - 1
    P[:] = 0.0
    Kv[:] = 0.0
    slack = -1
    for k in range(n + 1):
        d = segment_vector(y, k, n, A, B)
        l = length(d)
        e = vdiv(d, l)
        T = tension(l, S[k], EA)
        if T <= 0.0 and slack < 0:
            slack = k
        T *= taut[k]
        dv = vsub(node_rate(v, k, n, vA, vB), node_rate(v, k - 1, n, vA, vB))
        ka, kg = block_coefficients(l, T, S[k], EA, taut[k])
        r = block_times(ka, kg, e, dv)
        if k < n:  # the segment ends at node k
            vadd_to(P, dim * k, e, T)
            vadd_to(Kv, dim * k, r, 1.0)
        if k > 0:  # and starts at node k - 1
            vadd_to(P, dim * (k - 1), e, -T)
            vadd_to(Kv, dim * (k - 1), r, -1.0)
    return slack


@njit
def force_and_stiffness(y, S, EA, A, B, taut, P, K):
    """Resisting force ``P(y)`` and the dense tangent stiffness ``K(y)`` (n DIM, n DIM), N/m."""
    dim = len(A)
    n = S.size - 1
    P[:] = 0.0
    K[:, :] = 0.0
    slack = -1
    for k in range(n + 1):
        d = segment_vector(y, k, n, A, B)
        l = length(d)
        e = vdiv(d, l)
        T = tension(l, S[k], EA)
        if T <= 0.0 and slack < 0:
            slack = k
        T *= taut[k]
        ka, kg = block_coefficients(l, T, S[k], EA, taut[k])
        a, b = dim * (k - 1), dim * k  # first DOF of the start and end nodes
        if k < n:
            vadd_to(P, b, e, T)
        if k > 0:
            vadd_to(P, a, e, -T)
        for r in range(dim):
            for c in range(dim):
                kk = block_entry(ka, kg, e, r, c)
                if k < n:
                    K[b + r, b + c] += kk
                if k > 0:
                    K[a + r, a + c] += kk
                if 0 < k < n:
                    K[a + r, b + c] -= kk
                    K[b + r, a + c] -= kk
    return slack


@njit
def force_and_stiffness_band(y, S, EA, A, B, taut, P, Kb):
    """:func:`force_and_stiffness` with ``K`` in general band storage,
    ``Kb[h + i - j, j] = K[i, j]``, ``h = 2 DIM - 1`` (shape ``(2 h + 1, n DIM)``)."""
    dim = len(A)
    hb = 2 * dim - 1
    n = S.size - 1
    P[:] = 0.0
    Kb[:, :] = 0.0
    slack = -1
    for k in range(n + 1):
        d = segment_vector(y, k, n, A, B)
        l = length(d)
        e = vdiv(d, l)
        T = tension(l, S[k], EA)
        if T <= 0.0 and slack < 0:
            slack = k
        T *= taut[k]
        ka, kg = block_coefficients(l, T, S[k], EA, taut[k])
        a, b = dim * (k - 1), dim * k
        if k < n:
            vadd_to(P, b, e, T)
        if k > 0:
            vadd_to(P, a, e, -T)
        for r in range(dim):
            for c in range(dim):
                kk = block_entry(ka, kg, e, r, c)
                if k < n:
                    Kb[hb + r - c, b + c] += kk
                if k > 0:
                    Kb[hb + r - c, a + c] += kk
                if 0 < k < n:
                    Kb[hb + (a + r) - (b + c), b + c] -= kk
                    Kb[hb + (b + r) - (a + c), a + c] -= kk
    return slack


@njit
def displaced_force_and_stiffness(z, y0, S, EA, A, B, zA, zB, taut, P, J, row, col):
    """Resisting force and tangent stiffness at ``y0 + z`` of the segments in their modes
    ``taut`` (1 taut, 0 slack; all ones: every segment a spring whatever its length), from the
    change of each segment vector (module docstring).

    ``z`` holds the interior nodes' displacements (its first ``n DIM`` entries are read), ``A``
    and ``B`` the supports' reference positions and ``zA``, ``zB`` their displacements. ``P``
    (n DIM) receives the force; ``K`` is written into ``J[row:row + n DIM, col:col + n DIM]``.
    """
    dim = len(A)
    n = S.size - 1
    nd = n * dim
    for i in range(nd):
        P[i] = 0.0
        for j in range(nd):
            J[row + i, col + j] = 0.0
    slack = -1
    for k in range(n + 1):
        d0 = segment_vector(y0, k, n, A, B)
        dd = vsub(node(z, k, n, zA, zB), node(z, k - 1, n, zA, zB))
        dvec = vadd(d0, dd)
        l = length(dvec)
        T = tension_of_stretch(displaced_stretch(d0, dd, l, S[k]), S[k], EA)
        if T <= 0.0 and slack < 0:
            slack = k
        T *= taut[k]  # (times 1.0 for a taut segment: bitwise the spring's force)
        e = vdiv(dvec, l)
        ka, kg = block_coefficients(l, T, S[k], EA, taut[k])
        a, b = dim * (k - 1), dim * k
        if k < n:
            vadd_to(P, b, e, T)
        if k > 0:
            vadd_to(P, a, e, -T)
        for r in range(dim):
            for c in range(dim):
                kk = block_entry(ka, kg, e, r, c)
                if k < n:
                    J[row + b + r, col + b + c] += kk
                if k > 0:
                    J[row + a + r, col + a + c] += kk
                if 0 < k < n:
                    J[row + a + r, col + b + c] -= kk
                    J[row + b + r, col + a + c] -= kk
    return slack


@njit
def displaced_block(z, y0, k, S, EA, A, B, zA, zB, mode):
    """Segment ``k``'s tangent block at ``y0 + z`` (supports at ``A + zA``, ``B + zB``), as a
    flat ``DIM x DIM`` tuple in the displaced form of :func:`displaced_force_and_stiffness`
    (``mode``: 1.0 taut, 0.0 slack)."""
    n = S.size - 1
    d0 = segment_vector(y0, k, n, A, B)
    dd = vsub(node(z, k, n, zA, zB), node(z, k - 1, n, zA, zB))
    dvec = vadd(d0, dd)
    l = length(dvec)
    T = tension_of_stretch(displaced_stretch(d0, dd, l, S[k]), S[k], EA) * mode
    ka, kg = block_coefficients(l, T, S[k], EA, mode)
    e = vdiv(dvec, l)
    return madd_outer(madd_diag(mzero(A), kg), e, e, ka - kg)


@njit
def displaced_gaps(z, y0, S, A, B, zA, zB, g):
    """``g[k] = l_k - S_k`` of every segment at ``y0 + z`` (negative: shorter than its natural
    length), m, in the displaced form of :func:`displaced_force_and_stiffness` (the same
    stretches, so a gap and the tension the field uses change sign together)."""
    n = S.size - 1
    for k in range(n + 1):
        d0 = segment_vector(y0, k, n, A, B)
        dd = vsub(node(z, k, n, zA, zB), node(z, k - 1, n, zA, zB))
        g[k] = displaced_stretch(d0, dd, length(vadd(d0, dd)), S[k])
