"""Cost of a simulated second against the number of nodes n, for a heavy cable.

The cable: a 100 m span, natural length 102.5 m, EA = 2e8 N, 10 kg/m, under its own weight
(case-file shorthand: ``length``, ``nodes``, ``mass_per_length``, ``gravity``) with a harmonic
point load at a third of the span, forced at 2 rad/s, 1 % Rayleigh damping in modes 1 and 2;
exact analysis. For each n it times, in one process after a warm-up run (numba's compilation
excluded), ``simulate(..., split=False)`` over a short stretch with

- ``rk4`` at the stable step cablesim chooses (2.0 / fastest damped root), with the damping
  product banded (O(n) per evaluation, today's kernels) and dense (the former O(n^2) product);
- the default integrator that ``make_integrator`` picks for the case.

and prints the wall time per simulated second, the step, and the banded/dense speed-up, and the
same for the default with dense damping (dense Newton solves, the former cost).

``--error``: the default's error over ``ERROR_SECONDS`` of forced response from rest, max over
the saved instants and all DOF of ``|z - z_ref|`` / ``max |z_ref|``, against ``dopri5`` at rtol
1e-10 (n <= ``--error-max``).

Usage::

    .venv/bin/python benchmarks/bench_heavy.py              # n = 10 ... 400
    .venv/bin/python benchmarks/bench_heavy.py --n 50 --n 100
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from cablesim.analyses.setup import build_equations, make_integrator, rk4_stable_step
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics.integrators import DOPRI5, RK4
from cablesim.dynamics.simulate import simulate
from cablesim.modal import fastest_rate

CASE = """\
cable: {{L: 100.0, H: 0.0, length: 102.5, nodes: {n}, EA: 2.0e8, mass_per_length: 10.0}}
loads: {{gravity: 9.81, point: [{{node: {k}, FL: [0.0, 1.0e3]}}]}}
"""
OMEGA = 2.0
ERROR_SECONDS = 6.0


def timed(eom, integrator, steps: int) -> tuple[float, float]:
    """Wall seconds per simulated second over about ``steps`` steps (best of two)."""
    dt = getattr(integrator, "dt", None) or 1e-3
    duration = steps * dt
    simulate(eom, integrator, min(duration, 5 * dt), min(duration, 5 * dt), split=False)  # warm-up
    best = np.inf
    for _ in range(2):
        t = time.perf_counter()
        h = simulate(eom, integrator, duration, duration / 4, split=False)
        best = min(best, time.perf_counter() - t)
    assert h.completed, h.message
    return best / duration, duration


def default_error(eom, default) -> float:
    """Relative error of the default scheme over ERROR_SECONDS against dopri5 at rtol 1e-10."""
    ref = simulate(eom, DOPRI5(rtol=1e-10, atol=1e-12 * eom.cable.chord_length), ERROR_SECONDS, 0.05, split=False)
    got = simulate(eom, default, ERROR_SECONDS, 0.05, split=False)
    return float(np.abs(got.z - ref.z).max() / np.abs(ref.z).max())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, action="append", help="node counts (repeatable)")
    ap.add_argument("--steps", type=int, default=2000, help="rk4 steps timed per point")
    ap.add_argument("--dense-max", type=int, default=200, help="largest n timed with dense damping")
    ap.add_argument("--error", action="store_true", help="also measure the default's error")
    ap.add_argument("--error-max", type=int, default=50, help="largest n whose error is measured")
    args = ap.parse_args(argv)
    print(f"{'n':>5} {'w_max':>9} {'rate':>10} {'rk4 dt':>9} {'banded s/s':>11} {'dense s/s':>10} "
          f"{'speed-up':>8}  {'default':>17} {'dt':>9} {'banded s/s':>10} {'dense s/s':>10} {'error':>9}")
    for n in args.n or [10, 25, 50, 100, 200, 400]:
        case = parse_case(CASE.format(n=n, k=max(1, n // 3)))
        static = run_static(case, all_models=False)
        banded = build_equations(case, static, omega=OMEGA)
        dense = dataclasses.replace(banded, C_band=None)
        rk4 = RK4(dt=rk4_stable_step(banded))
        tb, _ = timed(banded, rk4, args.steps)
        td = timed(dense, rk4, args.steps)[0] if n <= args.dense_max else np.nan
        default = make_integrator(case.integrator, banded, OMEGA)
        steps = args.steps if getattr(default, "dt", None) else 200
        tdef, _ = timed(banded, default, steps)
        tdef_dense = timed(dense, default, steps)[0] if n <= args.dense_max else np.nan
        err = default_error(banded, default) if args.error and n <= args.error_max else np.nan
        rate = fastest_rate(banded.frequencies, banded.a0, banded.a1)
        print(f"{n:5d} {banded.frequencies[-1]:9.4g} {rate:10.4g} {rk4.dt:9.3g} {tb:11.4g} {td:10.4g} "
              f"{td / tb:8.3g}  {default.name:>17} {getattr(default, 'dt', np.nan):9.3g} {tdef:10.4g} "
              f"{tdef_dense:10.4g} {err:9.2e}", flush=True)


if __name__ == "__main__":
    main()
