"""Cost of a spatial continuation against the planar one of the same case, side by side.

The paper's example (``configs/paper-example.yaml``) continued over omega 0.5-6 rad/s as it is
(planar, 2 components per node) and with ``spatial: true`` (3 components per node, its loads
in the plane): every periodic response, the period-2 branch and the bifurcations of each, and
for the spatial case the split of every planar orbit's monodromy into its in-plane and
out-of-plane blocks with the out-of-plane tests. After a warm-up of each that compiles or loads
the kernels, the planar and the spatial runs alternate ``--repeats`` times in this process;
quoted: the median CPU (``time.process_time``) and wall seconds of each, their ratio (the
target is at most 3), and what each found. ``--profile`` adds the top of a cProfile of one
spatial run; ``--check-steps`` one more spatial run that re-solves the orbit at the middle of
every accepted step of its planar branches and compares the out-of-plane multipliers of the
step rule's linear interpolant of the block (:func:`~cablesim.orbits.stability.interpolated_step_ratio`)
with the true ones there. Run with ``python benchmarks/bench_spatial_continuation.py`` (part of
``make bench``).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import time
from pathlib import Path

import numpy as np

from cablesim import api
from cablesim.orbits import problems, stability
from cablesim.orbits.shooting import solve_orbit
from cablesim.orbits.stability import sort_multipliers

CASE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
#: The same range and the same two channels (vertical of both nodes) in both runs.
CONTINUATION = "continuation={omega: {start: 0.5, stop: 6.0}, channels: [node1.v, node2.v]}"


def cases():
    """The planar and the spatial case (``spatial: true``, loads in the plane)."""
    return {False: api.load_case(CASE, overrides=[CONTINUATION]),
            True: api.load_case(CASE, overrides=[CONTINUATION, "spatial=true"])}


def timed(case):
    """CPU and wall seconds of a continuation, its result and the CPU seconds spent on each
    branch (by index: the time up to each orbit delivered goes to that orbit's branch, so the
    location of a bifurcation counts on the branch it is on and a switch on the new branch)."""
    per_branch: dict = {}
    last = [time.process_time()]

    def progress(point):
        now = time.process_time()
        per_branch[point.branch] = per_branch.get(point.branch, 0.0) + now - last[0]
        last[0] = now

    c0, w0 = time.process_time(), time.perf_counter()
    res = api.continuation(case, progress=progress).result
    return time.process_time() - c0, time.perf_counter() - w0, res, per_branch


def found(res) -> str:
    """Branches, orbits and bifurcations of a result, in words."""
    bifs = ", ".join(f"{b.kind}{'' if b.plane == 'in-plane' else ' ' + b.plane} {b.parameter:.5f}"
                     for b in sorted(res.bifurcations, key=lambda b: b.parameter))
    return (f"{len(res.branches)} branches, {res.n_points} orbits, {res.stats.get('evaluations', 0)} shooting "
            f"evaluations; bifurcations: {bifs or 'none'}")


def profile(case, top: int) -> str:
    """The functions taking the most cumulative time in one run of ``case``."""
    prof = cProfile.Profile()
    prof.enable()
    api.continuation(case)
    prof.disable()
    out = io.StringIO()
    pstats.Stats(prof, stream=out).sort_stats("cumulative").print_stats(top)
    return out.getvalue()


def rule_midpoint(P_a: np.ndarray, P_b: np.ndarray, geodesic: bool) -> np.ndarray:
    """The out-of-plane block the step rule assumes at mid-step: on the geodesic
    ``P_a (P_a^-1 P_b)^(1/2)`` where the rule follows it, else on the straight line."""
    if geodesic:
        step = stability.StepLog(P_a, P_b)
        if step.usable():
            return P_a @ step.power(np.array([0.5]))[0]
    return 0.5 * (P_a + P_b)


def check_steps(case) -> str:
    """The largest error of the out-of-plane multipliers of the step rule's interpolant at
    mid-step, over the accepted steps of the planar branches, relative to the true multipliers'
    distance from the unit circle there (the orbit re-solved at the chord's middle parameter)."""
    rule = problems.PlanarOrbitProblem.step_ratio
    worst = []

    def checked(self, ev_a, ev_b, ev_before=None):
        ratio = rule(self, ev_a, ev_b, ev_before)
        if ratio <= 1.0:
            sol = solve_orbit(self.shooting, 0.5 * (ev_a.u + ev_b.u), 0.5 * (ev_a.lam + ev_b.lam),
                              scale=self.u_scale[: self.shooting.n])
            if sol.converged:
                true = sort_multipliers(np.linalg.eigvals(self.mirror.blocks(sol.evaluation.monodromy)[1]))
                P_a, P_b = (problems.monodromy_blocks(self.mirror, ev)[1] for ev in (ev_a, ev_b))
                mid = np.linalg.eigvals(rule_midpoint(P_a, P_b, ev_before is not None))
                err = max(float(np.abs(mid - mu).min()) for mu in true)
                worst.append(err / float(np.abs(np.abs(true) - 1.0).min()))
        return ratio

    problems.PlanarOrbitProblem.step_ratio = checked
    try:
        api.continuation(case)
    finally:
        problems.PlanarOrbitProblem.step_ratio = rule
    return (f"  mid-step check of {len(worst)} accepted steps: the interpolated out-of-plane multipliers within "
            f"{max(worst):.3f} of the true ones' distance from the unit circle (median {np.median(worst):.3f})")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="alternations of planar and spatial runs (median quoted)")
    ap.add_argument("--profile", type=int, default=0, metavar="N", help="print the top N functions of a profile "
                    "of one spatial run")
    ap.add_argument("--check-steps", action="store_true", help="check the out-of-plane step rule's interpolant "
                    "against orbits re-solved at mid-step")
    args = ap.parse_args(argv)
    case = cases()
    last = {sp: timed(case[sp])[2] for sp in (False, True)}  # compile or load the kernels
    cpu, wall, branch_cpu = {False: [], True: []}, {False: [], True: []}, {False: [], True: []}
    for _ in range(args.repeats):
        for sp in (False, True):
            c, w, last[sp], per_branch = timed(case[sp])
            cpu[sp].append(c)
            wall[sp].append(w)
            branch_cpu[sp].append(per_branch)
    print(f"continuation of the paper example over omega 0.5-6 rad/s; median of {args.repeats} alternating runs")
    for sp in (False, True):
        print(f"  {'spatial' if sp else 'planar ':7s}: {np.median(cpu[sp]):7.2f} s CPU, {np.median(wall[sp]):7.2f} s "
              f"wall; {found(last[sp])}")
        for k, b in enumerate(last[sp].branches):
            kind = "nonplanar" if getattr(b, "nonplanar", False) else "planar"
            secs = np.median([run.get(k, 0.0) for run in branch_cpu[sp]])
            print(f"      {b.name} ({kind}, period {b.period}): {b.parameter.size} orbits, {secs:.2f} s CPU")
    rc = np.median(cpu[True]) / np.median(cpu[False])
    rw = np.median(wall[True]) / np.median(wall[False])
    print(f"  spatial / planar: {rc:.2f} in CPU, {rw:.2f} in wall time (target: at most 3)")
    same = [sum(t for k, t in run.items() if not getattr(last[True].branches[k], "nonplanar", False))
            for run in branch_cpu[True]]
    print(f"  the branches both compute (the spatial run's planar ones): {np.median(same):.2f} s CPU, "
          f"{np.median(same) / np.median(cpu[False]):.2f} times the planar run", flush=True)
    if args.check_steps:
        print(check_steps(case[True]), flush=True)
    if args.profile:
        print(profile(case[True], args.profile))


if __name__ == "__main__":
    main()
