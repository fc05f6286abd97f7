"""Tests of the time-history plots and the spectrum helpers."""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.dynamics.result import HistoryResult
from cablesim.errors import CablesimError
from cablesim.channels import channel_index
from cablesim.dynamics.status import Status
from cablesim.dynamics.spectra import spectrum, spectrum_peaks
from cablesim.plots.history import plot_history

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
SUFFIXES = ["waveforms", "phase", "lissajous", "tensions", "fft"]


def _two_tone(t, mean=0.0):
    # Frequencies deliberately not on a bin of the (unpadded) FFT of the last half.
    w1, a1, w2, a2 = 2.5031, 0.05, 6.7777, 0.02
    x = mean + a1 * np.sin(w1 * t + 0.7) + a2 * np.cos(w2 * t + 0.2)
    return x, (w1, a1, w2, a2)


# --------------------------------------------------------------------------------------------
# spectrum / spectrum_peaks
# --------------------------------------------------------------------------------------------


def test_spectrum_two_sinusoids_frequencies_and_amplitudes():
    t = np.arange(40000) * 0.02  # 800 s; the last half has a bin width of 2 pi / 400 s
    x, (w1, a1, w2, a2) = _two_tone(t, mean=0.37)
    peaks = spectrum_peaks(t, x)
    assert peaks.shape == (2,)
    assert abs(peaks[0] - w1) < 1e-3  # strongest first
    assert abs(peaks[1] - w2) < 1e-3
    omega, amp = spectrum(t, x)
    assert omega.shape == amp.shape
    assert omega[0] == 0.0
    assert omega[-1] == pytest.approx(np.pi / 0.02, rel=1e-3)  # up to Nyquist
    for w, a in [(w1, a1), (w2, a2)]:
        near = np.abs(omega - w) < 0.05
        assert amp[near].max() == pytest.approx(a, rel=0.02)
    # The mean (0.37) is removed: nothing left at zero frequency.
    assert amp[0] < 1e-9
    assert amp[omega < 1.0].max() < 1e-3 * a2


def test_spectrum_peak_is_sub_bin_accurate_for_a_pure_sinusoid():
    dt, m = 0.01, 30000
    t = np.arange(m) * dt
    bin_width = 2 * np.pi / (0.5 * m * dt)
    for w in (3.0 + 0.37 * bin_width, 11.0 + 0.5 * bin_width, 1.3):
        (peak,) = spectrum_peaks(t, 1.5 * np.sin(w * t), max_peaks=1)
        assert abs(peak - w) < 0.01 * bin_width


def test_spectrum_peaks_rel_height_and_max_peaks():
    t = np.arange(40000) * 0.02
    x, (w1, _, w2, _) = _two_tone(t)
    # The second tone is 0.4 of the first: rel_height 0.5 drops it.
    assert spectrum_peaks(t, x, rel_height=0.5) == pytest.approx([w1], abs=1e-3)
    assert spectrum_peaks(t, x, max_peaks=1) == pytest.approx([w1], abs=1e-3)
    assert spectrum_peaks(t, np.full_like(t, 2.0)).size == 0  # constant: no peaks


def test_steady_fraction_ignores_decaying_transient():
    t = np.arange(40000) * 0.02  # 800 s
    x, (w1, a1, w2, a2) = _two_tone(t)
    # A large transient at 4 rad/s (amplitude 10) that has died out (to ~1e-6) by the time the
    # last half starts.
    transient = 10.0 * np.exp(-0.04 * t) * np.sin(4.0 * t)
    peaks = spectrum_peaks(t, x + transient)
    assert peaks == pytest.approx([w1, w2], abs=1e-3)
    omega, amp = spectrum(t, x + transient)
    assert amp[np.abs(omega - 4.0) < 0.05].max() < 1e-6
    near = np.abs(omega - w1) < 0.05
    assert amp[near].max() == pytest.approx(a1, rel=0.02)
    # Analysing the whole record instead shows the transient.
    omega, amp = spectrum(t, x + transient, steady_fraction=1.0)
    assert amp[np.abs(omega - 4.0) < 0.05].max() > 1e-3
    assert np.min(np.abs(spectrum_peaks(t, x + transient, steady_fraction=1.0) - 4.0)) < 0.01


def test_spectrum_input_errors():
    t = np.arange(100) * 0.1
    with pytest.raises(CablesimError):
        spectrum(t, np.sin(t)[:50])
    with pytest.raises(CablesimError):
        spectrum(t, np.sin(t), steady_fraction=0.0)
    with pytest.raises(CablesimError):
        spectrum(t[:10], np.sin(t[:10]))  # 5 samples in the last half


# --------------------------------------------------------------------------------------------
# channel_index
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name, expected", [("z2", 1), ("2", 1), (2, 1), ("Z4", 3), (" z1 ", 0), (np.int64(3), 2)])
def test_channel_index_accepts(name, expected):
    assert channel_index(name, 4) == expected


@pytest.mark.parametrize("name", ["z0", "z5", 0, 5, -1, "x2", "z", "z2.5", "", "zz2", 2.0, None, True])
def test_channel_index_rejects(name):
    with pytest.raises(CablesimError) as info:
        channel_index(name, 4)
    message = str(info.value)
    assert "z1 to z4" in message
    assert message.count(".") <= 2  # one sentence (plus the quoted name)


# --------------------------------------------------------------------------------------------
# plot_history
# --------------------------------------------------------------------------------------------


def _history(split: bool, status: str = "completed", omega: float | None = 2.5, m: int = 6001):
    """A synthetic n = 2 history: every DOF a mix of the forcing and the two lowest modes."""
    t = np.linspace(0.0, 120.0, m)
    modal = np.array([1.7, 3.9, 9.5, 14.2])
    w = omega if omega is not None else modal[0]
    decay = np.exp(-0.05 * t)
    z = np.empty((m, 4))
    v = np.empty((m, 4))
    for k in range(4):
        a, b = 0.01 * (k + 1), 0.004 * (4 - k)
        z[:, k] = a * np.sin(w * t + k) + b * decay * np.sin(modal[1] * t)
        v[:, k] = a * w * np.cos(w * t + k) + b * decay * (modal[1] * np.cos(modal[1] * t) - 0.05 * np.sin(modal[1] * t))
    T0 = np.array([12e3, 11e3, 12.5e3])
    T = T0 + 800.0 * np.sin(w * t[:, None] + np.arange(3))
    return HistoryResult(
        t=t,
        z=z,
        v=v,
        zc=0.8 * z if split else None,
        ze=0.2 * z if split else None,
        T=T,
        residual=np.full(m, 1e-9),
        y0=np.array([5.0, 2.0, 10.0, 2.5]),
        T0=T0,
        omega=omega,
        analysis="exact",
        integrator="newmark",
        status=Status.COMPLETED if status == "completed" else Status.STEP_UNDERFLOW,
        message=status,
        t_stop=None if status == "completed" else 80.0,
        modal_omega=modal,
        settings={},
    )


def _check_pngs(paths, prefix):
    assert [p.name for p in paths] == [f"{prefix.name}-{s}.png" for s in SUFFIXES]
    for p in paths:
        data = p.read_bytes()
        assert data[:8] == PNG_MAGIC
        assert len(data) > 5000
    assert not list(prefix.parent.glob("*.part.png"))


def test_plot_history_writes_five_pngs(tmp_path):
    # zc/ze present, completed, forced, default channels (z2, z4) and pair.
    prefix = tmp_path / "out" / "case-history"
    paths = plot_history(_history(True), prefix, "test case")
    _check_pngs(paths, prefix)


def test_plot_history_stopped_free_custom_channels(tmp_path):
    # No zc/ze, stopped early, free vibration; channels and pair given explicitly.
    result = _history(False, "stopped at t = 80 s: step size underflow", None)
    prefix = tmp_path / "custom"
    paths = plot_history(result, prefix, "custom channels", channels=["z1", 4, "3"], pair=("z1", "z3"))
    _check_pngs(paths, prefix)


def test_plot_history_many_nodes_and_short_run(tmp_path):
    # n = 7 nodes (default: 3 spread nodes), 8 segments (tensions: first, middle, last), and a
    # run stopped after a few samples (too short for a spectrum: the figure says so).
    m = 9
    t = np.linspace(0.0, 0.08, m)
    z = 1e-3 * np.sin(np.outer(t, np.arange(1, 15)))
    T0 = np.linspace(10e3, 12e3, 8)
    result = HistoryResult(
        t=t, z=z, v=z.copy(), zc=None, ze=None, T=T0 + 0 * t[:, None], residual=np.zeros(m),
        y0=np.zeros(14), T0=T0, omega=None, analysis="approximate", integrator="rk45",
        status=Status.NONFINITE, message="diverged", t_stop=0.08, modal_omega=np.array([]),
    )
    prefix = tmp_path / "short"
    _check_pngs(plot_history(result, prefix, "short run"), prefix)


@pytest.mark.parametrize("kwargs", [{"channels": ["z9"]}, {"channels": ["q2"]}, {"pair": ("z2", "z5")}, {"pair": "z2"}])
def test_plot_history_bad_channels(tmp_path, kwargs):
    with pytest.raises(CablesimError):
        plot_history(_history(False), tmp_path / "bad", "bad", **kwargs)
    assert not list(tmp_path.glob("*.png"))


def test_waveforms_are_drawn_as_true_envelopes(tmp_path, monkeypatch):
    """A long record is thinned to the extremes of each bucket, never to every k-th sample: a
    one-sample spike and each bucket's extremes stay on the drawn line."""
    from matplotlib.figure import Figure

    drawn = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        drawn.append([(ln.get_xdata(), ln.get_ydata()) for ax in self.axes for ln in ax.lines])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    result = _history(False, m=120_001)
    spike = 54_321  # not a multiple of any stride
    result.z[spike, 1] = 0.5
    plot_history(result, tmp_path / "env", "envelope", channels=["z2"])
    t_drawn, z_drawn = drawn[0][0]  # waveforms: the first line of the first axes
    assert z_drawn.max() == 0.5 and t_drawn[np.argmax(z_drawn)] == result.t[spike]
    assert z_drawn.size < 10_000
    z = result.z[:, 1]
    for lo in range(0, z.size, 20_000):  # each stretch's extremes are on the line
        inside = (t_drawn >= result.t[lo]) & (t_drawn <= result.t[min(lo + 19_999, z.size - 1)])
        assert z_drawn[inside].min() == pytest.approx(z[lo:lo + 20_000].min(), abs=0.0005)
        assert z_drawn[inside].max() == pytest.approx(z[lo:lo + 20_000].max(), abs=0.0005)


def test_spectrum_labels_state_the_window_and_print_peaks_to_the_bin(tmp_path, monkeypatch):
    """The spectrum names the window it analysed and its bin width; peak labels carry the digits
    the bin allows; a run that stopped early is analysed whole (its longest stretch)."""
    from matplotlib.figure import Figure

    seen = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        notes = [lg.get_title().get_text() for lg in self.legends]  # the notes under the figure
        notes += [self._supxlabel.get_text()] if getattr(self, "_supxlabel", None) is not None else []
        seen.append([t.get_text() for ax in self.axes for t in [ax.title, ax._right_title, *ax.texts]]
                    + [" ".join(n.split()) for n in notes])  # unwrapped
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    plot_history(_history(False), tmp_path / "done", "spectrum", channels=["z2"])
    texts = seen[-1]
    window = [t for t in texts if "window $t$" in t]
    assert len(window) == 1 and "window $t$ = 60.02 s to 120.00 s (last half); bins $2\\pi/T$ = 0.1 rad/s" in window[0]
    assert "2.5" in texts  # the forcing at 2.5 rad/s, to the 0.1 rad/s bin: one decimal
    assert not any(t.startswith("2.50") for t in texts)
    stopped = _history(False, "stopped at t = 80 s: step size underflow")
    plot_history(stopped, tmp_path / "stopped", "spectrum", channels=["z2"])
    assert any("window $t$ = 0.00 s to 120.00 s (whole run, stopped early)" in t for t in seen[-1])
