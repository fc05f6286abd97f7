"""The ``fdr`` composite figure: the frequency response of several sweep files on shared axes.

One row per channel; one colour per file (or per gamma value of a file), line style per
sweep direction; the point classes of :func:`cablesim.plots.sweep.draw_curve`. A subharmonic
band too small to read beside the main resonance gets an inset with its own scale.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.hdf5 import attr_text
from ..io.sweeps import read_sweep, select_channels
from .base import bottom_notes, figure_width, legend_below, pyplot, save_atomic, title_line
from .style import COLOURS, SERIES, grid_step, symbols, to_resolution
from .sweep import DIRECTION_STYLE, channel_label, draw_curve, marker_handles, point_markers, sweep_conditions

#: Largest number of channel rows.
MAX_ROWS = 8
#: A subharmonic band gets an inset when its largest amplitude is below this fraction of the axes' top ...
SMALL_BAND = 0.25
#: ... or when it is narrower than this fraction of the frequency range.
NARROW_BAND = 0.05
#: Width of the inset (axes fraction).
INSET_WIDTH = 0.34


def _series(sweeps, names):
    """``(file index, gamma, label)`` of every curve colour, and the colour of each."""
    series = []
    for k, (sw, name) in enumerate(zip(sweeps, names)):
        for g in [None] if sw.gamma is None else list(sw.gamma):
            gamma = "" if g is None else f"$\\gamma$ = {g:g}"
            series.append((k, g, name if g is None else gamma if len(sweeps) == 1 else f"{name}, {gamma}"))
    colors = {(k, g): SERIES[r % len(SERIES)] for r, (k, g, _) in enumerate(series)}
    return series, colors


def _names(fig_spec, sweeps) -> list[str]:
    if fig_spec.labels is not None:
        return list(fig_spec.labels)
    names = [attr_text(sw.attrs.get("case_name", sw.path.stem)) for sw in sweeps]
    return names if len(set(names)) == len(names) else [sw.path.name for sw in sweeps]


def _channels(fig_spec, sweeps) -> list[str]:
    """The figure's channels (each must be in every file), else the first file's."""
    if fig_spec.channels is None:
        return list(sweeps[0].channels)
    chans = []
    for sw in sweeps:
        chans = [sw.channels[k] for k in select_channels(sw, fig_spec.channels)]
    return chans


def _modal_lines(sweeps, names, colors, x_lo: float, x_hi: float) -> list[tuple[str, list[float], str]]:
    """``(whose, frequencies, colour)`` of the modal lines: one grey set when every file has the
    same cable, else one set per file in its curve's colour (files of different cables, such as
    an approximate and an exact analysis, have different linear frequencies)."""
    per_file = [[float(w) for w in sw.modal if np.isfinite(w) and x_lo <= w <= x_hi] for sw in sweeps]
    if all(len(ws) == len(per_file[0]) and np.allclose(ws, per_file[0], rtol=1e-9, atol=0.0) for ws in per_file):
        return [("", per_file[0], COLOURS["reference"])] if per_file[0] else []
    first_colour = {}
    for (k, _), colour in colors.items():
        first_colour.setdefault(k, colour)
    return [(f" of {names[k]}", ws, first_colour[k]) for k, ws in enumerate(per_file) if ws]


def draw_fdr(fig_spec, infos, png: Path, title: str) -> Path:
    """Draw the ``fdr`` figure of the sweep files ``infos`` as ``png`` (see the module)."""
    from matplotlib.lines import Line2D  # matplotlib loads only when drawing

    sweeps = [read_sweep(i.path) for i in infos]
    names = [symbols(nm) for nm in _names(fig_spec, sweeps)]
    chans = _channels(fig_spec, sweeps)
    notes = []
    if len(chans) > MAX_ROWS:
        notes.append(f"showing the first {MAX_ROWS} of {len(chans)} channels")
        chans = chans[:MAX_ROWS]
    series, colors = _series(sweeps, names)
    lo = min(float(sw.omega[0]) for sw in sweeps)
    hi = max(float(sw.omega[-1]) for sw in sweeps)
    pad = 0.02 * (hi - lo) if hi > lo else max(0.05 * abs(lo), 0.1)
    x_lo, x_hi = lo - pad, hi + pad
    modal = _modal_lines(sweeps, names, colors, x_lo, x_hi)

    plt = pyplot()
    fig = plt.figure(figsize=(figure_width(), 1.6 + 2.1 * len(chans)), layout="constrained")
    axes = fig.subplots(len(chans), 1, sharex=True, squeeze=False)[:, 0]
    markers = np.zeros(4, dtype=bool)  # not steady, subharmonic, stopped early, went slack
    marked = all(point_markers(sw.omega.size) for sw in sweeps)
    for ax, name in zip(axes, chans):
        markers |= _draw_row(ax, sweeps, name, colors, marked)
        for _, ws, colour in modal:
            for w in ws:
                ax.axvline(w, color=colour, ls=":", lw=0.9, alpha=0.8, zorder=1)
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel(channel_label(name, components=sweeps[0].attrs.get("components", 2)))
        subharmonic_inset(ax, sweeps, name, colors)
    axes[-1].set_xlim(x_lo, x_hi)
    axes[-1].set_xlabel("forcing frequency $\\omega$ (rad/s)")
    # one curve colour needs no legend entry unless the figure names it
    named = len(series) > 1 or fig_spec.labels is not None
    handles = [Line2D([], [], color=colors[(k, g)], lw=2.0, label=label) for k, g, label in series if named]
    for d in dict.fromkeys(cv.direction for sw in sweeps for cv in sw.curves):
        st = DIRECTION_STYLE[d]
        handles.append(Line2D([], [], ls=st["ls"], marker=st["marker"] if marked else "none", ms=st["ms"] + 1,
                              color="0.3", lw=1.2, label=st["label"]))
    handles += marker_handles(*markers)
    for whose, ws, colour in modal:
        handles.append(Line2D([], [], ls=":", color=colour, lw=1.0,
                              label=f"linear modal frequencies{whose} (" + ", ".join(f"{w:.4g}" for w in ws) + " rad/s)"))
    legend_below(fig, handles, ncol=2)
    incomplete = [f"{nm}: {sum(int(cv.data.done.sum()) for cv in sw.curves)} of {sw.omega.size * len(sw.curves)} points"
                  for sw, nm in zip(sweeps, names)
                  if sum(int(cv.data.done.sum()) for cv in sw.curves) < sw.omega.size * len(sw.curves)]
    if incomplete:
        notes.insert(0, "incomplete sweep(s): " + "; ".join(incomplete))
    bottom_notes(fig, notes, bool(incomplete))
    conditions = {sweep_conditions(sw) for sw in sweeps}
    title_line(fig, title, conditions.pop() if len(conditions) == 1 else None)
    return save_atomic(fig, png)


def _draw_row(ax, sweeps, name: str, colors, marked: bool) -> np.ndarray:
    """Every curve of channel ``name`` of every file; which point classes were drawn."""
    drawn = np.zeros(4, dtype=bool)
    for k, sw in enumerate(sweeps):
        if name not in sw.channels:
            continue
        c = sw.channels.index(name)
        for curve in sw.curves:
            drawn |= draw_curve(ax, sw.omega, curve, c, "amplitude", colors[(k, curve.gamma)], marked, 1.2)
    return drawn


def subharmonic_band(sweeps, name: str):
    """``(lowest, highest frequency, largest amplitude, grid step)`` of the steady subharmonic
    points of channel ``name``, or None when there are none."""
    w_sub, a_sub, steps = [], [], []
    for sw in sweeps:
        if name not in sw.channels:
            continue
        c = sw.channels.index(name)
        for curve in sw.curves:
            sub = curve.valid & curve.data.steady & (curve.data.period >= 2)
            a = curve.data.amplitude[:, c]
            sub &= np.isfinite(a)
            w_sub += list(sw.omega[sub])
            a_sub += list(a[sub])
        steps.append(grid_step(sw.omega))
    if not w_sub:
        return None
    return min(w_sub), max(w_sub), max(a_sub), float(np.nanmin(steps))


def subharmonic_inset(ax, sweeps, name: str, colors):
    """An inset of the subharmonic band of channel ``name`` on its own scale, when the band is
    low beside the axes' largest value or narrow beside the frequency range; placed clear of
    the main peak and of the band. Returns it or None."""
    band = subharmonic_band(sweeps, name)
    if band is None:
        return None
    w0, w1, a_max, step = band
    x_lo, x_hi = ax.get_xlim()
    width = w1 - w0 + (step if np.isfinite(step) else 0.0)
    if not (a_max < SMALL_BAND * ax.get_ylim()[1] or width < NARROW_BAND * (x_hi - x_lo)):
        return None
    margin = max(4 * step, 0.25 * (w1 - w0)) if np.isfinite(step) else 0.25 * (w1 - w0) + 0.05
    lo, hi = w0 - margin, w1 + margin
    x0 = inset_position([(v - x_lo) / (x_hi - x_lo) for v in (_peak_frequency(ax), lo, hi)])
    inset = ax.inset_axes([x0, 0.42, INSET_WIDTH, 0.46])
    _draw_row(inset, sweeps, name, colors, True)
    top = 1.3 * max(a_max, _largest_between(inset, lo, hi))
    inset.set_xlim(lo, hi)
    inset.set_ylim(0.0, top)
    inset.tick_params(labelsize=8, pad=1)
    inset.set_title(f"subharmonic band {to_resolution(w0, step)}\u2013{to_resolution(w1, step)} rad/s"
                    f" (step {step:.2g})", fontsize=8, pad=2)
    ax.indicate_inset([lo, 0.0, hi - lo, top], inset, edgecolor="0.4", lw=0.7)
    return inset


def inset_position(avoid, width: float = INSET_WIDTH, gap: float = 0.02) -> float:
    """Left edge (axes fraction) of an inset ``width`` wide that covers none of the positions
    ``avoid`` (axes fractions: the main peak, the band's edges), as close to the last ones as
    possible; the side away from the band when no place is clear."""
    candidates = np.linspace(0.1, 0.98 - width, 45)
    clear = [x for x in candidates if all(not (x - gap <= a <= x + width + gap) for a in avoid if np.isfinite(a))]
    if clear:
        target = np.nanmean(avoid[1:]) if len(avoid) > 1 else 0.5
        return float(min(clear, key=lambda x: abs(x + 0.5 * width - target)))
    return 0.12 if np.nanmean(avoid[1:]) > 0.5 else 0.98 - width


def _largest_between(ax, lo: float, hi: float) -> float:
    """The largest value of the curves drawn on ``ax`` between the frequencies ``lo`` and ``hi``."""
    best = 0.0
    for line in ax.get_lines():
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        inside = (x >= lo) & (x <= hi) & np.isfinite(y)
        if inside.any():
            best = max(best, float(y[inside].max()))
    return best


def _peak_frequency(ax) -> float:
    """Frequency of the largest value drawn on the axes (NaN if none)."""
    best, where = -np.inf, np.nan
    for line in ax.get_lines():
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        if line.get_transform() != ax.transData:  # reference lines (axvline) are not data
            continue
        if y.size and np.isfinite(y).any() and np.nanmax(y) > best:
            best, where = np.nanmax(y), x[np.nanargmax(y)]
    return float(where)
