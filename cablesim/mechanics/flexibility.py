"""The approximate analysis' flexibility ``N = D + f`` and stiffness ``K = N(P)^-1``, in O(n).

Write ``F_k = F_1 - Q_k`` for the force in segment k, ``T_k = |F_k|``, ``e_k`` its unit vector
and ``Pi_k = I - e_k e_k^T`` the projector across it (``DIM x DIM``). A load rate ``P'`` gives
segment force rates ``F'_k = F'_1 - sum_{j<k} P'_j`` that keep the inextensible cable closed,
``sum_k G_k F'_k = 0`` with ``G_k = (S_k / T_k) Pi_k`` (``H = sum_k G_k`` is the closure's
Hessian), and the node velocities are

    y'_j = sum_{k <= j} (M_k F'_k - G_k lambda),   lambda = H^-1 sum_k M_k F'_k,

with ``M_k`` the ``DIM x DIM`` flexibility of segment k. Differentiating the elastic
displacements of the approximate analysis (paper eq. 8, ``u = dOmega_e/dP``) gives, with
``v = H^-1 sum_k S_k F_k`` (the chord rotation of the elastic part),

    M_k = alpha_k Pi_k + beta_k e e^T + (p_k e^T + e p_k^T),
    alpha_k = S_k/T_k + (S_k + S_k (e.v)/T_k^2)/EA,  beta_k = S_k/EA,  p_k = S_k Pi_k v / (EA T_k^2),

(``S_k / T_k Pi_k`` is the configurational part ``D``, the rest the elastic part ``f``). Every
product is then O(n): ``N w`` forward (:func:`flexibility_product`), and its inverse

    K = Delta^T M^-1 Delta - U Gamma^-1 U^T,  U = Delta^T M^-1 G,  Gamma = sum_k G_k M_k^-1 G_k,

a chain of segment springs ``M_k^-1`` (block-tridiagonal, like the exact analysis' stiffness)
less a rank-``DIM`` term that keeps the inextensible cable's chord (:func:`stiffness_product`,
:func:`stiffness_band`). With ``s_k = beta_k - |p_k|^2 / alpha_k``,
``M_k^-1 = Pi/alpha + e e^T/s - (p e^T + e p^T)/(alpha s) + p p^T/(alpha^2 s)``.

The same factors give the dense matrices the statics report (``B = dT/dP``, ``D``, ``f``, ``N``)
column by column (:func:`force_rates`), and the natural and elastic states ``x(P)``, ``u(P)``
(:func:`natural_and_elastic`). Written once for any ``DIM`` (:mod:`.vectors`); checked against
finite differences of ``x`` and ``u`` (``tests/test_mechanics_flexibility.py``).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from .vectors import (madd, madd_outer, mblock, mdet, mload, mstore, msym_inverse, mvec, mzero, vadd, vcombo, vdiv,
                      vdot, vload, vnorm, vnormal, vrow, vscale, vstore, vsub, vunit, vzero)

def factor_columns(dim: int) -> int:
    """Columns of a row of :func:`segment_factors`' table for ``dim`` components per node:
    ``e`` and ``p`` (``dim`` each), then ``g``, ``h`` (the closure block ``G = g Pi + h e e^T``),
    ``alpha``, ``beta``, ``s``."""
    return 2 * dim + 5


def factor_workspace(n: int, dim: int = 2):
    """Scratch for :func:`segment_factors` and :func:`stiffness_product` of an n-node cable:
    the factors (n + 1, 2 dim + 5), the entries of ``Gamma^-1`` and ``H^-1`` (2 dim^2), and the
    product's scratch (segment force rates (n + 1, dim), a residual and a correction (dim n each))."""
    return (np.empty((n + 1, factor_columns(dim))), np.empty(2 * dim * dim),
            (np.empty((n + 1, dim)), np.empty(dim * n), np.empty(dim * n)))


@njit(inline="always")
def _e(fac, k, like):
    return vload(fac[k], 0, like)


@njit(inline="always")
def _p(fac, k, like):
    return vload(fac[k], len(like), like)


@njit(inline="always")
def flex_times(fac, k, x, like, part):
    """``M_k x`` (``part`` 0), its configurational part ``(S/T) Pi x`` (1) or its elastic part
    ``M_k x - (S/T) Pi x`` (2)."""
    dim = len(like)
    if part == 1:
        return closure_times(fac, k, x, like)
    e, p = _e(fac, k, like), _p(fac, k, like)
    g, h, alpha, beta = fac[k, 2 * dim], fac[k, 2 * dim + 1], fac[k, 2 * dim + 2], fac[k, 2 * dim + 3]
    ex = vdot(e, x)
    nx = vnormal(x, e)
    a, b = (alpha, beta) if part == 0 else (alpha - g, beta - h)
    return vadd(vadd(vscale(nx, a), vscale(e, b * ex + vdot(p, x))), vscale(p, ex))


@njit(inline="always")
def closure_times(fac, k, x, like):
    """``G_k x = g_k Pi_k x + h_k e_k (e_k . x)`` (``g = S/T``, ``h = 0`` for the inextensible
    closure of the approximate analysis)."""
    dim = len(like)
    e = _e(fac, k, like)
    g, h = fac[k, 2 * dim], fac[k, 2 * dim + 1]
    return vcombo(x, e, g, (h - g) * vdot(e, x))


@njit(inline="always")
def inverse_times(fac, k, x, like):
    """``M_k^-1 x`` (module docstring)."""
    dim = len(like)
    e, p = _e(fac, k, like), _p(fac, k, like)
    alpha, s = fac[k, 2 * dim + 2], fac[k, 2 * dim + 4]
    ex, px = vdot(e, x), vdot(p, x)
    out = vscale(vnormal(x, e), 1.0 / alpha)
    out = vadd(out, vscale(e, ex / s - px / (alpha * s)))
    return vadd(out, vscale(p, px / (alpha * alpha * s) - ex / (alpha * s)))


@njit
def segment_factors(S, EA, Q, F, T, fac, gi, like):
    """Per-segment factors of ``N`` and ``K`` at the solved inextensible closure (segment-1 force
    ``F``, cumulative loads ``Q``).

    Fills ``T`` (n+1) with the tensions ``|F - Q_k|``, ``fac`` (n+1, 2 DIM + 5) with
    ``e_k, p_k, g_k = S_k/T_k, h_k = 0, alpha_k, beta_k, s_k`` and ``gi`` (2 DIM^2) with
    ``Gamma^-1`` and ``H^-1``. Returns False if ``Gamma``, ``H`` or an ``M_k`` is singular.
    With ``EA = inf`` (the inextensible cable: ``N = D``, which has no inverse) only the forward
    products are defined: ``p = 0``, ``beta = s = 0`` and ``Gamma^-1`` is NaN.
    """
    dim = len(like)
    n1 = S.size
    Ft = vload(F, 0, like)
    H = mzero(like)
    w = vzero(like)
    for k in range(n1):
        f = vsub(Ft, vrow(Q, k, like))
        T[k] = vnorm(f)
        e = vdiv(f, T[k])
        H = madd(H, mblock(S[k] / T[k], 0.0, e))
        w = vadd(w, vscale(f, S[k]))
    if not abs(mdet(H)) > 0.0:
        return False
    Hi = msym_inverse(H)
    mstore(gi, dim * dim, Hi)
    v = mvec(Hi, w)  # the chord rotation of the elastic part
    elastic = EA < np.inf
    Gm = mzero(like)
    for k in range(n1):
        e = vdiv(vsub(Ft, vrow(Q, k, like)), T[k])
        g = S[k] / T[k]
        alpha = g + (S[k] + S[k] * vdot(e, v) / (T[k] * T[k])) / EA
        beta = S[k] / EA
        p = vscale(vnormal(v, e), S[k] / (EA * T[k] * T[k]))
        s = beta - vdot(p, p) / alpha
        if elastic and not (abs(alpha) > 0.0 and abs(s) > 0.0):  # near slack M_k may turn indefinite
            return False
        vstore(fac[k], 0, e)
        vstore(fac[k], dim, p)
        fac[k, 2 * dim], fac[k, 2 * dim + 1] = g, 0.0
        fac[k, 2 * dim + 2], fac[k, 2 * dim + 3], fac[k, 2 * dim + 4] = alpha, beta, s
        if not elastic:
            continue
        # G_k M_k^-1 G_k = g^2 (Pi / alpha + p p^T / (alpha^2 s))
        Gm = madd(Gm, mblock(g * g / alpha, 0.0, e))
        Gm = madd_outer(Gm, p, p, g * g / (alpha * alpha * s))
    if not elastic:
        for i in range(dim * dim):
            gi[i] = np.nan
        return True
    if not abs(mdet(Gm)) > 0.0:
        return False
    mstore(gi, 0, msym_inverse(Gm))
    return True


@njit
def exact_factors(S, EA, Fk, T, lengths, fac, gi, like):
    """Factors whose forward product (part 0) is the exact elastic cable's ``dy/dP``: every
    segment's flexibility is its compliance ``M_k = G_k = (l_k/T_k) Pi_k + (S_k/EA) e_k e_k^T``,
    closure included (``Gamma^-1`` NaN: the stiffness is the assembled tangent instead).
    ``Fk`` (n+1, DIM) holds the segment forces of the solved equilibrium. False if ``H`` is
    singular."""
    dim = len(like)
    H = mzero(like)
    for k in range(S.size):
        e = vdiv(vrow(Fk, k, like), T[k])
        g, h = lengths[k] / T[k], S[k] / EA
        H = madd(H, mblock(g, h, e))
        vstore(fac[k], 0, e)
        vstore(fac[k], dim, vzero(like))
        fac[k, 2 * dim], fac[k, 2 * dim + 1] = g, h
        fac[k, 2 * dim + 2], fac[k, 2 * dim + 3], fac[k, 2 * dim + 4] = g, h, h
    if not abs(mdet(H)) > 0.0:
        return False
    mstore(gi, dim * dim, msym_inverse(H))
    for i in range(dim * dim):
        gi[i] = np.nan
    return True


@njit
def dense_flexibility(fac, gi, out, Fd, like, part):
    """The dense ``N`` (part 0), ``D`` (1) or ``f`` (2) column by column, O(n^2)."""
    nd = out.shape[0]
    w = np.zeros(nd)
    col = np.empty(nd)
    for j in range(nd):
        w[j] = 1.0
        flexibility_product(fac, gi, w, col, Fd, like, part)
        w[j] = 0.0
        for i in range(nd):
            out[i, j] = col[i]


@njit
def dense_tension_rates(fac, gi, B, Fd, like):
    """``B = dT/dP`` ((n+1, n DIM), dimensionless) column by column: ``dT_k = e_k . F'_k``."""
    n1, nd = B.shape
    w = np.zeros(nd)
    for j in range(nd):
        w[j] = 1.0
        force_rates(fac, gi, w, Fd, like)
        w[j] = 0.0
        for k in range(n1):
            B[k, j] = vdot(_e(fac, k, like), vrow(Fd, k, like))


@njit
def force_rates(fac, gi, w, Fd, like):
    """Segment force rates ``F'_k`` (into ``Fd``, (n+1, DIM)) under the load rate ``w`` (n DIM):
    ``F'_k = F'_1 - sum_{j<k} w_j`` with ``F'_1 = H^-1 sum_j (sum_{k>j} G_k) w_j`` (closure)."""
    dim = len(like)
    n1 = fac.shape[0]
    prefix = vzero(like)
    o = vzero(like)
    for k in range(1, n1):  # o = sum_j (sum_{k>j} G_k) w_j = sum_k G_k (sum_{j<k} w_j)
        prefix = vadd(prefix, vload(w, dim * (k - 1), like))
        o = vadd(o, closure_times(fac, k, prefix, like))
    F1 = mvec(mload(gi, dim * dim, like), o)
    prefix = vzero(like)
    for k in range(n1):
        f = vsub(F1, prefix)
        for d in range(dim):
            Fd[k, d] = f[d]
        if k < n1 - 1:
            prefix = vadd(prefix, vload(w, dim * k, like))


@njit
def flexibility_product(fac, gi, w, out, Fd, like, part):
    """``out = N w`` (``part`` 0), ``D w`` (1) or ``f w`` (2), O(n) (module docstring; scratch
    ``Fd`` (n+1, DIM))."""
    dim = len(like)
    n1 = fac.shape[0]
    force_rates(fac, gi, w, Fd, like)
    sg = vzero(like)
    for k in range(n1):
        mf = flex_times(fac, k, vrow(Fd, k, like), like, part)
        for d in range(dim):
            Fd[k, d] = mf[d]
        sg = vadd(sg, mf)
    lam = mvec(mload(gi, dim * dim, like), sg)
    a = vzero(like)
    for j in range(n1 - 1):
        a = vadd(a, vsub(vrow(Fd, j, like), closure_times(fac, j, lam, like)))
        vstore(out, dim * j, a)


@njit
def _factored_solve(fac, gi, v, out, Fd, like):
    """``out = K v`` by the factors alone (module docstring; scratch ``Fd`` (n+1, DIM))."""
    dim = len(like)
    n1 = fac.shape[0]
    nn = n1 - 1
    r = vzero(like)
    z = vzero(like)
    for k in range(n1):
        psi = vsub(vload(v, dim * k, like) if k < nn else z, vload(v, dim * (k - 1), like) if k > 0 else z)
        m = inverse_times(fac, k, psi, like)
        for d in range(dim):
            Fd[k, d] = m[d]
        r = vadd(r, closure_times(fac, k, m, like))
    lam = vscale(mvec(mload(gi, 0, like), r), -1.0)
    for k in range(n1):
        c = inverse_times(fac, k, closure_times(fac, k, lam, like), like)
        for d in range(dim):
            Fd[k, d] += c[d]
    for j in range(nn):
        vstore(out, dim * j, vsub(vrow(Fd, j, like), vrow(Fd, j + 1, like)))


@njit
def stiffness_product(fac, gi, v, out, scratch, like):
    """``out = K v = N^-1 v`` in O(n) from :func:`segment_factors` (``scratch`` from
    :func:`factor_workspace`), with one step of iterative refinement against the forward
    product :func:`flexibility_product`.

    The factored inverse loses digits where the segment flexibilities ``M_k`` span a wide range
    (a nearly taut cable, whose elastic closure terms grow as the chord's rotation does); the
    forward product does not. Measured on the paper's cable at 1.0001 times its chord:
    ``|N (K v) - v| / |v|`` 6e-11 without the refinement, 1e-16 with it.
    """
    Fd, r, dw = scratch
    _factored_solve(fac, gi, v, out, Fd, like)
    flexibility_product(fac, gi, out, r, Fd, like, 0)
    for i in range(v.size):
        r[i] = v[i] - r[i]
    _factored_solve(fac, gi, r, dw, Fd, like)
    for i in range(v.size):
        out[i] += dw[i]


@njit
def stiffness_band(fac, gi, Kb, U, like):
    """``K = B - U Gamma^-1 U^T`` from :func:`segment_factors`, O(n): the block-tridiagonal
    ``B = Delta^T M^-1 Delta`` into ``Kb`` in general band storage (:mod:`.banded`, half
    bandwidth ``2 DIM - 1``), and ``U = Delta^T M^-1 G`` into ``U`` (n DIM, DIM). ``Gamma^-1`` is
    ``gi[:DIM^2]`` (for Newton matrices: banded solves plus a rank-DIM correction)."""
    dim = len(like)
    n1 = fac.shape[0]
    nn = n1 - 1
    hb = (Kb.shape[0] - 1) // 2
    Kb[:, :] = 0.0
    U[:, :] = 0.0
    for k in range(n1):
        for c in range(dim):
            unit = vunit(like, c)
            mc = inverse_times(fac, k, unit, like)  # column c of M_k^-1
            qc = inverse_times(fac, k, closure_times(fac, k, unit, like), like)  # of M_k^-1 G_k
            for a, sa in ((k - 1, -1.0), (k, 1.0)):  # segment k joins node k-1 to node k
                if a < 0 or a >= nn:
                    continue
                for r in range(dim):
                    U[dim * a + r, c] += sa * qc[r]
                for b, sb in ((k - 1, -1.0), (k, 1.0)):
                    if b < 0 or b >= nn:
                        continue
                    for r in range(dim):
                        i, j = dim * a + r, dim * b + c
                        Kb[hb + i - j, j] += sa * sb * mc[r]


@njit
def natural_and_elastic(S, EA, fac, gi, T, x, u, like):
    """Natural state ``x`` and elastic displacement ``u`` of the approximate analysis, O(n),
    from :func:`segment_factors` and the tensions ``T``:
    ``x_j = sum_{k<=j} S_k e_k``, ``u_j = (sum_{k>j} G_k) H^-1 sigma - sum_{k>j} eps_k`` with
    ``eps_k = S_k T_k e_k / EA`` and ``sigma = sum_k eps_k`` (the same ``u`` as eq. 7's
    ``(1/EA) sum_k S_k T_k dT_k/dP``)."""
    dim = len(like)
    n1 = S.size
    sig = vzero(like)
    px = vzero(like)
    for k in range(n1):
        e = _e(fac, k, like)
        sig = vadd(sig, vscale(e, S[k] * T[k] / EA))
        if k < n1 - 1:
            px = vadd(px, vscale(e, S[k]))
            vstore(x, dim * k, px)
    lam = mvec(mload(gi, dim * dim, like), sig)
    b = vzero(like)
    gl = vzero(like)
    for j in range(n1 - 2, -1, -1):  # suffix sums over segments k > j
        k = j + 1
        gl = vadd(gl, closure_times(fac, k, lam, like))
        b = vadd(b, vscale(_e(fac, k, like), S[k] * T[k] / EA))
        vstore(u, dim * j, vsub(gl, b))


@njit
def dense_stiffness(fac, gi, K, row, col, Kb, U, like):
    """The dense ``K = B - U Gamma^-1 U^T`` (n DIM, n DIM) into ``K[row:, col:]``, O(n^2), with
    scratch ``Kb`` (band storage, half bandwidth ``2 DIM - 1``) and ``U`` (n DIM, DIM)."""
    nd = U.shape[0]
    hb = (Kb.shape[0] - 1) // 2
    stiffness_band(fac, gi, Kb, U, like)
    Gi = mload(gi, 0, like)
    for i in range(nd):
        gu = mvec(Gi, vload(U[i], 0, like))
        for j in range(nd):
            kij = Kb[hb + i - j, j] if abs(i - j) <= hb else 0.0
            K[row + i, col + j] = kij - vdot(gu, vload(U[j], 0, like))


