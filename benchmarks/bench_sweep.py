"""Cost of a sweep: the paper's Fig. 3a case over 0.5-6 rad/s at 0.01 rad/s steps, default cap.

Prints the wall time, the time per point and per simulated second, and the parallel
efficiency on the cores of this machine (the same subset of points with 1 job and with all
jobs, side by side in one run). Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from cablesim import api
from cablesim.case import example_text, parse_case

CASE = example_text().split("\nsweep:")[0] + """
sweep:
  omega: {start: 0.5, stop: 6.0, num: %d}
  refine: false
  duration: 3000.0
  window: 200.0
  channels: [z2, z4]
"""


def run(num: int, jobs: int, tmp: Path):
    text = CASE % num
    case = parse_case(text, default_name="bench-fig3a")
    out = tmp / f"sweep-{num}-{jobs}.h5"
    t0 = time.perf_counter()
    res = api.sweep(case, jobs=jobs, output=out).result
    wall = time.perf_counter() - t0
    d = res.data[0]
    return wall, float(np.sum(d["t_end"])), float(np.sum(d["wall"])), res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=551, help="grid size of the full sweep")
    ap.add_argument("--subset", type=int, default=60, help="points for the 1-job vs all-jobs test")
    args = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        run(4, 1, tmp)  # warm the compiled kernels' cache
        w1, *_ = run(args.subset, 1, tmp)
        wn, *_ = run(args.subset, cores, tmp)
        print(f"{args.subset} points: 1 job {w1:.2f} s, {cores} jobs {wn:.2f} s, speed-up {w1 / wn:.2f} "
              f"(includes starting the worker processes, about a second each)")
        wall, sim, work, res = run(args.points, cores, tmp)
        d = res.data[0]
        print(f"full sweep: {args.points} points on {cores} cores in {wall:.1f} s wall "
              f"({wall / args.points:.3f} s per point; {work / args.points:.3f} s of one core per point)")
        print(f"simulated {sim:.0f} s in all ({sim / args.points:.0f} s per point on average), "
              f"{1e3 * work / sim:.3f} ms of one core per simulated second")
        print(f"parallel efficiency of the full sweep: {work:.1f} s of per-point work in {wall:.1f} s on "
              f"{cores} cores = {work / (cores * wall):.0%} (the rest is start-up, scheduling and I/O)")
        print(f"steady: {int(d['steady'].sum())} of {args.points}; subharmonic (p >= 2): "
              f"{int((d['period'] >= 2).sum())}; reached the cap: {int((~d['steady']).sum())}")


if __name__ == "__main__":
    main()
