"""Cost of a spatial time history against the planar one of the same cable, side by side.

A planar case run with ``spatial: true`` carries three components per node instead of two (its
out-of-plane components stay zero). Scenes: the paper's 2-node cable forced at 2.4 rad/s
(dopri5, its default), and the heavy span of ``configs/heavy-span.yaml`` with 50 and 200 nodes
(generalized-alpha with banded Newton solves, its default). For each, the planar and the spatial
run alternate ``--rounds`` times in this process after a warm-up that compiles or loads the
kernels; quoted: the median CPU and wall seconds per simulated second, and their ratio.
Run with ``python benchmarks/bench_spatial.py`` (part of ``make bench``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from cablesim import api
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.dynamics.simulate import simulate

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SCENES = {
    "n = 2 (paper example, dopri5)": ("paper-example.yaml", [], 2.4, 200.0),
    "n = 50 (heavy span, generalized-alpha)": ("heavy-span.yaml", ["cable.nodes=50", "loads.point=[]"], 2.0, 10.0),
    "n = 200 (heavy span, generalized-alpha)": ("heavy-span.yaml", ["cable.nodes=200", "loads.point=[]"], 2.0, 2.0),
}


def job(path: str, overrides: list[str], omega: float, duration: float, spatial: bool):
    case = api.load_case(CONFIGS / path, overrides=overrides + (["spatial=true"] if spatial else []))
    eom = build_equations(case, run_static(case, all_models=False), omega=omega)
    integ = make_integrator(case.integrator, eom, max(omega, float(eom.frequencies[0])))
    return lambda: simulate(eom, integ, duration, duration / 200, split=False), integ.name


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5, help="alternations of planar and spatial runs")
    args = ap.parse_args(argv)
    print(f"median over {args.rounds} alternating runs; seconds per simulated second")
    print(f"{'scene':42s} {'CPU planar':>11s} {'CPU spatial':>12s} {'ratio':>6s} {'wall planar':>12s} "
          f"{'wall spatial':>13s} {'ratio':>6s}")
    for name, (path, ov, omega, duration) in SCENES.items():
        runs = {sp: job(path, ov, omega, duration, sp) for sp in (False, True)}
        for sp in (False, True):
            runs[sp][0]()  # compile or load the kernels
        cpu = {False: [], True: []}
        wall = {False: [], True: []}
        for _ in range(args.rounds):
            for sp in (False, True):
                c0, w0 = time.process_time(), time.perf_counter()
                runs[sp][0]()
                cpu[sp].append((time.process_time() - c0) / duration)
                wall[sp].append((time.perf_counter() - w0) / duration)
        cp, cs = np.median(cpu[False]), np.median(cpu[True])
        wp, ws = np.median(wall[False]), np.median(wall[True])
        print(f"{name:42s} {cp:11.4f} {cs:12.4f} {cs / cp:6.2f} {wp:12.4f} {ws:13.4f} {ws / wp:6.2f}", flush=True)


if __name__ == "__main__":
    main()
