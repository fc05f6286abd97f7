"""Accelerated sweeps of a heavy cable above the matrix-free crossover, against integration alone.

The case: ``configs/heavy-span.yaml`` at ``nodes: 50`` (100 degrees of freedom, 200 states: an
accelerated point shoots matrix-free by the measured rule of
:data:`cablesim.orbits.mfproblem.MATRIX_FREE_DOF`; Radau IIA shooting, the scheme chosen
automatically for this stiff cable), its default integrator (generalized-alpha, the cable being
stiff) and default sweep settings, each point started from rest, forced at ``--omega`` (default
2.0, 2.2, 2.3, 2.4, 2.6 rad/s, through the first resonance at 2.36 rad/s).

Every point is a one-point sweep (``cablesim.api.sweep``, one job, in this process), run with
``accelerate: false`` and ``true`` alternately, ``--repeats`` times, numba's compilation excluded
by a warm-up on a 4-node cable: per point the medians of CPU time (``time.process_time``) and
wall time of each, how the accelerated point was decided, the simulated seconds of each, and the
largest relative difference of the amplitudes (every channel) where both are steady; then the
totals and their ratio. ``--profile`` prints instead where an accelerated point's CPU goes.

Usage::

    .venv/bin/python benchmarks/bench_accelerate_heavy.py
    .venv/bin/python benchmarks/bench_accelerate_heavy.py --nodes 20 --omega 2.0 --repeats 3
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from cablesim import api

CASE = Path(__file__).resolve().parents[1] / "configs" / "heavy-span.yaml"


def point(nodes: int, omega: float, accelerate: bool, tmp: Path):
    """``(cpu_s, wall_s, data)`` of a one-point sweep."""
    case = api.load_case(CASE, overrides=[f"cable.nodes={nodes}", f"sweep.omega=[{omega}]",
                                          f"sweep.accelerate={str(accelerate).lower()}"])
    t, w = time.process_time(), time.perf_counter()
    res = api.sweep(case, jobs=1, output=tmp / f"p{nodes}-{omega}-{accelerate}.h5").result
    return time.process_time() - t, time.perf_counter() - w, res.data[0]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, default=50)
    ap.add_argument("--omega", type=float, action="append", help="rad/s (repeatable)")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--profile", action="store_true", help="profile the accelerated points instead")
    a = ap.parse_args(argv)
    omegas = a.omega or [2.0, 2.2, 2.3, 2.4, 2.6]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        point(4, 2.0, True, tmp), point(4, 2.0, False, tmp)  # warm-up: compilation
        if a.profile:
            prof = cProfile.Profile()
            prof.enable()
            for w in omegas:
                point(a.nodes, w, True, tmp)
            prof.disable()
            pstats.Stats(prof).sort_stats("tottime").print_stats(15)
            return
        print(f"heavy span, {a.nodes} nodes; medians of {a.repeats} alternating runs")
        print("| omega, rad/s | alone: CPU s / wall s / simulated s | accelerated: CPU s / wall s / simulated s "
              "| decided | CPU ratio | max rel. amplitude difference |")
        print("|---|---|---|---|---|---|")
        tot = np.zeros(4)
        for w in omegas:
            runs = {False: [], True: []}
            for _ in range(a.repeats):
                for acc in (False, True):
                    runs[acc].append(point(a.nodes, w, acc, tmp))
            (cp, wp), (ca, wa) = [(statistics.median(r[0] for r in runs[acc]), statistics.median(r[1] for r in runs[acc]))
                                  for acc in (False, True)]
            dp, da = runs[False][-1][2], runs[True][-1][2]
            both = bool(dp["steady"][0] and da["steady"][0])
            diff = float(np.max(np.abs(da["amplitude"][0] - dp["amplitude"][0]) / np.abs(dp["amplitude"][0]))) if both \
                else np.nan
            flags = "" if dp["period"][0] == da["period"][0] and dp["steady"][0] == da["steady"][0] else \
                f" (differ: period {dp['period'][0]} / {da['period'][0]}, steady {dp['steady'][0]} / {da['steady'][0]})"
            print(f"| {w:g} | {cp:.1f} / {wp:.1f} / {dp['t_end'][0]:.0f} | {ca:.1f} / {wa:.1f} / {da['t_end'][0]:.0f} | "
                  f"{da['decided'][0]}{flags} | {cp / ca:.1f}x | {diff:.1e} |", flush=True)
            tot += [cp, wp, ca, wa]
        print(f"| total | {tot[0]:.1f} / {tot[1]:.1f} | {tot[2]:.1f} / {tot[3]:.1f} | | {tot[0] / tot[2]:.1f}x "
              f"(wall {tot[1] / tot[3]:.1f}x) | |")


if __name__ == "__main__":
    main()
