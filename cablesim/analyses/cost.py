"""What a run will cost, before it starts: time steps, saved instants, memory, disk.

The command line prints the estimate of a long run and refuses one above :data:`MAX_STEPS`
steps or :data:`MAX_MEMORY` bytes unless ``--force`` is given; a run whose results could not fit
in this machine's memory at all is refused even then (it would only fail later).

Step counts are exact for the fixed-step schemes (``duration / dt``) and an estimate for
``dopri5``, whose step is set by stability (about ``3.3 / rate``, the fastest damped rate of
the linearised cable) or accuracy (a fraction ``rtol ** (1/5)`` of the forcing period),
whichever is smaller, and for the error-controlled implicit schemes, which are not limited by
stability: ``w h = sqrt(12 rtol / amplification)``, the step at which their local error
``(w h)^2 / 12`` per radian meets the tolerance (:mod:`cablesim.dynamics.integrators.adaptive`). A sweep's count is an upper bound: every point integrated to the cap.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import Integrator
from ..errors import CablesimError
from ..modal import fastest_rate

#: Most time steps a time history may take without ``--force`` (a few minutes to half an hour of
#: compiled stepping, at 4 to 30 microseconds a step on the paper's example).
MAX_STEPS = 1e8
#: The same for a sweep, whose count is an upper bound (points stop once steady, usually far
#: sooner: the paper's Fig. 3a sweep of 551 points is bounded by 6e7).
MAX_SWEEP_STEPS = 1e9
#: Most bytes a run may hold in memory without ``--force``.
MAX_MEMORY = 4e9
#: Most Runge-Kutta steps the flows of a continuation's first branch may take without
#: ``--force`` (variational equations included). Measured: the paper example's whole continuation
#: over 0.5-6 rad/s takes 1.2e5 (estimated 2.2e5 for its first branch); the stiff cable of Fig. 8
#: takes 4.2e6 over 1.3-2 rad/s, and is estimated at 2.5e8 over 0.4-2 rad/s (refused without it).
MAX_ORBIT_STEPS = 1e8
#: Most orbits expected on a continuation's first branch without ``--force``.
MAX_ORBITS = 20_000
#: A run estimated to take longer than this (s) has its estimate printed before it starts.
LONG_SECONDS = 10.0
#: Fine samples per forcing period a sweep point keeps in its last window.
SWEEP_SAMPLES_PER_PERIOD = 128


def physical_memory() -> float:
    """Bytes of memory of this machine (a large number if unknown)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 1e15


def _size(n: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} bytes"


@dataclass(frozen=True)
class Cost:
    """The estimated cost of one run.

    Attributes
    ----------
    what : str
        ``"history"``, ``"free-vibration"`` or ``"sweep"``.
    steps : float
        Time steps (an estimate for adaptive schemes; for sweeps an upper bound).
    samples : float
        Saved instants (time histories) or points (sweeps).
    memory : float
        Bytes held in memory.
    disk : float
        Bytes written.
    detail : str
        How the steps were counted (scheme, step, duration).
    per_point : float
        A sweep's steps for one point at most (0 for a time history).
    """

    what: str
    steps: float
    samples: float
    memory: float
    disk: float
    detail: str = ""
    per_point: float = 0.0

    def text(self) -> str:
        """One line: ``about 6e+11 time steps (rk4, dt = 1e-09 s over 600 s), 12001 saved instants, ...``."""
        unit = "points" if self.what == "sweep" else "saved instants"
        bound = "at most " if self.what == "sweep" else "about "
        return (f"{self.what}: {bound}{self.steps:.3g} time steps ({self.detail}), {self.samples:.0f} {unit}, "
                f"{_size(self.memory)} in memory, {_size(self.disk)} on disk")

    @property
    def long(self) -> bool:
        """Whether the estimate is printed before the run (not only with ``--verbose``)."""
        return self.steps > 1e7 or self.memory > 1e8

    def excess(self) -> str | None:
        """Why this run needs ``--force`` (None if it does not)."""
        why = []
        limit = MAX_SWEEP_STEPS if self.what == "sweep" else MAX_STEPS
        if not self.steps <= limit:
            why.append(f"{self.steps:.3g} time steps, more than the {limit:.0e} allowed")
        if not self.per_point <= MAX_STEPS:
            why.append(f"up to {self.per_point:.3g} time steps for one point, more than the {MAX_STEPS:.0e} allowed")
        if not self.memory <= MAX_MEMORY:
            why.append(f"{_size(self.memory)} of memory, more than the {_size(MAX_MEMORY)} allowed")
        return "; ".join(why) or None

    def refusal(self, force: bool, fix: str) -> CablesimError | None:
        """The error refusing this run (None if it may run): above the limits without ``force``,
        or impossible on this machine at all. ``fix`` says what to change."""
        why = self.impossible()
        if why is not None:
            return CablesimError(f"This {self.what} cannot run on this machine: {why} ({self.text()}). {fix}.")
        why = self.excess()
        if why is not None and not force:
            return CablesimError(
                f"This {self.what} would need {why} ({self.text()}). {fix}, or add --force to run it anyway.")
        return None

    def impossible(self) -> str | None:
        """Why this run cannot be done on this machine at all (None if it can)."""
        ram = physical_memory()
        if not self.memory <= ram:
            return f"its results need {_size(self.memory)} of memory and this machine has {_size(ram)}"
        if not math.isfinite(self.steps) or self.steps > 1e15:
            return f"it would take {self.steps:.3g} time steps"
        return None


def steps_per_second(eom: EquationsOfMotion, integ: Integrator, omega_interest: float) -> float:
    """Time steps per simulated second (exact for fixed steps, estimated for dopri5)."""
    if integ.fixed_step:
        return 1.0 / integ.dt
    rtol = float(getattr(integ, "rtol", 1e-8))
    if integ.stability_limit is None:  # implicit, error-controlled: (w h)^2 / 12 per radian, amplified
        w_ref = float(getattr(integ, "omega_ref", 0.0)) or omega_interest
        h = math.sqrt(12.0 * max(rtol, 1e-16) / float(getattr(integ, "amplification", 1.0))) / w_ref
        return 1.0 / min(h, float(getattr(integ, "dt_max", np.inf)))
    rate = fastest_rate(eom.frequencies, eom.a0, eom.a1)
    h_stability = 3.3 / rate
    h_accuracy = 2.0 * np.pi / omega_interest * max(rtol, 1e-16) ** 0.2
    h = min(h_stability, h_accuracy, float(getattr(integ, "dt_max", np.inf)))
    return 1.0 / h


def _detail(integ: Integrator, duration: float, per_s: float) -> str:
    if integ.fixed_step:
        return f"{integ.name}, dt = {integ.dt:.3g} s over {duration:.6g} s"
    return f"{integ.name}, steps of about {1.0 / per_s:.3g} s over {duration:.6g} s"


def history_cost(what: str, eom: EquationsOfMotion, integ: Integrator, omega_interest: float, duration: float,
                 output_step: float, split: bool = True) -> Cost:
    """Cost of a time history of ``duration`` seconds saved every ``output_step``."""
    per_s = steps_per_second(eom, integ, omega_interest)
    nd, ns = eom.n_dof, eom.cable.n_segments
    samples = math.floor(duration / output_step + 1e-9) + 1
    per_sample = 8.0 * (3 * nd + (2 * nd if split else 0) + ns + 2)
    stored = 8.0 * (2 * nd + (2 * nd if split else 0) + ns + 2)
    return Cost(what, duration * per_s, samples, 2.0 * samples * per_sample, samples * stored,
                _detail(integ, duration, per_s))


def sweep_cost(points: list[tuple[EquationsOfMotion, Integrator, float]], n_points: int, curves: int, cap: float,
               window: float, channels: int, refined: int = 0) -> Cost:
    """Upper bound of a sweep's cost: every point of the grid integrated to the cap.

    ``points`` holds ``(eom, integrator, omega)`` at a few frequencies of the grid; the largest
    step rate among them stands for every point. Refinement may add up to ``refined``
    frequencies; they are named in the detail but left out of the count that the limits judge
    (a refinement is never the user's mistake, and each point it adds costs what one of the
    grid does).
    """
    per_s = max(steps_per_second(eom, integ, max(w, float(eom.frequencies[0]))) for eom, integ, w in points)
    w_high = max(w for _, _, w in points)
    nd = points[0][0].n_dof
    total = n_points * curves
    fine = window * w_high / (2 * np.pi) * SWEEP_SAMPLES_PER_PERIOD  # last-window samples of one point
    strobes = cap * w_high / (2 * np.pi)
    memory = 8.0 * (total * (4 * channels + 8 + 3 * nd) + 2 * (fine * 3 * nd + strobes * 2 * nd))
    disk = 8.0 * total * (3 * channels + 8) + 80.0 * total
    more = f"; refinement may add up to {refined * curves} more where neighbouring points disagree" if refined else ""
    return Cost("sweep", total * cap * per_s, total, memory, disk,
                f"{total} points of up to {cap:.6g} s, {points[0][1].name}, up to {per_s:.3g} steps per simulated "
                f"second{more}", per_point=cap * per_s)


@dataclass(frozen=True)
class ContinuationCost(Cost):
    """The estimated cost of a continuation's first branch (:class:`Cost` with ``what``
    ``"continuation"``; ``steps`` are the Runge-Kutta steps of its flows, variational equations
    included, ``samples`` the orbits).

    Attributes
    ----------
    seconds : float
        Wall seconds on this machine, from the measured pace of a probe (NaN: not measured, the
        run being refused on its least cost alone).
    least : bool
        The counts are the least the range can take (no probe was run), not an estimate.
    most : bool
        The counts are the most the run can take (a backbone: every orbit it may compute).
    """

    seconds: float = float("nan")
    least: bool = False
    most: bool = False

    def text(self) -> str:
        """One line: ``continuation: about 230 orbits on the first branch, 1.2e+05 Runge-Kutta
        steps (...), about 3 s on this machine, 1.5 MB in memory``."""
        bound = "at least" if self.least else "at most" if self.most else "about"
        secs = "" if not math.isfinite(self.seconds) else f", about {seconds_text(self.seconds)} on this machine"
        where = " on the first branch" if self.what == "continuation" else ""
        return (f"{self.what}: {bound} {self.samples:.0f} orbits{where}, {bound} {self.steps:.3g} "
                f"Runge-Kutta steps ({self.detail}){secs}, {_size(self.memory)} in memory")

    @property
    def long(self) -> bool:
        return not self.seconds <= LONG_SECONDS or self.memory > 1e8

    def excess(self, count_samples: bool = True) -> str | None:
        """Why the run is above the limits (None if it is not); ``count_samples`` False leaves
        the number of orbits out (steps and memory bound it)."""
        why = []
        if not self.steps <= MAX_ORBIT_STEPS:
            why.append(f"{self.steps:.3g} Runge-Kutta steps, more than the {MAX_ORBIT_STEPS:.0e} allowed")
        if count_samples and not self.samples <= MAX_ORBITS:
            why.append(f"{self.samples:.0f} orbits, more than the {MAX_ORBITS} allowed")
        if not self.memory <= MAX_MEMORY:
            why.append(f"{_size(self.memory)} of memory, more than the {_size(MAX_MEMORY)} allowed")
        return "; ".join(why) or None


def seconds_text(seconds: float) -> str:
    """``"0.42 s"``, ``"3.5 min"``, ``"2.1 h"``: two significant digits, never an exponent
    (99.7 s is "100 s", not "1e+02 s")."""
    def two(v: float) -> str:
        return f"{v:.0f}" if v >= 10 else f"{v:.2g}"
    if seconds < 120:
        return f"{two(seconds)} s"
    if seconds < 7200:
        return f"{two(seconds / 60)} min"
    return f"{two(seconds / 3600)} h"

