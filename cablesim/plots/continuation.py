"""The response diagram of ``cablesim continue``: every periodic response, stable and unstable.

One panel per channel: amplitude (largest ``|z|`` over the orbit) against the continuation
parameter; stable orbits solid, unstable dashed, one colour per response period; points whose
multipliers failed the accuracy checks crossed in grey; bifurcations marked and named; linear
modal frequencies dotted; optionally a brute-force sweep's points on top. A spatial cable's
nonplanar (whirling) branches are drawn in colours of their own, thicker, their unstable orbits
dotted, and a last panel shows every branch's out-of-plane amplitude (the largest ``|w|`` over
the nodes; planar branches on zero). Through slack (``continuation.through_slack``) the orbits
on which a segment goes slack are shaded along the branches, and a last panel shows the peak
tension (snap load) of every segment against the parameter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.continuation import read_continuation, support_meaning
from ..io.sweeps import read_sweep
from .base import figure_grid, legend_below, save_atomic, title_line
from .style import COLOURS, SERIES, WORDS, styled
from .sweep import channel_label

#: Colour of each response period (period 1 first).
PERIOD_COLOURS = SERIES
#: Colour of the nonplanar (whirling) branches of a spatial cable, by their period (period 1
#: first): none of them a period colour, red (warnings) or orange (the forcing).
NONPLANAR_COLOURS = ("#0b7a75", "#b0306e", "#6b6b00")
#: Marker and short label of each bifurcation kind.
BIFURCATION_STYLE = {
    "fold": ("^", "F", "fold (multiplier +1)"),
    "period-doubling": ("s", "PD", "period doubling (multiplier -1)"),
    "neimark-sacker": ("D", "NS", "Neimark-Sacker (complex pair)"),
    "branch-point": ("o", "BP", "branch point"),
    "pitchfork": ("P", "PF", "pitchfork (out-of-plane multiplier +1: whirling)"),
    "grazing": ("v", "G", "grazing (a segment's tension reaches zero)"),
}


def stability_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the runs where ``mask`` holds, each extended by one point so
    that consecutive runs of opposite stability join."""
    runs, k, n = [], 0, mask.size
    while k < n:
        if mask[k]:
            j = k
            while j + 1 < n and mask[j + 1]:
                j += 1
            runs.append((max(k - 1, 0) if k else 0, min(j + 2, n)))
            k = j + 1
        else:
            k += 1
    return runs


def _branch_style(b: dict, colour) -> dict:
    """Line styles of a branch: stable and unstable orbits of a planar branch solid and dashed in
    its period's colour; of a nonplanar (whirling) branch solid and dotted in
    :data:`NONPLANAR_COLOURS`, thicker."""
    if _nonplanar(b):
        return {"stable": dict(ls="-", lw=2.2, color=colour), "unstable": dict(ls=":", lw=1.6, color=colour)}
    return {"stable": dict(ls="-", lw=1.6, color=colour), "unstable": dict(ls="--", lw=1.1, color=colour)}


def _nonplanar(b: dict) -> bool:
    """A branch of a spatial cable whose orbits leave the plane."""
    return "tilt" in b and not b.get("planar", False)


def _draw_branch(ax, b: dict, y: np.ndarray, colour, slack: np.ndarray | None = None, grazing=()) -> None:
    """Amplitudes ``y`` (one per orbit) of branch ``b`` against its parameter; ``slack``: the
    orbits to shade (default: those on which some segment goes slack, if recorded), the bands
    drawn from the ``grazing`` parameters between a taut and a slack orbit."""
    x = b["parameter"]
    stable = b["stable"].astype(bool)
    style = _branch_style(b, colour)
    for lo, hi in stability_runs(stable):
        ax.plot(x[lo:hi], y[lo:hi], zorder=3, **style["stable"])
    for lo, hi in stability_runs(~stable):
        ax.plot(x[lo:hi], y[lo:hi], zorder=2, **style["unstable"])
    slack = b["slack"].astype(bool) if slack is None and "slack" in b else slack
    if slack is not None:  # orbits with a slack segment: a wide pale band under the line
        _slack_bands(ax, x, y, slack, grazing, colour)
    bad = ~b["trusted"].astype(bool)
    if bad.any():
        ax.plot(x[bad], y[bad], "x", color=COLOURS["failed_point"], ms=4, zorder=4)


#: Opacity of the band under the orbits with a slack segment.
SLACK_ALPHA = 0.28


def _slack_bands(ax, x: np.ndarray, y: np.ndarray, slack: np.ndarray, grazing, colour) -> None:
    """Bands under the runs of slack orbits, each from the grazing point (in ``grazing``) between
    it and a taut neighbour, the value there interpolated linearly."""
    for lo, hi in _slack_runs(slack):
        xs, ys = list(x[lo:hi]), list(y[lo:hi])
        for k, inner, first in ((lo - 1, lo, True), (hi, hi - 1, False)):
            g = [p for p in grazing if 0 <= k < x.size and min(x[k], x[inner]) <= p <= max(x[k], x[inner])]
            if g and x[inner] != x[k]:
                w = (g[0] - x[k]) / (x[inner] - x[k])
                at = 0 if first else len(xs)
                xs.insert(at, g[0])
                ys.insert(at, y[k] + w * (y[inner] - y[k]))
        ax.plot(xs, ys, zorder=1, lw=6.0, alpha=SLACK_ALPHA, color=colour, solid_capstyle="butt")


def _slack_runs(mask: np.ndarray):
    """(start, stop) index pairs of the runs where ``mask`` holds (not extended)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return list(zip(edges[::2], edges[1::2]))


def _grazing_at(d: dict, k: int) -> list:
    """The parameters of the grazing points located on branch ``k``."""
    bif = d["bifurcations"]
    return [float(bif["parameter"][i]) for i, kind in enumerate(bif["kind"])
            if kind == "grazing" and int(bif["branch"][i]) == k]


def _slack_run(d: dict) -> bool:
    """A continuation through slack whose branches carry their snap loads."""
    return bool(d.get("through_slack", False)) and any("peak_tension" in b for b in d["branches"])


def _tension_panel(ax, d: dict, modal: list) -> None:
    """The peak tension (snap load) of every segment of every orbit against the parameter, a
    colour per segment, stable solid and unstable dashed, slack orbits shaded; MN or kN."""
    from matplotlib.lines import Line2D

    peak = max((float(np.max(b["peak_tension"], initial=0.0)) for b in d["branches"] if "peak_tension" in b),
               default=0.0)
    scale, unit = (1e6, "MN") if peak >= 1e6 else (1e3, "kN")
    segments = max((np.shape(b["peak_tension"])[1] for b in d["branches"] if "peak_tension" in b), default=0)
    for k, b in enumerate(d["branches"]):
        if "peak_tension" not in b:
            continue
        for j in range(segments):  # each segment's band where that segment goes slack
            _draw_branch(ax, b, np.asarray(b["peak_tension"])[:, j] / scale, SERIES[j % len(SERIES)],
                         np.asarray(b["slack_episodes"])[:, j] > 0, _grazing_at(d, k))
    handles = [Line2D([], [], color=SERIES[j % len(SERIES)], lw=1.6, label=f"segment {j + 1}") for j in range(segments)]
    ax.legend(handles=handles, fontsize=7, loc="best", ncol=min(segments, 4))
    _finish_panel(ax, modal, f"peak tension\n(snap load, {unit})")


def _largest_w(b: dict) -> np.ndarray:
    """The largest ``|w|`` over the nodes of every orbit of a branch, m (zero on planar ones)."""
    if "max_w" not in b:
        return np.zeros(b["parameter"].size)
    w = np.asarray(b["max_w"], dtype=float).reshape(b["parameter"].size, -1)
    return np.nanmax(w, axis=1, initial=0.0) if np.isfinite(w).any() else np.full(w.shape[0], np.nan)


def _mark_bifurcations(ax, xs, ys, kinds, span: float) -> None:
    """Each bifurcation's marker and short name, above its point (a label whose neighbour is
    close goes to the left, a third one higher up: below it would be under the axis for a small
    response)."""
    placed: list[tuple[float, float]] = []
    y_top = float(np.nanmax(ys)) if len(ys) else 0.0
    for k in np.argsort(np.asarray(xs, dtype=float)):
        if not np.isfinite(ys[k]):
            continue
        marker, short, _ = BIFURCATION_STYLE.get(kinds[k], ("o", kinds[k], kinds[k]))
        x, y = float(xs[k]), float(ys[k])
        ax.plot(x, y, marker, color=COLOURS["annotation"], mfc="white", ms=5, zorder=6)
        near = sum(abs(x - px) < 0.05 * span and abs(y - py) <= 0.1 * max(y_top, 1e-300) for px, py in placed)
        offset, ha = [((5, 6), "left"), ((-5, 6), "right"), ((5, 17), "left")][min(near, 2)]
        ax.annotate(short, (x, y), textcoords="offset points", xytext=offset, ha=ha, fontsize=8, zorder=7)
        placed.append((x, y))


def _bifurcation_w(d: dict, scale: float) -> np.ndarray:
    """The out-of-plane amplitude (largest ``|w|``, in units of ``scale`` m) at each bifurcation:
    that of the orbit of its branch nearest to it in the parameter and the channel amplitudes."""
    bif, out = d["bifurcations"], []
    lo, hi = sorted((float(d["start"]), float(d["stop"])))
    for k in range(len(bif["kind"])):
        idx = int(bif["branch"][k])
        if idx >= len(d["branches"]):
            out.append(np.nan)
            continue
        b = d["branches"][idx]
        amp = np.asarray(b["amplitude"], dtype=float)
        size = max(float(np.abs(amp).max(initial=0.0)), 1e-300)
        dist = (np.abs(b["parameter"] - bif["parameter"][k]) / max(hi - lo, 1e-300)
                + np.abs(amp - bif["amplitude"][k]).max(axis=1, initial=0.0) / size)
        out.append(_largest_w(b)[int(np.argmin(dist))] / scale if dist.size else np.nan)
    return np.array(out, dtype=float)


def _draw_overlay(ax, sweep, c_name: str) -> set:
    """A sweep's points of one channel; which kinds (``steady``, ``not steady``) were drawn."""
    drawn = set()
    if c_name not in sweep.channels:
        return drawn
    c = sweep.channels.index(c_name)
    for curve in sweep.curves:
        ok = curve.valid
        y = curve.data.amplitude[:, c]
        for kind, mask, colour in (("steady", ok & curve.data.steady, COLOURS["annotation"]),
                                   ("not steady", ok & ~curve.data.steady, COLOURS["failure"])):
            if mask.any():
                drawn.add(kind)
                ax.plot(sweep.omega[mask], y[mask], "o", ms=3.2, mfc="none", mec=colour, mew=0.7, zorder=5)
    return drawn


def parameter_axis(d: dict) -> tuple[str, str, str]:
    """The x-axis label, the parameter's symbol and the fixed conditions in words of the
    continuation file read as ``d`` (:func:`~cablesim.io.continuation.read_continuation`); in the
    support multiplier s the label says what s = 1 stands for (the supports' amplitudes)."""
    fixed_omega = f"$\\omega$ = {float(d['fixed']):g} rad/s"
    if d["parameter"] == "omega":
        return "forcing frequency $\\omega$ (rad/s)", "$\\omega$", f"$\\gamma$ = {float(d['fixed']):g}"
    if d["parameter"] == "gamma":
        return "load factor $\\gamma$ (multiplies $F_L$)", "$\\gamma$", fixed_omega
    meaning = support_meaning(d.get("support_amplitudes", {})).replace("|u_A|", "$|u_A|$").replace("|u_B|", "$|u_B|$")
    label = "support motion multiplier $s$" + (f" ({meaning})" if meaning else "")
    return label, "$s$", f"{fixed_omega}, $\\gamma$ = {float(d.get('gamma', 1.0)):g}"
def _colours(d: dict) -> dict:
    """Colour of every branch (by index): its period's, from :data:`NONPLANAR_COLOURS` for a
    nonplanar one."""
    planar = sorted({b["period"] for b in d["branches"] if not _nonplanar(b)})
    whirling = sorted({b["period"] for b in d["branches"] if _nonplanar(b)})
    out = {}
    for k, b in enumerate(d["branches"]):
        if _nonplanar(b):
            out[k] = NONPLANAR_COLOURS[whirling.index(b["period"]) % len(NONPLANAR_COLOURS)]
        else:
            out[k] = PERIOD_COLOURS[planar.index(b["period"]) % len(PERIOD_COLOURS)]
    return out


def _period_words(p: int) -> str:
    return f"period ${p}T$ (subharmonic 1/{p})" if p > 1 else "period $T$ of the forcing"


def _branch_handles(d: dict, colour: dict) -> list:
    """Legend entries of the branches: a colour per period (planar, then nonplanar) and the
    line styles of stable and unstable orbits of each kind."""
    from matplotlib.lines import Line2D

    handles, seen = [], set()
    spatial = any(_nonplanar(b) for b in d["branches"])
    for k, b in enumerate(d["branches"]):
        key = (_nonplanar(b), b["period"])
        if key in seen:
            continue
        seen.add(key)
        text = _period_words(b["period"])
        if spatial and not key[0]:
            text = f"planar, {text}"
        if key[0]:
            mirror = any(x.get("mirror_image", False) for x in d["branches"] if _nonplanar(x))
            text = (f"nonplanar (whirling), {text}"
                    + (";\neach with its mirror image $w \\to -w$ (same amplitudes)" if mirror else ""))
        handles.append((key, Line2D([], [], color=colour[k], lw=2.0, label=text)))
    handles = [h for _, h in sorted(handles, key=lambda kh: kh[0])]
    handles += [Line2D([], [], color="0.3", lw=1.6, label="stable, planar" if spatial else "stable"),
                Line2D([], [], color="0.3", ls="--", lw=1.1, label="unstable, planar" if spatial else "unstable")]
    if spatial:
        handles += [Line2D([], [], color="0.3", lw=2.2, label="stable, nonplanar"),
                    Line2D([], [], color="0.3", ls=":", lw=1.6, label="unstable, nonplanar")]
    return handles


def _other_handles(d: dict, overlaid: set, modal: list) -> list:
    """Legend entries of the bifurcations, untrusted points, a sweep drawn on top and the modal
    frequencies."""
    from matplotlib.lines import Line2D

    handles = []
    for kind in dict.fromkeys(d["bifurcations"]["kind"]):
        marker, short, text = BIFURCATION_STYLE.get(kind, ("o", kind, kind))
        handles.append(Line2D([], [], ls="none", marker=marker, color=COLOURS["annotation"], mfc="white",
                              label=f"{short}: {text}"))
    if any(np.any(b.get("slack", False)) for b in d["branches"]):
        handles.append(Line2D([], [], color="0.3", lw=6.0, alpha=SLACK_ALPHA, solid_capstyle="butt",
                              label="shaded: orbits on which a segment goes slack"))
    if any((~b["trusted"].astype(bool)).any() for b in d["branches"]):
        handles.append(Line2D([], [], ls="none", marker="x", color=COLOURS["failed_point"],
                              label="multipliers not trusted"))
    if "steady" in overlaid:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec=COLOURS["annotation"],
                              label="time integration: steady response"))
    if "not steady" in overlaid:
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec=COLOURS["failure"],
                              label=f"time integration: {WORDS['not steady']}"))
    if modal:
        handles.append(Line2D([], [], ls=":", color=COLOURS["reference"], label="linear modal frequencies"))
    return handles


def _finish_panel(ax, modal: list, label: str) -> None:
    for _, w in modal:
        ax.axvline(w, color=COLOURS["reference"], ls=":", lw=0.9, alpha=0.8, zorder=1)
    ax.set_ylim(bottom=0.0)
    ax.set_ylim(top=ax.get_ylim()[1] * 1.12)  # room above the highest bifurcation for its label
    ax.set_ylabel(label)


def _out_of_plane_panel(ax, d: dict, colour: dict, modal: list, span: float) -> None:
    """The largest ``|w|`` over the nodes of every orbit of every branch (planar ones on zero),
    in mm below 1 m."""
    peak = max((float(np.nanmax(_largest_w(b), initial=0.0)) for b in d["branches"]), default=0.0)
    scale, unit = (1e-3, "mm") if peak < 1.0 else (1.0, "m")
    for k, b in enumerate(d["branches"]):
        _draw_branch(ax, b, _largest_w(b) / scale, colour[k])
    bif = d["bifurcations"]
    if len(bif["kind"]):
        _mark_bifurcations(ax, bif["parameter"], _bifurcation_w(d, scale), bif["kind"], span)
    _finish_panel(ax, modal, f"out of plane: largest $|w|$\nover the nodes ({unit})")
    top = ax.get_ylim()[1] if peak > 0.0 else 1.0
    ax.set_ylim(-0.03 * top, top)  # the planar branches on zero, clear of the axis


@styled
def plot_continuation(h5_path, png_path=None, overlay=None, title: str | None = None) -> Path:
    """Draw a continuation file as a PNG.

    A spatial cable's diagram has a last panel, sharing the frequency axis, of the out-of-plane
    amplitude (the largest ``|w|`` over the nodes, of every branch: planar ones on zero), and
    draws its nonplanar (whirling) branches in their own colours, thicker, unstable orbits
    dotted.

    Parameters
    ----------
    h5_path : str or Path
        The HDF5 file written by ``cablesim continue``.
    png_path : str or Path, optional
        Default: ``h5_path`` with the suffix ``.png``.
    overlay : str or Path, optional
        A sweep file whose points are drawn on top (open circles: steady; red: not steady).
    title : str, optional
        Title; default ``"<case name>: periodic responses"`` (the conditions follow on a
        second, smaller line).

    Returns
    -------
    Path
    """
    d = read_continuation(h5_path)
    png_path = Path(h5_path).with_suffix(".png") if png_path is None else Path(png_path)
    sweep = read_sweep(overlay) if overlay is not None else None
    chans = d["channels"][:8]
    spatial = any("tilt" in b for b in d["branches"])
    colour = _colours(d)
    lo, hi = sorted((float(d["start"]), float(d["stop"])))
    pad = 0.02 * (hi - lo)
    is_omega = d["parameter"] == "omega"
    modal = [(k + 1, w) for k, w in enumerate(d["modal"]) if is_omega and lo - pad <= w <= hi + pad]
    slack = _slack_run(d)
    fig, axes = figure_grid(len(chans) + spatial + slack, 1, 2.1, sharex=True, extra_height=1.7)
    bif = d["bifurcations"]
    overlaid = set()
    for c, (ax, name) in enumerate(zip(axes[:, 0], chans)):
        for k, b in enumerate(d["branches"]):
            _draw_branch(ax, b, b["amplitude"][:, c], colour[k], grazing=_grazing_at(d, k))
        if len(bif["kind"]):
            _mark_bifurcations(ax, bif["parameter"], bif["amplitude"][:, c], bif["kind"], hi - lo)
        if sweep is not None and is_omega:
            overlaid |= _draw_overlay(ax, sweep, name)
        _finish_panel(ax, modal, channel_label(name, components=d.get("components", 3 if spatial else 2)))
    if spatial:
        _out_of_plane_panel(axes[len(chans), 0], d, colour, modal, hi - lo)
    if slack:
        _tension_panel(axes[-1, 0], d, modal)
    axes[-1, 0].set_xlim(lo - pad, hi + pad)
    axes[-1, 0].set_xlabel(parameter_axis(d)[0])
    legend_below(fig, _branch_handles(d, colour) + _other_handles(d, overlaid, modal), ncol=2)
    title_line(fig, title or f"{d['case_name']}: periodic responses", _conditions(d))
    return save_atomic(fig, png_path)


def _conditions(d: dict) -> str:
    """The second title line: analysis, continuation, branches, orbits and bifurcations found."""
    counts = {}
    for kind in d["bifurcations"]["kind"]:
        counts[kind] = counts.get(kind, 0) + 1
    found = ", ".join(f"{n} {BIFURCATION_STYLE.get(k, ('', k, ''))[1]}" for k, n in counts.items()) or "none"
    _, symbol, fixed = parameter_axis(d)
    n = len(d["branches"])
    whirling = sum(_nonplanar(b) for b in d["branches"])
    return (f"{d['analysis']} analysis; continuation in {symbol}, {fixed}; {n} branch{'es' if n != 1 else ''}"
            + (f" ({whirling} nonplanar)" if whirling else "")
            + f", {sum(b['parameter'].size for b in d['branches'])} orbits; bifurcations: {found}"
            + ("" if d.get("complete", True) else "; INTERRUPTED: only the orbits computed until then"))
