"""Time-history plots: waveforms, phase plots, Lissajous figure, tensions and spectra.

Plots a :class:`cablesim.dynamics.result.HistoryResult`. Channels are named as users write them:
``"z1"``, ``"z2"``, ... are the degrees of freedom 1, 2, ... (1-based) in the order
``[x1, x2, x3, x4, ...]`` = (horizontal, vertical) of node 1, then node 2, ...; so ``"z2k"`` is
the vertical displacement (pointing down) of node k. matplotlib is imported lazily through
:func:`cablesim.plotting._plt` (Agg backend).
"""

from __future__ import annotations

import numbers
import re
from pathlib import Path

import numpy as np

from .errors import CablesimError
from .plotting import _plt, save_atomic

#: Largest number of points drawn per line in the time-domain plots.
MAX_LINE_POINTS = 20000
#: Largest number of channels drawn in the waveform and spectrum figures.
MAX_CHANNELS = 8
#: Largest number of channels drawn in the phase figure.
MAX_PHASE_CHANNELS = 3
#: Zero-padding: the FFT length is about this many times the record length ...
_PAD_FACTOR = 8
#: ... but no longer than this (unless the record itself is longer).
_MAX_NFFT = 2**21

_CHANNEL_RE = re.compile(r"^\s*[zZ]?\s*(\d+)\s*$")


# --------------------------------------------------------------------------------------------
# Channels
# --------------------------------------------------------------------------------------------


def channel_index(name_or_int, n_dof: int) -> int:
    """Convert a channel name to a 0-based degree-of-freedom index.

    Parameters
    ----------
    name_or_int : str or int
        ``"z2"``, ``"2"`` or ``2``: degree of freedom 2 (1-based), i.e. the vertical
        displacement of node 1.
    n_dof : int
        Number of degrees of freedom of the cable (``2 n``).

    Returns
    -------
    int
        The 0-based index into the DOF axis of the result arrays.

    Raises
    ------
    CablesimError
        If the name is malformed or the channel does not exist.
    """
    hint = f"use z1 to z{n_dof} (z2k is the vertical displacement of node k)"
    if isinstance(name_or_int, bool):
        raise CablesimError(f"Channel {name_or_int!r} is not a channel name; {hint}.")
    if isinstance(name_or_int, numbers.Integral):
        k = int(name_or_int)
    elif isinstance(name_or_int, str):
        match = _CHANNEL_RE.match(name_or_int)
        if match is None:
            raise CablesimError(f"Channel name {name_or_int!r} is malformed; {hint}.")
        k = int(match.group(1))
    else:
        raise CablesimError(f"Channel {name_or_int!r} is not a channel name or number; {hint}.")
    if not 1 <= k <= n_dof:
        raise CablesimError(
            f"Channel {name_or_int!r} is out of range for a cable with {n_dof} degrees of freedom; {hint}."
        )
    return k - 1


def _channel_name(i: int) -> str:
    return f"z{i + 1}"


def _channel_desc(i: int) -> str:
    node, comp = divmod(i, 2)
    return f"node {node + 1}, {'horizontal' if comp == 0 else 'vertical (down +)'}"


def default_channels(n_dof: int) -> list[int]:
    """Default channels (0-based): vertical DOF of every node if n <= 3, else of 3 spread nodes."""
    n = n_dof // 2
    if n <= 3:
        nodes = list(range(1, n + 1))
    else:
        k1 = max(1, int(np.floor((n + 1) / 4 + 0.5)))
        nodes = sorted({k1, (n + 1) // 2, n + 1 - k1})
    return [2 * k - 1 for k in nodes]


def _resolve_channels(channels, n_dof: int) -> list[int]:
    if channels is None:
        return default_channels(n_dof)
    if isinstance(channels, (str, numbers.Integral)):
        channels = [channels]
    out: list[int] = []
    for c in channels:
        i = channel_index(c, n_dof)
        if i not in out:
            out.append(i)
    if not out:
        raise CablesimError("No channels were chosen to plot; name at least one, e.g. z2.")
    return out


# --------------------------------------------------------------------------------------------
# Stored columns: a history may keep only some DOF (``result.dof``)
# --------------------------------------------------------------------------------------------


def cable_dof(result) -> int:
    """Number of degrees of freedom of the cable (``2 n``), even if fewer columns were kept."""
    dofs = result.dof_numbers
    return max(int(np.asarray(result.y0).size), max(dofs) if len(dofs) else 0, int(result.z.shape[1]))


def stored_names(result) -> str:
    """The stored channels, for messages: ``"z2, z4"``."""
    return ", ".join(f"z{d}" for d in result.dof_numbers)


def column_of(result, channel) -> int:
    """Column of ``result.z`` (``v``, ``zc``, ``ze``) holding a channel.

    Raises
    ------
    CablesimError
        If the name is malformed or out of range for the cable, or the history did not keep
        that channel (the message names the stored ones).
    """
    i = channel_index(channel, cable_dof(result))
    dofs = list(result.dof_numbers)
    if i + 1 not in dofs:
        raise CablesimError(
            f"Channel {channel!r} (z{i + 1}) was not stored in this history: it kept only "
            f"{stored_names(result)} (outputs.channels). Choose among those, or rerun with the channel "
            "listed in outputs.channels."
        )
    return dofs.index(i + 1)


def resolve_columns(result, channels=None) -> list[int]:
    """Columns of ``result.z`` for the channels; default: the default channels that were stored.

    The default is the vertical DOF of every node (n <= 3) or of three spread nodes, among the
    stored channels; if none of those was kept, every stored channel.
    """
    if channels is None:
        dofs = list(result.dof_numbers)
        cols = [dofs.index(i + 1) for i in default_channels(cable_dof(result)) if i + 1 in dofs]
        return cols or list(range(len(dofs)))
    if isinstance(channels, (str, numbers.Integral)):
        channels = [channels]
    out: list[int] = []
    for c in channels:
        col = column_of(result, c)
        if col not in out:
            out.append(col)
    if not out:
        raise CablesimError(f"No channels were chosen to plot; name at least one of {stored_names(result)}.")
    return out


def default_pair(result):
    """Default Lissajous pair (columns): vertical DOF of the first and last node if stored.

    Otherwise the first two default (or stored) columns; None if fewer than two were kept.
    """
    n_dof = cable_dof(result)
    dofs = list(result.dof_numbers)
    want = (1, 2) if n_dof <= 2 else (2, n_dof)
    if all(d in dofs for d in want):
        return dofs.index(want[0]), dofs.index(want[1])
    cols = resolve_columns(result)
    if len(cols) < 2:
        cols = list(range(len(dofs)))
    return (cols[0], cols[1]) if len(cols) >= 2 else None


def col_name(result, col: int) -> str:
    """Channel name of a stored column, e.g. ``"z4"``."""
    return f"z{result.dof_numbers[col]}"


def col_desc(result, col: int) -> str:
    """What a stored column is, e.g. ``"node 2, vertical (down +)"``."""
    return _channel_desc(result.dof_numbers[col] - 1)


# --------------------------------------------------------------------------------------------
# Spectra
# --------------------------------------------------------------------------------------------


def _steady_uniform(t, signal, steady_fraction: float):
    """The last ``steady_fraction`` of the record, on a uniform grid: (dt, samples)."""
    t = np.asarray(t, dtype=float).ravel()
    x = np.asarray(signal, dtype=float).ravel()
    if t.shape != x.shape:
        raise CablesimError(
            f"The time axis ({t.size} samples) and the signal ({x.size} samples) differ in length."
        )
    if not (0.0 < float(steady_fraction) <= 1.0):
        raise CablesimError(f"steady_fraction must lie in (0, 1], got {steady_fraction!r}.")
    m = t.size
    n = int(round(float(steady_fraction) * m))
    if n < 8:
        raise CablesimError(
            f"The steady part of the record holds only {n} samples; a spectrum needs at least 8."
        )
    t, x = t[m - n :], x[m - n :]
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise CablesimError("The signal holds non-finite values, so its spectrum cannot be computed.")
    dts = np.diff(t)
    if np.any(dts < 0):
        raise CablesimError("The time axis is not increasing, so the spectrum cannot be computed.")
    dt = (t[-1] - t[0]) / (n - 1)
    if not dt > 0:
        raise CablesimError("The steady part of the record spans no time, so it has no spectrum.")
    if np.max(np.abs(dts - dt)) > 1e-6 * dt:
        # Not uniformly sampled (e.g. saved at adaptive steps): resample linearly.
        keep = np.concatenate(([True], dts > 0))
        t, x = t[keep], x[keep]
        grid = np.linspace(t[0], t[-1], n)
        x = np.interp(grid, t, x)
    return dt, x


def _amplitude_spectrum(t, signal, steady_fraction: float, pad_factor: int = _PAD_FACTOR):
    from scipy.fft import next_fast_len, rfft

    dt, x = _steady_uniform(t, signal, steady_fraction)
    n = x.size
    w = np.hanning(n + 2)[1:-1]  # Hann without its zero end points
    # Remove the mean as the window sees it (the plain mean of a sinusoid over a non-integer
    # number of periods is not zero and would leave a spurious zero-frequency lobe).
    scale = np.max(np.abs(x))
    x = x - np.dot(w, x) / w.sum()
    if np.max(np.abs(x)) <= 1e-12 * scale:
        x = np.zeros_like(x)  # a constant signal: leave no round-off "spectrum"
    nfft = next_fast_len(max(n, min(pad_factor * n, _MAX_NFFT)), real=True)
    X = rfft(x * w, n=nfft)
    amp = np.abs(X) / w.sum()  # coherent gain
    amp[1:] *= 2.0  # one-sided
    if nfft % 2 == 0:
        amp[-1] /= 2.0  # the Nyquist bin has no mirror image
    omega = 2.0 * np.pi * np.arange(amp.size) / (nfft * dt)
    return omega, amp, n, dt


def spectrum(t, signal, steady_fraction: float = 0.5):
    """One-sided amplitude spectrum of the steady part of a uniformly sampled signal.

    The last ``steady_fraction`` of the record has its mean removed, is multiplied by a Hann
    window and zero-padded (about 8 times, for a smooth curve); the magnitude is normalised by
    the window's coherent gain, so a sinusoid of amplitude ``A`` shows a peak of about ``A``.

    Parameters
    ----------
    t : array_like, shape (m,)
        Sample instants, s (uniform; a slightly non-uniform axis is resampled linearly).
    signal : array_like, shape (m,)
        The samples.
    steady_fraction : float, optional
        Fraction of the record, counted from its end, that is analysed (default: last half).

    Returns
    -------
    omega : ndarray
        Circular frequencies from 0 to the Nyquist frequency, rad/s.
    amplitude : ndarray
        Amplitude at each frequency, in the units of ``signal``.

    Raises
    ------
    CablesimError
        If the steady part has fewer than 8 samples, non-finite values or no duration.
    """
    omega, amp, _, _ = _amplitude_spectrum(t, signal, steady_fraction)
    return omega, amp


def _peaks(omega, amp, max_peaks: int, rel_height: float):
    """Refined (omega, amplitude) of the strongest local maxima, strongest first."""
    top = amp[1:].max() if amp.size > 2 else 0.0
    if not top > 0 or max_peaks < 1:
        return np.empty(0), np.empty(0)
    # Interior local maxima (the zero-frequency and Nyquist bins excluded) high enough.
    mid = amp[1:-1]
    idx = 1 + np.flatnonzero((mid > amp[:-2]) & (mid >= amp[2:]) & (mid >= rel_height * top))
    if idx.size == 0:
        return np.empty(0), np.empty(0)
    tiny = top * 1e-300 + np.finfo(float).tiny
    la, lb, lc = (np.log(np.maximum(amp[k], tiny)) for k in (idx - 1, idx, idx + 1))
    den = la - 2.0 * lb + lc
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.where(den < 0, 0.5 * (la - lc) / den, 0.0)
    p = np.clip(p, -0.5, 0.5)
    d_omega = omega[1] - omega[0]
    w_pk = omega[idx] + p * d_omega
    a_pk = np.exp(lb - 0.25 * (la - lc) * p)
    order = np.argsort(-a_pk, kind="stable")[:max_peaks]
    return w_pk[order], a_pk[order]


def spectrum_peaks(t, signal, steady_fraction: float = 0.5, max_peaks: int = 4, rel_height: float = 0.05):
    """Frequencies of the strongest peaks of the amplitude spectrum.

    Local maxima of :func:`spectrum` (the zero-frequency bin excluded) at least ``rel_height``
    times the largest amplitude are refined by fitting a parabola to the log-magnitude of the
    peak bin and its two neighbours; with the Hann window and the zero-padding this locates a
    pure sinusoid's frequency to a small fraction of a bin width ``2 pi / T`` (T: duration of
    the analysed part).

    Parameters
    ----------
    t, signal : array_like, shape (m,)
        As in :func:`spectrum`.
    steady_fraction : float, optional
        Fraction of the record, counted from its end, that is analysed.
    max_peaks : int, optional
        Largest number of peaks returned.
    rel_height : float, optional
        Peaks lower than this fraction of the highest one are ignored.

    Returns
    -------
    ndarray
        Peak frequencies, rad/s, strongest first (empty for a constant signal).
    """
    omega, amp, _, _ = _amplitude_spectrum(t, signal, steady_fraction)
    return _peaks(omega, amp, int(max_peaks), float(rel_height))[0]


# --------------------------------------------------------------------------------------------
# Figure helpers
# --------------------------------------------------------------------------------------------


def _stride(m: int, max_points: int = MAX_LINE_POINTS) -> int:
    return max(1, -(-m // max_points))


def _describe(result) -> str:
    if result.omega is None:
        forcing = "free vibration"
    else:
        forcing = f"forcing omega = {result.omega:.4g} rad/s"
    t = np.asarray(result.t)
    span = f"t = {t[0]:.4g} to {t[-1]:.4g} s" if t.size else "no samples"
    return f"{forcing}, {result.analysis} analysis, {result.integrator}, {span}"


def _figure(nrows, ncols, ax_w, ax_h, *, sharex=False, top=0.75, hspace=0.25, wspace=0.9, left=1.0):
    """Figure with fixed margins in inches (no layout engine: log axes make those slow).

    ``top`` leaves room for the two-line figure title (plus any axes titles); the saved file
    is cropped to its content by ``save_atomic`` (``bbox_inches="tight"``).
    """
    plt = _plt()
    right, bottom = 0.3, 0.65
    width = left + ncols * ax_w + (ncols - 1) * wspace + right
    height = top + nrows * ax_h + (nrows - 1) * hspace + bottom
    fig, axes = plt.subplots(nrows, ncols, sharex=sharex, squeeze=False, figsize=(width, height))
    fig.subplots_adjust(
        left=left / width,
        right=1 - right / width,
        bottom=bottom / height,
        top=1 - top / height,
        hspace=hspace / ax_h,
        wspace=wspace / ax_w,
    )
    return fig, axes


def _finish(fig, result, title: str, what: str, path: Path, notes: list[str] = ()) -> Path:
    height = fig.get_figheight()
    fig.suptitle(f"{title}: {what}\n{_describe(result)}", fontsize=10, y=1 - 0.08 / height, va="top")
    lines = []
    if result.status != "completed":
        lines.append(f"run stopped early: {result.status}")
    lines += list(notes)
    if lines:
        fig.text(
            0.5,
            0.0,
            "\n".join(lines),
            ha="center",
            va="top",
            color="red" if result.status != "completed" else "0.3",
            fontsize=9,
            fontweight="bold" if result.status != "completed" else "normal",
        )
    return save_atomic(fig, path)


def _t_split(t: np.ndarray, steady_fraction: float = 0.5) -> int:
    """Index where the steady part (last ``steady_fraction``) starts."""
    return t.size - int(round(steady_fraction * t.size))


def _two_tone(ax, x, y, i0, label_early, label_late, color="C0"):
    """Draw the early part of a curve light and the latter part dark."""
    s = _stride(x.size)
    ax.plot(x[: i0 + 1 : s], y[: i0 + 1 : s], "-", color=color, alpha=0.3, lw=0.7, label=label_early)
    ax.plot(x[i0::s], y[i0::s], "-", color="k", lw=0.9, label=label_late)
    if x.size:
        ax.plot(x[-1], y[-1], "o", color="C3", ms=4, zorder=3, label="end of run")


# --------------------------------------------------------------------------------------------
# The five figures
# --------------------------------------------------------------------------------------------


def _plot_waveforms(result, chans, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    s = _stride(t.size)
    k = len(chans)
    fig, axes = _figure(k, 1, 8.6, 2.0, sharex=True, top=0.95, hspace=0.2, left=1.3)
    split = result.zc is not None or result.ze is not None
    for ax, i in zip(axes[:, 0], chans):
        ax.plot(t[::s], result.z[::s, i], "-", color="C0", lw=1.2, label="z = z_c + z_e" if split else "z")
        if result.zc is not None:
            ax.plot(t[::s], result.zc[::s, i], "--", color="C1", lw=0.9, label="configurational part z_c")
        if result.ze is not None:
            ax.plot(t[::s], result.ze[::s, i], "-", color="C2", lw=0.8, alpha=0.8, label="elastic part z_e")
        ax.set_ylabel(f"{col_name(result, i)} (m)\n{col_desc(result, i)}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=3, fontsize=8, frameon=False)
    axes[-1, 0].set_xlabel("time t (s)")
    return _finish(fig, result, title, "displacements from the static equilibrium", path, notes)


def _plot_phase(result, chans, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    chans = chans[:MAX_PHASE_CHANNELS]
    i0 = _t_split(t)
    t_s = t[min(i0, t.size - 1)] if t.size else 0.0
    k = len(chans)
    fig, axes = _figure(1, k, 3.8, 3.8, top=1.0, wspace=0.95)
    for ax, i in zip(axes[0], chans):
        name = col_name(result, i)
        _two_tone(ax, result.z[:, i], result.v[:, i], i0, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
        ax.set_xlabel(f"{name} (m)")
        ax.set_ylabel(f"{name}' (m/s)")
        ax.set_title(f"{name}: {col_desc(result, i)}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0, -1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    return _finish(fig, result, title, "phase plots (velocity against displacement)", path, notes)


def _plot_lissajous(result, pair, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    i, j = pair
    i0 = _t_split(t)
    t_s = t[min(i0, t.size - 1)] if t.size else 0.0
    fig, axes = _figure(1, 1, 5.2, 5.2, left=0.9)
    ax = axes[0, 0]
    x, y = result.z[:, i], result.z[:, j]
    _two_tone(ax, x, y, i0, f"t < {t_s:.4g} s", f"t >= {t_s:.4g} s (last half)")
    ax.set_xlabel(f"{col_name(result, i)} (m): {col_desc(result, i)}")
    ax.set_ylabel(f"{col_name(result, j)} (m): {col_desc(result, j)}")
    rx = np.ptp(x[np.isfinite(x)]) if np.isfinite(x).any() else 0.0
    ry = np.ptp(y[np.isfinite(y)]) if np.isfinite(y).any() else 0.0
    if rx > 0 and ry > 0 and 0.2 <= rx / ry <= 5.0:
        ax.set_aspect("equal", adjustable="datalim")
    else:
        ax.set_box_aspect(1.0)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    what = f"Lissajous figure {col_name(result, j)} against {col_name(result, i)}"
    return _finish(fig, result, title, what, path, notes)


def _plot_tensions(result, title, path, notes):
    t = np.asarray(result.t, dtype=float)
    T = np.asarray(result.T, dtype=float)
    T0 = np.asarray(result.T0, dtype=float)
    nseg = T.shape[1]
    segs = list(range(nseg)) if nseg <= 6 else sorted({0, nseg // 2, nseg - 1})
    s = _stride(t.size)
    fig, axes = _figure(1, 1, 7.4, 4.2)
    ax = axes[0, 0]
    for c, r in enumerate(segs):
        color = f"C{c % 10}"
        ax.plot(t[::s], T[::s, r] / 1e3, "-", color=color, lw=1.0, label=f"T{r + 1}(t)")
        ax.axhline(T0[r] / 1e3, ls="--", color=color, lw=1.0, alpha=0.8, label=f"static T{r + 1} = {T0[r] / 1e3:.4g} kN")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("segment tension T (kN)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    which = "all segments" if nseg <= 6 else f"segments {', '.join(str(r + 1) for r in segs)} of {nseg}"
    return _finish(fig, result, title, f"segment tensions ({which})", path, notes)


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
            omega, amp, n, dt = _amplitude_spectrum(t, result.z[:, i], 0.5)
        except CablesimError as exc:
            spectra[i] = exc
            continue
        w_pk, a_pk = _peaks(omega, amp, 4, 0.05)
        spectra[i] = (omega, amp, n, dt, w_pk, a_pk)
        nyq = np.pi / dt
        top = 1.5 * max(refs) if refs else nyq
        if w_pk.size:
            top = max(top, 1.15 * w_pk[0])
        x_max = max(x_max, min(top, nyq))

    k = len(chans)
    fig, axes = _figure(k, 1, 8.6, 2.4, sharex=True, top=1.0, hspace=0.45, left=0.9)
    for ax, i in zip(axes[:, 0], chans):
        name = col_name(result, i)
        ax.set_ylabel(f"amplitude of {name} (m)", fontsize=9)
        ax.set_title(f"{name}: {col_desc(result, i)}", fontsize=9, loc="left")
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
