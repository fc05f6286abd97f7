"""Composite figures: several stored results drawn as one PNG (a ``figure:`` section).

Composite kinds (``figure.kind``):

- ``fdr``: frequency response of every sweep file on shared axes, one row per channel;
- ``waveform``: z(t) of the channels, one row per channel;
- ``waveform_phase``: z(t) of the first channel beside its phase plot z' against z;
- ``waveform_fft``: z(t) of the first channel beside the amplitude spectrum of the last half;
- ``split``: z with its configurational and elastic parts z_c, z_e, one row per channel;
- ``lissajous_tension``: z_j against z_i above the tension changes T_r - T0_r (last quarter).
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
from ..dynamics.spectra import spectrum, spectrum_peaks
from ..errors import CablesimError
from ..io.hdf5 import FAMILY_TEXT, ResultInfo, attr_text, inspect_result, read_history
from ..io.sweeps import read_sweep, select_channels
from .base import MAX_LINE_POINTS, pyplot, save_atomic, steady_start, two_tone
from .sweep import DIRECTION_STYLE, channel_label, draw_curve, marker_handles

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
#: Colours of the files (or gamma curves) in an fdr figure; red marks non-steady points.
_COLORS = ["C0", "C1", "C2", "C4", "C5", "C6", "C8", "C9", "C7"]


# --------------------------------------------------------------------------------------------
# Composite figures
# --------------------------------------------------------------------------------------------


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
    title = fig_spec.title if fig_spec.title else f"{case_name}: {_KIND_TEXT[kind]}"
    if kind == "fdr":
        return _draw_fdr(fig_spec, infos, png, title)
    hists = [read_history(i.path) for i in infos]
    for info, h in zip(infos, hists):
        if h.t.size < 2:
            raise CablesimError(f"The history in {info.path} holds a single instant; there is nothing to plot.")
    captions = list(labels) if labels is not None else [_caption(h) for h in hists]
    return _draw_history_figure(fig_spec, infos, hists, captions, png, title)


def _caption(h) -> str:
    if h.omega is None:
        return "free vibration"
    return f"forcing omega = {h.omega:.4g} rad/s"


def _stride(m: int) -> int:
    return max(1, -(-m // MAX_LINE_POINTS))


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


def _draw_history_figure(fig_spec, infos, hists, captions, png: Path, title: str) -> Path:
    kind = fig_spec.kind
    n = len(hists)
    # Resolve everything first, so that a bad channel or segment writes no file.
    plans = []
    for info, h in zip(infos, hists):
        plan = {"notes": []}
        if kind in ("waveform", "split"):
            plan["cols"], plan["notes"] = _channel_columns(fig_spec, h, info.path, single=False)
        elif kind in ("waveform_phase", "waveform_fft"):
            plan["cols"], plan["notes"] = _channel_columns(fig_spec, h, info.path, single=True)
        if kind == "split" and (h.zc is None or h.ze is None):
            raise CablesimError(
                f"figure.kind 'split' needs the configurational and elastic parts z_c and z_e, but {info.path} "
                "has none (they were not computed); run the scene with outputs.split: true."
            )
        if kind == "lissajous_tension":
            plan["pair"] = _pair_columns(fig_spec, h, info.path)
            plan["segments"] = _segments(fig_spec, h, info.path)
        if kind != "lissajous_tension":
            plan["window"] = _window(np.asarray(h.t, dtype=float), fig_spec.time_window, info.path)
        else:
            plan["window"] = _tension_window(h, fig_spec.time_window, info.path)
        plans.append(plan)

    rows = max(len(p.get("cols", [0])) for p in plans)
    if kind == "waveform":
        col_w, height = 5.2, 1.2 + 2.0 * rows
    elif kind == "split":
        col_w, height = 5.6, 1.3 + 2.3 * rows
    elif kind in ("waveform_phase", "waveform_fft"):
        col_w, height = 9.0, 4.8
    else:  # lissajous_tension
        col_w, height = 4.8, 8.6
    plt = pyplot()
    fig = plt.figure(figsize=(col_w * n, height), layout="constrained")
    fig.get_layout_engine().set(w_pad=0.06, h_pad=0.06, wspace=0.04, hspace=0.04)
    subs = fig.subfigures(1, n, squeeze=False, wspace=0.03)[0]
    for sf, info, h, cap, plan in zip(subs, infos, hists, captions, plans):
        stopped = not h.completed
        if stopped:  # wrapped to the column width
            cap += "\n" + textwrap.fill(f"run stopped early: {h.message}", width=int(11 * col_w))
        sf.suptitle(cap, fontsize=11 if not stopped else 9.5, color="C3" if stopped else "black",
                    fontweight="bold")
        if kind == "waveform":
            _draw_waveforms(sf, h, plan["cols"], plan["window"], rows, fig_spec.time_window)
        elif kind == "split":
            _draw_split(sf, h, plan["cols"], plan["window"], rows, fig_spec.time_window)
        elif kind == "waveform_phase":
            _draw_waveform_phase(sf, h, plan["cols"][0], plan["window"], fig_spec.time_window)
        elif kind == "waveform_fft":
            _draw_waveform_fft(sf, h, plan["cols"][0], plan["window"], fig_spec.time_window)
        else:
            _draw_lissajous_tension(sf, h, plan["pair"], plan["segments"], plan["window"], fig_spec.time_window)
        if plan["notes"]:
            sf.supxlabel("; ".join(plan["notes"]), fontsize=8, color="0.3")
    fig.suptitle(title, fontsize=13)
    return save_atomic(fig, png)


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


def _label_axes(ax, h, col, xlabel: bool, name_suffix: str = ""):
    ax.set_ylabel(f"{column_name(h, col)}{name_suffix} (m)\n{column_description(h, col)}", fontsize=9)
    if xlabel:
        ax.set_xlabel("time t (s)")
    ax.grid(True, alpha=0.3)


def _draw_waveforms(sf, h, cols, win, rows, tw=None):
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    s = _stride(i1 - i0)
    axes = sf.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for r, ax in enumerate(axes):
        if r >= len(cols):
            ax.set_visible(False)
            continue
        c = cols[r]
        ax.plot(t[i0:i1:s], h.z[i0:i1:s, c], "-", color="C0", lw=1.0, label=f"{column_name(h, c)}(t)")
        ax.axhline(0.0, color="0.5", lw=0.7, ls="--", label="static equilibrium")
        _label_axes(ax, h, c, xlabel=(r == len(cols) - 1))
        _xlim(ax, t, win, tw)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=2, fontsize=7, frameon=False,
                  handlelength=1.6, columnspacing=0.8, borderaxespad=0.2)
        if r < len(cols) - 1:
            ax.tick_params(labelbottom=False)


def _draw_split(sf, h, cols, win, rows, tw=None):
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    s = _stride(i1 - i0)
    axes = sf.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for r, ax in enumerate(axes):
        if r >= len(cols):
            ax.set_visible(False)
            continue
        c = cols[r]
        ax.plot(t[i0:i1:s], h.z[i0:i1:s, c], "-", color="k", lw=1.4, label="z = z_c + z_e")
        ax.plot(t[i0:i1:s], h.zc[i0:i1:s, c], "--", color="C1", lw=1.1, label="configurational part z_c")
        ze_max = float(np.max(np.abs(h.ze[i0:i1, c])))
        ax.plot(t[i0:i1:s], h.ze[i0:i1:s, c], "-", color="C2", lw=1.0, label=f"elastic part z_e (max |z_e| {ze_max:.3g} m)")
        _label_axes(ax, h, c, xlabel=(r == len(cols) - 1))
        _xlim(ax, t, win, tw)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=3, fontsize=7, frameon=False,
                  handlelength=1.6, columnspacing=0.8, borderaxespad=0.2)
        if r < len(cols) - 1:
            ax.tick_params(labelbottom=False)


def _draw_waveform_left(ax, h, c, win, tw=None):
    t = np.asarray(h.t, dtype=float)
    i0, i1 = win
    s = _stride(i1 - i0)
    ax.plot(t[i0:i1:s], h.z[i0:i1:s, c], "-", color="C0", lw=0.9, label=f"{column_name(h, c)}(t)")
    ax.axhline(0.0, color="0.5", lw=0.7, ls="--", label="static equilibrium")
    _label_axes(ax, h, c, xlabel=True)
    _xlim(ax, t, win, tw)
    ax.set_title(f"waveform of {column_name(h, c)}", fontsize=10)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=7.5, frameon=False)


def _draw_waveform_phase(sf, h, c, win, tw=None):
    ax1, ax2 = sf.subplots(1, 2)
    _draw_waveform_left(ax1, h, c, win, tw)
    t = np.asarray(h.t, dtype=float)
    i_half = steady_start(t)
    t_s = t[min(i_half, t.size - 1)]
    name = column_name(h, c)
    two_tone(ax2, h.z[:, c], h.v[:, c], i_half, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
    ax2.set_xlabel(f"{name} (m)")
    ax2.set_ylabel(f"{name}' (m/s)")
    ax2.set_title(f"phase plot of {name} (whole run)", fontsize=10)
    ax2.grid(True, alpha=0.3)
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3, fontsize=7.5, frameon=False)


def _draw_waveform_fft(sf, h, c, win, tw=None):
    from matplotlib.ticker import NullLocator  # matplotlib loads only when drawing

    ax1, ax2 = sf.subplots(1, 2)
    _draw_waveform_left(ax1, h, c, win, tw)
    t = np.asarray(h.t, dtype=float)
    name = column_name(h, c)
    ax2.set_title(f"amplitude spectrum of {name}, t >= {t[t.size - int(round(0.5 * t.size))]:.4g} s (last half)",
                  fontsize=10)
    ax2.set_xlabel("circular frequency omega (rad/s)")
    ax2.set_ylabel(f"amplitude of {name} (m)")
    ax2.grid(True, alpha=0.3)
    try:
        omega, amp = spectrum(t, h.z[:, c], 0.5)
        peaks = spectrum_peaks(t, h.z[:, c], 0.5, max_peaks=4, rel_height=0.05)
    except CablesimError as exc:
        ax2.text(0.5, 0.5, f"no spectrum:\n{exc}", transform=ax2.transAxes, ha="center", va="center",
                 color="C3", fontsize=9, wrap=True)
        return
    modal = np.sort(np.asarray(h.modal_omega, dtype=float).ravel())
    modal = modal[np.isfinite(modal) & (modal > 0)]
    # Frequency range: 1.5 x the largest of the peaks and the forcing frequency (free vibration:
    # and the four lowest modal frequencies), capped at the Nyquist frequency.
    refs = list(peaks) + ([h.omega] if h.omega is not None else list(modal[:4])) + list(modal[:1])
    x_max = min(float(omega[-1]), 1.5 * max(refs)) if refs else float(omega[-1])
    sel = omega <= x_max
    ax2.semilogy(omega[sel], np.maximum(amp[sel], 1e-300), "-", color="C0", lw=1.0, label="amplitude spectrum")
    ax2.yaxis.set_minor_locator(NullLocator())
    top = amp[sel][1:].max() if sel.sum() > 1 else 0.0
    if top > 0:
        ax2.set_ylim(top * 1e-5, top * 30.0)
    peaks = peaks[peaks <= x_max]
    if peaks.size:
        a_pk = np.interp(peaks, omega, amp)
        ax2.plot(peaks, a_pk, "v", color="C3", ms=6, zorder=4, label="spectral peaks")
        for r, (w, a) in enumerate(sorted(zip(peaks, a_pk))):
            ax2.annotate(f"{w:#.4g}", (w, a), textcoords="offset points", xytext=(4, 3 + 9 * (r % 2)),
                         fontsize=8, color="C3")
    if h.omega is not None and h.omega <= x_max:
        ax2.axvline(h.omega, color="C1", ls="--", lw=1.0, alpha=0.7, label=f"forcing omega = {h.omega:.4g} rad/s")
    shown = modal[modal <= x_max]
    if shown.size:
        for r, w in enumerate(shown):
            ax2.axvline(w, color="0.45", ls=":", lw=1.0, alpha=0.7,
                        label=("linear modal frequencies" if r == 0 else None))
    ax2.set_xlim(0.0, x_max)
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=7.5, frameon=False)


def _draw_lissajous_tension(sf, h, pair, segs, win, tw=None):
    ax1, ax2 = sf.subplots(2, 1, height_ratios=[1.25, 1.0])
    t = np.asarray(h.t, dtype=float)
    i, j = pair
    i_half = steady_start(t)
    t_s = t[min(i_half, t.size - 1)]
    x, y = h.z[:, i], h.z[:, j]
    two_tone(ax1, x, y, i_half, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
    ax1.set_xlabel(f"{column_name(h, i)} (m): {column_description(h, i)}", fontsize=9)
    ax1.set_ylabel(f"{column_name(h, j)} (m): {column_description(h, j)}", fontsize=9)
    ax1.set_title(f"Lissajous figure {column_name(h, j)} against {column_name(h, i)}", fontsize=10)
    ax1.grid(True, alpha=0.3)
    ax1.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3, fontsize=7, frameon=False)

    i0, i1 = win
    s = _stride(i1 - i0)
    T = np.asarray(h.T, dtype=float)
    T0 = np.asarray(h.T0, dtype=float)
    for k, r in enumerate(segs):
        ax2.plot(t[i0:i1:s], (T[i0:i1:s, r] - T0[r]) / 1e3, "-", color=f"C{k % 10}", lw=1.1,
                 label=f"T{r + 1} - T0 (T0 = {T0[r] / 1e3:.4g} kN)")
    ax2.axhline(0.0, color="0.5", lw=0.7, ls="--")
    _xlim(ax2, t, win, tw)
    ax2.set_xlabel("time t (s)")
    ax2.set_ylabel("tension change T - T0 (kN)")
    if tw is not None:
        span = f"t = {t[i0]:.4g} to {t[i1 - 1]:.4g} s"
    elif h.omega is not None and TENSION_PERIODS and t[-1] - t[i0] < 0.24 * (t[-1] - t[0]):
        span = f"last {TENSION_PERIODS} forcing periods"
    else:
        span = "last quarter of the run"
    ax2.set_title(f"segment tension changes ({span})", fontsize=10)
    ax2.grid(True, alpha=0.3)
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=7, frameon=False)


# --------------------------------------------------------------------------------------------
# fdr: several sweep files on shared axes
# --------------------------------------------------------------------------------------------


def _draw_fdr(fig_spec, infos, png: Path, title: str) -> Path:
    from matplotlib.lines import Line2D

    sweeps = [read_sweep(i.path) for i in infos]
    if fig_spec.labels is not None:
        names = list(fig_spec.labels)
    else:
        names = [attr_text(sw.attrs.get("case_name", sw.path.stem)) for sw in sweeps]
        if len(set(names)) < len(names):
            names = [sw.path.name for sw in sweeps]
    # Channels: the figure's (each must be in every file), else the first file's.
    if fig_spec.channels is not None:
        chans = []
        for sw in sweeps:
            idx = select_channels(sw, fig_spec.channels)
            chans = [sw.channels[k] for k in idx]
    else:
        chans = list(sweeps[0].channels)
    notes = []
    if len(chans) > MAX_ROWS:
        notes.append(f"showing the first {MAX_ROWS} of {len(chans)} channels")
        chans = chans[:MAX_ROWS]

    # One colour per (file, gamma); line style per direction.
    series = []
    for k, (sw, name) in enumerate(zip(sweeps, names)):
        gammas = [None] if sw.gamma is None else list(sw.gamma)
        for g in gammas:
            label = name if g is None else f"{name}, gamma = {g:g}"
            series.append((k, g, label))
    colors = {(k, g): _COLORS[r % len(_COLORS)] for r, (k, g, _) in enumerate(series)}

    lo = min(float(sw.omega[0]) for sw in sweeps)
    hi = max(float(sw.omega[-1]) for sw in sweeps)
    pad = 0.02 * (hi - lo) if hi > lo else max(0.05 * abs(lo), 0.1)
    x_lo, x_hi = lo - pad, hi + pad
    modal = [w for w in sweeps[0].modal if np.isfinite(w) and x_lo <= w <= x_hi]

    plt = pyplot()
    n = len(chans)
    fig = plt.figure(figsize=(10.5, 1.3 + 2.8 * n), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    markers = np.zeros(4, dtype=bool)  # not steady, subharmonic, stopped early, went slack
    for ax, name in zip(axes, chans):
        for k, sw in enumerate(sweeps):
            if name not in sw.channels:
                continue
            c = sw.channels.index(name)
            markevery = max(1, sw.omega.size // 80)
            for curve in sw.curves:
                markers |= draw_curve(ax, sw.omega, curve, c, "amplitude", colors[(k, curve.gamma)], markevery, 1.3)
        for w in modal:
            ax.axvline(w, color="0.5", ls=":", lw=1.0, alpha=0.7, zorder=1)
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel(channel_label(name), fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlim(x_lo, x_hi)
    axes[-1].set_xlabel("forcing frequency omega (rad/s)")
    handles = [Line2D([], [], color=colors[(k, g)], lw=2.5, label=label) for k, g, label in series]
    for d in dict.fromkeys(cv.direction for sw in sweeps for cv in sw.curves):
        st = DIRECTION_STYLE[d]
        handles.append(Line2D([], [], ls=st["ls"], marker=st["marker"], ms=st["ms"] + 1, color="0.3", lw=1.2,
                              label=st["label"]))
    handles += marker_handles(*markers)
    if modal:
        handles.append(Line2D([], [], ls=":", color="0.5", lw=1.0,
                              label="linear modal frequencies\n(" + ", ".join(f"{w:.4g}" for w in modal) + " rad/s)"))
    axes[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    incomplete = [f"{nm}: {sum(int(cv.data['done'].sum()) for cv in sw.curves)} of {sw.omega.size * len(sw.curves)} points"
                  for sw, nm in zip(sweeps, names)
                  if sum(int(cv.data["done"].sum()) for cv in sw.curves) < sw.omega.size * len(sw.curves)]
    if incomplete:
        notes.insert(0, "incomplete sweep(s): " + "; ".join(incomplete))
    if notes:
        fig.supxlabel("\n".join(notes), fontsize=9, color="C3" if incomplete else "0.3")
    fig.suptitle(title, fontsize=13)
    return save_atomic(fig, png)
