"""Accelerated sweeps (steady states by shooting) against integration alone, side by side.

For the shipped example over 0.5-6 rad/s at 0.01 rad/s steps (551 points, the paper's Fig. 3a
case), the same case swept up and down at 0.05 rad/s steps (chains: each point starts from the
previous one's end), and for every sweep in ``configs/paper/``: the same sweep with ``accelerate: true`` and
``false`` in one run, on all cores. Prints wall time, per-point CPU, the speed-up, and whether
the answers agree: same period and same steady / not steady / failed flags at every point, and
the largest relative amplitude difference over the points steady in both. Run with
``make bench`` (or ``--quick`` for the shipped example on a coarse grid).

``--integration`` measures instead the marginal cost of the time loop (ms of CPU per simulated
second) on the paper example forced at 2.4 rad/s for 1000 s from rest, all settings round-robin
in one run (median of 3): DOPRI5 at the sweep default rtol 1e-8, and at the transient's rtol
1e-6 with atol unchanged (as before) or loosened alike (as now), and at rtol 1e-5, each with strobes only (one
output per forcing period) or an output every 0.05 s, in one call or in chunks of 4 forcing
periods (how an accelerated sweep integrates); error: max over the strobes of ``|z - z_ref|``
over ``max |z_ref|`` against rtol 1e-11.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from cablesim import api
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.dynamics.integrators import DOPRI5
from cablesim.dynamics.simulate import advance_in_chunks

ROOT = Path(__file__).resolve().parents[1]
SCENES = ["paper-example", "paper-example-both"] + [f"paper/{f}" for f in ("fig3a", "fig4", "fig5a", "fig6", "fig7a",
                                                                           "fig8a")]
#: Scenes that are a case file with settings changed: (case file, overrides).
VARIANTS = {"paper-example": ("paper-example", ["sweep.omega.num=551", "sweep.refine=false"]),
            "paper-example-both": ("paper-example", ["sweep.omega.num=111", "sweep.direction=both", "sweep.refine=false"])}


def run(scene: str, accelerate: bool, tmp: Path, overrides: list[str]):
    config, extra = VARIANTS.get(scene, (scene, []))
    overrides = [*extra, *overrides]
    case = api.load_case(ROOT / "configs" / f"{config}.yaml",
                         overrides=[f"sweep.accelerate={str(accelerate).lower()}", *overrides])
    w0 = time.perf_counter()
    res = api.sweep(case, jobs=os.cpu_count() or 1, output=tmp / f"{scene.replace('/', '-')}-{accelerate}.h5").result
    return res, time.perf_counter() - w0


def compare(a, b) -> dict:
    """Agreement of two sweep results over all curves (``a`` accelerated, ``b`` integration
    alone); ``differ`` lists the points whose period or flags differ."""
    out = dict(points=0, period=0, steady=0, failed=0, amp=0.0, shooting=0, differ=[])
    for c in a.data:
        da, db = a.data[c], b.data[c]
        bad = (da["period"] != db["period"]) | (da["steady"] != db["steady"]) | (da["failed"] != db["failed"])
        for i in np.flatnonzero(bad):
            mu = np.abs(da["multipliers"][i])
            rho = float(np.nanmax(mu)) if np.any(np.isfinite(mu)) else np.nan
            out["differ"].append(f"curve {c}, {a.omega[i]:.4g} rad/s: alone period {db['period'][i]} "
                                 f"({'steady' if db['steady'][i] else 'not steady'}, {db['t_end'][i]:.0f} s), "
                                 f"accelerated period {da['period'][i]} ({da['decided'][i]}, {da['t_end'][i]:.0f} s, "
                                 f"largest |multiplier| {rho:.4f})")
        out["points"] += da["period"].size
        out["period"] += int(np.sum(da["period"] != db["period"]))
        out["steady"] += int(np.sum(da["steady"] != db["steady"]))
        out["failed"] += int(np.sum(da["failed"] != db["failed"]))
        both = da["steady"] & db["steady"]
        if both.any():
            rel = np.abs(da["amplitude"][both] - db["amplitude"][both]) / np.maximum(np.abs(db["amplitude"][both]), 1e-12)
            out["amp"] = max(out["amp"], float(rel.max()))
        out["shooting"] += int(np.sum(da["decided"] == "shooting"))
    return out


def integrate(eom, integ, t_out, chunk_periods):
    """``(seconds, strobes)``: ``integ`` from rest to ``t_out[-1]``, in chunks of
    ``chunk_periods`` forcing periods (0: one call)."""
    nd, T = eom.n_dof, 2.0 * np.pi / eom.omega
    out = np.empty((t_out.size, 3 * nd))
    st = integ.start(eom, eom.initial_state())
    ends = T * np.arange(chunk_periods, t_out[-1] / T, chunk_periods) if chunk_periods else np.empty(0)
    ends = np.append(ends[ends < t_out[-1]], t_out[-1])
    w0 = time.process_time()
    j = 0
    for t_end in ends:
        k = j + int(np.searchsorted(t_out[j:], t_end, side="right"))
        n, code = advance_in_chunks(integ, eom.params(), st, t_end, t_out[j:k], out[j:k])
        assert code == 0
        j = k
    strobe = np.isclose(np.mod(t_out / T + 0.5, 1.0), 0.5)
    return time.process_time() - w0, out[strobe, :nd]


def integration_cost(duration: float = 1000.0, omega: float = 2.4) -> None:
    """Marginal cost of the time loop (module docstring, ``--integration``)."""
    case = api.load_case(ROOT / "configs" / "paper-example.yaml")
    eom = build_equations(case, run_static(case), omega=omega)
    chord, T = eom.cable.chord_length, 2.0 * np.pi / omega
    strobes = T * np.arange(1, int(duration / T) + 1)
    fine = np.union1d(strobes, 0.05 * np.arange(1, int(duration / 0.05) + 1))
    _, ref = integrate(eom, DOPRI5(rtol=1e-11, atol=1e-13 * chord), strobes, 0)
    settings = {"rtol 1e-8 (sweep default)": DOPRI5(rtol=1e-8, atol=1e-10 * chord),
                "rtol 1e-6, atol unchanged": DOPRI5(rtol=1e-6, atol=1e-10 * chord),
                "rtol 1e-6, atol loosened alike": DOPRI5(rtol=1e-6, atol=1e-8 * chord),
                "rtol 1e-5, atol loosened alike": DOPRI5(rtol=1e-5, atol=1e-7 * chord)}
    runs = [(name, out, chunk) for name in settings for out in ("strobes", "every 0.05 s") for chunk in (0, 4)]
    times = {r: [] for r in runs}
    errors = {}
    for _ in range(3):
        for name, out, chunk in runs:
            sec, z = integrate(eom, settings[name], strobes if out == "strobes" else fine, chunk)
            times[(name, out, chunk)].append(sec)
            errors[name] = float(np.abs(z - ref).max() / np.abs(ref).max())
    print(f"| DOPRI5 setting | outputs | chunks | ms per simulated second | error |")
    print("|---|---|---|---|---|")
    for name, out, chunk in runs:
        print(f"| {name} | {out} | {'4 periods' if chunk else 'one call'} | "
              f"{1e3 * np.median(times[(name, out, chunk)]) / duration:.3f} | {errors[name]:.1e} |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the shipped example on 56 points only")
    ap.add_argument("--scene", action="append", help="scenes to run (default: all)")
    ap.add_argument("--integration", action="store_true", help="the marginal cost of the time loop instead")
    args = ap.parse_args(argv)
    if args.integration:
        integration_cost()
        return
    scenes = args.scene or (["paper-example"] if args.quick else SCENES)
    print("| sweep | points | integration alone | accelerated | speed-up | CPU per point (alone / accel.) | "
          "decided by shooting | period, steady, failed differ at | max rel. amplitude difference |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for scene in scenes:
            # compile the scene's kernels (exact or approximate, its integrator) before timing
            run(scene, True, tmp, ["sweep.omega.num=2", "sweep.duration=30", "sweep.window=10", "sweep.refine=false"])
            extra = ["sweep.omega.num=56", "sweep.refine=false"] if args.quick else []
            plain, w_plain = run(scene, False, tmp, extra)
            fast, w_fast = run(scene, True, tmp, extra)
            c = compare(fast, plain)
            cpu_p = np.nansum([np.nansum(d["wall"]) for d in plain.data.values()]) / c["points"]
            cpu_f = np.nansum([np.nansum(d["wall"]) for d in fast.data.values()]) / c["points"]
            print(f"| {scene} | {c['points']} | {w_plain:.1f} s | {w_fast:.1f} s | {w_plain / w_fast:.1f}x | "
                  f"{cpu_p:.3f} / {cpu_f:.3f} s | {c['shooting']} | {c['period']}, {c['steady']}, {c['failed']} | "
                  f"{c['amp']:.1e} |", flush=True)
            for line in c["differ"]:
                print(f"    differs at {line}", flush=True)


if __name__ == "__main__":
    main()
