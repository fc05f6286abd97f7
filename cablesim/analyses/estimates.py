"""What each command would take on a case, in words and in seconds (``cablesim check``).

Step counts and memory come from :mod:`cablesim.analyses.cost`; the seconds are measured: a
short run of the same plan on this machine gives the wall time per simulated second, which the
full run multiplies (a sweep: every point to its cap, an upper bound; a continuation: the pace
of its first few orbits, extrapolated over the range, :func:`continuation_cost`). Nothing is written.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..case import Case
from ..errors import CablesimError
from ..orbits.backbone import linear_modes
from ..orbits.budget import orbit_budget
from ..orbits.conservative import conservative_cable_system
from ..orbits.diagram import BranchEnd
from ..orbits.shooting import Shooting
from .charts import LOCUS_FLOWS
from .continuation import prepare_continuation, trace
from .dynamic import HistoryPlan, plan_free_vibration, plan_history
from .setup import build_equations
from .static import run_static
from .sweep import estimate_sweep
from .cost import ContinuationCost, seconds_text

#: A probe integrates about this many steps (at least a few periods), twice: the second is timed.
PROBE_STEPS = 2000
#: Orbits of a continuation's first branch computed to time it and find its pace.
PROBE_ORBITS = 6


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


def continuation_cost(case: Case, analysis: str | None = None) -> ContinuationCost:
    """The cost of a continuation's first branch, before it runs.

    The least it can take comes first, from the shooting's step rule and the continuation's
    largest step (:func:`~cablesim.orbits.budget.orbit_budget`, nothing integrated); a range
    whose least cost is above :data:`~cablesim.analyses.cost.MAX_ORBIT_STEPS` is judged on it
    alone. Otherwise the first :data:`PROBE_ORBITS` orbits of the branch are computed: their
    pace (parameter per orbit after the first) gives the orbits expected over the range (at
    most ``continuation.max_points``), their Runge-Kutta steps per orbit the steps, and the wall
    time between them the seconds. Folds and resonances slow a branch down, so the count is
    an estimate, not a bound; each branch switched onto at a period doubling adds to it.

    Raises
    ------
    CablesimError
        The case cannot be continued (:func:`~cablesim.analyses.continuation.prepare_continuation`).
    KeyboardInterrupt
        Ctrl-C or SIGTERM during the probe.
    """
    start = prepare_continuation(case, analysis)
    spec, rng = start.spec, start.spec.range
    budget = orbit_budget(start.eom, spec.parameter, rng.start, rng.stop, spec.period, spec.segments,
                          spec.fixed_gamma, spec.fixed_support)
    shooting = (f"{'matrix-free' if budget.matrix_free else 'dense'} {budget.scheme} shooting of {budget.states} "
                f"states, {min(budget.steps):.3g} to {max(budget.steps):.3g} steps per orbit period")
    least = ContinuationCost("continuation", budget.least_orbits * min(budget.steps), budget.least_orbits,
                             budget.working + budget.per_orbit * budget.least_orbits, 0.0, shooting, least=True)
    if least.excess() is not None:
        return least
    seen: list = []

    def clock(point):
        seen.append((time.perf_counter(), point.parameter))

    t_probe = time.perf_counter()
    diagram = trace(start, clock, max_points=PROBE_ORBITS, switch_branches=False)
    if len(seen) < 2:  # no orbit, or the branch is one orbit long: the probe was the run
        return dataclasses.replace(least, seconds=time.perf_counter() - t_probe)
    branch = diagram.branches[0]
    done = branch.end != BranchEnd.MAX_POINTS  # the probe reached the end of the branch
    pace = abs(seen[-1][1] - seen[0][1]) / (len(seen) - 1)
    orbits = len(seen) if done else min(spec.max_points, max(len(seen), math.ceil(abs(rng.stop - rng.start) / pace)
                                                                  if pace > 0 else spec.max_points))
    # the probe ran at the start of the range: its flows' steps scaled to the range's mean
    ratio = 1.0 if done else budget.mean_steps / budget.steps[0]
    per_orbit = diagram.stats["steps"] / len(seen) * ratio
    # the median interval between orbits: the first uses of the kernels load them
    seconds = float(np.median(np.diff([t for t, _ in seen]))) * ratio * orbits
    curves = (f"; with loci, each bifurcation curve adds up to {2 * spec.max_points} points (both directions), "
              f"each point about {LOCUS_FLOWS} flows like an orbit's" if spec.loci else "")
    return ContinuationCost("continuation", orbits * per_orbit, orbits, budget.working + budget.per_orbit * orbits,
                            budget.per_orbit * orbits, f"{per_orbit:.3g} per orbit, {shooting}{curves}",
                            seconds=seconds)


#: Shooting evaluations one backbone orbit takes (predictor, Newton corrections, the accepted one).
BACKBONE_EVALUATIONS = 4


def backbone_cost(case: Case, mode: int | None = None, analysis: str | None = None) -> ContinuationCost:
    """The most a backbone can cost, before it runs: ``backbone.max_points`` orbits of about
    :data:`BACKBONE_EVALUATIONS` shooting evaluations each, every one a flow over the linear
    mode's period with its variational equations (the shooting's own step rule; the frequency
    changes little along a backbone), and the memory of the stored orbits and the dense
    Jacobians. An upper bound on the orbits: the amplitude asked for usually ends it sooner."""
    k = int(mode if mode is not None else case.backbone.mode)
    static = run_static(case, analysis, all_models=False)
    eom = build_equations(case, static, omega=float(static.modes.omega[0]), load_scale=1.0)
    system = conservative_cable_system(eom)
    freqs, _ = linear_modes(system, "delta")
    w = float(freqs[min(max(k, 1), freqs.size) - 1])
    steps = Shooting(system).segment_steps(w)
    orbits = int(case.backbone.max_points)
    n = system.dim
    per_orbit = 8.0 * (3 * n + 2 * n)  # unknowns, state, multipliers (complex)
    working = 8.0 * (20 * n * (n + 1) + 4 * (n * n + (n + 1) ** 2))
    return ContinuationCost("backbone", orbits * BACKBONE_EVALUATIONS * steps, orbits, working + per_orbit * orbits,
                            per_orbit * orbits, f"{steps} per flow over the period of mode {k}, {w:.4g} rad/s, "
                            f"{n} states", most=True)


def _backbone_text(case: Case, analysis) -> str:
    cost = backbone_cost(case, analysis=analysis)
    why = cost.impossible() or cost.excess()
    return cost.text().split(": ", 1)[1] + (f"; needs --force: {why}" if why else "")


def _continuation_text(case: Case, analysis) -> str:
    cost = continuation_cost(case, analysis)
    why = cost.impossible() or cost.excess()
    return (cost.text().split(": ", 1)[1] + "; each branch switched onto at a period doubling adds to it"
            + (f"; needs --force: {why}" if why else ""))


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
        "backbone": lambda: _backbone_text(case, analysis),
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
