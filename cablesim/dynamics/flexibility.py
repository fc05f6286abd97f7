"""The approximate analysis' tangent stiffness ``K = N(P)^-1`` without forming ``N``.

The flexibility of the approximate analysis, ``N = D + f`` (configurational plus elastic), is
a full matrix: every load moves every node of an inextensible cable. Its inverse is not. Write
``F_k`` for the force in segment k (``F_k = F_1 - Q_k``, ``Q_k`` the loads on the nodes before
it) and ``t_k, e_k`` for the unit vectors normal and along it. A load rate ``P'`` gives segment
force rates ``F'_k`` that satisfy the closure ``sum_k G_k F'_k = 0`` (``G_k = (S_k/T_k) t_k t_k^T``,
the inextensible cable's ends stay put), and the node velocities are

    y'_j = sum_{k <= j} psi_k,     psi_k = M_k F'_k - G_k lambda,

with ``M_k`` the 2x2 flexibility of segment k (``(S_k/T_k + a_k) t t^T + b_k e e^T +
c_k (t e^T + e t^T)`` in the notation of the elastic flexibility) and ``lambda`` a 2-vector
(the rotation of the chord that closes the elastic part). Inverted: ``psi_k = y'_k - y'_{k-1}``
(a difference of neighbours), ``F'_k = M_k^-1 (psi_k + G_k lambda)`` with ``lambda`` fixed by the
closure, and ``P'_j = F'_j - F'_{j+1}``. So

    K = Delta^T M^-1 Delta - U Gamma^-1 U^T,   U = Delta^T M^-1 G,   Gamma = sum_k G_k M_k^-1 G_k,

block-tridiagonal (like the exact analysis' stiffness, with ``M_k^-1`` for the segment
stiffness) minus a rank-2 correction: ``K v`` costs O(n) and needs no solve. Checked against
``N^-1`` from the full flexibility (``tests/test_approximate_stiffness.py``).
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

#: Columns of a row of :func:`segment_factors`: t (2), e (2), S/T, M^-1 and M in the (t, e) basis.
FACTOR_COLUMNS = 11


def factor_workspace(n: int):
    """Scratch for :func:`segment_factors` and :func:`stiffness_product` of an n-node cable:
    the factors (n + 1, 11), the entries of ``Gamma^-1`` and ``H^-1`` (6), and the product's
    scratch (segment force rates (n + 1, 2), a residual and a correction (2n each))."""
    return (np.empty((n + 1, FACTOR_COLUMNS)), np.empty(6),
            (np.empty((n + 1, 2)), np.empty(2 * n), np.empty(2 * n)))


@njit
def segment_factors(S, EA, Q, F, T, fac, gi):
    """Per-segment factors of ``K`` at the solved inextensible closure (segment-1 force ``F``).

    Fills ``T`` (n+1) with the tensions ``|F - Q_k|``, ``fac`` (n+1, 11) with ``t_k, e_k, S_k/T_k``
    and the entries ``(tt, te, ee)`` of ``M_k^-1`` and of ``M_k`` in the ``(t_k, e_k)`` basis, and
    ``gi`` (6) with ``Gamma^-1`` and ``H^-1`` (entries 00, 01, 11 of each, ``H = sum_k G_k``).
    Returns False if ``Gamma``, ``H`` or an ``M_k`` is singular.
    """
    n1 = S.size
    h00 = 0.0
    h01 = 0.0
    h11 = 0.0
    w0 = 0.0
    w1 = 0.0
    for k in range(n1):
        f0 = F[0] - Q[k, 0]
        f1 = F[1] - Q[k, 1]
        T[k] = np.sqrt(f0 * f0 + f1 * f1)
        g = S[k] / T[k]
        h00 += g * f1 * f1 / (T[k] * T[k])
        h01 -= g * f0 * f1 / (T[k] * T[k])
        h11 += g * f0 * f0 / (T[k] * T[k])
        w0 += S[k] * f0
        w1 += S[k] * f1
    det = h00 * h11 - h01 * h01
    if not abs(det) > 0.0:
        return False
    # the chord rotation of the elastic part (eq. of the elastic flexibility's closure)
    v0 = (h11 * w0 - h01 * w1) / det
    v1 = (-h01 * w0 + h00 * w1) / det
    g00 = 0.0
    g01 = 0.0
    g11 = 0.0
    for k in range(n1):
        e0 = (F[0] - Q[k, 0]) / T[k]
        e1 = (F[1] - Q[k, 1]) / T[k]
        t0, t1 = -e1, e0
        g = S[k] / T[k]
        c1 = S[k] * (t0 * v0 + t1 * v1) / (T[k] * T[k])
        c2 = S[k] * (e0 * v0 + e1 * v1) / (T[k] * T[k])
        att = g + (S[k] + c2) / EA  # M_k in the (t, e) basis
        ate = c1 / EA
        aee = S[k] / EA
        dm = att * aee - ate * ate
        if not abs(dm) > 0.0:  # near slack M_k may turn indefinite (c1 ~ 1/T^2) but stays invertible
            return False
        ltt, lte, lee = aee / dm, -ate / dm, att / dm
        fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3] = t0, t1, e0, e1
        fac[k, 4], fac[k, 5], fac[k, 6], fac[k, 7] = g, ltt, lte, lee
        fac[k, 8], fac[k, 9], fac[k, 10] = att, ate, aee
        c = g * g * ltt  # G_k M_k^-1 G_k = g^2 (t . M^-1 t) t t^T
        g00 += c * t0 * t0
        g01 += c * t0 * t1
        g11 += c * t1 * t1
    det = g00 * g11 - g01 * g01
    if not abs(det) > 0.0:
        return False
    gi[0], gi[1], gi[2] = g11 / det, -g01 / det, g00 / det
    dh = h00 * h11 - h01 * h01
    gi[3], gi[4], gi[5] = h11 / dh, -h01 / dh, h00 / dh
    return True


@njit
def stiffness_product(fac, gi, v, out, scratch):
    """``out = K v = N^-1 v`` in O(n) from :func:`segment_factors` (``scratch`` from
    :func:`factor_workspace`), with one step of iterative refinement against the forward
    product :func:`flexibility_product`.

    The factored inverse loses digits where the segment flexibilities ``M_k`` span a wide range
    (a nearly taut cable, whose elastic closure terms ``c1, c2`` grow as the chord's rotation
    does); the forward product does not. Measured on the paper's cable at 1.0001 times its
    chord: ``|N (K v) - v| / |v|`` 6e-11 without the refinement, 1e-16 with it.
    """
    Fd, r, dw = scratch
    _factored_solve(fac, gi, v, out, Fd)
    flexibility_product(fac, gi, out, r, Fd)
    for i in range(v.size):
        r[i] = v[i] - r[i]
    _factored_solve(fac, gi, r, dw, Fd)
    for i in range(v.size):
        out[i] += dw[i]


@njit
def flexibility_product(fac, gi, w, out, Fd):
    """``out = N w`` in O(n) from :func:`segment_factors`: ``N = sum_k (dF_k/dP)^T M_k (dF_k/dP)``
    with the segment force rates ``F'_k = F'_1 - sum_{j<k} w_j`` (``F'_1`` from the closure) and
    ``(N w)_j = sum_{k<=j} (M_k F'_k - G_k H^-1 sum_i M_i F'_i)`` (scratch ``Fd`` (n+1, 2))."""
    n1 = fac.shape[0]
    nn = n1 - 1
    s00 = 0.0
    s01 = 0.0
    s11 = 0.0
    o0 = 0.0
    o1 = 0.0
    for j in range(nn - 1, -1, -1):  # sum_j (sum_{k>j} G_k) w_j
        k = j + 1
        t0, t1, g = fac[k, 0], fac[k, 1], fac[k, 4]
        s00 += g * t0 * t0
        s01 += g * t0 * t1
        s11 += g * t1 * t1
        o0 += s00 * w[2 * j] + s01 * w[2 * j + 1]
        o1 += s01 * w[2 * j] + s11 * w[2 * j + 1]
    f10 = gi[3] * o0 + gi[4] * o1  # F'_1 = H^-1 (...), the closure
    f11 = gi[4] * o0 + gi[5] * o1
    p0 = 0.0
    p1 = 0.0
    sg0 = 0.0
    sg1 = 0.0
    for k in range(n1):
        t0, t1, e0, e1 = fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3]
        f0 = f10 - p0
        f1 = f11 - p1
        ft = t0 * f0 + t1 * f1
        fe = e0 * f0 + e1 * f1
        pt = fac[k, 8] * ft + fac[k, 9] * fe  # M_k F'_k in the (t, e) basis
        pe = fac[k, 9] * ft + fac[k, 10] * fe
        Fd[k, 0] = pt * t0 + pe * e0
        Fd[k, 1] = pt * t1 + pe * e1
        sg0 += Fd[k, 0]
        sg1 += Fd[k, 1]
        if k < nn:
            p0 += w[2 * k]
            p1 += w[2 * k + 1]
    l0 = gi[3] * sg0 + gi[4] * sg1
    l1 = gi[4] * sg0 + gi[5] * sg1
    a0 = 0.0
    a1 = 0.0
    for j in range(nn):
        t0, t1, g = fac[j, 0], fac[j, 1], fac[j, 4]
        c = g * (t0 * l0 + t1 * l1)
        a0 += Fd[j, 0] - c * t0
        a1 += Fd[j, 1] - c * t1
        out[2 * j] = a0
        out[2 * j + 1] = a1


@njit
def _factored_solve(fac, gi, v, out, Fd):
    """``out = K v`` by the factors alone (see the module docstring; scratch ``Fd`` (n+1, 2))."""
    n1 = fac.shape[0]
    nd = v.size
    r0 = 0.0
    r1 = 0.0
    for k in range(n1):
        p0 = (v[2 * k] if k < n1 - 1 else 0.0) - (v[2 * k - 2] if k > 0 else 0.0)
        p1 = (v[2 * k + 1] if k < n1 - 1 else 0.0) - (v[2 * k - 1] if k > 0 else 0.0)
        t0, t1, e0, e1 = fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3]
        pt = t0 * p0 + t1 * p1
        pe = e0 * p0 + e1 * p1
        al = fac[k, 5] * pt + fac[k, 6] * pe
        be = fac[k, 6] * pt + fac[k, 7] * pe
        Fd[k, 0] = al * t0 + be * e0  # M_k^-1 psi_k
        Fd[k, 1] = al * t1 + be * e1
        r0 += fac[k, 4] * al * t0  # closure of those: sum G_k M_k^-1 psi_k
        r1 += fac[k, 4] * al * t1
    l0 = -(gi[0] * r0 + gi[1] * r1)
    l1 = -(gi[1] * r0 + gi[2] * r1)
    for k in range(n1):
        t0, t1, e0, e1 = fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3]
        c = fac[k, 4] * (t0 * l0 + t1 * l1)  # M_k^-1 G_k lambda = c M_k^-1 t_k
        Fd[k, 0] += c * (fac[k, 5] * t0 + fac[k, 6] * e0)
        Fd[k, 1] += c * (fac[k, 5] * t1 + fac[k, 6] * e1)
    for j in range(nd // 2):
        out[2 * j] = Fd[j, 0] - Fd[j + 1, 0]
        out[2 * j + 1] = Fd[j, 1] - Fd[j + 1, 1]


@njit
def stiffness_band(fac, gi, Kb, U):
    """``K = B - U Gamma^-1 U^T`` from :func:`segment_factors`, O(n): the block-tridiagonal
    ``B = Delta^T M^-1 Delta`` into ``Kb`` in the general band storage of
    :mod:`cablesim.dynamics.banded` (shape (7, 2n)), and ``U = Delta^T M^-1 G`` into ``U`` (2n, 2).
    ``Gamma^-1`` is ``gi`` (for Newton matrices: banded solves plus a rank-2 correction)."""
    n1 = fac.shape[0]
    nn = n1 - 1
    hb = Kb.shape[0] // 2
    Kb[:, :] = 0.0
    U[:, :] = 0.0
    for k in range(n1):
        t0, t1, e0, e1, g = fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3], fac[k, 4]
        ltt, lte, lee = fac[k, 5], fac[k, 6], fac[k, 7]
        mk = ((ltt * t0 * t0 + lee * e0 * e0 + 2.0 * lte * t0 * e0,  # M_k^-1 in x, y
               ltt * t0 * t1 + lee * e0 * e1 + lte * (t0 * e1 + e0 * t1)),
              (ltt * t0 * t1 + lee * e0 * e1 + lte * (t0 * e1 + e0 * t1),
               ltt * t1 * t1 + lee * e1 * e1 + 2.0 * lte * t1 * e1))
        q0 = g * (ltt * t0 + lte * e0)  # M_k^-1 G_k = q t^T
        q1 = g * (ltt * t1 + lte * e1)
        for a, sa in ((k - 1, -1.0), (k, 1.0)):  # segment k joins node k-1 to node k
            if a < 0 or a >= nn:
                continue
            U[2 * a, 0] += sa * q0 * t0
            U[2 * a, 1] += sa * q0 * t1
            U[2 * a + 1, 0] += sa * q1 * t0
            U[2 * a + 1, 1] += sa * q1 * t1
            for b, sb in ((k - 1, -1.0), (k, 1.0)):
                if b < 0 or b >= nn:
                    continue
                for r in range(2):
                    for c in range(2):
                        i, j = 2 * a + r, 2 * b + c
                        Kb[hb + i - j, j] += sa * sb * mk[r][c]


@njit
def natural_and_elastic(S, EA, fac, gi, T, x, u):
    """Natural state ``x`` and elastic displacement ``u`` of the approximate analysis, O(n),
    from :func:`segment_factors` (``fac`` and ``gi``, whose ``H^-1`` it uses) and the tensions
    ``T`` (the same ``u`` as the full elastic flexibility's ``sum_k (S_k T_k / EA) b_k``)."""
    n1 = S.size
    # u_j = (sum_{k>j} G_k) H^-1 sigma - sum_{k>j} eps_k, eps_k = S_k T_k e_k / EA, sigma = sum eps
    s0 = 0.0
    s1 = 0.0
    px = 0.0
    py = 0.0
    for k in range(n1):
        e0, e1 = fac[k, 2], fac[k, 3]
        s0 += S[k] * T[k] * e0 / EA
        s1 += S[k] * T[k] * e1 / EA
        if k < n1 - 1:
            px += S[k] * e0
            py += S[k] * e1
            x[2 * k] = px
            x[2 * k + 1] = py
    l0 = gi[3] * s0 + gi[4] * s1
    l1 = gi[4] * s0 + gi[5] * s1
    a00 = 0.0
    a01 = 0.0
    a11 = 0.0
    b0 = 0.0
    b1 = 0.0
    for j in range(n1 - 2, -1, -1):  # suffix sums over segments k > j
        k = j + 1
        t0, t1, e0, e1, g = fac[k, 0], fac[k, 1], fac[k, 2], fac[k, 3], fac[k, 4]
        a00 += g * t0 * t0
        a01 += g * t0 * t1
        a11 += g * t1 * t1
        b0 += S[k] * T[k] * e0 / EA
        b1 += S[k] * T[k] * e1 / EA
        u[2 * j] = a00 * l0 + a01 * l1 - b0
        u[2 * j + 1] = a01 * l0 + a11 * l1 - b1
