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

from .. import kernels as kn
from ..equations import APPROXIMATE, EXACT, approximate_stiffness, load
from .base import Integrator, IntegratorState, hermite


@njit(cache=True)
def _internal(prm, z, P_n, z_n, warm, P1, K, first):
    """Internal force at the step end and its tangent; returns a status code."""
    model, S, EA, L, H = prm[0], prm[1], prm[2], prm[3], prm[4]
    nd = z.size
    if model == EXACT:
        if kn.exact_force_and_stiffness(prm[10] + z, S, EA, L, H, P1, K) >= 0:
            return kn.SLACK
        return kn.OK
    n = S.size - 1
    Q = np.empty((n + 1, 2))
    x = np.empty(nd)
    u = np.empty(nd)
    T = np.empty(n + 1)
    N = np.empty((nd, nd))
    # Implicit midpoint for the rate law: a few fixed-point sweeps on P_{n+1}.
    Pm = P_n.copy() if first else 0.5 * (P_n + P1)
    for _ in range(3):
        st = approximate_stiffness(prm, Pm, warm, Q, x, u, T, N)
        if st != kn.OK:
            return st
        K[:, :] = np.linalg.inv(N)
        P1[:] = P_n + K @ (z - z_n)
        Pm_new = 0.5 * (P_n + P1)
        if np.max(np.abs(Pm_new - Pm)) <= 1e-13 * np.max(np.abs(P_n)):
            break
        Pm = Pm_new
    return kn.OK


@njit(cache=True)
def _galpha_advance(prm, s, P_n, warm, t0, h, i0, nsteps, am, af, beta, gamma, t_out, out, ztol, maxit):
    m, C = prm[5], prm[6]
    nd = m.size
    z = s[:nd].copy()
    v = s[nd : 2 * nd].copy()
    a = s[2 * nd :].copy()
    P1 = np.empty(nd)
    K = np.empty((nd, nd))
    J = np.empty((nd, nd))
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
        Ff = load(prm, tb - af * h)
        z1 = z + h * v + 0.5 * h * h * a  # predictor: constant acceleration
        P1[:] = P_n
        converged = False
        for it in range(maxit):
            a1 = (z1 - z - h * v) / (beta * h * h) - (0.5 / beta - 1.0) * a
            v1 = v + h * ((1.0 - gamma) * a + gamma * a1)
            st = _internal(prm, z1, P_n, z, warm, P1, K, it == 0)
            if st != kn.OK:
                s[:nd] = z
                s[nd : 2 * nd] = v
                s[2 * nd :] = a
                return i, j, st
            R = m * ((1.0 - am) * a1 + am * a) + C @ ((1.0 - af) * v1 + af * v) + (1.0 - af) * P1 + af * P_n - Ff
            J[:, :] = (1.0 - af) * K + c_c * C
            for q in range(nd):
                J[q, q] += c_m * m[q]
            dz = np.linalg.solve(J, -R)
            z1 += dz
            if np.max(np.abs(dz)) <= ztol + 1e-10 * np.max(np.abs(z1 - z)):
                converged = True
                break
        if not converged or not np.all(np.isfinite(z1)):
            s[:nd] = z
            s[nd : 2 * nd] = v
            s[2 * nd :] = a
            if not converged:
                return i, j, kn.INNER_SOLVE
            return i, j, kn.NONFINITE
        a1 = (z1 - z - h * v) / (beta * h * h) - (0.5 / beta - 1.0) * a
        v1 = v + h * ((1.0 - gamma) * a + gamma * a1)
        st = _internal(prm, z1, P_n, z, warm, P1, K, False)
        if st != kn.OK:
            return i, j, st
        if j < t_out.size and t_out[j] <= tb + 1e-9 * h:
            sa[:nd] = z
            sa[nd : 2 * nd] = v
            sa[2 * nd :] = a
            sb[:nd] = z1
            sb[nd : 2 * nd] = v1
            sb[2 * nd :] = a1
            jerk = (a1 - a) / h
            da[:nd] = v
            da[nd : 2 * nd] = a
            da[2 * nd :] = jerk
            db[:nd] = v1
            db[nd : 2 * nd] = a1
            db[2 * nd :] = jerk
            while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
                hermite(ta, tb, sa, sb, da, db, t_out[j], out[j])
                j += 1
        z[:] = z1
        v[:] = v1
        a[:] = a1
        P_n[:] = P1
    s[:nd] = z
    s[nd : 2 * nd] = v
    s[2 * nd :] = a
    return i0 + nsteps, j, kn.OK


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
        if eom.analysis == "exact":
            from ...statics import resisting_force

            P = resisting_force(eom.cable, eom.y0 + st.s[:nd])
        else:
            # eq. 15 at t0
            P = eom.F0 + eom.FL * np.sin(eom.omega * t0) - eom.C @ st.s[nd : 2 * nd] - eom.mass * st.s[2 * nd :]
        c = eom.cable
        st.extra.update(P=np.array(P, dtype=float), t0=t0, i=0, ztol=1e-12 * max(c.chord_length, 1.0))
        return st

    def advance(self, prm, state, t_end, t_out, out):
        am, af, beta, gamma = self._coefficients()
        t0, i = state.extra["t0"], state.extra["i"]
        nsteps = max(int(np.ceil((t_end - t0) / self.dt - 1e-9)) - i, 0)
        i_new, j, code = _galpha_advance(
            prm, state.s, state.extra["P"], state.warm, t0, self.dt, i, nsteps,
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
