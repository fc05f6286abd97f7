"""Explicit Runge-Kutta schemes on the paper's third-order state ``(z, y', y'')``.

- ``rk4``: the classical fixed-step fourth-order method (the paper's first scheme);
- ``dopri5``: the Dormand-Prince 5(4) embedded pair with error control (``rtol``, ``atol``).

Both are explicit: stable only while the step resolves the highest mode (``omega_max h`` below
about 2.8 for ``rk4``, 3.3 for ``dopri5``). For stiff cables (very large EA) use ``newmark`` or
``generalized-alpha``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import kernels as kn
from ..equations import rate
from .base import Integrator, IntegratorState, hermite


def _start(eom, s0, t0) -> IntegratorState:
    """State of an explicit scheme at ``t0``, with the rate there (``extra['fa']``, ``['code']``)."""
    st = IntegratorState(t=t0, s=np.array(s0, dtype=float), warm=np.array(eom.F1, dtype=float))
    st.wk = eom.workspaces()
    fa = np.empty_like(st.s)
    code = rate(eom.params(), t0, st.s, st.warm, fa, *st.wk)
    st.extra.update(fa=fa, code=code)
    return st


@njit(cache=True)
def _rk4_advance(prm, s, fa, warm, wk, awk, t0, h, i0, nsteps, t_out, out):
    n = s.size
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    fb = np.empty(n)
    tmp = np.empty(n)
    snew = np.empty(n)
    j = 0
    for i in range(i0, i0 + nsteps):
        ta = t0 + i * h
        tb = t0 + (i + 1) * h
        for q in range(n):
            tmp[q] = s[q] + 0.5 * h * fa[q]
        st = rate(prm, ta + 0.5 * h, tmp, warm, k2, wk, awk)
        if st != kn.OK:
            return i, j, st
        for q in range(n):
            tmp[q] = s[q] + 0.5 * h * k2[q]
        st = rate(prm, ta + 0.5 * h, tmp, warm, k3, wk, awk)
        if st != kn.OK:
            return i, j, st
        for q in range(n):
            tmp[q] = s[q] + h * k3[q]
        st = rate(prm, tb, tmp, warm, k4, wk, awk)
        if st != kn.OK:
            return i, j, st
        for q in range(n):
            snew[q] = s[q] + h / 6.0 * (fa[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q])
        st = rate(prm, tb, snew, warm, fb, wk, awk)
        if st != kn.OK:
            return i, j, st
        while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
            hermite(ta, tb, s, snew, fa, fb, t_out[j], out[j])
            j += 1
        s[:] = snew
        fa[:] = fb
    return i0 + nsteps, j, kn.OK


@dataclass(frozen=True)
class RK4(Integrator):
    """Classical fourth-order Runge-Kutta with a fixed step ``dt`` (s)."""

    dt: float

    name = "rk4"
    fixed_step = True
    order = 4
    description = "classical Runge-Kutta, fixed step (explicit; third-order state)"

    def start(self, eom, s0, t0=0.0):
        st = _start(eom, s0, t0)
        st.extra.update(t0=t0, i=0)
        return st

    def advance(self, prm, state, t_end, t_out, out):
        if state.extra["code"] != kn.OK:
            return 0, state.extra["code"]
        t0, i = state.extra["t0"], state.extra["i"]
        nsteps = max(int(np.ceil((t_end - t0) / self.dt - 1e-9)) - i, 0)
        i_new, j, code = _rk4_advance(prm, state.s, state.extra["fa"], state.warm, *state.wk, t0, self.dt, i, nsteps, t_out, out)
        state.extra["i"] = i_new
        state.t = t0 + i_new * self.dt
        return j, code


# Dormand-Prince 5(4) coefficients.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.zeros((7, 7))
_A[1, :1] = [1 / 5]
_A[2, :2] = [3 / 40, 9 / 40]
_A[3, :3] = [44 / 45, -56 / 15, 32 / 9]
_A[4, :4] = [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729]
_A[5, :5] = [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656]
_A[6, :6] = [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]
_E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])


@njit(cache=True)
def _dopri_advance(prm, s, fa, warm, wk, awk, t, h, t_end, rtol, atol, h_max, t_out, out, A, Cc, E):
    n = s.size
    K = np.empty((7, n))
    tmp = np.empty(n)
    snew = np.empty(n)
    warm_try = np.empty(2)
    j = 0
    h_min = 1e-12 * (1.0 + abs(t))
    last_bad = kn.OK
    while t < t_end:
        if h > h_max:
            h = h_max
        K[0] = fa
        warm_try[:] = warm
        failed = kn.OK
        for st_i in range(1, 7):
            for q in range(n):
                acc = 0.0
                for r in range(st_i):
                    acc += A[st_i, r] * K[r, q]
                tmp[q] = s[q] + h * acc
            code = rate(prm, t + Cc[st_i] * h, tmp, warm_try, K[st_i], wk, awk)
            if code != kn.OK:
                failed = code
                break
        if failed != kn.OK:
            last_bad = failed
            h *= 0.25
            if h < h_min:
                return t, h, j, failed
            continue
        snew[:] = tmp  # stage 7 is evaluated at the 5th-order solution (FSAL)
        err = 0.0
        for q in range(n):
            eq = 0.0
            for r in range(7):
                eq += E[r] * K[r, q]
            sc = atol[q] + rtol * max(abs(s[q]), abs(snew[q]))
            err += (h * eq / sc) ** 2
        err = np.sqrt(err / n)
        if err <= 1.0:
            tb = t + h
            while j < t_out.size and t_out[j] <= tb:
                hermite(t, tb, s, snew, fa, K[6], t_out[j], out[j])
                j += 1
            t = tb
            s[:] = snew
            fa[:] = K[6]
            warm[:] = warm_try
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-0.2))
            h *= fac
            last_bad = kn.OK
        else:
            h *= max(0.2, 0.9 * err ** (-0.2))
            if h < h_min:
                return t, h, j, kn.STEP_UNDERFLOW
    return t, h, j, kn.OK


@dataclass(frozen=True)
class DOPRI5(Integrator):
    """Dormand-Prince 5(4) with error control.

    Parameters
    ----------
    rtol : float
        Relative tolerance.
    atol : float
        Absolute tolerance on displacements, m; velocities and accelerations get
        ``atol * w_ref`` and ``atol * w_ref^2`` with ``w_ref`` the fundamental frequency.
    dt_max : float
        Largest step, s (default: no limit beyond stability, which the controller finds).
    """

    rtol: float = 1e-7
    atol: float = 1e-9
    dt_max: float = np.inf

    name = "dopri5"
    fixed_step = False
    order = 5
    description = "Dormand-Prince 5(4), adaptive step (explicit; third-order state)"

    def start(self, eom, s0, t0=0.0):
        st = _start(eom, s0, t0)
        nd = eom.n_dof
        w = eom.frequencies
        w_ref = float(w[0])
        atol = np.concatenate([np.full(nd, self.atol), np.full(nd, self.atol * w_ref), np.full(nd, self.atol * w_ref**2)])
        # First step: a fraction of the shortest modal period, refined by the controller.
        h0 = min(0.2 / float(w[-1]), self.dt_max)
        st.extra.update(h=h0, atol=atol)
        return st

    def advance(self, prm, state, t_end, t_out, out):
        if state.extra["code"] != kn.OK:
            return 0, state.extra["code"]
        t, h, j, code = _dopri_advance(
            prm, state.s, state.extra["fa"], state.warm, *state.wk, state.t, state.extra["h"], t_end,
            self.rtol, state.extra["atol"], self.dt_max, t_out, out, _A, _C, _E,
        )
        state.t = t
        state.extra["h"] = h
        return j, code
