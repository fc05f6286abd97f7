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
from ...jit import njit

from ..field import consistent_acceleration, rate
from ..status import OK, STEP_UNDERFLOW
from .base import Integrator, IntegratorState, hermite
from .events import locate_event, start_events, transition


def _start(eom, s0, t0) -> IntegratorState:
    """State of an explicit scheme at ``t0``, with the rate there (``extra['fa']``, ``['code']``)."""
    st = IntegratorState(t=t0, s=np.array(s0, dtype=float), warm=np.array(eom.F1, dtype=float))
    st.wk = eom.workspaces()
    start_events(eom, st)
    fa = np.empty_like(st.s)
    code = rate(eom.model(), t0, st.s, st.warm, fa, *st.wk)
    st.extra.update(fa=fa, code=code)
    return st


def _after_event(model, state, k, t):
    """Change segment k's mode at t and restart there: ``y''`` from eq. 15 (so that the
    interpolation error of the cut step does not persist as a load, docs/theory.md section 6)
    and the rate of the new modes."""
    transition(state, k, t)
    consistent_acceleration(model, t, state.s, state.wk[0])
    return rate(model, t, state.s, state.warm, state.extra["fa"], *state.wk)


@njit
def _rk4_step(model, s, fa, warm, wk, awk, t, h, k2, k3, k4, tmp, snew):
    """One classical Runge-Kutta step of size h from ``(t, s)`` (rate ``fa``) into ``snew``."""
    n = s.size
    for q in range(n):
        tmp[q] = s[q] + 0.5 * h * fa[q]
    st = rate(model, t + 0.5 * h, tmp, warm, k2, wk, awk)
    if st != OK:
        return st
    for q in range(n):
        tmp[q] = s[q] + 0.5 * h * k2[q]
    st = rate(model, t + 0.5 * h, tmp, warm, k3, wk, awk)
    if st != OK:
        return st
    for q in range(n):
        tmp[q] = s[q] + h * k3[q]
    st = rate(model, t + h, tmp, warm, k4, wk, awk)
    if st != OK:
        return st
    for q in range(n):
        snew[q] = s[q] + h / 6.0 * (fa[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q])
    return OK


@njit
def _rk4_advance(model, s, fa, warm, wk, awk, evw, track, t0, h, i, i_end, t, t_out, out):
    """Steps on the grid ``t0 + i h`` up to step ``i_end``, from ``t`` (inside step i after an
    event). Returns ``(i, t, written, status, segment)``; ``segment >= 0``: it changes mode at t
    (the state is there, the step split)."""
    n = s.size
    k2, k3, k4, fb, tmp, snew = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    j = 0
    while i < i_end:
        tb = t0 + (i + 1) * h
        if tb - t <= 1e-9 * h:  # an event ended at the grid point
            while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
                out[j] = s
                j += 1
            t = tb
            i += 1
            continue
        st = _rk4_step(model, s, fa, warm, wk, awk, t, tb - t, k2, k3, k4, tmp, snew)
        if st == OK:
            st = rate(model, tb, snew, warm, fb, wk, awk)
        if st != OK:
            return i, t, j, st, -1
        if track:
            te, k = locate_event(model, t, tb, s, snew, wk.taut, evw)
            if k >= 0:
                if te > t:  # redo the step up to the event, in the modes valid there
                    st = _rk4_step(model, s, fa, warm, wk, awk, t, te - t, k2, k3, k4, tmp, snew)
                    if st == OK:
                        st = rate(model, te, snew, warm, fb, wk, awk)
                    if st != OK:
                        return i, t, j, st, -1
                    while j < t_out.size and t_out[j] <= te:
                        hermite(t, te, s, snew, fa, fb, t_out[j], out[j])
                        j += 1
                    s[:] = snew
                return i, te, j, OK, k
        while j < t_out.size and t_out[j] <= tb + 1e-9 * h:
            hermite(t, tb, s, snew, fa, fb, t_out[j], out[j])
            j += 1
        s[:] = snew
        fa[:] = fb
        t = tb
        i += 1
    return i, t, j, OK, -1


@dataclass(frozen=True)
class RK4(Integrator):
    """Classical fourth-order Runge-Kutta with a fixed step ``dt`` (s); a step in which a segment
    changes mode is split at the event."""

    dt: float

    name = "rk4"
    fixed_step = True
    order = 4
    description = "classical Runge-Kutta, fixed step (explicit; third-order state)"
    stability_limit = 2.8

    def start(self, eom, s0, t0=0.0):
        st = _start(eom, s0, t0)
        st.extra.update(t0=t0, i=0)
        return st

    def advance(self, model, state, t_end, t_out, out):
        ex = state.extra
        if ex["code"] != OK:
            return 0, ex["code"]
        i_end = max(int(np.ceil((t_end - ex["t0"]) / self.dt - 1e-9)), ex["i"])
        written, code = 0, OK
        while True:
            i, t, j, code, k = _rk4_advance(model, state.s, ex["fa"], state.warm, *state.wk, ex["evw"], ex["track"],
                                            ex["t0"], self.dt, ex["i"], i_end, state.t, t_out[written:], out[written:])
            written += j
            ex["i"], state.t = i, t
            if code != OK or k < 0:
                return written, code
            code = _after_event(model, state, k, t)
            if code != OK:
                return written, code


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


@njit
def _dopri_advance(model, s, fa, warm, wk, awk, evw, track, t, h, t_end, rtol, atol, h_max, t_out, out, A, Cc, E):
    n = s.size
    K = np.empty((7, n))
    tmp = np.empty(n)
    snew = np.empty(n)
    warm_try = np.empty(warm.size)
    j = 0
    h_min = 1e-12 * (1.0 + abs(t))
    last_bad = OK
    while t < t_end:
        if h > h_max:
            h = h_max
        K[0] = fa
        warm_try[:] = warm
        failed = OK
        for st_i in range(1, 7):
            for q in range(n):
                acc = 0.0
                for r in range(st_i):
                    acc += A[st_i, r] * K[r, q]
                tmp[q] = s[q] + h * acc
            code = rate(model, t + Cc[st_i] * h, tmp, warm_try, K[st_i], wk, awk)
            if code != OK:
                failed = code
                break
        if failed != OK:
            last_bad = failed
            h *= 0.25
            if h < h_min:
                return t, h, j, failed, -1
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
            if track:
                te, k = locate_event(model, t, tb, s, snew, wk.taut, evw)
                if k >= 0:  # cut the step at the event: the state there from the interpolant
                    while j < t_out.size and t_out[j] <= te:
                        hermite(t, tb, s, snew, fa, K[6], t_out[j], out[j])
                        j += 1
                    hermite(t, tb, s, snew, fa, K[6], te, tmp)
                    s[:] = tmp
                    warm[:] = warm_try
                    return te, h, j, OK, k
            while j < t_out.size and t_out[j] <= tb:
                hermite(t, tb, s, snew, fa, K[6], t_out[j], out[j])
                j += 1
            t = tb
            s[:] = snew
            fa[:] = K[6]
            warm[:] = warm_try
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-0.2))
            h *= fac
            last_bad = OK
        else:
            h *= max(0.2, 0.9 * err ** (-0.2))
            if h < h_min:
                return t, h, j, STEP_UNDERFLOW, -1
    return t, h, j, OK, -1


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
    stability_limit = 3.3

    def for_finite_differences(self) -> "DOPRI5":
        return DOPRI5(rtol=1e-11, atol=self.atol * 1e-3, dt_max=self.dt_max)

    def for_measuring(self, spacing: float) -> "DOPRI5":
        return self if self.dt_max <= spacing else DOPRI5(rtol=self.rtol, atol=self.atol, dt_max=spacing)

    def for_transient(self, rtol: float) -> "DOPRI5":
        return self if self.rtol >= rtol else DOPRI5(rtol=rtol, atol=self.atol, dt_max=self.dt_max)

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

    def advance(self, model, state, t_end, t_out, out):
        ex = state.extra
        if ex["code"] != OK:
            return 0, ex["code"]
        written = 0
        while True:
            t, h, j, code, k = _dopri_advance(
                model, state.s, ex["fa"], state.warm, *state.wk, ex["evw"], ex["track"], state.t, ex["h"], t_end,
                self.rtol, ex["atol"], self.dt_max, t_out[written:], out[written:], _A, _C, _E,
            )
            written += j
            state.t, ex["h"] = t, h
            if code != OK or k < 0:
                return written, code
            code = _after_event(model, state, k, t)
            if code != OK:
                return written, code
