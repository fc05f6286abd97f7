"""Compiled physics for the time loop.

The same mechanics as :mod:`cablesim.statics`, written as scalar loops that numba compiles, so
that one right-hand-side evaluation of the equations of motion costs well under a microsecond
for the paper's 2-node cable. :mod:`cablesim.statics` (vectorised numpy, with full error
reporting) stays the reference; the tests check these kernels against it.

Conventions: ``pts[0] = A``, ``pts[1..n]`` the interior nodes, ``pts[n+1] = B``; segment ``k``
(0-based) joins ``pts[k]`` to ``pts[k+1]``; DOF block ``i`` is interior node ``i + 1``.
Every kernel returns a status code (:data:`OK` or a failure) instead of raising.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from .banded import BAND_HALF
from .status import Status

# Status codes returned by the kernels: the values of :class:`cablesim.dynamics.status.Status`.
OK = int(Status.COMPLETED)
NONFINITE = int(Status.NONFINITE)
SLACK = int(Status.SLACK)
INNER_SOLVE = int(Status.INNER_SOLVE)
STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)


# ----------------------------------------------------------------------------------------------
# Exact model: forces and stiffness of a deformed configuration
# ----------------------------------------------------------------------------------------------
@njit
def _segment(y, k, n, L, H):
    """Difference vector of segment k in configuration y."""
    if k == 0:
        x0, y0 = 0.0, 0.0
    else:
        x0, y0 = y[2 * k - 2], y[2 * k - 1]
    if k == n:
        x1, y1 = L, H
    else:
        x1, y1 = y[2 * k], y[2 * k + 1]
    return x1 - x0, y1 - y0


@njit
def exact_tensions(y, S, EA, L, H, T):
    """Fill ``T`` with ``EA (l - S) / S``; return the first slack segment or -1."""
    n = S.size - 1
    slack = -1
    for k in range(n + 1):
        dx, dy = _segment(y, k, n, L, H)
        l = np.sqrt(dx * dx + dy * dy)
        T[k] = EA * (l - S[k]) / S[k]
        if T[k] <= 0.0 and slack < 0:
            slack = k
    return slack


@njit
def segment_gaps(y, S, L, H, g):
    """Fill ``g`` with ``l - S`` of every segment (negative: shorter than its natural length)."""
    n = S.size - 1
    for k in range(n + 1):
        dx, dy = _segment(y, k, n, L, H)
        g[k] = np.sqrt(dx * dx + dy * dy) - S[k]


@njit
def segment_gap(y, k, S, L, H):
    """``l - S`` of segment k in configuration y."""
    n = S.size - 1
    dx, dy = _segment(y, k, n, L, H)
    return np.sqrt(dx * dx + dy * dy) - S[k]


@njit
def tension_only_mask(y, S, L, H, taut):
    """``taut[k]`` = 1 where segment k is longer than its natural length, else 0 (slack)."""
    n = S.size - 1
    for k in range(n + 1):
        dx, dy = _segment(y, k, n, L, H)
        taut[k] = 1.0 if np.sqrt(dx * dx + dy * dy) > S[k] else 0.0


@njit
def exact_force_and_Kv(y, v, S, EA, L, H, P, Kv, taut):
    """Resisting force ``P(y)`` and the product ``K(y) v``; returns the first segment not longer
    than its natural length, or -1.

    ``taut[k]`` (1 or 0) multiplies segment k's force and stiffness: a segment the integrator
    treats as slack contributes nothing; one it treats as taut acts as a linear spring even if it
    is (within a step, before the event is located) slightly shorter than S.
    """
    n = S.size - 1
    P[:] = 0.0
    Kv[:] = 0.0
    slack = -1
    for k in range(n + 1):
        dx, dy = _segment(y, k, n, L, H)
        l = np.sqrt(dx * dx + dy * dy)
        e0, e1 = dx / l, dy / l
        T = EA * (l - S[k]) / S[k]
        if T <= 0.0 and slack < 0:
            slack = k
        T *= taut[k]
        # relative velocity of the segment's end over its start
        if k == n:
            dv0, dv1 = 0.0, 0.0
        else:
            dv0, dv1 = v[2 * k], v[2 * k + 1]
        if k > 0:
            dv0 -= v[2 * k - 2]
            dv1 -= v[2 * k - 1]
        ka = taut[k] * EA / S[k]
        kg = T / l
        ed = e0 * dv0 + e1 * dv1
        r0 = kg * dv0 + (ka - kg) * ed * e0
        r1 = kg * dv1 + (ka - kg) * ed * e1
        if k < n:  # segment ends at node k+1 (block k)
            P[2 * k] += T * e0
            P[2 * k + 1] += T * e1
            Kv[2 * k] += r0
            Kv[2 * k + 1] += r1
        if k > 0:  # segment starts at node k (block k-1)
            P[2 * k - 2] -= T * e0
            P[2 * k - 1] -= T * e1
            Kv[2 * k - 2] -= r0
            Kv[2 * k - 1] -= r1
    return slack


@njit
def segment_stiffness(y, k, n, S, EA, L, H, taut_k):
    """Segment ``k``'s tension, unit vector and 2x2 stiffness block ``(EA/S) e e^T + (T/l)(I - e e^T)``
    in configuration ``y``, scaled by ``taut_k`` (0 while slack): ``(T, e0, e1, k00, k01, k11,
    short)``, ``short`` whether the segment is not longer than its natural length."""
    dx, dy = _segment(y, k, n, L, H)
    l = np.sqrt(dx * dx + dy * dy)
    e0, e1 = dx / l, dy / l
    T = EA * (l - S[k]) / S[k]
    short = T <= 0.0
    T *= taut_k
    ka = taut_k * EA / S[k]
    kg = T / l
    return T, e0, e1, kg + (ka - kg) * e0 * e0, (ka - kg) * e0 * e1, kg + (ka - kg) * e1 * e1, short


@njit
def exact_force_and_stiffness(y, S, EA, L, H, P, K, taut):
    """Resisting force ``P(y)`` and the assembled tangent stiffness ``K(y)`` of the segments with
    ``taut[k] = 1`` (see :func:`exact_force_and_Kv`); the first segment not longer than S, or -1."""
    n = S.size - 1
    P[:] = 0.0
    K[:, :] = 0.0
    slack = -1
    for k in range(n + 1):
        T, e0, e1, k00, k01, k11, short = segment_stiffness(y, k, n, S, EA, L, H, taut[k])
        if short and slack < 0:
            slack = k
        i = k - 1  # start block
        j = k  # end block
        if j < n:
            P[2 * j] += T * e0
            P[2 * j + 1] += T * e1
            K[2 * j, 2 * j] += k00
            K[2 * j, 2 * j + 1] += k01
            K[2 * j + 1, 2 * j] += k01
            K[2 * j + 1, 2 * j + 1] += k11
        if i >= 0:
            P[2 * i] -= T * e0
            P[2 * i + 1] -= T * e1
            K[2 * i, 2 * i] += k00
            K[2 * i, 2 * i + 1] += k01
            K[2 * i + 1, 2 * i] += k01
            K[2 * i + 1, 2 * i + 1] += k11
        if i >= 0 and j < n:
            K[2 * i, 2 * j] -= k00
            K[2 * i, 2 * j + 1] -= k01
            K[2 * i + 1, 2 * j] -= k01
            K[2 * i + 1, 2 * j + 1] -= k11
            K[2 * j, 2 * i] -= k00
            K[2 * j, 2 * i + 1] -= k01
            K[2 * j + 1, 2 * i] -= k01
            K[2 * j + 1, 2 * i + 1] -= k11
    return slack


# ----------------------------------------------------------------------------------------------
# Inextensible closure and the approximate model's flexibility
# ----------------------------------------------------------------------------------------------
@njit
def _phi(S, Q, eps, L, H, F0, F1):
    """Complementary energy, its gradient and Hessian at segment-1 force (F0, F1)."""
    phi = -(F0 * L + F1 * H)
    g0 = -L
    g1 = -H
    h00 = 0.0
    h01 = 0.0
    h11 = 0.0
    tmin = np.inf
    for k in range(S.size):
        f0 = F0 - Q[k, 0]
        f1 = F1 - Q[k, 1]
        T = np.sqrt(f0 * f0 + f1 * f1)
        if T < tmin:
            tmin = T
        if T == 0.0:
            T = 1e-300
        e0 = f0 / T
        e1 = f1 / T
        lk = S[k] * (1.0 + eps * T)
        g0 += lk * e0
        g1 += lk * e1
        phi += S[k] * T * (1.0 + 0.5 * eps * T)
        wt = S[k] * (1.0 / T + eps)
        we = S[k] * eps
        h00 += wt * e1 * e1 + we * e0 * e0
        h01 += (we - wt) * e0 * e1
        h11 += wt * e0 * e0 + we * e1 * e1
    return phi, g0, g1, h00, h01, h11, tmin


@njit
def _escape_kink(S, Q, eps, L, H, F):
    """Move F out of the kink ``F = Q_k`` nearest to it, along the exact descent ray.

    At the kink the steepest-descent direction of Phi is ``-g_rest`` (the gradient of the other
    terms); if the segment is not slack Phi decreases along it, and the 1-D problem is convex:
    bisect its slope. Returns False if no descent exists (the segment is slack).
    """
    n1 = S.size
    k = 0
    tmin = np.inf
    qmax = 0.0
    for m in range(n1):
        T = np.sqrt((F[0] - Q[m, 0]) ** 2 + (F[1] - Q[m, 1]) ** 2)
        if T < tmin:
            tmin = T
            k = m
        qmax = max(qmax, abs(Q[m, 0]), abs(Q[m, 1]))
    ztol = 1e-13 * max(qmax, 1e-300)
    g0 = -L
    g1 = -H
    radius = 0.0
    for m in range(n1):
        d0 = Q[k, 0] - Q[m, 0]
        d1 = Q[k, 1] - Q[m, 1]
        T = np.sqrt(d0 * d0 + d1 * d1)
        if T <= ztol:
            radius += S[m]
        else:
            c = S[m] * (1.0 / T + eps)
            g0 += c * d0
            g1 += c * d1
    gn = np.sqrt(g0 * g0 + g1 * g1)
    if gn <= radius:
        return False
    u0 = -g0 / gn
    u1 = -g1 / gn
    hi = 1e-9 * max(qmax, abs(F[0]), abs(F[1]), 1e-300)
    for _ in range(200):
        r = _phi(S, Q, eps, L, H, Q[k, 0] + hi * u0, Q[k, 1] + hi * u1)
        if r[1] * u0 + r[2] * u1 >= 0.0:
            break
        hi *= 4.0
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        r = _phi(S, Q, eps, L, H, Q[k, 0] + mid * u0, Q[k, 1] + mid * u1)
        if r[1] * u0 + r[2] * u1 < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    F[0] = Q[k, 0] + 0.5 * (lo + hi) * u0
    F[1] = Q[k, 1] + 0.5 * (lo + hi) * u1
    return True


@njit
def closure_solve(S, Q, eps, L, H, F, tol, maxit):
    """Damped Newton on the complementary energy from the start ``F`` (updated in place).

    Near a kink of Phi (a segment force passing through zero) Newton's model is useless; there
    the iterate escapes along the exact descent ray (see :func:`_escape_kink`), as in
    :func:`cablesim.closure.solve_segment_forces`. Returns the number of iterations, or -1 if
    it failed (a slack segment, or no convergence).
    """
    phi, g0, g1, h00, h01, h11, tmin = _phi(S, Q, eps, L, H, F[0], F[1])
    gn = np.sqrt(g0 * g0 + g1 * g1)
    it = 0
    escapes = 0
    while gn > tol:
        if it >= maxit:
            return -1
        it += 1
        tr = h00 + h11
        det = h00 * h11 - h01 * h01
        if det <= 1e-12 * tr * tr:  # (nearly) parallel segments: regularise
            h00 += 1e-6 * tr
            h11 += 1e-6 * tr
            det = h00 * h11 - h01 * h01
        d0 = -(h11 * g0 - h01 * g1) / det
        d1 = -(h00 * g1 - h01 * g0) / det
        slope = g0 * d0 + g1 * d1
        step = 1.0
        stalled = False
        while True:
            phin, gn0, gn1, hn00, hn01, hn11, tminn = _phi(S, Q, eps, L, H, F[0] + step * d0, F[1] + step * d1)
            gnn = np.sqrt(gn0 * gn0 + gn1 * gn1)
            if phin <= phi + 1e-4 * step * slope or gnn < 0.5 * gn:
                break
            step *= 0.5
            if step < 1e-10:
                stalled = True
                break
        fnorm = np.sqrt((F[0] + step * d0) ** 2 + (F[1] + step * d1) ** 2)
        if stalled or tminn < 1e-9 * max(fnorm, 1e-300):
            if escapes >= 50:
                return -1
            escapes += 1
            if not stalled:
                F[0] += step * d0
                F[1] += step * d1
            if not _escape_kink(S, Q, eps, L, H, F):
                return -1
            phi, g0, g1, h00, h01, h11, tmin = _phi(S, Q, eps, L, H, F[0], F[1])
            gn = np.sqrt(g0 * g0 + g1 * g1)
            continue
        F[0] += step * d0
        F[1] += step * d1
        phi, g0, g1, h00, h01, h11, tmin, gn = phin, gn0, gn1, hn00, hn01, hn11, tminn, gnn
    return it


@njit
def cumulative_loads(P, Q):
    """``Q_k = sum_{j<k} P_j`` into Q of shape (n+1, 2)."""
    Q[0, 0] = 0.0
    Q[0, 1] = 0.0
    for k in range(1, Q.shape[0]):
        Q[k, 0] = Q[k - 1, 0] + P[2 * k - 2]
        Q[k, 1] = Q[k - 1, 1] + P[2 * k - 1]


@njit
def inextensible_tangents(S, Q, F, x, T, a, b, e, gt, W):
    """Positions, tensions and force derivatives of the inextensible cable at its solution.

    Fills ``x`` (2n), ``T`` (n+1) and the rows ``a_k = t_k . dF_k/dP``, ``b_k = e_k . dF_k/dP``
    (both (n+1, 2n)), using the scratch arrays ``e`` (n+1, 2), ``gt`` (n+1) and ``W`` (2, 2n);
    returns the entries (h00, h01, h11) of the inverse closure Hessian.
    """
    n = S.size - 1
    H00 = 0.0
    H01 = 0.0
    H11 = 0.0
    px = 0.0
    py = 0.0
    for k in range(n + 1):
        f0 = F[0] - Q[k, 0]
        f1 = F[1] - Q[k, 1]
        T[k] = np.sqrt(f0 * f0 + f1 * f1)
        e[k, 0] = f0 / T[k]
        e[k, 1] = f1 / T[k]
        gt[k] = S[k] / T[k]
        # t = (-e1, e0); G_k = gt t t^T
        H00 += gt[k] * e[k, 1] * e[k, 1]
        H01 -= gt[k] * e[k, 0] * e[k, 1]
        H11 += gt[k] * e[k, 0] * e[k, 0]
        if k < n:
            px += S[k] * e[k, 0]
            py += S[k] * e[k, 1]
            x[2 * k] = px
            x[2 * k + 1] = py
    det = H00 * H11 - H01 * H01
    i00 = H11 / det
    i01 = -H01 / det
    i11 = H00 / det
    # suffix sums of G_k for k > j give W_j = H^-1 sum_{k>j} G_k (2x2 per node j)
    s00 = 0.0
    s01 = 0.0
    s11 = 0.0
    for j in range(n - 1, -1, -1):
        k = j + 1
        s00 += gt[k] * e[k, 1] * e[k, 1]
        s01 -= gt[k] * e[k, 0] * e[k, 1]
        s11 += gt[k] * e[k, 0] * e[k, 0]
        W[0, 2 * j] = i00 * s00 + i01 * s01
        W[0, 2 * j + 1] = i00 * s01 + i01 * s11
        W[1, 2 * j] = i01 * s00 + i11 * s01
        W[1, 2 * j + 1] = i01 * s01 + i11 * s11
    for k in range(n + 1):
        t0 = -e[k, 1]
        t1 = e[k, 0]
        for c in range(2 * n):
            a[k, c] = t0 * W[0, c] + t1 * W[1, c]
            b[k, c] = e[k, 0] * W[0, c] + e[k, 1] * W[1, c]
        for j in range(min(k, n)):  # nodes j < k feel -I
            a[k, 2 * j] -= t0
            a[k, 2 * j + 1] -= t1
            b[k, 2 * j] -= e[k, 0]
            b[k, 2 * j + 1] -= e[k, 1]
    return i00, i01, i11


@njit
def approximate_flexibility(S, EA, Q, F, x, u, T, N, wk):
    """Natural state ``x``, elastic displacement ``u``, tensions and ``N = D + f`` at loads Q.

    The inextensible closure must already be solved (``F`` its segment-1 force). ``wk`` is a
    :func:`flexibility_workspace`.
    """
    n = S.size - 1
    m = 2 * n
    a, b, e, gt, W, acc = wk
    i00, i01, i11 = inextensible_tangents(S, Q, F, x, T, a, b, e, gt, W)
    # D rows: node r = sum_{k<=r} (S_k/T_k) t_k a_k
    N[:, :] = 0.0
    acc[:, :] = 0.0
    for r in range(n):
        f0 = F[0] - Q[r, 0]
        f1 = F[1] - Q[r, 1]
        e0 = f0 / T[r]
        e1 = f1 / T[r]
        g = S[r] / T[r]
        for c in range(m):
            acc[0, c] += g * (-e1) * a[r, c]
            acc[1, c] += g * e0 * a[r, c]
        for c in range(m):
            N[2 * r, c] = acc[0, c]
            N[2 * r + 1, c] = acc[1, c]
    # f = (1/EA) [B^T S B + A^T (S + c2) A + A^T c1 B + B^T c1 A] (see statics.elastic_flexibility)
    w0 = 0.0
    w1 = 0.0
    for k in range(n + 1):
        f0 = F[0] - Q[k, 0]
        f1 = F[1] - Q[k, 1]
        w0 += S[k] * f0
        w1 += S[k] * f1
    v0 = i00 * w0 + i01 * w1
    v1 = i01 * w0 + i11 * w1
    inv = 1.0 / EA
    u[:] = 0.0
    for k in range(n + 1):
        e0 = (F[0] - Q[k, 0]) / T[k]
        e1 = (F[1] - Q[k, 1]) / T[k]
        c1 = S[k] * (-e1 * v0 + e0 * v1) / (T[k] * T[k])
        c2 = S[k] * (e0 * v0 + e1 * v1) / (T[k] * T[k])
        sa = (S[k] + c2) * inv
        sb = S[k] * inv
        sc = c1 * inv
        for i in range(m):
            u[i] += S[k] * T[k] * b[k, i] * inv
            ai = a[k, i]
            bi = b[k, i]
            for j in range(m):
                N[i, j] += sb * bi * b[k, j] + sa * ai * a[k, j] + sc * (ai * b[k, j] + bi * a[k, j])
    # symmetrise (D is symmetric analytically; remove round-off asymmetry)
    for i in range(m):
        for j in range(i + 1, m):
            s = 0.5 * (N[i, j] + N[j, i])
            N[i, j] = s
            N[j, i] = s


def flexibility_workspace(n: int):
    """Scratch arrays for :func:`approximate_flexibility` of an n-node cable."""
    m = 2 * n
    return (
        np.empty((n + 1, m)),
        np.empty((n + 1, m)),
        np.empty((n + 1, 2)),
        np.empty(n + 1),
        np.empty((2, m)),
        np.empty((2, m)),
    )


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


# ----------------------------------------------------------------------------------------------
# Banded stiffness and solves (heavy cables: O(n) per Newton iteration)
# ----------------------------------------------------------------------------------------------
@njit
def exact_force_and_stiffness_band(y, S, EA, L, H, P, Kb, taut):
    """:func:`exact_force_and_stiffness` with ``K`` in banded storage
    (``Kb[BAND_HALF + i - j, j] = K[i, j]``, shape (BAND_ROWS, 2n), see
    :mod:`cablesim.dynamics.banded`); the first segment not longer than S, or -1."""
    n = S.size - 1
    P[:] = 0.0
    Kb[:, :] = 0.0
    slack = -1
    for k in range(n + 1):
        T, e0, e1, k00, k01, k11, short = segment_stiffness(y, k, n, S, EA, L, H, taut[k])
        if short and slack < 0:
            slack = k
        hb = BAND_HALF
        for b, sign in ((k - 1, -1.0), (k, 1.0)):  # start block (force -T e), end block (+T e)
            if 0 <= b < n:
                P[2 * b] += sign * T * e0
                P[2 * b + 1] += sign * T * e1
                Kb[hb, 2 * b] += k00  # diagonal block: K[2b + r, 2b + c] at Kb[hb + r - c, 2b + c]
                Kb[hb + 1, 2 * b] += k01
                Kb[hb - 1, 2 * b + 1] += k01
                Kb[hb, 2 * b + 1] += k11
        if k >= 1 and k < n:  # coupling of block k (rows) and block k-1 (columns), and its mirror
            c0 = 2 * (k - 1)
            Kb[hb + 2, c0] -= k00
            Kb[hb + 3, c0] -= k01
            Kb[hb + 1, c0 + 1] -= k01
            Kb[hb + 2, c0 + 1] -= k11
            c1 = 2 * k
            Kb[hb - 2, c1] -= k00
            Kb[hb - 1, c1] -= k01
            Kb[hb - 3, c1 + 1] -= k01
            Kb[hb - 2, c1 + 1] -= k11
    return slack
