"""One finished sweep point as a typed record, and the columns of a sweep curve.

A point travels from the worker that computed it to the journal, the result, the HDF5 file and
the plots as one :class:`SweepPoint` (frozen); its JSON form (:meth:`SweepPoint.to_json`,
:meth:`SweepPoint.from_json`) is the journal's line. A curve's points, ordered by forcing
frequency, become the arrays of a :class:`CurveTable`: the HDF5 writer writes those columns,
the reader reads them back into the same class, and the plots draw from it.

Sizes come from the cable: ``C`` channels, ``n_dof = dim n`` degrees of freedom (``dim`` = 2
planar, 3 spatial) (the state
``(z, y', y'')`` of a chain's end has ``3 n_dof`` values, the multipliers of the shooting
state ``(z, y')`` at most ``2 n_dof``) and ``n + 1`` segments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ..dynamics.status import Status

_NUMBER = (int, float)


class BadRecord(ValueError):
    """A journal record that cannot be a point of this sweep; the message says why."""


def _finite_or_none(x: float):
    return float(x) if math.isfinite(x) else None


def _floats(values) -> tuple[float, ...]:
    """A tuple of floats, NaN for a missing value (None)."""
    return tuple(math.nan if v is None else float(v) for v in values)


@dataclass(frozen=True)
class SweepPoint:
    """The steady (or last-window) response of one point of one sweep curve.

    Attributes
    ----------
    curve : int
        Index of the curve (:class:`~cablesim.analyses.sweep.Curve`) in the sweep.
    omega : float
        Forcing frequency, rad/s.
    amplitude, halfrange : tuple of float
        Per channel: peak ``|z|`` from the equilibrium and half the peak-to-peak range, m.
    response_frequency : tuple of float
        Per channel: the dominant response frequency, rad/s (NaN when none was found).
    period : int
        Response period in forcing periods (0: no periodic response found).
    steady : bool
        Whether a stable periodic response was found before the cap.
    t_end : float
        Simulated time used, s.
    floquet : float
        Largest Floquet multiplier modulus of the last orbit checked (NaN if none).
    decided : str
        ``"integrated"``, ``"shooting"``, ``"cap"`` or ``"failed"``.
    multipliers : tuple of complex
        Floquet multipliers where computed by shooting (empty elsewhere).
    status : str
        The outcome in words (``"steady"``, ``"cap reached"``, when and why it stopped).
    code : int
        The :class:`~cablesim.dynamics.status.Status` of the integration.
    final_state : tuple of float or None
        ``(z, y', y'')`` at the end, at forcing phase 0 (the start of the next point of a
        chain); None when not finite.
    peak_tension, slack_fraction : tuple of float or None
        Per segment: largest tension (N) and fraction of the time slack (exact analysis with
        ``slack: continue``; None elsewhere).
    wall : float
        Wall-clock time of the point, s.
    integrator : str
        The scheme that integrated it.
    """

    curve: int
    omega: float
    amplitude: tuple[float, ...]
    halfrange: tuple[float, ...]
    response_frequency: tuple[float, ...]
    period: int
    steady: bool
    t_end: float
    floquet: float
    decided: str
    multipliers: tuple[complex, ...]
    status: str
    code: int
    final_state: tuple[float, ...] | None
    peak_tension: tuple[float, ...] | None
    slack_fraction: tuple[float, ...] | None
    wall: float
    integrator: str

    @property
    def failed(self) -> bool:
        """Whether the integration stopped early (a slack segment, a blow-up): partial values."""
        return not Status(self.code).success

    @classmethod
    def from_response(cls, curve: int, omega: float, r, wall: float, integrator: str) -> "SweepPoint":
        """The record of a :class:`~cablesim.dynamics.steady.PointResult`."""
        final = np.asarray(r.final_state, dtype=float)
        return cls(
            curve=int(curve), omega=float(omega),
            amplitude=_floats(r.amplitude), halfrange=_floats(r.halfrange),
            response_frequency=_floats(r.response_frequency),
            period=int(r.period), steady=bool(r.steady), t_end=float(r.t_end), floquet=float(r.floquet),
            decided=str(r.decided),
            multipliers=() if r.multipliers is None else tuple(complex(m) for m in r.multipliers),
            status=str(r.message), code=int(r.status),
            final_state=tuple(final.tolist()) if np.all(np.isfinite(final)) else None,
            peak_tension=None if r.peak_tension is None else _floats(r.peak_tension),
            slack_fraction=None if r.slack_fraction is None else _floats(r.slack_fraction),
            wall=float(wall), integrator=str(integrator),
        )

    def to_json(self) -> dict:
        """The journal's form: plain JSON values, ``null`` for what is not finite."""
        def listed(values):
            return None if values is None else [_finite_or_none(v) for v in values]

        return {
            "curve": self.curve, "omega": self.omega,
            "amplitude": listed(self.amplitude), "halfrange": listed(self.halfrange),
            "response_frequency": listed(self.response_frequency),
            "period": self.period, "steady": self.steady, "t_end": self.t_end,
            "floquet": _finite_or_none(self.floquet), "decided": self.decided,
            "multipliers": [[m.real, m.imag] for m in self.multipliers] or None,
            "status": self.status, "code": self.code,
            "final_state": None if self.final_state is None else list(self.final_state),
            "peak_tension": listed(self.peak_tension), "slack_fraction": listed(self.slack_fraction),
            "wall": self.wall, "integrator": self.integrator,
        }

    @classmethod
    def from_json(cls, rec, n_channels: int, n_dof: int, n_segments: int | None = None) -> "SweepPoint":
        """A point from its journal form, checked against the sweep's sizes.

        Raises
        ------
        BadRecord
            Saying what is wrong (a missing field, a wrong type or size).
        """
        _check_json(rec, n_channels, n_dof)
        mu = rec.get("multipliers") or ()
        seg = n_segments if n_segments is not None else n_dof // 2 + 1

        def per_segment(key):
            v = rec.get(key)
            return None if v is None else _floats(v)

        return cls(
            curve=rec["curve"], omega=float(rec["omega"]),
            amplitude=_floats(rec["amplitude"]), halfrange=_floats(rec["halfrange"]),
            response_frequency=_floats(rec["response_frequency"]),
            period=rec["period"], steady=rec["steady"], t_end=float(rec["t_end"]),
            floquet=math.nan if rec["floquet"] is None else float(rec["floquet"]),
            decided=str(rec.get("decided", "")), multipliers=tuple(complex(a, b) for a, b in mu),
            status=str(rec.get("status", "")), code=rec["code"],
            final_state=None if rec.get("final_state") is None else tuple(float(x) for x in rec["final_state"]),
            peak_tension=per_segment("peak_tension") if _sized(rec.get("peak_tension"), seg) else None,
            slack_fraction=per_segment("slack_fraction") if _sized(rec.get("slack_fraction"), seg) else None,
            wall=float(rec.get("wall", math.nan)), integrator=str(rec.get("integrator", "")),
        )


def _sized(values, n: int) -> bool:
    return isinstance(values, list) and len(values) == n


def _numbers(x, n: int, none_ok: bool = True) -> bool:
    return isinstance(x, list) and len(x) == n and all(
        (v is None and none_ok) or (isinstance(v, _NUMBER) and not isinstance(v, bool)) for v in x)


PER_CHANNEL = ("amplitude", "halfrange", "response_frequency")
#: Largest value of each per-channel field a sweep computes (m, m, rad/s): a cable spans at most
#: 1e5 m and frequencies are at most 1e4 rad/s, so anything beyond is a damaged record.
RECORD_BOUND = {"amplitude": 1e6, "halfrange": 1e6, "response_frequency": 1e6}
REQUIRED = ("curve", "omega", *PER_CHANNEL, "period", "steady", "t_end", "code", "floquet")


def _check_json(rec, n_channels: int, n_dof: int) -> None:
    if not isinstance(rec, dict):
        raise BadRecord("it is not a record")
    missing = [k for k in REQUIRED if k not in rec]
    if missing:
        raise BadRecord(f"it lacks {', '.join(missing)}")
    if not all(isinstance(rec[k], int) and not isinstance(rec[k], bool) for k in ("curve", "period", "code")):
        raise BadRecord("curve, period and code must be whole numbers")
    if not isinstance(rec["omega"], _NUMBER) or isinstance(rec["omega"], bool) or not math.isfinite(rec["omega"]):
        raise BadRecord(f"its frequency {rec['omega']!r} is not a number")
    if not all(_numbers(rec[k], n_channels) for k in PER_CHANNEL):
        raise BadRecord(f"its per-channel values are not {n_channels} numbers each")
    for k in PER_CHANNEL:  # the writer stores null for what is not finite: anything else is damage
        bad = [v for v in rec[k] if v is not None and not (math.isfinite(v) and 0.0 <= v <= RECORD_BOUND[k])]
        if bad:
            raise BadRecord(f"its {k} {bad[0]!r} is not a value a sweep computes (from 0 to {RECORD_BOUND[k]:g})")
    if rec["code"] not in {int(s) for s in Status}:
        raise BadRecord(f"its status code {rec['code']} is unknown")
    if not isinstance(rec["steady"], bool) or not _numbers([rec["t_end"], rec.get("wall", 0.0)], 2, none_ok=False):
        raise BadRecord("steady must be true or false, t_end and wall numbers")
    if not (math.isfinite(rec["t_end"]) and rec["t_end"] >= 0.0):
        raise BadRecord(f"its end time {rec['t_end']!r} is not a time a sweep reaches")
    if not _numbers([rec["floquet"]], 1):
        raise BadRecord("floquet must be a number or null")
    final, n = rec.get("final_state"), 3 * n_dof
    if final is not None and not _numbers(final, n, none_ok=False):
        raise BadRecord(f"its final state is not a list of {n} numbers")
    mu = rec.get("multipliers")
    if mu and not (isinstance(mu, list) and len(mu) <= 2 * n_dof and all(_numbers(m, 2, none_ok=False) for m in mu)):
        raise BadRecord(f"its multipliers are not at most {2 * n_dof} pairs of numbers")


# ----------------------------------------------------------------------------------------------
# A curve's columns
# ----------------------------------------------------------------------------------------------
@dataclass
class CurveTable:
    """A sweep curve as columns over its ``P`` frequencies (ascending): what the HDF5 file
    stores and the plots draw. Points not computed have ``done`` False, NaN in the float
    columns, period 0 and empty texts. Item access (``table["amplitude"]``) names a column.

    Shapes: ``(P, C)`` for :data:`PER_CHANNEL` columns, ``(P, n + 1)`` for the per-segment
    ``peak_tension`` and ``slack_fraction``, ``(P, 2 n_dof)`` for ``multipliers``, ``(P,)`` for
    the rest.
    """

    amplitude: np.ndarray
    halfrange: np.ndarray
    response_frequency: np.ndarray
    period: np.ndarray
    steady: np.ndarray
    failed: np.ndarray
    t_end: np.ndarray
    floquet: np.ndarray
    wall: np.ndarray
    decided: np.ndarray
    multipliers: np.ndarray
    peak_tension: np.ndarray
    slack_fraction: np.ndarray
    done: np.ndarray
    status: np.ndarray

    @classmethod
    def empty(cls, P: int, n_channels: int, n_dof: int, n_segments: int | None = None) -> "CurveTable":
        """Nothing computed yet."""
        C, seg = n_channels, (n_segments if n_segments is not None else n_dof // 2 + 1)
        return cls(
            amplitude=np.full((P, C), np.nan), halfrange=np.full((P, C), np.nan),
            response_frequency=np.full((P, C), np.nan), period=np.zeros(P, dtype=np.int64),
            steady=np.zeros(P, dtype=bool), failed=np.zeros(P, dtype=bool), t_end=np.full(P, np.nan),
            floquet=np.full(P, np.nan), wall=np.full(P, np.nan), decided=np.full(P, "", dtype=object),
            multipliers=np.full((P, 2 * n_dof), np.nan + 0j), peak_tension=np.full((P, seg), np.nan),
            slack_fraction=np.full((P, seg), np.nan), done=np.zeros(P, dtype=bool),
            status=np.full(P, "", dtype=object),
        )

    @classmethod
    def from_points(cls, omega: np.ndarray, points: dict, n_channels: int, n_dof: int,
                    n_segments: int | None = None) -> "CurveTable":
        """The columns of one curve's ``points`` (``{omega: SweepPoint}``) over ``omega``."""
        table = cls.empty(omega.size, n_channels, n_dof, n_segments)
        for i, w in enumerate(omega):
            p = points.get(float(w))
            if p is not None:
                table.enter(i, p)
        return table

    def enter(self, i: int, p: SweepPoint) -> None:
        """Put point ``p`` in row ``i``."""
        self.amplitude[i] = p.amplitude
        self.halfrange[i] = p.halfrange
        self.response_frequency[i] = p.response_frequency
        self.period[i] = p.period
        self.steady[i] = p.steady
        self.failed[i] = p.failed
        self.t_end[i] = p.t_end
        self.floquet[i] = p.floquet
        self.wall[i] = p.wall
        self.decided[i] = p.decided
        if p.multipliers:
            self.multipliers[i, : len(p.multipliers)] = p.multipliers
        if p.peak_tension is not None:
            self.peak_tension[i] = p.peak_tension
        if p.slack_fraction is not None:
            self.slack_fraction[i] = p.slack_fraction
        self.status[i] = p.status
        self.done[i] = True

    @property
    def went_slack(self) -> np.ndarray:
        """Points on which some segment went slack (at any time of their integration)."""
        frac = self.slack_fraction
        return (np.nan_to_num(frac.astype(float)) > 0).any(axis=1) if frac.ndim == 2 and frac.shape[1] \
            else np.zeros(self.done.size, dtype=bool)

    @property
    def valid(self) -> np.ndarray:
        """Points computed to their end (done, not stopped early, with a finite amplitude): the
        ones a response curve or a peak may be drawn from."""
        return self.done & ~self.failed & np.all(np.isfinite(self.amplitude), axis=1)

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in COLUMNS and name != "went_slack":
            raise KeyError(name)
        return getattr(self, name)

    def __contains__(self, name: str) -> bool:
        return name in COLUMNS

    def get(self, name: str, default=None):
        """A column by name, or ``default``."""
        return getattr(self, name) if name in COLUMNS else default

    def items(self):
        """``(name, column)`` of every column."""
        return [(name, getattr(self, name)) for name in COLUMNS]


#: Every column of a :class:`CurveTable`, in the order of its fields.
COLUMNS = tuple(f.name for f in fields(CurveTable))
