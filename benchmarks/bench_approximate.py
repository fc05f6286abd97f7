"""The approximate analysis for many nodes: its stiffness ``K = N(P)^-1`` applied in O(n).

The cable of ``bench_heavy.py`` (100 m span, natural length 102.5 m, EA = 2e8 N, 10 kg/m under
gravity, 1 kN harmonic point load at a third of the span, 2 rad/s, 1 % Rayleigh damping) in the
approximate analysis. For each n, in one process, numba's compilation excluded by warm-up calls:

- **kernel, side by side**: ``K v`` at loads ``P`` near F0 (the closure already solved) by the
  full flexibility, ``N = D + f`` assembled (:func:`cablesim.dynamics.kernels.approximate_flexibility`)
  and solved (``solve_small``), against the factored form
  (:func:`cablesim.dynamics.flexibility.segment_factors` + ``stiffness_product``). Median of
  ``--repeats`` timings of each, alternating; agreement ``max |K v - N^-1 v| / max |N^-1 v|``,
  and the residual ``max |N (K v) - v| / max |v|`` of the factored product.
- **whole run**: wall seconds per simulated second of a history from rest with the default
  integrator (generalized-alpha for these stiff cables; its Newton matrices are banded plus a
  rank-4 correction, solved in O(n)), over ``--seconds`` simulated seconds (median of
  ``--repeats``), and its time per step; with the growth exponent of the cost per step from the
  smallest to the largest n timed.

Usage::

    .venv/bin/python benchmarks/bench_approximate.py
    .venv/bin/python benchmarks/bench_approximate.py --n 25 --n 50 --repeats 5
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from bench_heavy import cost  # the same timing rule (median of repeats after a warm-up)

from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.case import IntegratorSpec, parse_case
from cablesim.dynamics import flexibility as fx
from cablesim.dynamics import kernels as kn

CASE = """\
cable: {{L: 100.0, H: 0.0, length: 102.5, nodes: {n}, EA: 2.0e8, mass_per_length: 10.0}}
loads: {{gravity: 9.81, point: [{{node: {k}, FL: [0.0, 1.0e3]}}]}}
analysis: approximate
"""
OMEGA = 2.0


def equations(n: int):
    case = parse_case(CASE.format(n=n, k=max(1, n // 3)))
    return build_equations(case, run_static(case, all_models=False), omega=OMEGA)


def kernel_row(n: int, repeats: int) -> dict:
    """Both ways of ``K v`` at loads 10 % off F0, timed alternately (medians, seconds)."""
    eom = equations(n)
    c = eom.cable
    S, EA = np.asarray(c.S, float), float(c.EA)
    P = eom.F0 * (1.0 + 0.1 * np.random.default_rng(1).standard_normal(eom.n_dof))
    Q, F = np.empty((n + 1, 2)), np.array(eom.F1, float)
    kn.cumulative_loads(P, Q)
    assert kn.closure_solve(S, Q, 0.0, c.L, c.H, F, 1e-13 * c.total_length, 60) >= 0
    v = np.random.default_rng(2).standard_normal(eom.n_dof)
    nd = eom.n_dof
    x, u, T, N, LU = np.empty(nd), np.empty(nd), np.empty(n + 1), np.empty((nd, nd)), np.empty((nd, nd))
    fw = kn.flexibility_workspace(n)
    fac, gi, Fd = fx.factor_workspace(n)
    full, factored = np.empty(nd), np.empty(nd)

    def by_full():
        kn.approximate_flexibility(S, EA, Q, F, x, u, T, N, fw)
        kn.solve_small(N, v, full, LU)

    def by_factors():
        fx.segment_factors(S, EA, Q, F, T, fac, gi)
        fx.stiffness_product(fac, gi, v, factored, Fd)

    by_full(), by_factors()  # compile
    inner = max(1, int(2e5 / n**2))  # calls per timing of the full form, so each timing is ~ms
    walls = {"full": [], "factored": []}
    for _ in range(repeats):
        for name, f, calls in (("full", by_full, max(1, inner // 10)), ("factored", by_factors, inner)):
            t = time.perf_counter()
            for _ in range(calls):
                f()
            walls[name].append((time.perf_counter() - t) / calls)
    by_full()
    kn.approximate_flexibility(S, EA, Q, F, x, u, T, N, fw)
    return dict(
        n=n,
        full=float(np.median(walls["full"])),
        factored=float(np.median(walls["factored"])),
        agreement=float(np.abs(factored - full).max() / np.abs(full).max()),
        residual=float(np.abs(N @ factored - v).max() / np.abs(v).max()),
    )


def run_cost(n: int, seconds: float, repeats: int) -> tuple[float, float, str]:
    """(wall s per simulated s, ms per step, integrator) of a history from rest."""
    eom = equations(n)
    integ = make_integrator(IntegratorSpec(), eom, OMEGA)
    per_s = cost(eom, integ, seconds, repeats)
    dt = getattr(integ, "dt", None)
    return per_s, (1e3 * per_s * dt if dt else math.nan), integ.name


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, action="append", help="node counts (repeatable)")
    ap.add_argument("--repeats", type=int, default=5, help="timings of each (median)")
    ap.add_argument("--seconds", type=float, default=0.2, help="simulated seconds of each whole run")
    ap.add_argument("--run-max", type=int, default=400, help="largest n of the whole-run timing")
    args = ap.parse_args(argv)
    ns = args.n or [10, 25, 50, 100, 200, 400]
    print(f"{'n':>4} | {'full N (s)':>10} {'factored (s)':>12} {'ratio':>8} {'agreement':>9} {'residual':>9} | "
          f"{'run s/s':>9} {'ms/step':>8} integrator")
    per_step = {}
    for n in ns:
        r = kernel_row(n, args.repeats)
        run = run_cost(n, args.seconds, args.repeats) if n <= args.run_max else (math.nan, math.nan, "-")
        if np.isfinite(run[1]):
            per_step[n] = run[1]
        print(f"{n:4d} | {r['full']:10.3g} {r['factored']:12.3g} {r['full'] / r['factored']:8.4g} "
              f"{r['agreement']:9.1e} {r['residual']:9.1e} | {run[0]:9.4g} {run[1]:8.3g} {run[2]}", flush=True)
    if len(per_step) >= 2:
        lo, hi = min(per_step), max(per_step)
        print(f"whole run: cost per step grows as n^{math.log(per_step[hi] / per_step[lo]) / math.log(hi / lo):.2f} "
              f"from n = {lo} to {hi}")


if __name__ == "__main__":
    main()
