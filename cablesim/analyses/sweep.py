"""Frequency-domain response sweeps.

A sweep is a set of *curves*, one per ``gamma`` (scale of FL) and direction. On an
``independent`` curve every point starts from the static equilibrium at rest (as in the paper),
so all points run in parallel. On an ``up`` or ``down`` curve each point starts from the end
state of the previous one, which reveals jumps and hysteresis; such a curve is a chain, and the
chains (up, down, each gamma) run in parallel with one another.

Robustness: every completed point is appended at once to a journal (``OUT.h5.journal``, one
JSON record per line, flushed to disk), and the HDF5 file is rewritten atomically from it every
few seconds and at the end. A killed run therefore loses no completed point and never leaves a
corrupt file; ``resume=True`` reads the journal and computes only what is missing. The journal
is removed when the sweep completes.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from ..case import Case, parse_case
from ..errors import CablesimError
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

    Arrays have a leading curve-specific layout: ``data[curve][field]`` with ``(P, C)`` for the
    per-channel fields and ``(P,)`` for ``period``, ``steady``, ``t_end``, ``floquet``,
    ``done``.
    """

    omega: np.ndarray
    gamma: np.ndarray | None
    direction: str
    channels: list[str]
    curves: list[Curve]
    data: dict = field(default_factory=dict)
    states: dict = field(default_factory=dict)  # (curve, index) -> final state (chains)

    @property
    def n_done(self) -> int:
        """Completed points over all curves."""
        return int(sum(d["done"].sum() for d in self.data.values()))

    @property
    def n_total(self) -> int:
        """Points over all curves."""
        return len(self.curves) * self.omega.size

    @property
    def complete(self) -> bool:
        """Whether every point has been computed."""
        return self.n_done == self.n_total


def channel_indices(case: Case, names: Iterable[str] | None) -> tuple[list[str], np.ndarray]:
    """Channel names and 0-based DOF indices (default: every DOF)."""
    from ..plot_history import channel_index

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


@functools.lru_cache(maxsize=8)
def _static_for(case_text: str, analysis: str | None):
    case = parse_case(case_text)
    return case, run_static(case, analysis, all_models=False)


def solve_point(job: PointJob) -> dict:
    """Steady response of one sweep point (the unit of parallel work)."""
    from ..dynamics.history import build_equations
    from ..dynamics.steady import SteadyCriterion, steady_response
    from .dynamic import make_integrator

    case, static = _static_for(job.case_text, job.analysis)
    sw = case.sweep
    eom = build_equations(case, static, omega=job.omega, load_scale=job.gamma)
    integ = make_integrator(case.integrator, eom, max(job.omega, float(static.modes.omega[0])), job.integrator)
    crit = SteadyCriterion(
        cap=sw.duration, window=sw.window, tol=sw.tol, max_period=sw.max_period, floquet=sw.floquet
    )
    s0 = None if job.start is None else np.array(job.start)
    t0 = time.perf_counter()
    r = steady_response(eom, integ, np.array(job.channels), crit, s0=s0)
    return {
        "curve": job.curve,
        "index": job.index,
        "omega": job.omega,
        "amplitude": r.amplitude.tolist(),
        "halfrange": r.halfrange.tolist(),
        "response_frequency": [None if not np.isfinite(x) else float(x) for x in r.response_frequency],
        "period": int(r.period),
        "steady": bool(r.steady),
        "t_end": float(r.t_end),
        "floquet": None if not np.isfinite(r.floquet) else float(r.floquet),
        "status": r.status,
        "final_state": r.final_state.tolist(),
        "wall": time.perf_counter() - t0,
        "integrator": integ.name,
    }


# ----------------------------------------------------------------------------------------------
# Journal and result assembly
# ----------------------------------------------------------------------------------------------
def _fingerprint(case_text: str, analysis, integrator) -> str:
    h = hashlib.sha256()
    for part in (case_text, str(analysis), str(integrator)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def _empty_result(omega, gamma, direction, channels, curves) -> SweepResult:
    res = SweepResult(omega=omega, gamma=gamma, direction=direction, channels=channels, curves=curves)
    P, C = omega.size, len(channels)
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
            "done": np.zeros(P, dtype=bool),
        }
    return res


def _record(res: SweepResult, rec: dict) -> None:
    d = res.data[rec["curve"]]
    i = rec["index"]
    for f in FLOAT_FIELDS:
        d[f][i] = [np.nan if x is None else x for x in rec[f]]
    d["period"][i] = rec["period"]
    d["steady"][i] = rec["steady"]
    d["failed"][i] = rec["status"] not in ("steady", "cap reached")
    d["t_end"][i] = rec["t_end"]
    d["floquet"][i] = np.nan if rec["floquet"] is None else rec["floquet"]
    d["wall"][i] = rec.get("wall", np.nan)
    d["done"][i] = True
    # Only a point that ran to its end (at forcing phase 0) can start the next one of a chain.
    res.states[(rec["curve"], i)] = None if d["failed"][i] else rec["final_state"]


def _read_journal(path: Path, fingerprint: str) -> list[dict]:
    records = []
    with open(path) as f:
        lines = f.read().split("\n")
    if not lines or not lines[0].strip():
        return records
    head = json.loads(lines[0])
    if head.get("fingerprint") != fingerprint:
        raise CablesimError(
            f"The journal {path} belongs to a different case or different settings, so --resume "
            "cannot continue it. Run without --resume to start afresh (the journal is replaced), "
            "or give another output file with -o.",
            field="sweep",
        )
    good = len(lines[0]) + 1
    for line in lines[1:]:
        if not line.strip():
            good += len(line) + 1
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            break  # a record torn by a kill: everything before it is intact
        good += len(line) + 1
    # Cut a torn tail off, so that new records start on a line of their own.
    with open(path, "r+b") as f:
        f.truncate(min(good, os.path.getsize(path)))
    return records


class _Journal:
    def __init__(self, path: Path, fingerprint: str, fresh: bool):
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        if fresh:
            with open(path, "w") as f:
                f.write(json.dumps({"fingerprint": fingerprint}) + "\n")
                f.flush()
                os.fsync(f.fileno())
        self.f = open(path, "a")

    def append(self, rec: dict) -> None:
        self.f.write(json.dumps(rec) + "\n")
        self.f.flush()
        os.fsync(self.f.fileno())

    def close(self, remove: bool) -> None:
        self.f.close()
        if remove:
            self.path.unlink(missing_ok=True)


# ----------------------------------------------------------------------------------------------
# The driver
# ----------------------------------------------------------------------------------------------
def _parallel(n_jobs: int, backend: str | None, scheduler: str | None):
    """``(config context, Parallel, client)``; the context selects joblib's backend."""
    import contextlib

    import joblib

    if backend == "dask":
        try:
            from dask.distributed import Client
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


def run_sweep(
    case: Case,
    case_text: str,
    out: Path,
    analysis: str | None = None,
    integrator: str | None = None,
    n_jobs: int = -1,
    resume: bool = False,
    backend: str | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    snapshot_every: float = 3.0,
) -> SweepResult:
    """Run (or resume) the sweep of a case, writing results to ``out`` as they complete.

    Parameters
    ----------
    case : Case
        Must have a ``sweep:`` section.
    case_text : str
        Its YAML text (sent to the workers and stored in the file).
    out : Path
        HDF5 file; the journal is ``out`` + ``.journal``.
    analysis, integrator : str, optional
        Overrides of the case file.
    n_jobs : int
        Worker processes (-1: all cores).
    resume : bool
        Continue from the journal of an interrupted run.
    backend, scheduler : str, optional
        ``"dask"`` and the scheduler address to run the points on a Dask cluster.
    progress : callable, optional
        Called as ``progress(done, total)`` after each point.
    snapshot_every : float
        Seconds between atomic rewrites of the HDF5 file.

    Returns
    -------
    SweepResult
    """
    from ..io_hdf5 import write_sweep

    if case.sweep is None:
        raise CablesimError(
            "This case has no `sweep:` section. Add one, for example "
            "`sweep: {omega: {start: 0.5, stop: 6.0, num: 111}, channels: [z2, z4]}` "
            "(`cablesim example` shows a complete one).",
            field="sweep",
        )
    static = run_static(case, analysis, all_models=False)
    if static.inextensible is None:
        raise CablesimError("Sweeps need sum(cable.S) greater than the chord (see `history`).", field="cable.S")
    if not np.any(case.FL):
        raise CablesimError("loads.FL is zero, so a sweep has nothing to force the cable with.", field="loads.FL")
    omega, gamma, curves = plan(case)
    names, idx = channel_indices(case, case.sweep.channels)
    res = _empty_result(omega, gamma, case.sweep.direction, names, curves)
    fp = _fingerprint(case_text, analysis, integrator)
    jpath = out.with_name(out.name + ".journal")
    if resume:
        if not jpath.exists():
            if out.exists():
                raise CablesimError(f"{out} is already complete (no journal to resume); nothing to do.")
            raise CablesimError(f"There is no interrupted sweep to resume at {out} (no {jpath.name}).")
        for rec in _read_journal(jpath, fp):
            _record(res, rec)
    meta = dict(static=static, case_name=case.name, case_text=case_text, sweep=case.sweep)
    last = [time.monotonic()]

    def save(force: bool = False):
        if force or time.monotonic() - last[0] >= snapshot_every:
            write_sweep(out, res, **meta)
            last[0] = time.monotonic()

    def job(c: int, i: int, start) -> PointJob:
        g = 1.0 if gamma is None else float(gamma[curves[c].gamma_index])
        return PointJob(case_text, analysis, integrator, g, float(omega[i]), tuple(int(x) for x in idx), c, i,
                        None if start is None else tuple(start))

    config, parallel, client = _parallel(n_jobs, backend, scheduler)  # settings errors first
    _warm_up(case_text, analysis, integrator, idx)
    journal = _Journal(jpath, fp, fresh=not resume)
    import joblib

    def done(rec):
        journal.append(rec)
        _record(res, rec)
        if progress is not None:
            progress(res.n_done, res.n_total)
        save()

    completed = False
    try:
        with config, parallel:
            if case.sweep.direction == "independent":
                todo = [job(c, i, None) for c in range(len(curves)) for i in range(omega.size) if not res.data[c]["done"][i]]
                for rec in parallel(joblib.delayed(solve_point)(j) for j in todo):
                    done(rec)
            else:
                # Chains advance one point per round, all chains in parallel.
                order = {c: (range(omega.size) if curves[c].direction == "up" else range(omega.size - 1, -1, -1)) for c in range(len(curves))}
                pos = {c: 0 for c in order}
                while True:
                    batch = []
                    for c, seq in order.items():
                        seq = list(seq)
                        while pos[c] < len(seq) and res.data[c]["done"][seq[pos[c]]]:
                            pos[c] += 1
                        if pos[c] < len(seq):
                            i = seq[pos[c]]
                            prev = res.states.get((c, seq[pos[c] - 1])) if pos[c] > 0 else None
                            batch.append(job(c, i, prev))
                    if not batch:
                        break
                    for rec in parallel(joblib.delayed(solve_point)(j) for j in batch):
                        done(rec)
        completed = res.complete
    finally:
        save(force=True)
        journal.close(remove=completed)
        if client is not None:
            client.close()
    return res


def _warm_up(case_text, analysis, integrator, idx) -> None:
    """Compile (or load from numba's cache) the kernels once before forking workers."""
    case, static = _static_for(case_text, analysis)
    w = float(static.modes.omega[0])
    job = PointJob(case_text, analysis, integrator, 1.0, w, tuple(int(x) for x in idx), 0, 0, None)
    from ..dynamics.history import build_equations
    from ..dynamics.steady import SteadyCriterion, steady_response
    from .dynamic import make_integrator

    eom = build_equations(case, static, omega=w)
    integ = make_integrator(case.integrator, eom, w, integrator)
    steady_response(eom, integ, np.array(job.channels), SteadyCriterion(cap=4 * 2 * np.pi / w, window=2 * 2 * np.pi / w))
