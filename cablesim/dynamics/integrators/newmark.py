"""Implicit Newmark-family schemes on the second-order form of the equations of motion.

The third-order equation (17) is the time derivative of dynamic equilibrium (eq. 15),
``M y'' + C y' + P = F(t)``, with the internal force following the analysis' constitutive law:

- exact analysis: ``P = P(y)``, the resisting force of the deformed configuration;
- approximate analysis: the rate law ``P' = K(P) y'`` with ``K = N(P)^-1``, integrated over a
  step by the implicit midpoint rule ``P_{n+1} = P_n + K((P_n + P_{n+1})/2) (y_{n+1} - y_n)``.

Each step solves its equilibrium by Newton's method. Schemes:

- ``newmark``: average acceleration (``beta = 1/4``, ``gamma = 1/2``), second order,
  unconditionally stable and without numerical damping (the paper's second scheme);
- ``generalized-alpha``: Chung and Hulbert's scheme, second order, unconditionally stable, with
  numerical dissipation of the high modes set by the spectral radius ``rho_inf`` in [0, 1]
  (1: none, like ``newmark``; 0: annihilates the highest modes in one step). For stiff cables
  (very large EA) whose axial modes are far above the response of interest.

Here are the kernels of one step and of the fixed-step loop; the error-controlled loop is
:mod:`.adaptive`, the integrator classes :mod:`.implicit`.
"""

from __future__ import annotations

import numpy as np
from ...jit import njit

from ...mechanics import assembly as asm
from ...mechanics import banded as bd
from ...mechanics import flexibility as fx
from ...mechanics.linalg import solve_small
from ...mechanics.model import STOP
from ...mechanics.supports import add_support_damping, support_positions, support_velocities
from ..field import approximate_stiffness
from ..status import INNER_SOLVE, NONFINITE, OK, SLACK
from .base import hermite
from .events import locate_event


@njit
def _internal(model, z, P_n, z_n, warm, P1, K, first, wk, awk, check_slack, tb):
    """Internal force at the step end ``tb`` and its tangent; returns a status code.

    Newton iterates may pass through configurations with a segment shorter than its natural
    length (for a stiff cable the margin is microns): only the converged state is checked
    (``check_slack``); during the iteration such a segment acts as a linear spring.
    """
    nd = z.size
    y, Pm = wk.y, wk.v
    if awk is None:
        for i in range(nd):
            y[i] = model.y0[i] + z[i]
        A, B = support_positions(model, tb)
        if asm.force_and_stiffness(y, model.S, model.EA, A, B, wk.taut, P1, K) >= 0 and check_slack \
                and model.slack == STOP:
            return SLACK
        return OK
    # Implicit midpoint for the rate law P' = K(P) y': a few fixed-point sweeps on P_{n+1}.
    for i in range(nd):
        Pm[i] = P_n[i] if first else 0.5 * (P_n[i] + P1[i])
    scale = 0.0
    for i in range(nd):
        scale = max(scale, abs(P_n[i]))
    dz, Kdz = wk.P, wk.Kv
    for i in range(nd):
        dz[i] = z[i] - z_n[i]
    for _ in range(4):
        st = approximate_stiffness(model, Pm, warm, awk)
        if st != OK:
            return st
        fx.stiffness_product(awk.fac, awk.gi, dz, Kdz, awk.scratch, model.A)  # O(n): K = N^-1 is never inverted
        change = 0.0
        for i in range(nd):
            P1[i] = P_n[i] + Kdz[i]
            new = 0.5 * (P_n[i] + P1[i])
            change = max(change, abs(new - Pm[i]))
            Pm[i] = new
        if change <= 1e-13 * scale:
            break
    return OK  # awk holds the factors of K at the last midpoint's loads, for the Newton matrix


@njit
def store_state(s, z, v, a):
    """``s = (z, v, a)``."""
    nd = z.size
    s[:nd] = z
    s[nd : 2 * nd] = v
    s[2 * nd :] = a


@njit
def equilibrium_acceleration(model, t, v, P, a_out, Cv):
    """``y'' = M^-1 (F(t) - C y' - P)`` (eq. 15) from the internal force ``P`` the scheme carries.

    For the saved states of the approximate analysis, whose outputs (tensions, ``z_c``, ``z_e``)
    follow from eq. 15: the scheme's own acceleration variable approximates ``y''`` at
    ``t + (alpha_m - alpha_f) h``, which would make them first order in the step."""
    m, F0, FL, w = model.mass, model.F0, model.FL, model.omega
    bd.damping_product(model.C, model.Cr, v, 0, Cv)
    sw = np.sin(w * t)
    for q in range(m.size):
        a_out[q] = (F0[q] + FL[q] * sw - Cv[q] - P[q]) / m[q]


@njit
def write_step_outputs(model, awk, ta, tb, z, v, a, z1, v1, a1, P_a, P_b, ae, ae1, scratch, sa, sb, da, db, t_out,
                       out, j):
    """:func:`write_outputs` for an implicit step ``ta -> tb``: in the approximate analysis the
    saved ``y''`` comes from the carried internal forces ``P_a``, ``P_b`` (see
    :func:`equilibrium_acceleration`, into ``ae``, ``ae1``)."""
    if awk is None:
        return write_outputs(ta, tb, tb - ta, z, v, a, z1, v1, a1, sa, sb, da, db, t_out, out, j)
    equilibrium_acceleration(model, ta, v, P_a, ae, scratch[9])
    equilibrium_acceleration(model, tb, v1, P_b, ae1, scratch[9])
    return write_outputs(ta, tb, tb - ta, z, v, ae, z1, v1, ae1, sa, sb, da, db, t_out, out, j)


@njit
def write_outputs(ta, tb, h, z, v, a, z1, v1, a1, sa, sb, da, db, t_out, out, j):
    """Interpolate the step ``ta -> tb`` at the output instants it covers; the next index."""
    nd = z.size
    for q in range(nd):
        sa[q] = z[q]
        sa[nd + q] = v[q]
        sa[2 * nd + q] = a[q]
        sb[q] = z1[q]
        sb[nd + q] = v1[q]
        sb[2 * nd + q] = a1[q]
        jerk = (a1[q] - a[q]) / h
        da[q] = v[q]
        da[nd + q] = a[q]
        da[2 * nd + q] = jerk
        db[q] = v1[q]
        db[nd + q] = a1[q]
        db[2 * nd + q] = jerk
    while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
        hermite(ta, tb, sa, sb, da, db, t_out[j], out[j])
        j += 1
    return j


@njit
def _dense_newton(model, z, v, a, z1, v1, a1, P_n, P1, K, J, R, warm, wk, awk, coef, c_m, c_c, sf, first, tb, ta):
    """Residual ``R`` (minus the generalized-alpha equilibrium at ``ta``) and dense Newton matrix
    ``J`` for the step ending at ``tb``; a status code."""
    m, C, F0, FL = model.mass, model.C, model.F0, model.FL
    am, af = coef[0], coef[1]
    nd = m.size
    st = _internal(model, z1, P_n, z, warm, P1, K, first, wk, awk, False, tb)
    if st != OK:
        return st
    for q in range(nd):
        acc = m[q] * ((1.0 - am) * a1[q] + am * a[q]) + (1.0 - af) * P1[q] + af * P_n[q]
        acc -= F0[q] + FL[q] * sf
        for r in range(nd):
            acc += C[q, r] * ((1.0 - af) * v1[r] + af * v[r])
            J[q, r] = (1.0 - af) * K[q, r] + c_c * C[q, r]
        J[q, q] += c_m * m[q]
        R[q] = -acc
    if model.moving:  # minus the supports' part of the damping force
        vA, vB = support_velocities(model, ta)
        add_support_damping(model, vA, vB, R, 1.0)
    return OK


@njit
def _band_newton(model, z, v, a, z1, v1, a1, P_n, P1, Kb, J, R, Cv, wk, coef, c_m, c_c, sf, check_slack, tb, ta):
    """:func:`_dense_newton` in banded storage (exact analysis, banded damping), O(n): ``Kb``
    receives the tangent stiffness of the segment modes ``wk.taut``, ``Cv`` is scratch."""
    y = wk.y
    for q in range(model.mass.size):
        y[q] = model.y0[q] + z1[q]
    A, B = support_positions(model, tb)
    if asm.force_and_stiffness_band(y, model.S, model.EA, A, B, wk.taut, P1, Kb) >= 0 and check_slack \
            and model.slack == STOP:
        return SLACK
    _band_system(model, v, a, v1, a1, P_n, P1, Kb, J, R, Cv, coef, c_m, c_c, sf, ta)
    return OK


@njit
def _band_system(model, v, a, v1, a1, P_n, P1, Kb, J, R, Cv, coef, c_m, c_c, sf, ta):
    """The generalized-alpha residual ``R`` and the banded part of the Newton matrix
    ``J = c_m M + c_c C + (1 - af) K`` from the internal force ``P1`` and the banded ``Kb``."""
    m, C, F0, FL = model.mass, model.C, model.F0, model.FL
    am, af = coef[0], coef[1]
    nd = m.size
    for q in range(nd):
        R[q] = (1.0 - af) * v1[q] + af * v[q]  # the velocity C multiplies, for now
    bd.damping_product(C, model.Cr, R, 0, Cv)
    if model.moving:  # the supports' part of the damping force at the alpha instant
        vA, vB = support_velocities(model, ta)
        add_support_damping(model, vA, vB, Cv, -1.0)
    for q in range(nd):
        acc = m[q] * ((1.0 - am) * a1[q] + am * a[q]) + (1.0 - af) * P1[q] + af * P_n[q] + Cv[q]
        R[q] = F0[q] + FL[q] * sf - acc
    for d in range(J.shape[0]):
        for q in range(nd):
            J[d, q] = (1.0 - af) * Kb[d, q] + c_c * C[d, q]
    hb = bd.half_band(J)
    for q in range(nd):
        J[hb, q] += c_m * m[q]


@njit
def _approximate_newton(model, z, v, a, z1, v1, a1, P_n, P1, Kb, J, R, Cv, warm, wk, awk, coef, c_m, c_c, sf, first,
                        V, U, D):
    """:func:`_dense_newton` for the approximate analysis in O(n): the Newton matrix is the band
    ``J`` minus ``V^T D V`` of rank 4 (``V = [Cr, U]``: the low-rank parts of ``C`` and of
    ``K = B - U Gamma^-1 U^T``, see :mod:`cablesim.dynamics.flexibility`), for
    :func:`solve_band_low_rank`."""
    Cr = model.Cr
    af = coef[1]
    nd = model.mass.size
    dim = len(model.A)
    st = _internal(model, z1, P_n, z, warm, P1, Kb, first, wk, awk, False, 0.0)
    if st != OK:
        return st
    fx.stiffness_band(awk.fac, awk.gi, Kb, U, model.A)
    _band_system(model, v, a, v1, a1, P_n, P1, Kb, J, R, Cv, coef, c_m, c_c, sf, 0.0)
    D[:, :] = 0.0
    r = Cr.shape[1]
    for c in range(r):  # c_c C = c_c C_band - U (c_c G) U^T
        V[c, :] = Cr[:nd, c]
        for d in range(r):
            D[c, d] = c_c * Cr[nd + c, d]
    gi = awk.gi
    for c in range(dim):  # (1 - af) K = (1 - af) B - (1 - af) U Gamma^-1 U^T
        V[r + c, :] = U[:, c]
    for i in range(dim):
        for j in range(dim):
            D[r + i, r + j] = (1.0 - af) * gi[dim * i + j]
    return OK


@njit
def solve_band_low_rank(J, V, D, R, out, LU, Z, small):
    """Solve ``(J - V^T D V) out = R`` with ``J`` banded and ``V`` (k, nd) of small rank k, O(n):
    ``out = y + Z^T w`` with ``J y = R``, ``J Z^T = V^T`` and ``(I - D V Z^T) w = D V y``
    (Sherman-Morrison-Woodbury without inverting D, which may be singular)."""
    k = V.shape[0]
    if not bd.factor_band(J, LU):
        return False
    bd.solve_factored(LU, R, out)
    for c in range(k):
        bd.solve_factored(LU, V[c], Z[c])
    A, LUs = small
    Vy, VZ = np.empty(k), np.empty((k, k))
    for i in range(k):
        Vy[i] = np.dot(V[i], out)
        for j in range(k):
            VZ[i, j] = np.dot(V[i], Z[j])
    rhs, w = np.empty(k), np.empty(k)
    for i in range(k):
        rhs[i] = 0.0
        for j in range(k):
            rhs[i] += D[i, j] * Vy[j]
            acc = 0.0
            for m in range(k):
                acc += D[i, m] * VZ[m, j]
            A[i, j] = (1.0 if i == j else 0.0) - acc
    if not solve_small(A, rhs, w, LUs):
        return False
    for c in range(k):
        out += w[c] * Z[c]
    return True


@njit
def _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma):
    """Acceleration and velocity at the step end from the displacement ``z1`` (Newmark)."""
    for q in range(z.size):
        a1[q] = (z1[q] - z[q] - h * v[q]) / (beta * h * h) - (0.5 / beta - 1.0) * a[q]
        v1[q] = v[q] + h * ((1.0 - gamma) * a[q] + gamma * a1[q])


@njit
def scheme_acceleration(a, jerk, shift, out):
    """Generalized-alpha's acceleration variable for the step about to be taken, into ``out``.

    The scheme's acceleration approximates ``y''`` at ``t_n + (alpha_m - alpha_f) h``, not at
    ``t_n`` (Erlicher, Bonaventura and Bursi, 2002). The loops carry ``a = y''(t_n)`` and shift it
    by ``shift = (alpha_m - alpha_f) h`` with the last step's jerk ``dy''/dt``: carrying the
    scheme's own variable from one step size into the next would leave it at the wrong instant,
    an error of ``(alpha_m - alpha_f) (h_n - h_(n-1))`` times the jerk at every change of step,
    first order in the velocity wherever the steps vary (as an error-controlled run's do).
    Newmark: ``shift = 0``.
    """
    for q in range(a.size):
        out[q] = a[q] + shift * jerk[q]


@njit
def carried_acceleration(a_used, a1, h, shift, jerk):
    """After a step of size ``h`` that started from the scheme's ``a_used``: the jerk of the step
    into ``jerk`` and ``a1`` turned from the scheme's variable into ``y''`` at the step's end
    (the inverse of :func:`scheme_acceleration`)."""
    if shift == 0.0:
        return
    for q in range(a1.size):
        jerk[q] = (a1[q] - a_used[q]) / h
        a1[q] -= shift * jerk[q]


@njit
def galpha_step(model, z, v, a, P_n, warm, wk, awk, tb, h, coef, ztol, zround, maxit, z1, v1, a1, P1, scratch):
    """One step of size h ending at ``tb`` from ``(z, v, a, P_n)`` into ``(z1, v1, a1, P1)``.

    Newton stops at an increment below ``ztol`` (m), or below ``zround`` (m: near the rounding of
    the coordinates; 0 for none) once the increments no longer decrease.

    With banded damping every Newton iteration assembles and solves a banded system, O(n) (in
    the approximate analysis plus a rank-4 correction); otherwise a dense one.
    """
    am, af, beta, gamma = coef[0], coef[1], coef[2], coef[3]
    R, dz, K, J, LU, V, Z, U, D, Cv, small = scratch
    nd = z.size
    banded = awk is None and bd.is_band(model.C)
    approx_band = awk is not None and bd.is_band(model.C)
    c_m = (1.0 - am) / (beta * h * h)
    c_c = (1.0 - af) * gamma / (beta * h)
    ta = tb - af * h  # the instant the generalized-alpha equilibrium holds at
    sf = np.sin(model.omega * ta)
    for q in range(nd):
        z1[q] = z[q] + h * v[q] + 0.5 * h * h * a[q]  # predictor: constant acceleration
        P1[q] = P_n[q]
    converged = False
    previous = np.inf
    for it in range(maxit):
        _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma)
        if banded:
            _band_newton(model, z, v, a, z1, v1, a1, P_n, P1, K, J, R, dz, wk, coef, c_m, c_c, sf, False, tb, ta)
            solved = bd.solve_band(J, R, dz, LU)
        elif approx_band:
            st = _approximate_newton(model, z, v, a, z1, v1, a1, P_n, P1, K, J, R, Cv, warm, wk, awk, coef, c_m, c_c,
                                     sf, it == 0, V, U, D)
            if st != OK:
                return st
            solved = solve_band_low_rank(J, V, D, R, dz, LU, Z, small)
        else:
            st = _dense_newton(model, z, v, a, z1, v1, a1, P_n, P1, K, J, R, warm, wk, awk, coef, c_m, c_c, sf, it == 0,
                               tb, ta)
            if st != OK:
                return st
            solved = solve_small(J, R, dz, LU)
        if not solved:
            break
        big, step = 0.0, 0.0
        for q in range(nd):
            z1[q] += dz[q]
            big = max(big, abs(dz[q]))
            step = max(step, abs(z1[q] - z[q]))
        if not np.isfinite(big):
            break
        if big <= ztol + 1e-10 * step or (big <= zround and big >= previous):
            converged = True
            break
        previous = big
    if not converged:
        for q in range(nd):
            if not np.isfinite(z1[q]):
                return NONFINITE
        return INNER_SOLVE
    _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma)
    if banded:
        return _band_newton(model, z, v, a, z1, v1, a1, P_n, P1, K, J, R, dz, wk, coef, c_m, c_c, sf, True, tb, ta)
    return _internal(model, z1, P_n, z, warm, P1, K, False, wk, awk, True, tb)


@njit
def step_scratch(model):
    """Scratch arrays of :func:`galpha_step` (banded Newton matrices: O(n))."""
    nd = model.mass.size
    dim = len(model.A)
    rows = model.C.shape[0] if bd.is_band(model.C) else nd
    k = model.Cr.shape[1] + dim  # rank of the approximate analysis' correction (damping, stiffness)
    return (np.empty(nd), np.empty(nd), np.empty((rows, nd)), np.empty((rows, nd)), np.empty((rows, nd)),
            np.empty((k, nd)), np.empty((k, nd)), np.empty((nd, dim)), np.empty((k, k)), np.empty(nd),
            (np.empty((k, k)), np.empty((k, k))))


@njit
def fixed_step_advance(model, s, P_n, warm, wk, awk, evw, track, t0, h, i, i_end, t, coef, t_out, out, ztol, maxit,
                       jerk):
    """Steps on the grid ``t0 + i h`` up to step ``i_end`` from ``t``, split where a segment
    changes mode; returns ``(i, t, written, status, segment)`` as the explicit schemes do.
    ``jerk`` is the last step's ``dy''/dt`` (updated; see :func:`scheme_acceleration`)."""
    nd = model.mass.size
    z, v, a = s[:nd].copy(), s[nd : 2 * nd].copy(), s[2 * nd :].copy()
    z1, v1, a1, P1, a_used = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd)
    delta = coef[0] - coef[1]
    jerk_try = jerk.copy()
    scratch = step_scratch(model)
    sa, sb, da, db = np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd)
    ae, ae1 = np.empty(nd), np.empty(nd)
    j = 0
    while i < i_end:
        tb = t0 + (i + 1) * h
        if tb - t <= 1e-9 * h:  # an event ended at the grid point
            while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
                store_state(out[j], z, v, a)
                j += 1
            t, i = tb, i + 1
            continue
        scheme_acceleration(a, jerk, delta * (tb - t), a_used)
        st = galpha_step(model, z, v, a_used, P_n, warm, wk, awk, tb, tb - t, coef, ztol, 0.0, maxit, z1, v1, a1, P1,
                         scratch)
        if st != OK:
            store_state(s, z, v, a)
            return i, t, j, st, -1
        jerk_try[:] = jerk
        carried_acceleration(a_used, a1, tb - t, delta * (tb - t), jerk_try)
        k = -1
        if track:
            store_state(sa, z, v, a)
            store_state(sb, z1, v1, a1)
            te, k = locate_event(model, t, tb, sa, sb, wk.taut, evw)
            if k >= 0 and te <= t:  # across already at the start (end of a chatter hold)
                store_state(s, z, v, a)
                return i, t, j, OK, k
            if k >= 0:  # redo the step up to the event, in the modes valid there
                scheme_acceleration(a, jerk, delta * (te - t), a_used)
                st = galpha_step(model, z, v, a_used, P_n, warm, wk, awk, te, te - t, coef, ztol, 0.0, maxit, z1, v1,
                                 a1, P1, scratch)
                if st != OK:
                    store_state(s, z, v, a)
                    return i, t, j, st, -1
                jerk_try[:] = jerk
                carried_acceleration(a_used, a1, te - t, delta * (te - t), jerk_try)
            tb = te
        if j < t_out.size and t_out[j] <= tb + (1e-9 * h if k < 0 else 0.0):
            j = write_step_outputs(model, awk, t, tb, z, v, a, z1, v1, a1, P_n, P1, ae, ae1, scratch, sa, sb, da, db,
                                   t_out, out, j)
        z[:], v[:], a[:], P_n[:] = z1, v1, a1, P1
        jerk[:] = jerk_try
        t = tb
        if k >= 0:
            store_state(s, z, v, a)
            return i, t, j, OK, k
        i += 1
    store_state(s, z, v, a)
    return i, t, j, OK, -1
