"""Cost of a complete frequency response by continuation against brute force, in one run.

The paper's Fig. 3a case (the shipped example) over 0.5-6 rad/s: every periodic response,
the period-2 branch near 2 w1 and its bifurcations, by ``cablesim.continuation``; and the
551-point brute-force sweep (``cablesim.sweep``, default cap) on all cores. Times are CPU
seconds of this process (continuation, median of repeats after a warm-up that compiles or
loads the kernels) and the summed per-point CPU of the sweep's workers, so that the ratio does
not depend on how many cores run the sweep. Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from cablesim import api

CASE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
CONTINUATION = "continuation={omega: {start: 0.5, stop: 6.0}, channels: [z2, z4]}"


def continuation_cost(repeats: int):
    case = api.load_case(CASE, overrides=[CONTINUATION])
    api.continuation(case)  # compile or load the kernels
    cpu, wall, runs = [], [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        run = api.continuation(case)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
        runs.append(run)
    return float(np.median(cpu)), float(np.median(wall)), runs[-1].result


def sweep_cost(points: int, tmp: Path):
    case = api.load_case(CASE, overrides=[f"sweep.omega.num={points}", "sweep.refine=false"])
    w0 = time.perf_counter()
    res = api.sweep(case, jobs=os.cpu_count() or 1, output=tmp / "sweep.h5").result
    wall = time.perf_counter() - w0
    return float(np.nansum(res.data[0]["wall"])), wall, res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="continuation runs (median quoted)")
    ap.add_argument("--points", type=int, default=551, help="points of the brute-force sweep")
    args = ap.parse_args(argv)
    cpu, wall, res = continuation_cost(args.repeats)
    st = res.stats
    print(f"continuation 0.5-6 rad/s: {cpu:.2f} s CPU (median of {args.repeats}; wall {wall:.2f} s), "
          f"{len(res.branches)} branches, {res.n_points} orbits, {len(res.bifurcations)} bifurcations "
          f"({', '.join(f'{b.kind} {b.parameter:.5f}' for b in res.bifurcations)})")
    if st.get("evaluations"):
        print(f"  {1e3 * cpu / res.n_points:.2f} ms per orbit, {1e3 * cpu / st['evaluations']:.2f} ms per Newton step "
              f"(shooting evaluation with its monodromy), {st['evaluations']} evaluations")
    with tempfile.TemporaryDirectory() as tmp:
        work, swall, sres = sweep_cost(args.points, Path(tmp))
    print(f"brute-force sweep, {args.points} points: {work:.1f} s of per-point CPU ({swall:.1f} s wall on "
          f"{os.cpu_count()} cores); steady {int(sres.data[0]['steady'].sum())} of {args.points}")
    print(f"continuation is {work / cpu:.0f} times cheaper in CPU")


if __name__ == "__main__":
    main()
