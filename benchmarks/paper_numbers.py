"""Every number docs/paper-reproduction.md quotes for cablesim, computed from stored results.

``python benchmarks/paper_numbers.py [RESULTS] --check docs/paper-numbers.json`` (what ``make
paper-numbers`` runs after building any missing or outdated result in RESULTS, default
runs/paper) prints each number with its resolution and exits 1 if the file differs;
``--write FILE`` rewrites the file instead. Nothing is simulated here: sweeps, histories and
continuations are read from their HDF5 files; only the modal frequencies of load cases no scene
stores are recomputed (a static solution, instantaneous).

Each number is stored under a key with the text the document prints (``"text"``), the value,
the unit, its resolution in words and the result it comes from. The document tags each quoted
number with its key (``6.56<!--=fig4.peak.g0.06.z2-->``) and tests/test_paper_reproduction.py
checks every tag against the file. Rules for the printed digits:

- a frequency read off a sweep is a grid point: printed to the grid step; entries with ``grid``
  name the scene whose grid it belongs to (the FAST grids must contain them);
- a frequency read off a spectrum: printed to the bin width 2 pi / T of the analysed record;
- a bifurcation of a continuation: located to about 1e-9 rad/s, printed to 1e-5 or 1e-4;
- an amplitude: 3 significant digits (the steady-state test's tolerance is 1e-5 relative), but
  a peak amplitude read off a grid is only the largest grid value: the document quotes the local
  refinement beside it;
- a time of a history: printed to the output step or to the block over which it is measured.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import h5py
import numpy as np
from scipy.signal import find_peaks

from cablesim.api import static
from cablesim.case import parse_case
from cablesim.dynamics.spectra import spectrum_peaks
from cablesim.io.continuation import read_continuation
from cablesim.io.hdf5 import read_case_text, read_history
from cablesim.io.sweeps import read_sweep
from cablesim.plots.style import decimals_for as decimals  # the plots' rule: a number to its resolution

#: The steady-state tolerance makes amplitudes good to far more digits; the document uses 3.
AMP_DIGITS = 3


class Numbers:
    """The quoted numbers, in the order they are computed."""

    def __init__(self):
        self.items: dict[str, dict] = {}

    def add(self, key, value, text, unit, resolution, source, grid=None):
        if key in self.items:
            raise KeyError(f"{key} computed twice")
        item = dict(text=text, value=float(value), unit=unit, resolution=resolution, source=source)
        if grid is not None:
            item["grid"] = grid
        self.items[key] = item
        print(f"  {key:32s} {text:>10s} {unit:6s} ({resolution}; {source})")

    def freq(self, key, w, step, source, grid=None):
        """A frequency read off a grid of the given step (or located to it), printed to the step."""
        self.add(key, w, f"{w:.{step_decimals(step)}f}", "rad/s", f"grid step {step:.3g} rad/s", source, grid)

    def spaced(self, key, w, spacing, source):
        """The frequency of a continuation point, printed to the spacing of the points there."""
        self.add(key, w, f"{w:.{decimals(spacing)}f}", "rad/s",
                 f"continuation points {spacing:.2g} rad/s apart there", source)

    def amp(self, key, a, source, note="3 significant digits", digits=AMP_DIGITS):
        self.add(key, a, significant(a, digits), "m", note, source)



def step_decimals(step: float) -> int:
    """Decimals that print every point of a grid of this step (0.025 -> 3, 0.02 -> 2); a step that
    is not a round number (a continuation's local spacing) is printed to its resolution."""
    for d in range(7):
        if abs(round(step, d) - step) < 1e-9 * max(1.0, step):
            return d
    return decimals(step)


def significant(x: float, digits: int) -> str:
    """``x`` to ``digits`` significant digits in fixed notation (0.00523 -> '0.00523')."""
    if x == 0:
        return "0"
    d = max(0, digits - 1 - math.floor(math.log10(abs(x))))
    return f"{x:.{d}f}"


def grid_step(omega: np.ndarray) -> float:
    steps = np.diff(np.sort(omega))
    return float(np.round(steps.max(), 10))


def read_grid(N, D, src: str, key: str):
    """A scene's sweep and its grid step, the step recorded as the number ``key``."""
    sw = read_sweep(read(D / src))
    step = grid_step(sw.omega)
    N.freq(key, step, step, src)
    return sw, step


def curve(sw, direction="independent", gamma=None):
    for c in sw.curves:
        if c.direction == direction and (gamma is None or np.isclose(c.gamma, gamma)):
            return c.data
    raise KeyError(f"{sw.path}: no curve {direction} gamma={gamma}")


def grid_peak(sw, data, channel, lo, hi):
    """Largest amplitude of ``channel`` over the steady, not failed points in [lo, hi]."""
    j = sw.channels.index(channel)
    ok = (sw.omega >= lo - 1e-9) & (sw.omega <= hi + 1e-9) & data["done"] & ~data["failed"]
    i = np.flatnonzero(ok)[np.argmax(data["amplitude"][ok, j])]
    return float(sw.omega[i]), float(data["amplitude"][i, j])


def branch_peak(cont, channel, lo, hi, period=1):
    """Largest amplitude of ``channel`` on the branches of ``period`` over [lo, hi]; the local
    spacing of the continuation's points there (the resolution of the peak's frequency)."""
    j = cont["channels"].index(channel)
    best = None
    for b in cont["branches"]:
        if b["period"] != period:
            continue
        w, a = b["omega"], b["amplitude"][:, j]
        m = np.flatnonzero((w >= lo) & (w <= hi))
        if m.size == 0:
            continue
        i = m[np.argmax(a[m])]
        if best is None or a[i] > best[1]:
            nb = [k for k in (i - 1, i + 1) if 0 <= k < w.size]
            best = (float(w[i]), float(a[i]), float(max(abs(w[k] - w[i]) for k in nb)))
    return best


def bifurcations(cont, kind):
    bif = cont["bifurcations"]
    idx = [i for i, k in enumerate(bif["kind"]) if k == kind]
    order = np.argsort([bif["omega"][i] for i in idx])
    return [(float(bif["omega"][idx[k]]), bif["amplitude"][idx[k]]) for k in order]


def envelope(t, z, block):
    """Largest |z| over consecutive blocks of ``block`` seconds: (block starts, values)."""
    edges = np.arange(t[0], t[-1], block)
    k = np.searchsorted(t, edges)
    k = np.append(k, t.size)
    env = np.array([np.abs(z[a:b]).max() if b > a else 0.0 for a, b in zip(k[:-1], k[1:])])
    return edges, env


def jump_time(t, z, omega):
    """The jump time used for every late jump (Figs. 3b and 8c): the start of the first block
    from which the envelope (largest |z| per block of one period-2 orbit, 4 pi / w) stays above
    half its final value (the envelope's median over the last tenth of the run).

    Returns (time, block length, final amplitude)."""
    block = 4 * np.pi / omega
    edges, env = envelope(t, z, block)
    final = float(np.median(env[-max(1, env.size // 10):]))
    below = np.flatnonzero(env < 0.5 * final)
    start = edges[below[-1] + 1] if below.size else edges[0]
    return float(start), block, final


def read(path):
    if not Path(path).is_file():
        raise SystemExit(f"{path} is missing: run `make paper-numbers` (it builds the results first).")
    return path


def fig2(N, D):
    src = "fig2.h5"
    h = read_history(read(D / src))
    z = h.z[:, h.dof_numbers.index(2)]
    N.add("fig2.mode3", h.modal_omega[2], f"{h.modal_omega[2]:.2f}", "rad/s", "linear modal analysis", src)
    dt = float(np.median(np.diff(h.t)))
    pk, _ = find_peaks(np.abs(z))
    for k, i in enumerate(pk[:6], start=1):
        N.add(f"fig2.extreme{k}.t", h.t[i], f"{h.t[i]:.{decimals(dt)}f}", "s", f"output step {dt:g} s", src)
        N.add(f"fig2.extreme{k}.z2", z[i], f"{z[i]:+.{max(0, 1 - math.floor(math.log10(abs(z[i]))))}f}", "m",
              "2 significant digits", src)
    same = [k for k in range(1, min(6, pk.size)) if np.sign(z[pk[k]]) == np.sign(z[pk[k - 1]])]
    if not same:
        raise SystemExit("fig2: no two consecutive extremes of z2 of the same sign")
    first = same[0]  # the pair is extremes `first` and `first + 1` (counted from 1)
    N.add("fig2.samesign.first", first, f"{first}", "", "count", src)
    N.add("fig2.samesign.second", first + 1, f"{first + 1}", "", "count", src)
    ratio = 100 * abs(z[pk[first - 1]]) / abs(z[pk[0]])
    N.add("fig2.samesign.percent", ratio, f"{ratio:.0f}", "%", "of the first extreme, to 1 %", src)


def fig3a(N, D):
    src = "fig3a.h5"
    sw, step = read_grid(N, D, src, "fig3a.step")
    d = curve(sw)
    for k, w in enumerate(sw.modal[:4], start=1):
        N.add(f"fig3a.mode{k}", w, significant(w, 4), "rad/s", "linear modal analysis, 4 digits", src)
    N.add("fig3a.points", sw.omega.size, f"{sw.omega.size}", "", "count", src)
    N.add("fig3a.steady", d["steady"].sum(), f"{int(d['steady'].sum())}", "", "count", src)
    cap = float(sw.attrs["cap"])
    N.add("fig3a.cap", cap, f"{cap:.0f}", "s", "setting", src)
    for name, lo, hi in (("fundamental", 2.0, 3.0), ("irregular", 1.0, 1.5)):
        for ch in ("z2", "z4"):
            w, a = grid_peak(sw, d, ch, lo, hi)
            N.freq(f"fig3a.{name}.{ch}.omega", w, step, src, grid="fig3a")
            N.amp(f"fig3a.{name}.{ch}", a, src, "largest grid value, 3 significant digits")
    sub = np.flatnonzero(d["period"] >= 2)
    N.freq("fig3a.band.lo", sw.omega[sub[0]], step, src, grid="fig3a")
    N.freq("fig3a.band.hi", sw.omega[sub[-1]], step, src, grid="fig3a")
    N.amp("fig3a.band.z2", d["amplitude"][sub, 0].max(), src)
    N.freq("fig3a.band.response", d["response_frequency"][sub[0], 0], step / 2, src)
    unsteady = np.flatnonzero(~d["steady"])
    for k, i in enumerate(unsteady, start=1):
        N.freq(f"fig3a.unsteady{k}", sw.omega[i], step, src, grid="fig3a")
    with h5py.File(D / src) as f:
        floq = f["sweep/floquet"][()]
        w = f["sweep/omega"][()]
    i = int(np.argmin(abs(w - 5.10)))
    N.freq("fig3a.at510", w[i], step, src, grid="fig3a")
    N.add("fig3a.at510.floquet", floq[i], f"{floq[i]:.2f}", "", "largest Floquet multiplier modulus, 2 decimals", src)

    src = "fig3a-continuation.h5"
    cont = read_continuation(read(D / src))
    w, a, sp = branch_peak(cont, "z2", 2.0, 3.0)
    N.spaced("fig3a.cont.peak.omega", w, sp, src)
    N.amp("fig3a.cont.peak.z2", a, src)
    pd = bifurcations(cont, "period-doubling")
    folds = bifurcations(cont, "fold")
    for k, (w, _) in enumerate(pd, start=1):
        N.add(f"fig3a.cont.pd{k}", w, f"{w:.5f}", "rad/s", "located to ~1e-9, printed to 1e-5", src)
    for k, (w, a) in enumerate(folds, start=1):
        N.add(f"fig3a.cont.fold{k}", w, f"{w:.5f}", "rad/s", "located to ~1e-9, printed to 1e-5", src)
        N.amp(f"fig3a.cont.fold{k}.z2", a[0], src)


def late_jump(N, D, name, channel_index=0, fraction=0.2):
    src = f"{name}.h5"
    h = read_history(read(D / src))
    z = h.z[:, channel_index]
    tj, block, final = jump_time(h.t, z, h.omega)
    N.add(f"{name}.omega", h.omega, f"{h.omega:.2f}", "rad/s", "setting", src)
    N.add(f"{name}.duration", h.t[-1], f"{h.t[-1]:.0f}", "s", "setting", src)
    N.add(f"{name}.jump", tj, f"{10 * round(tj / 10):.0f}", "s",
          f"envelope blocks of 4 pi/w = {block:.2f} s; printed to 10 s", src)
    edges, env = envelope(h.t, z, block)
    small = float(env[np.searchsorted(edges, 0.3 * tj)])
    N.amp(f"{name}.small", small, src, f"envelope at {0.3 * tj:.0f} s (0.3 x the jump time), 2 significant digits", 2)
    N.amp(f"{name}.final", final, src)
    T = fraction * (h.t[-1] - h.t[0])
    bin_w = 2 * np.pi / T
    pk = np.sort(spectrum_peaks(h.t, z, fraction, 2))
    for k, w in enumerate(pk, start=1):
        N.add(f"{name}.spectrum{k}", w, f"{w:.{decimals(bin_w)}f}", "rad/s",
              f"spectral bin 2 pi / {T:.0f} s = {bin_w:.2g} rad/s", src)
    N.add(f"{name}.bin", bin_w, f"{bin_w:.2g}", "rad/s", "2 pi / analysed record", src)
    return pk, bin_w


def fig4(N, D):
    src = "fig4.h5"
    sw, step = read_grid(N, D, src, "fig4.step")
    for g in sw.gamma:
        d = curve(sw, gamma=g)
        w, a = grid_peak(sw, d, "z2", 2.0, 3.0)
        N.freq(f"fig4.grid.g{g:g}.omega", w, step, src, grid="fig4")
        N.amp(f"fig4.grid.g{g:g}.z2", a, src, "largest grid value, 3 significant digits")
        w, a = grid_peak(sw, d, "z2", 4.5, 5.5)
        sub = np.flatnonzero(d["period"] >= 2)
        N.add(f"fig4.g{g:g}.subpoints", sub.size, f"{sub.size}", "", "count of period-2 points", src)
        if sub.size:
            N.freq(f"fig4.sub.g{g:g}.omega", w, step, src, grid="fig4")
            N.amp(f"fig4.sub.g{g:g}.z2", a, src)
            N.freq(f"fig4.band.g{g:g}.lo", sw.omega[sub[0]], step, src, grid="fig4")
            N.freq(f"fig4.band.g{g:g}.hi", sw.omega[sub[-1]], step, src, grid="fig4")
        else:
            N.amp(f"fig4.sub.g{g:g}.z2", a, src, "largest value near 2 w1, 1 significant digit", 1)
    src = "fig4-peak.h5"
    sw, step = read_grid(N, D, src, "fig4.peak.step")
    for g in sw.gamma:
        w, a = grid_peak(sw, curve(sw, gamma=g), "z2", 0, 10)
        N.freq(f"fig4.peak.g{g:g}.omega", w, step, src)
        N.amp(f"fig4.peak.g{g:g}.z2", a, src)
    src = "fig4-continuation.h5"
    cont = read_continuation(read(D / src))
    N.add("fig4.cont.gamma", cont["fixed"], f"{cont['fixed']:g}", "", "setting", src)
    w, a, sp = branch_peak(cont, "z2", 2.0, 3.0)
    N.spaced("fig4.cont.peak.omega", w, sp, src)
    N.amp("fig4.cont.peak.z2", a, src)
    for k, (w, _) in enumerate(bifurcations(cont, "period-doubling"), start=1):
        N.add(f"fig4.cont.pd{k}", w, f"{w:.4f}", "rad/s", "located to ~1e-9, printed to 1e-4", src)
    for k, (w, a) in enumerate(bifurcations(cont, "fold"), start=1):
        N.add(f"fig4.cont.fold{k}", w, f"{w:.4f}", "rad/s", "located to ~1e-9, printed to 1e-4", src)
        N.amp(f"fig4.cont.fold{k}.z2", a[0], src)


def fig5a(N, D):
    src = "fig5a.h5"
    sw, step = read_grid(N, D, src, "fig5a.step")
    d = curve(sw)
    modes = [w for w in sw.modal if 11.5 <= w <= 13.5]
    for k, w in enumerate(modes, start=1):
        N.add(f"fig5a.mode{k}", w, f"{w:.4f}", "rad/s", "linear modal analysis (approximate), 1e-4", src)
    # The same loads in the exact analysis (no scene stores it: a static solution, recomputed).
    exact = static(parse_case(read_case_text(D / src)), analysis="exact").result.modes.omega
    for k, w in enumerate(exact[:2], start=1):
        N.add(f"fig5a.exact.mode{k}", w, f"{w:.2f}", "rad/s", "linear modal analysis (exact), 0.01, recomputed", src)
    N.add("fig5a.points", sw.omega.size, f"{sw.omega.size}", "", "count", src)
    failed = np.flatnonzero(d["failed"])
    N.add("fig5a.failed", failed.size, f"{failed.size}", "", "count of points stopped by a slack segment", src)
    for k, i in enumerate(failed, start=1):
        N.freq(f"fig5a.failed{k}", sw.omega[i], step, src, grid="fig5a")
    for ch, windows in (("z2", (("top", 11.5, 13.5),)), ("z4", (("low", 11.5, 12.3), ("high", 12.3, 13.5)))):
        for name, lo, hi in windows:
            w, a = grid_peak(sw, d, ch, lo, hi)
            N.freq(f"fig5a.{name}.{ch}.omega", w, step, src, grid="fig5a")
            N.amp(f"fig5a.{name}.{ch}", a, src, "largest value of the points that did not fail")
    src = "fig5a-updown.h5"
    sw = read_sweep(read(D / src))
    j = sw.channels.index("z4")
    down = curve(sw, "down")
    a = down["amplitude"][:, j]
    low = np.flatnonzero((sw.omega < 12.3) & down["done"] & ~down["failed"])
    drop = low[np.argmax(a[low[1:]] - a[low[:-1]]) + 1]  # lowest point of the large branch
    N.freq("fig5a.down.last", sw.omega[drop], step, src)
    N.amp("fig5a.down.last.z4", a[drop], src)
    up = curve(sw, "up")
    N.amp("fig5a.up.at.z4", up["amplitude"][drop, j], src)
    src = "fig5a-continuation.h5"
    cont = read_continuation(read(D / src))
    for k, (w, _) in enumerate(bifurcations(cont, "fold"), start=1):
        N.add(f"fig5a.cont.fold{k}", w, f"{w:.4f}", "rad/s", "located to ~1e-9, printed to 1e-4", src)
    last = max(cont["branches"], key=lambda b: b["omega"].max())
    i = int(np.argmax(last["omega"]))
    N.add("fig5a.cont.end", last["omega"][i], f"{last['omega'][i]:.3f}", "rad/s", "last converged point, 1e-3", src)
    N.amp("fig5a.cont.end.z2", last["amplitude"][i, cont["channels"].index("z2")], src)


def fig5b(N, D):
    src = "fig5b.h5"
    h = read_history(read(D / src))
    z = h.z[:, h.dof_numbers.index(4)]
    N.add("fig5b.stop", h.t[-1], f"{h.t[-1]:.1f}", "s", "output step 0.01 s, printed to 0.1 s", src)
    T = h.t[-1] - h.t[0]
    bin_w = 2 * np.pi / T
    N.add("fig5b.bin", bin_w, f"{bin_w:.2f}", "rad/s", f"2 pi / {T:.1f} s (the whole record)", src)
    pk = spectrum_peaks(h.t, z, 1.0, 3)
    N.add("fig5b.response", pk[0], f"{pk[0]:.{decimals(bin_w)}f}", "rad/s", f"spectral bin {bin_w:.2f} rad/s", src)
    rest = np.sort(pk[1:])
    for k, w in enumerate(rest, start=1):
        N.add(f"fig5b.component{k}", w, f"{w:.{decimals(bin_w)}f}", "rad/s", f"spectral bin {bin_w:.2f} rad/s", src)
    N.amp("fig5b.max.z4", np.abs(z).max(), src, "2 significant digits", 2)


def fig6_7a(N, D):
    peaks = {}
    for name, src in (("fig6", "fig6.h5"), ("fig7a", "fig7a.h5")):
        sw, step = read_grid(N, D, src, f"{name}.step")
        d = curve(sw)
        for k, w in enumerate(sw.modal[:2], start=1):
            N.add(f"{name}.mode{k}", w, f"{w:.3f}", "rad/s", "linear modal analysis, 1e-3", src)
        for label, lo, hi in (("first", 1.0, 2.1), ("second", 2.1, 4.0)):
            w, a = grid_peak(sw, d, "z2", lo, hi)
            N.freq(f"{name}.{label}.omega", w, step, src, grid=name)
            N.amp(f"{name}.{label}.z2", a, src, "largest grid value, 2 significant digits", 2)
        for ch in ("z1", "z3"):
            _, a = grid_peak(sw, d, ch, 1.0, 4.0)
            N.amp(f"{name}.max.{ch}", a, src, "largest grid value, 2 significant digits", 2)
        src = f"{name}-continuation.h5"
        cont = read_continuation(read(D / src))
        top = {}
        for ch in ("z2", "z4"):
            for label, lo, hi in (("first", 1.0, 2.1), ("second", 2.1, 4.0)):
                w, a, sp = branch_peak(cont, ch, lo, hi)
                N.spaced(f"{name}.cont.{label}.{ch}.omega", w, max(sp, 1e-3), src)
                N.amp(f"{name}.cont.{label}.{ch}", a, src)
                top[label] = max(top.get(label, 0.0), a)
        N.add(f"{name}.cont.bifurcations", len(cont["bifurcations"]["kind"]),
              f"{len(cont['bifurcations']['kind'])}", "", "count", src)
        peaks[name] = top
    both = "fig6-continuation.h5, fig7a-continuation.h5"
    for label in ("first", "second"):
        r = 100 * (peaks["fig6"][label] / peaks["fig7a"][label] - 1)
        N.add(f"fig6.higher.{label}", r, f"{r:.0f}", "%",
              f"larger continuation peak of z2, z4 at the {label} resonance, approximate over exact, 1 %", both)
    r = 100 * (max(peaks["fig6"].values()) / max(peaks["fig7a"].values()) - 1)
    N.add("fig6.higher.percent", r, f"{r:.0f}", "%", "highest continuation peak of z2, z4, approximate over exact, 1 %",
          both)


def fig7_modes(N, D):
    dT = {}
    for m in (1, 2):
        src = f"fig7-mode{m}.h5"
        h = read_history(read(D / src))
        i2, i4 = h.dof_numbers.index(2), h.dof_numbers.index(4)
        half = h.t.size // 2
        z2, z4 = h.z[half:, i2], h.z[half:, i4]
        pre = f"fig7.mode{m}"
        note = "last half of the run, 2 significant digits"
        N.add(f"{pre}.omega", h.omega, f"{h.omega:.2f}", "rad/s", "setting", src)
        N.amp(f"{pre}.z2", np.abs(z2).max(), src, note, 2)
        N.amp(f"{pre}.z4", np.abs(z4).max(), src, note, 2)
        c = np.corrcoef(z2, z4)[0, 1]
        N.add(f"{pre}.corr", c, f"{c:+.2f}", "", "correlation of z2 and z4, 2 decimals", src)
        T = (h.T[half:, 0] - h.T0[0]) / 1e3
        dT[m] = T.max() - T.min()
        N.add(f"{pre}.T1.up", T.max(), f"+{T.max():.0f}", "kN", "last half of the run, 1 kN", src)
        N.add(f"{pre}.T1.down", T.min(), f"{T.min():.0f}", "kN", "last half of the run, 1 kN", src)
        zc, ze = h.zc[half:, i4], h.ze[half:, i4]
        N.amp(f"{pre}.z4c", np.abs(zc).max(), src, note, 2)
        N.amp(f"{pre}.z4e", np.abs(ze).max(), src, note, 2)
        if m == 1:  # the configurational mode: its unequal excursions
            N.amp(f"{pre}.z4c.up", zc.max(), src, note, 2)
            N.add(f"{pre}.z4c.down", zc.min(), significant(zc.min(), 2), "m", note, src)
    r = dT[2] / dT[1]
    N.add("fig7.T1.ratio", r, f"{r:.0f}", "", "peak-to-peak T1, mode 2 over mode 1, to 1", "fig7-mode1.h5, fig7-mode2.h5")


def fig8(N, D):
    src = "fig8a.h5"
    sw, step = read_grid(N, D, src, "fig8a.step")
    d = curve(sw)
    for k, w in enumerate(sw.modal, start=1):
        N.add(f"fig8a.mode{k}", w, significant(w, 5 if w > 100 else 4), "rad/s", "linear modal analysis", src)
    N.add("fig8a.points", sw.omega.size, f"{sw.omega.size}", "", "count", src)
    N.add("fig8a.steady", d["steady"].sum(), f"{int(d['steady'].sum())}", "", "count", src)
    w, a = grid_peak(sw, d, "z2", 0.6, 1.2)
    N.freq("fig8a.fundamental.omega", w, step, src, grid="fig8a")
    N.amp("fig8a.fundamental.z2", a, src, "largest grid value, 3 significant digits")
    sub = np.flatnonzero(d["period"] >= 2)
    N.freq("fig8a.band.lo", sw.omega[sub[0]], step, src, grid="fig8a")
    N.freq("fig8a.band.hi", sw.omega[sub[-1]], step, src, grid="fig8a")
    N.add("fig8a.band.points", sub.size, f"{sub.size}", "", "count of period-2 grid points", src)
    N.amp("fig8a.band.z2", d["amplitude"][sub, 0].max(), src)
    # The low end of the range: the irregular (superharmonic) resonance near w1 / 2.
    a0 = d["amplitude"][:, 0]
    N.freq("fig8a.start", sw.omega[0], step, src, grid="fig8a")
    N.amp("fig8a.start.z2", a0[0], src, "2 significant digits", 2)
    N.freq("fig8a.second", sw.omega[1], step, src, grid="fig8a")
    N.amp("fig8a.second.z2", a0[1], src, "2 significant digits", 2)
    # sum w^2 = trace(M^-1 K) >= the axial part of the exact tangent stiffness, for any loads
    cable = parse_case(read_case_text(D / src)).cable
    n = len(cable.masses)
    ends = [[i for i in (r - 1, r) if 0 <= i < n] for r in range(n + 1)]  # the masses at each segment's ends
    bound = sum(cable.EA / S * sum(1 / cable.masses[i] for i in e) for S, e in zip(cable.S, ends))
    N.add("fig8.trace.bound", bound, f"{bound:.4e}", "rad^2/s^2", "sum over segments of EA/S (1/M_i + 1/M_j), 5 digits", src)
    total = float(np.sum(sw.modal ** 2))
    N.add("fig8.trace.cablesim", total, f"{total:.4e}", "rad^2/s^2", "sum of the squared modal frequencies, 5 digits", src)
    paper = sum(w ** 2 for w in (0.8154, 401.02, 864.32, 1472.63))  # the paper's Fig. 8 frequencies
    N.add("fig8.trace.paper", paper, f"{paper:.4e}", "rad^2/s^2", "the paper's four frequencies, 5 digits", "the paper")
    src = "fig8a-continuation.h5"
    cont = read_continuation(read(D / src))
    for k, (w, _) in enumerate(bifurcations(cont, "period-doubling"), start=1):
        N.add(f"fig8a.cont.pd{k}", w, f"{w:.4f}", "rad/s", "located to ~1e-9, printed to 1e-4", src)
    N.add("fig8a.cont.folds", len(bifurcations(cont, "fold")), f"{len(bifurcations(cont, 'fold'))}", "", "count", src)
    w, a, sp = branch_peak(cont, "z2", 1.2, 2.0, period=2)
    N.amp("fig8a.cont.p2.z2", a, src)
    maxima = 0
    for b in cont["branches"]:
        if b["period"] == 2:
            maxima += find_peaks(b["amplitude"][:, 0])[0].size
    N.add("fig8a.cont.p2.maxima", maxima, f"{maxima}", "", "count of local maxima of z2 along the period-2 branch", src)
    orbits = sum(b["trusted"].size for b in cont["branches"])
    untrusted = orbits - sum(int(b["trusted"].sum()) for b in cont["branches"])
    N.add("fig8a.cont.orbits", orbits, f"{orbits}", "", "count of periodic orbits computed", src)
    N.add("fig8a.cont.untrusted", untrusted, f"{untrusted}", "", "count of orbits whose multipliers failed a check", src)
    # its end points are the period doublings, where a multiplier is on the unit circle
    stable = all(b["stable"][1:-1].all() for b in cont["branches"] if b["period"] == 2)
    N.add("fig8a.cont.p2.stable", stable, "stable" if stable else "unstable", "",
          "every point of the period-2 branch between its end points", src)

    src = "fig8b.h5"
    h = read_history(read(D / src))
    half = h.t.size // 2
    N.add("fig8b.omega", h.omega, f"{h.omega:.2f}", "rad/s", "setting", src)
    N.amp("fig8b.z2", np.abs(h.z[half:, 0]).max(), src)
    N.amp("fig8b.z2e", np.abs(h.ze[half:, 0]).max(), src, "2 significant digits", 2)
    pk, bin_w = late_jump(N, D, "fig8c", fraction=0.5)  # the half the figure analyses
    for k, (ours, paper) in enumerate(zip(pk, (0.8325, 1.649)), start=1):  # the paper's response frequencies
        bins = (paper - ours) / bin_w
        N.add(f"fig8c.paper.bins{k}", bins, f"{bins:.0f}", "bins", "the paper's frequency minus cablesim's, in bins", "fig8c.h5")


def compute(D: Path) -> dict:
    N = Numbers()
    for part in (fig2, fig3a, lambda N, D: late_jump(N, D, "fig3b"), fig4, fig5a, fig5b, fig6_7a, fig7_modes, fig8):
        part(N, D)
    return N.items


def compare(new: dict, path: Path) -> list[str]:
    """Differences between the computed numbers and the file (as printed: their texts)."""
    if not path.is_file():
        return [f"{path} does not exist"]
    old = json.loads(path.read_text())["numbers"]
    out = [f"{k}: {old[k]['text']} in {path}, now {new[k]['text']}" for k in new if k in old and old[k]["text"] != new[k]["text"]]
    out += [f"{k}: new, {new[k]['text']}" for k in new if k not in old]
    out += [f"{k}: in {path} only" for k in old if k not in new]
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("results", nargs="?", default="runs/paper", type=Path)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--check", type=Path, metavar="JSON", help="exit 1 if the file differs from the results")
    g.add_argument("--write", type=Path, metavar="JSON", help="write the numbers to the file")
    a = p.parse_args(argv)
    numbers = compute(a.results)
    if a.write:
        doc = {"about": "Numbers quoted by docs/paper-reproduction.md, written by `make paper-numbers WRITE=1` "
                        "from the results of `make figures refine`; the tests check the document against them.",
               "numbers": numbers}
        a.write.write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {len(numbers)} numbers to {a.write}")
    elif a.check:
        diff = compare(numbers, a.check)
        for line in diff:
            print("DIFFERS", line)
        if diff:
            print(f"{len(diff)} numbers differ from {a.check}: update the document and rewrite the file "
                  "(make paper-numbers WRITE=1)")
            return 1
        print(f"all {len(numbers)} numbers agree with {a.check}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
