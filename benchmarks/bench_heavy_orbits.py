"""Periodic orbits of heavy cables: the dense against the matrix-free shooting.

The cable: the heavy span of ``configs/heavy-span.yaml`` (300 m span, ACSR conductor, 0.5 %
Rayleigh damping in modes 1 and 2, the marker ball at midspan) with ``n`` interior nodes, a
harmonic load at a fifth of the span (``--load``, default 50 N: the case file's 200 N drives the
20-node cable to 6 m at its first resonance, where a segment goes slack and the branch ends at a
grazing orbit at 2.33 rad/s before the second resonance); exact analysis.

Two measurements, in one process, numba's compilation excluded by a warm-up:

- ``--crossover``: for small ``n``, the CPU time of one orbit by Newton's method from the linear
  response at 1.5 rad/s with its Floquet multipliers, dense (:class:`Shooting`, the whole
  monodromy) and matrix-free (:class:`MatrixFreeShooting`, same rk8 scheme, Newton-GMRES and
  the leading multipliers), medians of ``--repeats`` runs alternating the two; this sets
  :data:`cablesim.orbits.mfproblem.MATRIX_FREE_DOF`;
- the continuation (default): the frequency response of the period-1 branch from ``--start``
  to ``--stop`` rad/s (the first two linear resonances are 2.35 and 2.93 rad/s at 20 nodes) by
  the matrix-free shooting (``--scheme``, default ``auto``: Radau IIA for these stiff cables),
  for each ``--n``: CPU and wall time, points, orbits evaluated, Newton steps and Krylov
  iterations per Newton step;
- ``--against-multipliers``: the continuation by the step rule of the leading subspace's
  geodesic (:func:`~cablesim.orbits.floquet.leading_step_ratio`) and by the kept multipliers
  alone (:func:`~cablesim.orbits.floquet.truncated_step_ratio`, the rule before it), alternating
  in this process ``--repeats`` times for each ``--n``;
- ``--check-steps``: the continuation once more, the orbit re-solved at the middle of every
  step accepted on the geodesic, its kept multipliers against the geodesic's there (the error
  over their distance from the unit circle; the rule allows 0.5).

Usage::

    .venv/bin/python benchmarks/bench_heavy_orbits.py                 # n = 20, 50
    .venv/bin/python benchmarks/bench_heavy_orbits.py --crossover
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.orbits import Shooting, cable_system, continue_branches, floquet, linear_response_state, mfproblem, solve_orbit
from cablesim.orbits.branches import cable_scales
from cablesim.orbits.floquet import aligned_block, kept_block, truncated_step_ratio
from cablesim.orbits.matrixfree import MatrixFreeShooting, orbit_leading, solve_orbit_mf
from cablesim.orbits.stability import StepLog

CASE = Path(__file__).resolve().parents[1] / "configs" / "heavy-span.yaml"


def equations(n: int, omega: float, load: float = 200.0):
    """The heavy span with ``n`` interior nodes and a harmonic load of ``load`` N at 60 m."""
    text = CASE.read_text().replace("nodes: 100", f"nodes: {n}")  # its point loads stay at x = 150 m and 60 m
    if "FL: [0.0, 200.0]" not in text:
        raise SystemExit(f"{CASE} no longer has the 200 N load this benchmark replaces")
    text = text.replace("FL: [0.0, 200.0]", f"FL: [0.0, {load!r}]")
    case = parse_case(text)
    return build_equations(case, run_static(case), omega=omega)


def one_orbit(eom, omega: float, dense: bool) -> float:
    """CPU seconds of one orbit with its multipliers."""
    sysm = cable_system(eom)
    scale, _ = cable_scales(eom, "omega", 1.0, 3.0)
    u0 = linear_response_state(eom, omega)
    t = time.process_time()
    if dense:
        sol = solve_orbit(Shooting(sysm), u0, omega, scale=scale)
    else:
        sh = MatrixFreeShooting(sysm, scheme="rk8")
        sol = solve_orbit_mf(sh, u0, omega, scale=scale)
        orbit_leading(sh, sol.evaluation, scale)
    if not sol.converged:
        raise RuntimeError(f"no orbit at {omega} rad/s ({'dense' if dense else 'matrix-free'})")
    return time.process_time() - t


def crossover(nodes: list, repeats: int) -> None:
    print("nodes  states  dense_cpu_s  matrixfree_cpu_s  ratio")
    for n in nodes:
        eom = equations(n, 1.5)
        one_orbit(eom, 1.5, True), one_orbit(eom, 1.5, False)  # warm-up
        d, m = [], []
        for _ in range(repeats):
            d.append(one_orbit(eom, 1.5, True))
            m.append(one_orbit(eom, 1.5, False))
        dm, mm = statistics.median(d), statistics.median(m)
        print(f"{n:5d}  {4 * n:6d}  {dm:11.3f}  {mm:16.3f}  {dm / mm:5.2f}")


def response(n: int, start: float, stop: float, scheme: str, load: float) -> None:
    eom = equations(n, start, load)
    t, w = time.process_time(), time.perf_counter()
    d = continue_branches(eom, "omega", start, stop, switch_branches=False, scheme=scheme, matrix_free=True)
    cpu, wall = time.process_time() - t, time.perf_counter() - w
    s = d.stats
    per = s["krylov_iterations"] / max(s["newton_steps"], 1)
    # a branch stopped by a flow that failed says why (SLACK: it ended at a grazing orbit)
    ends = ",".join(b.end.name + (f"({b.failure.name})" if getattr(b, "failure", None) is not None else "")
                    for b in d.branches)
    folds = ",".join(f"{p.parameter:.4f}" for b in d.branches for p in b.points if p.special == "fold")
    print(f"{n:5d}  {cpu:8.1f}  {wall:8.1f}  {s['points']:6d}  {s['evaluations']:6d}  {s['newton_steps']:6d}  "
          f"{per:6.1f}  {ends}  {folds or '-'}")


def multipliers_alone(lead_a, lead_b, *before):
    """The step rule before the geodesic: the kept multipliers alone."""
    return truncated_step_ratio(lead_a.multipliers, lead_b.multipliers)


def against_multipliers(nodes: list, start: float, stop: float, scheme: str, load: float, repeats: int) -> None:
    print("nodes  rule         cpu_s  wall_s  points  orbits  newton  krylov/newton  end  folds_rad/s")
    for n in nodes:
        for _ in range(repeats):
            for name, rule in (("geodesic", floquet.leading_step_ratio), ("multipliers", multipliers_alone)):
                mfproblem.leading_step_ratio = rule
                try:
                    print(f"{name:11s}", end="  ")
                    response(n, start, stop, scheme, load)
                finally:
                    mfproblem.leading_step_ratio = floquet.leading_step_ratio


def check_steps(n: int, start: float, stop: float, scheme: str, load: float) -> None:
    """The geodesic's kept multipliers at mid-step against the orbit's there (module docstring)."""
    rule = mfproblem.MatrixFreeOrbitProblem.step_ratio
    errors, far = [], 0

    def checked(self, ev_a, ev_b, ev_before=None):
        nonlocal far
        ratio = rule(self, ev_a, ev_b, ev_before)
        la, lb = self.leading(ev_a), self.leading(ev_b)
        if ratio > 1.0 or ev_before is None or la.complete:
            return ratio
        (Va, Sa), (Vb, Sb) = kept_block(la), kept_block(lb)
        if Va.shape != Vb.shape:
            return ratio  # judged on the multipliers
        step = StepLog(Sa, aligned_block(Vb, Sb, Va))
        if not step.usable():
            return ratio
        u_mid = 0.5 * (ev_a.u + ev_b.u)
        sol = solve_orbit_mf(self.shooting, u_mid, 0.5 * (ev_a.lam + ev_b.lam), scale=self.state_scale)
        if not sol.converged:
            return ratio
        if np.linalg.norm((sol.u - u_mid) / self.u_scale) > 0.25 * np.linalg.norm((ev_b.u - ev_a.u) / self.u_scale):
            far += 1  # another orbit at the middle parameter (a step across a fold)
            return ratio
        true = orbit_leading(self.shooting, sol.evaluation, self.state_scale, start=la.basis).multipliers
        true = true[np.abs(true) > self.bound + 0.02]  # those that cannot have crossed the bound
        mid = np.linalg.eigvals(Sa @ step.power(np.array([0.5]))[0])
        errors.append(max(float(np.abs(mid - mu).min()) / abs(1.0 - abs(mu)) for mu in true))
        return ratio

    mfproblem.MatrixFreeOrbitProblem.step_ratio = checked
    try:
        eom = equations(n, start, load)
        continue_branches(eom, "omega", start, stop, switch_branches=False, scheme=scheme, matrix_free=True)
    finally:
        mfproblem.MatrixFreeOrbitProblem.step_ratio = rule
    e = np.array(errors)
    print(f"  mid-step check, {n} nodes: {e.size} steps on the geodesic, the kept multipliers within {e.max():.3f} "
          f"of their distance from the unit circle (median {np.median(e):.4f}; {int((e > 0.25).sum())} above 0.25); "
          f"{far} steps across a fold not checked")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, action="append", help="interior nodes (repeatable; default 20, 50)")
    ap.add_argument("--start", type=float, default=1.5)
    ap.add_argument("--stop", type=float, default=3.2)
    ap.add_argument("--scheme", default="auto")
    ap.add_argument("--load", type=float, default=50.0, help="harmonic load at 60 m, N (continuation)")
    ap.add_argument("--crossover", action="store_true")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--against-multipliers", action="store_true", help="the step rule against the multipliers alone")
    ap.add_argument("--check-steps", action="store_true", help="check the geodesic's multipliers at mid-step")
    a = ap.parse_args()
    if a.crossover:
        crossover(a.n or [3, 5, 8, 12], a.repeats)
        return
    response(4, a.start, a.start + 0.05, a.scheme, a.load)  # warm-up: compilation
    if a.check_steps:
        for n in a.n or [20]:
            check_steps(n, a.start, a.stop, a.scheme, a.load)
        return
    if a.against_multipliers:
        against_multipliers(a.n or [20], a.start, a.stop, a.scheme, a.load, a.repeats)
        return
    print("nodes  cpu_s  wall_s  points  orbits  newton  krylov/newton  end  folds_rad/s")
    for n in a.n or [20, 50]:
        response(n, a.start, a.stop, a.scheme, a.load)


if __name__ == "__main__":
    main()
