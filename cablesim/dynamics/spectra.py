"""Amplitude spectra of sampled signals and their peak frequencies.

Used by the text summaries (response frequencies) and the spectrum plots.
"""

from __future__ import annotations

import numpy as np

from ..errors import CablesimError

#: Zero-padding: the FFT length is about this many times the record length ...
PAD_FACTOR = 8
#: ... but no longer than this (unless the record itself is longer).
MAX_NFFT = 2**21


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


def amplitude_spectrum(t, signal, steady_fraction: float, pad_factor: int = PAD_FACTOR):
    """``(omega, amplitude, n, dt)``: :func:`spectrum` with the analysed sample count and step."""
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
    nfft = next_fast_len(max(n, min(pad_factor * n, MAX_NFFT)), real=True)
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
    omega, amp, _, _ = amplitude_spectrum(t, signal, steady_fraction)
    return omega, amp


def spectral_peaks(omega, amp, max_peaks: int, rel_height: float):
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
    omega, amp, _, _ = amplitude_spectrum(t, signal, steady_fraction)
    return spectral_peaks(omega, amp, int(max_peaks), float(rel_height))[0]
