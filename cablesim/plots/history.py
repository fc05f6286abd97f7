"""Time-history plots: waveforms, phase plots, Lissajous figure, tensions and spectra.

Plots a :class:`cablesim.dynamics.result.HistoryResult`; channels are named as in
:mod:`cablesim.channels`.
"""

from __future__ import annotations

import numbers
from pathlib import Path

import numpy as np

from ..channels import column_description, column_name, column_of, default_pair, resolve_columns
from ..dynamics.spectra import amplitude_spectrum, spectral_peaks
from ..errors import CablesimError
from .base import figure_grid, save_atomic, steady_start, stride, two_tone

#: Largest number of channels drawn in the waveform and spectrum figures.
MAX_CHANNELS = 8
#: Largest number of channels drawn in the phase figure.
MAX_PHASE_CHANNELS = 3


# --------------------------------------------------------------------------------------------
# Figure helpers
# --------------------------------------------------------------------------------------------



def _describe(result) -> str:
    if result.omega is None:
        forcing = "free vibration"
    else:
        forcing = f"forcing omega = {result.omega:.4g} rad/s"
    t = np.asarray(result.t)
    span = f"t = {t[0]:.4g} to {t[-1]:.4g} s" if t.size else "no samples"
    return f"{forcing}, {result.analysis} analysis, {result.integrator}, {span}"



def _finish(fig, result, title: str, what: str, path: Path, notes: list[str] = ()) -> Path:
    height = fig.get_figheight()
    fig.suptitle(f"{title}: {what}\n{_describe(result)}", fontsize=10, y=1 - 0.08 / height, va="top")
    lines = []
    if not result.completed:
        lines.append(f"run stopped early: {result.message}")
    lines += list(notes)
    if lines:
        fig.text(
            0.5,
            0.0,
            "\n".join(lines),
            ha="center",
            va="top",
            color="red" if not result.completed else "0.3",
            fontsize=9,
            fontweight="bold" if not result.completed else "normal",
        )
    return save_atomic(fig, path)



# --------------------------------------------------------------------------------------------
# The five figures
# --------------------------------------------------------------------------------------------


def _plot_waveforms(result, chans, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    s = stride(t.size)
    k = len(chans)
    fig, axes = figure_grid(k, 1, 8.6, 2.0, sharex=True, top=0.95, hspace=0.2, left=1.3)
    split = result.zc is not None or result.ze is not None
    for ax, i in zip(axes[:, 0], chans):
        ax.plot(t[::s], result.z[::s, i], "-", color="C0", lw=1.2, label="z = z_c + z_e" if split else "z")
        if result.zc is not None:
            ax.plot(t[::s], result.zc[::s, i], "--", color="C1", lw=0.9, label="configurational part z_c")
        if result.ze is not None:
            ax.plot(t[::s], result.ze[::s, i], "-", color="C2", lw=0.8, alpha=0.8, label="elastic part z_e")
        ax.set_ylabel(f"{column_name(result, i)} (m)\n{column_description(result, i)}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=3, fontsize=8, frameon=False)
    axes[-1, 0].set_xlabel("time t (s)")
    return _finish(fig, result, title, "displacements from the static equilibrium", path, notes)


def _plot_phase(result, chans, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    chans = chans[:MAX_PHASE_CHANNELS]
    i0 = steady_start(t)
    t_s = t[min(i0, t.size - 1)] if t.size else 0.0
    k = len(chans)
    fig, axes = figure_grid(1, k, 3.8, 3.8, top=1.0, wspace=0.95)
    for ax, i in zip(axes[0], chans):
        name = column_name(result, i)
        two_tone(ax, result.z[:, i], result.v[:, i], i0, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
        ax.set_xlabel(f"{name} (m)")
        ax.set_ylabel(f"{name}' (m/s)")
        ax.set_title(f"{name}: {column_description(result, i)}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0, -1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    return _finish(fig, result, title, "phase plots (velocity against displacement)", path, notes)


def _plot_lissajous(result, pair, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    i, j = pair
    i0 = steady_start(t)
    t_s = t[min(i0, t.size - 1)] if t.size else 0.0
    fig, axes = figure_grid(1, 1, 5.2, 5.2, left=0.9)
    ax = axes[0, 0]
    x, y = result.z[:, i], result.z[:, j]
    two_tone(ax, x, y, i0, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
    ax.set_xlabel(f"{column_name(result, i)} (m): {column_description(result, i)}")
    ax.set_ylabel(f"{column_name(result, j)} (m): {column_description(result, j)}")
    rx = np.ptp(x[np.isfinite(x)]) if np.isfinite(x).any() else 0.0
    ry = np.ptp(y[np.isfinite(y)]) if np.isfinite(y).any() else 0.0
    if rx > 0 and ry > 0 and 0.2 <= rx / ry <= 5.0:
        ax.set_aspect("equal", adjustable="datalim")
    else:
        ax.set_box_aspect(1.0)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    what = f"Lissajous figure {column_name(result, j)} against {column_name(result, i)}"
    return _finish(fig, result, title, what, path, notes)


def _plot_tensions(result, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    T = np.asarray(result.T, dtype=float)
    T0 = np.asarray(result.T0, dtype=float)
    nseg = T.shape[1]
    segs = list(range(nseg)) if nseg <= 6 else sorted({0, nseg // 2, nseg - 1})
    s = stride(t.size)
    fig, axes = figure_grid(1, 1, 7.4, 4.2)
    ax = axes[0, 0]
    for c, r in enumerate(segs):
        color = f"C{c % 10}"
        ax.plot(t[::s], T[::s, r] / 1e3, "-", color=color, lw=1.0, label=f"T{r + 1}(t)")
        ax.axhline(T0[r] / 1e3, ls="--", color=color, lw=1.0, alpha=0.8, label=f"static T{r + 1} = {T0[r] / 1e3:.4g} kN")
    rec = getattr(result, "slack", None)
    if rec is not None:
        _mark_slack(ax, rec, segs, float(t[-1]))
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("segment tension T (kN)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
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


def _mark_slack(ax, rec, segs, t_end):
    """Shade each shown segment's slack episodes and mark its peak tension (the snap load)."""
    for c, r in enumerate(segs):
        color = f"C{c % 10}"
        spans = slack_intervals(rec, r + 1, t_end)
        for i, (a, b) in enumerate(spans):
            ax.axvspan(a, b, color=color, alpha=0.15, lw=0, label=f"segment {r + 1} slack" if i == 0 else None)
        if spans:
            ax.plot(rec.peak_time[r], rec.peak_tension[r] / 1e3, "v", color=color, ms=7,
                    label=f"snap load T{r + 1} = {rec.peak_tension[r] / 1e3:.4g} kN at {rec.peak_time[r]:.4g} s")


def _plot_fft(result, chans, title, path, notes):
    from matplotlib.ticker import NullLocator

    t = np.asarray(result.t, dtype=float)
    modal = np.sort(np.asarray(result.modal_omega, dtype=float).ravel())
    modal = modal[np.isfinite(modal) & (modal > 0)]
    forcing = result.omega if result.omega is not None and np.isfinite(result.omega) and result.omega > 0 else None
    refs = list(modal[:4]) + ([float(forcing)] if forcing is not None else [])

    # First pass: the spectra, their peaks and a common frequency range: 1.5 x the largest of
    # the forcing and the 4 lowest modal frequencies, widened to show the strongest peak of
    # every channel, and capped at the Nyquist frequency.
    spectra = {}
    x_max = 0.0
    for i in chans:
        try:
            omega, amp, n, dt = amplitude_spectrum(t, result.z[:, i], 0.5)
        except CablesimError as exc:
            spectra[i] = exc
            continue
        w_pk, a_pk = spectral_peaks(omega, amp, 4, 0.05)
        spectra[i] = (omega, amp, n, dt, w_pk, a_pk)
        nyq = np.pi / dt
        top = 1.5 * max(refs) if refs else nyq
        if w_pk.size:
            top = max(top, 1.15 * w_pk[0])
        x_max = max(x_max, min(top, nyq))

    k = len(chans)
    fig, axes = figure_grid(k, 1, 8.6, 2.4, sharex=True, top=1.0, hspace=0.45, left=0.9)
    for ax, i in zip(axes[:, 0], chans):
        name = column_name(result, i)
        ax.set_ylabel(f"amplitude of {name} (m)", fontsize=9)
        ax.set_title(f"{name}: {column_description(result, i)}", fontsize=9, loc="left")
        ax.grid(True, alpha=0.25)
        if isinstance(spectra[i], CablesimError):
            ax.text(0.5, 0.5, f"no spectrum: {spectra[i]}", transform=ax.transAxes, ha="center", va="center",
                    color="C3", fontsize=9)
            continue
        omega, amp, n, dt, w_pk, a_pk = spectra[i]
        sel = omega <= x_max
        ax.semilogy(omega[sel], np.maximum(amp[sel], 1e-300), "-", color="C0", lw=1.0, label="amplitude spectrum")
        ax.yaxis.set_minor_locator(NullLocator())  # log minor ticks are slow to lay out
        a_top = amp[sel][1:].max() if sel.sum() > 1 else 0.0
        if a_top > 0:
            ax.set_ylim(a_top * 1e-6, a_top * 20.0)  # headroom for the labels
        inside = w_pk <= x_max
        w_pk, a_pk = w_pk[inside], a_pk[inside]
        if w_pk.size:
            ax.plot(w_pk, a_pk, "v", color="C3", ms=6, zorder=4, label="spectral peaks")
            for r, (w, a) in enumerate(sorted(zip(w_pk, a_pk))):
                ax.annotate(
                    f"{w:#.4g} rad/s",
                    (w, a),
                    textcoords="offset points",
                    xytext=(5, 4 + 10 * (r % 2)),
                    fontsize=8,
                    color="C3",
                )
        if forcing is not None and forcing <= x_max:
            ax.axvline(forcing, color="C1", ls="--", lw=1.0, alpha=0.6, label=f"forcing omega = {forcing:.4g} rad/s")
        shown = modal[modal <= x_max]
        listed = ", ".join(f"{w:.4g}" for w in shown[:4]) + (", ..." if shown.size > 4 else "")
        last_text = -np.inf
        for r, w in enumerate(shown):
            label = f"modal frequencies ({listed} rad/s)" if r == 0 else None
            ax.axvline(w, color="0.45", ls=":", lw=1.0, alpha=0.7, label=label)
            if w - last_text >= 0.08 * x_max and w < 0.93 * x_max:  # name the lines that have room
                last_text = w
                ax.text(w, 0.98, f" mode {r + 1}", transform=ax.get_xaxis_transform(), fontsize=7,
                        color="0.4", ha="left", va="top", clip_on=True)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
        info = f"{n} samples, dt = {dt:.3g} s, resolution 2 pi / T = {2 * np.pi / (n * dt):.3g} rad/s"
        ax.set_title(info, fontsize=7, loc="right", color="0.35")
    if x_max > 0:
        axes[-1, 0].set_xlim(0.0, x_max)
    axes[-1, 0].set_xlabel("circular frequency omega (rad/s)")
    return _finish(fig, result, title, "amplitude spectra of the steady part (last half, Hann window)", path, notes)


def plot_history(result, prefix, title: str, channels=None, pair=None) -> list[Path]:
    """Write the time-history figures of a run as PNG files.

    Parameters
    ----------
    result : cablesim.dynamics.result.HistoryResult
        The time history. If it kept only some DOF (``result.dof``), channels are looked up
        among the stored ones.
    prefix : str or Path
        Path prefix without suffix; the files are ``{prefix}-waveforms.png``,
        ``{prefix}-phase.png``, ``{prefix}-lissajous.png``, ``{prefix}-tensions.png`` and
        ``{prefix}-fft.png``.
    title : str
        First title line of every figure (the case name).
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
    return paths
