"""Cost of a continuation through slack: the tracing of the branches against the slack patterns
and grazing points taken on their orbits afterwards.

The paper's cable at 2.45 rad/s continued in the load factor gamma from 12.8 to 14 with
``continuation.through_slack`` (segment 3 grazes at gamma = 13.376; the period-2 branch born at
13.730 has two more grazing points). Times are this process's CPU and wall seconds, medians of
repeats after a warm-up run that compiles or loads the kernels: the whole continuation, its
tracing (``stats["seconds"]``) and the rest (strains, slack patterns, grazing location); then,
per orbit (the orbit of FL x 13.5, medians of 25), one shooting evaluation with its monodromy,
the slack pattern (:func:`cablesim.orbits.slackpattern.slack_pattern`) and the least tensions
(:func:`cablesim.analyses.orbit_slack.tension_minima`) and both as a continuation takes them
(:func:`cablesim.analyses.orbit_slack.orbit_pattern`). Run with
``.venv/bin/python benchmarks/bench_slack_continuation.py``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from cablesim import api
from cablesim.analyses.orbit_slack import orbit_pattern, tension_minima
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.orbits.shooting import Shooting, solve_orbit
from cablesim.orbits.slackpattern import slack_pattern
from cablesim.orbits.systems import cable_system

CASE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
SECTION = ("continuation={parameter: gamma, omega: 2.45, gamma: {start: 12.8, stop: 14.0}, channels: [z2, z4], "
           "through_slack: true}")
#: A state near the orbit at FL x 13.5 (tests/test_orbits_slack.py).
START = np.array([-4.334, 7.088, -2.68, -3.665, -18.247, 26.177, -14.215, -21.179])


def timed(f, repeats: int):
    """Medians of CPU and wall seconds of ``f()`` over ``repeats`` calls (after one more)."""
    f()
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        out = f()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return float(np.median(cpu)), float(np.median(wall)), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="continuation runs (median quoted)")
    args = ap.parse_args(argv)
    case = api.load_case(CASE, overrides=[SECTION])
    traced = []

    def run():
        c0 = time.process_time()
        res = api.continuation(case).result
        traced.append((res.stats["seconds"], time.process_time() - c0))
        return res

    cpu, wall, res = timed(run, args.repeats)
    trace = float(np.median([t for t, _ in traced[1:]]))
    graz = [b for b in res.bifurcations if b.kind == "grazing"]
    print(f"continuation through slack, gamma 12.8-14: {cpu:.2f} s CPU, {wall:.2f} s wall (medians of {args.repeats}); "
          f"{res.n_points} orbits on {len(res.branches)} branches, {len(graz)} grazing points; tracing {trace:.2f} s wall, "
          f"the rest (strains, slack patterns, grazing points) {wall - trace:.2f} s wall")
    paper = api.load_case(None)
    static = run_static(paper)
    eom = build_equations(paper, static, omega=2.45, load_scale=13.5)
    sh = Shooting(cable_system(eom), through_slack=True)
    sol = solve_orbit(sh, START)
    u, lam = sol.u, sh.default_lam()
    for name, f in (("shooting evaluation with its monodromy", lambda: sh.evaluate(u, lam)),
                    ("slack pattern (events, snap loads)", lambda: slack_pattern(sh, u, lam)),
                    ("least tensions", lambda: tension_minima(sh, eom, u, lam)),
                    ("both as the continuation takes them (one refined flow)", lambda: orbit_pattern(sh, eom, u, lam))):
        c, w, _ = timed(f, 25)
        print(f"  per orbit, {name}: {1e3 * c:.2f} ms CPU, {1e3 * w:.2f} ms wall (medians of 25)")


if __name__ == "__main__":
    main()
