"""Sweep files (``cablesim sweep``): writer, reader, summary rows."""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from ..analyses.sweep_points import COLUMNS, CurveTable
from ..channels import normalise_channel
from ..errors import CablesimError
from ..names import DIRECTIONS
from .hdf5 import DIRECTION_GROUPS, atomic_h5, attr_text, attribute_units, put, stamp


#: Each column of a sweep curve in the file: unit and description.
COLUMN_UNITS = {
    "amplitude": ("m", "peak |z| from the static equilibrium"),
    "halfrange": ("m", "half the peak-to-peak range"),
    "response_frequency": ("rad/s", "dominant response frequency"),
    "period": ("forcing periods", "response period p (0: no periodic response found)"),
    "steady": ("1", "whether a stable periodic response was found before the cap"),
    "failed": ("1", "whether the run stopped early (slack segment, blow-up); its values are partial"),
    "t_end": ("s", "simulated time used"),
    "floquet": ("1", "largest Floquet multiplier modulus of the last periodic orbit checked"),
    "done": ("1", "whether the point has been computed"),
    "wall": ("s", "wall-clock time of the point"),
    "multipliers": ("1", "Floquet multipliers of the orbit where computed by shooting (NaN elsewhere)"),
    "peak_tension": ("N", "per segment, the largest tension over the point's integration, transient included "
                     "(exact analysis with slack: continue; NaN elsewhere)"),
    "slack_fraction": ("1", "per segment, the fraction of the point's integration spent slack "
                       "(exact analysis with slack: continue; NaN elsewhere)"),
}
#: The sweep's settings stored as attributes of /sweep.
SETTINGS_ATTRS = ("cap", "window", "tol", "max_period", "floquet_check", "accelerate", "refine", "grid_points",
                  "finest_step", "disturbance", "integrator", "integrator_rtol", "integrator_atol", "integrator_dt_max")


def write_sweep(path: str | Path, res, fingerprint: str | None = None) -> Path:
    """Write a (possibly incomplete) :class:`~cablesim.analyses.sweep.SweepResult` atomically.

    Layout: ``/sweep/omega``, optional ``/sweep/gamma`` (then every result dataset has a
    leading gamma axis); for ``independent`` sweeps the columns of
    :class:`~cablesim.analyses.sweep_points.CurveTable` (``/sweep/{amplitude, halfrange,
    period, steady, response_frequency, t_end, floquet, done, peak_tension, slack_fraction,
    ...}``), for up/down sweeps the same under ``/sweep/up/`` and ``/sweep/down/``;
    ``/modal/omega``. Points not yet computed have ``done = False`` and NaN in the float
    datasets; a point that stopped early (``failed``) may have NaN response frequencies. These
    marked gaps are the only NaN cablesim writes. ``status`` holds each point's outcome in words
    (``"steady"``, ``"cap reached"``, ``"stopped at t = ...: segment 2 went slack ..."``, ``""``
    when not computed). ``fingerprint`` (of the case and settings,
    :func:`cablesim.io.journal.fingerprint`) is stored as an attribute of ``/sweep``; so are the
    settings, and, for a refined sweep, ``grid_points`` (the grid's frequencies come first in
    no particular place: ``omega`` is ascending) and ``points_refined``.
    """
    with atomic_h5(path) as f:
        stamp(f, res.case_text, "sweep", analysis=res.analysis)
        g = f.create_group("sweep")
        put(g, "omega", res.omega, "rad/s", "forcing frequencies")
        if res.gamma is not None:
            put(g, "gamma", res.gamma, "1", "scale of the harmonic loads FL")
        g.attrs["direction"] = res.direction
        g.attrs["channels"] = np.array(res.channels, dtype="S")
        g.attrs["case_name"] = res.case_name
        g.attrs["components"] = int(res.dim)  # per node: 2 planar, 3 spatial
        for k in SETTINGS_ATTRS:
            if k in res.settings and not (k == "finest_step" and not np.isfinite(res.settings[k])):
                g.attrs[k] = res.settings[k]
        g.attrs["points_refined"] = res.n_refined
        g.attrs["complete"] = res.complete
        if fingerprint is not None:
            g.attrs["fingerprint"] = fingerprint
        g.attrs["points_failed"] = res.n_failed
        g.attrs["points_done"] = res.n_done
        g.attrs["points_total"] = res.n_total
        attribute_units(g)
        dirs = sorted({c.direction for c in res.curves}, key=DIRECTIONS.index)
        for d in dirs:
            target = g if d == "independent" else g.create_group(d)
            tables = [res.table(k) for k, c in enumerate(res.curves) if c.direction == d]

            def column(name):
                arrs = [getattr(t, name) for t in tables]
                return np.stack(arrs) if res.gamma is not None else arrs[0]

            for name, (u, desc) in COLUMN_UNITS.items():
                put(target, name, column(name), u, desc, allow_nan=True)
            put(target, "decided", np.asarray(column("decided"), dtype="S"), "1",
                "how each point was decided: integrated, shooting, cap, failed (empty: not computed)")
            ds = target.create_dataset("status", data=np.asarray(column("status"), dtype=object),
                                       dtype=h5py.string_dtype())
            ds.attrs["units"] = "text"
            ds.attrs["description"] = "outcome of each point in words ('' if not computed)"
        m = f.create_group("modal")
        put(m, "omega", res.modal_omega, "rad/s", "linear modal frequencies about the equilibrium")
    return Path(path)


@dataclass
class StoredCurve:
    """One sweep curve: one gamma value (or none) and one direction; its columns over P points
    (a :class:`~cablesim.analyses.sweep_points.CurveTable`, ascending omega)."""

    gamma: float | None
    direction: str  # "independent", "up" or "down"
    data: CurveTable

    @property
    def valid(self) -> np.ndarray:
        """Points computed to their end (done, not stopped early, with a finite amplitude): the
        ones a response curve or a peak may be drawn from."""
        return self.data.valid

    @property
    def failed(self) -> np.ndarray:
        """Points that stopped early (a segment went slack, the state blew up): their values are
        partial and never part of a curve."""
        return self.data.done & self.data.failed

    @property
    def label(self) -> str:
        """``"gamma = 0.5, up"``: which curve this is."""
        g = "" if self.gamma is None else f"gamma = {self.gamma:g}, "
        return f"{g}{self.direction}"


@dataclass
class StoredSweep:
    path: Path
    omega: np.ndarray
    channels: list[str]
    direction: str
    analysis: str
    attrs: dict
    gamma: np.ndarray | None
    curves: list[StoredCurve] = field(default_factory=list)
    modal: np.ndarray = field(default_factory=lambda: np.empty(0))


def _str_list(value) -> list[str]:
    if isinstance(value, (str, bytes)):
        return [attr_text(value)]
    return [attr_text(v) for v in np.asarray(value, dtype=object).ravel()]


#: Columns with a second axis (channels, segments or multipliers), and their kind.
_WIDE = {"amplitude": "C", "halfrange": "C", "response_frequency": "C", "peak_tension": "any",
         "slack_fraction": "any", "multipliers": "any"}


def _read_group(where, name: str, P: int, G: int | None, order, bad):
    """The result datasets of one direction group, points in ascending omega; channel count."""
    if "amplitude" not in where:
        raise bad(f"{name}/amplitude is missing")
    raw = {}
    amp = np.asarray(where["amplitude"][()])
    C = amp.shape[-1] if amp.ndim >= 2 else 0
    for key in COLUMNS:
        if key not in where or not isinstance(where[key], h5py.Dataset):
            continue
        arr = np.asarray(where[key][()])
        kind = _WIDE.get(key)
        if kind == "C":
            tail = (P, C)
        elif kind == "any":  # per segment or per multiplier: its own second axis
            tail = (P, arr.shape[-1]) if arr.ndim >= 2 else (P,)
        else:
            tail = (P,)
        if G is not None and arr.ndim == len(tail):  # gamma axis left out for G = 1
            if G != 1:
                raise bad(f"{name}/{key} has no gamma axis but /sweep/gamma has {G} values")
            arr = arr[None]
        want = ((G,) if G is not None else ()) + tail
        if arr.shape != want:
            raise bad(f"{name}/{key} has shape {arr.shape}, expected {want}")
        raw[key] = np.take(arr, order, axis=0 if G is None else 1)
    return raw, C


def _curve_table(data: dict, P: int, C: int) -> CurveTable:
    """One curve's columns with their types, and defaults for datasets older files lack."""
    t = CurveTable.empty(P, C, 0)
    t.peak_tension = t.slack_fraction = np.full((P, 0), np.nan)  # unless stored
    amp = data["amplitude"].astype(float).reshape(P, C)
    t.amplitude = amp
    for key in ("halfrange", "response_frequency"):
        setattr(t, key, data[key].astype(float) if key in data else np.full_like(amp, np.nan))
    t.period = data["period"].astype(int) if "period" in data else np.ones(P, dtype=int)
    t.steady = data["steady"].astype(bool) if "steady" in data else np.ones(P, dtype=bool)
    t.failed = data["failed"].astype(bool) if "failed" in data else np.zeros(P, dtype=bool)
    for key in ("t_end", "floquet", "wall"):
        if key in data:
            setattr(t, key, data[key].astype(float))
    for key in ("peak_tension", "slack_fraction", "multipliers"):
        if key in data and data[key].ndim == 2:
            setattr(t, key, data[key])
    for key in ("decided", "status"):
        if key in data:
            setattr(t, key, np.array([attr_text(x) for x in data[key]], dtype=object))
    finite = np.all(np.isfinite(amp), axis=1)
    t.done = (data["done"].astype(bool) & finite) if "done" in data else finite
    return t


def read_sweep(h5_path) -> StoredSweep:
    """Read a sweep file (see :func:`write_sweep` for the layout), points in ascending omega."""

    path = Path(h5_path)
    if not path.is_file():
        raise CablesimError(f"The sweep file {path} does not exist.")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise CablesimError(f"{path} is not an HDF5 file (or cannot be read): {exc}.") from exc
    with f:
        if "sweep" not in f or not isinstance(f["sweep"], h5py.Group):
            command = attr_text(f.attrs.get("command", "unknown"))
            raise CablesimError(
                f"{path} is not a sweep file: it has no /sweep group (it was written by the "
                f"'{command}' command). Plot the output of 'cablesim sweep'."
            )
        g = f["sweep"]

        def bad(what: str):
            return CablesimError(f"The sweep file {path} is malformed: {what}.")

        if "omega" not in g:
            raise bad("/sweep/omega is missing")
        omega = np.asarray(g["omega"][()], dtype=float).ravel()
        P = omega.size
        if P == 0:
            raise bad("/sweep/omega is empty")
        order = np.argsort(omega, kind="stable")
        omega = omega[order]

        direction = attr_text(g.attrs.get("direction", "independent"))
        if direction not in DIRECTION_GROUPS:
            raise bad(f"unknown sweep direction {direction!r} (expected one of {', '.join(DIRECTION_GROUPS)})")
        gamma = np.atleast_1d(np.asarray(g["gamma"][()], dtype=float)) if "gamma" in g else None
        G = None if gamma is None else gamma.size

        curves: list[StoredCurve] = []
        n_chan = None
        for sub in DIRECTION_GROUPS[direction]:
            where = g if sub is None else g.get(sub)
            name = "/sweep" if sub is None else f"/sweep/{sub}"
            if where is None:
                raise bad(f"direction {direction!r} but the group {name} is missing")
            raw, C = _read_group(where, name, P, G, order, bad)
            if n_chan is not None and C != n_chan:
                raise bad(f"{name} holds {C} channels, another group {n_chan}")
            n_chan = C
            for gi in range(1 if G is None else G):
                data = _curve_table({k: (v if G is None else v[gi]) for k, v in raw.items()}, P, C)
                curves.append(StoredCurve(None if G is None else float(gamma[gi]), sub or "independent", data))
        channels = _str_list(g.attrs["channels"]) if "channels" in g.attrs else [f"z{k + 1}" for k in range(n_chan)]
        if len(channels) != n_chan:
            raise bad(f"the attribute channels names {len(channels)} channels but the results hold {n_chan}")
        components = int(g.attrs.get("components", 2))
        channels = [normalise_channel(c, components) or c for c in channels]
        analysis = attr_text(f.attrs.get("analysis", g.attrs.get("analysis", "unknown")))
        attrs = {k: g.attrs[k] for k in ("case_name", "integrator", "integrator_rtol", "integrator_atol", "cap", "window",
                                         "refine", "grid_points", "finest_step", "points_refined") if k in g.attrs}
        attrs["components"] = components
        modal = np.empty(0)
        if "modal" in f and "omega" in f["modal"]:
            modal = np.sort(np.asarray(f["modal"]["omega"][()], dtype=float).ravel())
    return StoredSweep(path, omega, channels, direction, analysis, attrs, gamma, curves, modal)




def select_channels(sweep: StoredSweep, channels) -> list[int]:
    """Indices into the file's channel axis of the chosen channels."""
    have = ", ".join(sweep.channels)
    if channels is None:
        return list(range(len(sweep.channels)))
    if isinstance(channels, (str, bytes, numbers.Integral)):
        channels = [channels]
    out: list[int] = []
    for c in channels:
        name = normalise_channel(c)
        if name is None:
            raise CablesimError(f"Channel name {c!r} is malformed; the sweep file {sweep.path} holds {have}.")
        if name not in sweep.channels:
            raise CablesimError(
                f"Channel {c!r} was not recorded in the sweep file {sweep.path}; it holds {have}. "
                "Choose one of those, or rerun the sweep with the channel."
            )
        i = sweep.channels.index(name)
        if i not in out:
            out.append(i)
    if not out:
        raise CablesimError(f"No channels were chosen to plot; name at least one of {have}.")
    return out




def sweep_summary_rows(h5_path, quantity: str = "amplitude") -> list[dict]:
    """The largest response of every curve and channel of a sweep file.

    Parameters
    ----------
    h5_path : str or Path
        The HDF5 file written by ``cablesim sweep``.
    quantity : {"amplitude", "halfrange"}, optional
        The quantity whose maximum is sought.

    Returns
    -------
    list of dict
        One row per curve (gamma value, direction) and channel, in file order, with keys
        ``gamma`` (float or None), ``direction`` (``"independent"``, ``"up"`` or ``"down"``),
        ``channel`` (``"z2"``), ``omega`` (forcing frequency of the largest value, rad/s),
        ``value`` (that largest value, m), ``period`` and ``steady`` (at that point),
        ``points_done`` and ``points``. ``omega`` and ``value`` are NaN (``period`` 0,
        ``steady`` False) if no point of the curve was computed.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5 or not a sweep file, or the quantity is unknown.
    """
    if quantity not in ("amplitude", "halfrange"):
        raise CablesimError(f"Unknown quantity {quantity!r}; choose amplitude or halfrange.")
    sweep = read_sweep(h5_path)
    rows = []
    for curve in sweep.curves:
        valid = curve.valid
        y_all = curve.data[quantity]
        for c, name in enumerate(sweep.channels):
            ok = valid & np.isfinite(y_all[:, c])
            row = dict(gamma=curve.gamma, direction=curve.direction, channel=name,
                       omega=float("nan"), value=float("nan"), period=0, steady=False,
                       points_done=int(valid.sum()), points=int(sweep.omega.size))
            if ok.any():
                k = np.flatnonzero(ok)[np.argmax(y_all[ok, c])]
                row.update(omega=float(sweep.omega[k]), value=float(y_all[k, c]),
                           period=int(curve.data["period"][k]), steady=bool(curve.data["steady"][k]))
            rows.append(row)
    return rows


