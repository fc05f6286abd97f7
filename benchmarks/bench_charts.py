"""Cost of the design charts of the paper example: a fold curve over a decade of gamma and the
backbone of mode 1 to 5 m.

- Fold curve: ``cablesim.continuation`` with ``continuation.loci`` near the fundamental
  (2.2-2.8 rad/s), the response computed at gamma = 3 (where it folds: jumps, hysteresis) and
  its fold curves continued over gamma = 0.3 to 3 until they meet at their cusp. The cost of the
  curves alone is the run's less that of the same response without loci, timed alternately in
  the same run.
- Backbone: ``cablesim.backbone`` of mode 1 to a largest amplitude of 5 m.

Times are CPU seconds of this process (``time.process_time``; median of repeats after a warm-up
that compiles or loads the kernels) and wall seconds. Run with ``make bench`` or directly.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from cablesim import api

CASE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
RESPONSE = "continuation={omega: {start: 2.2, stop: 2.8}, gamma: 3.0, channels: [z2, z4]}"
LOCI = "continuation={omega: {start: 2.2, stop: 2.8}, channels: [z2, z4], loci: true, gamma: {start: 0.3, stop: 3.0}}"
GOAL = 30.0  # s of CPU, each


def timed(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return time.process_time() - c0, time.perf_counter() - w0, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="runs of each (median quoted)")
    args = ap.parse_args(argv)
    plain, loci, bb = api.load_case(CASE, overrides=[RESPONSE]), api.load_case(CASE, overrides=[LOCI]), api.load_case(CASE)
    api.continuation(loci)  # compile or load the kernels
    api.backbone(bb, mode=1, amplitude=0.5)
    rows = {"response": [], "loci": [], "backbone": []}
    for _ in range(args.repeats):  # alternating, so that a busy machine weighs on each alike
        rows["response"].append(timed(lambda: api.continuation(plain)))
        rows["loci"].append(timed(lambda: api.continuation(loci)))
        rows["backbone"].append(timed(lambda: api.backbone(bb, mode=1, amplitude=5.0)))
    med = {k: (float(np.median([r[0] for r in v])), float(np.median([r[1] for r in v]))) for k, v in rows.items()}
    res = rows["loci"][-1][2].result
    fold_cpu = med["loci"][0] - med["response"][0]
    print(f"response at gamma = 3, 2.2-2.8 rad/s: {med['response'][0]:.2f} s CPU (wall {med['response'][1]:.2f} s)")
    print(f"same with loci over gamma 0.3-3: {med['loci'][0]:.2f} s CPU (wall {med['loci'][1]:.2f} s); "
          f"the curves alone {fold_cpu:.2f} s CPU (goal < {GOAL:g} s)")
    for L in res.loci:
        print(f"  {L.name}: {L.omega.size} points, gamma {L.gamma.min():.4g}-{L.gamma.max():.4g}, "
              f"omega {L.omega.min():.5g}-{L.omega.max():.5g} rad/s; ends: {L.ends[0]}; {L.ends[1]}")
    for p in res.codim2:
        print(f"  {p.kind} at omega {p.omega:.6g} rad/s, gamma {p.gamma:.6g}")
    print(f"  {res.stats.get('loci_evaluations')} evaluations of the curves' defining systems")
    b = rows["backbone"][-1][2].result
    print(f"backbone of mode 1 to 5 m: {med['backbone'][0]:.2f} s CPU (wall {med['backbone'][1]:.2f} s; goal < {GOAL:g} s), "
          f"{b.omega.size} orbits, {b.stats.get('evaluations')} evaluations, omega {b.linear_omega:.6g} -> "
          f"{b.omega[-1]:.6g} rad/s; {b.end}")
    print(f"(median of {args.repeats} runs each, alternating)")


if __name__ == "__main__":
    main()
