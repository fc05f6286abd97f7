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
from ..io.sweeps import StoredSweep, read_sweep, select_channels
from .base import figure_grid, save_atomic

#: Largest number of channels drawn (one subplot each).
MAX_CHANNELS = 8
#: The quantities that can be plotted, with their axis wording.
QUANTITIES = {"amplitude": "peak |z|", "halfrange": "half range"}
#: Curve colours, one per gamma value (red is kept for the non-steady markers).
GAMMA_COLOURS = ["C0", "C1", "C2", "C4", "C5", "C6", "C8", "C9", "C7"]
#: Line style and marker of each sweep direction.
DIRECTION_STYLE = {
    "independent": dict(ls="-", marker="o", ms=3.0, label="independent sweep"),
    "up": dict(ls="-", marker=">", ms=4.0, label="up sweep"),
    "down": dict(ls="--", marker="<", ms=4.0, label="down sweep"),
}


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


def _subtitle(sweep: StoredSweep, shown: list[str]) -> str:
    d = sweep.direction
    dir_text = {"independent": "independent points", "up": "up sweep", "down": "down sweep",
                "both": "up and down sweeps"}[d]
    parts = [f"channels {', '.join(shown)}", dir_text]
    if sweep.gamma is not None:
        parts.append(f"{sweep.gamma.size} gamma values")
    if "cap" in sweep.attrs:
        cap = f"cap {float(sweep.attrs['cap']):.4g} s per point"
        if "window" in sweep.attrs:
            cap += f" (window {float(sweep.attrs['window']):.4g} s)"
        parts.append(cap)
    if "integrator" in sweep.attrs:
        parts.append(attr_text(sweep.attrs["integrator"]))
    return ", ".join(parts)


def draw_curve(ax, omega, curve, c: int, quantity: str, color, markevery: int, lw: float = 1.2):
    """One sweep curve of channel ``c``: a line through its steady points only, broken where the
    response period changes; points that reached the cap without a steady state as red open
    circles and points that stopped early (a segment went slack) as grey crosses at their
    partial values, neither joined into the line; subharmonic points as black diamonds labelled
    ``1/p``. Returns which markers were drawn: ``(not steady, subharmonic, stopped early)``."""
    valid = curve.valid
    steady = valid & curve.data["steady"]
    period = curve.data["period"]
    values = curve.data[quantity][:, c]
    y = np.where(steady, values, np.nan)
    # break the line between responses of different period (different branches)
    jumps = np.flatnonzero(steady[:-1] & steady[1:] & (period[:-1] != period[1:]))
    x_line, y_line = np.insert(omega, jumps + 1, np.nan), np.insert(y, jumps + 1, np.nan)
    st = DIRECTION_STYLE[curve.direction]
    ax.plot(x_line, y_line, ls=st["ls"], marker=st["marker"], ms=st["ms"], color=color, lw=lw,
            markevery=markevery, zorder=2)
    unsteady = valid & ~curve.data["steady"] & np.isfinite(values)
    if unsteady.any():
        ax.plot(omega[unsteady], values[unsteady], ls="none", marker="o", ms=8, mfc="none",
                mec="red", mew=1.2, zorder=4)
    failed = curve.failed & np.isfinite(values)
    if failed.any():
        ax.plot(omega[failed], values[failed], ls="none", marker="x", ms=6, color="0.4", mew=1.2, zorder=4)
    went_slack = valid & curve.data["went_slack"] & np.isfinite(values)
    if went_slack.any():
        ax.plot(omega[went_slack], values[went_slack], ls="none", marker="s", ms=7, mfc="none", mec="C1", mew=1.0,
                zorder=4)
    sub = steady & (period >= 2) & np.isfinite(y)
    if sub.any():
        ax.plot(omega[sub], y[sub], ls="none", marker="D", ms=3.5, color="k", zorder=5)
        for k in period_runs(sub, period):
            ax.annotate(f"1/{period[k]}", (omega[k], y[k]), textcoords="offset points",
                        xytext=(0, 7), ha="center", va="bottom", fontsize=7, color="0.15", zorder=6,
                        bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))
    return bool(unsteady.any()), bool(sub.any()), bool(failed.any()), bool(went_slack.any())


def channel_label(name: str, quantity: str = "amplitude") -> str:
    """Axis label of a channel, e.g. ``"z2 peak |z| (m)\nnode 1, vertical (down +)"``."""
    desc = f"\n{channel_description(int(name[1:]) - 1)}" if name[1:].isdigit() else ""
    return f"{name} {QUANTITIES[quantity]} (m){desc}"


def _draw_channel(ax, sweep: StoredSweep, c: int, quantity: str, color_of, markevery: int):
    """Every curve of channel ``c``; which markers were drawn (see :func:`draw_curve`)."""
    drawn = np.zeros(4, dtype=bool)
    for curve in sweep.curves:
        drawn |= draw_curve(ax, sweep.omega, curve, c, quantity, color_of(curve), markevery)
    ax.set_ylim(bottom=0.0)
    ax.set_ylabel(channel_label(sweep.channels[c], quantity), fontsize=9)
    ax.grid(True, alpha=0.3)
    return tuple(bool(x) for x in drawn)


def _legend(sweep: StoredSweep, gammas, colors, markers, modal_k) -> list:
    """Proxy artists: colours = gamma values, line styles = directions, markers."""
    from matplotlib.lines import Line2D

    handles = []
    if gammas:
        shown = list(range(len(gammas))) if len(gammas) <= 12 else [0, len(gammas) - 1]
        for r in shown:
            handles.append(Line2D([], [], color=colors[r], lw=2.5, label=f"gamma = {gammas[r]:g}"))
            if len(shown) == 2 and r == 0:
                handles.append(Line2D([], [], ls="none", label=f"... ({len(gammas) - 2} more)"))
    style_color = "0.3" if gammas else colors[0]
    for d in dict.fromkeys(cv.direction for cv in sweep.curves):
        st = DIRECTION_STYLE[d]
        handles.append(Line2D([], [], ls=st["ls"], marker=st["marker"], ms=st["ms"] + 1, color=style_color,
                              lw=1.2, label=st["label"]))
    handles += marker_handles(*markers)
    if modal_k:
        handles.append(Line2D([], [], ls=":", color="0.5", lw=1.0, label="linear modal frequencies"))
    return handles


def plot_sweep(h5_path, png_path=None, channels=None, quantity: str = "amplitude", title: str | None = None) -> Path:
    """Draw the frequency response of a sweep file as a PNG.

    One subplot per channel, stacked and sharing the frequency axis: the response amplitude
    (or half range) in metres against the forcing frequency in rad/s. Independent sweeps are
    solid lines with small dots; up sweeps solid lines with ``>`` markers, down sweeps dashed
    lines with ``<`` markers; one colour per gamma value. Points whose response did not become
    steady within the cap are ringed in red; points with a subharmonic response (period of
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
        First title line; default ``"<case_name>: frequency response (<analysis> analysis)"``.

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
    markevery = max(1, P // 80)

    gammas = [] if sweep.gamma is None else list(sweep.gamma)
    if len(gammas) <= len(GAMMA_COLOURS):
        colors = GAMMA_COLOURS[: max(1, len(gammas))]
    else:
        import matplotlib

        cmap = matplotlib.colormaps["viridis"]
        colors = [cmap(v) for v in np.linspace(0.0, 0.9, len(gammas))]

    def color_of(curve):
        return colors[0] if curve.gamma is None else colors[gammas.index(curve.gamma)]

    modal_k = [(k + 1, w) for k, w in enumerate(sweep.modal) if np.isfinite(w) and x_lo <= w <= x_hi]

    n = len(chans)
    fig, axes = figure_grid(n, 1, 8.6, 2.6, sharex=True, top=0.8 if modal_k else 0.65, hspace=0.3, left=1.4)
    markers = np.zeros(4, dtype=bool)  # not steady, subharmonic, stopped early, went slack
    for ax, c in zip(axes[:, 0], chans):
        markers |= _draw_channel(ax, sweep, c, quantity, color_of, markevery)
        for _, w in modal_k:
            ax.axvline(w, color="0.5", ls=":", lw=1.0, alpha=0.7, zorder=1)
    top_ax = axes[0, 0]
    last_text = -np.inf
    for k, w in modal_k:  # above the top axes; name the lines that have room
        if w - last_text >= 0.09 * (x_hi - x_lo):
            last_text = w
            top_ax.text(w, 1.01, f"w{k} = {w:.4g}", transform=top_ax.get_xaxis_transform(), fontsize=7,
                        color="0.35", ha="center", va="bottom")
    axes[-1, 0].set_xlim(x_lo, x_hi)
    axes[-1, 0].set_xlabel("forcing frequency omega (rad/s)")

    top_ax.legend(handles=_legend(sweep, gammas, colors, markers, modal_k), loc="upper left",
                  bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)

    # Incomplete sweep.
    total = P * len(sweep.curves)
    done = sum(int(cv.data["done"].sum()) for cv in sweep.curves)
    warn = done < total
    if warn:
        text = f"incomplete sweep: {done} of {total} points"
        short = [f"{cv.label}: {int(cv.data['done'].sum())} of {P}" for cv in sweep.curves if cv.data['done'].sum() < P]
        if len(sweep.curves) > 1:
            more = f"; and {len(short) - 4} more curves" if len(short) > 4 else ""
            text += " (" + "; ".join(short[:4]) + more + ")"
        notes.insert(0, text)
    if done == 0:
        top_ax.text(0.5, 0.5, "no computed points", transform=top_ax.transAxes, ha="center",
                    va="center", color="C3", fontsize=10)

    first = title if title is not None else (
        f"{attr_text(sweep.attrs.get('case_name', sweep.path.stem))}: frequency response ({sweep.analysis} analysis)"
    )
    height = fig.get_figheight()
    fig.suptitle(f"{first}\n{_subtitle(sweep, [sweep.channels[c] for c in chans])}", fontsize=10,
                 y=1 - 0.08 / height, va="top")
    if notes:
        pos = axes[-1, 0].get_position()
        fig.text(0.5 * (pos.x0 + pos.x1), 0.0, "\n".join(notes), ha="center", va="top", fontsize=9,
                 color="red" if warn else "0.3", fontweight="bold" if warn else "normal", wrap=True)
    return save_atomic(fig, png_path)


def marker_handles(any_unsteady: bool, any_sub: bool, any_failed: bool = False, any_slack: bool = False) -> list:
    """Legend entries for the point markers of a frequency-response plot (those present)."""
    from matplotlib.lines import Line2D

    handles = []
    if any_unsteady:
        handles.append(Line2D([], [], ls="none", marker="o", ms=8, mfc="none", mec="red", mew=1.2,
                              label="not steady (cap reached)"))
    if any_sub:
        handles.append(Line2D([], [], ls="none", marker="D", ms=3.5, color="k",
                              label="subharmonic response (period p >= 2),\nlabelled 1/p"))
    if any_failed:
        handles.append(Line2D([], [], ls="none", marker="x", ms=6, color="0.4", mew=1.2,
                              label="stopped early (a segment went slack):\npartial value, not a peak"))
    if any_slack:
        handles.append(Line2D([], [], ls="none", marker="s", ms=7, mfc="none", mec="C1", mew=1.0,
                              label="a segment went slack during the run\n(slack_fraction, peak_tension in the file)"))
    return handles
