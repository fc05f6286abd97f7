"""The closure problem of a cable fixed at both ends, solved on its complementary energy.

With both ends fixed, every segment's force vector follows from the force ``F`` (``DIM``
unknowns) carried by segment 1: segment ``k`` carries ``F_k = F - Q_k`` with
``Q_k = sum_{j<k} P_j`` the loads on the nodes before it. The polygon must close,
``sum_k l_k e_k = c`` (``c = B - A``, the chord), with ``e_k = F_k / |F_k|`` and
``l_k = S_k (1 + eps T_k)`` (``eps = 1/EA``; 0 for the inextensible cable). Closure is exactly
the stationarity condition of the convex complementary energy::

    Phi(F) = sum_k [ S_k |F_k| + eps S_k |F_k|^2 / 2 ] - F . c

whose gradient is the closure error ``sum_k l_k e_k - c`` and whose Hessian is
``sum_k [ S_k (1/T_k + eps) (I - e_k e_k^T) + eps S_k e_k e_k^T ]``. A damped Newton method on
``Phi`` converges from any start; near a kink of ``Phi`` (a segment force passing through zero)
its quadratic model is useless, and the iterate escapes along the exact descent ray there
(:func:`escape_kink`); a segment whose force must vanish is slack.

Compiled kernels, written once for any ``DIM`` (vectors are tuples, :mod:`.vectors`): ``F`` is a
float array of ``DIM`` entries, updated in place; ``Q`` is ``(n + 1, DIM)``; ``c`` a tuple.
:mod:`cablesim.mechanics.equilibrium` wraps them for the statics (scaling, messages, the slack
test).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from .vectors import (madd, madd_diag, mblock, mdet, msym_solve, mtrace, mzero, vadd, vdiv, vdot, vload,
                      vmaxabs, vnorm, vrow, vscale, vstore, vsub, vzero)

#: Return codes of :func:`minimise` when it fails (it returns the iteration count otherwise).
FAIL_ITERATIONS = -1
FAIL_STALLED = -2
FAIL_SLACK = -3
#: Escapes from a kink allowed in one solve.
MAX_ESCAPES = 50


@njit
def cumulative_loads(P, Q, like):
    """``Q_k = sum_{j<k} P_j`` into ``Q`` (n + 1, DIM), ``DIM = len(like)``."""
    dim = len(like)
    for d in range(dim):
        Q[0, d] = 0.0
    for k in range(1, Q.shape[0]):
        for d in range(dim):
            Q[k, d] = Q[k - 1, d] + P[dim * (k - 1) + d]


@njit
def energy(S, Q, eps, c, F):
    """``(Phi, grad Phi, Hess Phi, smallest |F_k|)`` at the segment-1 force ``F`` (a tuple)."""
    phi = -vdot(F, c)
    g = vscale(c, -1.0)
    h = mzero(c)
    tmin = np.inf
    for k in range(S.size):
        f = vsub(F, vrow(Q, k, c))
        T = vnorm(f)
        if T < tmin:
            tmin = T
        if T == 0.0:
            T = 1e-300
        e = vdiv(f, T)
        lk = S[k] * (1.0 + eps * T)
        g = vadd(g, vscale(e, lk))
        phi += S[k] * T * (1.0 + 0.5 * eps * T)
        h = madd(h, mblock(S[k] * (1.0 / T + eps), S[k] * eps, e))
    return phi, g, h, tmin


@njit
def _slope(S, Q, eps, c, point, u):
    return vdot(energy(S, Q, eps, c, point)[1], u)


@njit
def escape_kink(S, Q, eps, c, F):
    """Move ``F`` (array, updated) out of the kink ``F = Q_k`` nearest to it, along the exact
    descent ray.

    At the kink the steepest-descent direction of Phi is ``-g_rest``, the gradient of the other
    terms; if the segment is not slack (``|g_rest|`` exceeds the radius ``S_k`` of the kink's
    subdifferential) Phi decreases along it and the 1-D problem is convex: bisect its slope.
    Returns False if no descent exists (the segment is slack).
    """
    n1 = S.size
    Ft = vload(F, 0, c)
    k = 0
    tmin = np.inf
    qmax = 0.0
    for m in range(n1):
        Qm = vrow(Q, m, c)
        T = vnorm(vsub(Ft, Qm))
        if T < tmin:
            tmin = T
            k = m
        qmax = max(qmax, vmaxabs(Qm))
    ztol = 1e-13 * max(qmax, 1e-300)
    Qk = vrow(Q, k, c)
    g = vscale(c, -1.0)
    radius = 0.0
    for m in range(n1):
        d = vsub(Qk, vrow(Q, m, c))
        T = vnorm(d)
        if T <= ztol:
            radius += S[m]
        else:
            g = vadd(g, vscale(d, S[m] * (1.0 / T + eps)))
    gn = vnorm(g)
    if gn <= radius:
        return False
    u = vdiv(vscale(g, -1.0), gn)
    hi = 1e-9 * max(qmax, vmaxabs(Ft), 1e-300)
    for _ in range(200):
        if _slope(S, Q, eps, c, vadd(Qk, vscale(u, hi)), u) >= 0.0:
            break
        hi *= 4.0
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _slope(S, Q, eps, c, vadd(Qk, vscale(u, mid)), u) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    vstore(F, 0, vadd(Qk, vscale(u, 0.5 * (lo + hi))))
    return True


@njit
def _power(x, p):
    out = 1.0
    for _ in range(p):
        out *= x
    return out


@njit
def minimise(S, Q, eps, c, F, tol, maxit):
    """Damped Newton on Phi from the start ``F`` (array, updated in place) until the closure
    error is below ``tol``.

    Returns the number of iterations, or :data:`FAIL_ITERATIONS` (not converged in ``maxit``),
    :data:`FAIL_STALLED` (the line search stalled at kinks :data:`MAX_ESCAPES` times) or
    :data:`FAIL_SLACK` (a kink with no descent: a slack segment).
    """
    dim = len(c)
    Ft = vload(F, 0, c)
    phi, g, h, tmin = energy(S, Q, eps, c, Ft)
    gn = vnorm(g)
    it = 0
    escapes = 0
    while gn > tol:
        if it >= maxit:
            return FAIL_ITERATIONS
        it += 1
        tr = mtrace(h)
        if mdet(h) <= 1e-12 * _power(tr, dim):  # (nearly) parallel segments: regularise
            h = madd_diag(h, 1e-6 * tr)
        d = vscale(msym_solve(h, g), -1.0)
        slope = vdot(g, d)
        step = 1.0
        stalled = False
        while True:
            phin, gnew, hn, tminn = energy(S, Q, eps, c, vadd(Ft, vscale(d, step)))
            gnn = vnorm(gnew)
            if phin <= phi + 1e-4 * step * slope or gnn < 0.5 * gn:
                break
            step *= 0.5
            if step < 1e-10:
                stalled = True
                break
        fnorm = vnorm(vadd(Ft, vscale(d, step)))
        if stalled or tminn < 1e-9 * max(fnorm, 1e-300):
            if escapes >= MAX_ESCAPES:
                return FAIL_STALLED
            escapes += 1
            if not stalled:
                Ft = vadd(Ft, vscale(d, step))
            vstore(F, 0, Ft)
            if not escape_kink(S, Q, eps, c, F):
                return FAIL_SLACK
            Ft = vload(F, 0, c)
            phi, g, h, tmin = energy(S, Q, eps, c, Ft)
            gn = vnorm(g)
            continue
        Ft = vadd(Ft, vscale(d, step))
        vstore(F, 0, Ft)
        phi, g, h, tmin, gn = phin, gnew, hn, tminn, gnn
    vstore(F, 0, Ft)
    return it


@njit
def polish(S, Q, c, F, steps):
    """Plain Newton steps on the inextensible closure ``sum_k S_k e_k = c`` after
    :func:`minimise`, whose stopping test leaves ``F`` accurate only to its tolerance: quadratic
    convergence takes it to round-off, so that ``x(P)`` no longer depends on the warm start."""
    for _ in range(steps):
        Ft = vload(F, 0, c)
        g = vscale(c, -1.0)
        h = mzero(c)
        for k in range(S.size):
            f = vsub(Ft, vrow(Q, k, c))
            T = vnorm(f)
            e = vdiv(f, T)
            g = vadd(g, vscale(e, S[k]))
            h = madd(h, mblock(S[k] / T, 0.0, e))
        if not mdet(h) > 0.0:
            return
        vstore(F, 0, vsub(Ft, msym_solve(h, g)))


@njit
def start_along_chord(S, Q, eps, c, F):
    """A kink-free start for :func:`minimise`: the minimiser of Phi on the line through the mean
    segment force along the chord (a convex 1-D problem: bracket the root of its slope, then
    regula falsi with the Illinois rule), into ``F``. Returns False if no bracket is found.

    For loads and lengths in scaled units (chord 1, load scale 1): the bracket starts at +-1.
    """
    n1 = S.size
    base = vzero(c)
    for k in range(n1):
        base = vadd(base, vrow(Q, k, c))
    base = vdiv(base, float(n1))
    u = vdiv(c, vnorm(c))
    hi = 1.0
    while _slope(S, Q, eps, c, vadd(base, vscale(u, hi)), u) <= 0.0:
        hi *= 4.0
        if hi > 1e30:
            return False
    lo = -1.0
    while _slope(S, Q, eps, c, vadd(base, vscale(u, lo)), u) >= 0.0:
        lo *= 4.0
        if lo < -1e30:
            return False
    flo = _slope(S, Q, eps, c, vadd(base, vscale(u, lo)), u)
    fhi = _slope(S, Q, eps, c, vadd(base, vscale(u, hi)), u)
    side = 0
    for _ in range(400):
        if hi - lo <= 1e-14 + 1e-12 * max(abs(lo), abs(hi)):
            break
        mid = (lo * fhi - hi * flo) / (fhi - flo)
        if not (lo < mid < hi):
            mid = 0.5 * (lo + hi)
        fm = _slope(S, Q, eps, c, vadd(base, vscale(u, mid)), u)
        if fm == 0.0:
            lo = hi = mid
            break
        if fm < 0.0:
            lo, flo = mid, fm
            if side == -1:
                fhi *= 0.5
            side = -1
        else:
            hi, fhi = mid, fm
            if side == 1:
                flo *= 0.5
            side = 1
    vstore(F, 0, vadd(base, vscale(u, 0.5 * (lo + hi))))
    return True


@njit
def segment_forces(S, Q, eps, c, F, Fk, T, e, lengths):
    """The segments' force vectors ``F_k = F - Q_k`` (into ``Fk``, (n + 1, DIM)), tensions
    ``T_k = |F_k|``, unit vectors ``e_k`` and stretched lengths ``l_k = S_k (1 + eps T_k)`` at
    the segment-1 force ``F``; returns the closure error ``|sum_k l_k e_k - c|``."""
    dim = len(c)
    Ft = vload(F, 0, c)
    g = vscale(c, -1.0)
    for k in range(S.size):
        f = vsub(Ft, vrow(Q, k, c))
        Tk = vnorm(f)
        T[k] = Tk
        lengths[k] = S[k] * (1.0 + eps * Tk)
        ek = vdiv(f, max(Tk, 1e-300))
        for d in range(dim):
            Fk[k, d] = f[d]
            e[k, d] = ek[d]
        g = vadd(g, vscale(ek, lengths[k]))
    return vnorm(g)
