"""The response diagram of ``cablesim continue``: every periodic response, stable and unstable.

One panel per channel: amplitude (largest ``|z|`` over the orbit) against the continuation
parameter; stable orbits solid, unstable dashed, one colour per response period; points whose
multipliers failed the accuracy checks crossed in grey; bifurcations marked and named; linear
modal frequencies dotted; optionally a brute-force sweep's points on top.
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
#: Marker and short label of each bifurcation kind.
BIFURCATION_STYLE = {
    "fold": ("^", "F", "fold (multiplier +1)"),
    "period-doubling": ("s", "PD", "period doubling (multiplier -1)"),
    "neimark-sacker": ("D", "NS", "Neimark-Sacker (complex pair)"),
    "branch-point": ("o", "BP", "branch point"),
    "pitchfork": ("P", "PF", "pitchfork (out-of-plane multiplier +1: whirling)"),
    "grazing": ("v", "G", "grazing (a segment's tension reaches zero)"),
}


def _runs(mask: np.ndarray):
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


def _draw_branch(ax, b: dict, c: int, colour) -> None:
    x, y = b["parameter"], b["amplitude"][:, c]
    stable = b["stable"].astype(bool)
    for lo, hi in _runs(stable):
        ax.plot(x[lo:hi], y[lo:hi], "-", color=colour, lw=1.6, zorder=3)
    for lo, hi in _runs(~stable):
        ax.plot(x[lo:hi], y[lo:hi], "--", color=colour, lw=1.1, zorder=2)
    bad = ~b["trusted"].astype(bool)
    if bad.any():
        ax.plot(x[bad], y[bad], "x", color=COLOURS["failed_point"], ms=4, zorder=4)


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


@styled
def plot_continuation(h5_path, png_path=None, overlay=None, title: str | None = None) -> Path:
    """Draw a continuation file as a PNG.

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
    from matplotlib.lines import Line2D  # matplotlib loads only when drawing

    d = read_continuation(h5_path)
    png_path = Path(h5_path).with_suffix(".png") if png_path is None else Path(png_path)
    sweep = read_sweep(overlay) if overlay is not None else None
    chans = d["channels"][:8]
    periods = sorted({b["period"] for b in d["branches"]})
    colour = {p: PERIOD_COLOURS[i % len(PERIOD_COLOURS)] for i, p in enumerate(periods)}
    lo, hi = sorted((float(d["start"]), float(d["stop"])))
    pad = 0.02 * (hi - lo)
    is_omega = d["parameter"] == "omega"
    modal = [(k + 1, w) for k, w in enumerate(d["modal"]) if is_omega and lo - pad <= w <= hi + pad]
    fig, axes = figure_grid(len(chans), 1, 2.1, sharex=True, extra_height=1.7)
    bif = d["bifurcations"]
    overlaid = set()
    for c, (ax, name) in enumerate(zip(axes[:, 0], chans)):
        for b in d["branches"]:
            _draw_branch(ax, b, c, colour[b["period"]])
        placed: list[tuple[float, float]] = []
        y_top = float(np.nanmax(bif["amplitude"][:, c])) if len(bif["kind"]) else 0.0
        for k in np.argsort(np.asarray(bif["parameter"], dtype=float)) if len(bif["kind"]) else ():
            marker, short, _ = BIFURCATION_STYLE.get(bif["kind"][k], ("o", bif["kind"][k], bif["kind"][k]))
            x, y = float(bif["parameter"][k]), float(bif["amplitude"][k, c])
            ax.plot(x, y, marker, color=COLOURS["annotation"], mfc="white", ms=5, zorder=6)
            # above the point (below it would be under the axis for a small response); a label
            # whose neighbour is close goes to the left, a third one higher up
            near = sum(abs(x - px) < 0.05 * (hi - lo) and abs(y - py) <= 0.1 * max(y_top, 1e-300) for px, py in placed)
            offset, ha = [((5, 6), "left"), ((-5, 6), "right"), ((5, 17), "left")][min(near, 2)]
            ax.annotate(short, (x, y), textcoords="offset points", xytext=offset, ha=ha, fontsize=8, zorder=7)
            placed.append((x, y))
        if sweep is not None and is_omega:
            overlaid |= _draw_overlay(ax, sweep, name)
        for _, w in modal:
            ax.axvline(w, color=COLOURS["reference"], ls=":", lw=0.9, alpha=0.8, zorder=1)
        ax.set_ylim(bottom=0.0)
        ax.set_ylim(top=ax.get_ylim()[1] * 1.12)  # room above the highest bifurcation for its label
        ax.set_ylabel(channel_label(name, components=d.get("components", 2)))
    axes[-1, 0].set_xlim(lo - pad, hi + pad)
    xlabel, symbol, fixed = parameter_axis(d)
    axes[-1, 0].set_xlabel(xlabel)
    handles = [Line2D([], [], color=colour[p], lw=2.0,
                      label=f"period ${p}T$ (subharmonic 1/{p})" if p > 1 else "period $T$ of the forcing")
               for p in periods]
    handles += [Line2D([], [], color="0.3", lw=1.6, label="stable"), Line2D([], [], color="0.3", ls="--", lw=1.1,
                                                                             label="unstable")]
    for kind in dict.fromkeys(bif["kind"]):
        marker, short, text = BIFURCATION_STYLE.get(kind, ("o", kind, kind))
        handles.append(Line2D([], [], ls="none", marker=marker, color=COLOURS["annotation"], mfc="white",
                              label=f"{short}: {text}"))
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
    legend_below(fig, handles, ncol=2)
    counts = {}
    for kind in bif["kind"]:
        counts[kind] = counts.get(kind, 0) + 1
    found = ", ".join(f"{n} {BIFURCATION_STYLE.get(k, ('', k, ''))[1]}" for k, n in counts.items()) or "none"
    first = title or f"{d['case_name']}: periodic responses"
    sub = (f"{d['analysis']} analysis; continuation in {symbol}, {fixed}; {len(d['branches'])} branch{'es' if len(d['branches']) != 1 else ''}, "
           f"{sum(b['parameter'].size for b in d['branches'])} orbits; bifurcations: {found}"
           + ("" if d.get("complete", True) else "; INTERRUPTED: only the orbits computed until then"))
    title_line(fig, first, sub)
    return save_atomic(fig, png_path)
