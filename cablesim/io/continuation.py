"""Continuation files (``cablesim continue``): writer and reader.

Layout (with the root attributes of every cablesim file, see :mod:`cablesim.io.hdf5`):

- ``/continuation`` attributes ``parameter`` (``omega``, ``gamma`` or ``support``), ``start``,
  ``stop``, ``fixed`` (the other parameter's value: gamma in omega, omega in rad/s in gamma or
  support), ``gamma`` (the fixed gamma, unless it is the parameter), ``channels``,
  ``components`` (per node: 2 planar, 3 spatial; the channels' DOF count in them),
  ``case_name``, ``complete`` (False: an interrupted run, holding the orbits computed until
  then) and the cost counters;
- ``/continuation/branches/<name>/{parameter, omega, gamma, support, amplitude (points x channels,
  max |z| over the orbit), halfrange, stable, trusted, multipliers (complex), state}`` with
  attributes ``period``, ``channels``, ``parent`` (-1: none) and ``end``; ``support`` is the
  support motion multiplier s (the supports move by gamma s times the amplitudes of
  ``supports:``), with the attribute ``amplitude_<A|B>`` (m) of each moving support at s = 1;
- ``/continuation/support_amplitude`` (moving supports, one row each, m), attribute ``supports``;
- ``/continuation/bifurcations/{kind, parameter, omega, gamma, support, branch, period,
  amplitude (x channels), multiplier (complex), located, trusted, plane (in-plane,
  out-of-plane or coupled),
  frequency_ratio (``|arg(mu)| / 2 pi`` of the critical multiplier: the new frequency over the
  orbit's at a Neimark-Sacker point)}``; an out-of-plane
  multiplier of a planar orbit through +1 is a ``pitchfork`` (symmetry breaking);
- per branch also ``multiplier_plane`` (points x multipliers: the block of each multiplier),
  the attributes ``planar`` (orbits in the mirror plane of a symmetric spatial cable) and
  ``mirror_image`` (a nonplanar branch born at a pitchfork, whose mirror image ``w -> -w`` is a
  branch too) and, for a spatial cable, ``whirl_area`` (points x nodes, m^2: the signed area of
  each node's path in its ``(w, v)`` plane, positive counter-clockwise as seen from support A
  looking towards B), ``whirl_sense`` (points x nodes: ``counter-clockwise``, ``clockwise`` or
  ``none``, that sign in words), ``max_w`` (points x nodes, m: each node's largest out-of-plane
  ``|w|`` over the orbit; zero on a planar orbit) and ``tilt`` (deg: the orbit's mean plane of
  motion from the cable's plane);
- through slack (``continuation.through_slack``, attribute ``through_slack``): per branch
  ``peak_tension`` (points x segments, N: each segment's largest tension over the orbit, its
  snap load), ``peak_time`` (s from forcing phase 0), ``slack_episodes`` (points x segments:
  slack episodes per orbit period), ``slack_fraction`` (of the period), ``least_tension``
  (points x segments, N: the least elastic tension ``EA (l - S) / S``, negative where the
  segment goes slack), ``slack`` (points: some segment slack) and the episodes themselves,
  flattened orbit by orbit and segment by segment within an orbit (``slack_episodes`` counts
  them): ``slack_onset``, ``slack_end`` (s from forcing phase 0; an end beyond the period for
  an episode through its end); in ``/continuation/bifurcations`` also ``segment`` (1-based, 0:
  not a grazing point located on a branch through slack), ``episodes_before``,
  ``episodes_after`` (the segment's slack episodes on the orbits either side, in continuation
  order; -1 elsewhere), ``multipliers_before``, ``multipliers_after`` (those orbits' Floquet
  multipliers) and ``multiplier_jump`` (the largest distance between them, matched), NaN on
  the other rows;
- with ``continuation.loci``: ``/continuation/loci/<name>/...`` and ``/continuation/codim2/...``,
  the bifurcation curves in (omega, gamma) or (omega, s) (:mod:`cablesim.io.charts`);
- ``/modal/omega``: the linear modal frequencies, rad/s.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import CablesimError
from .charts import read_loci, write_loci
from .hdf5 import atomic_h5, attr_text, open_result, put, stamp

#: Bifurcation kinds, in the order the files store their names.
KINDS = ("fold", "period-doubling", "neimark-sacker", "branch-point", "pitchfork", "grazing")


#: Each continuation parameter in words, with its unit (summaries, tables and figures).
PARAMETER_WORDS = {"omega": "forcing frequency omega (rad/s)", "gamma": "load factor gamma",
                   "support": "support motion multiplier s"}


def length_text(metres: float) -> str:
    """A support amplitude in words: ``"5.0 mm"`` below 1 m, else ``"1.25 m"``."""
    if abs(metres) >= 1.0:
        return f"{metres:.3g} m"
    mm = abs(metres) * 1e3
    return f"{mm:.0f} mm" if mm >= 10 else f"{mm:.1f} mm" if mm >= 0.1 else f"{mm:.2g} mm"


def support_meaning(amplitudes: dict) -> str:
    """What support multiplier s = 1 stands for: ``"s = 1: |u_A| = 5.0 mm"`` (the length of each
    moving support's amplitude vector, m, as ``supports:`` gives it); "" without one."""
    parts = [f"|u_{name}| = {length_text(float(np.linalg.norm(u)))}" for name, u in amplitudes.items()]
    return f"s = 1: {', '.join(parts)}" if parts else ""


#: Description of the support motion multiplier s in the files.
SUPPORT_TEXT = ("support motion multiplier s: multiplies the amplitudes of supports: (s = 1: as written; "
                "the supports move by gamma s times them)")


def _put_neutral(h, b) -> None:
    """A branch's residuals of the multiplier excluded by a rotation symmetry, if any."""
    if getattr(b, "neutral_residual", None) is not None:
        put(h, "neutral_residual", b.neutral_residual, "1", "the orbit's multiplier +1 forced by the cable's "
            "rotation symmetry about its chord, excluded from the bifurcation tests and from stable: "
            "|M g - g| / |g| of its eigenvector g, the rotation's generator (NaN: none excluded)", allow_nan=True)


def _put_support(group, values, amplitudes: dict):
    """The support multiplier column, with the amplitude (m) of each moving support at s = 1."""
    ds = put(group, "support", values, "1", SUPPORT_TEXT)
    for name, u in amplitudes.items():
        ds.attrs[f"amplitude_{name}"] = np.asarray(u, dtype=float)
    if amplitudes:
        ds.attrs["amplitude_units"] = "m"
    return ds


def _put_state(g, res, fingerprint: str | None) -> None:
    """The attributes of ``/continuation`` that say how far it got and what it was."""
    g.attrs["complete"] = bool(getattr(res, "complete", True))  # False: interrupted, the orbits until then
    if fingerprint is not None:
        g.attrs["fingerprint"] = fingerprint
    g.attrs["warnings"] = json.dumps(list(getattr(res, "warnings", ())))  # plausibility warnings
    g.attrs["channels"] = np.array(res.channels, dtype="S")
    g.attrs["components"] = int(getattr(res, "components", 2))  # per node: 2 planar, 3 spatial
    for k, v in res.stats.items():
        g.attrs[f"cost_{k}"] = v


def _put_slack(h, sl) -> None:
    """A branch's slack patterns (module docstring)."""
    put(h, "peak_tension", sl.peak_tension, "N", "largest tension of each segment over the orbit (snap load)")
    put(h, "peak_time", sl.peak_time, "s", "when it occurs, from forcing phase 0")
    put(h, "slack_episodes", np.asarray(sl.episodes, dtype=np.int64), "1", "slack episodes of each segment per orbit period")
    put(h, "slack_fraction", sl.fraction, "1", "fraction of the orbit's period each segment is slack")
    put(h, "least_tension", sl.least_tension, "N", "least elastic tension EA (l - S) / S of each segment over the "
        "orbit (negative: the segment goes slack; zero: grazing)")
    put(h, "slack", sl.slack, "1", "some segment goes slack on the orbit")
    put(h, "slack_onset", sl.onset, "s", "onset of every slack episode, from forcing phase 0 (orbit by orbit, segment "
        "by segment; slack_episodes counts them)")
    put(h, "slack_end", sl.end, "s", "re-tightening of every slack episode, from forcing phase 0 (beyond the period: "
        "through its end)")


def _put_grazing(fg, bifs) -> None:
    """The grazing columns of the bifurcations of a continuation through slack (module docstring)."""
    n = max([b.grazing.before.size for b in bifs if getattr(b, "grazing", None) is not None], default=0)

    def column(b, name):
        g = getattr(b, "grazing", None)
        return np.asarray(getattr(g, name), dtype=complex) if g is not None else np.full(n, np.nan + 0j)

    graz = [getattr(b, "grazing", None) for b in bifs]
    put(fg, "segment", np.array([g.segment if g is not None else 0 for g in graz], dtype=np.int64), "1",
        "1-based segment that grazes (0: not a grazing point of a branch through slack)")
    for k, side in enumerate(("before", "after")):
        put(fg, f"episodes_{side}", np.array([g.episodes[k] if g is not None else -1 for g in graz], dtype=np.int64),
            "1", f"slack episodes per period of that segment on the orbit {side} it (continuation order; -1: none)")
        put(fg, f"multipliers_{side}", np.array([column(b, side) for b in bifs], dtype=complex).reshape(len(bifs), n),
            "1", f"Floquet multipliers of the branch's orbit {side} the grazing point (NaN: not a grazing point)",
            allow_nan=True)
    put(fg, "multiplier_jump", np.array([g.jump if g is not None else np.nan for g in graz], dtype=float), "1",
        "largest distance between the multipliers before and after, matched (NaN: not a grazing point)", allow_nan=True)


def _put_whirling(h, b) -> None:
    """A spatial branch's whirling measures (none on a planar cable's branch)."""
    if b.whirl_area is not None:
        put(h, "whirl_area", b.whirl_area, "m^2", "signed area of each node's path in its (w, v) "
            "cross-section plane over the orbit (positive counter-clockwise as seen from support A "
            "looking towards B; NaN: not measured)", allow_nan=True)
        put(h, "tilt", b.tilt, "deg", "angle of the orbit's mean plane of motion from the cable's plane",
            allow_nan=True)
    if getattr(b, "max_w", None) is not None:
        put(h, "max_w", b.max_w, "m", "largest out-of-plane displacement |w| of each node over the orbit "
            "(NaN: not measured)", allow_nan=True)
        put(h, "whirl_sense", np.asarray(b.whirl_sense, dtype="S"), "1", "sense in which each node goes "
            "round, seen from support A looking towards B: counter-clockwise, clockwise or none")


def write_continuation(path: str | Path, res, fingerprint: str | None = None) -> Path:
    """Write a :class:`~cablesim.analyses.continuation.ContinuationResult` atomically
    (``fingerprint``: of the case and settings, :func:`cablesim.io.journal.fingerprint`, stored
    as an attribute of ``/continuation`` for ``--resume``)."""
    unit = "rad/s" if res.parameter == "omega" else "1"
    amplitudes = dict(getattr(res, "support_amplitudes", {}) or {})
    with atomic_h5(path) as f:
        stamp(f, res.case_text, "continue", analysis=res.analysis)
        g = f.create_group("continuation")
        for k, v in dict(parameter=res.parameter, start=res.start, stop=res.stop, fixed=res.fixed,
                         case_name=res.case_name).items():
            g.attrs[k] = v
        if res.parameter != "gamma":
            g.attrs["gamma"] = float(getattr(res, "fixed_gamma", 1.0))  # the fixed gamma
        if amplitudes:
            ds = put(g, "support_amplitude", np.array(list(amplitudes.values()), dtype=float), "m",
                     "amplitude of each moving support at support multiplier s = 1 and gamma = 1, as supports: gives it")
            ds.attrs["supports"] = np.array(list(amplitudes), dtype="S")
        _put_state(g, res, fingerprint)
        bg = g.create_group("branches")
        for k, b in enumerate(res.branches):
            h = bg.create_group(b.name)
            h.attrs.update(period=b.period, parent=-1 if b.parent is None else b.parent, end=b.end, index=k)
            h.attrs["channels"] = np.array(res.channels, dtype="S")
            put(h, "parameter", b.parameter, unit, f"continuation parameter ({res.parameter})")
            put(h, "omega", b.omega, "rad/s", "forcing frequency")
            put(h, "gamma", b.gamma, "1", "scale of the harmonic loads FL and of the supports' motion")
            _put_support(h, b.support if b.support is not None else np.ones(b.parameter.size), amplitudes)
            put(h, "amplitude", b.amplitude, "m", "largest |z| over the orbit, per channel")
            put(h, "halfrange", b.halfrange, "m", "half the peak-to-peak range over the orbit, per channel")
            put(h, "stable", b.stable, "1", "all Floquet multipliers inside the unit circle (but a neutral one "
                "forced by a symmetry, neutral_residual)")
            put(h, "trusted", b.trusted, "1", "multipliers passed the residual and Liouville checks")
            put(h, "multipliers", b.multipliers, "1", "Floquet multipliers, by decreasing modulus")
            put(h, "state", b.state, "m, m/s", "(z, y') at forcing phase 0")
            if getattr(b, "strain", None) is not None:
                put(h, "strain", b.strain, "1", "largest strain (l - S) / S of any segment over the orbit (NaN: not "
                    "measured)", allow_nan=True)
                put(h, "strained", b.strained, "1", "the orbit's strain is beyond the model's small strains")
            _put_neutral(h, b)
            if getattr(b, "slack", None) is not None:
                _put_slack(h, b.slack)
            if b.planes is not None:
                put(h, "multiplier_plane", np.asarray(b.planes, dtype="S"), "1",
                    "block of each multiplier: in-plane, out-of-plane (a planar orbit of a symmetric "
                    "spatial cable) or coupled")
            h.attrs["planar"] = bool(b.planar)
            h.attrs["mirror_image"] = bool(b.mirror_image)
            _put_whirling(h, b)
        fg = g.create_group("bifurcations")
        bifs = res.bifurcations
        put(fg, "kind", np.array([b.kind for b in bifs], dtype="S"), "1", "fold, period-doubling, neimark-sacker")
        put(fg, "parameter", np.array([b.parameter for b in bifs], dtype=float), unit, "where")
        put(fg, "omega", np.array([b.omega for b in bifs], dtype=float), "rad/s", "forcing frequency")
        put(fg, "gamma", np.array([getattr(b, "gamma", 1.0) for b in bifs], dtype=float), "1",
            "scale of the harmonic loads FL and of the supports' motion")
        _put_support(fg, np.array([getattr(b, "support", 1.0) for b in bifs], dtype=float), amplitudes)
        put(fg, "branch", np.array([b.branch for b in bifs], dtype=int), "1", "index of the branch")
        put(fg, "period", np.array([b.period for b in bifs], dtype=int), "forcing periods", "of the orbit")
        put(fg, "amplitude", np.array([b.amplitude for b in bifs], dtype=float).reshape(len(bifs), len(res.channels)),
            "m", "largest |z| over the orbit, per channel")
        put(fg, "multiplier", np.array([b.multiplier for b in bifs], dtype=complex), "1", "critical multiplier")
        put(fg, "located", np.array([b.located for b in bifs], dtype=bool), "1", "location converged")
        put(fg, "trusted", np.array([b.trusted for b in bifs], dtype=bool), "1", "multipliers trusted")
        put(fg, "plane", np.array([b.plane for b in bifs], dtype="S"), "1",
            "block of the critical multiplier: in-plane, out-of-plane or coupled")
        put(fg, "frequency_ratio", np.array([b.frequency_ratio for b in bifs], dtype=float), "1",
            "|arg(mu)| / 2 pi of the critical multiplier (0: fold, pitchfork; 1/2: period doubling)")
        if getattr(res, "through_slack", False):
            g.attrs["through_slack"] = True
            _put_grazing(fg, bifs)
        if getattr(res, "loci_range", None) is not None:
            write_loci(g, res)  # bifurcation curves (cablesim.io.charts)
        m = f.create_group("modal")
        put(m, "omega", res.modal_omega, "rad/s", "linear modal frequencies about the equilibrium")
    return Path(path)


def read_continuation(path: str | Path) -> dict:
    """Read a continuation file into plain arrays.

    Returns
    -------
    dict
        ``parameter``, ``start``, ``stop``, ``fixed``, ``gamma`` (the fixed gamma; 1 in gamma), ``channels``,
        ``case_name``, ``analysis``, ``complete``, ``components``, ``through_slack``, ``modal`` (rad/s),
        ``support_amplitudes`` (support
        name -> amplitude, m, at support multiplier 1; empty if none moves, or a file written before
        it was stored), ``branches`` (list of dicts with the datasets and ``name``, ``period``,
        ``parent``, ``end``, in file order), ``bifurcations`` (dict of arrays) and ``loci``
        (:func:`~cablesim.io.charts.read_loci`, None without bifurcation curves).
    """
    path = Path(path)
    with open_result(path, "continuation", "continuation", "cablesim continue") as f:
        try:
            out = _read(f, path)
        except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
            raise CablesimError(f"{path} is not a continuation file as cablesim continue writes it: {_what(exc)}. "
                                "It may be damaged or edited; run cablesim continue again to rebuild it.") from None
    for b in out["branches"]:
        _check_branch(path, b, len(out["channels"]))
    return out


def _what(exc: Exception) -> str:
    """The first line of an exception's text, for a message."""
    text = str(exc).strip().strip("'\"").splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def _check_branch(path: Path, b: dict, n_chan: int) -> None:
    """Refuse a branch whose datasets do not fit together (a damaged or edited file)."""
    n = np.asarray(b["parameter"]).size
    for key, shape in (("omega", (n,)), ("gamma", (n,)), ("stable", (n,)), ("trusted", (n,)),
                       ("amplitude", (n, n_chan)), ("halfrange", (n, n_chan))):
        if key not in b or np.shape(b[key]) != shape:
            got = "is missing" if key not in b else f"has shape {np.shape(b[key])}, not {shape}"
            raise CablesimError(f"{path} is not a continuation file as cablesim continue writes it: branch "
                                f"{b['name']}'s {key} {got}. It may be damaged or edited; run cablesim continue "
                                "again to rebuild it.")


def _read(f, path: Path) -> dict:
    """The body of :func:`read_continuation` (``f`` open)."""
    g = f["continuation"]
    out = {k: g.attrs[k] for k in ("start", "stop", "fixed")}
    out["parameter"] = attr_text(g.attrs["parameter"])
    out["gamma"] = float(g.attrs.get("gamma", out["fixed"] if out["parameter"] == "omega" else 1.0))
    out["support_amplitudes"] = {}
    if "support_amplitude" in g:
        ds = g["support_amplitude"]
        names = [attr_text(n) for n in np.asarray(ds.attrs["supports"]).ravel()]
        out["support_amplitudes"] = dict(zip(names, np.asarray(ds[()], dtype=float).reshape(len(names), -1)))
    out["complete"] = bool(g.attrs.get("complete", True))
    out["through_slack"] = bool(g.attrs.get("through_slack", False))
    out["case_name"] = attr_text(g.attrs.get("case_name", path.stem))
    out["channels"] = [attr_text(c) for c in np.asarray(g.attrs["channels"]).ravel()]
    out["analysis"] = attr_text(f.attrs.get("analysis", "exact"))
    out["modal"] = np.asarray(f["modal/omega"][()], dtype=float) if "modal/omega" in f else np.empty(0)
    branches = []
    for name, h in g["branches"].items():
        b = {k: np.asarray(h[k][()]) for k in h}
        b.setdefault("support", np.ones(np.asarray(b.get("parameter", ())).size))  # files before the support column
        for key in ("multiplier_plane", "whirl_sense"):
            if key in b:
                b[key] = np.char.decode(b[key].astype("S"))
        b["planar"] = bool(h.attrs.get("planar", False))
        b["mirror_image"] = bool(h.attrs.get("mirror_image", False))
        b.update(name=name, period=int(h.attrs["period"]), parent=int(h.attrs["parent"]),
                 end=attr_text(h.attrs["end"]), index=int(h.attrs.get("index", len(branches))))
        branches.append(b)
    out["branches"] = sorted(branches, key=lambda b: b["index"])
    fg = g["bifurcations"]
    bif = {k: np.asarray(fg[k][()]) for k in fg}
    bif["kind"] = [attr_text(k) for k in bif.get("kind", [])]
    if "plane" in bif:
        bif["plane"] = [attr_text(k) for k in bif["plane"]]
    out["bifurcations"] = bif
    out["loci"] = read_loci(g)
    spatial = any("whirl_area" in b for b in branches)  # (files written before the attribute)
    out["components"] = int(g.attrs.get("components", 3 if spatial else 2))
    return out
