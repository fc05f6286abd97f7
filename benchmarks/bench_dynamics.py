"""Work-precision of the time integrators: wall time against error, side by side in one run.

Scene: the paper example (exact analysis), forced at w = 2.4 rad/s near its softening
fundamental resonance (several metres of amplitude), 1000 s, output every 0.05 s, from the
static equilibrium at rest.

Reference: the independent second-order formulation M y'' + C y' + P(y) = F(t), with P(y) from
:func:`cablesim.statics.resisting_force`, integrated by scipy's DOP853 at rtol = atol-scale
1e-12 (cached under runs/bench/ after the first run). Error: max over saved instants and DOF of
|z - z_ref|, relative to max |z_ref|.

Baseline: scipy's solve_ivp (RK45 and DOP853) on the same second-order formulation with a plain
Python right-hand side, timed in the same run.

Timing: median of several in-process runs after a warm-up (numba's compilation is excluded;
it is cached on disk after the first use anyway). Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from cablesim.analyses.static import run_static
from cablesim.case import load_case
from cablesim.dynamics.history import build_equations, simulate
from cablesim.dynamics.integrators import DOPRI5, RK4, GeneralizedAlpha, Newmark
from cablesim.statics import resisting_force

OUT = Path("runs/bench")


def second_order_rhs(eom):
    """Plain Python right-hand side of M y'' + C y' + P(y) = F0 + FL sin(w t), state (z, v)."""
    nd = eom.n_dof
    M, C, F0, FL, w, y0, cable = eom.mass, eom.C, eom.F0, eom.FL, eom.omega, eom.y0, eom.cable

    def f(t, s):
        z, v = s[:nd], s[nd:]
        a = (F0 + FL * np.sin(w * t) - C @ v - resisting_force(cable, y0 + z)) / M
        return np.concatenate([v, a])

    return f


def reference(eom, duration, t_out, tag):
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"reference-{tag}.npz"
    if path.exists():
        ref = np.load(path)
        if ref["t"].shape == t_out.shape and np.allclose(ref["t"], t_out):
            return ref["z"]
    nd = eom.n_dof
    sol = solve_ivp(second_order_rhs(eom), (0, duration), np.zeros(2 * nd), method="DOP853",
                    t_eval=t_out, rtol=1e-12, atol=1e-12)
    z = sol.y[:nd].T
    np.savez(path, t=t_out, z=z)
    return z


def timed(fn, repeats):
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1000.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer settings (for a smoke run)")
    args = ap.parse_args(argv)

    case, _ = load_case(None)
    static = run_static(case, "exact", all_models=False)
    eom = build_equations(case, static, omega=2.4)
    dt_out = 0.05
    t_out = np.arange(0, args.duration + 1e-9, dt_out)
    t0 = time.perf_counter()
    zref = reference(eom, args.duration, t_out, f"w2.4-T{args.duration:g}")
    print(f"reference ready ({time.perf_counter() - t0:.1f} s; max |z| = {np.abs(zref).max():.4g} m)")
    scale = np.abs(zref).max()

    settings = {
        "rk4": [RK4(dt=d) for d in (0.04, 0.02, 0.01, 0.005)],
        "dopri5": [DOPRI5(rtol=r, atol=r * 1e-2) for r in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)],
        "newmark": [Newmark(dt=d) for d in (0.02, 0.01, 0.005, 0.0025, 0.00125)],
        "generalized-alpha": [GeneralizedAlpha(dt=d, rho_inf=0.8) for d in (0.02, 0.01, 0.005, 0.0025, 0.00125)],
    }
    if args.quick:
        settings = {k: v[:2] for k, v in settings.items()}
    rows = []
    for name, integs in settings.items():
        for integ in integs:
            wall, h = timed(lambda: simulate(eom, integ, args.duration, dt_out, split=False), args.repeats)
            n = min(h.z.shape[0], zref.shape[0])
            err = np.abs(h.z[:n] - zref[:n]).max() / scale
            label = ", ".join(f"{k}={v:g}" for k, v in integ.settings().items() if np.isfinite(v))
            rows.append(dict(method=name, setting=label, wall_s=wall, error=err, status=h.status))
            print(f"{name:18s} {label:28s} wall {wall:8.4f} s  error {err:9.2e}  {h.status}")
    f = second_order_rhs(eom)
    nd = eom.n_dof
    for method, rtols in (("RK45", (1e-6, 1e-8)), ("DOP853", (1e-6, 1e-8, 1e-10))):
        for rtol in (rtols[:1] if args.quick else rtols):
            def run():
                return solve_ivp(f, (0, args.duration), np.zeros(2 * nd), method=method, t_eval=t_out,
                                 rtol=rtol, atol=rtol * 1e-2)
            wall, sol = timed(run, 1)
            err = np.abs(sol.y[:nd].T - zref).max() / scale
            rows.append(dict(method=f"scipy {method} (Python rhs)", setting=f"rtol={rtol:g}", wall_s=wall, error=err, status=sol.message))
            print(f"scipy {method:12s} rtol={rtol:<22g} wall {wall:8.4f} s  error {err:9.2e}")

    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "dynamics.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("\nCheapest setting of each method with error below 1e-4 (relative to max |z|):")
    for m in dict.fromkeys(r["method"] for r in rows):
        ok = [r for r in rows if r["method"] == m and r["error"] < 1e-4]
        if ok:
            best = min(ok, key=lambda r: r["wall_s"])
            print(f"  {m:28s} {best['setting']:28s} {best['wall_s']:8.4f} s  (error {best['error']:.1e})")
        else:
            print(f"  {m:28s} none of the settings tried reached 1e-4")
    _plot(rows, OUT / "dynamics-work-precision.png", args.duration)
    print(f"\nwrote {OUT / 'dynamics.csv'} and {OUT / 'dynamics-work-precision.png'}")


def _plot(rows, path, duration):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for m in dict.fromkeys(r["method"] for r in rows):
        rs = [r for r in rows if r["method"] == m]
        ax.loglog([r["error"] for r in rs], [r["wall_s"] for r in rs], "o-", label=m)
    ax.axvline(1e-4, color="0.6", ls=":", label="error 1e-4")
    ax.set_xlabel("max |z - z_ref| / max |z_ref|")
    ax.set_ylabel("wall time (s), median")
    ax.set_title(f"Work-precision: paper example, exact analysis, w = 2.4 rad/s, {duration:g} s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    main()
