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
- ``rk4``, ``newmark``, ``generalized-alpha``: :data:`STEPS_PER_PERIOD` steps per period of the
  frequency of interest, rounded to divide the forcing period; ``rk4`` kept inside its stability
  limit (:data:`RK4_SAFE_STEP` over the fastest damped rate); ``generalized-alpha``'s
  ``rho_inf`` 0.8;
- no scheme named: ``dopri5``, unless the cable is stiff (its fastest damped root more than
  :data:`STIFF_RATIO` times the frequency of interest), then ``generalized-alpha`` with
  :data:`STIFF_STEPS_PER_PERIOD` steps per period.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...modal import fastest_rate
from ...names import INTEGRATOR_SETTINGS
from .base import Integrator
from .newmark import GeneralizedAlpha, Newmark
from .rk import DOPRI5, RK4

#: Default tolerances of dopri5: relative, and absolute per metre of chord at that rtol. An atol
#: not given follows rtol (``atol = DEFAULT_ATOL_PER_CHORD * chord * rtol / DEFAULT_RTOL``): a
#: fixed atol would dominate the error test once rtol is tightened (the paper example's
#: displacements are metres, atol 3e-8 m), and halving rtol would change nothing.
DEFAULT_RTOL = 1e-8
DEFAULT_ATOL_PER_CHORD = 1e-10
#: Fixed steps per period of the highest frequency of interest, when no ``dt`` is given.
STEPS_PER_PERIOD = 100
#: The same for the default scheme of stiff cables (generalized-alpha): its error falls as dt^2,
#: and 1600 steps per period give about 3e-5 (100 steps: 7e-3), see benchmarks/README.md.
STIFF_STEPS_PER_PERIOD = 1600
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

    def build(self, eom, omega_interest: float, given: dict, stiff_default: bool = False) -> Integrator:
        """The scheme with ``given`` settings and defaults for the others (``stiff_default``:
        chosen automatically for a stiff cable)."""
        bad = sorted(set(given) - set(self.keys))
        if bad:
            raise ValueError(f"{self.name} takes {', '.join(self.keys)}, not {', '.join(bad)}")
        s = dict(given)
        if self.cls is DOPRI5:
            rtol = s.get("rtol") or DEFAULT_RTOL
            return DOPRI5(rtol=rtol, atol=s.get("atol") or default_atol(eom.cable.chord_length, rtol))
        dt = s.get("dt")
        if dt is None:
            dt = _period_step(eom, omega_interest, STEPS_PER_PERIOD)
            if stiff_default:  # the non-stiff default step refined, still dividing the period
                dt = dividing_step(dt * STEPS_PER_PERIOD / STIFF_STEPS_PER_PERIOD, eom.omega)
            if self.cls is RK4 and dt > rk4_stable_step(eom):
                dt = rk4_stable_step(eom)
                if eom.omega > 0:  # the stable step, shortened to divide the forcing period
                    period = 2.0 * np.pi / eom.omega
                    dt = period / np.ceil(period / dt)
        if self.cls is GeneralizedAlpha:
            rho = s.get("rho_inf")
            return GeneralizedAlpha(dt=dt, rho_inf=DEFAULT_RHO_INF if rho is None else rho)
        return self.cls(dt=dt)


_CLASSES = {"rk4": RK4, "dopri5": DOPRI5, "newmark": Newmark, "generalized-alpha": GeneralizedAlpha}
_DEFAULTS = {
    "rk4": f"dt: {STEPS_PER_PERIOD} steps per period of interest, inside the stability limit",
    "dopri5": f"rtol {DEFAULT_RTOL:g}, atol {DEFAULT_ATOL_PER_CHORD:g} x chord x rtol / {DEFAULT_RTOL:g} (m)",
    "newmark": f"dt: {STEPS_PER_PERIOD} steps per period of interest",
    "generalized-alpha": f"dt: {STEPS_PER_PERIOD} steps per period of interest ({STIFF_STEPS_PER_PERIOD} as the "
                         f"default of stiff cables), rho_inf {DEFAULT_RHO_INF:g}",
}
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
    (a case may give ``rtol`` for the default ``dopri5`` and ``dt`` for its stiff alternative).
    """
    given = {k: v for k, v in (given or {}).items() if v is not None}
    if name is None:
        name = default_scheme(eom, omega_interest)
        applies = {k: v for k, v in given.items() if k in SCHEMES[name].keys}
        return SCHEMES[name].build(eom, omega_interest, applies, stiff_default=name == "generalized-alpha")
    return SCHEMES[name].build(eom, omega_interest, given)
