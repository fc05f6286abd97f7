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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ...statics import resisting_force
from .. import kernels as kn
from ..equations import approximate_stiffness
from .base import Integrator, IntegratorState, hermite


@njit(cache=True)
def _internal(prm, z, P_n, z_n, warm, P1, K, first, wk, awk, check_slack):
    """Internal force at the step end and its tangent; returns a status code.

    Newton iterates may pass through configurations with a segment shorter than its natural
    length (for a stiff cable the margin is microns): only the converged state is checked
    (``check_slack``); during the iteration such a segment acts as a linear spring.
    """
    S, EA, L, H = prm[1], prm[2], prm[3], prm[4]
    nd = z.size
    y, Pm = wk[0], wk[3]
    if awk is None:
        for i in range(nd):
            y[i] = prm[10][i] + z[i]
        if kn.exact_force_and_stiffness(y, S, EA, L, H, P1, K) >= 0 and check_slack:
            return kn.SLACK
        return kn.OK
    # Implicit midpoint for the rate law P' = K(P) y': a few fixed-point sweeps on P_{n+1}.
    for i in range(nd):
        Pm[i] = P_n[i] if first else 0.5 * (P_n[i] + P1[i])
    scale = 0.0
    for i in range(nd):
        scale = max(scale, abs(P_n[i]))
    for _ in range(4):
        st = approximate_stiffness(prm, Pm, warm, awk)
        if st != kn.OK:
            return st
        K[:, :] = np.linalg.inv(awk[4])
        change = 0.0
        for i in range(nd):
            acc = P_n[i]
            for j in range(nd):
                acc += K[i, j] * (z[j] - z_n[j])
            P1[i] = acc
            new = 0.5 * (P_n[i] + acc)
            change = max(change, abs(new - Pm[i]))
            Pm[i] = new
        if change <= 1e-13 * scale:
            break
    return kn.OK


@njit(cache=True)
def _store(s, z, v, a):
    """``s = (z, v, a)``."""
    nd = z.size
    s[:nd] = z
    s[nd : 2 * nd] = v
    s[2 * nd :] = a


@njit(cache=True)
def _write_outputs(ta, tb, h, z, v, a, z1, v1, a1, sa, sb, da, db, t_out, out, j):
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


@njit(cache=True)
def _galpha_advance(prm, s, P_n, warm, wk, awk, t0, h, i0, nsteps, am, af, beta, gamma, t_out, out, ztol, maxit):
    m, C, F0, FL, w = prm[5], prm[6], prm[7], prm[8], prm[9]
    nd = m.size
    z = s[:nd].copy()
    v = s[nd : 2 * nd].copy()
    a = s[2 * nd :].copy()
    z1 = np.empty(nd)
    v1 = np.empty(nd)
    a1 = np.empty(nd)
    P1 = np.empty(nd)
    R = np.empty(nd)
    dz = np.empty(nd)
    K = np.empty((nd, nd))
    J = np.empty((nd, nd))
    LU = np.empty((nd, nd))
    sa = np.empty(3 * nd)
    sb = np.empty(3 * nd)
    da = np.empty(3 * nd)
    db = np.empty(3 * nd)
    c_m = (1.0 - am) / (beta * h * h)
    c_c = (1.0 - af) * gamma / (beta * h)
    j = 0
    for i in range(i0, i0 + nsteps):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        sf = np.sin(w * (tb - af * h))
        for q in range(nd):
            z1[q] = z[q] + h * v[q] + 0.5 * h * h * a[q]  # predictor: constant acceleration
            P1[q] = P_n[q]
        converged = False
        for it in range(maxit):
            for q in range(nd):
                a1[q] = (z1[q] - z[q] - h * v[q]) / (beta * h * h) - (0.5 / beta - 1.0) * a[q]
                v1[q] = v[q] + h * ((1.0 - gamma) * a[q] + gamma * a1[q])
            st = _internal(prm, z1, P_n, z, warm, P1, K, it == 0, wk, awk, False)
            if st != kn.OK:
                _store(s, z, v, a)
                return i, j, st
            big = 0.0
            for q in range(nd):
                acc = m[q] * ((1.0 - am) * a1[q] + am * a[q]) + (1.0 - af) * P1[q] + af * P_n[q]
                acc -= F0[q] + FL[q] * sf
                for r in range(nd):
                    acc += C[q, r] * ((1.0 - af) * v1[r] + af * v[r])
                    J[q, r] = (1.0 - af) * K[q, r] + c_c * C[q, r]
                J[q, q] += c_m * m[q]
                R[q] = -acc
            if not kn.solve_small(J, R, dz, LU):
                break
            step = 0.0
            for q in range(nd):
                z1[q] += dz[q]
                big = max(big, abs(dz[q]))
                step = max(step, abs(z1[q] - z[q]))
            if not np.isfinite(big):
                break
            if big <= ztol + 1e-10 * step:
                converged = True
                break
        if not converged:
            _store(s, z, v, a)
            for q in range(nd):
                if not np.isfinite(z1[q]):
                    return i, j, kn.NONFINITE
            return i, j, kn.INNER_SOLVE
        for q in range(nd):
            a1[q] = (z1[q] - z[q] - h * v[q]) / (beta * h * h) - (0.5 / beta - 1.0) * a[q]
            v1[q] = v[q] + h * ((1.0 - gamma) * a[q] + gamma * a1[q])
        st = _internal(prm, z1, P_n, z, warm, P1, K, False, wk, awk, True)
        if st != kn.OK:
            return i, j, st
        if j < t_out.size and t_out[j] <= tb + 1e-9 * h:
            j = _write_outputs(ta, tb, h, z, v, a, z1, v1, a1, sa, sb, da, db, t_out, out, j)
        for q in range(nd):
            z[q] = z1[q]
            v[q] = v1[q]
            a[q] = a1[q]
            P_n[q] = P1[q]
    _store(s, z, v, a)
    return i0 + nsteps, j, kn.OK


@njit(cache=True)
def _band_newton(prm, z, v, a, z1, v1, a1, P_n, P1, Kb, J, R, y, am, af, c_m, c_c, sf, check_slack):
    """Residual ``R`` (minus the generalized-alpha equilibrium) and Newton matrix ``J`` in banded
    storage, exact analysis; a status code."""
    S, EA, L, H, m, C, F0, FL = prm[1], prm[2], prm[3], prm[4], prm[5], prm[6], prm[7], prm[8]
    nd = m.size
    for q in range(nd):
        y[q] = prm[10][q] + z1[q]
        R[q] = (1.0 - af) * v1[q] + af * v[q]  # the velocity C multiplies, for now
    if kn.exact_force_and_stiffness_band(y, S, EA, L, H, P1, Kb) >= 0 and check_slack:
        return kn.SLACK
    for q in range(nd):
        y[q] = kn.band_row(C, R, q)
    for q in range(nd):
        acc = m[q] * ((1.0 - am) * a1[q] + am * a[q]) + (1.0 - af) * P1[q] + af * P_n[q] + y[q]
        R[q] = F0[q] + FL[q] * sf - acc
    for d in range(kn.BAND_ROWS):
        for q in range(nd):
            J[d, q] = (1.0 - af) * Kb[d, q] + c_c * C[d, q]
    for q in range(nd):
        J[kn.BAND_HALF, q] += c_m * m[q]
    return kn.OK


@njit(cache=True)
def _galpha_advance_band(prm, s, P_n, warm, wk, awk, t0, h, i0, nsteps, am, af, beta, gamma, t_out, out, ztol, maxit):
    """:func:`_galpha_advance` for the exact analysis with banded damping: every Newton
    iteration assembles and solves a banded system, O(n)."""
    nd = prm[5].size
    z, v, a = s[:nd].copy(), s[nd : 2 * nd].copy(), s[2 * nd :].copy()
    z1, v1, a1, P1, R, dz = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd)
    Kb, J, LU = np.empty((kn.BAND_ROWS, nd)), np.empty((kn.BAND_ROWS, nd)), np.empty((kn.BAND_ROWS, nd))
    sa, sb, da, db = np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd)
    c_m = (1.0 - am) / (beta * h * h)
    c_c = (1.0 - af) * gamma / (beta * h)
    j = 0
    for i in range(i0, i0 + nsteps):
        ta, tb = t0 + i * h, t0 + (i + 1) * h
        sf = np.sin(prm[9] * (tb - af * h))
        for q in range(nd):
            z1[q] = z[q] + h * v[q] + 0.5 * h * h * a[q]  # predictor: constant acceleration
        converged = False
        for it in range(maxit):
            _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma)
            _band_newton(prm, z, v, a, z1, v1, a1, P_n, P1, Kb, J, R, wk[0], am, af, c_m, c_c, sf, False)
            if not kn.solve_band(J, R, dz, LU):
                break
            big, step = 0.0, 0.0
            for q in range(nd):
                z1[q] += dz[q]
                big = max(big, abs(dz[q]))
                step = max(step, abs(z1[q] - z[q]))
            if not np.isfinite(big):
                break
            if big <= ztol + 1e-10 * step:
                converged = True
                break
        if not converged:
            _store(s, z, v, a)
            for q in range(nd):
                if not np.isfinite(z1[q]):
                    return i, j, kn.NONFINITE
            return i, j, kn.INNER_SOLVE
        _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma)
        st = _band_newton(prm, z, v, a, z1, v1, a1, P_n, P1, Kb, J, R, wk[0], am, af, c_m, c_c, sf, True)
        if st != kn.OK:
            return i, j, st
        if j < t_out.size and t_out[j] <= tb + 1e-9 * h:
            j = _write_outputs(ta, tb, h, z, v, a, z1, v1, a1, sa, sb, da, db, t_out, out, j)
        z[:], v[:], a[:], P_n[:] = z1, v1, a1, P1
    _store(s, z, v, a)
    return i0 + nsteps, j, kn.OK


@njit(cache=True)
def _newmark_update(z, v, a, z1, v1, a1, h, beta, gamma):
    """Acceleration and velocity at the step end from the displacement ``z1`` (Newmark)."""
    for q in range(z.size):
        a1[q] = (z1[q] - z[q] - h * v[q]) / (beta * h * h) - (0.5 / beta - 1.0) * a[q]
        v1[q] = v[q] + h * ((1.0 - gamma) * a[q] + gamma * a1[q])


@dataclass(frozen=True)
class GeneralizedAlpha(Integrator):
    """Chung-Hulbert generalized-alpha with a fixed step ``dt`` (s) and spectral radius ``rho_inf``."""

    dt: float
    rho_inf: float = 0.8

    name = "generalized-alpha"
    fixed_step = True
    order = 2
    description = "generalized-alpha, fixed step (implicit; dissipates high modes by rho_inf)"

    def _coefficients(self):
        r = self.rho_inf
        am = (2.0 * r - 1.0) / (r + 1.0)
        af = r / (r + 1.0)
        gamma = 0.5 - am + af
        beta = 0.25 * (1.0 - am + af) ** 2
        return am, af, beta, gamma

    def start(self, eom, s0, t0=0.0):
        st = IntegratorState(t=t0, s=np.array(s0, dtype=float), warm=np.array(eom.F1, dtype=float))
        nd = eom.n_dof
        if eom.exact:
            P = resisting_force(eom.cable, eom.y0 + st.s[:nd])
        else:
            # eq. 15 at t0
            P = eom.F0 + eom.FL * np.sin(eom.omega * t0) - eom.C @ st.s[nd : 2 * nd] - eom.mass * st.s[2 * nd :]
        c = eom.cable
        st.extra.update(P=np.array(P, dtype=float), t0=t0, i=0, ztol=1e-12 * max(c.chord_length, 1.0),
                        C=np.ascontiguousarray(eom.C))
        st.wk = eom.workspaces()
        return st

    def advance(self, prm, state, t_end, t_out, out):
        am, af, beta, gamma = self._coefficients()
        advance = _galpha_advance
        if prm[6].shape != state.extra["C"].shape:  # banded damping (exact analysis): O(n) steps
            advance = _galpha_advance_band if state.wk[1] is None else advance
            prm = prm if state.wk[1] is None else prm[:6] + (state.extra["C"],) + prm[7:]
        t0, i = state.extra["t0"], state.extra["i"]
        nsteps = max(int(np.ceil((t_end - t0) / self.dt - 1e-9)) - i, 0)
        i_new, j, code = advance(
            prm, state.s, state.extra["P"], state.warm, *state.wk, t0, self.dt, i, nsteps,
            am, af, beta, gamma, t_out, out, state.extra["ztol"], 25,
        )
        state.extra["i"] = i_new
        state.t = t0 + i_new * self.dt
        return j, code


@dataclass(frozen=True)
class Newmark(GeneralizedAlpha):
    """Newmark's average-acceleration method (``beta = 1/4``, ``gamma = 1/2``), fixed step ``dt``."""

    dt: float
    rho_inf: float = 1.0

    name = "newmark"
    description = "Newmark average acceleration, fixed step (implicit; no numerical damping)"

    def _coefficients(self):
        return 0.0, 0.0, 0.25, 0.5
