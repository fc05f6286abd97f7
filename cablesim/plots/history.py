"""Time-history plots: waveforms, phase plots, Lissajous figure, tensions and spectra.

Plots a :class:`cablesim.dynamics.result.HistoryResult`; channels are named as in
:mod:`cablesim.channels`. Long records are drawn as their true envelopes, numbers are printed
to their resolution (times to the output step, spectral peaks to the bin width).
"""

from __future__ import annotations

import numbers
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..channels import column_description, column_name, column_of, default_pair, resolve_columns
from ..analyses.records import spectrum_part
from ..dynamics.spectra import amplitude_spectrum, spectral_peaks
from ..errors import CablesimError
from .base import bottom_notes, envelope_plot, figure_grid, legend_below, save_atomic, steady_start, title_line, two_tone
from .insets import add_time_inset
from .spatial import plot_across
from .style import COLOURS, SERIES, channel_tex, force_unit, styled, to_resolution

#: Largest number of channels drawn in the waveform and spectrum figures.
MAX_CHANNELS = 8
#: Largest number of channels drawn in the phase figure.
MAX_PHASE_CHANNELS = 3


# --------------------------------------------------------------------------------------------
# Figure helpers
# --------------------------------------------------------------------------------------------


def output_step(t: np.ndarray) -> float:
    """The output step of a record (its smallest sample spacing), s; NaN for one sample."""
    t = np.asarray(t, dtype=float)
    return float(np.diff(t).min()) if t.size > 1 else float("nan")


def time_text(t: np.ndarray, value: float) -> str:
    """A time of the record ``t``, printed to its output step, with the unit."""
    return to_resolution(value, output_step(t), "s")


def _describe(result) -> str:
    """The conditions of a run, in one line."""
    t = np.asarray(result.t)
    forcing = "free vibration" if result.omega is None else f"$\\omega$ = {result.omega:.4g} rad/s"
    span = f"$t$ = {time_text(t, t[0])} to {time_text(t, t[-1])}" if t.size else "no samples"
    return f"{forcing}; {result.analysis} analysis ({result.integrator}); {span}"


def _finish(fig, result, title: str, what: str, path: Path, notes: list[str] = ()) -> Path:
    title_line(fig, f"{title}: {what}", _describe(result))
    lines = []
    if not result.completed:
        lines.append(f"run stopped early: {result.message}")
    lines += list(notes)
    bottom_notes(fig, lines, warn=not result.completed)
    return save_atomic(fig, path)


def panel_label(ax, label: str, description: str) -> None:
    """A stacked panel's y label (one line: a two-line label is taller than a low panel and runs
    into its neighbours') and, above the panel at its left, what the channel is."""
    ax.set_ylabel(label)
    ax.set_title(description, loc="left", fontsize=8, color="0.3", pad=2)


# --------------------------------------------------------------------------------------------
# The five figures
# --------------------------------------------------------------------------------------------


def _plot_waveforms(result, chans, title, path, notes):
    from matplotlib.lines import Line2D  # matplotlib loads only when drawing

    t = np.asarray(result.t, dtype=float)
    fig, axes = figure_grid(len(chans), 1, 1.45, sharex=True, extra_height=1.0)
    split = result.zc is not None or result.ze is not None
    for ax, i in zip(axes[:, 0], chans):
        envelope_plot(ax, t, result.z[:, i], "-", color=COLOURS["response"], lw=0.9)
        if result.zc is not None:
            envelope_plot(ax, t, result.zc[:, i], "--", color=COLOURS["configurational"], lw=0.8)
        if result.ze is not None:
            envelope_plot(ax, t, result.ze[:, i], "-", color=COLOURS["elastic"], lw=0.7, alpha=0.8)
        panel_label(ax, f"{channel_tex(column_name(result, i))} (m)", column_description(result, i))
        add_time_inset(ax, t, result.z[:, i])
    handles = [Line2D([], [], color=COLOURS["response"], label="$z = z_c + z_e$" if split else "displacement $z$")]
    if result.zc is not None:
        handles.append(Line2D([], [], color=COLOURS["configurational"], ls="--", label="configurational part $z_c$"))
    if result.ze is not None:
        handles.append(Line2D([], [], color=COLOURS["elastic"], label="elastic part $z_e$"))
    if len(handles) > 1:
        legend_below(fig, handles, ncol=3)
    axes[-1, 0].set_xlabel("time $t$ (s)")
    return _finish(fig, result, title, "displacements from the static equilibrium", path, notes)


def _plot_phase(result, chans, title, path, notes):
    from matplotlib.ticker import MaxNLocator

    t = np.asarray(result.t, dtype=float)
    chans = chans[:MAX_PHASE_CHANNELS]
    i0 = steady_start(t)
    t_s = time_text(t, t[min(i0, t.size - 1)]) if t.size else "0 s"
    k = len(chans)
    fig, axes = figure_grid(1, k, min(3.4, 6.8 / k + 0.3), extra_height=1.2)
    for ax, i in zip(axes[0], chans):
        name = channel_tex(column_name(result, i))
        two_tone(ax, result.z[:, i], result.v[:, i], i0, f"$t$ < {t_s}", f"$t \\geq$ {t_s} (last half)")
        ax.set_xlabel(f"{name} (m)")
        ax.set_ylabel(f"{name}' (m/s)")
        ax.set_title(f"{name}:\n{column_description(result, i)}", fontsize=9)
        ax.xaxis.set_major_locator(MaxNLocator(nbins=7 - k, steps=[1, 2, 2.5, 5, 10]))  # room for long labels
    legend_below(fig, axes[0, 0].get_legend_handles_labels()[0], ncol=3)
    return _finish(fig, result, title, "phase plots (velocity against displacement)", path, notes)


def _plot_lissajous(result, pair, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    i, j = pair
    i0 = steady_start(t)
    t_s = time_text(t, t[min(i0, t.size - 1)]) if t.size else "0 s"
    fig, axes = figure_grid(1, 1, 5.0, extra_height=1.0)
    ax = axes[0, 0]
    x, y = result.z[:, i], result.z[:, j]
    two_tone(ax, x, y, i0, f"$t$ < {t_s}", f"$t \\geq$ {t_s} (last half)")
    ax.set_xlabel(f"{channel_tex(column_name(result, i))} (m): {column_description(result, i)}")
    ax.set_ylabel(f"{channel_tex(column_name(result, j))} (m): {column_description(result, j)}")
    rx = np.ptp(x[np.isfinite(x)]) if np.isfinite(x).any() else 0.0
    ry = np.ptp(y[np.isfinite(y)]) if np.isfinite(y).any() else 0.0
    if rx > 0 and ry > 0 and 0.2 <= rx / ry <= 5.0:
        ax.set_aspect("equal", adjustable="datalim")
    legend_below(fig, ax.get_legend_handles_labels()[0], ncol=3)
    what = f"Lissajous figure {channel_tex(column_name(result, j))} against {channel_tex(column_name(result, i))}"
    return _finish(fig, result, title, what, path, notes)


def _plot_tensions(result, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    T = np.asarray(result.T, dtype=float)
    T0 = np.asarray(result.T0, dtype=float)
    nseg = T.shape[1]
    segs = list(range(nseg)) if nseg <= 6 else sorted({0, nseg // 2, nseg - 1})
    fig, axes = figure_grid(1, 1, 3.2, extra_height=1.4)
    ax = axes[0, 0]
    div, unit = force_unit(T0)
    for c, r in enumerate(segs):
        color = SERIES[c % len(SERIES)]
        envelope_plot(ax, t, T[:, r] / div, "-", color=color, lw=0.9, label=f"$T_{{{r + 1}}}(t)$")
        ax.axhline(T0[r] / div, ls="--", color=color, lw=0.9, alpha=0.8,
                   label=f"static $T_{{{r + 1}}}$ = {T0[r] / div:.4g} {unit}")
    rec = getattr(result, "slack", None)
    if rec is not None:
        _mark_slack(ax, rec, segs, float(t[-1]), t, (div, unit))
    ax.set_xlabel("time $t$ (s)")
    ax.set_ylabel(f"segment tension $T$ ({unit})")
    legend_below(fig, ax.get_legend_handles_labels()[0], ncol=3)
    which = "all segments" if nseg <= 6 else f"segments {', '.join(str(r + 1) for r in segs)} of {nseg}"
    return _finish(fig, result, title, f"segment tensions ({which})", path, notes)


def slack_intervals(rec, segment: int, t_end: float) -> list[tuple[float, float]]:
    """``(start, end)`` of each slack episode of a segment (1-based), from its events."""
    mine = [(t, k) for t, s, k in zip(rec.t, rec.segment, rec.kind) if s == segment]
    out, start = [], (0.0 if rec.episodes[segment - 1] > sum(k == "slack" for _, k in mine) else None)
    for t, k in mine:
        if k == "slack":
            start = t
        elif start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, t_end))
    return out


def _mark_slack(ax, rec, segs, t_end, t, unit=(1e3, "kN")):
    """Shade each shown segment's slack episodes and mark its peak tension (the snap load)."""
    for c, r in enumerate(segs):
        color = SERIES[c % len(SERIES)]
        spans = slack_intervals(rec, r + 1, t_end)
        for i, (a, b) in enumerate(spans):  # the segment's own colour: which one is slack, when
            ax.axvspan(a, b, color=color, alpha=0.18, lw=0, label=f"segment {r + 1} slack" if i == 0 else None)
        if spans:
            ax.plot(rec.peak_time[r], rec.peak_tension[r] / unit[0], "v", color=color, mec=COLOURS["annotation"], ms=6,
                    label=f"snap load $T_{{{r + 1}}}$ = {rec.peak_tension[r] / unit[0]:.4g} {unit[1]} "
                          f"at {time_text(t, rec.peak_time[r])}")


# --------------------------------------------------------------------------------------------
# Spectra
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ChannelSpectrum:
    """The amplitude spectrum of one channel over the part of its record a spectrum reads
    (:func:`cablesim.analyses.records.spectrum_part`), with its peaks; ``short`` says why there
    is none (the record too short, or not finite)."""

    omega: np.ndarray
    amplitude: np.ndarray
    n: int
    dt: float
    peaks: np.ndarray
    peak_amplitudes: np.ndarray
    t0: float
    t1: float
    how: str
    short: str | None = None

    @property
    def bin_width(self) -> float:
        """``2 pi / T`` of the analysed part, rad/s."""
        return 2 * np.pi / (self.n * self.dt)


def channel_spectrum(result, i: int) -> ChannelSpectrum:
    """The spectrum of column ``i`` of a time history (see :class:`ChannelSpectrum`)."""
    t, z = np.asarray(result.t, dtype=float), np.asarray(result.z[:, i], dtype=float)
    forcing = result.omega if result.omega is not None and np.isfinite(result.omega) and result.omega > 0 else None
    part = spectrum_part(t, z, forcing, getattr(result, "completed", True))
    empty = np.empty(0)
    try:
        omega, amp, n, dt = amplitude_spectrum(t[part.start:part.stop], z[part.start:part.stop], 1.0)
    except CablesimError as exc:
        return ChannelSpectrum(empty, empty, 0, 1.0, empty, empty, 0.0, 0.0, part.how, str(exc).rstrip("."))
    w_pk, a_pk = spectral_peaks(omega, amp, 4, 0.05)
    if forcing is None and w_pk.size:  # a free vibration: count the periods of its strongest motion
        part = spectrum_part(t, z, None, frequency=float(w_pk[0]))
    t0, t1 = float(t[part.start]), float(t[part.stop - 1])
    return ChannelSpectrum(omega, amp, n, dt, w_pk, a_pk, t0, t1, part.how, part.short)


def resolved_peaks(w_pk, a_pk, bin_width: float, x_max: float):
    """The spectral peaks below ``x_max`` at least two bins from every stronger one (closer
    peaks are not resolved by the window), strongest first."""
    kept_w, kept_a = [], []
    for w, a in zip(w_pk, a_pk):
        if w <= x_max and all(abs(w - k) >= 2.0 * bin_width for k in kept_w):
            kept_w.append(w)
            kept_a.append(a)
    return np.array(kept_w), np.array(kept_a)


def window_text(t0: float, t1: float, t, how: str, bin_width: float, sep: str = "; ") -> str:
    """``"window t = 300.00 s to 600.00 s (last half); bins 2 pi/T = 0.021 rad/s"``."""
    return (f"window $t$ = {time_text(t, t0)} to {time_text(t, t1)} ({how}){sep}"
            f"bins $2\\pi/T$ = {bin_width:.2g} rad/s")


def label_peaks(ax, w_pk, a_pk, bin_width: float, span: float) -> None:
    """Mark the peaks and write each frequency to the bin width (``span``: the axis range)."""
    if not w_pk.size:
        return
    ax.plot(w_pk, a_pk, "v", color=COLOURS["annotation"], ms=5, zorder=4, label="spectral peaks")
    peaks = sorted(zip(w_pk, a_pk))
    for r, (w, a) in enumerate(peaks):
        # a label whose right neighbour is close goes to the left of its peak
        crowded = r + 1 < len(peaks) and peaks[r + 1][0] - w < 0.1 * span
        ax.annotate(to_resolution(w, bin_width), (w, a), textcoords="offset points",
                    xytext=(-4 if crowded else 4, 3), ha="right" if crowded else "left",
                    fontsize=8, color=COLOURS["annotation"])


#: The frequency axis of a spectrum ends past its highest peak of at least this fraction of
#: the strongest (beyond it there is only the tail of the peaks, nothing to see) ...
SIGNIFICANT = 1e-3
#: ... by this factor, and past 1.5 times the forcing frequency and the strongest peak.
RANGE_MARGIN, FORCING_MARGIN = 1.25, 1.5


def spectrum_range(spectra, forcing: float | None) -> float:
    """The end of the frequency axis, rad/s: past every channel's significant peaks and the
    forcing, capped at the Nyquist frequency (0 if no channel has a spectrum)."""
    x_max = 0.0
    for sp in spectra:
        if sp.short is not None or not sp.omega.size:
            continue
        peaks, _ = spectral_peaks(sp.omega, sp.amplitude, 16, SIGNIFICANT)
        end = max([RANGE_MARGIN * float(peaks.max())] if peaks.size else [float(sp.omega[-1])])
        if sp.peaks.size:
            end = max(end, FORCING_MARGIN * float(sp.peaks[0]))
        if forcing is not None:
            end = max(end, FORCING_MARGIN * forcing)
        x_max = max(x_max, min(end, float(sp.omega[-1])))
    return x_max


def draw_modal_lines(ax, modal, x_max: float) -> None:
    """Linear modal frequencies as dotted reference lines, the ones with room named."""
    last_end = -np.inf
    width_pt = max(ax.bbox.width * 72.0 / ax.get_figure(root=True).dpi, 1.0)  # the axes' width in points
    for r, w in enumerate(modal[modal <= x_max]):
        ax.axvline(w, color=COLOURS["reference"], ls=":", lw=0.9, alpha=0.8,
                   label="linear modal frequencies" if r == 0 else None)
        text = f" mode {r + 1}"
        span = (len(text) + 1) * 5.0 / width_pt * x_max  # its width at 8 pt, about 5 pt a character
        if w >= last_end and w + span < x_max:
            last_end = w + span
            ax.text(w, 0.98, text, transform=ax.get_xaxis_transform(), fontsize=8,
                    color=COLOURS["reference"], ha="left", va="top", clip_on=True)


def _plot_fft(result, chans, title, path, notes):
    from matplotlib.ticker import NullLocator

    t = np.asarray(result.t, dtype=float)
    modal = np.sort(np.asarray(result.modal_omega, dtype=float).ravel())
    modal = modal[np.isfinite(modal) & (modal > 0)]
    forcing = result.omega if result.omega is not None and np.isfinite(result.omega) and result.omega > 0 else None
    spectra = {i: channel_spectrum(result, i) for i in chans}
    x_max = spectrum_range(spectra.values(), forcing)
    fig, axes = figure_grid(len(chans), 1, 1.8, sharex=True, extra_height=1.4)
    window = ""
    for ax, i in zip(axes[:, 0], chans):
        sp = spectra[i]
        panel_label(ax, f"amplitude of {channel_tex(column_name(result, i))} (m)", column_description(result, i))
        if sp.short is not None:
            ax.text(0.5, 0.5, "no spectrum: " + textwrap.fill(sp.short, 80), transform=ax.transAxes, ha="center",
                    va="center", color=COLOURS["failure"], fontsize=8)
            ax.set_yticks([])
            continue
        window = window_text(sp.t0, sp.t1, t, sp.how, sp.bin_width)
        sel = sp.omega <= x_max
        ax.semilogy(sp.omega[sel], np.maximum(sp.amplitude[sel], 1e-300), "-", color=COLOURS["response"], lw=0.9,
                    label="amplitude spectrum")
        ax.yaxis.set_minor_locator(NullLocator())  # log minor ticks are slow to lay out
        a_top = sp.amplitude[sel][1:].max() if sel.sum() > 1 else 0.0
        if a_top > 0:
            ax.set_ylim(a_top * 1e-6, a_top * 20.0)  # headroom for the labels
        label_peaks(ax, *resolved_peaks(sp.peaks, sp.peak_amplitudes, sp.bin_width, x_max), sp.bin_width, x_max)
        if forcing is not None and forcing <= x_max:
            ax.axvline(forcing, color=COLOURS["forcing"], ls="--", lw=1.0, label="forcing frequency")
        draw_modal_lines(ax, modal, x_max)
    if x_max > 0:
        axes[-1, 0].set_xlim(0.0, x_max)
    axes[-1, 0].set_xlabel("circular frequency $\\omega$ (rad/s)")
    legend_below(fig, axes[0, 0].get_legend_handles_labels()[0], ncol=4)
    # the window under the figure: beside a panel's own label it would overlap it when long
    return _finish(fig, result, title, "amplitude spectra (Hann window)", path, [*notes, window] if window else notes)


@styled
def plot_history(result, prefix, title: str, channels=None, pair=None) -> list[Path]:
    """Write the time-history figures of a run as PNG files.

    Parameters
    ----------
    result : cablesim.dynamics.result.HistoryResult
        The time history. If it kept only some DOF (``result.dof``), channels are looked up
        among the stored ones.
    prefix : str or Path
        Path prefix without suffix; the files are ``{prefix}-waveforms.png``,
        ``{prefix}-phase.png``, ``{prefix}-lissajous.png``, ``{prefix}-tensions.png``,
        ``{prefix}-fft.png`` and, for a spatial cable, ``{prefix}-across.png`` (the nodes'
        paths in the (w, v) plane, :func:`cablesim.plots.spatial.plot_across`).
    title : str
        Start of the title of every figure (the case name).
    channels : sequence of str or int, optional
        Channels for the waveform, phase (first 3) and spectrum figures, e.g. ``["z2", "z4"]``.
        Default: the vertical DOF of every node if n <= 3, else of 3 nodes spread along the
        cable, among the stored channels (every stored channel if none of those was kept). At
        most 8 are drawn.
    pair : (str or int, str or int), optional
        The two channels of the Lissajous figure (x axis, y axis). Default: the vertical DOF
        of the first and the last node (``("z2", "z4")`` for n = 2); ``("z1", "z2")`` if n = 1;
        if those were not stored, the first two stored default channels.

    Returns
    -------
    list of Path
        The files written, in the order above. The Lissajous figure is left out when the
        history kept fewer than two channels (then four files).

    Raises
    ------
    CablesimError
        If a channel name is malformed or out of range, or names a channel the history did
        not store.
    """
    chans = resolve_columns(result, channels)
    notes = []
    if len(chans) > MAX_CHANNELS:
        notes.append(f"showing the first {MAX_CHANNELS} of {len(chans)} chosen channels")
        chans = chans[:MAX_CHANNELS]
    if pair is None:
        pair_idx = default_pair(result)
    else:
        if isinstance(pair, (str, numbers.Integral)) or len(pair) != 2:
            raise CablesimError(f"The Lissajous pair must name two channels, e.g. ('z2', 'z4'); got {pair!r}.")
        pair_idx = (column_of(result, pair[0]), column_of(result, pair[1]))
    prefix = str(prefix)
    paths = [
        _plot_waveforms(result, chans, title, Path(f"{prefix}-waveforms.png"), notes),
        _plot_phase(result, chans, title, Path(f"{prefix}-phase.png"), notes),
    ]
    if pair_idx is not None:
        paths.append(_plot_lissajous(result, pair_idx, title, Path(f"{prefix}-lissajous.png"), []))
    paths += [
        _plot_tensions(result, title, Path(f"{prefix}-tensions.png"), []),
        _plot_fft(result, chans, title, Path(f"{prefix}-fft.png"), notes),
    ]
    across = plot_across(result, Path(f"{prefix}-across.png"), title, _describe(result))  # spatial cables
    return paths + ([across] if across is not None else [])
