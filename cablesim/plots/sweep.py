"""Frequency-response (FDR) plot of a sweep file (layout: :func:`cablesim.io.hdf5.write_sweep`).

One subplot per channel against the forcing frequency; channels are named as in
:mod:`cablesim.channels`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..channels import channel_description
from ..errors import CablesimError
from ..io.hdf5 import attr_text
from ..io.report import grid_note
from ..io.sweeps import StoredSweep, read_sweep, select_channels
from .base import bottom_notes, figure_grid, legend_below, save_atomic, title_line
from .style import COLOURS, SERIES, WORDS, channel_tex, styled

#: Largest number of channels drawn (one subplot each).
MAX_CHANNELS = 8
#: The quantities that can be plotted, with their axis wording.
QUANTITIES = {"amplitude": "peak $|z|$", "halfrange": "half range"}
#: Curve colours, one per gamma value (never the warning red).
GAMMA_COLOURS = list(SERIES)
#: Line style and marker of each sweep direction (the markers are drawn only on sparse grids,
#: where they show the computed frequencies).
DIRECTION_STYLE = {
    "independent": dict(ls="-", marker="o", ms=2.5, label=WORDS["independent"]),
    "up": dict(ls="-", marker=">", ms=3.5, label=WORDS["up"]),
    "down": dict(ls="--", marker="<", ms=3.5, label=WORDS["down"]),
}
#: Grids with more points than this are drawn as lines without point markers.
MARKED_POINTS = 60


def _check_quantity(quantity: str) -> str:
    if quantity not in QUANTITIES:
        raise CablesimError(f"Unknown quantity {quantity!r}; choose one of {', '.join(QUANTITIES)}.")
    return quantity


# --------------------------------------------------------------------------------------------
# The plot
# --------------------------------------------------------------------------------------------


def period_runs(mask: np.ndarray, values: np.ndarray):
    """Start indices of the runs of equal ``values`` where ``mask`` holds."""
    starts = []
    prev = None
    for k in range(mask.size):
        if mask[k] and (prev is None or values[k] != values[prev] or prev != k - 1):
            starts.append(k)
        if mask[k]:
            prev = k
    return starts


def sweep_conditions(sweep: StoredSweep) -> str:
    """The conditions of a sweep in one line: analysis, integrator, start, time limit per point."""
    d = sweep.direction
    dir_text = {"independent": WORDS["independent"], "up": "increasing frequency", "down": "decreasing frequency",
                "both": "increasing and decreasing frequency"}[d]
    analysis = f"{sweep.analysis} analysis"
    if "integrator" in sweep.attrs:
        analysis += f" ({attr_text(sweep.attrs['integrator'])})"
    parts = [analysis, dir_text]
    grid = grid_note(sweep.omega, sweep.attrs.get("refine"), sweep.attrs.get("grid_points"),
                     sweep.attrs.get("finest_step"))
    if grid:
        parts.append(grid)
    if "cap" in sweep.attrs:
        cap = f"at most {float(sweep.attrs['cap']):.4g} s per point"
        if "window" in sweep.attrs:
            cap += f", steady over the last {float(sweep.attrs['window']):.4g} s"
        parts.append(cap)
    return "; ".join(parts)


def point_markers(n_points: int) -> bool:
    """Whether the computed points of a curve get markers (sparse grids only)."""
    return n_points <= MARKED_POINTS


def draw_curve(ax, omega, curve, c: int, quantity: str, color, marked: bool, lw: float = 1.2):
    """One sweep curve of channel ``c``: a line through its steady points only (markers on each
    if ``marked``), broken where the response period changes; points that reached the time
    limit without a steady state as red open circles and points that stopped early (a segment
    went slack) as grey crosses at their partial values, neither joined into the line;
    subharmonic points as black diamonds labelled ``1/p``. Returns which markers were drawn:
    ``(not steady, subharmonic, stopped early, went slack)``."""
    valid = curve.valid
    steady = valid & curve.data.steady
    period = curve.data.period
    values = curve.data[quantity][:, c]
    y = np.where(steady, values, np.nan)
    # break the line between responses of different period (different branches)
    jumps = np.flatnonzero(steady[:-1] & steady[1:] & (period[:-1] != period[1:]))
    x_line, y_line = np.insert(omega, jumps + 1, np.nan), np.insert(y, jumps + 1, np.nan)
    st = DIRECTION_STYLE[curve.direction]
    ax.plot(x_line, y_line, ls=st["ls"], marker=st["marker"] if marked else "none", ms=st["ms"], color=color,
            lw=lw, zorder=2)
    unsteady = valid & ~curve.data.steady & np.isfinite(values)
    if unsteady.any():
        ax.plot(omega[unsteady], values[unsteady], ls="none", marker="o", ms=7, mfc="none",
                mec=COLOURS["failure"], mew=1.1, zorder=4)
    failed = curve.failed & np.isfinite(values)
    if failed.any():
        ax.plot(omega[failed], values[failed], ls="none", marker="x", ms=6, color=COLOURS["failed_point"], mew=1.2,
                zorder=4)
    went_slack = valid & curve.data.went_slack & np.isfinite(values)
    if went_slack.any():
        ax.plot(omega[went_slack], values[went_slack], ls="none", marker="s", ms=6, mfc="none",
                mec=COLOURS["failure"], mew=0.9, zorder=4)
    sub = steady & (period >= 2) & np.isfinite(y)
    if sub.any():
        ax.plot(omega[sub], y[sub], ls="none", marker="D", ms=3.5, color=COLOURS["annotation"], zorder=5)
        for k in period_runs(sub, period):
            ax.annotate(f"1/{period[k]}", (omega[k], y[k]), textcoords="offset points",
                        xytext=(0, 7), ha="center", va="bottom", fontsize=8, color=COLOURS["annotation"], zorder=6,
                        bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    return bool(unsteady.any()), bool(sub.any()), bool(failed.any()), bool(went_slack.any())


def channel_label(name: str, quantity: str = "amplitude", components: int = 2) -> str:
    """Axis label of a channel, e.g. ``"$z_{2}$: peak $|z|$ (m)\nnode 1, vertical (down +)"``
    (``components`` per node: 2 planar, 3 spatial)."""
    desc = f"\n{channel_description(int(name[1:]) - 1, components)}" if name[1:].isdigit() else ""
    return f"{channel_tex(name)}: {QUANTITIES[quantity]} (m){desc}"


def _draw_channel(ax, sweep: StoredSweep, c: int, quantity: str, color_of, marked: bool):
    """Every curve of channel ``c``; which markers were drawn (see :func:`draw_curve`)."""
    drawn = np.zeros(4, dtype=bool)
    for curve in sweep.curves:
        drawn |= draw_curve(ax, sweep.omega, curve, c, quantity, color_of(curve), marked)
    ax.set_ylim(bottom=0.0)
    ax.set_ylabel(channel_label(sweep.channels[c], quantity, sweep.attrs.get("components", 2)))
    return tuple(bool(x) for x in drawn)


def _legend(sweep: StoredSweep, gammas, colors, markers, modal_k, marked: bool) -> list:
    """Proxy artists: colours = gamma values, line styles = directions, markers."""
    from matplotlib.lines import Line2D

    handles = []
    if gammas:
        many = len(gammas) > 12
        shown = [0, len(gammas) - 1] if many else list(range(len(gammas)))
        for r in shown:
            handles.append(Line2D([], [], color=colors[r], lw=2.5, label=f"$\\gamma$ = {gammas[r]:g}"))
            if many and r == 0:  # the colours run between the first and the last
                handles.append(Line2D([], [], ls="none", label=f"... ({len(gammas) - 2} more)"))
    style_color = "0.3" if gammas else colors[0]
    for d in dict.fromkeys(cv.direction for cv in sweep.curves):
        st = DIRECTION_STYLE[d]
        handles.append(Line2D([], [], ls=st["ls"], marker=st["marker"] if marked else "none", ms=st["ms"] + 1,
                              color=style_color, lw=1.2, label=st["label"]))
    handles += marker_handles(*markers)
    if modal_k:
        handles.append(Line2D([], [], ls=":", color=COLOURS["reference"], lw=1.0, label="linear modal frequencies"))
    return handles


@styled
def plot_sweep(h5_path, png_path=None, channels=None, quantity: str = "amplitude", title: str | None = None) -> Path:
    """Draw the frequency response of a sweep file as a PNG.

    One subplot per channel, stacked and sharing the frequency axis: the response amplitude
    (or half range) in metres against the forcing frequency in rad/s. Independent sweeps are
    solid lines; up sweeps solid lines, down sweeps dashed lines (on grids of at most
    :data:`MARKED_POINTS` frequencies with a dot, ``>`` or ``<`` on each computed point); one
    colour per gamma value. Points whose response did not become steady within the time limit
    are ringed in red, points that stopped early (a segment went slack) crossed in grey; points with a subharmonic response (period of
    2 or more forcing periods) get a black diamond and a ``1/p`` label at the start of each run.
    Linear modal frequencies inside the frequency range are faint dotted lines. Points not
    computed (an interrupted sweep) are left out and counted in a note under the plot.

    Parameters
    ----------
    h5_path : str or Path
        The HDF5 file written by ``cablesim sweep``.
    png_path : str or Path, optional
        PNG to write; default: ``h5_path`` with the suffix ``.png``.
    channels : str or int or sequence of those, optional
        Channels to draw, e.g. ``["z2", "z4"]``; they must have been recorded in the file.
        Default: all recorded channels (at most 8 are drawn).
    quantity : {"amplitude", "halfrange"}, optional
        Peak displacement from the equilibrium, or half the peak-to-peak range.
    title : str, optional
        Title; default ``"<case_name>: frequency response"`` (the conditions follow on a
        second, smaller line).

    Returns
    -------
    Path
        The PNG written.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5 or not a sweep file, a channel is unknown or the
        quantity is unknown.
    """
    _check_quantity(quantity)
    sweep = read_sweep(h5_path)
    chans = select_channels(sweep, channels)
    notes = []
    if len(chans) > MAX_CHANNELS:
        notes.append(f"showing the first {MAX_CHANNELS} of {len(chans)} chosen channels")
        chans = chans[:MAX_CHANNELS]
    png_path = Path(h5_path).with_suffix(".png") if png_path is None else Path(png_path)
    omega = sweep.omega
    P = omega.size
    lo, hi = float(omega[0]), float(omega[-1])
    pad = 0.02 * (hi - lo) if hi > lo else max(0.05 * abs(lo), 0.1)
    x_lo, x_hi = lo - pad, hi + pad
    marked = point_markers(P)
    gammas = [] if sweep.gamma is None else list(sweep.gamma)
    colors = gamma_colours(len(gammas))

    def color_of(curve):
        return colors[0] if curve.gamma is None else colors[gammas.index(curve.gamma)]

    modal_k = [(k + 1, w) for k, w in enumerate(sweep.modal) if np.isfinite(w) and x_lo <= w <= x_hi]
    fig, axes = figure_grid(len(chans), 1, 2.0, sharex=True, extra_height=1.5)
    markers = np.zeros(4, dtype=bool)  # not steady, subharmonic, stopped early, went slack
    for ax, c in zip(axes[:, 0], chans):
        markers |= _draw_channel(ax, sweep, c, quantity, color_of, marked)
        for _, w in modal_k:
            ax.axvline(w, color=COLOURS["reference"], ls=":", lw=0.9, alpha=0.8, zorder=1)
    name_modal_lines(axes[0, 0], modal_k, x_hi - x_lo)
    axes[-1, 0].set_xlim(x_lo, x_hi)
    axes[-1, 0].set_xlabel("forcing frequency $\\omega$ (rad/s)")
    legend_below(fig, _legend(sweep, gammas, colors, markers, modal_k, marked), ncol=2)
    warn = _incomplete_note(sweep, notes)
    if not any(int(cv.data.done.sum()) for cv in sweep.curves):
        axes[0, 0].text(0.5, 0.5, "no computed points", transform=axes[0, 0].transAxes, ha="center",
                        va="center", color=COLOURS["failure"], fontsize=10)
    first = title if title is not None else f"{attr_text(sweep.attrs.get('case_name', sweep.path.stem))}: frequency response"
    title_line(fig, first, sweep_conditions(sweep))
    bottom_notes(fig, notes, warn)
    return save_atomic(fig, png_path)


def gamma_colours(n: int) -> list:
    """One colour per gamma value (a colour map beyond the series colours)."""
    if n <= len(GAMMA_COLOURS):
        return GAMMA_COLOURS[: max(1, n)]
    import matplotlib  # matplotlib loads only when drawing

    cmap = matplotlib.colormaps["viridis"]
    return [cmap(v) for v in np.linspace(0.0, 0.9, n)]


def name_modal_lines(top_ax, modal_k, x_range: float) -> None:
    """Name the modal frequency lines above the top axes (those that have room)."""
    last_text = -np.inf
    for k, w in modal_k:
        if w - last_text >= 0.09 * x_range:
            last_text = w
            top_ax.text(w, 1.01, f"$\\omega_{{{k}}}$ = {w:.4g}", transform=top_ax.get_xaxis_transform(), fontsize=8,
                        color=COLOURS["reference"], ha="center", va="bottom")


def _incomplete_note(sweep: StoredSweep, notes: list) -> bool:
    """Put the note of an incomplete sweep first in ``notes``; whether the sweep is incomplete."""
    P = sweep.omega.size
    total = P * len(sweep.curves)
    done = sum(int(cv.data.done.sum()) for cv in sweep.curves)
    if done >= total:
        return False
    text = f"incomplete sweep: {done} of {total} points"
    short = [f"{cv.label}: {int(cv.data.done.sum())} of {P}" for cv in sweep.curves if cv.data.done.sum() < P]
    if len(sweep.curves) > 1:
        more = f"; and {len(short) - 4} more curves" if len(short) > 4 else ""
        text += " (" + "; ".join(short[:4]) + more + ")"
    notes.insert(0, text)
    return True


def marker_handles(any_unsteady: bool, any_sub: bool, any_failed: bool = False, any_slack: bool = False) -> list:
    """Legend entries for the point markers of a frequency-response plot (those present)."""
    from matplotlib.lines import Line2D

    handles = []
    if any_unsteady:
        handles.append(Line2D([], [], ls="none", marker="o", ms=7, mfc="none", mec=COLOURS["failure"], mew=1.1,
                              label=WORDS["not steady"]))
    if any_sub:
        handles.append(Line2D([], [], ls="none", marker="D", ms=3.5, color=COLOURS["annotation"],
                              label=WORDS["subharmonic"]))
    if any_failed:
        handles.append(Line2D([], [], ls="none", marker="x", ms=6, color=COLOURS["failed_point"], mew=1.2,
                              label=WORDS["failed"]))
    if any_slack:
        handles.append(Line2D([], [], ls="none", marker="s", ms=6, mfc="none", mec=COLOURS["failure"], mew=0.9,
                              label=WORDS["went slack"]))
    return handles
