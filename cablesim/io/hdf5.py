"""HDF5 files: every writer and every reader of cablesim's results, and their layout.

Layout (every dataset has a ``units`` attribute; every file has the root attributes
``case_yaml``, ``cablesim_version``, ``command``, ``created_utc`` and ``analysis``):

- ``cablesim static``: ``/static/P``, ``/static/{inextensible,approximate,exact}/...``,
  ``/modal/{omega, shapes, damping_ratio, inextensible_omega}`` (attributes ``analysis``, ``a0``,
  ``a1``);
- ``cablesim history`` / ``free-vibration``: ``/history/{t, z, v, zc, ze, T, residual, dof, y0,
  T0}`` (time along the first axis, DOF along the second) with attributes ``omega``,
  ``analysis``, ``integrator``, ``status`` (the outcome in words), ``status_code``, ``t_stop``
  and the integrator's settings; ``/modal/omega``; exact analysis: ``/history/events/{t, segment,
  kind}`` (slack onsets and re-tightenings) and ``/history/segments/{peak_tension, peak_time,
  slack_time, slack_episodes}``;
- ``cablesim sweep``: see :func:`cablesim.io.sweeps.write_sweep`;
- ``cablesim continue``: see :func:`cablesim.io.continuation.write_continuation`.

Files are written atomically: into ``NAME.<pid>.part`` beside the target, then renamed over
it, so a failed or interrupted run never leaves a corrupt or half-written result under the real
name (and the next run removes the temporary a killed writer left).
Every dataset carries a ``units`` attribute; non-finite numbers are refused unless a caller
says explicitly that they mark missing values.
"""

from __future__ import annotations

import datetime
import io
import json
import os
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np

from ..dynamics.result import HistoryResult, SlackRecord
from ..dynamics.status import Status
from ..errors import CablesimError
from ..version import __version__
from . import provenance
from .paths import discard, part_path, remove_stale_parts, write_error


#: Arrays of at least this many values are written gzip-compressed.
COMPRESS_SIZE = 4096
#: Static files keep the dense 2n x 2n matrices up to this many DOF unless asked (n = 200 nodes:
#: nine matrices of 400 x 400, about 11 MB).
MATRIX_DOF = 400


@contextmanager
def atomic_h5(path: str | Path, mode: str = "w"):
    """Open ``path`` for writing via a temporary file renamed into place on success.

    The HDF5 file is built in memory and written to ``NAME.part`` in one piece by the operating
    system's own calls, then renamed into place: a full disk is then a plain OSError (ENOSPC),
    where the HDF5 library, running out of room while it writes a file, only prints the failure
    on closing (or crashes) and leaves a truncated file.

    Parameters
    ----------
    path : str or Path
        Final file name; its folder is created if needed.
    mode : str
        ``"w"`` starts empty; ``"a"`` starts from a copy of the existing file.

    Yields
    ------
    h5py.File
    """
    path = Path(path)
    remove_stale_parts(path)
    tmp = part_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        image = io.BytesIO(path.read_bytes() if mode == "a" and path.exists() else b"")
        with h5py.File(image, "a" if image.getbuffer().nbytes else "w") as f:
            yield f
        with open(tmp, "wb") as out:
            out.write(image.getbuffer())
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        discard(tmp)
        raise write_error(path, exc) from None
    except RuntimeError as exc:
        discard(tmp)
        if not _raised_by_h5py(exc):
            raise
        raise write_error(path, exc) from None  # an HDF5 library failure while the file was built
    except BaseException:
        discard(tmp)
        raise


def _raised_by_h5py(exc: BaseException) -> bool:
    """Whether the innermost frame of ``exc``'s traceback is in h5py (a file system error, not a bug)."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return tb is not None and "h5py" in Path(tb.tb_frame.f_code.co_filename).parts


#: Units of the numeric group attributes (stored per group as the JSON attribute ``units``).
ATTRIBUTE_UNITS = {
    "point_load_snap": "m", "point_load_x": "m",
    "omega": "rad/s", "t_stop": "s", "duration": "s", "output_step": "s", "a0": "1/s", "a1": "s",
    "integrator_dt": "s", "integrator_dt_max": "s", "integrator_rtol": "1", "integrator_atol": "m",
    "integrator_rho_inf": "1", "omega_c": "J", "omega_e": "J", "sole_inextensible_omega": "rad/s",
    "cap": "s", "window": "s", "tol": "1", "max_period": "forcing periods", "points_done": "1",
    "points_total": "1", "points_failed": "1", "peak_velocity": "m/s", "damping_ratio": "1",
    "omega_max": "rad/s", "modes_computed": "1",
}


def stamp(f: h5py.File, case_text: str, command: str, **attrs) -> None:
    """Root attributes every cablesim file has: the case, the command, the versions, the platform,
    the git commit, the command line and every effective option (:mod:`cablesim.io.provenance`)."""
    f.attrs["case_yaml"] = case_text
    f.attrs["cablesim_version"] = __version__
    f.attrs["command"] = command
    f.attrs["created_utc"] = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    for k, v in provenance.record().items():
        f.attrs[k] = v
    for k, v in attrs.items():
        f.attrs[k] = v


def attribute_units(group: h5py.Group) -> None:
    """Store the units of the group's numeric attributes as its JSON attribute ``units``."""
    units = {k: ATTRIBUTE_UNITS[k] for k in group.attrs if k in ATTRIBUTE_UNITS}
    if units:
        group.attrs["units"] = json.dumps(units, sort_keys=True)


def put(group: h5py.Group, name: str, data, units: str, description: str = "", allow_nan: bool = False):
    """Write one dataset with its units (and an optional description).

    Raises
    ------
    ValueError
        If ``data`` holds NaN or infinity and ``allow_nan`` is False.
    """
    arr = np.asarray(data)
    if arr.dtype.kind in "fc" and not allow_nan and not np.all(np.isfinite(arr)):
        raise ValueError(f"refusing to write non-finite values to {group.name}/{name}")
    # Large arrays are chunked and compressed (lossless; h5py reads them transparently).
    packed = {"compression": "gzip", "compression_opts": 4, "shuffle": True} if arr.size >= COMPRESS_SIZE else {}
    ds = group.create_dataset(name, data=arr, **packed)
    ds.attrs["units"] = units
    if description:
        ds.attrs["description"] = description
    return ds


def write_static(path: str | Path, result, case_text: str, matrices: bool | None = None, placements=()) -> Path:
    """Write a :class:`~cablesim.analyses.static.StaticResult` to HDF5.

    Layout: ``/static/inextensible/{x,T,B,D}``, ``/static/approximate/{x,u,y,T,B,D,f,N,K}``,
    ``/static/exact/{y,T,K}``, ``/modal/{omega,shapes,damping_ratio}`` with attributes
    ``analysis``, ``a0``, ``a1``; the case YAML and the version as root attributes.

    The dense 2n x 2n matrices (B, D, f, N, K) are written when ``matrices`` is True, or when it
    is None and 2n <= MATRIX_DOF; otherwise they are left out (root attribute
    ``matrices_stored`` False) and the banded exact stiffness ``/static/exact/K_band``
    (``K_band[d, j] = K[j + d, j]``) is written instead. ``/modal/shapes`` holds the shapes the
    analysis computed (all of them for small cables, the lowest modes for large ones).
    """
    path = Path(path)
    r = result
    dense = r.P.size <= MATRIX_DOF if matrices is None else bool(matrices)
    with atomic_h5(path) as f:
        stamp(f, case_text, "static", analysis=r.analysis)
        st = f.create_group("static")
        st.attrs["matrices_stored"] = dense
        put(st, "P", r.P, "N", "sustained loads F0 in DOF order")
        if placements:
            st.attrs["point_load_given"] = [p.given for p in placements]
            st.attrs["point_load_node"] = np.array([p.node for p in placements], dtype=np.int64)
            st.attrs["point_load_x"] = np.array([p.node_x for p in placements])
            st.attrs["point_load_snap"] = np.array([p.snap for p in placements])
            attribute_units(st)
        _write_static_models(st, r, dense)
        _write_static_modal(f, r)
    return path


def _write_static_models(st: h5py.Group, r, dense: bool) -> None:
    if r.inextensible is not None:
        g = st.create_group("inextensible")
        put(g, "x", r.inextensible.x, "m", "node coordinates of the inextensible cable")
        put(g, "T", r.inextensible.T, "N", "segment tensions")
        if dense:
            put(g, "B", r.inextensible.B, "1", "tangent transformation dT/dP")
            put(g, "D", r.inextensible.D, "m/N", "configurational flexibility dx/dP")
        g.attrs["omega_c"] = r.inextensible.omega_c
        attribute_units(g)
    if r.approximate is not None:
        a = r.approximate
        g = st.create_group("approximate")
        for name, val, units, desc in [
            ("x", a.x, "m", "natural-state coordinates x(P)"),
            ("u", a.u, "m", "elastic displacements (eq. 7)"),
            ("y", a.y, "m", "deformed coordinates y = x + u"),
            ("T", a.T, "N", "segment tensions"),
            ("B", a.B, "1", "tangent transformation dT/dP"),
            ("D", a.D, "m/N", "configurational flexibility"),
            ("f", a.f, "m/N", "elastic flexibility (eq. 8)"),
            ("N", a.N, "m/N", "elasto-configurational flexibility D + f"),
            ("K", a.K, "N/m", "tangent stiffness N^-1"),
        ]:
            if dense or np.ndim(val) < 2:
                put(g, name, val, units, desc)
        g.attrs["omega_c"] = a.omega_c
        g.attrs["omega_e"] = a.omega_e
        attribute_units(g)
    if r.exact is not None:
        g = st.create_group("exact")
        put(g, "y", r.exact.y, "m", "deformed node coordinates")
        put(g, "T", r.exact.T, "N", "segment tensions EA (l - S) / S")
        put(g, "l", r.exact.length, "m", "stretched segment lengths")
        if dense:
            put(g, "K", r.exact.K, "N/m", "tangent stiffness of the deformed configuration")
        elif r.K0_band is not None:
            put(g, "K_band", r.K0_band, "N/m", "tangent stiffness, lower band form: K_band[d, j] = K[j + d, j]")


def _write_static_modal(f: h5py.File, r) -> None:
    m = f.create_group("modal")
    put(m, "omega", r.modes.omega, "rad/s", "linear modal frequencies, ascending")
    put(m, "shapes", r.modes.shapes, "1/sqrt(kg)", "mass-normalised mode shapes (columns)")
    put(m, "damping_ratio", r.damping_ratios, "1", "Rayleigh damping ratio of each mode")
    put(m, "inextensible_omega", r.inextensible_omega, "rad/s", "finite frequencies of the inextensible cable")
    if r.modes.kinds:  # a spatial cable
        m.create_dataset("kind", data=np.array(r.modes.kinds, dtype="S"))
        m["kind"].attrs["description"] = "in-plane, out-of-plane (of a planar equilibrium's plane) or coupled"
    m.attrs["analysis"] = r.analysis
    m.attrs["a0"] = r.a0
    m.attrs["a1"] = r.a1
    m.attrs["shapes_stored"] = r.modes.shapes.shape[1]
    m.attrs["modes_computed"] = r.modes.omega.size  # the lowest ones; all when it equals 2n
    m.attrs["omega_max"] = r.modes.highest
    if r.sole_inextensible_omega is not None:
        m.attrs["sole_inextensible_omega"] = r.sole_inextensible_omega
    attribute_units(m)


def write_history(path: str | Path, hist, case_text: str, command: str, extra_attrs: dict | None = None) -> Path:
    """Write a :class:`~cablesim.dynamics.result.HistoryResult` to HDF5.

    Layout: ``/history/{t,z,v,zc,ze,T,residual}`` (time along the first axis, DOF along the
    second), ``/history/y0``, ``/history/T0``, ``/modal/omega``; attributes ``omega``,
    ``analysis``, ``integrator``, ``status`` and the integrator's settings on ``/history``.
    """
    with atomic_h5(path) as f:
        stamp(f, case_text, command, analysis=hist.analysis)
        g = f.create_group("history")
        put(g, "t", hist.t, "s", "saved instants")
        put(g, "z", hist.z, "m", "displacement from the static equilibrium, z = y - y(0) (DOF order)")
        put(g, "v", hist.v, "m/s", "velocity y'")
        if hist.zc is not None:
            put(g, "zc", hist.zc, "m", "configurational part x(P(t)) - x(P(0)) (eq. 22); NaN where the "
                "inextensible state under the current internal forces does not exist (a segment of it slack)",
                allow_nan=True)
            put(g, "ze", hist.ze, "m", "elastic part of z (eq. 22); NaN with zc", allow_nan=True)
        put(g, "T", hist.T, "N", "segment tensions EA max(l - S, 0) / S (zero while slack)")
        if hist.slack is not None:
            _write_slack(g, hist.slack)
        put(g, "residual", hist.residual, "1", "drift of eq. 15 relative to |F0|")
        put(g, "dof", np.array(hist.dof_numbers), "1", "1-based DOF number of each column of z, v, zc, ze")
        put(g, "y0", hist.y0, "m", "static equilibrium the displacements are measured from")
        put(g, "T0", hist.T0, "N", "tensions at that equilibrium")
        g.attrs["omega"] = np.nan if hist.omega is None else hist.omega
        g.attrs["forced"] = hist.omega is not None
        g.attrs["analysis"] = hist.analysis
        g.attrs["integrator"] = hist.integrator
        g.attrs["status"] = hist.message
        g.attrs["status_code"] = int(hist.status)
        g.attrs["t_stop"] = np.nan if hist.t_stop is None else hist.t_stop
        g.attrs["completed"] = hist.completed
        g.attrs["warnings"] = json.dumps(list(getattr(hist, "warnings", ())))  # plausibility warnings
        for k, v in hist.settings.items():
            g.attrs[k] = v
        for k, v in (extra_attrs or {}).items():
            g.attrs[k] = v
        attribute_units(g)
        m = f.create_group("modal")
        put(m, "omega", hist.modal_omega, "rad/s", "linear modal frequencies about the equilibrium")
    return Path(path)


def _write_slack(g: h5py.Group, rec: SlackRecord) -> None:
    """``/history/events/{t, segment, kind}`` and ``/history/segments/{peak_tension, peak_time,
    slack_time, slack_episodes}`` (one entry per segment)."""
    e = g.create_group("events")
    put(e, "t", rec.t, "s", "instant a segment changed mode (located to 1e-10 s on the step's interpolant)")
    put(e, "segment", rec.segment, "1", "1-based segment")
    ds = e.create_dataset("kind", data=np.array([k.encode() for k in rec.kind], dtype="S5"))
    ds.attrs["units"] = "1"
    ds.attrs["description"] = "slack (onset: length fell to the natural length) or taut (re-tightening)"
    e.attrs["handling"] = rec.handling
    e.attrs["chatter_holds"] = rec.chatter_holds
    s = g.create_group("segments")
    put(s, "peak_tension", rec.peak_tension, "N", "largest tension over the run (tracked at every step: snap loads)")
    put(s, "peak_time", rec.peak_time, "s", "when it occurred")
    put(s, "slack_time", rec.slack_time, "s", "time spent slack")
    put(s, "slack_episodes", rec.episodes, "1", "number of slack episodes")


def _read_slack(g: h5py.Group) -> SlackRecord | None:
    if "events" not in g or "segments" not in g:
        return None
    e, s = g["events"], g["segments"]
    kind = np.array([k.decode() if isinstance(k, bytes) else str(k) for k in e["kind"][()]], dtype=str)
    return SlackRecord(
        t=np.asarray(e["t"][()], dtype=float), segment=np.asarray(e["segment"][()], dtype=np.int64), kind=kind,
        peak_tension=np.asarray(s["peak_tension"][()], dtype=float), peak_time=np.asarray(s["peak_time"][()], dtype=float),
        slack_time=np.asarray(s["slack_time"][()], dtype=float), episodes=np.asarray(s["slack_episodes"][()], dtype=np.int64),
        chatter_holds=int(e.attrs.get("chatter_holds", 0)), handling=attr_text(e.attrs.get("handling", "")),
    )


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------
#: Result file families: the ``command`` root attribute -> the kind of data it holds.
FAMILIES = {"static": "static", "history": "history", "free-vibration": "history", "sweep": "sweep",
            "continue": "continuation", "backbone": "backbone"}
#: How messages name each family.
FAMILY_TEXT = {"static": "a static file", "history": "a time-history file", "sweep": "a sweep file",
               "continuation": "a continuation file", "backbone": "a backbone file"}
#: Sweep directions and the result groups they use.
DIRECTION_GROUPS = {"independent": [None], "up": ["up"], "down": ["down"], "both": ["up", "down"]}


def open_result(path: Path, group: str, what: str, command: str) -> h5py.File:
    """The HDF5 file ``path`` opened for reading, refused in one message unless it holds
    ``/group`` (a ``what`` file, the output of ``command``)."""
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise CablesimError(f"{path} is not an HDF5 file (or cannot be read).") from None
    if group not in f:
        f.close()
        raise CablesimError(f"{path} is not a {what} file (no /{group} group); give the output of {command}.")
    return f


def attr_text(value) -> str:
    """An HDF5 attribute (bytes, 1-element array, ...) as str."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return attr_text(value.item())
    return str(value)


def _plain(value):
    """numpy scalars (from HDF5 attributes) as Python numbers, bytes as str."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.generic):
        return value.item()
    return value


@dataclass(frozen=True)
class ResultInfo:
    path: Path
    command: str
    family: str
    case_text: str


def is_complete_result(path) -> bool:
    """Whether ``path`` holds a cablesim result that an incomplete run must not replace:
    a static file, a completed history, or a complete sweep (unreadable files are not)."""
    path = Path(path)
    if not path.is_file():
        return False
    try:
        with h5py.File(path, "r") as f:
            if "command" not in f.attrs:
                return False
            if "history" in f:
                return bool(f["history"].attrs.get("completed", False))
            if "sweep" in f:
                return bool(f["sweep"].attrs.get("complete", False))
            for group in ("backbone", "continuation/loci"):  # cablesim.io.charts
                if group in f:
                    return bool(f[group].attrs.get("complete", False))
            if "continuation" in f:  # written before the attribute existed: complete
                return bool(f["continuation"].attrs.get("complete", True))
            return True
    except (OSError, KeyError, ValueError):
        return False


def inspect_result(path) -> ResultInfo:
    """Check that ``path`` is a cablesim result file; its command and stored case text."""

    path = Path(path)
    if not path.exists():
        raise CablesimError(f"The result file {path} does not exist. Check the path.")
    if not path.is_file():
        raise CablesimError(f"{path} is not a file; give the HDF5 file a cablesim command wrote.")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise CablesimError(
            f"{path} is not an HDF5 file (or cannot be read); give a .h5 file written by cablesim "
            "static, history, free-vibration, sweep, continue or backbone."
        ) from None
    with f:
        command = f.attrs.get("command")
        case_text = f.attrs.get("case_yaml")
    if command is None or case_text is None:
        raise CablesimError(
            f"{path} is an HDF5 file but not a cablesim result: it has no 'command' and 'case_yaml' "
            "attributes. Give a file written by cablesim static, history, free-vibration, sweep, continue "
            "or backbone."
        )
    command = attr_text(command)
    if command not in FAMILIES:
        raise CablesimError(
            f"{path} was written by the command '{command}', which cablesim plot does not know; it "
            f"redraws the results of {', '.join(FAMILIES)}."
        )
    return ResultInfo(path, command, FAMILIES[command], attr_text(case_text))


def read_case_text(path) -> str:
    """The case YAML stored in a cablesim result file (root attribute ``case_yaml``).

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5 or not a cablesim result file.
    """
    return inspect_result(path).case_text


def read_history(path):
    """Rebuild the :class:`~cablesim.dynamics.result.HistoryResult` stored in a history file.

    Parameters
    ----------
    path : str or Path
        HDF5 file written by ``cablesim history`` or ``cablesim free-vibration``.

    Returns
    -------
    HistoryResult
        With ``dof`` from ``/history/dof`` (None when every DOF was kept, in order), ``omega``
        None for free vibration (NaN attribute), ``modal_omega`` from ``/modal/omega`` and
        ``settings`` from the remaining attributes of ``/history``.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5, not a cablesim file, not a time history, or malformed.
    """


    info = inspect_result(path)
    path = info.path
    if info.family != "history":
        raise CablesimError(
            f"{path} is {FAMILY_TEXT[info.family]} (written by 'cablesim {info.command}'), not a time "
            "history; give a file written by cablesim history or free-vibration."
        )
    with h5py.File(path, "r") as f:
        g = f.get("history")
        need = ("t", "z", "v", "T", "residual", "y0", "T0")
        missing = [k for k in need if g is None or k not in g]
        if missing:
            raise CablesimError(
                f"The history file {path} is malformed: /history/{{{', '.join(missing)}}} missing. "
                "Rerun the history."
            )
        try:
            data = {k: np.asarray(g[k][()], dtype=float) for k in need}
            zc = np.asarray(g["zc"][()], dtype=float) if "zc" in g else None
            ze = np.asarray(g["ze"][()], dtype=float) if "ze" in g else None
            dof = tuple(int(d) for d in np.asarray(g["dof"][()]).ravel()) if "dof" in g else None
            attrs = {k: _plain(v) for k, v in g.attrs.items()}
            modal = np.asarray(f["modal/omega"][()], dtype=float) if "modal/omega" in f else np.empty(0)
            slack = _read_slack(g)
        except (TypeError, ValueError, KeyError, AttributeError):
            raise CablesimError(f"The history file {path} is malformed: a dataset under /history is not an "
                                "array of numbers. Rerun the history.") from None
    _check_history_shapes(path, data, zc, ze)
    if dof is not None and dof == tuple(range(1, data["y0"].size + 1)):
        dof = None  # every DOF, in order
    omega = attrs.pop("omega", None)
    omega = None if omega is None or not np.isfinite(float(omega)) else float(omega)
    analysis = attr_text(attrs.pop("analysis", "unknown"))
    integrator = attr_text(attrs.pop("integrator", "unknown"))
    message = attr_text(attrs.pop("status", "completed"))
    completed = bool(attrs.pop("completed", message == "completed"))
    code = attrs.pop("status_code", None)
    if code is not None:
        status = Status(int(code))
    else:  # files without a status code: only whether the run completed is known
        status = Status.COMPLETED if completed else Status.UNKNOWN
    t_stop = attrs.pop("t_stop", None)
    t_stop = None if t_stop is None or not np.isfinite(float(t_stop)) else float(t_stop)
    attrs.pop("forced", None)  # derived from omega
    attrs.pop("units", None)  # the units of these attributes
    warnings = _warnings(attrs.pop("warnings", "[]"))
    return HistoryResult(
        t=data["t"], z=data["z"], v=data["v"], zc=zc, ze=ze, T=data["T"], residual=data["residual"],
        y0=data["y0"], T0=data["T0"], omega=omega, analysis=analysis, integrator=integrator,
        status=status, message=message, t_stop=t_stop, modal_omega=modal, settings=attrs, dof=dof, slack=slack,
        warnings=warnings,
    )


def _warnings(text) -> tuple[str, ...]:
    """The plausibility warnings stored as a JSON list (none if unreadable)."""
    try:
        value = json.loads(attr_text(text))
    except ValueError:
        return ()
    return tuple(str(w) for w in value) if isinstance(value, list) else ()


def _check_history_shapes(path, data: dict, zc, ze) -> None:
    """Refuse a history file whose arrays do not fit together (time along the first axis)."""
    m = data["t"].shape[0] if data["t"].ndim == 1 else -1
    want = {"z": 2, "v": 2, "T": 2, "residual": 1}
    bad = [k for k, nd in want.items() if data[k].ndim != nd or data[k].shape[0] != m]
    bad += [k for k, a in (("zc", zc), ("ze", ze)) if a is not None and a.shape != data["z"].shape]
    if m < 1 or data["z"].shape != data["v"].shape:
        bad.append("t")
    if bad:
        raise CablesimError(
            f"The history file {path} is malformed: /history/{{{', '.join(sorted(set(bad)))}}} do not match "
            "the saved instants /history/t. Rerun the history."
        )


def read_static_drawing(path: Path, case):
    """What :func:`cablesim.plots.cable.plot_cable` and :func:`cablesim.plots.modes.draw_modes` need,
    from a static file (no solving)."""

    with h5py.File(path, "r") as f:
        analysis = attr_text(f.attrs.get("analysis", f["modal"].attrs.get("analysis", "exact") if "modal" in f else "exact"))
        st = f.get("static")
        try:
            grp = st[analysis]
            y0 = np.asarray(grp["y"][()], dtype=float)
            T0 = np.asarray(grp["T"][()], dtype=float)
            P = np.asarray(st["P"][()], dtype=float)
            omega = np.asarray(f["modal/omega"][()], dtype=float)
        except (KeyError, TypeError):
            raise CablesimError(
                f"The static file {path} is malformed (its /static/{analysis} results or /modal/omega "
                "are missing); rerun cablesim static, which draws the cable too."
            ) from None
        inext = None
        if "inextensible" in st and "x" in st["inextensible"]:
            inext = SimpleNamespace(x=np.asarray(st["inextensible/x"][()], dtype=float))
        # the lowest shapes, which the drawings name (symmetric, antisymmetric) and draw
        shapes = np.asarray(f["modal/shapes"][:, :20], dtype=float) if "modal/shapes" in f else None
        kinds = tuple(attr_text(k) for k in f["modal/kind"][()]) if "modal/kind" in f else ()
        ratios = np.asarray(f["modal/damping_ratio"][()], dtype=float) if "modal/damping_ratio" in f else np.zeros(0)
    return SimpleNamespace(cable=case.to_cable(), analysis=analysis, P=P, y0=y0, T0=T0, inextensible=inext,
                           modes=SimpleNamespace(omega=omega, shapes=shapes, kinds=kinds), damping_ratios=ratios)






def describe_result(path) -> str | None:
    """``"a complete sweep of 56 points, written 2026-12-01 21:40 UTC by `cablesim sweep ...`"``
    for a complete cablesim result at ``path``; None if it is not one (or cannot be read)."""
    if not is_complete_result(path):
        return None
    try:
        with h5py.File(path, "r") as f:
            command = attr_text(f.attrs.get("command", "?"))
            when = attr_text(f.attrs.get("created_utc", ""))[:16].replace("T", " ")
            line = attr_text(f.attrs.get("command_line", ""))
            size = ""
            if "sweep" in f:
                size = f" of {int(f['sweep'].attrs.get('points_total', 0))} points"
            elif "history" in f and "t" in f["history"]:
                size = f" of {float(f['history/t'][-1]):g} s"
    except (OSError, KeyError, ValueError, IndexError):
        return None
    by = f" by `{line}`" if line else ""
    return f"a complete {command} result{size}, written {when} UTC{by}" if when else f"a complete {command} result{size}{by}"
