"""The same scenes timed on this tree and on an earlier revision, side by side in one run.

For a change that must not make cablesim slower (a rewrite of its compiled kernels, say): each
scene runs in a fresh process per tree (``PYTHONPATH`` pointing at the tree), the trees
alternating round by round so that a shared machine's load falls on both alike; each process
first runs the scene once (compiling or loading its kernels), then times it ``--repeats`` times.
Reported: the median CPU and wall time of each tree over all its timed runs, and their ratio
(this tree over the other). The earlier revision is exported with ``git archive`` into
``runs/bench-trees/<revision>/`` (kept, so that its kernels compile once).

Scenes (all public entry points that every revision since the heavy-cable release has):

- ``2-node dopri5``: the paper's example (exact analysis) forced at 2.4 rad/s for 1000 s by
  dopri5 at its default tolerance (the time loop of a 2-node cable);
- ``2-node rk4``: the same with rk4, dt = 0.02 s;
- ``approximate``: the paper's Fig. 6 cable (approximate analysis) for 200 s by dopri5;
- ``200-node``: ``configs/heavy-span.yaml`` with 200 nodes for 2 s by its default integrator
  (generalized-alpha, banded Newton solves);
- ``continuation``: every periodic response of the paper's example over 0.5-6 rad/s.

Usage: ``python benchmarks/bench_revisions.py --against REV [--this REV] [--rounds 3] [--repeats 3]``
(``--this``: time a committed revision instead of the working tree, which may then be edited
while the benchmark runs).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]

SCENE = r'''
import json, sys, time
from pathlib import Path
import numpy as np
from cablesim import api
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.dynamics.integrators import DOPRI5, RK4
from cablesim.dynamics.simulate import simulate

repo, name, repeats = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])

def history(path, overrides, omega, duration, integ=None, step=0.05):
    case = api.load_case(repo / path, overrides=overrides)
    eom = build_equations(case, run_static(case, all_models=False), omega=omega)
    integ = integ(eom) if integ else make_integrator(case.integrator, eom, max(omega, float(eom.frequencies[0])))
    return lambda: simulate(eom, integ, duration, step, split=False)

if name == "2-node dopri5":
    job = history("configs/paper-example.yaml", [], 2.4, 1000.0)
elif name == "2-node rk4":
    job = history("configs/paper-example.yaml", [], 2.4, 1000.0, lambda eom: RK4(dt=0.02))
elif name == "approximate":
    job = history("configs/paper/fig6.yaml", [], 1.84, 200.0)
elif name == "200-node":
    job = history("configs/heavy-span.yaml", ["cable.nodes=200", "loads.point=[]"], 2.0, 2.0, step=0.01)
elif name == "continuation":
    case = api.load_case(repo / "configs/paper-example.yaml",
                         overrides=["continuation={omega: {start: 0.5, stop: 6.0}, channels: [z2, z4]}"])
    job = lambda: api.continuation(case)
else:
    raise SystemExit(f"unknown scene {name!r}")
job()  # compile or load the kernels
out = []
for _ in range(repeats):
    c0, w0 = time.process_time(), time.perf_counter()
    job()
    out.append((time.process_time() - c0, time.perf_counter() - w0))
print(json.dumps(out))
'''

SCENES = ("2-node dopri5", "2-node rk4", "approximate", "200-node", "continuation")


def export(rev: str) -> Path:
    """The tree of revision ``rev`` (exported once, kept with its compiled kernels)."""
    sha = subprocess.run(["git", "rev-parse", "--short=12", rev], cwd=REPO, check=True, capture_output=True,
                         text=True).stdout.strip()
    dest = REPO / "runs" / "bench-trees" / sha
    if not (dest / "cablesim").is_dir():
        dest.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "archive", sha], cwd=REPO, check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return dest


def timed(tree: Path, scene: str, repeats: int) -> list[tuple[float, float]]:
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "-c", SCENE, str(tree), scene, str(repeats)], env=env, cwd=tree,
                         check=True, capture_output=True, text=True)
    return [tuple(x) for x in json.loads(res.stdout.strip().splitlines()[-1])]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", required=True, help="the earlier revision (a commit, tag or branch)")
    ap.add_argument("--this", help="a revision to time instead of the working tree")
    ap.add_argument("--rounds", type=int, default=3, help="alternations of the two trees per scene")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per process")
    ap.add_argument("--scene", action="append", choices=SCENES, help="scenes to run (default: all)")
    args = ap.parse_args(argv)
    other = export(args.against)
    mine_tree = export(args.this) if args.this else REPO
    print(f"this tree ({mine_tree}) against {args.against} ({other.name}); medians over {args.rounds} rounds x "
          f"{args.repeats} runs; ratio = this / earlier")
    print(f"{'scene':16s} {'CPU this':>10s} {'CPU earlier':>12s} {'ratio':>6s} {'wall this':>10s} {'wall earlier':>13s} {'ratio':>6s}")
    for scene in args.scene or SCENES:
        mine, theirs = [], []
        for r in range(args.rounds):
            order = (mine_tree, other) if r % 2 == 0 else (other, mine_tree)
            for tree in order:
                (mine if tree == mine_tree else theirs).extend(timed(tree, scene, args.repeats))
        a, b = np.array(mine), np.array(theirs)
        ca, cb, wa, wb = np.median(a[:, 0]), np.median(b[:, 0]), np.median(a[:, 1]), np.median(b[:, 1])
        print(f"{scene:16s} {ca:10.3f} {cb:12.3f} {ca / cb:6.2f} {wa:10.3f} {wb:13.3f} {wa / wb:6.2f}", flush=True)


if __name__ == "__main__":
    main()
