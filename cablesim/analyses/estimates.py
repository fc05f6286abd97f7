"""What each command would take on a case, in words and in seconds (``cablesim check``).

Step counts and memory come from :mod:`cablesim.analyses.cost`; the seconds are measured: a
short run of the same plan on this machine gives the wall time per simulated second, which the
full run multiplies (a sweep: every point to its cap, an upper bound; a continuation: its first
stretch of the range, extrapolated). Nothing is written.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..case import Case, parse_case
from ..errors import CablesimError
from .continuation import run_continuation
from .dynamic import HistoryPlan, plan_free_vibration, plan_history
from .sweep import estimate_sweep

#: A probe integrates about this many steps (at least a few periods), twice: the second is timed.
PROBE_STEPS = 2000
#: A continuation is timed over this fraction of its range.
PROBE_FRACTION = 0.05


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


def wall_per_simulated_second(plan: HistoryPlan) -> float:
    """Wall seconds one simulated second of ``plan`` takes on this machine (a short run, twice:
    the first loads the kernels)."""
    steps = max(plan.cost().steps, 1.0)
    period = 2.0 * np.pi / plan.omega_interest
    probe_t = min(plan.duration, max(3.0 * period, plan.duration * PROBE_STEPS / steps))
    probe = dataclasses.replace(plan, duration=probe_t, output_step=min(plan.output_step, probe_t / 4))
    probe.run()
    t0 = time.perf_counter()
    probe.run()
    return (time.perf_counter() - t0) / probe_t


def _history_text(plan: HistoryPlan) -> str:
    cost = plan.cost()
    seconds = wall_per_simulated_second(plan) * plan.duration
    why = cost.impossible() or cost.excess()
    return (f"about {seconds_text(seconds)} on this machine; " + cost.text().split(": ", 1)[1]
            + (f"; needs --force: {why}" if why else ""))


def _sweep_text(case: Case, analysis, integrator) -> str:
    cost = estimate_sweep(case, analysis, integrator)
    w_high = float(np.max(case.sweep.frequencies()))
    rate = wall_per_simulated_second(plan_history(case, omega=w_high, duration=case.sweep.duration,
                                                  analysis=analysis, integrator=integrator))
    bound = rate * case.sweep.duration * cost.samples
    why = cost.impossible() or cost.excess()
    return (f"at most {seconds_text(bound)} of one core (every point to its cap; points stop once steady, "
            "usually far sooner, and run on every core); " + cost.text().split(": ", 1)[1]
            + (f"; needs --force: {why}" if why else ""))


def _continuation_text(case: Case, analysis) -> str:
    spec = case.continuation
    if spec is None:
        raise CablesimError("This case has no `continuation:` section (`cablesim example` shows one).")
    rng = spec.range
    stop = rng.start + PROBE_FRACTION * (rng.stop - rng.start)
    key = spec.parameter
    probe_case = parse_case(case.text, overrides=[f"continuation.{key}={{start: {rng.start!r}, stop: {stop!r}}}",
                                                  "continuation.switch_branches=false"])
    run_continuation(probe_case, analysis)  # loads the kernels
    t0 = time.perf_counter()
    res = run_continuation(probe_case, analysis)
    seconds = (time.perf_counter() - t0) / PROBE_FRACTION
    return (f"roughly {seconds_text(seconds)} on this machine for the branch from {rng.start:g} to {rng.stop:g} "
            f"({res.n_points} orbits over the first {100 * PROBE_FRACTION:g} % of it in "
            f"{seconds_text(seconds * PROBE_FRACTION)}); each branch switched onto at a period doubling adds to it")


def estimates(case: Case, analysis: str | None = None, integrator: str | None = None) -> dict[str, str]:
    """What each command would take on this case, in words: the seconds and cost of
    ``history``, ``free-vibration``, ``sweep`` and ``continue`` with the case's settings, or why
    the command needs more (``"cannot run with the case's settings alone: ..."``)."""
    out = {"static": f"statics and modes of {case.cable.n_nodes} nodes (a fraction of a second)"}
    tries = {
        "history": lambda: _history_text(plan_history(case, analysis=analysis, integrator=integrator)),
        "free-vibration": lambda: _history_text(plan_free_vibration(case, analysis=analysis, integrator=integrator)),
        "sweep": lambda: _sweep_text(case, analysis, integrator) if case.sweep is not None else estimate_sweep(case),
        "continue": lambda: _continuation_text(case, analysis),
    }
    for command, text in tries.items():
        try:
            out[command] = text()
        except CablesimError as exc:
            out[command] = f"cannot run with the case's settings alone: {exc}"
    return out


def chosen_integrator(case: Case, analysis: str | None = None, integrator: str | None = None) -> str | None:
    """What a history of the case would integrate with, in words (None without a history frequency)."""
    try:
        plan = plan_history(case, analysis=analysis, integrator=integrator)
    except CablesimError:
        return None
    settings = ", ".join(f"{k} = {v:.3g}" for k, v in plan.integrator.settings().items() if isinstance(v, float)
                         and np.isfinite(v))
    return (f"{plan.integrator.name} ({settings}) for a history at {plan.eom.omega:g} rad/s; cablesim chooses per "
            "command and frequency")
