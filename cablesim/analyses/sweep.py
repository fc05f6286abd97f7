"""Frequency-domain response sweeps.

A sweep is a set of *curves*, one per ``gamma`` (scale of FL) and direction. On an
``independent`` curve every point starts from the static equilibrium at rest (as in the paper),
so all points run in parallel. On an ``up`` or ``down`` curve each point starts from the end
state of the previous one, which reveals jumps and hysteresis; such a curve is a chain, and the
chains (up, down, each gamma) run in parallel with one another.

After the grid, the sweep refines itself where neighbouring points disagree
(:mod:`cablesim.analyses.refine`, ``sweep.refine``): each round computes the midpoints of the
intervals the rules flag, on every curve (a refined point of a chain starts from the end state
of its neighbour before it in the chain's direction).

The statics are solved once per sweep; the workers receive them with the rest of the sweep's
:class:`SweepContext` (:mod:`cablesim.analyses.pool`), and each finished point comes back as a
:class:`~cablesim.analyses.sweep_points.SweepPoint`.

The driver knows nothing of files: every finished point goes to a *recorder* (see
:class:`SweepRecorder`); :class:`cablesim.io.journal.SweepFile` is the one that journals each
point and keeps the HDF5 file up to date, so that a killed run loses nothing.
"""

from __future__ import annotations

import time
import uuid
from dataclasses import dataclass, field, replace
from typing import Callable, Iterable, Protocol

import numpy as np

from ..case import Case
from ..channels import channel_index
from ..dynamics import interrupts
from ..dynamics.steady import SteadyCriterion, steady_response
from ..errors import CablesimError
from ..orbits.accelerate import accelerated_steady_response
from . import pool
from .cost import Cost, sweep_cost
from .refine import BUDGET, BUDGET_FLOOR, finest_step, refinements
from .setup import build_equations, disturbed_start, need_inextensible, integrator_record, make_integrator, sweep_disturbance
from .static import StaticResult, run_static
from .sweep_points import BadRecord, CurveTable, SweepPoint


@dataclass(frozen=True)
class Curve:
    """One curve of a sweep: a gamma (index) and a direction."""

    gamma_index: int
    direction: str  # "independent" | "up" | "down"


@dataclass
class SweepResult:
    """All results of a sweep, complete or not.

    ``omega`` holds the frequencies computed or to compute, rad/s (the grid, then the refined
    points, ascending once refined); ``points`` every finished point by ``(curve, omega)``;
    :meth:`table` (or ``data[curve]``) a curve's columns over ``omega``
    (:class:`~cablesim.analyses.sweep_points.CurveTable`: ``(P, C)`` per-channel columns,
    ``(P,)`` ``period``, ``steady``, ``t_end``, ``floquet``, ``done``, ...). ``settings`` holds
    the sweep's ``cap``, ``window``, ``tol``, ``max_period``, ``floquet_check``, ``accelerate``
    and ``refine`` (halvings allowed), ``grid_points`` and ``finest_step``; ``modal_omega`` the
    linear modal frequencies, rad/s. Sizes come from the cable: ``n_dof`` (``dim n``, with
    ``dim`` the components per node, 2 planar or 3 spatial) and ``n_segments`` (n + 1).
    """

    omega: np.ndarray
    gamma: np.ndarray | None
    direction: str
    channels: list[str]
    curves: list[Curve]
    n_dof: int
    dim: int = 2
    analysis: str = "exact"
    modal_omega: np.ndarray = field(default_factory=lambda: np.empty(0))
    case_name: str = "case"
    case_text: str = ""
    settings: dict = field(default_factory=dict)
    points: dict = field(default_factory=dict)  # (curve, omega) -> SweepPoint
    warnings: list = field(default_factory=list)  # e.g. journal records that were skipped
    _tables: dict = field(default_factory=dict, repr=False)

    @property
    def n_segments(self) -> int:
        """Segments of the cable (n + 1)."""
        return self.n_dof // self.dim + 1

    def add(self, p: SweepPoint) -> None:
        """Enter a finished point."""
        self.points[(p.curve, p.omega)] = p
        self._tables.clear()

    def extend(self, new_omega: np.ndarray) -> None:
        """Add frequencies to compute (refinement): ``omega`` becomes the sorted union."""
        self.omega = np.unique(np.concatenate([self.omega, np.asarray(new_omega, dtype=float)]))
        self._tables.clear()

    def has(self, curve: int, omega: float) -> bool:
        """Whether the point is finished."""
        return (curve, float(omega)) in self.points

    def table(self, curve: int) -> CurveTable:
        """The columns of one curve over :attr:`omega`."""
        if curve not in self._tables:
            mine = {w: p for (c, w), p in self.points.items() if c == curve}
            self._tables[curve] = CurveTable.from_points(self.omega, mine, len(self.channels), self.n_dof,
                                                           self.n_segments)
        return self._tables[curve]

    @property
    def data(self) -> dict[int, CurveTable]:
        """Every curve's columns, by curve index (``data[0]["amplitude"]``, ``data[0].amplitude``)."""
        return {c: self.table(c) for c in range(len(self.curves))}

    def state(self, curve: int, omega: float):
        """The end state of a finished point that can start the next one of a chain (None if
        it is not finished or stopped early: only a point that ran to its end, at forcing phase
        0, can)."""
        p = self.points.get((curve, float(omega)))
        return None if p is None or p.failed else p.final_state

    @property
    def n_done(self) -> int:
        """Completed points over all curves."""
        return int(sum(t.done.sum() for t in self.data.values()))

    @property
    def n_total(self) -> int:
        """Points over all curves."""
        return len(self.curves) * self.omega.size

    @property
    def n_failed(self) -> int:
        """Points that stopped early (a slack segment, a blow-up): their values are partial."""
        return int(sum((t.failed & t.done).sum() for t in self.data.values()))

    @property
    def n_refined(self) -> int:
        """Frequencies added by refinement."""
        return self.omega.size - int(self.settings.get("grid_points", self.omega.size))

    def failures(self) -> list[str]:
        """``"w = 5.05 rad/s (up): stopped at t = 12.3 s: segment 2 went slack ..."`` per failed point."""
        out = []
        for c, curve in enumerate(self.curves):
            d = self.table(c)
            g = "" if self.gamma is None else f", gamma = {self.gamma[curve.gamma_index]:g}"
            label = "" if curve.direction == "independent" and not g else f" ({curve.direction}{g})"
            for i in np.flatnonzero(d.failed & d.done):
                out.append(f"w = {self.omega[i]:.6g} rad/s{label}: {d.status[i]}")
        return out

    @property
    def complete(self) -> bool:
        """Whether every point has been computed."""
        return self.n_done == self.n_total


def channel_indices(case: Case, names: Iterable[str] | None) -> tuple[list[str], np.ndarray]:
    """Channel names and 0-based DOF indices (default: every DOF)."""
    n_dof = case.dim * case.cable.n_nodes
    if not names:
        names = [f"z{i + 1}" for i in range(n_dof)]
    idx = np.array([channel_index(c, n_dof, case.dim) for c in names], dtype=int)
    return [f"z{i + 1}" for i in idx], idx


def plan(case: Case) -> tuple[np.ndarray, np.ndarray | None, list[Curve]]:
    """Frequencies, gammas and curves of the case's sweep."""
    sw = case.sweep
    omega = sw.frequencies()
    if sw.refine_levels:
        omega = np.unique(omega)  # refinement works on the ascending grid
    gamma = None if sw.gamma is None else np.array(sw.gamma, dtype=float)
    dirs = {"independent": ["independent"], "up": ["up"], "down": ["down"], "both": ["up", "down"]}[sw.direction]
    curves = [Curve(g, d) for g in range(1 if gamma is None else gamma.size) for d in dirs]
    return omega, gamma, curves


# ----------------------------------------------------------------------------------------------
# One point (runs in a worker)
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepContext:
    """What every point of one sweep shares, solved once: the case, its statics, the channels
    and the choices of analysis and integrator. Sent to each worker once."""

    case: Case
    static: StaticResult
    integrator: str | None
    channels: tuple[int, ...]
    disturbance: float = 0.0  # m, out of the plane at each point's start (spatial cables)

    def fundamental(self):
        """The equations of motion and the integrator of this sweep forced at the first mode's
        frequency."""
        w = float(self.static.modes.omega[0])
        eom = build_equations(self.case, self.static, omega=w)
        return eom, make_integrator(self.case.integrator, eom, w, self.integrator)

    def warm_up(self) -> None:
        """Load (or compile) the kernels of this sweep: a few forcing periods at the fundamental."""
        w = float(self.static.modes.omega[0])
        eom, integ = self.fundamental()
        steady_response(eom, integ, np.array(self.channels), SteadyCriterion(cap=4 * 2 * np.pi / w,
                                                                               window=2 * 2 * np.pi / w))


@dataclass(frozen=True)
class PointJob:
    """One point to compute (small: the rest is in the :class:`SweepContext`)."""

    curve: int
    omega: float
    gamma: float
    start: tuple | None  # initial state for chains


def solve_point(ctx: SweepContext, job: PointJob) -> SweepPoint:
    """Steady response of one sweep point (the unit of parallel work)."""
    case, static, sw = ctx.case, ctx.static, ctx.case.sweep
    eom = build_equations(case, static, omega=job.omega, load_scale=job.gamma)
    integ = make_integrator(case.integrator, eom, max(job.omega, float(static.modes.omega[0])), ctx.integrator)
    crit = SteadyCriterion(cap=sw.duration, window=sw.window, tol=sw.tol, max_period=sw.max_period, floquet=sw.floquet)
    s0 = None if job.start is None else np.array(job.start)
    s0 = disturbed_start(eom, static, ctx.disturbance, "sweep.disturbance", s0)
    t0 = time.perf_counter()
    decide = accelerated_steady_response if sw.accelerate else steady_response
    r = decide(eom, integ, np.array(ctx.channels), crit, s0=s0)
    return SweepPoint.from_response(job.curve, job.omega, r, time.perf_counter() - t0, integ.name)


def _solve_in_worker(key: str, job: PointJob) -> SweepPoint:
    return solve_point(pool.context(key), job)


def _solve_remote(ctx: SweepContext, job: PointJob) -> SweepPoint:
    return solve_point(ctx, job)


# ----------------------------------------------------------------------------------------------
# Setting up: the statics once
# ----------------------------------------------------------------------------------------------
def _check_sweepable(case: Case, static) -> None:
    need_inextensible(static)
    if not case.forced:
        raise CablesimError("loads.FL is zero and no support moves, so a sweep has nothing to force the cable with; "
                            "give peak harmonic loads FL or a support amplitude (supports:).", field="loads.FL")


#: The last statics solved for a sweep, by (case text, analysis): the estimate and the sweep share them.
_STATICS: dict = {}


def _statics(case: Case, analysis: str | None) -> StaticResult:
    key = (case.text or repr(case), analysis)
    if key not in _STATICS:
        _STATICS.clear()
        _STATICS[key] = run_static(case, analysis, all_models=False)
    return _STATICS[key]


def sweep_statics(case: Case, analysis: str | None = None) -> StaticResult:
    """The static equilibrium a sweep of ``case`` starts from, solved once per case and
    analysis (the cost estimate and the sweep share it)."""
    if case.sweep is None:
        raise CablesimError(
            "This case has no `sweep:` section. Add one, for example "
            "`sweep: {omega: {start: 0.5, stop: 6.0, num: 111}, channels: [z2, z4]}` "
            "(`cablesim example` shows a complete one).",
            field="sweep",
        )
    static = _statics(case, analysis)
    _check_sweepable(case, static)
    return static


def new_sweep_result(case: Case, case_text: str, analysis: str | None = None,
                     static: StaticResult | None = None) -> SweepResult:
    """An empty :class:`SweepResult` for the case's ``sweep:`` section (nothing computed)."""
    static = static if static is not None else sweep_statics(case, analysis)
    omega, gamma, curves = plan(case)
    names, _ = channel_indices(case, case.sweep.channels)
    sw = case.sweep
    settings = dict(cap=sw.duration, window=sw.window, tol=sw.tol, max_period=sw.max_period, floquet_check=sw.floquet,
                    accelerate=sw.accelerate, refine=sw.refine_levels, grid_points=int(omega.size),
                    finest_step=finest_step(omega, sw.refine_levels),
                    disturbance=sweep_disturbance(case, static.analysis))
    return SweepResult(omega=omega, gamma=gamma, direction=sw.direction, channels=names, curves=curves,
                       n_dof=case.dim * case.cable.n_nodes, dim=case.dim, analysis=static.analysis, modal_omega=static.modes.omega.copy(),
                       case_name=case.name, case_text=case_text, settings=settings)


def estimate_sweep(case: Case, analysis: str | None = None, integrator: str | None = None) -> Cost:
    """Upper bound of the cost of the case's sweep (:mod:`cablesim.analyses.cost`), nothing
    integrated: every point, refined ones included, to its cap."""
    static = sweep_statics(case, analysis)
    res = new_sweep_result(case, case.text, analysis, static)
    w1 = float(static.modes.omega[0])
    picks = np.unique(np.linspace(0, res.omega.size - 1, min(res.omega.size, 12)).round().astype(int))
    points = []
    for w in res.omega[picks]:
        eom = build_equations(case, static, omega=float(w))
        points.append((eom, make_integrator(case.integrator, eom, max(float(w), w1), integrator), float(w)))
    sw = case.sweep
    return sweep_cost(points, res.omega.size, len(res.curves), sw.duration, sw.window, len(res.channels),
                      refine_budget(res))


def refine_budget(res: SweepResult) -> int:
    """Most frequencies refinement may add (:data:`cablesim.analyses.refine.BUDGET` times the
    grid's and :data:`~cablesim.analyses.refine.BUDGET_FLOOR`)."""
    return BUDGET * int(res.settings["grid_points"]) + BUDGET_FLOOR if res.settings.get("refine") else 0


# ----------------------------------------------------------------------------------------------
# The recorder
# ----------------------------------------------------------------------------------------------
class SweepRecorder(Protocol):
    """What :func:`run_sweep` tells about its progress (all methods optional in spirit: a
    recorder that keeps nothing returns ``[]`` from :meth:`previous` and ignores the rest)."""

    def previous(self) -> list[dict]:
        """Journal records (JSON form) of points already computed (resuming a sweep)."""

    def begin(self) -> None:
        """Called once the settings are valid, before the first point."""

    def point(self, point: SweepPoint, result: SweepResult) -> None:
        """Called after each point, with it and the result so far."""

    def end(self, result: SweepResult, complete: bool) -> None:
        """Called last, also when the sweep is interrupted or fails."""


class _NoRecorder:
    def previous(self) -> list[dict]:
        return []

    def begin(self) -> None:
        pass

    def point(self, point: SweepPoint, result: SweepResult) -> None:
        pass

    def end(self, result: SweepResult, complete: bool) -> None:
        pass


def _read_previous(res: SweepResult, records) -> dict:
    """Check the journal's records: ``{(curve, omega): point}``; warnings for those skipped."""
    found = {}
    lo, hi = float(res.omega.min()), float(res.omega.max())
    for rec in records:
        where = f"journal line {rec['line']}" if isinstance(rec, dict) and "line" in rec else "a journal record"
        try:
            p = SweepPoint.from_json(rec, len(res.channels), res.n_dof, res.n_segments)
            if not 0 <= p.curve < len(res.curves):
                raise BadRecord(f"curve {p.curve} is not a curve of this sweep")
            on_grid = np.abs(res.omega - p.omega) <= 1e-9 * p.omega
            if "index" in rec:  # journals of earlier versions name the grid point by its index too
                i = rec["index"]
                if not isinstance(i, int) or isinstance(i, bool) or not 0 <= i < res.omega.size:
                    raise BadRecord(f"point ({p.curve}, {i}) is not a point of this sweep")
                if not on_grid[i]:
                    raise BadRecord(f"its frequency {p.omega!r} is not that of point {i + 1} ({res.omega[i]:g} rad/s)")
            if not on_grid.any() and not (res.settings.get("refine") and lo < p.omega < hi):
                raise BadRecord(f"its frequency {p.omega:g} rad/s is not a point of this sweep")
            p = replace(p, omega=float(res.omega[np.argmax(on_grid)])) if on_grid.any() else p
        except BadRecord as why:
            res.warnings.append(f"{where} was skipped ({why}); its point is computed again")
            continue
        found[(p.curve, p.omega)] = p
    return found


# ----------------------------------------------------------------------------------------------
# The driver
# ----------------------------------------------------------------------------------------------
def _dask(scheduler: str | None):
    """``(joblib config context, Parallel, client)`` for a Dask cluster."""
    import joblib

    try:
        from dask.distributed import Client  # optional extra, loaded only when asked for
    except ImportError:
        raise CablesimError(
            "--backend dask needs dask.distributed: install cablesim with the 'dask' extra "
            "(pip install 'cablesim[dask]')."
        ) from None
    if scheduler is None:
        raise CablesimError("--backend dask needs --scheduler ADDRESS (e.g. tcp://host:8786).")
    try:
        client = Client(scheduler, timeout=10)
    except OSError as exc:
        raise CablesimError(f"Could not reach the Dask scheduler at {scheduler}: {exc}.") from None
    # joblib registers its Dask backend through parallel_config, not by name in Parallel.
    return joblib.parallel_config(backend="dask"), joblib.Parallel(return_as="generator_unordered"), client


class _Runner:
    """Runs the rounds of points: in this process, in a warm local pool, or on Dask."""

    def __init__(self, ctx: SweepContext, jobs: int, backend: str | None, scheduler: str | None, rate: float):
        self.ctx, self.jobs, self.rate = ctx, jobs, rate
        self.pool = None
        self.dask = _dask(scheduler) if backend == "dask" else None
        self.key = uuid.uuid4().hex
        self.workers = 1

    def run(self, batch: list[PointJob], rounds: int = 1):
        """Every job of a round (``rounds``: how many such rounds are to come, for the estimate
        of the work), results in the order they finish."""
        if self.dask is not None:
            import joblib

            config, parallel, _ = self.dask
            with config:
                yield from parallel(joblib.delayed(_solve_remote)(self.ctx, j) for j in batch)
            return
        if self.pool is None and len(batch) > 1:
            work = len(batch) * rounds * self.ctx.case.sweep.duration * self.rate
            workers = pool.choose_workers(self.jobs, work, len(batch))
            if workers > 1:
                self.workers = workers
                self.pool = pool.WorkerPool(workers, self.key, self.ctx)
        if self.pool is None:
            for j in batch:
                yield solve_point(self.ctx, j)
            return
        yield from self.pool.map_unordered(_solve_in_worker, batch)

    def close(self, failed: bool) -> None:
        if self.pool is not None:
            self.pool.__exit__(KeyboardInterrupt if failed else None, None, None)
        if self.dask is not None:
            self.dask[2].close()


def _calibrate(ctx: SweepContext, measure: bool) -> float:
    """Load the kernels here before any worker is forked; if ``measure``, the wall seconds one
    simulated second of this sweep costs (from a second, warm, run; else 0)."""
    ctx.warm_up()
    if not measure:
        return 0.0
    w = float(ctx.static.modes.omega[0])
    t0 = time.perf_counter()
    ctx.warm_up()
    return (time.perf_counter() - t0) / (4 * 2 * np.pi / w)


def _chain_rounds(res: SweepResult, make_job):
    """Rounds of up/down chains over the grid: each advances every unfinished chain by one point."""
    n = res.omega.size
    order = {c: (list(range(n)) if cv.direction == "up" else list(range(n - 1, -1, -1))) for c, cv in enumerate(res.curves)}
    pos = {c: 0 for c in order}
    while True:
        batch = []
        for c, seq in order.items():
            while pos[c] < len(seq) and res.has(c, res.omega[seq[pos[c]]]):
                pos[c] += 1
            if pos[c] < len(seq):
                prev = res.state(c, res.omega[seq[pos[c] - 1]]) if pos[c] > 0 else None
                batch.append(make_job(c, float(res.omega[seq[pos[c]]]), prev))
        if not batch:
            return
        yield batch


def _refined_round(res: SweepResult, new: np.ndarray, make_job) -> list[PointJob]:
    """The jobs of the new frequencies on every curve; a chain's point starts from its done
    neighbour before it in the chain's direction."""
    res.extend(new)
    batch = []
    for c, cv in enumerate(res.curves):
        for w in new:
            start = None
            if cv.direction != "independent":
                i = int(np.searchsorted(res.omega, w))
                j = i - 1 if cv.direction == "up" else i + 1
                start = res.state(c, res.omega[j]) if 0 <= j < res.omega.size else None
            if not res.has(c, w):
                batch.append(make_job(c, float(w), start))
    return batch


def run_sweep(
    case: Case,
    case_text: str,
    analysis: str | None = None,
    integrator: str | None = None,
    n_jobs: int = -1,
    backend: str | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    recorder: SweepRecorder | None = None,
) -> SweepResult:
    """Run (or finish) the sweep of a case.

    Parameters
    ----------
    case : Case
        Must have a ``sweep:`` section.
    case_text : str
        Its YAML text (stored with the results).
    analysis, integrator : str, optional
        Overrides of the case file.
    n_jobs : int
        Most worker processes (-1: one per core). The sweep uses a pool only when its estimated
        work exceeds what starting one costs (:func:`cablesim.analyses.pool.choose_workers`).
    backend, scheduler : str, optional
        ``"dask"`` and the scheduler address to run the points on a Dask cluster.
    progress : callable, optional
        Called as ``progress(done, total)`` after each point (``total`` grows with refinement).
    recorder : SweepRecorder, optional
        Receives every finished point and supplies those of an interrupted run
        (:class:`cablesim.io.journal.SweepFile` journals them and writes the HDF5 file).

    Returns
    -------
    SweepResult
    """
    recorder = recorder or _NoRecorder()
    static = sweep_statics(case, analysis)
    res = new_sweep_result(case, case_text, analysis, static)
    _, idx = channel_indices(case, case.sweep.channels)
    stored = _read_previous(res, recorder.previous())
    res.warnings[:0] = list(getattr(recorder, "warnings", ()))
    ctx = SweepContext(case, static, integrator, tuple(int(x) for x in idx), res.settings["disturbance"])

    def make_job(c: int, w: float, start) -> PointJob:
        g = 1.0 if res.gamma is None else float(res.gamma[res.curves[c].gamma_index])
        return PointJob(c, w, g, None if start is None else tuple(start))

    local = backend != "dask"
    runner = _Runner(ctx, n_jobs, backend, scheduler, rate=_calibrate(ctx, n_jobs != 1) if local else 0.0)
    res.settings.update(integrator_record(ctx.fundamental()[1]))
    recorder.begin()

    def done(p: SweepPoint, new: bool = True):
        # the point enters the result and the journal together: a signal between the two left a
        # final snapshot holding a point its journal did not, which a resume then computed again
        with interrupts.Deferred() as held:
            res.add(p)
            if new:
                recorder.point(p, res)
        if held.hit:
            raise KeyboardInterrupt
        if progress is not None:
            progress(res.n_done, res.n_total)

    def take_stored(batch):
        for j in batch:
            p = stored.pop((j.curve, j.omega), None)
            if p is not None:
                res.add(p)
        return [j for j in batch if not res.has(j.curve, j.omega)]

    completed, failed = False, True
    try:
        take_stored([make_job(c, float(w), None) for c in range(len(res.curves)) for w in res.omega])
        chains = case.sweep.direction != "independent"
        rounds = _chain_rounds(res, make_job) if chains else iter([[make_job(c, float(w), None)
                                                                     for c in range(len(res.curves))
                                                                     for w in dict.fromkeys(res.omega.tolist())
                                                                     if not res.has(c, w)]])
        for batch in rounds:
            for p in runner.run(batch, res.omega.size if chains else 1):
                done(p)
        while True:
            new = refinements(res.omega, [res.table(c) for c in range(len(res.curves))],
                              res.settings["finest_step"], refine_budget(res) - res.n_refined)
            if not new.size:
                break
            batch = take_stored(_refined_round(res, new, make_job))
            if progress is not None:
                progress(res.n_done, res.n_total)
            for p in runner.run(batch):
                done(p)
        for (c, w) in stored:
            res.warnings.append(f"a journal record of w = {w:g} rad/s (curve {c + 1}) is not a point of this sweep; "
                                "it was skipped")
        completed, failed = res.complete, False
    finally:
        res.settings["workers"] = runner.workers
        runner.close(failed)
        recorder.end(res, completed)
    return res


def workers_used(res: SweepResult) -> int:
    """Worker processes the sweep ran on (1: in the driver), as recorded in its settings."""
    return int(res.settings.get("workers", 1))

