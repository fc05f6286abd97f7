"""Every periodic response of a case over a range of the forcing frequency omega, the load factor
gamma (FL and the supports' motion) or the support motion multiplier s: case in, result out.

Builds the equations of motion, starts the first branch from the linear response (or from a
response integrated from rest), and lets :func:`cablesim.orbits.continue_branches` follow it and
every period-doubled branch, with Floquet stability and located bifurcations. The result is
plain arrays per branch, in the case's channels, ready to be written and drawn.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from ..case import Case
from ..channels import channel_index
from ..errors import CablesimError
from ..dynamics.steady import SteadyCriterion, steady_response
from ..modal import COUPLED, IN_PLANE
from ..orbits import OrbitPoint, Settings, continue_branches
from ..orbits.diagram import BranchEnd, BranchesInterrupted
from ..orbits.resume import TraceLog
from ..orbits.stability import frequency_ratio
from ..orbits.symmetry import in_plane_whirling, rotation_sense
from .charts import CurvesRefused, Interrupted, finish_loci, loci_cost
from .continuation_results import BifurcationResult, BranchResult, ContinuationResult
from .orbit_slack import BranchSlack, Grazing, branch_grazings, branch_slack
from .orbit_strain import orbit_strains, strain_measure, strain_warning
from .setup import build_equations, frequency_of_interest, make_integrator
from .static import run_static


def support_amplitudes(case: Case) -> dict:
    """The amplitude (m, ``case.dim`` components) of each moving support as ``supports:`` gives
    it (support multiplier s = 1, gamma = 1): ``{"A": array, "B": array}``, the still ones left out."""
    uA, uB, _, _ = case.support_motion()
    return {name: u.copy() for name, u in (("A", uA), ("B", uB)) if np.any(u != 0.0)}


def continuation_channels(case: Case) -> tuple[list[str], np.ndarray]:
    """The channels a continuation reports (``z<k>`` names) and their DOF indices."""
    dim = case.dim
    n_dof = dim * case.cable.n_nodes
    names = case.continuation.channels or case.history.channels or [f"z{i + 1}" for i in range(n_dof)]
    idx = np.array([channel_index(c, n_dof, dim) for c in names], dtype=int)
    return [f"z{i + 1}" for i in idx], idx


#: Why a flow integration failed, in words (the orbits' FlowStatus names).
_FAILURE_TEXT = {"SLACK": "a segment went slack", "NONFINITE": "the state became non-finite",
                 "INNER_SOLVE": "the inner equilibrium solve failed"}


def _end_text(br) -> str:
    """Why a branch ended, with the cause of a failed flow when there is one."""
    text = br.end.name.lower().replace("_", " ")
    failure = getattr(br, "failure", None)
    if failure is not None and failure.name in _FAILURE_TEXT:
        text += f" ({_FAILURE_TEXT[failure.name]})"
    return text


def _start_failure(diagram) -> str:
    """Why the first orbit could not be computed, in words ("" when it was)."""
    if any(br.points for br in diagram.branches) or not diagram.branches:
        return ""
    br = diagram.branches[0]
    failure = getattr(br, "failure", None)
    if br.end != BranchEnd.START_FAILED:
        return ""
    if failure is not None and failure.name in _FAILURE_TEXT:
        return f"on the first orbit {_FAILURE_TEXT[failure.name]}"
    return "Newton's method did not converge on the first orbit, nor from a response integrated towards steady"


def _start_cause(diagram) -> str:
    """:attr:`ContinuationResult.start_cause` of a diagram whose first orbit failed."""
    failure = getattr(diagram.branches[0], "failure", None) if diagram.branches else None
    return failure.name if failure is not None and failure.name in _FAILURE_TEXT else "NEWTON"


def parameter_values(spec, value: float) -> dict:
    """``omega`` (rad/s), ``gamma`` and ``support`` (s) of an orbit at parameter ``value`` of the
    ``continuation:`` section ``spec`` (the others at their fixed values)."""
    out = {"omega": spec.fixed if spec.parameter != "omega" else 0.0, "gamma": spec.fixed_gamma,
           "support": spec.fixed_support}
    out[spec.parameter] = float(value)
    return out


def _grazing_points(diagram, spec, idx: np.ndarray, dim: int = 2) -> list:
    """A branch that ended because a segment went slack ends at a *grazing* orbit: its last
    orbit, whose smallest tension is about to reach zero (orbits with slack intervals are not
    followed). One record per such branch, at its last orbit."""
    out = []
    for k, br in enumerate(diagram.branches):
        failure = getattr(br, "failure", None)
        if not br.points or failure is None or failure.name != "SLACK":
            continue
        p = br.points[-1]
        at = parameter_values(spec, p.parameter)
        out.append(BifurcationResult(
            kind="grazing", parameter=float(p.parameter), omega=float(p.omega), gamma=at["gamma"], support=at["support"],
            branch=k, period=int(br.period), amplitude=np.asarray(p.amplitude)[idx],
            multiplier=complex(p.multipliers[0]), located=False, trusted=bool(p.trusted),
            frequency_ratio=frequency_ratio(complex(p.multipliers[0])), plane=IN_PLANE if dim == 2 or br.planar else COUPLED))
    return out


def _grazing_result(g: Grazing, spec, idx: np.ndarray, plane: str) -> BifurcationResult:
    """The bifurcation record of a located grazing orbit (the branch goes on through it)."""
    return BifurcationResult(
        kind="grazing", parameter=g.parameter, **parameter_values(spec, g.parameter), branch=g.branch, period=g.period,
        amplitude=np.asarray(g.amplitude)[idx], multiplier=g.multiplier, located=g.located, trusted=g.trusted,
        plane=plane, frequency_ratio=frequency_ratio(g.multiplier), grazing=g)


def _planes(br, dim: int) -> np.ndarray:
    """The block of every multiplier of every point (:attr:`BranchResult.planes`)."""
    other = IN_PLANE if dim == 2 else COUPLED
    return np.array([p.planes if p.planes is not None else (other,) * len(p.multipliers) for p in br.points],
                    dtype=str).reshape(len(br.points), -1)


def _branch(k: int, br, spec, idx: np.ndarray, dim: int = 2, strain: np.ndarray | None = None,
            slack: BranchSlack | None = None) -> BranchResult:
    pts = br.points
    values = np.array([p.parameter for p in pts], dtype=float)
    omega = np.array([p.omega for p in pts], dtype=float)
    gamma = values.copy() if spec.parameter == "gamma" else np.full(values.size, spec.fixed_gamma)
    support = values.copy() if spec.parameter == "support" else np.full(values.size, spec.fixed_support)
    return BranchResult(
        name=f"b{k}-p{br.period}",
        period=int(br.period),
        parameter=values,
        omega=omega,
        gamma=gamma,
        support=support,
        amplitude=np.array([p.amplitude[idx] for p in pts]).reshape(len(pts), idx.size),
        halfrange=np.array([p.halfrange[idx] for p in pts]).reshape(len(pts), idx.size),
        stable=np.array([p.stable for p in pts], dtype=bool),
        trusted=np.array([p.trusted for p in pts], dtype=bool),
        multipliers=np.array([p.multipliers for p in pts]),
        state=np.array([p.state for p in pts]),
        parent=br.parent,
        end=_end_text(br),
        planes=_planes(br, dim),
        planar=bool(getattr(br, "planar", False)),
        mirror_image=bool(getattr(br, "mirror_image", False)),
        strain=np.full(len(pts), np.nan) if strain is None else strain,
        neutral_residual=_neutral(pts),
        slack=slack,
        **_whirling(br, dim),
    )


def _neutral(points) -> np.ndarray | None:
    """``|M g - g| / |g|`` of every point's excluded multiplier (NaN: none), or None if none."""
    res = np.array([p.neutral.residual if getattr(p, "neutral", None) is not None else np.nan for p in points],
                   dtype=float)
    return res if np.isfinite(res).any() else None


def _whirling(br, dim: int) -> dict:
    """The whirling measures of a spatial branch's points: zero on planar orbits, NaN where they
    could not be measured (an equilibrium not in one plane)."""
    if dim == 2:
        return {}
    n = br.points[0].state.size // 6 if br.points else 0
    whirls = [p.whirl if p.whirl is not None or not (getattr(br, "planar", False) or p.planes is not None)
              else in_plane_whirling(n) for p in br.points]  # (multipliers split in blocks: a planar orbit)
    area = np.array([q.area if q is not None else np.full(n, np.nan) for q in whirls], dtype=float).reshape(-1, n)
    max_w = np.array([q.max_w if q is not None else np.full(n, np.nan) for q in whirls], dtype=float).reshape(-1, n)
    tilt = np.array([q.tilt if q is not None else np.nan for q in whirls], dtype=float)
    return {"whirl_area": area, "max_w": max_w, "whirl_sense": rotation_sense(area, max_w), "tilt": tilt}


def _integrated_start(case: Case, static, omega: float, gamma: float, names, idx, support: float = 1.0) -> np.ndarray:
    """``(z, y')`` at forcing phase 0 of the response integrated from rest until steady (the
    supports' motion scaled by ``gamma support``)."""
    eom = build_equations(case, static, omega=omega, load_scale=gamma, support_scale=support)
    integ = make_integrator(case.integrator, eom, frequency_of_interest(eom, omega))
    sw = case.sweep
    crit = SteadyCriterion() if sw is None else SteadyCriterion(cap=sw.duration, window=sw.window, tol=sw.tol,
                                                                  max_period=sw.max_period)
    point = steady_response(eom, integ, idx, crit)
    if point.failed:
        raise CablesimError(
            f"continuation.start_from is history, but the response at the start ({omega:g} rad/s, gamma "
            f"{gamma:g}, support {support:g}) could not be integrated: {point.message}. Start from the linear response instead "
            "(start_from: linear).", field="continuation.start_from")
    return point.final_state[: 2 * eom.n_dof]


@dataclass(frozen=True)
class ContinuationStart:
    """What a continuation starts from: the ``continuation:`` section ``spec``, the statics, the
    equations of motion at the start of the range, the channels (``names``, DOF ``idx``) and the
    first orbit's guess ``initial`` (None: the linear response)."""

    spec: object
    static: object
    eom: object
    names: list
    idx: np.ndarray
    initial: np.ndarray | None


def prepare_continuation(case: Case, analysis: str | None = None) -> ContinuationStart:
    """Check that the case can be continued and build what its continuation starts from.

    Raises
    ------
    CablesimError
        No ``continuation:`` section, nothing forcing the cable, or a start that cannot be
        integrated (``start_from: history``).
    """
    spec = case.continuation
    if spec is None:
        raise CablesimError(
            "This case has no `continuation:` section. Add one, for example "
            "`continuation: {omega: {start: 0.5, stop: 6.0}, channels: [z2, z4]}`.",
            field="continuation",
        )
    if not case.forced:
        raise CablesimError("loads.FL is zero and no support moves, so there is no forced response to continue; "
                            "give peak harmonic loads FL or a support amplitude (supports:).", field="loads.FL")
    static = run_static(case, analysis, all_models=False)
    at_start = parameter_values(spec, spec.range.start)
    eom = build_equations(case, static, omega=at_start["omega"], load_scale=1.0)
    if spec.through_slack and (not eom.exact or eom.moving_supports or case.slack != "continue"):
        why = ("the approximate analysis needs every segment taut" if not eom.exact else
               "the orbits of moving supports are not followed through slack" if eom.moving_supports else
               "slack: stop ends every flow where a segment goes slack")
        raise CablesimError(f"continuation.through_slack is true, but {why}. Orbits through slack are computed in "
                            "the exact analysis (analysis: exact) with the supports at rest and slack: continue; "
                            "set continuation.through_slack: false to stop the branches at the first slack "
                            "segment instead.", field="continuation.through_slack")
    names, idx = continuation_channels(case)
    initial = None
    if spec.start_from == "history":
        initial = _integrated_start(case, static, at_start["omega"], at_start["gamma"], names, idx, at_start["support"])
    return ContinuationStart(spec, static, eom, names, idx, initial)


def trace(start: ContinuationStart, callback, max_points: int | None = None, switch_branches: bool | None = None,
          log: TraceLog | None = None):
    """:func:`~cablesim.orbits.continue_branches` over the range of ``start`` (``max_points`` and
    ``switch_branches``: the section's unless given; ``log``: see
    :func:`~cablesim.orbits.trace_branches`)."""
    spec = start.spec
    return continue_branches(
        start.eom, spec.parameter, spec.range.start, spec.range.stop, period=spec.period,
        switch_branches=spec.switch_branches if switch_branches is None else switch_branches,
        callback=callback, gamma=spec.fixed_gamma, support=spec.fixed_support, initial_state=start.initial,
        segments=spec.segments, max_period=spec.max_period,
        settings=Settings(max_points=spec.max_points if max_points is None else max_points), log=log,
        measure=strain_measure(start.eom), through_slack=spec.through_slack,
    )


class ContinuationRecorder(Protocol):
    """What :func:`run_continuation` tells about its progress, so that a killed run loses no orbit
    (:class:`cablesim.io.continuation_journal.ContinuationFile` journals the records and keeps the
    HDF5 file current)."""

    def previous(self) -> list[dict]:
        """The records of the interrupted run to go on from (empty unless resuming)."""

    def begin(self) -> None:
        """Called once the case is known to be good, before the first orbit."""

    def record(self, record: dict, result: Callable[[], ContinuationResult]) -> None:
        """Called with every record of the tracing (:mod:`cablesim.orbits.resume`); ``result()``
        gives the result so far."""

    def end(self, result: ContinuationResult | None, complete: bool) -> None:
        """Called last, also when interrupted (``result``: what was done; None after a failure)."""


def _log(start: ContinuationStart, case: Case, recorder) -> TraceLog:
    """The tracing's log: its records to ``recorder``, those of an interrupted run replayed."""
    def sink(record: dict, partial) -> None:
        recorder.record(record, lambda: assemble(start, case, partial(), None, complete=False))

    try:
        log = TraceLog(sink, recorder.previous())
        log.replay.check(2 * start.eom.n_dof)
        return log
    except ValueError as exc:
        where = getattr(recorder, "journal_path", "of this continuation")
        raise CablesimError(f"The journal {where} does not fit this case ({exc}), so --resume cannot trust it. Run "
                            "the same command without --resume to start afresh (the journal is replaced), or give "
                            "another -o.", field="continuation") from None


def assemble(start: ContinuationStart, case: Case, diagram, strains, complete: bool = True,
             slack: tuple | None = None) -> ContinuationResult:
    """The :class:`ContinuationResult` of a traced diagram (``strains``: per branch with orbits,
    or None where not measured; ``slack``: through slack, the :class:`BranchSlack` per branch
    with orbits and the located :class:`Grazing` orbits, or None)."""
    spec, static, idx = start.spec, start.static, start.idx
    kept = [(k, br) for k, br in enumerate(diagram.branches) if br.points]
    strains = [None] * len(kept) if strains is None else strains
    patterns, grazings = slack if slack is not None else ([None] * len(kept), [])
    branches = [_branch(k, br, spec, idx, case.dim, st, sl) for (k, br), st, sl in zip(kept, strains, patterns)]
    other = IN_PLANE if case.dim == 2 else COUPLED
    bifs = [
        BifurcationResult(
            kind=b.kind, parameter=float(b.parameter), **parameter_values(spec, b.parameter),
            branch=int(b.branch), period=int(b.period), amplitude=np.asarray(b.amplitude)[idx],
            multiplier=complex(b.multiplier), located=bool(b.located), trusted=bool(b.trusted),
            plane=b.plane or other, frequency_ratio=frequency_ratio(complex(b.multiplier)),
        )
        for b in diagram.bifurcations
    ]
    bifs += _grazing_points(diagram, spec, idx, case.dim) + [_grazing_result(g, spec, idx, other) for g in grazings]
    result = ContinuationResult(
        parameter=spec.parameter, start=spec.range.start, stop=spec.range.stop, fixed=spec.fixed, channels=start.names,
        branches=branches, bifurcations=bifs, analysis=static.analysis, modal_omega=static.modes.omega.copy(),
        case_name=case.name, case_text=case.text, stats=dict(diagram.stats), start_failure=_start_failure(diagram),
        warnings=[*static.warnings, *strain_warning([b.name for b in branches], [b.strain for b in branches],
                                                    spec.parameter, [b.parameter for b in branches])],
        fixed_gamma=spec.fixed_gamma, fixed_support=spec.fixed_support, support_amplitudes=support_amplitudes(case),
        components=case.dim, complete=complete, through_slack=spec.through_slack,
    )
    result.start_cause = _start_cause(diagram) if result.start_failure else ""
    return result


def run_continuation(
    case: Case,
    analysis: str | None = None,
    progress: Callable[[OrbitPoint], None] | None = None,
    loci_progress: Callable | None = None,
    recorder: ContinuationRecorder | None = None,
    force: bool = False,
) -> ContinuationResult:
    """Continue the periodic responses of a case over its ``continuation:`` range.

    Parameters
    ----------
    case : Case
        Must have a ``continuation:`` section.
    analysis : str, optional
        Overrides the case's analysis.
    progress : callable, optional
        Receives every converged orbit (branch, parameter, period, stability).
    loci_progress : callable, optional
        With ``continuation.loci``: ``loci_progress(locus, point)`` for every point of every
        bifurcation curve.
    recorder : ContinuationRecorder, optional
        Receives every orbit and checkpoint as it comes and the result at the end; its
        ``previous()`` records (an interrupted run of the same case) are restored and the
        tracing goes on from them (:mod:`cablesim.orbits.resume`). The bifurcation curves
        are traced again.
    force : bool
        Trace the bifurcation curves even where their estimate (:func:`~.charts.loci_cost`,
        made once the branches are known) is above the limits.

    Returns
    -------
    ContinuationResult

    Raises
    ------
    Interrupted
        Ctrl-C or SIGTERM while the branches or the bifurcation curves were traced: ``result``
        holds the orbits and the curves traced so far (``complete`` False).
    CurvesRefused
        The curves' estimate is above the limits (and not ``force``): ``result`` holds the
        branches (``complete`` False; the recorder keeps them, and its journal resumes).
    """
    start = prepare_continuation(case, analysis)
    spec, eom = start.spec, start.eom
    log = _log(start, case, recorder) if recorder is not None else None
    t0 = time.perf_counter()

    def callback(point):
        if progress is not None:
            progress(point)
        return None

    if recorder is not None:
        recorder.begin()
    result = None
    try:
        result, diagram = _branches(start, case, callback, log)
        result.warnings[:0] = list(getattr(recorder, "warnings", ()))  # journal records skipped
        if result.complete and spec.loci:
            _check_loci_cost(case, eom, diagram, result, force)
            result.loci, result.codim2, more, interrupted = finish_loci(case, eom, diagram, start.idx, loci_progress)
            result.loci_parameter = spec.loci_parameter
            result.loci_range = (spec.loci_range.start, spec.loci_range.stop)
            result.stats.update(more)
            result.complete = not interrupted
        result.stats["wall"] = time.perf_counter() - t0
    finally:
        if recorder is not None:
            recorder.end(result, result is not None and result.complete)
    if not result.complete:
        raise Interrupted(result)
    return result


def _check_loci_cost(case: Case, eom, diagram, result: ContinuationResult, force: bool) -> None:
    """Refuse bifurcation curves whose estimate is above the limits (unless ``force``), the
    branches kept in ``result`` (marked incomplete)."""
    if force:
        return
    cost = loci_cost(case, eom, diagram)
    # steps and memory only: the count of curve points is a loose bound (a curve usually leaves
    # the range long before max_points), which the default max_points of a few curves exceeds
    why = cost.excess(count_samples=False)
    if why is not None:
        result.complete = False
        raise CurvesRefused(result, cost, why, case.continuation.loci_parameter)


def _branches(start: ContinuationStart, case: Case, callback, log) -> tuple:
    """The branches traced: their result (``complete`` False after an interruption) and the
    diagram (for the bifurcation curves)."""
    spec, eom = start.spec, start.eom
    interrupted = False
    try:
        diagram = trace(start, callback, log=log)
    except BranchesInterrupted as exc:  # keep the orbits computed so far
        diagram, interrupted = exc.diagram, True
    kept = [br for br in diagram.branches if br.points]
    slack = None
    try:
        strains = [orbit_strains(eom, br, spec.parameter, spec.fixed_gamma, spec.fixed_support) for br in kept]
        if spec.through_slack:
            slack = _slack(eom, spec, diagram)
    except KeyboardInterrupt:  # the orbits are kept, their strains not measured
        strains, interrupted = None, True
    return assemble(start, case, diagram, strains, complete=not interrupted, slack=slack), diagram


def _slack(eom, spec, diagram) -> tuple:
    """Through slack: the slack pattern of every branch with orbits and its grazing orbits."""
    at = (spec.parameter, spec.fixed_gamma, spec.fixed_support)
    kept = [(k, br) for k, br in enumerate(diagram.branches) if br.points]
    patterns = [branch_slack(eom, br, *at) for _, br in kept]
    return patterns, [g for (k, br), sl in zip(kept, patterns) for g in branch_grazings(eom, br, sl, *at, k)]
