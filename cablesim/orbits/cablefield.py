"""The cable's equations of motion as a first-order vector field on the physical state.

``M y'' + C y' + P(y) = F0 + gamma FL sin(theta)``, ``theta = omega t``, written for the state
``x = (z, v)`` with ``z = y - y0`` (displacement from the static equilibrium) and ``v = y'``::

    z' = v
    v' = M^-1 (F0 + gamma FL sin(theta) - C v - P(y0 + z))

with Jacobian ``[[0, I], [-M^-1 K, -M^-1 C]]``, ``K = dP/dy``. Its trace is ``-tr(M^-1 C)``,
constant, in both analyses.

- Exact analysis: ``P(y)`` and ``K(y)`` of the deformed configuration, the same mechanics as
  :func:`cablesim.dynamics.kernels.exact_force_and_stiffness` written in displacement form
  (:func:`force_and_stiffness`): the segment stretch is computed as
  ``l - S = (|d0|^2 - S^2 + 2 d0.dd + dd.dd) / (l + S)`` from the equilibrium segment vector
  ``d0`` and its change ``dd``, so the force follows a small ``z`` with full relative precision
  instead of the round-off of ``y0 + z`` (about 1e-14 of the coordinates). A slack segment stops
  the integration with :data:`~cablesim.dynamics.kernels.SLACK`. The field runs at every stage
  of every step: it indexes ``prm``, ``work`` and ``J`` directly (no array views) and its helpers
  are inlined.
- Approximate analysis: ``P`` is defined implicitly by ``y = x(P) + u(P)``; an inner damped
  Newton iteration ``P <- P + a N(P)^-1 (y - x(P) - u(P))`` (``N = D + f = dy/dP``), warm-started
  from the previous call, converges to round-off (:func:`solve_loads`); from too far away (the
  first call of an integration starts at the equilibrium's ``F0``) it walks from the warm
  start's configuration to ``y`` in 16 steps. Then ``K = N^-1``. Each inner step solves the
  inextensible closure for ``x(P)`` to round-off (:func:`polish_closure`), so the flow map does
  not depend on the warm starts beyond round-off.

  Round-off of the inner solve: ``x(P)`` is a sum of ``S_k e_k`` in absolute coordinates, so the
  residual ``y - x(P) - u(P)`` is resolved only to a few ulps of the cable's length (measured up
  to 5 ulps of ``sum S``), and the loads only to ``|N^-1|`` (about ``EA / S_k``) times that:
  some ``EA`` machine epsilons (1e-6 N for ``EA = 1e9`` N), an absolute level independent of
  the loads. Relative to ``|P|`` it is 6e-13 on the paper's example but 1e-11 on
  ``configs/paper/fig6.yaml`` (the same ``EA``, a thirteenth of the loads): a stopping test on
  the correction relative to ``|P|`` alone cannot be met on light loads, and a line search that
  insists on a decreasing residual fails on the floor. The iteration therefore stops when the
  residual reaches its round-off level (:data:`FLOOR_ULPS` ulps of the length,
  :func:`residual_floor`) or the correction is small, whichever comes first, and takes one more
  full step (at quadratic convergence that leaves P at its round-off level wherever it
  stopped); a damped step that lands on the floor is accepted.

The vector fields follow the contract of :mod:`cablesim.orbits.kernels` (``FIELD_SIG``): the
model's constants are packed into one float array ``prm`` (layout in :func:`pack`), the scratch
space and warm starts into ``work``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from ..jit import njit

from ..dynamics import kernels as dk
from .kernels import FIELD_SIG, INNER_SOLVE, OK, SLACK

#: Round-off level of the approximate analysis' inner residual ``y - x(P) - u(P)``, in ulps of
#: the cable's length (measured up to 5 on ``configs/paper/fig6.yaml``, 1.5 on the paper's
#: example; :func:`residual_floor`). The final Newton step from there leaves P at its own
#: round-off level, so the margin costs no accuracy.
FLOOR_ULPS = 32.0


@dataclass(frozen=True)
class Layout:
    """Offsets of the packed parameter array (see :func:`pack`)."""

    nd: int
    S: int
    EA: int
    m: int
    C: int
    F0: int
    FL: int
    gamma: int
    y0: int
    tol: int
    size: int


@njit(inline="always")
def param_offsets(nd):
    """Offsets ``(S, EA, m, C, F0, FL, gamma, y0, tol, size)`` of the packed parameter array of
    ``nd`` DOF (see :func:`pack`): the one statement of its layout, for the kernels and Python."""
    o_S = 1
    o_EA = o_S + nd // 2 + 1  # EA, L, H
    o_m = o_EA + 3
    o_C = o_m + nd
    o_F0 = o_C + nd * nd
    o_FL = o_F0 + nd
    o_g = o_FL + nd
    o_y0 = o_g + 1
    o_tol = o_y0 + nd
    return o_S, o_EA, o_m, o_C, o_F0, o_FL, o_g, o_y0, o_tol, o_tol + 1


def layout(nd: int) -> Layout:
    """The offsets of :func:`param_offsets` by name."""
    return Layout(nd, *(int(o) for o in param_offsets(nd)))


def pack(eom, gamma: float = 1.0) -> np.ndarray:
    """``[nd, S, EA, L, H, m, C (row-major), F0, FL, gamma, y0, tol]`` of an
    :class:`~cablesim.dynamics.equations.EquationsOfMotion`."""
    c = eom.cable
    nd = eom.n_dof
    tol = 1e-13 * max(c.total_length, c.chord_length)
    parts = [
        [float(nd)], np.asarray(c.S, float), [float(c.EA), float(c.L), float(c.H)],
        np.asarray(eom.mass, float), np.asarray(eom.C, float).ravel(), np.asarray(eom.F0, float),
        np.asarray(eom.FL, float), [float(gamma)], np.asarray(eom.y0, float), [tol],
    ]
    prm = np.ascontiguousarray(np.concatenate([np.asarray(p, float) for p in parts]))
    assert prm.size == layout(nd).size
    return prm


def exact_work(eom) -> np.ndarray:
    """Scratch space of :func:`exact_field`: ``y``, ``P``."""
    return np.zeros(2 * eom.n_dof)


def approximate_work(eom) -> np.ndarray:
    """Scratch space and warm starts of :func:`approximate_field` (``P`` starts at ``F0`` and
    the inextensible closure at the equilibrium's segment-1 force ``F1``)."""
    nd = eom.n_dof
    nn = nd // 2
    w = np.zeros(_approx_size(nd))
    w[nd : 2 * nd] = eom.F0
    w[2 * nd : 2 * nd + 2] = eom.F1
    assert nn >= 1
    return w


def _approx_size(nd):
    nn = nd // 2
    # y, P, F1, Q, x, u, T, N, LU, r, d, e_k, a, b, e, gt, W, acc, Pt, Pw, yt, F1t, F1w
    return nd + nd + 2 + 2 * (nn + 1) + nd + nd + (nn + 1) + nd * nd + nd * nd + nd + nd + nd \
        + 2 * (nn + 1) * nd + 2 * (nn + 1) + (nn + 1) + 4 * nd + 3 * nd + 4


@njit(inline="always")
def _node(prm, o_y0, j, n, L, H):
    """Equilibrium coordinates of node ``j`` (``0 .. n-1`` the masses, ``-1`` and ``n`` the
    supports), from ``y0`` at ``prm[o_y0:]``."""
    if j < 0:
        return 0.0, 0.0
    if j >= n:
        return L, H
    return prm[o_y0 + 2 * j], prm[o_y0 + 2 * j + 1]


@njit(inline="always")
def force_and_stiffness(x, prm, o_y0, o_S, EA, L, H, P, o_P, J, nd):
    """Resisting force ``P(y0 + z)`` into ``P[o_P : o_P + nd]`` and tangent stiffness ``K`` into
    ``J[nd:, :nd]`` (displacement form, module docstring; ``z = x[:nd]``, ``y0`` at
    ``prm[o_y0:]``, ``S`` at ``prm[o_S:]``); returns the first slack segment or -1. Indexes its
    arrays directly (no views: this runs at every stage of every step)."""
    n = nd // 2
    for i in range(nd):
        P[o_P + i] = 0.0
        for j in range(nd):
            J[nd + i, j] = 0.0
    slack = -1
    for k in range(n + 1):
        ax, ay = _node(prm, o_y0, k - 1, n, L, H)
        bx, by = _node(prm, o_y0, k, n, L, H)
        d0x = bx - ax
        d0y = by - ay
        zax, zay = (0.0, 0.0) if k == 0 else (x[2 * k - 2], x[2 * k - 1])
        zbx, zby = (0.0, 0.0) if k == n else (x[2 * k], x[2 * k + 1])
        ddx = zbx - zax
        ddy = zby - zay
        dx = d0x + ddx
        dy = d0y + ddy
        l = np.sqrt(dx * dx + dy * dy)
        Sk = prm[o_S + k]
        num = (d0x * d0x + d0y * d0y - Sk * Sk) + 2.0 * (d0x * ddx + d0y * ddy) + (ddx * ddx + ddy * ddy)
        stretch = num / (l + Sk)
        T = EA * stretch / Sk
        if T <= 0.0 and slack < 0:
            slack = k
        e0, e1 = dx / l, dy / l
        ka = EA / Sk
        kg = T / l
        k00 = kg + (ka - kg) * e0 * e0
        k01 = (ka - kg) * e0 * e1
        k11 = kg + (ka - kg) * e1 * e1
        a = 2 * (k - 1)  # DOFs of the segment's start node (a mass if k > 0)
        b = 2 * k  # and of its end node (a mass if k < n)
        if k < n:
            P[o_P + b] += T * e0
            P[o_P + b + 1] += T * e1
            _add_block(J, nd + b, b, k00, k01, k11)
        if k > 0:
            P[o_P + a] -= T * e0
            P[o_P + a + 1] -= T * e1
            _add_block(J, nd + a, a, k00, k01, k11)
        if k > 0 and k < n:
            _add_block(J, nd + a, b, -k00, -k01, -k11)
            _add_block(J, nd + b, a, -k00, -k01, -k11)
    return slack


@njit(inline="always")
def _add_block(J, r, c, k00, k01, k11):
    """``J[r:r+2, c:c+2] += [[k00, k01], [k01, k11]]``."""
    J[r, c] += k00
    J[r, c + 1] += k01
    J[r + 1, c] += k01
    J[r + 1, c + 1] += k11


@njit(inline="always")
def _second_order(theta, x, prm, P, dx, J, dp, ipar, nd, o_m, o_C, o_F0, o_FL, o_g):
    """Fill dx, the lower blocks of J (K already in ``J[nd:, :nd]``) and dp."""
    sn = np.sin(theta)
    g = prm[o_g]
    for i in range(nd):
        dx[i] = x[nd + i]
        rm = 1.0 / prm[o_m + i]
        acc = prm[o_F0 + i] + g * prm[o_FL + i] * sn - P[i]
        for j in range(nd):
            cij = prm[o_C + i * nd + j]
            acc -= cij * x[nd + j]
            J[nd + i, nd + j] = -cij * rm
            J[nd + i, j] = -J[nd + i, j] * rm
            J[i, j] = 0.0
            J[i, nd + j] = 0.0
        J[i, nd + i] = 1.0
        dx[nd + i] = acc * rm
    if ipar == o_g:
        for i in range(nd):
            dp[i] = 0.0
            dp[nd + i] = prm[o_FL + i] * sn / prm[o_m + i]
    elif ipar >= 0:
        for i in range(2 * nd):
            dp[i] = 0.0


@njit(FIELD_SIG)
def exact_field(theta, x, prm, work, dx, J, dp, ipar):
    """Exact analysis (module docstring)."""
    nd = int(prm[0])
    o_S, o_EA, o_m, o_C, o_F0, o_FL, o_g, o_y0, _, _ = param_offsets(nd)
    # P lives in work[nd : 2 nd]
    slack = force_and_stiffness(x, prm, o_y0, o_S, prm[o_EA], prm[o_EA + 1], prm[o_EA + 2], work, nd, J, nd)
    if slack >= 0:
        return SLACK
    _second_order(theta, x, prm, work[nd : 2 * nd], dx, J, dp, ipar, nd, o_m, o_C, o_F0, o_FL, o_g)
    return OK


@njit
def polish_closure(S, Q, L, H, F, steps):
    """Plain Newton steps on the inextensible closure ``sum_k S_k e_k = (L, H)`` after
    :func:`cablesim.dynamics.kernels.closure_solve`, whose stopping test leaves the segment
    force accurate only to its tolerance: quadratic convergence takes it to round-off, so the
    configuration ``x(P)`` no longer depends on the warm start."""
    for _ in range(steps):
        g0 = -L
        g1 = -H
        h00 = 0.0
        h01 = 0.0
        h11 = 0.0
        for k in range(S.size):
            f0 = F[0] - Q[k, 0]
            f1 = F[1] - Q[k, 1]
            T = np.sqrt(f0 * f0 + f1 * f1)
            e0 = f0 / T
            e1 = f1 / T
            g0 += S[k] * e0
            g1 += S[k] * e1
            w = S[k] / T
            h00 += w * e1 * e1
            h01 -= w * e0 * e1
            h11 += w * e0 * e0
        det = h00 * h11 - h01 * h01
        if not det > 0.0:
            return
        F[0] -= (h11 * g0 - h01 * g1) / det
        F[1] -= (h00 * g1 - h01 * g0) / det


@njit
def _inner_state(P, F1, S, EA, L, H, tol, Q, xx, u, T, N, fw):
    """Inextensible closure (to round-off) and ``x, u, T, N`` at loads P; False if it fails
    (no closure, or a slack segment)."""
    dk.cumulative_loads(P, Q)
    if dk.closure_solve(S, Q, 0.0, L, H, F1, tol, 60) < 0:
        return False
    polish_closure(S, Q, L, H, F1, 2)
    dk.approximate_flexibility(S, EA, Q, F1, xx, u, T, N, fw)
    for k in range(T.size):
        if not T[k] > 0.0:
            return False
    return True


@njit
def _residual(yt, xx, u, r):
    big = 0.0
    for i in range(yt.size):
        r[i] = yt[i] - xx[i] - u[i]
        big = max(big, abs(r[i]))
    return big


@njit
def residual_floor(S, L, H):
    """Round-off level of the residual ``y - x(P) - u(P)``: :data:`FLOOR_ULPS` ulps of the
    cable's length (module docstring)."""
    return FLOOR_ULPS * np.finfo(np.float64).eps * max(np.sum(S), np.sqrt(L * L + H * H))


@njit
def solve_loads(yt, P, F1, S, EA, L, H, tol, maxit, Q, xx, u, T, N, fw, LU, r, d, Pt, F1t):
    """Damped Newton for the loads ``P`` with ``x(P) + u(P) = yt``, from ``(P, F1)`` (updated).

    The step is halved until the residual decreases (the configuration ``x(P)`` turns fast with
    the direction of P: full steps from far away overshoot). Converged when the residual is at
    its round-off level (:func:`residual_floor`), or once a full step is below 1e-9 of ``|P|``;
    one more full step is then taken (quadratic convergence: P to round-off). Near the floor
    the residual cannot decrease reliably, so a step that lands on it is accepted. ``N`` (and
    ``x, u, T``) belong to the last iterate before that final step. Returns True on
    convergence.
    """
    nd = P.size
    if not _inner_state(P, F1, S, EA, L, H, tol, Q, xx, u, T, N, fw):
        return False
    floor = residual_floor(S, L, H)
    rn = _residual(yt, xx, u, r)
    done = False
    for it in range(maxit):
        if not dk.solve_small(N, r, d, LU):
            return False
        dmax = 0.0
        pmax = 0.0
        for i in range(nd):
            dmax = max(dmax, abs(d[i]))
            pmax = max(pmax, abs(P[i]))
        if not np.isfinite(dmax):
            return False
        if done or rn <= floor or dmax <= 1e-12 * pmax:
            for i in range(nd):
                P[i] += d[i]
            return True
        a = 1.0
        accepted = False
        for ls in range(30):
            for i in range(nd):
                Pt[i] = P[i] + a * d[i]
            F1t[0] = F1[0]
            F1t[1] = F1[1]
            if _inner_state(Pt, F1t, S, EA, L, H, tol, Q, xx, u, T, N, fw):
                rt = _residual(yt, xx, u, r)
                if rt < (1.0 - 0.25 * a) * rn or rt <= floor:
                    accepted = True
                    rn = rt
                    break
            a *= 0.5
        if not accepted:
            return False
        for i in range(nd):
            P[i] = Pt[i]
        F1[0] = F1t[0]
        F1[1] = F1t[1]
        if a == 1.0 and dmax <= 1e-9 * pmax:
            done = True
    return False


@njit
def _approximate_scratch(work, nd):
    """Views of :func:`approximate_field`'s scratch space, in the order of :func:`_approx_size`:
    ``(y, P, F1, Q, xx, u, T, N, LU, r, d, ek, fw, Pt, Pw, yt, F1t, F1w)``, ``fw`` the workspace
    of :func:`cablesim.dynamics.kernels.approximate_flexibility`."""
    nn = nd // 2
    o = 0
    y = work[o : o + nd]
    o += nd
    P = work[o : o + nd]
    o += nd
    F1 = work[o : o + 2]
    o += 2
    Q = work[o : o + 2 * (nn + 1)].reshape((nn + 1, 2))
    o += 2 * (nn + 1)
    xx = work[o : o + nd]
    o += nd
    u = work[o : o + nd]
    o += nd
    T = work[o : o + nn + 1]
    o += nn + 1
    N = work[o : o + nd * nd].reshape((nd, nd))
    o += nd * nd
    LU = work[o : o + nd * nd].reshape((nd, nd))
    o += nd * nd
    r = work[o : o + nd]
    o += nd
    d = work[o : o + nd]
    o += nd
    ek = work[o : o + nd]
    o += nd
    fa = work[o : o + (nn + 1) * nd].reshape((nn + 1, nd))
    o += (nn + 1) * nd
    fb = work[o : o + (nn + 1) * nd].reshape((nn + 1, nd))
    o += (nn + 1) * nd
    fe = work[o : o + 2 * (nn + 1)].reshape((nn + 1, 2))
    o += 2 * (nn + 1)
    fgt = work[o : o + nn + 1]
    o += nn + 1
    fW = work[o : o + 2 * nd].reshape((2, nd))
    o += 2 * nd
    facc = work[o : o + 2 * nd].reshape((2, nd))
    o += 2 * nd
    fw = (fa, fb, fe, fgt, fW, facc)
    Pt = work[o : o + nd]
    o += nd
    Pw = work[o : o + nd]
    o += nd
    yt = work[o : o + nd]
    o += nd
    F1t = work[o : o + 2]
    o += 2
    F1w = work[o : o + 2]
    o += 2
    assert o <= work.size
    return y, P, F1, Q, xx, u, T, N, LU, r, d, ek, fw, Pt, Pw, yt, F1t, F1w


@njit
def _walk_to_loads(y, P, F1, Pw, F1w, S, EA, L, H, tol, Q, xx, u, T, N, fw, LU, r, d, Pt, F1t, yt):
    """Loads at ``y`` from far away: restart from the warm start ``(Pw, F1w)`` and walk from its
    own configuration to ``y`` in 16 steps, each solved by :func:`solve_loads`; False if any
    step fails."""
    nd = P.size
    for i in range(nd):
        P[i] = Pw[i]
    F1[0] = F1w[0]
    F1[1] = F1w[1]
    if not _inner_state(P, F1, S, EA, L, H, tol, Q, xx, u, T, N, fw):
        return False
    for i in range(nd):
        Pw[i] = xx[i] + u[i]  # y of the warm start (Pw reused)
    K = 16
    for k in range(1, K + 1):
        f = k / K
        for i in range(nd):
            yt[i] = Pw[i] + f * (y[i] - Pw[i])
        if not solve_loads(yt, P, F1, S, EA, L, H, tol, 40, Q, xx, u, T, N, fw, LU, r, d, Pt, F1t):
            return False
    return True


@njit(FIELD_SIG)
def approximate_field(theta, x, prm, work, dx, J, dp, ipar):
    """Approximate analysis (module docstring)."""
    nd = int(prm[0])
    nn = nd // 2
    o_S, o_EA, o_m, o_C, o_F0, o_FL, o_g, o_y0, o_tol, _ = param_offsets(nd)
    S = prm[o_S : o_S + nn + 1]
    EA, L, H = prm[o_EA], prm[o_EA + 1], prm[o_EA + 2]
    tol = prm[o_tol]
    y, P, F1, Q, xx, u, T, N, LU, r, d, ek, fw, Pt, Pw, yt, F1t, F1w = _approximate_scratch(work, nd)
    for i in range(nd):
        y[i] = prm[o_y0 + i] + x[i]
        Pw[i] = P[i]
    F1w[0] = F1[0]
    F1w[1] = F1[1]
    if not solve_loads(y, P, F1, S, EA, L, H, tol, 40, Q, xx, u, T, N, fw, LU, r, d, Pt, F1t):
        if not _walk_to_loads(y, P, F1, Pw, F1w, S, EA, L, H, tol, Q, xx, u, T, N, fw, LU, r, d, Pt, F1t, yt):
            return INNER_SOLVE
    for k in range(nn + 1):
        if T[k] <= 0.0:
            return SLACK
    # K = N^-1 into J[nd:, :nd]
    for j in range(nd):
        for i in range(nd):
            ek[i] = 0.0
        ek[j] = 1.0
        if not dk.solve_small(N, ek, d, LU):
            return INNER_SOLVE
        for i in range(nd):
            J[nd + i, j] = d[i]
    _second_order(theta, x, prm, P, dx, J, dp, ipar, nd, o_m, o_C, o_F0, o_FL, o_g)
    return OK
