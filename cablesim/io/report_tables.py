"""What a run report (``cablesim report``) shows of a result file, read from the file: how the
run was made, the case in brief, the tables of results and the warnings.

Each table cell keeps the number it shows at full precision (``Cell.value``, in the unit of its
column), which the HTML page stores beside the rounded text (``data-value``): a reader, or a
test, compares the page with the file without parsing rounded text.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from ..analyses.static import strain_warnings
from ..case import parse_case
from ..channels import channel_description
from .continuation import read_continuation, support_meaning
from .hdf5 import attr_text, inspect_result
from .sweeps import read_sweep, sweep_summary_rows

#: Rows a table shows at most (a heavy cable's nodes): the first and last half of these.
MAX_ROWS = 40
#: Root attributes shown under "How it was run", with their labels.
PROVENANCE = (("command_line", "command line"), ("created_utc", "written (UTC)"), ("cablesim_version", "cablesim"),
              ("git_commit", "git commit"), ("python_version", "Python"), ("numpy_version", "numpy"),
              ("scipy_version", "scipy"), ("numba_version", "numba"), ("h5py_version", "h5py"),
              ("platform", "platform"), ("analysis", "analysis"))


@dataclass(frozen=True)
class Cell:
    """A table cell: its ``text``, and the number it shows (None for text), in the column's unit."""

    text: str
    value: float | None = None


@dataclass
class Table:
    """A table of a report: ``key`` (unique in the page), ``title``, ``columns`` (with units),
    ``rows`` of :class:`Cell`, an optional ``note`` under it."""

    key: str
    title: str
    columns: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    note: str = ""


@dataclass
class FileReport:
    """Everything a report shows of one result file (figures apart)."""

    path: Path
    family: str
    command: str
    case_name: str
    provenance: list[tuple[str, str]]
    options: str
    case_text: str
    case_summary: list[tuple[str, str]]
    tables: list[Table]
    warnings: list[str]


def num(value, fmt: str = ".6g", scale: float = 1.0) -> Cell:
    """A number cell: ``value / scale`` printed with ``fmt``; NaN as an en dash."""
    v = float(value) / scale
    return Cell("–" if not np.isfinite(v) else format(v, fmt), v if np.isfinite(v) else None)


def text(value) -> Cell:
    """A text cell."""
    return Cell(str(value))


def shown_rows(count: int) -> list[int]:
    """Indices of the rows of a table of ``count`` rows shown (all up to :data:`MAX_ROWS`)."""
    if count <= MAX_ROWS:
        return list(range(count))
    half = MAX_ROWS // 2
    return [*range(half), *range(count - half, count)]


def _clip_note(count: int, what: str) -> str:
    return f"{MAX_ROWS} of {count} {what} shown: the first and last {MAX_ROWS // 2}." if count > MAX_ROWS else ""


def read_file_report(path: str | Path) -> FileReport:
    """The report of one cablesim result file (static, history, free vibration, sweep,
    continuation or backbone)."""
    info = inspect_result(path)
    case = parse_case(info.case_text, source=f"(the case stored in {info.path})", default_name=info.path.stem)
    with h5py.File(info.path, "r") as f:
        provenance = [(label, attr_text(f.attrs[k])) for k, label in PROVENANCE if k in f.attrs]
        options = attr_text(f.attrs.get("options", "{}"))
        tables, warnings = _family_tables(f, info, case)
        tables.append(_datasets_table(f))
    try:
        options = json.dumps(json.loads(options), indent=1, sort_keys=True)
    except ValueError:
        pass
    return FileReport(info.path, info.family, info.command, case.name, provenance, options, info.case_text,
                      case_summary(case), tables, warnings)


def case_summary(case) -> list[tuple[str, str]]:
    """The case in a few lines: geometry, rigidity, masses, loads' size, analysis, damping."""
    c = case.to_cable()
    d = case.damping
    damping = (f"ratio {d.ratio:g} in modes {', '.join(str(m) for m in d.modes)}" if d.ratio is not None
               else f"a0 = {d.a0:g} 1/s, a1 = {d.a1:g} s")
    return [("name", case.name), ("cable", f"{'spatial' if c.dim == 3 else 'planar'}, n = {c.n_nodes} interior nodes"),
            ("supports", f"L = {c.L:g} m, H = {c.H:g} m" + (f", W = {c.W:g} m" if c.dim == 3 else "")),
            ("natural length", f"{float(np.sum(c.S)):.6g} m in {c.n_segments} segments"),
            ("axial rigidity EA", f"{c.EA:.4g} N"), ("total mass", f"{float(np.sum(c.masses)):.6g} kg"),
            ("analysis", case.analysis), ("damping (Rayleigh)", damping)]


def _family_tables(f, info, case) -> tuple[list[Table], list[str]]:
    if info.family == "static":
        return static_tables(f, case)
    if info.family == "history":
        return history_tables(f, case)
    if info.family == "sweep":
        return sweep_tables(info.path)
    if info.family == "continuation":
        return continuation_tables(info.path)
    return [], []  # a backbone: its datasets are listed and its figure shown


# ----------------------------------------------------------------------------------------------
# static files
# ----------------------------------------------------------------------------------------------
def support_forces(y: np.ndarray, T: np.ndarray, cable) -> tuple[np.ndarray, np.ndarray]:
    """The forces the cable exerts on supports A and B, N: each end segment's tension along it,
    towards the cable's first and last node (components as the DOF: horizontal, vertical down,
    out of plane)."""
    pts = np.reshape(y, (-1, cable.dim))
    ea, eb = pts[0], pts[-1] - cable.chord  # support A at the origin, B at the chord's end
    return T[0] * ea / np.linalg.norm(ea), T[-1] * eb / np.linalg.norm(eb)


def static_tables(f, case) -> tuple[list[Table], list[str]]:
    """Segment tensions, support reactions, node coordinates and modes of a static file."""
    cable = case.to_cable()
    analysis = attr_text(f.attrs.get("analysis", "exact"))
    g = f["static"][analysis]
    y, T = np.asarray(g["y"][()], dtype=float), np.asarray(g["T"][()], dtype=float)
    tens = Table("tensions", f"Segment tensions under F0 ({analysis} analysis)", ["segment", "T (kN)"])
    if "l" in g:
        tens.columns.append("stretched length l (m)")
    for k in shown_rows(T.size):
        tens.rows.append([text(k + 1), num(T[k], scale=1e3)] + ([num(g["l"][k])] if "l" in g else []))
    tens.note = _clip_note(T.size, "segments")
    comps = ["horizontal (kN)", "vertical, down + (kN)"] + (["out of plane (kN)"] if cable.dim == 3 else [])
    reac = Table("reactions", "Forces of the cable on its supports", ["support", *comps, "magnitude (kN)"],
                 note="Each end segment's tension along it, towards the cable; their sum is the sum of the loads F0.")
    for name, force in zip("AB", support_forces(y, T, cable)):
        reac.rows.append([text(name), *(num(c, scale=1e3) for c in force), num(np.linalg.norm(force), scale=1e3)])
    coords = Table("nodes", f"Node coordinates under F0 ({analysis} analysis)",
                   ["node", "x (m)", "v (m), down +"] + (["w (m)"] if cable.dim == 3 else []))
    pts = y.reshape(-1, cable.dim)
    for k in shown_rows(pts.shape[0]):
        coords.rows.append([text(k + 1), *(num(c) for c in pts[k])])
    coords.note = _clip_note(pts.shape[0], "nodes")
    return [tens, reac, coords, modes_table(f)], [w[0].upper() + w[1:] for w in strain_warnings(cable, T)]


def modes_table(f) -> Table:
    """The linear modes stored in ``/modal``: frequency, period, damping ratio, kind."""
    m = f["modal"]
    omega = np.asarray(m["omega"][()], dtype=float)
    ratio = np.asarray(m["damping_ratio"][()], dtype=float) if "damping_ratio" in m else None
    kinds = [attr_text(k) for k in m["kind"][()]] if "kind" in m else None
    cols = ["mode", "ω (rad/s)", "f (Hz)", "period (s)"] + (["damping ratio ξ"] if ratio is not None else []) + \
        (["kind"] if kinds else [])
    table = Table("modes", "Linear modes about the equilibrium", cols)
    for k in shown_rows(omega.size):
        row = [text(k + 1), num(omega[k]), num(omega[k] / (2 * np.pi)), num(2 * np.pi / omega[k])]
        row += [num(ratio[k], ".4g")] if ratio is not None else []
        row += [text(kinds[k])] if kinds else []
        table.rows.append(row)
    extra = []
    if "a0" in m.attrs:
        extra.append(f"Rayleigh damping C = a0 M + a1 K0 with a0 = {float(m.attrs['a0']):.6g} 1/s, "
                     f"a1 = {float(m.attrs['a1']):.6g} s.")
    if "omega_max" in m.attrs and omega.size < int(m.attrs.get("modes_computed", omega.size) or omega.size):
        extra.append(f"Highest frequency {float(m.attrs['omega_max']):.6g} rad/s.")
    table.note = " ".join([_clip_note(omega.size, "modes"), *extra]).strip()
    return table


# ----------------------------------------------------------------------------------------------
# time histories
# ----------------------------------------------------------------------------------------------
def history_tables(f, case) -> tuple[list[Table], list[str]]:
    """The run's outcome, the largest displacements per DOF and the tensions of a history file."""
    g = f["history"]
    a = g.attrs
    cable = case.to_cable()
    t = np.asarray(g["t"][()], dtype=float)
    outcome = Table("outcome", "The run", ["quantity", "value"])
    forced = bool(a.get("forced", True))
    rows = [("status", attr_text(a.get("status", "?"))), ("integrator", attr_text(a.get("integrator", "?"))),
            ("simulated time (s)", f"{t[-1]:.6g}" if t.size else "0"), ("saved instants", str(t.size))]
    if forced:
        rows.insert(1, ("forcing frequency ω (rad/s)", f"{float(a.get('omega', float('nan'))):.6g}"))
    outcome.rows = [[text(k), text(v)] for k, v in rows]
    z = np.asarray(g["z"][()], dtype=float)
    dofs = [int(d) for d in g["dof"][()]] if "dof" in g else list(range(1, z.shape[1] + 1))
    disp = Table("displacements", "Displacements from the equilibrium", ["DOF", "channel", "min z (m)", "max z (m)",
                                                                         "max |z| (m)"])
    for j in shown_rows(len(dofs)):
        col = z[:, j]
        disp.rows.append([text(f"z{dofs[j]}"), text(channel_description(dofs[j] - 1, cable.dim)), num(col.min()),
                          num(col.max()), num(np.abs(col).max())])
    disp.note = _clip_note(len(dofs), "DOF")
    tens, warnings = _history_tensions(g, t)
    if attr_text(a.get("status", "completed")) != "completed":
        warnings.insert(0, f"The run stopped early at t = {float(a.get('t_stop', t[-1] if t.size else 0)):.6g} s "
                           f"({attr_text(a.get('status'))}); the file holds everything up to then.")
    return [outcome, disp, tens], warnings


def _history_tensions(g, t) -> tuple[Table, list[str]]:
    T = np.asarray(g["T"][()], dtype=float)
    T0 = np.asarray(g["T0"][()], dtype=float)
    seg = g.get("segments")
    peak = np.asarray(seg["peak_tension"][()], dtype=float) if seg is not None else T.max(axis=0)
    slack = np.asarray(seg["slack_time"][()], dtype=float) if seg is not None else np.zeros(T0.size)
    episodes = np.asarray(seg["slack_episodes"][()], dtype=int) if seg is not None else np.zeros(T0.size, int)
    table = Table("history-tensions", "Segment tensions", ["segment", "static T0 (kN)", "min T (kN)",
                                                          "peak T (kN)", "time slack (s)", "slack episodes"])
    for k in shown_rows(T0.size):
        table.rows.append([text(k + 1), num(T0[k], scale=1e3), num(T[:, k].min(), scale=1e3),
                           num(peak[k], scale=1e3), num(slack[k]), num(episodes[k], ".0f")])
    table.note = ("Peak tensions are tracked at every step (snap loads), not only at the saved instants. "
                  + _clip_note(T0.size, "segments")).strip()
    warnings = []
    if episodes.sum() > 0:
        went = np.flatnonzero(episodes > 0) + 1
        warnings.append(f"{went.size} segment(s) went slack during the run (segments "
                        f"{', '.join(str(s) for s in went[:12])}{', ...' if went.size > 12 else ''}); "
                        f"largest time slack {slack.max():.4g} s of {t[-1]:.4g} s.")
    return table, warnings


# ----------------------------------------------------------------------------------------------
# sweeps and continuations
# ----------------------------------------------------------------------------------------------
def sweep_tables(path: Path) -> tuple[list[Table], list[str]]:
    """The peaks of every curve and channel of a sweep file, and its points."""
    peaks = Table("sweep-peaks", "Largest response of each curve and channel",
                  ["curve", "channel", "ω at the peak (rad/s)", "peak |z| (m)", "period (forcing periods)", "steady",
                   "points computed"])
    for r in sweep_summary_rows(path):
        curve = ("" if r["gamma"] is None else f"γ = {r['gamma']:g}, ") + r["direction"]
        peaks.rows.append([text(curve), text(r["channel"]), num(r["omega"]), num(r["value"]), num(r["period"], ".0f"),
                           text("yes" if r["steady"] else "no"), text(f"{r['points_done']} of {r['points']}")])
    sweep = read_sweep(path)
    tables, warnings = [peaks], []
    for c, curve in enumerate(sweep.curves):
        d = curve.data
        pts = Table(f"sweep-points-{c + 1}", f"Points ({curve.label})",
                    ["ω (rad/s)", *(f"|z| {ch} (m)" for ch in sweep.channels), "period", "decided", "status"])
        for k in shown_rows(sweep.omega.size):
            pts.rows.append([num(sweep.omega[k]), *(num(d["amplitude"][k, j]) for j in range(len(sweep.channels))),
                             num(d["period"][k], ".0f"), text(attr_text(d["decided"][k])), text(attr_text(d["status"][k]))])
        pts.note = _clip_note(sweep.omega.size, "points")
        tables.append(pts)
        done = d["done"]
        unsteady = np.flatnonzero(done & ~d["steady"] & ~d["failed"])
        failed = np.flatnonzero(done & d["failed"])
        if unsteady.size:
            warnings.append(f"{curve.label}: {unsteady.size} point(s) not steady within the time limit (ω = "
                            f"{', '.join(f'{w:.4g}' for w in sweep.omega[unsteady][:10])} rad/s).")
        if failed.size:
            warnings.append(f"{curve.label}: {failed.size} point(s) stopped early (ω = "
                            f"{', '.join(f'{w:.4g}' for w in sweep.omega[failed][:10])} rad/s); their values are partial.")
        if (~done).any():
            warnings.append(f"{curve.label}: {int((~done).sum())} point(s) not computed (an incomplete sweep).")
    return tables, warnings


def continuation_tables(path: Path) -> tuple[list[Table], list[str]]:
    """The branches and the bifurcations of a continuation file."""
    res = read_continuation(path)
    unit = "rad/s" if res["parameter"] == "omega" else "1"
    br = Table("branches", "Branches of periodic responses", ["branch", "period (forcing periods)", "orbits",
                                                               f"{res['parameter']} from ({unit})", f"to ({unit})",
                                                               "stable orbits", "end"])
    for b in res["branches"]:
        p = np.asarray(b["parameter"], dtype=float)
        br.rows.append([text(b["name"]), num(b["period"], ".0f"), num(p.size, ".0f"), num(p.min() if p.size else np.nan),
                        num(p.max() if p.size else np.nan), num(int(np.sum(b["stable"])), ".0f"), text(b["end"])])
    bif = res["bifurcations"]
    # in gamma or the support multiplier s: the parameter's column first (omega is fixed)
    symbol = {"omega": None, "gamma": "γ", "support": "s"}[res["parameter"]]
    planes = list(bif.get("plane", []))
    spatial = any(p != "in-plane" for p in planes)  # the block of the critical multiplier, when it varies
    cols = ["kind", *(["plane"] if spatial else []), *([symbol] if symbol else []), "ω (rad/s)", "branch", "period",
            *(f"|z| {ch} (m)" for ch in res["channels"]), "|μ|", "located", "trusted"]
    bt = Table("bifurcations", "Bifurcations", cols)
    if res["parameter"] == "support" and res.get("support_amplitudes"):
        bt.note = f"s multiplies the amplitudes of the moving supports ({support_meaning(res['support_amplitudes'])})."
    warnings = []
    for k, kind in enumerate(bif.get("kind", [])):
        amp = np.atleast_2d(bif["amplitude"])[k]
        bt.rows.append([text(kind), *([text(planes[k])] if spatial else []), *([num(bif["parameter"][k])] if symbol else []),
                        num(bif["omega"][k]),
                        num(bif["branch"][k], ".0f"), num(bif["period"][k], ".0f"),
                        *(num(a) for a in amp), num(abs(bif["multiplier"][k]), ".6g"),
                        text("yes" if bif["located"][k] else "no"), text("yes" if bif["trusted"][k] else "no")])
        if not bif["located"][k] or not bif["trusted"][k]:
            where = f"ω = {bif['omega'][k]:.6g} rad/s" if not symbol else f"{symbol} = {bif['parameter'][k]:.6g}"
            warnings.append(f"The {kind} near {where} was "
                            f"{'not located' if not bif['located'][k] else 'located with untrusted multipliers'}.")
    if not bt.rows:
        bt.note = "No bifurcation on the branches traced."
    return [br, bt], warnings


def _datasets_table(f) -> Table:
    """Every dataset of the file with its shape and units."""
    table = Table("datasets", "Datasets in the file", ["dataset", "shape", "units"])

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            table.rows.append([text("/" + name), text(" x ".join(map(str, obj.shape)) or "scalar"),
                               text(attr_text(obj.attrs.get("units", "")))])

    f.visititems(visit)
    return table
