"""Composite figures: several stored results drawn as one PNG (a ``figure:`` section).

Composite kinds (``figure.kind``):

- ``fdr``: frequency response of every sweep file on shared axes, one row per channel
  (:mod:`cablesim.plots.fdr`);
- ``waveform``: z(t) of the channels, one row per channel;
- ``waveform_phase``: z(t) of the first channel beside its phase plot z' against z;
- ``waveform_fft``: z(t) of the first channel beside the amplitude spectrum of the last half
  (of the whole record if the run stopped early), with its window and bin width;
- ``split``: z with its configurational and elastic parts z_c, z_e, one row per channel (z_e
  on a panel of its own when it is too small to read beside z);
- ``lissajous_tension``: z_j against z_i above the tension changes T_r - T0_r (last quarter).

Files side by side (or, for the two-panel kinds, stacked) share the scales of the panels that
compare them; a stretch too small to read on a waveform gets an inset.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from ..channels import (
    column_description,
    column_name,
    column_of,
    default_pair,
    resolve_columns,
    stored_names,
)

from ..errors import CablesimError
from ..io.hdf5 import FAMILY_TEXT, ResultInfo, inspect_result, read_history
from .base import bottom_notes, figure_width, envelope_plot, pyplot, save_atomic, steady_start, two_tone, wrap_text
from .fdr import draw_fdr
from .history import (channel_spectrum, draw_modal_lines, label_peaks, resolved_peaks, spectrum_range, time_text,
                      window_text)
from .insets import add_time_inset
from .style import COLOURS, SERIES, channel_tex, force_unit, styled, symbols

#: Kinds drawing time histories (history or free-vibration files).
HISTORY_KINDS = ("waveform", "waveform_phase", "waveform_fft", "split", "lissajous_tension")
_KIND_TEXT = {
    "fdr": "frequency response",
    "waveform": "displacement waveforms",
    "waveform_phase": "waveform and phase plot",
    "waveform_fft": "waveform and amplitude spectrum",
    "split": "configurational and elastic parts of the displacements",
    "lissajous_tension": "Lissajous figures and tension changes",
}
#: Largest number of channel rows in a composite figure.
MAX_ROWS = 8
#: lissajous_tension without a time window: the tension panel shows the last quarter of the
#: run, but no more than this many forcing periods (so that the waveform stays readable).
TENSION_PERIODS = 12
#: Kinds drawing two panels per file side by side (several files stack as rows).
PAIRED_KINDS = ("waveform_phase", "waveform_fft")


# --------------------------------------------------------------------------------------------
# Composite figures
# --------------------------------------------------------------------------------------------


@styled
def draw_figure(fig_spec, infos, png: Path, case_name: str = "case") -> Path:
    """Draw the composite figure ``fig_spec`` (a :class:`~cablesim.case.FigureSpec`) as one PNG.

    Parameters
    ----------
    fig_spec : FigureSpec
    infos : list of result files (paths, or the checked file descriptions of :func:`redraw`)
    png : Path
        The PNG to write.
    case_name : str
        For the default title.
    """
    infos = [i if isinstance(i, ResultInfo) else inspect_result(i) for i in infos]
    kind = fig_spec.kind
    labels = fig_spec.labels
    if labels is not None and len(labels) != len(infos):
        raise CablesimError(
            f"figure.labels has {len(labels)} caption(s) but {len(infos)} result file(s) were given; "
            "give one caption per file, in the order of the files."
        )
    want = "sweep" if kind == "fdr" else "history"
    for info in infos:
        if info.family != want:
            needs = "sweep files (cablesim sweep)" if want == "sweep" else "time-history files (cablesim history or free-vibration)"
            raise CablesimError(
                f"figure.kind {kind!r} draws {needs}, but {info.path} is {FAMILY_TEXT[info.family]}."
            )
    title = symbols(fig_spec.title) if fig_spec.title else f"{case_name}: {_KIND_TEXT[kind]}"
    if kind == "fdr":
        return draw_fdr(fig_spec, infos, png, title)
    hists = [read_history(i.path) for i in infos]
    for info, h in zip(infos, hists):
        if h.t.size < 2:
            raise CablesimError(f"The history in {info.path} holds a single instant; there is nothing to plot.")
    captions = [symbols(c) for c in labels] if labels is not None else [_caption(h, title) for h in hists]
    return _draw_history_figure(fig_spec, infos, hists, captions, png, title)


def _caption(h, title: str) -> str:
    """A file's caption: its forcing, unless the figure's title states it already."""
    if h.omega is None:
        return "" if "free vibration" in title else "free vibration"
    return "" if f"{h.omega:.4g}" in title else f"forcing frequency $\\omega$ = {h.omega:.4g} rad/s"


def _xlim(ax, t, win, tw=None):
    i0, i1 = win
    lo, hi = t[i0], t[i1 - 1]
    if tw is not None and float(tw[0]) < t[-1]:
        lo, hi = max(float(tw[0]), t[0]), min(float(tw[1]), t[-1])
    ax.set_xlim(lo, hi)


def _window(t: np.ndarray, tw, path: Path):
    """Index range ``(i0, i1)`` of the samples inside the time window (whole run if None)."""
    if tw is None:
        return 0, t.size
    lo, hi = float(tw[0]), float(tw[1])
    if not hi > lo:
        raise CablesimError(f"figure.time_window [{lo:g}, {hi:g}] s must be increasing: give [start, end] in seconds.")
    if lo >= t[-1]:
        # The run ended before the window (a shorter run, or one that stopped early): show a
        # window of the same length at its end.
        lo, hi = t[-1] - (hi - lo), t[-1]
    inside = np.flatnonzero((t >= lo) & (t <= hi))
    if inside.size < 2:
        raise CablesimError(
            f"figure.time_window [{lo:g}, {hi:g}] s holds fewer than two saved instants of {path}, which runs "
            f"from {t[0]:.4g} to {t[-1]:.4g} s; choose a window inside the run."
        )
    return int(inside[0]), int(inside[-1]) + 1


def _channel_columns(fig_spec, hist, path: Path, single: bool) -> tuple[list[int], list[str]]:
    """Stored columns to draw (at most MAX_ROWS), and notes."""
    notes = []
    try:
        cols = resolve_columns(hist, fig_spec.channels)
    except CablesimError as exc:
        raise CablesimError(f"figure.channels does not fit {path}: {exc}") from None
    if fig_spec.channels is None and hist.dof is not None:
        cols = list(range(len(hist.dof_numbers)))  # a scene kept what it draws: all of it
        if single:  # one channel: prefer the default (vertical) one among the stored
            cols = resolve_columns(hist) or cols
    if single:
        cols = cols[:1]
    elif len(cols) > MAX_ROWS:
        notes.append(f"showing the first {MAX_ROWS} of {len(cols)} channels ({stored_names(hist)})")
        cols = cols[:MAX_ROWS]
    return cols, notes


def _plan(fig_spec, info, h) -> dict:
    """What to draw from one file, resolved before drawing so that bad input writes no file."""
    kind = fig_spec.kind
    plan = {"notes": []}
    if kind in ("waveform", "split"):
        plan["cols"], plan["notes"] = _channel_columns(fig_spec, h, info.path, single=False)
    elif kind in PAIRED_KINDS:
        plan["cols"], plan["notes"] = _channel_columns(fig_spec, h, info.path, single=True)
    if kind == "split" and (h.zc is None or h.ze is None):
        raise CablesimError(
            f"figure.kind 'split' needs the configurational and elastic parts z_c and z_e, but {info.path} "
            "has none (they were not computed); run the scene with outputs.split: true."
        )
    if kind == "lissajous_tension":
        plan["pair"] = _pair_columns(fig_spec, h, info.path)
        plan["segments"] = _segments(fig_spec, h, info.path)
        plan["window"] = _tension_window(h, fig_spec.time_window, info.path)
    else:
        plan["window"] = _window(np.asarray(h.t, dtype=float), fig_spec.time_window, info.path)
    return plan


def _split_rows(h, cols, win) -> list[bool]:
    """Per channel of a split figure: whether z_e gets its own panel (too small beside z)."""
    i0, i1 = win
    out = []
    for c in cols:
        z_max = float(np.nanmax(np.abs(h.z[i0:i1, c]))) if i1 > i0 else 0.0
        ze_max = float(np.nanmax(np.abs(h.ze[i0:i1, c]))) if i1 > i0 else 0.0
        out.append(bool(z_max > 0 and ze_max < 0.1 * z_max))
    return out


def _figure_size(kind: str, n: int, plans, hists) -> tuple[float, int, int]:
    """(height in inches, subfigure rows, subfigure columns) of a composite history figure."""
    rows = max(len(p.get("cols", [0])) for p in plans)
    if kind == "waveform":
        return 0.9 + 1.5 * rows, 1, n
    if kind == "split":
        panels = max(len(p["cols"]) + sum(_split_rows(h, p["cols"], p["window"])) for p, h in zip(plans, hists))
        return 1.0 + 1.6 * panels, 1, n
    if kind in PAIRED_KINDS:
        return 0.4 + 3.0 * n, n, 1
    return 6.4, 1, n  # lissajous_tension


def _draw_history_figure(fig_spec, infos, hists, captions, png: Path, title: str) -> Path:
    kind = fig_spec.kind
    n = len(hists)
    plans = [_plan(fig_spec, info, h) for info, h in zip(infos, hists)]
    height, sub_rows, sub_cols = _figure_size(kind, n, plans, hists)
    plt = pyplot()
    fig = plt.figure(figsize=(figure_width(), height), layout="constrained")
    fig.get_layout_engine().set(w_pad=0.04, h_pad=0.04, wspace=0.03, hspace=0.03)
    subs = fig.subfigures(sub_rows, sub_cols, squeeze=False).ravel()
    roles: dict = {}  # panels compared across files share their scales
    tw = fig_spec.time_window
    for sf, h, cap, plan in zip(subs, hists, captions, plans):
        stopped = not h.completed
        if stopped:  # wrapped to the column width
            cap += "\n" + textwrap.fill(f"run stopped early: {h.message}", width=int(13 * figure_width() / sub_cols))
        if cap:
            sf.suptitle(cap.strip(), fontsize=9, color=COLOURS["failure"] if stopped else "black", fontweight="bold")
        if kind == "waveform":
            drawn = _draw_waveforms(sf, h, plan["cols"], plan["window"], tw)
        elif kind == "split":
            drawn = _draw_split(sf, h, plan["cols"], plan["window"], tw)
        elif kind == "waveform_phase":
            drawn = _draw_waveform_phase(sf, h, plan["cols"][0], plan["window"], tw)
        elif kind == "waveform_fft":
            drawn = _draw_waveform_fft(sf, h, plan["cols"][0], plan["window"], tw)
        else:
            drawn = _draw_lissajous_tension(sf, h, plan["pair"], plan["segments"], plan["window"], tw)
        for role, ax in drawn.items():
            roles.setdefault(role, []).append(ax)
        if plan["notes"]:
            bottom_notes(sf, ["; ".join(plan["notes"])])
    if n > 1:
        share_scales(roles)
    fig.suptitle(title, fontsize=10)
    return save_atomic(fig, png)


def share_scales(roles: dict) -> None:
    """Give the panels of one role (e.g. the tension panel of each file) common limits: the
    ``y`` axis, and the ``x`` axis too for roles named ``"xy:..."`` (Lissajous, phase plots)."""
    for role, axes in roles.items():
        if len(axes) < 2:
            continue
        which = ("x", "y") if role.startswith("xy:") else ("y",)
        for name in which:
            lims = np.array([getattr(ax, f"get_{name}lim")() for ax in axes])
            both = (lims[:, 0].min(), lims[:, 1].max())
            for ax in axes:
                getattr(ax, f"set_{name}lim")(*both)


def _pair_columns(fig_spec, h, path: Path):
    if fig_spec.pair is not None:
        try:
            return column_of(h, fig_spec.pair[0]), column_of(h, fig_spec.pair[1])
        except CablesimError as exc:
            raise CablesimError(f"figure.pair does not fit {path}: {exc}") from None
    pair = default_pair(h)
    if pair is None:
        raise CablesimError(
            f"A Lissajous figure needs two channels but {path} kept only one (z{h.dof_numbers[0]}); "
            "list two in outputs.channels and rerun the scene."
        )
    return pair


def _segments(fig_spec, h, path: Path) -> list[int]:
    nseg = int(np.asarray(h.T).shape[1])
    segs = list(fig_spec.segments) if fig_spec.segments else [1]
    bad = [r for r in segs if not 1 <= r <= nseg]
    if bad:
        raise CablesimError(
            f"figure.segments {', '.join(str(r) for r in bad)} out of range: the cable in {path} has "
            f"segments 1 to {nseg}."
        )
    return list(dict.fromkeys(r - 1 for r in segs))


def _tension_window(h, tw, path: Path):
    """The time window, else the last quarter of the run (at most TENSION_PERIODS forcing periods)."""
    t = np.asarray(h.t, dtype=float)
    if tw is not None:
        return _window(t, tw, path)
    t_lo = t[-1] - 0.25 * (t[-1] - t[0])
    if h.omega is not None and TENSION_PERIODS:
        t_lo = max(t_lo, t[-1] - TENSION_PERIODS * 2.0 * np.pi / h.omega)
    i0 = min(int(np.searchsorted(t, t_lo)), t.size - 2)
    return max(0, i0), t.size



def _label_axes(ax, h, col, xlabel: bool, name_suffix: str = "", stacked: bool = False):
    """The y label; what the channel is under it, or, in a stack of low panels (where a two-line
    label runs into the next panel's), above the panel at its right."""
    label, what = f"{channel_tex(column_name(h, col))}{name_suffix} (m)", column_description(h, col)
    ax.set_ylabel(label if stacked else f"{label}\n{what}")
    if stacked:
        ax.set_title(what, loc="right", fontsize=8, color="0.3", pad=2)
    if xlabel:
        ax.set_xlabel("time $t$ (s)")


def _legend_above(ax, ncol: int) -> None:
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=ncol, frameon=False, handlelength=1.6,
              columnspacing=0.8, borderaxespad=0.2)


def _draw_waveforms(sf, h, cols, win, tw=None) -> dict:
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    axes = sf.subplots(len(cols), 1, sharex=True, squeeze=False)[:, 0]
    drawn = {}
    for r, (ax, c) in enumerate(zip(axes, cols)):
        envelope_plot(ax, t[i0:i1], h.z[i0:i1, c], "-", color=COLOURS["response"], lw=0.9,
                      label=f"{channel_tex(column_name(h, c))}$(t)$")
        ax.axhline(0.0, color=COLOURS["reference"], lw=0.7, ls="--", label="static equilibrium")
        _label_axes(ax, h, c, xlabel=(r == len(cols) - 1), stacked=len(cols) > 1)
        _xlim(ax, t, win, tw)
        add_time_inset(ax, t[i0:i1], h.z[i0:i1, c])
        if r == 0:
            _legend_above(ax, 2)
        drawn[f"y:z{r}"] = ax
    return drawn


def _draw_split(sf, h, cols, win, tw=None) -> dict:
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    own = _split_rows(h, cols, win)
    axes = sf.subplots(len(cols) + sum(own), 1, sharex=True, squeeze=False)[:, 0]
    drawn, k = {}, 0
    for r, c in enumerate(cols):
        ax = axes[k]
        # z wide and light beneath its parts, so that it shows where it coincides with one of them
        envelope_plot(ax, t[i0:i1], h.z[i0:i1, c], "-", color=COLOURS["response"], lw=2.4, alpha=0.45,
                      label="$z = z_c + z_e$")
        envelope_plot(ax, t[i0:i1], h.zc[i0:i1, c], "--", color=COLOURS["configurational"], lw=0.9,
                      label="configurational $z_c$")
        ze_ax = axes[k + 1] if own[r] else ax
        envelope_plot(ze_ax, t[i0:i1], h.ze[i0:i1, c], "-", color=COLOURS["elastic"], lw=0.9, label="elastic $z_e$")
        _label_axes(ax, h, c, xlabel=False)
        drawn[f"y:z{r}"] = ax
        if own[r]:
            ze_ax.set_ylabel(f"{channel_tex('z_e')} of {channel_tex(column_name(h, c))} (m),\nenlarged")
            ze_ax.axhline(0.0, color=COLOURS["reference"], lw=0.6, ls="--")
            drawn[f"y:ze{r}"] = ze_ax
        if r == 0:
            handles = ax.get_legend_handles_labels()[0] + (ze_ax.get_legend_handles_labels()[0] if own[r] else [])
            sf.legend(handles=handles, loc="outside lower center", ncol=3, frameon=False, handlelength=1.6,
                      columnspacing=0.8)
        k += 2 if own[r] else 1
    for ax in axes:
        _xlim(ax, t, win, tw)
    axes[-1].set_xlabel("time $t$ (s)")
    return drawn


def _draw_waveform_left(ax, h, c, win, tw=None):
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    name = channel_tex(column_name(h, c))
    envelope_plot(ax, t[i0:i1], h.z[i0:i1, c], "-", color=COLOURS["response"], lw=0.8, label=f"{name}$(t)$")
    ax.axhline(0.0, color=COLOURS["reference"], lw=0.7, ls="--", label="static equilibrium")
    _label_axes(ax, h, c, xlabel=True)
    _xlim(ax, t, win, tw)
    add_time_inset(ax, t[i0:i1], h.z[i0:i1, c])
    ax.set_title(f"waveform of {name}")


def _draw_waveform_phase(sf, h, c, win, tw=None) -> dict:
    ax1, ax2 = sf.subplots(1, 2)
    _draw_waveform_left(ax1, h, c, win, tw)
    t = np.asarray(h.t, dtype=float)
    i_half = steady_start(t)
    t_s = time_text(t, t[min(i_half, t.size - 1)])
    name = channel_tex(column_name(h, c))
    two_tone(ax2, h.z[:, c], h.v[:, c], i_half, f"$t$ < {t_s}", f"$t \\geq$ {t_s} (last half)")
    ax2.set_xlabel(f"{name} (m)")
    ax2.set_ylabel(f"{name}' (m/s)")
    ax2.set_title(f"phase plot of {name} (whole run)")
    sf.legend(handles=ax2.get_legend_handles_labels()[0], loc="outside lower center", ncol=3, frameon=False)
    return {"y:waveform": ax1, "xy:phase": ax2}


def _draw_waveform_fft(sf, h, c, win, tw=None) -> dict:
    from matplotlib.ticker import NullLocator  # matplotlib loads only when drawing

    ax1, ax2 = sf.subplots(1, 2)
    _draw_waveform_left(ax1, h, c, win, tw)
    t = np.asarray(h.t, dtype=float)
    name = channel_tex(column_name(h, c))
    ax2.set_xlabel("circular frequency $\\omega$ (rad/s)")
    ax2.set_ylabel(f"amplitude of {name} (m)")
    sp = channel_spectrum(h, c)
    if sp.short is not None:
        ax2.text(0.5, 0.5, "no spectrum:\n" + textwrap.fill(sp.short, 40), transform=ax2.transAxes, ha="center",
                 va="center", color=COLOURS["failure"], fontsize=8)
        return {"y:waveform": ax1}
    omega, amp, w_pk, a_pk, bin_width = sp.omega, sp.amplitude, sp.peaks, sp.peak_amplitudes, sp.bin_width
    ax2.set_title(f"amplitude spectrum of {name}\n" + "\n".join(
        wrap_text(window_text(sp.t0, sp.t1, t, sp.how, bin_width, "; "), 46)), fontsize=8)
    modal = np.sort(np.asarray(h.modal_omega, dtype=float).ravel())
    modal = modal[np.isfinite(modal) & (modal > 0)]
    x_max = spectrum_range([sp], h.omega)
    sel = omega <= x_max
    ax2.semilogy(omega[sel], np.maximum(amp[sel], 1e-300), "-", color=COLOURS["response"], lw=0.9,
                 label="amplitude spectrum")
    ax2.yaxis.set_minor_locator(NullLocator())
    top = amp[sel][1:].max() if sel.sum() > 1 else 0.0
    if top > 0:
        ax2.set_ylim(top * 1e-5, top * 30.0)
    label_peaks(ax2, *resolved_peaks(w_pk, a_pk, bin_width, x_max), bin_width, x_max)
    if h.omega is not None and h.omega <= x_max:
        ax2.axvline(h.omega, color=COLOURS["forcing"], ls="--", lw=1.0, label="forcing frequency")
    draw_modal_lines(ax2, modal, x_max)
    ax2.set_xlim(0.0, x_max)
    handles = ax2.get_legend_handles_labels()[0]  # the response's colour is the same on both
    sf.legend(handles=handles, loc="outside lower center", ncol=3, frameon=False)
    return {"y:waveform": ax1, "xy:spectrum": ax2}


def _draw_lissajous_tension(sf, h, pair, segs, win, tw=None) -> dict:
    ax1, ax2 = sf.subplots(2, 1, height_ratios=[1.25, 1.0])
    t = np.asarray(h.t, dtype=float)
    i, j = pair
    i_half = steady_start(t)
    t_s = time_text(t, t[min(i_half, t.size - 1)])
    two_tone(ax1, h.z[:, i], h.z[:, j], i_half, f"$t$ < {t_s}", f"$t \\geq$ {t_s} (last half)")
    ax1.set_xlabel(f"{channel_tex(column_name(h, i))} (m): {column_description(h, i)}")
    ax1.set_ylabel(f"{channel_tex(column_name(h, j))} (m): {column_description(h, j)}")
    ax1.set_title(f"Lissajous figure {channel_tex(column_name(h, j))} against {channel_tex(column_name(h, i))}")
    ax1.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, frameon=False)
    i0, i1 = win
    T = np.asarray(h.T, dtype=float)
    T0 = np.asarray(h.T0, dtype=float)
    div, unit = force_unit(T0)
    for k, r in enumerate(segs):
        envelope_plot(ax2, t[i0:i1], (T[i0:i1, r] - T0[r]) / 1e3, "-", color=SERIES[k % len(SERIES)], lw=0.9,
                      label=f"$T_{{{r + 1}}} - T_{{0}}$ ($T_0$ = {T0[r] / div:.4g} {unit})")
    ax2.axhline(0.0, color=COLOURS["reference"], lw=0.7, ls="--")
    _xlim(ax2, t, win, tw)
    ax2.set_xlabel("time $t$ (s)")
    ax2.set_ylabel("tension change $T - T_0$ (kN)")
    if tw is not None:
        span = f"$t$ = {time_text(t, t[i0])} to {time_text(t, t[i1 - 1])}"
    elif h.omega is not None and TENSION_PERIODS and t[-1] - t[i0] < 0.24 * (t[-1] - t[0]):
        span = f"last {TENSION_PERIODS} forcing periods"
    else:
        span = "last quarter of the run"
    ax2.set_title(f"segment tension changes\n({span})")
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.28), ncol=1, frameon=False)
    return {"xy:lissajous": ax1, "y:tension": ax2}
