"""Accelerated sweeps (steady states by shooting) against integration alone, side by side.

For the shipped example over 0.5-6 rad/s at 0.01 rad/s steps (551 points, the paper's Fig. 3a
case) and for every sweep in ``configs/paper/``: the same sweep with ``accelerate: true`` and
``false`` in one run, on all cores. Prints wall time, per-point CPU, the speed-up, and whether
the answers agree: same period and same steady / not steady / failed flags at every point, and
the largest relative amplitude difference over the points steady in both. Run with
``make bench`` (or ``--quick`` for the shipped example on a coarse grid).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from cablesim import api

ROOT = Path(__file__).resolve().parents[1]
SCENES = ["paper-example"] + [f"paper/{f}" for f in ("fig3a", "fig4", "fig5a", "fig6", "fig7a", "fig8a")]


def run(scene: str, accelerate: bool, tmp: Path, overrides: list[str]):
    case = api.load_case(ROOT / "configs" / f"{scene}.yaml",
                         overrides=[f"sweep.accelerate={str(accelerate).lower()}", *overrides])
    w0 = time.perf_counter()
    res = api.sweep(case, jobs=os.cpu_count() or 1, output=tmp / f"{scene.replace('/', '-')}-{accelerate}.h5").result
    return res, time.perf_counter() - w0


def compare(a, b) -> dict:
    """Agreement of two sweep results over all curves."""
    out = dict(points=0, period=0, steady=0, failed=0, amp=0.0, shooting=0)
    for c in a.data:
        da, db = a.data[c], b.data[c]
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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the shipped example on 56 points only")
    ap.add_argument("--scene", action="append", help="scenes to run (default: all)")
    args = ap.parse_args(argv)
    scenes = args.scene or (["paper-example"] if args.quick else SCENES)
    print("| sweep | points | integration alone | accelerated | speed-up | CPU per point (alone / accel.) | "
          "decided by shooting | period, steady, failed differ at | max rel. amplitude difference |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        run("paper-example", True, tmp, ["sweep.omega.num=4"])  # compile or load the kernels
        for scene in scenes:
            extra = ["sweep.omega.num=56"] if args.quick else (["sweep.omega.num=551"] if scene == "paper-example" else [])
            plain, w_plain = run(scene, False, tmp, extra)
            fast, w_fast = run(scene, True, tmp, extra)
            c = compare(fast, plain)
            cpu_p = np.nansum([np.nansum(d["wall"]) for d in plain.data.values()]) / c["points"]
            cpu_f = np.nansum([np.nansum(d["wall"]) for d in fast.data.values()]) / c["points"]
            print(f"| {scene} | {c['points']} | {w_plain:.1f} s | {w_fast:.1f} s | {w_plain / w_fast:.1f}x | "
                  f"{cpu_p:.3f} / {cpu_f:.3f} s | {c['shooting']} | {c['period']}, {c['steady']}, {c['failed']} | "
                  f"{c['amp']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
