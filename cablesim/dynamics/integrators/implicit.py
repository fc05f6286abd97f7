"""The implicit integrators: ``generalized-alpha`` and ``newmark``, each with a fixed step ``dt``
or, without one, error-controlled steps (``rtol``, ``atol``).

The step kernels are :mod:`.newmark` (one step, banded Newton solves, the fixed-step loop) and
:mod:`.adaptive` (the local error estimate and the step-size control).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..field import exact_force_and_rate
from ..status import OK
from .adaptive import NOISE_FLOOR, adaptive_advance
from .base import Integrator, IntegratorState
from .events import start_events, transition
from .newmark import fixed_step_advance

#: Steps per ``dt_max`` of the fixed-step version used for finite-difference monodromies
#: (:meth:`GeneralizedAlpha.for_finite_differences`).
FD_STEPS_PER_DT_MAX = 20
#: Newton iterations allowed per step.
MAX_NEWTON = 25
#: Newton's loose tolerance per metre of chord (the error-controlled steps hold it tighter).
NEWTON_PER_CHORD = 1e-12
#: Share of an error-controlled run's steps set by the estimate's rounding floor beyond which
#: the run says so (:meth:`GeneralizedAlpha.run_notes`).
ROUNDING_SHARE = 0.5


@dataclass(frozen=True)
class GeneralizedAlpha(Integrator):
    """Chung-Hulbert generalized-alpha with spectral radius ``rho_inf``.

    Parameters
    ----------
    dt : float, optional
        Fixed step, s. Without it the steps are error-controlled (:mod:`.adaptive`).
    rho_inf : float
        Spectral radius at infinite frequency, 0 to 1 (1: no numerical dissipation).
    rtol : float
        Relative tolerance: the error sought, relative to the peak displacement (error-controlled
        steps only; :mod:`.adaptive` says how a step's local error is held to it).
    atol : float
        Absolute tolerance on the displacements, m (error-controlled steps only).
    dt_max : float
        Largest error-controlled step, s (cablesim sets it to a fraction of the period of
        interest, dividing the forcing period).
    omega_ref : float
        Frequency of interest ``w_ref``, rad/s (0: the lowest natural frequency).
    amplification : float
        How much a relative frequency error can grow in the response, ``2 / xi`` at ``w_ref``
        (:func:`~cablesim.dynamics.integrators.settings.amplification`).
    """

    dt: float | None = None
    rho_inf: float = 0.8
    rtol: float = 1e-5
    atol: float = 1e-7
    dt_max: float = np.inf
    omega_ref: float = 0.0
    amplification: float = 200.0

    name = "generalized-alpha"
    order = 2
    description = ("generalized-alpha (implicit; dissipates high modes by rho_inf): fixed step dt, or "
                   "error-controlled steps (rtol, atol)")

    def __post_init__(self):
        if self.dt is not None and not self.dt > 0:
            raise ValueError(f"{self.name}: dt must be positive, got {self.dt!r}")
        if not (self.rtol > 0 and self.atol > 0 and self.dt_max > 0 and self.amplification > 0 and self.omega_ref >= 0):
            raise ValueError(f"{self.name}: rtol, atol, dt_max and amplification must be positive")

    @property
    def fixed_step(self) -> bool:
        """A fixed step when ``dt`` is given, else error-controlled steps."""
        return self.dt is not None

    def settings(self) -> dict:
        keys = ("dt",) if self.fixed_step else ("rtol", "atol", "dt_max", "omega_ref", "amplification")
        return {k: getattr(self, k) for k in keys + self._own_keys()}

    @staticmethod
    def _own_keys() -> tuple:
        return ("rho_inf",)

    def for_finite_differences(self) -> "GeneralizedAlpha":
        """Fixed steps (a flow map smooth in the initial state): ``dt_max`` /
        :data:`FD_STEPS_PER_DT_MAX`, which divides the forcing period as ``dt_max`` does; without a
        finite ``dt_max``, the tolerances tightened a thousandfold."""
        if self.fixed_step:
            return self
        if np.isfinite(self.dt_max):
            return replace(self, dt=self.dt_max / FD_STEPS_PER_DT_MAX)
        return replace(self, rtol=self.rtol * 1e-3, atol=self.atol * 1e-3)

    def for_measuring(self, spacing: float) -> "GeneralizedAlpha":
        if self.fixed_step or self.dt_max <= spacing:
            return self
        return replace(self, dt_max=spacing)

    def for_transient(self, rtol: float) -> "GeneralizedAlpha":
        if self.fixed_step or self.rtol >= rtol:
            return self
        return replace(self, rtol=rtol)

    def _coefficients(self):
        r = self.rho_inf
        am = (2.0 * r - 1.0) / (r + 1.0)
        af = r / (r + 1.0)
        gamma = 0.5 - am + af
        beta = 0.25 * (1.0 - am + af) ** 2
        return am, af, beta, gamma

    def start(self, eom, s0, t0=0.0):
        st = IntegratorState(t=t0, s=np.array(s0, dtype=float), warm=np.array(eom.F1, dtype=float))
        st.wk = eom.workspaces()
        start_events(eom, st)
        c = eom.cable
        # First error-controlled step: a tenth of the largest, refined by the controller.
        h0 = 0.1 * (self.dt_max if np.isfinite(self.dt_max) else 2.0 * np.pi / float(eom.frequencies[0]) / 20.0)
        w_ref = self.omega_ref or float(eom.frequencies[0])
        # steps: accepted, rejected by the error test, retried after a failed Newton iteration,
        # accepted with their allowed error below a tenth of the rounding floor (set by it)
        z0 = st.s[: eom.n_dof]
        peaks = np.array([np.abs(z0).max()])  # m
        st.extra.update(P=self._force(eom, st), t0=t0, i=0, h=h0, steps=np.zeros(4, dtype=np.int64), peaks=peaks,
                        per_step=w_ref / self.amplification, ztol=NEWTON_PER_CHORD * max(c.chord_length, 1.0), eom=eom,
                        jerk=np.zeros(eom.n_dof))
        return st

    def run_notes(self, state) -> tuple[str, ...]:
        """A run whose steps were mostly set by the error estimate's rounding floor (more than
        :data:`ROUNDING_SHARE` of them, each allowed less than a tenth of the floor by rtol) says
        so: its rtol asked more than double precision resolves, and a tighter one would only
        cost steps."""
        if self.fixed_step:
            return ()
        accepted, at_floor = int(state.extra["steps"][0]), int(state.extra["steps"][3])
        if accepted == 0 or at_floor <= ROUNDING_SHARE * accepted:
            return ()
        return (f"{self.name}: {100.0 * at_floor / accepted:.0f} % of the {accepted} steps were set by the rounding "
                f"floor of the error estimate ({NOISE_FLOOR * NEWTON_PER_CHORD:g} of the chord per step), not by rtol "
                f"{self.rtol:g}, which allows them less than a tenth of it: the tolerance asks more than double "
                "precision resolves on this cable, and a tighter one would only cost steps. The result is as "
                "accurate as these steps make it; to check it, compare with a run at a looser rtol or with "
                "--integrator dopri5.",)

    @staticmethod
    def _force(eom, st):
        """The internal force at the state: ``P(y)`` of the current segment modes, with the
        supports where they are at ``st.t`` (exact), or eq. 15."""
        nd = eom.n_dof
        if eom.exact:
            wk = st.wk[0]  # no dense K: O(n) for heavy cables
            exact_force_and_rate(eom.model(), float(st.t), eom.y0 + st.s[:nd], np.zeros(nd), wk)
            return wk.P.copy()
        return eom.internal_force(st.t, st.s)

    def advance(self, model, state, t_end, t_out, out):
        ex = state.extra
        coef = np.array(self._coefficients())
        written = 0
        while True:
            if self.fixed_step:
                i_end = max(int(np.ceil((t_end - ex["t0"]) / self.dt - 1e-9)), ex["i"])
                i, t, j, code, k = fixed_step_advance(
                    model, state.s, ex["P"], state.warm, *state.wk, ex["evw"], ex["track"], ex["t0"], self.dt, ex["i"],
                    i_end, state.t, coef, t_out[written:], out[written:], ex["ztol"], MAX_NEWTON, ex["jerk"],
                )
                ex["i"] = i
            else:
                t, h, j, code, k = adaptive_advance(
                    model, state.s, ex["P"], state.warm, *state.wk, ex["evw"], ex["track"], state.t, ex["h"], t_end,
                    coef, self.rtol, self.atol, self.dt_max, ex["per_step"], t_out[written:], out[written:], ex["ztol"],
                    MAX_NEWTON, ex["steps"], ex["peaks"], ex["jerk"],
                )
                ex["h"] = h
            written += j
            state.t = t
            if code != OK or k < 0:
                return written, code
            transition(state, k, t)
            ex["P"][:] = self._force(ex["eom"], state)


@dataclass(frozen=True)
class Newmark(GeneralizedAlpha):
    """Newmark's average-acceleration method (``beta = 1/4``, ``gamma = 1/2``): a fixed step
    ``dt`` (s), or without it error-controlled steps (``rtol``, ``atol``)."""

    rho_inf: float = 1.0

    name = "newmark"
    description = ("Newmark average acceleration (implicit; no numerical damping): fixed step dt, or "
                   "error-controlled steps (rtol, atol)")

    @staticmethod
    def _own_keys() -> tuple:
        return ()

    def _coefficients(self):
        return 0.0, 0.0, 0.25, 0.5
