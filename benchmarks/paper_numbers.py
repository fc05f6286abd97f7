"""Print the numbers that docs/paper-reproduction.md quotes, read from runs/paper/*.h5.

Run after ``make figures`` (``make paper-numbers``); nothing is recomputed.
"""

from __future__ import annotations

import sys
from pathlib import Path

import h5py
import numpy as np

from cablesim.dynamics.spectra import spectrum_peaks
from cablesim.io.hdf5 import read_history

D = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/paper")


def sweep(name, group="sweep"):
    with h5py.File(D / f"{name}.h5") as f:
        g = f[group]
        chans = [c.decode() if isinstance(c, bytes) else str(c) for c in f["sweep"].attrs["channels"]]
        out = dict(omega=f["sweep/omega"][()], amp=g["amplitude"][()], period=g["period"][()],
                   steady=g["steady"][()], failed=g["failed"][()], rf=g["response_frequency"][()],
                   chans=chans, modal=f["modal/omega"][()], gamma=f["sweep/gamma"][()] if "gamma" in f["sweep"] else None)
    return out


def local_peaks(w, a, lo, hi):
    m = (w >= lo) & (w <= hi)
    i = np.flatnonzero(m)[np.argmax(a[m])]
    return w[i], a[i]


def report_sweep(name, bands):
    s = sweep(name)
    print(f"== {name}: modal {np.round(s['modal'], 4)}; points {s['omega'].size}, steady {int(s['steady'].sum())}, "
          f"subharmonic {int((s['period'] >= 2).sum())}, failed {int(s['failed'].sum())}")
    amps = s["amp"] if s["gamma"] is None else s["amp"]
    curves = [(None, amps)] if s["gamma"] is None else list(zip(s["gamma"], amps))
    for g, A in curves:
        for j, c in enumerate(s["chans"]):
            for lo, hi in bands:
                w, a = local_peaks(s["omega"], A[:, j], lo, hi)
                print(f"   {'' if g is None else f'gamma={g:g} '}{c}: peak in [{lo}, {hi}] at {w:.3f} rad/s, {a:.4g} m")
    sub = s["period"] >= 2
    if np.any(sub):
        print(f"   subharmonic points: {s['omega'][sub.any(axis=0) if sub.ndim > 1 else sub].round(3)}")


def envelope_jump(t, z, t_ref, factor=2.0):
    """First time the running |z| peak (per 20 s block) exceeds factor x its value at t_ref."""
    blk = 20.0
    edges = np.arange(0, t[-1] + blk, blk)
    env = np.array([np.abs(z[(t >= a) & (t < a + blk)]).max() if np.any((t >= a) & (t < a + blk)) else 0 for a in edges])
    ref = env[np.searchsorted(edges, t_ref)]
    above = np.flatnonzero((edges > t_ref) & (env > factor * ref))
    return (edges[above[0]] if above.size else None), ref, env.max()


def main():
    h = read_history(D / "fig2.h5")
    z = h.z[:, h.dof_numbers.index(2)]
    from scipy.signal import find_peaks

    pk, _ = find_peaks(np.abs(z))
    print("== fig2: modal", np.round(h.modal_omega, 4), "; |z2| extremes (t, z2):",
          [(round(float(h.t[i]), 3), round(float(z[i]), 5)) for i in pk[:6]],
          "; late spectrum peaks", spectrum_peaks(h.t, z, 0.5, 2).round(3))
    report_sweep("fig3a", [(0.5, 1.5), (2.0, 3.0), (4.5, 5.5)])
    h = read_history(D / "fig3b.h5")
    z = h.z[:, 0]
    tj, ref, top = envelope_jump(h.t, z, 300.0)
    print(f"== fig3b: w = {h.omega}, envelope at 300 s {ref:.4g} m, first doubling after {tj} s, max {top:.4g} m, "
          f"final spectrum peaks {spectrum_peaks(h.t, z, 0.2, 3).round(4)} rad/s, status {h.message}")
    report_sweep("fig4", [(2.0, 3.0), (4.5, 5.5)])
    report_sweep("fig5a", [(11.5, 12.5), (12.5, 13.5)])
    h = read_history(D / "fig5b.h5")
    z = h.z[:, h.dof_numbers.index(4)]
    pk = spectrum_peaks(h.t, z, 1.0, 3)
    seg = z.size // 20
    env = np.array([np.abs(z[i:i + seg]).max() for i in range(0, z.size - seg, seg // 4)])
    print(f"== fig5b: status {h.message}; t_end {h.t[-1]:.4g}; z4 spectrum peaks {pk.round(4)}; "
          f"beat ~ half the peak spacing {abs(pk[0] - pk[1]) / 2 if pk.size > 1 else float('nan'):.4f} rad/s; max |z4| {np.abs(z).max():.4g}")
    report_sweep("fig6", [(1.0, 2.1), (2.1, 4.0)])
    report_sweep("fig7a", [(1.0, 2.3), (2.3, 4.0)])
    for m in (1, 2):
        h = read_history(D / f"fig7-mode{m}.h5")
        i2, i4 = h.dof_numbers.index(2), h.dof_numbers.index(4)
        half = h.t.size // 2
        z2, z4 = h.z[half:, i2], h.z[half:, i4]
        corr = np.corrcoef(z2, z4)[0, 1]
        dT = h.T[half:, 0] - h.T0[0]
        zc, ze = h.zc[half:, i4], h.ze[half:, i4]
        print(f"== fig7 mode {m}: w = {h.omega}; max|z2| {np.abs(z2).max():.4g}, max|z4| {np.abs(z4).max():.4g}, corr(z2,z4) {corr:+.3f}; "
              f"T1 change +{dT.max() / 1e3:.4g}/{dT.min() / 1e3:.4g} kN; z4: max|zc| {np.abs(zc).max():.4g} "
              f"(+{zc.max():.4g}/{zc.min():.4g}), max|ze| {np.abs(ze).max():.4g} (+{ze.max():.4g}/{ze.min():.4g}) m")
    report_sweep("fig8a", [(0.4, 1.2), (1.2, 2.0)])
    h = read_history(D / "fig8b.h5")
    half = h.t.size // 2
    print(f"== fig8b: w = {h.omega}; z2 max {np.abs(h.z[half:, 0]).max():.4g}, zc {np.abs(h.zc[half:, 0]).max():.4g}, "
          f"ze {np.abs(h.ze[half:, 0]).max():.4g} m")
    h = read_history(D / "fig8c.h5")
    z = h.z[:, 0]
    tj, ref, top = envelope_jump(h.t, z, 300.0)
    print(f"== fig8c: w = {h.omega}; envelope at 300 s {ref:.4g} m, first doubling after {tj} s, max {top:.4g} m; "
          f"final spectrum peaks {spectrum_peaks(h.t, z, 0.3, 3).round(4)} rad/s; status {h.message}")


if __name__ == "__main__":
    main()
