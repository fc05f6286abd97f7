"""The shared look of the figures: envelopes, numbers to their resolution, mode names, symbols,
provenance in the PNG and the preview stamp."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from cablesim.plots import base
from cablesim.plots.style import (
    decimals_for,
    grid_step,
    minmax_decimate,
    mode_symmetry,
    symbols,
    to_resolution,
)


def png_text_chunks(path) -> dict:
    """The tEXt/zTXt/iTXt chunks of a PNG file, read from its bytes."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, out = 8, {}
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"tEXt":
            key, _, value = body.partition(b"\0")
            out[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"zTXt":
            key, _, rest = body.partition(b"\0")
            out[key.decode("latin-1")] = zlib.decompress(rest[1:]).decode("latin-1")
        elif kind == b"iTXt":
            key, _, rest = body.partition(b"\0")
            flag, rest = rest[0], rest[2:]
            _, _, rest = rest.partition(b"\0")
            _, _, text = rest.partition(b"\0")
            out[key.decode("latin-1")] = (zlib.decompress(text) if flag else text).decode("utf-8")
    return out


# --------------------------------------------------------------------------------------------
# True envelopes
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("m, buckets", [(100_003, 500), (50_000, 1000), (7_919, 37)])
def test_minmax_decimation_keeps_each_buckets_extremes(m, buckets):
    rng = np.random.default_rng(m)
    t = np.linspace(0.0, 100.0, m)
    y = np.sin(7.3 * t) * (1 + 0.3 * rng.standard_normal(m))
    y[rng.integers(0, m, 5)] = [9.0, -8.0, 7.5, -7.0, 6.0]  # isolated spikes a stride would miss
    xd, yd = minmax_decimate(t, y, buckets)
    assert np.all(np.diff(xd) > 0)  # in time order, each sample once
    size = -(-m // buckets)
    for k in range(0, m, size):
        inside = (xd >= t[k]) & (xd <= t[min(k + size, m) - 1])
        assert yd[inside].min() == y[k:k + size].min()
        assert yd[inside].max() == y[k:k + size].max()
    assert yd.size <= 2 * buckets
    assert yd.max() == 9.0 and yd.min() == -8.0


def test_minmax_decimation_short_lines_and_nan():
    x, y = np.arange(10.0), np.arange(10.0) ** 2
    xd, yd = minmax_decimate(x, y, 5)
    assert xd is x or np.array_equal(xd, x)
    y = np.sin(np.linspace(0, 60, 10_000))
    y[:3000] = np.nan
    _, yd = minmax_decimate(np.arange(y.size), y, 100)
    assert np.nanmax(yd) == np.nanmax(y) and np.isfinite(yd).sum() >= 140


# --------------------------------------------------------------------------------------------
# Numbers to their resolution
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("value, resolution, unit, text", [
    (12.7751, 0.025, "", "12.78"),
    (1.6234, 0.043, "rad/s", "1.62 rad/s"),
    (0.8325, 0.43, "rad/s", "0.8 rad/s"),
    (38.8123, 0.001, "m", "38.812 m"),
    (600.0, 0.01, "s", "600.00 s"),
    (1234.0, 20.0, "", "1230"),
    (5.0, 1.0, "", "5"),
    (-0.0001, 0.01, "", "0.00"),
])
def test_numbers_are_printed_to_their_resolution(value, resolution, unit, text):
    assert to_resolution(value, resolution, unit) == text


def test_decimals_and_grid_step():
    assert [decimals_for(r) for r in (0.02, 0.1, 0.43, 1e-4, 3.0)] == [2, 1, 1, 4, 0]
    assert grid_step([0.5, 0.52, 0.54, 0.56]) == pytest.approx(0.02)
    assert np.isnan(grid_step([2.0]))


# --------------------------------------------------------------------------------------------
# Modes named by their shape
# --------------------------------------------------------------------------------------------


def _level_cable(n=3, span=300.0):
    x = span * np.arange(1, n + 1) / (n + 1)
    sag = 20.0 * np.sin(np.pi * x / span)
    return np.column_stack([x, sag])


def test_mode_symmetry_of_a_level_symmetric_cable():
    nodes = _level_cable()
    sym = np.array([0.1, 0.7, 0.0, 1.0, -0.1, 0.7])  # (horizontal, vertical) per node
    anti = np.array([0.3, 0.8, 0.5, 0.0, 0.3, -0.8])
    assert mode_symmetry(300.0, 0.0, nodes, sym) == "symmetric"
    assert mode_symmetry(300.0, 0.0, nodes, anti) == "antisymmetric"
    assert mode_symmetry(300.0, 0.0, nodes, np.array([0.0, 1.0, 0.0, 0.2, 0.0, 0.5])) == ""


def test_mode_symmetry_is_undecided_for_inclined_or_unsymmetric_cables():
    nodes = _level_cable()
    sym = np.array([0.1, 0.7, 0.0, 1.0, -0.1, 0.7])
    assert mode_symmetry(300.0, 20.0, nodes, sym) == ""  # inclined chord
    assert mode_symmetry(300.0, 0.0, nodes, sym, masses=[8e3, 14e3, 9e3]) == ""  # unsymmetric masses
    shifted = nodes + np.array([[0.0, 0.0], [0.0, 0.0], [10.0, 0.0]])
    assert mode_symmetry(300.0, 0.0, shifted, sym) == ""  # nodes not mirrored


# --------------------------------------------------------------------------------------------
# Symbols
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("plain, tex", [
    ("beats of z4 at w = 12.63 rad/s, xi = 0.002", r"beats of $z_{4}$ at $\omega$ = 12.63 rad/s, $\xi$ = 0.002"),
    ("FL = gamma [-300, 1100] kN", r"$F_{L}$ = $\gamma$ [-300, 1100] kN"),
    ("F0 = [300, 1100] kN, FL = 0.02 F0", r"$F_{0}$ = [300, 1100] kN, $F_{L}$ = 0.02 $F_{0}$"),
    ("Lissajous z2-z4 and T1 waveforms", r"Lissajous $z_{2}$-$z_{4}$ and $T_{1}$ waveforms"),
    ("z_c and z_e", r"$z_c$ and $z_e$"),
    ("forcing omega", r"forcing $\omega$"),
    ("two waves, EA = 1e12 N", "two waves, EA = 1e12 N"),
    ("already $z_2$ and w = 1", "already $z_2$ and w = 1"),
])
def test_plain_symbols_become_mathtext(plain, tex):
    assert symbols(plain) == tex


# --------------------------------------------------------------------------------------------
# Provenance and the stamp
# --------------------------------------------------------------------------------------------


def test_every_png_carries_version_commit_and_command(tmp_path, monkeypatch):
    from cablesim.io import provenance
    from cablesim.version import __version__

    monkeypatch.setattr(provenance, "_INVOCATION", {"command_line": "cablesim plot a.h5 -o b.png", "options": {}})
    fig, _ = base.figure_grid(1, 1, 2.0)
    png = base.save_atomic(fig, tmp_path / "meta.png")
    chunks = png_text_chunks(png)
    assert chunks["cablesim version"] == __version__
    assert chunks["Command"] == "cablesim plot a.h5 -o b.png"
    assert chunks["git commit"] == (provenance.git_commit() or "unknown (not a git checkout)")
    assert "Stamp" not in chunks


def test_the_stamp_is_drawn_and_recorded(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    drawn = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        drawn.append([t.get_text() for t in self.texts])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    with base.stamp_figures("preview: coarse grid"):
        fig, _ = base.figure_grid(1, 1, 2.0)
        png = base.save_atomic(fig, tmp_path / "stamped.png")
    fig, _ = base.figure_grid(1, 1, 2.0)
    base.save_atomic(fig, tmp_path / "plain.png")
    assert "preview: coarse grid" in drawn[0] and "preview: coarse grid" not in drawn[1]
    assert png_text_chunks(png)["Stamp"] == "preview: coarse grid"


def test_the_cable_drawing_names_the_lowest_modes_by_their_shape(tmp_path, monkeypatch):
    """A level cable with mirrored masses: its lowest modes are named symmetric/antisymmetric
    from their shapes; an inclined cable's modes are named by number only."""
    from matplotlib.figure import Figure

    from cablesim import api

    titles = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        titles.append(self._suptitle.get_text().replace("\u00a0", " "))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    level = api.load_case({"name": "level", "cable": {"L": 300.0, "H": 0.0, "S": [110.0, 100.0, 110.0], "EA": 1.0e9,
                                                      "masses": [1.0e4, 1.0e4]},
                           "loads": {"F0": [0.0, 1.0e5, 0.0, 1.0e5], "FL": [0.0, 1.0e3, 0.0, 1.0e3]}})
    api.static(level).plot(tmp_path / "level.png")
    assert "(mode 1, antisymmetric)" in titles[-1] and "(mode 2, symmetric)" in titles[-1]
    api.static(api.load_case(None)).plot(tmp_path / "inclined.png")  # the paper's example: H = 20 m
    assert "(mode 1)" in titles[-1] and "symmetric" not in titles[-1]


# --------------------------------------------------------------------------------------------
# Small stretches get an inset
# --------------------------------------------------------------------------------------------


def test_quiet_stretch_finds_a_small_ending_or_beginning():
    from cablesim.plots.insets import quiet_stretch

    t = np.linspace(0.0, 3.0, 3001)
    decaying = np.exp(-4.0 * t) * np.sin(20.0 * t)
    t0, t1, where = quiet_stretch(t, decaying)
    assert where == "late" and t1 == 3.0 and 0.3 < t0 < 1.0
    assert np.abs(decaying[t >= t0]).max() < 0.12 * np.abs(decaying).max()
    growing = np.where(t < 2.0, 0.02, 1.0) * np.sin(20.0 * t)
    t0, t1, where = quiet_stretch(t, growing)
    assert where == "early" and t0 == 0.0 and abs(t1 - 2.0) < 0.1
    assert quiet_stretch(t, np.sin(20.0 * t)) is None  # nothing small: no inset
