"""A convergence study in rtol on the paper example: does halving rtol halve the error?

The paper example's time history (``cablesim history configs/paper-example.yaml``: 2.4 rad/s,
600 s, saved every 0.05 s), dopri5 at rtol 1e-8 (the default), 5e-9, 2.5e-9 and 1.25e-9, with
``atol`` as cablesim chooses it (following rtol) and, for comparison, held at the default rtol's
3.0e-8 m. Error: max |z - z_ref| / max |z_ref| over the record against scipy's Fortran DOP853 at
rtol 1e-13 on the second-order form written in ``bench_dynamics.py`` (checked against rtol
1e-12). Costs: medians of three runs, wall and CPU time, in the same run. Prints a Markdown
table (``benchmarks/README.md``, tolerances).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from bench_dynamics import Scene, check_formulations, ref_dop853, setup
from cablesim.analyses.setup import make_integrator
from cablesim.case import IntegratorSpec
from cablesim.dynamics.integrators import DOPRI5
from cablesim.dynamics.simulate import simulate

SCENE = Scene(0, "paper example, history defaults: w = 2.4 rad/s, 600 s", None, "exact", 2.4, 600.0, 0.05, 100.0)


def timed(su, integ, repeats):
    walls, cpus = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        h = simulate(su.eom, integ, su.duration, su.scene.output_step, s0=su.s0, split=False)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    assert h.completed, h.message
    return h.z, statistics.median(walls), statistics.median(cpus)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=SCENE.duration, help="simulated seconds")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    su = setup(SCENE, args.duration)
    check_formulations(su)
    zref = ref_dop853(su, 1e-13)
    check = float(np.abs(ref_dop853(su, 1e-12) - zref).max() / np.abs(zref).max())
    scale = np.abs(zref).max()
    fixed_atol = make_integrator(IntegratorSpec(), su.eom, su.w_interest).atol
    simulate(su.eom, DOPRI5(), 1.0, 0.05)  # compile outside the timings
    print(f"reference: DOP853 rtol 1e-13; against rtol 1e-12: {check:.1e}; duration {args.duration:g} s\n")
    print("| rtol | atol (m), following rtol | error | ratio | wall (s) | CPU (s) "
          "| error, atol held at %.2g m | ratio |" % fixed_atol)
    print("|---|---|---|---|---|---|---|---|")
    prev = prev_fixed = None
    for k in range(4):
        rtol = 1e-8 / 2**k
        integ = make_integrator(IntegratorSpec(rtol=rtol), su.eom, su.w_interest)
        z, wall, cpu = timed(su, integ, args.repeats)
        e = float(np.abs(z - zref).max() / scale)
        zf, _, _ = timed(su, DOPRI5(rtol=rtol, atol=fixed_atol), 1)
        ef = float(np.abs(zf - zref).max() / scale)
        r = "-" if prev is None else f"{prev / e:.2f}"
        rf = "-" if prev_fixed is None else f"{prev_fixed / ef:.2f}"
        print(f"| {rtol:.3g} | {integ.atol:.3g} | {e:.2e} | {r} | {wall:.3f} | {cpu:.3f} | {ef:.2e} | {rf} |")
        prev, prev_fixed = e, ef


if __name__ == "__main__":
    main()
