"""Frequency-domain response sweeps.

A sweep is a set of *curves*, one per ``gamma`` (scale of FL) and direction. On an
``independent`` curve every point starts from the static equilibrium at rest (as in the paper),
so all points run in parallel. On an ``up`` or ``down`` curve each point starts from the end
state of the previous one, which reveals jumps and hysteresis; such a curve is a chain, and the
chains (up, down, each gamma) run in parallel with one another.

The driver knows nothing of files: every finished point goes to a *recorder* (see
:class:`SweepRecorder`); :class:`cablesim.io.journal.SweepFile` is the one that journals each
point and keeps the HDF5 file up to date, so that a killed run loses nothing.
"""

from __future__ import annotations

import contextlib
import functools
import multiprocessing
import os
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Protocol

import joblib
import numpy as np

from ..case import Case, parse_case
from ..channels import channel_index
from ..dynamics.integrators import Integrator
from ..dynamics.status import Status
from ..dynamics.steady import SteadyCriterion, steady_response
from ..orbits.accelerate import accelerated_steady_response
from ..errors import CablesimError
from .cost import Cost, sweep_cost
from .setup import build_equations, integrator_record, make_integrator
from .static import run_static

FLOAT_FIELDS = ("amplitude", "halfrange", "response_frequency")


@dataclass(frozen=True)
class Curve:
    """One curve of a sweep: a gamma (index) and a direction."""

    gamma_index: int
    direction: str  # "independent" | "up" | "down"


@dataclass
class SweepResult:
    """All results of a sweep, complete or not.

    ``settings`` holds the sweep's ``cap``, ``window``, ``tol``, ``max_period`` and
    ``floquet_check``; ``modal_omega`` the linear modal frequencies, rad/s. Arrays have a leading curve-specific layout: ``data[curve][field]`` with ``(P, C)`` for the
    per-channel fields and ``(P,)`` for ``period``, ``steady``, ``t_end``, ``floquet``,
    ``done``.
    """

    omega: np.ndarray
    gamma: np.ndarray | None
    direction: str
    channels: list[str]
    curves: list[Curve]
    analysis: str = "exact"
    modal_omega: np.ndarray = field(default_factory=lambda: np.empty(0))
    case_name: str = "case"
    case_text: str = ""
    settings: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    states: dict = field(default_factory=dict)  # (curve, index) -> final state (chains)
    warnings: list = field(default_factory=list)  # e.g. journal records that were skipped

    @property
    def n_done(self) -> int:
        """Completed points over all curves."""
        return int(sum(d["done"].sum() for d in self.data.values()))

    @property
    def n_total(self) -> int:
        """Points over all curves."""
        return len(self.curves) * self.omega.size

    @property
    def n_failed(self) -> int:
        """Points that stopped early (a slack segment, a blow-up): their values are partial."""
        return int(sum((d["failed"] & d["done"]).sum() for d in self.data.values()))

    def failures(self) -> list[str]:
        """``"w = 5.05 rad/s (up): stopped at t = 12.3 s: segment 2 went slack ..."`` per failed point."""
        out = []
        for c, curve in enumerate(self.curves):
            d = self.data[c]
            g = "" if self.gamma is None else f", gamma = {self.gamma[curve.gamma_index]:g}"
            label = "" if curve.direction == "independent" and not g else f" ({curve.direction}{g})"
            for i in np.flatnonzero(d["failed"] & d["done"]):
                out.append(f"w = {self.omega[i]:.6g} rad/s{label}: {d['status'][i]}")
        return out

    @property
    def complete(self) -> bool:
        """Whether every point has been computed."""
        return self.n_done == self.n_total


def channel_indices(case: Case, names: Iterable[str] | None) -> tuple[list[str], np.ndarray]:
    """Channel names and 0-based DOF indices (default: every DOF)."""
    n_dof = case.cable.n_nodes * 2
    if not names:
        names = [f"z{i + 1}" for i in range(n_dof)]
    idx = np.array([channel_index(c, n_dof) for c in names], dtype=int)
    return [f"z{i + 1}" for i in idx], idx


def plan(case: Case) -> tuple[np.ndarray, np.ndarray | None, list[Curve]]:
    """Frequencies, gammas and curves of the case's sweep."""
    sw = case.sweep
    omega = sw.frequencies()
    gamma = None if sw.gamma is None else np.array(sw.gamma, dtype=float)
    dirs = {"independent": ["independent"], "up": ["up"], "down": ["down"], "both": ["up", "down"]}[sw.direction]
    curves = [Curve(g, d) for g in range(1 if gamma is None else gamma.size) for d in dirs]
    return omega, gamma, curves


# ----------------------------------------------------------------------------------------------
# One point (runs in a worker)
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PointJob:
    """Everything a worker needs for one point (picklable, small)."""

    case_text: str
    analysis: str | None
    integrator: str | None
    gamma: float
    omega: float
    channels: tuple[int, ...]
    curve: int
    index: int
    start: tuple | None  # initial state for chains
    parent: int = 0  # process id of the sweep's driver (workers end when it ends)


@functools.lru_cache(maxsize=8)
def _static_for(case_text: str, analysis: str | None):
    case = parse_case(case_text)
    return case, run_static(case, analysis, all_models=False)


_WATCHDOG: list[int] = []


def end_with_parent(parent: int, interval: float = 0.5) -> None:
    """In a local worker process: exit as soon as the sweep's driver ``parent`` is gone.

    A worker whose driver was killed would otherwise finish its point (minutes, for a long cap)
    with nobody to report to. A daemon thread watches the parent process id; the compiled time
    loop returns to Python many times a second, so the thread gets its turn.
    """
    if _WATCHDOG or parent <= 0 or os.getpid() == parent:
        return  # already watching, or in the driver itself (one job: no workers)
    if not multiprocessing.current_process().name.startswith("LokyProcess"):
        return  # not a local worker of this sweep (a Dask worker belongs to its cluster)
    if os.getppid() != parent:
        os._exit(1)  # the driver died while this worker was starting
    _WATCHDOG.append(parent)

    def watch():
        while True:
            time.sleep(interval)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="cablesim-end-with-parent", daemon=True).start()


def solve_point(job: PointJob) -> dict:
    """Steady response of one sweep point (the unit of parallel work)."""
    end_with_parent(job.parent)
    case, static = _static_for(job.case_text, job.analysis)
    sw = case.sweep
    eom = build_equations(case, static, omega=job.omega, load_scale=job.gamma)
    integ = make_integrator(case.integrator, eom, max(job.omega, float(static.modes.omega[0])), job.integrator)
    crit = SteadyCriterion(
        cap=sw.duration, window=sw.window, tol=sw.tol, max_period=sw.max_period, floquet=sw.floquet
    )
    s0 = None if job.start is None else np.array(job.start)
    t0 = time.perf_counter()
    decide = accelerated_steady_response if sw.accelerate else steady_response
    r = decide(eom, integ, np.array(job.channels), crit, s0=s0)
    return {
        "curve": job.curve,
        "index": job.index,
        "omega": job.omega,
        "amplitude": [None if not np.isfinite(x) else float(x) for x in r.amplitude],
        "halfrange": [None if not np.isfinite(x) else float(x) for x in r.halfrange],
        "response_frequency": [None if not np.isfinite(x) else float(x) for x in r.response_frequency],
        "period": int(r.period),
        "steady": bool(r.steady),
        "t_end": float(r.t_end),
        "floquet": None if not np.isfinite(r.floquet) else float(r.floquet),
        "decided": r.decided,
        "multipliers": None if r.multipliers is None else [[float(m.real), float(m.imag)] for m in r.multipliers],
        "status": r.message,
        "code": int(r.status),
        "final_state": r.final_state.tolist() if np.all(np.isfinite(r.final_state)) else None,
        "peak_tension": None if r.peak_tension is None else r.peak_tension.tolist(),
        "slack_fraction": None if r.slack_fraction is None else r.slack_fraction.tolist(),
        "wall": time.perf_counter() - t0,
        "integrator": integ.name,
    }


# ----------------------------------------------------------------------------------------------
# Journal and result assembly
# ----------------------------------------------------------------------------------------------
def _empty_result(omega, gamma, direction, channels, curves, **meta) -> SweepResult:
    res = SweepResult(omega=omega, gamma=gamma, direction=direction, channels=channels, curves=curves, **meta)
    P, C = omega.size, len(channels)
    n_dof = res.modal_omega.size  # one modal frequency per degree of freedom
    for c in range(len(curves)):
        res.data[c] = {
            "amplitude": np.full((P, C), np.nan),
            "halfrange": np.full((P, C), np.nan),
            "response_frequency": np.full((P, C), np.nan),
            "period": np.zeros(P, dtype=np.int64),
            "steady": np.zeros(P, dtype=bool),
            "failed": np.zeros(P, dtype=bool),
            "t_end": np.full(P, np.nan),
            "floquet": np.full(P, np.nan),
            "wall": np.full(P, np.nan),
            "decided": np.full(P, "", dtype=object),
            "multipliers": np.full((P, 2 * n_dof), np.nan + 0j),
            "peak_tension": np.full((P, n_dof // 2 + 1), np.nan),
            "slack_fraction": np.full((P, n_dof // 2 + 1), np.nan),
            "done": np.zeros(P, dtype=bool),
            "status": np.full(P, "", dtype=object),
        }
    return res


def record_point(res: SweepResult, rec: dict) -> None:
    """Enter one point's record (from :func:`solve_point` or a journal) into the result."""
    d = res.data[rec["curve"]]
    i = rec["index"]
    for f in FLOAT_FIELDS:
        d[f][i] = [np.nan if x is None else x for x in rec[f]]
    d["period"][i] = rec["period"]
    d["steady"][i] = rec["steady"]
    d["failed"][i] = not Status(rec["code"]).success
    d["t_end"][i] = rec["t_end"]
    d["floquet"][i] = np.nan if rec["floquet"] is None else rec["floquet"]
    d["wall"][i] = rec.get("wall", np.nan)
    d["decided"][i] = rec.get("decided", "")
    for f in ("peak_tension", "slack_fraction"):
        if rec.get(f) is not None:
            d[f][i] = rec[f]
    if rec.get("multipliers"):
        mu = np.array([complex(a, b) for a, b in rec["multipliers"]])
        d["multipliers"][i, : mu.size] = mu
    d["status"][i] = str(rec.get("status", ""))
    d["done"][i] = True
    # Only a point that ran to its end (at forcing phase 0) can start the next one of a chain.
    res.states[(rec["curve"], i)] = None if d["failed"][i] else rec.get("final_state")


_NUMBER = (int, float)


def _numbers(x, n: int, none_ok: bool = True) -> bool:
    return isinstance(x, list) and len(x) == n and all(
        (v is None and none_ok) or (isinstance(v, _NUMBER) and not isinstance(v, bool)) for v in x)


def check_record(res: SweepResult, rec) -> str | None:
    """Why a journal record cannot be entered into ``res`` (None if it can)."""
    if not isinstance(rec, dict):
        return "it is not a record"
    need = ("curve", "index", "omega", "amplitude", "halfrange", "response_frequency", "period", "steady",
            "t_end", "code", "floquet")
    missing = [k for k in need if k not in rec]
    if missing:
        return f"it lacks {', '.join(missing)}"
    c, i = rec["curve"], rec["index"]
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in (c, i, rec["period"], rec["code"])):
        return "curve, index, period and code must be whole numbers"
    if not 0 <= c < len(res.curves) or not 0 <= i < res.omega.size:
        return f"point ({c}, {i}) is not a point of this sweep"
    if not isinstance(rec["omega"], _NUMBER) or not abs(rec["omega"] - res.omega[i]) <= 1e-9 * res.omega[i]:
        return f"its frequency {rec['omega']!r} is not that of point {i + 1} ({res.omega[i]:g} rad/s)"
    C = len(res.channels)
    if not all(_numbers(rec[k], C) for k in FLOAT_FIELDS):
        return f"its per-channel values are not {C} numbers each"
    if rec["code"] not in {int(s) for s in Status}:
        return f"its status code {rec['code']} is unknown"
    if not isinstance(rec["steady"], bool) or not _numbers([rec["t_end"], rec.get("wall", 0.0)], 2, none_ok=False):
        return "steady must be true or false, t_end and wall numbers"
    if not _numbers([rec["floquet"]], 1):
        return "floquet must be a number or null"
    final, n = rec.get("final_state"), 3 * res.modal_omega.size
    if final is not None and n and not _numbers(final, n, none_ok=False):
        return f"its final state is not a list of {n} numbers"
    return None


# ----------------------------------------------------------------------------------------------
# The driver
# ----------------------------------------------------------------------------------------------
class SweepRecorder(Protocol):
    """What :func:`run_sweep` tells about its progress (all methods optional in spirit: a
    recorder that keeps nothing returns ``[]`` from :meth:`previous` and ignores the rest)."""

    def previous(self) -> list[dict]:
        """Records of points already computed (resuming an interrupted sweep)."""

    def begin(self) -> None:
        """Called once the settings are valid, before the first point."""

    def point(self, record: dict, result: SweepResult) -> None:
        """Called after each point, with its record and the result so far."""

    def end(self, result: SweepResult, complete: bool) -> None:
        """Called last, also when the sweep is interrupted or fails."""


class _NoRecorder:
    def previous(self) -> list[dict]:
        return []

    def begin(self) -> None:
        pass

    def point(self, record: dict, result: SweepResult) -> None:
        pass

    def end(self, result: SweepResult, complete: bool) -> None:
        pass


def _parallel(n_jobs: int, backend: str | None, scheduler: str | None):
    """``(config context, Parallel, client)``; the context selects joblib's backend."""
    if backend == "dask":
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
    return contextlib.nullcontext(), joblib.Parallel(n_jobs=n_jobs, return_as="generator_unordered"), None


def _check_sweepable(case: Case, static) -> None:
    if static.inextensible is None:
        raise CablesimError("Sweeps need sum(cable.S) greater than the chord (see `history`).", field="cable.S")
    if not np.any(case.FL):
        raise CablesimError("loads.FL is zero, so a sweep has nothing to force the cable with.", field="loads.FL")


def new_sweep_result(case: Case, case_text: str, analysis: str | None = None) -> SweepResult:
    """An empty :class:`SweepResult` for the case's ``sweep:`` section (nothing computed)."""
    if case.sweep is None:
        raise CablesimError(
            "This case has no `sweep:` section. Add one, for example "
            "`sweep: {omega: {start: 0.5, stop: 6.0, num: 111}, channels: [z2, z4]}` "
            "(`cablesim example` shows a complete one).",
            field="sweep",
        )
    static = run_static(case, analysis, all_models=False)
    _check_sweepable(case, static)
    omega, gamma, curves = plan(case)
    names, _ = channel_indices(case, case.sweep.channels)
    sw = case.sweep
    settings = dict(cap=sw.duration, window=sw.window, tol=sw.tol, max_period=sw.max_period, floquet_check=sw.floquet,
                    accelerate=sw.accelerate)
    return _empty_result(omega, gamma, sw.direction, names, curves, analysis=static.analysis,
                         modal_omega=static.modes.omega.copy(), case_name=case.name, case_text=case_text,
                         settings=settings)


def estimate_sweep(case: Case, analysis: str | None = None, integrator: str | None = None) -> Cost:
    """Upper bound of the cost of the case's sweep (:mod:`cablesim.analyses.cost`), nothing integrated."""
    res = new_sweep_result(case, case.text, analysis)
    static = _static_for(case.text, analysis)[1] if case.text else run_static(case, analysis, all_models=False)
    w1 = float(static.modes.omega[0])
    picks = np.unique(np.linspace(0, res.omega.size - 1, min(res.omega.size, 12)).round().astype(int))
    points = []
    for w in res.omega[picks]:
        eom = build_equations(case, static, omega=float(w))
        points.append((eom, make_integrator(case.integrator, eom, max(float(w), w1), integrator), float(w)))
    sw = case.sweep
    return sweep_cost(points, res.omega.size, len(res.curves), sw.duration, sw.window, len(res.channels))


def _chain_batches(res: SweepResult, make_job):
    """Rounds of up/down chains: each round advances every unfinished chain by one point."""
    n = res.omega.size
    order = {c: (list(range(n)) if cv.direction == "up" else list(range(n - 1, -1, -1))) for c, cv in enumerate(res.curves)}
    pos = {c: 0 for c in order}
    while True:
        batch = []
        for c, seq in order.items():
            while pos[c] < len(seq) and res.data[c]["done"][seq[pos[c]]]:
                pos[c] += 1
            if pos[c] < len(seq):
                prev = res.states.get((c, seq[pos[c] - 1])) if pos[c] > 0 else None
                batch.append(make_job(c, seq[pos[c]], prev))
        if not batch:
            return
        yield batch


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
        Its YAML text (sent to the workers and stored with the results).
    analysis, integrator : str, optional
        Overrides of the case file.
    n_jobs : int
        Worker processes (-1: all cores).
    backend, scheduler : str, optional
        ``"dask"`` and the scheduler address to run the points on a Dask cluster.
    progress : callable, optional
        Called as ``progress(done, total)`` after each point.
    recorder : SweepRecorder, optional
        Receives every finished point and supplies those of an interrupted run
        (:class:`cablesim.io.journal.SweepFile` journals them and writes the HDF5 file).

    Returns
    -------
    SweepResult
    """
    recorder = recorder or _NoRecorder()
    res = new_sweep_result(case, case_text, analysis)
    _, idx = channel_indices(case, case.sweep.channels)
    for rec in recorder.previous():
        why = check_record(res, rec)
        if why is None:
            record_point(res, rec)
        else:
            where = f"journal line {rec['line']}" if isinstance(rec, dict) and "line" in rec else "a journal record"
            res.warnings.append(f"{where} was skipped ({why}); its point is computed again")
    res.warnings[:0] = list(getattr(recorder, "warnings", ()))
    gamma = res.gamma

    def job(c: int, i: int, start) -> PointJob:
        g = 1.0 if gamma is None else float(gamma[res.curves[c].gamma_index])
        return PointJob(case_text, analysis, integrator, g, float(res.omega[i]), tuple(int(x) for x in idx), c, i,
                        None if start is None else tuple(start), os.getpid())

    config, parallel, client = _parallel(n_jobs, backend, scheduler)  # settings errors first
    res.settings.update(integrator_record(_warm_up(case_text, analysis, integrator, idx)))
    recorder.begin()

    def done(rec):
        record_point(res, rec)
        recorder.point(rec, res)
        if progress is not None:
            progress(res.n_done, res.n_total)

    completed = False
    try:
        with config, parallel:
            if case.sweep.direction == "independent":
                todo = [job(c, i, None) for c in range(len(res.curves)) for i in range(res.omega.size)
                        if not res.data[c]["done"][i]]
                batches = [todo]
            else:
                batches = _chain_batches(res, job)
            for batch in batches:
                for rec in parallel(joblib.delayed(solve_point)(j) for j in batch):
                    done(rec)
        completed = res.complete
    finally:
        recorder.end(res, completed)
        if client is not None:
            client.close()
    return res


def _warm_up(case_text, analysis, integrator, idx) -> Integrator:
    """Compile (or load from numba's cache) the kernels once before forking workers; returns
    the integrator (at the first mode's frequency)."""
    case, static = _static_for(case_text, analysis)
    w = float(static.modes.omega[0])
    eom = build_equations(case, static, omega=w)
    integ = make_integrator(case.integrator, eom, w, integrator)
    steady_response(eom, integ, np.array(idx), SteadyCriterion(cap=4 * 2 * np.pi / w, window=2 * 2 * np.pi / w))
    return integ
