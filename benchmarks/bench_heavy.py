"""Cost of a simulated second against the number of nodes n for a heavy cable, beside scipy.

The cable: a 100 m span, natural length 102.5 m, EA = 2e8 N, 10 kg/m, under its own weight
(case-file shorthand: ``length``, ``nodes``, ``mass_per_length``, ``gravity``) with a harmonic
point load of 1 kN at a third of the span, forced at 2 rad/s, 1 % Rayleigh damping in modes 1
and 2; exact analysis, from rest at the static equilibrium.

For each n, in one process, with numba's compilation excluded by a warm-up run:

- **reference**: the second-order form ``M z'' + C z' + P(y0 + z) = F0 + FL sin(w t)`` written
  here independently of cablesim's kernels (segment geometry, ``T = EA (l - S) / S``,
  ``P_r = T_r e_r - T_{r+1} e_{r+1}``, the damping ``C = a0 M + a1 K0`` assembled here from the
  segment stiffnesses and multiplied in sparse form), compiled with numba and integrated by
  scipy's Fortran DOP853 (``scipy.integrate.ode``) at rtol ``--ref-rtol`` (default 1e-10; the
  reference is accuracy-bound there and dominates the benchmark's run time) over a window of
  ``W(n)`` simulated seconds (:func:`window`), checked against 100 times that rtol;
- **scipy**: ``solve_ivp(method="DOP853")`` with a plain Python/numpy right-hand side of the same
  form (sparse C product, ~30-80 us a call) over the same window, at rtol 1e-3 and 1e-6
  (atol 1e-3 rtol, m and m/s; above n = 200 only 1e-3): it is explicit, so its step is held by
  the fastest damped root whatever the tolerance (the two cost about the same), both errors reported;
- cablesim's **default** integrator (``make_integrator``), its **rk4** at the stable step it
  chooses and its **dopri5** at the default tolerances (rtol 1e-8), each over the same window
  for the error (rk4 and dopri5 only up to ``--error-max`` nodes: they are stability-bound too),
  and timed (median of ``--repeats`` runs) over ``--default-seconds`` simulated seconds for the
  default and ``--steps`` steps for rk4 (dopri5: as many seconds as rk4), output every 0.05 s.

Error: max over the saved instants (every W/50 s) and all DOF of ``|z - z_ref|``, relative to
``max |z_ref|``. Cost: wall seconds per simulated second.

Prints one row per n; then times the default once more for every n round-robin (``--growth-only``
does only this), so that the machine's load hits all n alike, and prints from those medians the
growth exponent of its cost from n = 50 to 400 and the scipy/default ratio at n = 200.

Usage::

    .venv/bin/python benchmarks/bench_heavy.py              # n = 10 ... 400
    .venv/bin/python benchmarks/bench_heavy.py --n 50 --n 100
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import scipy.sparse as sp
from numba import njit
from scipy.integrate import ode, solve_ivp

from cablesim.analyses.setup import build_equations, make_integrator, rk4_stable_step
from cablesim.analyses.static import run_static
from cablesim.case import IntegratorSpec, parse_case
from cablesim.dynamics.integrators import RK4
from cablesim.dynamics.simulate import simulate
from cablesim.modal import fastest_rate

CASE = """\
cable: {{L: 100.0, H: 0.0, length: 102.5, nodes: {n}, EA: 2.0e8, mass_per_length: 10.0}}
loads: {{gravity: 9.81, point: [{{node: {k}, FL: [0.0, 1.0e3]}}]}}
"""
OMEGA = 2.0
SCIPY_RTOLS = (1e-3, 1e-6)


def window(n: int) -> float:
    """Simulated seconds of the error window (and of the scipy runs): explicit schemes need
    ~n^2 steps per second here, so the window shrinks as 1/n to keep scipy at about a minute."""
    return float(min(2.0, 40.0 / n))


# ---------------------------------------------------------------------------------------------
# The second-order form, written independently of cablesim's kernels
# ---------------------------------------------------------------------------------------------
def segment_blocks(S, EA, L, H, y):
    """Unit vectors, lengths, tensions and 2x2 tangent stiffness of every segment at ``y``."""
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [L, H]])
    d = np.diff(pts, axis=0)
    length = np.hypot(d[:, 0], d[:, 1])
    e = d / length[:, None]
    T = EA * (length - S) / S
    ee = e[:, :, None] * e[:, None, :]
    ks = (EA / S)[:, None, None] * ee + (T / length)[:, None, None] * (np.eye(2) - ee)
    return e, length, T, ks


def stiffness_sparse(ks: np.ndarray) -> sp.csr_matrix:
    """The block-tridiagonal tangent stiffness assembled from the segment blocks (CSR)."""
    n = ks.shape[0] - 1
    rows, cols, vals = [], [], []
    for j in range(n + 1):  # segment j joins node j-1 to node j (-1 and n: supports)
        for a, b, sign in ((j - 1, j - 1, 1.0), (j, j, 1.0), (j - 1, j, -1.0), (j, j - 1, -1.0)):
            if 0 <= a < n and 0 <= b < n:
                for r in range(2):
                    for c in range(2):
                        rows.append(2 * a + r)
                        cols.append(2 * b + c)
                        vals.append(sign * ks[j, r, c])
    return sp.csr_matrix((vals, (rows, cols)), shape=(2 * n, 2 * n))


class SecondOrder:
    """The problem's arrays: masses, sparse damping, loads, equilibrium, segment data."""

    def __init__(self, eom):
        c = eom.cable
        self.S, self.EA, self.L, self.H = np.asarray(c.S, float), float(c.EA), float(c.L), float(c.H)
        self.m, self.F0, self.FL = np.asarray(eom.mass, float), np.asarray(eom.F0, float), np.asarray(eom.FL, float)
        self.w, self.y0, self.nd = float(eom.omega), np.asarray(eom.y0, float), eom.n_dof
        _, _, _, ks = segment_blocks(self.S, self.EA, self.L, self.H, self.y0)
        self.C = (eom.a0 * sp.diags(self.m) + eom.a1 * stiffness_sparse(ks)).tocsr()
        self.chord = math.hypot(self.L, self.H)

    def python_rhs(self):
        """Plain Python/numpy right-hand side of the state (z, v) for solve_ivp."""
        S, EA, L, H, m, F0, FL, w, y0, C, nd = (self.S, self.EA, self.L, self.H, self.m, self.F0, self.FL,
                                                 self.w, self.y0, self.C, self.nd)
        pts = np.zeros((nd // 2 + 2, 2))
        pts[-1] = (L, H)

        def f(t, s):
            z, v = s[:nd], s[nd:]
            pts[1:-1] = (y0 + z).reshape(-1, 2)
            d = pts[1:] - pts[:-1]
            length = np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2)
            Fs = (EA * (length - S) / (S * length))[:, None] * d
            P = (Fs[:-1] - Fs[1:]).ravel()
            return np.concatenate([v, (F0 + FL * np.sin(w * t) - C @ v - P) / m])

        return f

    def compiled_rhs(self):
        """The same right-hand side compiled with numba (for the reference)."""
        args = (self.S, self.EA, self.L, self.H, self.m, self.F0, self.FL, self.w, self.y0,
                self.C.indptr, self.C.indices, self.C.data)
        rhs = _nb_rhs

        @njit
        def f(t, s):
            return rhs(t, s, *args)

        return f


@njit(cache=True)
def _nb_rhs(t, s, S, EA, L, H, m, F0, FL, w, y0, ptr, idx, val):
    nd = m.size
    n = nd // 2
    out = np.empty(2 * nd)
    sw = math.sin(w * t)
    for i in range(nd):
        acc = F0[i] + FL[i] * sw
        for k in range(ptr[i], ptr[i + 1]):
            acc -= val[k] * s[nd + idx[k]]
        out[nd + i] = acc
        out[i] = s[nd + i]
    px, py = 0.0, 0.0
    for j in range(n + 1):
        qx = L if j == n else y0[2 * j] + s[2 * j]
        qy = H if j == n else y0[2 * j + 1] + s[2 * j + 1]
        dx, dy = qx - px, qy - py
        length = math.sqrt(dx * dx + dy * dy)
        f = EA * (length - S[j]) / (S[j] * length)
        if j < n:
            out[nd + 2 * j] -= f * dx
            out[nd + 2 * j + 1] -= f * dy
        if j > 0:
            out[nd + 2 * j - 2] += f * dx
            out[nd + 2 * j - 1] += f * dy
        px, py = qx, qy
    for i in range(nd):
        out[nd + i] /= m[i]
    return out


def reference(prob: SecondOrder, t_out: np.ndarray, rtol: float) -> np.ndarray:
    """scipy's Fortran DOP853 on the numba-compiled form, saved at ``t_out``."""
    r = ode(prob.compiled_rhs())
    r.set_integrator("dop853", rtol=rtol, atol=rtol * 1e-3, nsteps=10**9)
    r.set_initial_value(np.zeros(2 * prob.nd), 0.0)
    z = np.zeros((t_out.size, prob.nd))
    for i, t in enumerate(t_out[1:], 1):
        r.integrate(t)
        if not r.successful():
            raise RuntimeError(f"reference dop853 failed at t = {r.t}")
        z[i] = r.y[: prob.nd]
    return z


def rel_error(z: np.ndarray, zref: np.ndarray) -> float:
    if z.shape != zref.shape or not np.all(np.isfinite(z)):
        return math.inf
    return float(np.abs(z - zref).max() / np.abs(zref).max())


# ---------------------------------------------------------------------------------------------
# Measurements
# ---------------------------------------------------------------------------------------------
def cost(eom, integ, duration: float, repeats: int) -> float:
    """Median wall seconds per simulated second over ``duration`` (after a warm-up)."""
    simulate(eom, integ, min(duration, 0.01), min(duration, 0.01), split=False)
    walls = []
    for _ in range(repeats):
        t = time.perf_counter()
        h = simulate(eom, integ, duration, min(0.05, duration), split=False)
        walls.append(time.perf_counter() - t)
        assert h.completed, h.message
    return float(np.median(walls)) / duration


def cablesim_error(eom, integ, t_out, zref) -> float:
    h = simulate(eom, integ, t_out[-1], t_out[1] - t_out[0], split=False)
    return rel_error(h.z[: t_out.size], zref)


def scipy_run(prob: SecondOrder, t_out, zref, rtol):
    """(wall seconds per simulated second, error, right-hand-side calls) of solve_ivp DOP853."""
    f = prob.python_rhs()
    t = time.perf_counter()
    sol = solve_ivp(f, (0.0, t_out[-1]), np.zeros(2 * prob.nd), method="DOP853", t_eval=t_out,
                    rtol=rtol, atol=rtol * 1e-3)
    wall = time.perf_counter() - t
    assert sol.success, sol.message
    return wall / t_out[-1], rel_error(sol.y[: prob.nd].T, zref), sol.nfev


def measure(n: int, args) -> dict:
    case = parse_case(CASE.format(n=n, k=max(1, n // 3)))
    static = run_static(case, all_models=False)
    eom = build_equations(case, static, omega=OMEGA)
    prob = SecondOrder(eom)
    W = args.window or window(n)
    t_out = np.linspace(0.0, W, 51)
    f = prob.compiled_rhs()
    f(0.0, np.zeros(2 * prob.nd))  # compile outside the timings
    t = time.perf_counter()
    zref = reference(prob, t_out, args.ref_rtol)
    row = dict(n=n, W=W, ref_wall=time.perf_counter() - t, w_max=float(eom.frequencies[-1]),
               rate=fastest_rate(eom.frequencies, eom.a0, eom.a1))
    row["ref_check"] = rel_error(reference(prob, t_out, 100.0 * args.ref_rtol), zref)
    default = make_integrator(IntegratorSpec(), eom, OMEGA)
    rk4 = RK4(dt=rk4_stable_step(eom))
    dopri5 = make_integrator(IntegratorSpec(name="dopri5"), eom, OMEGA)
    row.update(default=default.name, default_dt=default.dt)
    row["default_err"] = cablesim_error(eom, default, t_out, zref)
    row["default_cost"] = cost(eom, default, args.default_seconds, args.repeats)
    explicit_seconds = min(args.steps * rk4.dt, W)
    row["rk4_dt"] = rk4.dt
    row["rk4_cost"] = cost(eom, rk4, explicit_seconds, args.repeats)
    row["dopri5_cost"] = cost(eom, dopri5, explicit_seconds, args.repeats)
    small = n <= args.error_max
    row["rk4_err"] = cablesim_error(eom, rk4, t_out, zref) if small else math.nan
    row["dopri5_err"] = cablesim_error(eom, dopri5, t_out, zref) if small else math.nan
    for rtol in SCIPY_RTOLS:  # above --scipy-both the tighter one is skipped: it costs the same (stability-bound)
        tight = rtol != max(SCIPY_RTOLS)
        row[f"scipy_{rtol:.0e}"] = (math.nan, math.nan, 0) if tight and n > args.scipy_both else scipy_run(
            prob, t_out, zref, rtol)
    return row


def print_row(r: dict) -> None:
    s1, s2 = (r[f"scipy_{x:.0e}"] for x in SCIPY_RTOLS)
    ratio = np.nanmin([s1[0], s2[0]]) / r["default_cost"]
    print(f"{r['n']:4d} {r['W']:5.2f} {r['w_max']:8.4g} {r['rate']:9.3g} {r['ref_check']:8.1e} | "
          f"{r['default_dt']:8.3g} {r['default_cost']:9.4g} {r['default_err']:8.1e} | "
          f"{r['rk4_dt']:8.2g} {r['rk4_cost']:9.4g} {r['rk4_err']:8.1e} | {r['dopri5_cost']:9.4g} {r['dopri5_err']:8.1e} | "
          f"{s1[0]:9.4g} {s1[1]:8.1e} {s1[2]:9d} | {s2[0]:9.4g} {s2[1]:8.1e} | {ratio:8.4g}", flush=True)


def growth(ns, seconds: float, repeats: int) -> dict:
    """The default's cost per simulated second for every n, timed round-robin (each round runs
    every n once) so that a change in the machine's load hits all n alike; medians."""
    runs = {}
    for n in ns:
        case = parse_case(CASE.format(n=n, k=max(1, n // 3)))
        eom = build_equations(case, run_static(case, all_models=False), omega=OMEGA)
        runs[n] = (eom, make_integrator(IntegratorSpec(), eom, OMEGA), [])
        cost(eom, runs[n][1], 0.01, 1)  # warm-up
    for _ in range(repeats):
        for n in ns:
            eom, integ, walls = runs[n]
            walls.append(cost(eom, integ, seconds, 1))
    return {n: float(np.median(w)) for n, (_, _, w) in runs.items()}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, action="append", help="node counts (repeatable)")
    ap.add_argument("--steps", type=int, default=4000, help="rk4 steps timed (dopri5: the same seconds)")
    ap.add_argument("--default-seconds", type=float, default=20.0, help="simulated seconds of the default's timing")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs of each cablesim scheme (median)")
    ap.add_argument("--error-max", type=int, default=200, help="largest n whose rk4 and dopri5 errors are measured")
    ap.add_argument("--growth-only", action="store_true", help="only the round-robin timing of the default")
    ap.add_argument("--scipy-both", type=int, default=200, help="largest n run by scipy at both tolerances")
    ap.add_argument("--window", type=float, help="error window, s (default: min(2, 40 / n))")
    ap.add_argument("--ref-rtol", type=float, default=1e-10,
                    help="reference tolerance (checked against 100 times it); 1e-11 costs ~25x more than 1e-9")
    args = ap.parse_args(argv)
    ns = args.n or [10, 25, 50, 100, 200, 400]
    rows = {}
    if not args.growth_only:
        print(f"{'n':>4} {'W s':>5} {'w_max':>8} {'root 1/s':>9} {'refchk':>8} | {'def. dt':>8} {'def. s/s':>9} "
              f"{'error':>8} | {'rk4 dt':>8} {'rk4 s/s':>9} {'error':>8} | {'dp5 s/s':>9} {'error':>8} | "
              f"{'DOP853-3':>9} {'error':>8} {'nfev':>9} | {'DOP853-6':>9} {'error':>8} | {'scipy/def':>8}")
        for n in ns:
            rows[n] = measure(n, args)
            print_row(rows[n])
    rounds = max(args.repeats, 5)
    g = growth(ns, args.default_seconds, rounds)
    print(f"default, round-robin over n ({rounds} rounds of {args.default_seconds:g} s, medians): "
          + ", ".join(f"n = {n}: {c:.4g} s/s" for n, c in g.items()))
    if 50 in g and 400 in g:
        print(f"default's cost from n = 50 to 400 grows as n^{math.log(g[400] / g[50]) / math.log(8.0):.2f}")
    if 200 in rows:
        best = np.nanmin([rows[200][f"scipy_{x:.0e}"][0] for x in SCIPY_RTOLS])
        print(f"n = 200: scipy DOP853 {best:.4g} s/s (cheaper of its two tolerances), default {g[200]:.4g} s/s "
              f"(round-robin): {best / g[200]:.0f}x cheaper")


if __name__ == "__main__":
    main()
