"""What a branch tracing needs to go on after it was killed: its records as they come, and their
replay.

:func:`~cablesim.orbits.branches.trace_branches` numbers its continuation *runs* in the order it
starts them (the first branch, then every attempt at a branch switch, failed attempts included)
and reports, through a :class:`TraceLog`, plain JSON-ready records:

- ``run``: run ``r`` began a branch (its index, period, shooting segments, whether planar);
- ``orbit``: an orbit delivered to the branch of run ``r``, at position ``at`` on it (every
  field of the :class:`~cablesim.orbits.diagram.OrbitPoint`, floats written exactly);
- ``step``: a checkpoint of the march after an accepted step: the last point's unknowns ``u``,
  parameter, scaled tangent, test function values and arclength, the next step length ``ds``,
  the count of points, the orbits delivered until then, and the state of the watch of a
  switched branch (:mod:`cablesim.orbits.switching`);
- ``end``: the run finished (why, the flow failure, the evaluations, where it merged).

The tracing is deterministic: traced again with the records (:class:`TraceReplay`), the runs
come in the same order; a finished run is restored without computing, the unfinished one goes
on from its last checkpoint (:class:`~cablesim.orbits.continuation.Resume`: the steps the
uninterrupted run took, bit for bit on the dense path), and the branch switches not yet made
(the period doublings and pitchforks of the restored branches, recorded as their special
points) follow in turn. Only the few evaluations that choose each switch's start are computed
again. Orbits delivered after the last checkpoint of an unfinished run are computed again (the
same orbits).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .continuation import Point, Resume
from .diagram import BranchEnd, OrbitBranch, OrbitPoint
from .shooting import FlowStatus
from .symmetry import Whirling


def _floats(a) -> list:
    return np.asarray(a, dtype=float).ravel().tolist()


def _complex(a) -> list:
    a = np.asarray(a, dtype=complex).ravel()
    return [a.real.tolist(), a.imag.tolist()]


def orbit_record(op: OrbitPoint) -> dict:
    """An orbit as plain data (:func:`orbit_from_record` reads it back exactly)."""
    w = op.whirl
    return {
        "parameter": float(op.parameter), "omega": float(op.omega), "period": int(op.period),
        "state": _floats(op.state), "u": _floats(op.u), "amplitude": _floats(op.amplitude),
        "halfrange": _floats(op.halfrange), "multipliers": _complex(op.multipliers), "stable": bool(op.stable),
        "trusted": bool(op.trusted), "residual": float(op.residual), "liouville": float(op.liouville),
        "special": op.special, "located": bool(op.located),
        "planes": None if op.planes is None else [str(x) for x in op.planes],
        "whirl": None if w is None else {"area": _floats(w.area), "tilt": float(w.tilt),
                                         "max_w": None if w.max_w is None else _floats(w.max_w)},
    }


def _array(rec: dict, key: str, size: int | None = None, finite: bool = True) -> np.ndarray:
    a = np.asarray(rec[key], dtype=float)
    if a.ndim != 1 or (size is not None and a.size != size) or (finite and not np.all(np.isfinite(a))):
        raise ValueError(f"its {key} is not {'a finite' if finite else 'a'} vector"
                         + (f" of {size} values" if size is not None else ""))
    return a


def orbit_from_record(rec: dict, n: int, branch: int, index: int) -> OrbitPoint:
    """The :class:`OrbitPoint` of an ``orbit`` record (``n``: the state's dimension).

    Raises
    ------
    ValueError
        The record is not an orbit of this system (sizes, non-finite state or parameter).
    """
    try:
        state, u = _array(rec, "state", n), _array(rec, "u")
        if u.size % n or not np.isfinite(float(rec["parameter"])):
            raise ValueError("its unknowns do not fit the state or its parameter is not finite")
        re, im = (np.asarray(x, dtype=float) for x in rec["multipliers"])
        w = rec["whirl"]
        whirl = None if w is None else Whirling(area=_array(w, "area", finite=False), tilt=float(w["tilt"]),
                                                max_w=None if w["max_w"] is None else _array(w, "max_w", finite=False))
        planes = rec["planes"]
        return OrbitPoint(
            branch=branch, index=index, parameter=float(rec["parameter"]), omega=float(rec["omega"]),
            period=int(rec["period"]), state=state, u=u, amplitude=_array(rec, "amplitude"),
            halfrange=_array(rec, "halfrange"), multipliers=re + 1j * im, stable=bool(rec["stable"]),
            trusted=bool(rec["trusted"]), residual=float(rec["residual"]), liouville=float(rec["liouville"]),
            special=None if rec["special"] is None else str(rec["special"]), located=bool(rec["located"]),
            planes=None if planes is None else tuple(str(x) for x in planes), whirl=whirl)
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"an orbit record cannot be read ({exc})") from None


class PastRun:
    """The records of one run: its orbits by position, its last checkpoint and its end."""

    def __init__(self):
        self.start: dict | None = None
        self.orbits: dict = {}
        self.step: dict | None = None
        self.end: dict | None = None

    def restore(self, br: OrbitBranch, n: int) -> None:
        """Append to ``br`` the orbits delivered until the end or the last checkpoint."""
        upto = int((self.end or self.step)["points"])
        for at in range(len(br.points), upto):
            if at not in self.orbits:
                raise ValueError(f"the orbit at position {at} of branch {br.index} is missing")
            br.points.append(orbit_from_record(self.orbits[at], n, br.index, at))

    def resume(self) -> Resume:
        """Where the march of the unfinished run goes on."""
        s = self.step
        return Resume(u=np.asarray(s["u"], dtype=float), lam=float(s["lam"]), tangent=np.asarray(s["tangent"], float),
                      tests=np.asarray(s["tests"], dtype=float), arclength=float(s["arclength"]), ds=float(s["ds"]),
                      count=int(s["count"]))

    def finish(self, br: OrbitBranch, parent: OrbitBranch | None) -> None:
        """Give ``br`` the end of the finished run (where it merged: a point of ``parent``)."""
        e = self.end
        br.end = BranchEnd(int(e["end"]))
        br.failure = None if e["failure"] is None else FlowStatus(int(e["failure"]))
        br.evaluations = int(e["evaluations"])
        br.merged_at = None if e["merged_at"] is None else parent.points[int(e["merged_at"])]


class TraceReplay:
    """The records of an interrupted tracing, by run (module docstring).

    Raises
    ------
    ValueError
        A record that does not fit (unknown kind, a run missing its start).
    """

    def __init__(self, records=()):
        self.runs: dict[int, PastRun] = {}
        for rec in records:
            try:
                kind, r = rec["record"], int(rec["run"])
            except (KeyError, TypeError, ValueError):
                raise ValueError("a record names no run") from None
            run = self.runs.setdefault(r, PastRun())
            if kind == "run":
                run.start = rec
            elif kind == "orbit":
                run.orbits[int(rec["at"])] = rec["point"]  # a later record of a position replaces it
            elif kind == "step":
                run.step = rec
            elif kind == "end":
                run.end = rec
            else:
                raise ValueError(f"a record is of an unknown kind {kind!r}")
        if any(run.start is None for run in self.runs.values()):
            raise ValueError("a run's records come without its start")

    def check(self, n: int) -> None:
        """Read every orbit record as an orbit of a system of state dimension ``n``, and check
        that no run lacks an orbit it delivered (the first may be a switched branch's start,
        not journaled).

        Raises
        ------
        ValueError
            Naming the first record that does not fit.
        """
        for r, run in sorted(self.runs.items()):
            for at, rec in run.orbits.items():
                orbit_from_record(rec, n, 0, at)
            last = run.end or run.step
            if last is not None and not set(range(1, int(last["points"]))) <= set(run.orbits):
                raise ValueError(f"run {r} lacks some of the orbits it delivered")

    def past(self, r: int) -> PastRun | None:
        """Run ``r`` if it finished or reached a checkpoint (else it is computed afresh)."""
        run = self.runs.get(r)
        return run if run is not None and (run.end is not None or run.step is not None) else None


class TraceLog:
    """Where a tracing sends its records (``sink(record, partial)``, ``partial()`` giving the
    diagram so far; None: nowhere) and the records it replays (module docstring)."""

    def __init__(self, sink: Callable | None = None, records=(), partial: Callable | None = None):
        self.sink = sink
        self.replay = TraceReplay(records)
        self.partial = partial
        self.count = 0

    def emit(self, record: dict) -> None:
        if self.sink is not None:
            self.sink(record, self.partial)

    def start(self, br: OrbitBranch) -> tuple[int, PastRun | None]:
        """Number the run that traces ``br`` and record its start; its past records, if any."""
        r, self.count = self.count, self.count + 1
        past = self.replay.past(r)
        if past is None:
            self.emit({"record": "run", "run": r, "branch": br.index, "period": br.period, "segments": br.segments,
                       "planar": bool(br.planar)})
        return r, past

    def orbit(self, r: int, op: OrbitPoint) -> None:
        if self.sink is not None:
            self.emit({"record": "orbit", "run": r, "at": int(op.index), "point": orbit_record(op)})

    def step(self, r: int, p: Point, ds: float, count: int, points: int, far: bool | None) -> None:
        if self.sink is not None:
            self.emit({"record": "step", "run": r, "u": _floats(p.u), "lam": float(p.lam),
                       "tangent": _floats(p.tangent), "tests": _floats(p.tests), "arclength": float(p.arclength),
                       "ds": float(ds), "count": int(count), "points": int(points), "far": far})

    def end(self, r: int, br: OrbitBranch) -> None:
        merged = None if br.merged_at is None else int(br.merged_at.index)
        self.emit({"record": "end", "run": r, "end": int(br.end), "evaluations": int(br.evaluations),
                   "failure": None if br.failure is None else int(br.failure), "merged_at": merged,
                   "points": len(br.points)})

    def planar(self, r: int) -> bool | None:
        """Whether the replayed run ``r`` was planar (None: not replayed)."""
        past = self.replay.past(r)
        return None if past is None else bool(past.start.get("planar", False))
