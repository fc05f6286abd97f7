"""The one table of time-integration settings: which keys each scheme takes, its defaults, and
how cablesim chooses a scheme when the case names none.

The case schema (which ``integrator:`` keys a named scheme accepts), the integrator factory
(:func:`make`), the check of a command-line ``--integrator`` against the case file
(:func:`ignored_keys`) and the stress harness all read this table; code downstream asks the
integrator object itself (its ``fixed_step``, ``order``, ``stability_limit``, and the methods
of :class:`~cablesim.dynamics.integrators.base.Integrator`), it does not branch on names.

Defaults (``docs/theory.md`` and the README's "Integrators" say why):

- ``dopri5``: ``rtol`` :data:`DEFAULT_RTOL`, ``atol`` :data:`DEFAULT_ATOL_PER_CHORD` times the
  chord (m) at that ``rtol``, following ``rtol`` when it is given (:func:`default_atol`);
- ``newmark``, ``generalized-alpha``: error-controlled steps (:mod:`.adaptive`) at ``rtol``
  :data:`IMPLICIT_RTOL` and ``atol`` :data:`IMPLICIT_ATOL_PER_CHORD` times the chord (m) at that
  ``rtol``, following ``rtol`` when it is given (:func:`implicit_atol`), with
  at least :data:`MIN_STEPS_PER_PERIOD` steps per period of the frequency of interest; a ``dt``
  fixes the step instead (``dt`` and ``rtol``/``atol`` exclude each other); ``generalized-alpha``'s
  ``rho_inf`` :data:`DEFAULT_RHO_INF`;
- ``rk4``: :data:`STEPS_PER_PERIOD` steps per period of the frequency of interest, rounded to
  divide the forcing period, shorter where a linear modal estimate of its error on the modes the
  start excites asks (:mod:`.modal_error`), kept inside its stability limit (:data:`RK4_SAFE_STEP` over the
  fastest damped rate);
- no scheme named: ``dopri5``, unless the cable is stiff (its fastest damped root more than
  :data:`STIFF_RATIO` times the frequency of interest), then ``generalized-alpha``.

``benchmarks/bench_adaptive.py --defaults`` measures every default against an independent
reference on the shipped examples (the aim: within 1e-5 of the peak in z and in the tensions);
benchmarks/README.md says which of them are measured.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...modal import fastest_rate
from ...names import INTEGRATOR_SETTINGS
from .base import Integrator
from .implicit import GeneralizedAlpha, Newmark
from .modal_error import accurate_step
from .rk import DOPRI5, RK4

#: Default tolerances of dopri5: relative, and absolute per metre of chord at that rtol. An atol
#: not given follows rtol (``atol = DEFAULT_ATOL_PER_CHORD * chord * rtol / DEFAULT_RTOL``): a
#: fixed atol would dominate the error test once rtol is tightened (the paper example's
#: displacements are metres, atol 3e-8 m), and halving rtol would change nothing.
DEFAULT_RTOL = 1e-8
DEFAULT_ATOL_PER_CHORD = 1e-10
#: rk4's fixed steps per period of the highest frequency of interest, when no ``dt`` is given:
#: the shipped paper example's history (2.4 rad/s, 600 s) is then within 1e-5 of its peaks (z
#: 7.2e-7, tensions 3.4e-6; at 100, 1.2e-5 and 5.1e-5: tests/test_integrator_defaults.py; the
#: error falls as dt^4 and grows with the duration).
STEPS_PER_PERIOD = 200
#: The constant of rk4's relative root error ``(|lambda| h)^4 / 120`` (the leading term of its
#: phase error), for the estimate of its error on the fast modes.
RK4_ROOT_ERROR = 1.0 / 120.0
#: newmark's and generalized-alpha's default relative tolerance on the local displacement error.
#: At 1e-5 the parametric stays' histories (stay-anchorage, stay-parametric: responses that grow
#: from a 1 mm disturbance, and a lightly damped nonlinear resonance) were 1e-4 off in z; at 1e-6
#: every shipped example is within 1e-5 (benchmarks/README.md, part 2) ...
IMPLICIT_RTOL = 1e-6
#: ... and absolute tolerance, m per m of chord at that rtol; an atol not given follows rtol
#: (:func:`implicit_atol`). At 1e-9 per chord (fixed) it set the steps of every cable whose
#: response is small beside its chord (a taut stay: 3 mm on 100 m), whatever rtol was asked.
IMPLICIT_ATOL_PER_CHORD = 1e-12
#: The amplification assumed of an undamped or very lightly damped cable (that of xi = 0.001).
AMPLIFICATION_MAX = 2000.0
#: Error-controlled implicit steps are at most a period of interest over this (a step estimate
#: built from two accelerations cannot see a step that aliases the forcing).
MIN_STEPS_PER_PERIOD = 20
#: A cable is stiff when its fastest damped root (the highest mode, or for stiffness-proportional
#: damping of a finely divided cable the overdamped root ~ a1 w_max^2, which grows as n^2) exceeds
#: the frequency of interest this many times: an explicit step would then be set by modes that
#: do not matter to the response, so cablesim integrates implicitly.
STIFF_RATIO = 200.0
#: Default rk4 steps stay inside this fraction of the stability limit 2.8 / rate.
RK4_SAFE_STEP = 2.0
#: generalized-alpha's default spectral radius.
DEFAULT_RHO_INF = 0.8


def dividing_step(dt: float, omega: float) -> float:
    """The largest step not above ``dt`` that divides the forcing period ``2 pi / omega`` (s), so
    that fixed-step runs sample every period at the same phases. Without forcing
    (``omega <= 0``) ``dt`` is returned unchanged."""
    if omega <= 0:
        return dt
    period = 2.0 * np.pi / omega
    return period / np.ceil(period / dt - 1e-9)


def default_atol(chord: float, rtol: float) -> float:
    """dopri5's absolute tolerance on displacements (m) when the case gives none: it scales with
    ``rtol``, ``1e-10`` of the chord at the default rtol 1e-8."""
    return DEFAULT_ATOL_PER_CHORD * chord * (rtol / DEFAULT_RTOL)


def implicit_atol(chord: float, rtol: float) -> float:
    """newmark's and generalized-alpha's absolute tolerance on displacements (m) when the case
    gives none: :data:`IMPLICIT_ATOL_PER_CHORD` of the chord at the default rtol, scaled with
    ``rtol``."""
    return IMPLICIT_ATOL_PER_CHORD * chord * (rtol / IMPLICIT_RTOL)


def _period_step(eom, omega_interest: float, steps: int) -> float:
    return dividing_step(2.0 * np.pi / omega_interest / steps, eom.omega)


def rk4_stable_step(eom) -> float:
    """A step safely inside rk4's stability limit ``2.8 / rate`` (rate: fastest damped root)."""
    return RK4_SAFE_STEP / fastest_rate(eom.frequencies, eom.a0, eom.a1)


def is_stiff(eom, omega_interest: float) -> bool:
    """Whether the fastest damped root of the linearised system is more than
    :data:`STIFF_RATIO` times the frequency of interest."""
    return fastest_rate(eom.frequencies, eom.a0, eom.a1) / omega_interest > STIFF_RATIO


@dataclass(frozen=True)
class Scheme:
    """One row of the table: a scheme, the settings it takes, and how its defaults are set."""

    name: str
    cls: type
    keys: tuple[str, ...]
    defaults: str

    def build(self, eom, omega_interest: float, given: dict) -> Integrator:
        """The scheme with ``given`` settings and defaults for the others."""
        bad = sorted(set(given) - set(self.keys))
        if bad:
            raise ValueError(f"{self.name} takes {', '.join(self.keys)}, not {', '.join(bad)}")
        s = dict(given)
        chord = eom.cable.chord_length
        if self.cls is DOPRI5:
            rtol = s.get("rtol") or DEFAULT_RTOL
            return DOPRI5(rtol=rtol, atol=s.get("atol") or default_atol(eom.cable.chord_length, rtol))
        dt = s.get("dt")
        if self.cls is RK4:
            return RK4(dt=dt if dt is not None else rk4_default_step(eom, omega_interest))
        if dt is not None and ("rtol" in s or "atol" in s):
            raise ValueError(f"{self.name}: dt (a fixed step) and rtol/atol (error-controlled steps) exclude each "
                             "other; give one of them")
        kw = {}
        if self.cls is GeneralizedAlpha:
            kw["rho_inf"] = DEFAULT_RHO_INF if s.get("rho_inf") is None else s["rho_inf"]
        if dt is not None:
            return self.cls(dt=dt, **kw)
        rtol = s.get("rtol") or IMPLICIT_RTOL
        return self.cls(rtol=rtol, atol=s.get("atol") or implicit_atol(chord, rtol),
                        dt_max=_period_step(eom, omega_interest, MIN_STEPS_PER_PERIOD), omega_ref=float(omega_interest),
                        amplification=amplification(eom, omega_interest), **kw)


def amplification(eom, omega: float) -> float:
    """How much a relative error in a natural frequency can grow in the response: ``2 / xi`` at
    ``omega`` (rad/s), with the Rayleigh damping ratio ``xi = a0 / (2 w) + a1 w / 2`` there, at
    most :data:`AMPLIFICATION_MAX`.

    A response from rest is a steady part and a decaying free transient. The steady part at
    resonance errs by ``1 / xi`` times the frequency error (``|d ln H / d ln w_n|`` of
    ``H = 1 / (w_n^2 - w^2 + 2 i xi w w_n)``, amplitude and phase); the transient's phase error
    grows as ``w t`` while it decays as ``exp(-xi w t)``, at most ``1 / (e xi)`` times the
    frequency error. Their sum is below ``2 / xi``.
    """
    xi = eom.a0 / (2.0 * omega) + eom.a1 * omega / 2.0
    return float(min(AMPLIFICATION_MAX, 2.0 / xi)) if xi > 0 else AMPLIFICATION_MAX


def rk4_default_step(eom, omega_interest: float) -> float:
    """rk4's default step: :data:`STEPS_PER_PERIOD` per period of interest dividing the forcing
    period, shortened (still dividing it) where the linear modal estimate of its error
    (:func:`~cablesim.dynamics.integrators.modal_error.accurate_step`: the fast modes the start
    excites) is above :data:`~cablesim.dynamics.integrators.modal_error.TARGET`, and to stay inside
    the stability limit."""
    dt = _period_step(eom, omega_interest, STEPS_PER_PERIOD)
    accurate = accurate_step(eom, dt, RK4.order, RK4_ROOT_ERROR)
    if accurate < dt:
        dt = dividing_step(accurate, eom.omega)
    if dt > rk4_stable_step(eom):
        dt = rk4_stable_step(eom)
        if eom.omega > 0:  # the stable step, shortened to divide the forcing period
            period = 2.0 * np.pi / eom.omega
            dt = period / np.ceil(period / dt)
    return dt


_CLASSES = {"rk4": RK4, "dopri5": DOPRI5, "newmark": Newmark, "generalized-alpha": GeneralizedAlpha}
_IMPLICIT_DEFAULT = (f"error-controlled steps, rtol {IMPLICIT_RTOL:g}, atol {IMPLICIT_ATOL_PER_CHORD:g} x chord x rtol / "
                     f"{IMPLICIT_RTOL:g} (m), "
                     f"at least {MIN_STEPS_PER_PERIOD} steps per period of interest (dt: a fixed step)")
_DEFAULTS = {
    "rk4": f"dt: {STEPS_PER_PERIOD} steps per period of interest, shorter where the fast modes need it, "
           "inside the stability limit",
    "dopri5": f"rtol {DEFAULT_RTOL:g}, atol {DEFAULT_ATOL_PER_CHORD:g} x chord x rtol / {DEFAULT_RTOL:g} (m)",
    "newmark": _IMPLICIT_DEFAULT,
    "generalized-alpha": f"{_IMPLICIT_DEFAULT}, rho_inf {DEFAULT_RHO_INF:g}",
}
#: The default relative tolerance of each adaptive scheme, for labels and listings.
DEFAULT_TOLERANCES = {"dopri5": DEFAULT_RTOL, "newmark": IMPLICIT_RTOL, "generalized-alpha": IMPLICIT_RTOL}
#: The schemes, by the name a case file and the command line use (the settings each takes:
#: :data:`cablesim.names.INTEGRATOR_SETTINGS`).
SCHEMES: dict[str, Scheme] = {
    name: Scheme(name, _CLASSES[name], keys, _DEFAULTS[name]) for name, keys in INTEGRATOR_SETTINGS.items()
}


def default_scheme(eom, omega_interest: float) -> str:
    """The scheme cablesim uses when the case names none: ``generalized-alpha`` for a stiff
    cable (:func:`is_stiff`; heavy cables with many nodes are, their highest mode growing as n
    and its damped root as n^2, and in the exact analysis each implicit step costs O(n)),
    ``dopri5`` otherwise."""
    return "generalized-alpha" if is_stiff(eom, omega_interest) else "dopri5"


def ignored_keys(name: str, given) -> list[str]:
    """The settings among ``given`` (names) that scheme ``name`` would ignore."""
    return [k for k in given if k not in SCHEMES[name].keys]


def make(name: str | None, eom, omega_interest: float, given: dict | None = None) -> Integrator:
    """The integrator ``name`` (or the default scheme) with the ``given`` settings and defaults.

    With no name the settings that apply to the chosen scheme are used and the others dropped
    (a case may give ``rtol`` for the default ``dopri5`` and ``dt`` for its stiff alternative,
    which then takes the fixed step).
    """
    given = {k: v for k, v in (given or {}).items() if v is not None}
    if name is None:
        name = default_scheme(eom, omega_interest)
        applies = {k: v for k, v in given.items() if k in SCHEMES[name].keys}
        if "dt" in applies:
            applies = {k: v for k, v in applies.items() if k not in ("rtol", "atol")}
        return SCHEMES[name].build(eom, omega_interest, applies)
    return SCHEMES[name].build(eom, omega_interest, given)
