"""Where the planar response leaves its plane, and what it becomes: the figure and the numbers of
the chapter "Out of the plane" of docs/paper-reproduction.md.

Two cases, each made spatial so that the cable is free to leave its plane:

- the paper's example cable (configs/paper-example.yaml) under its harmonic load, continued in
  omega over 5.3-5.7 rad/s: an out-of-plane period doubling pair on the planar branch, and the
  nonplanar period-2 branch born there;
- a stay (100 m chord, 80 kg/m, 3 nodes, under gravity) whose anchorage moves 2 mm along the
  chord, continued in omega across twice its first (out-of-plane) frequency: the parametric tongue.

Each prediction is then checked by a long time history (dopri5, rtol 1e-10) started from the
planar periodic orbit at a frequency inside the unstable band with 1 mm out of the plane: the
state after an even number of forcing periods is compared with the nonplanar period-2 orbit
(or the orbit one forcing period on, or their mirror images w -> -w), and the largest |w| over
the last two periods (4000 samples a period) with the orbit's.

Usage::

    .venv/bin/python benchmarks/out_of_plane.py [-o docs/out-of-plane.png] [--json docs/out-of-plane.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from cablesim.analyses.continuation import run_continuation  # noqa: E402
from cablesim.analyses.setup import build_equations  # noqa: E402
from cablesim.analyses.static import run_static  # noqa: E402
from cablesim.case import case_from_dict  # noqa: E402
from cablesim.dynamics.integrators import DOPRI5  # noqa: E402
from cablesim.dynamics.simulate import simulate  # noqa: E402
from cablesim.orbits import Shooting, cable_system, solve_orbit  # noqa: E402
from cablesim.plots.continuation import stability_runs  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def paper_case() -> dict:
    data = yaml.safe_load((REPO / "configs" / "paper-example.yaml").read_text())
    for key in ("history", "free_vibration", "sweep"):
        data.pop(key, None)
    data.update(spatial=True, name="paper-example-spatial")
    data["continuation"] = {"omega": {"start": 5.3, "stop": 5.7}, "channels": ["node1.v", "node1.w"]}
    return data


STAY = {
    "name": "stay-tongue",
    "spatial": True,
    "cable": {"L": 80.0, "H": -60.0, "length": 99.85, "nodes": 3, "EA": 2.0e9, "mass_per_length": 80.0},
    "loads": {"gravity": 9.81},
    "supports": {"A": {"amplitude": [0.0016, -0.0012, 0.0]}},  # 2 mm along the chord (0.8, -0.6)
    "damping": {"ratio": 0.002, "modes": [1, 2]},
    "continuation": {"omega": {"start": 11.7, "stop": 12.3}, "channels": ["node2.v", "node2.w"], "max_period": 2},
}


def nonplanar_child(result, pd):
    """The nonplanar period-2 branch switched onto at the out-of-plane period doubling ``pd``."""
    for b in result.branches:
        if b.period == 2 and not b.planar and b.parent is not None and np.isclose(b.omega[0], pd.omega, atol=1e-6):
            return b
    raise RuntimeError(f"no nonplanar period-2 branch starts at {pd.omega:.6g} rad/s")


def confirm_by_history(case_data: dict, planar_branch, child, omega: float, periods: int, node: int) -> dict:
    """Integrate from the planar orbit at ``omega`` disturbed by 1 mm in w at ``node`` (1-based)
    and compare the settled motion with the nonplanar period-2 orbit there."""
    case = case_from_dict(case_data)
    eom = build_equations(case, run_static(case), omega=omega)
    T = 2 * np.pi / omega
    nd = eom.n_dof
    near = int(np.argmin(np.abs(planar_branch.omega - omega)))
    planar = solve_orbit(Shooting(cable_system(eom)), planar_branch.state[near], omega)
    ok = [k for k in range(child.omega.size) if child.stable[k]]
    k2 = min(ok, key=lambda k: abs(child.omega[k] - omega))
    orbit = solve_orbit(Shooting(cable_system(eom), period=2), child.state[k2], omega)
    assert planar.converged and orbit.converged
    integ = DOPRI5(rtol=1e-10, atol=1e-13)
    z0, v0 = planar.u[:nd].copy(), planar.u[nd:].copy()
    w_index = 3 * (node - 1) + 2
    z0[w_index] += 1e-3
    t0 = time.process_time()
    run = simulate(eom, integ, periods * T, T / 50, s0=eom.initial_state(z0, v0), split=False)
    cpu = time.process_time() - t0
    one = simulate(eom, integ, T, T / 50, s0=eom.initial_state(orbit.u[:nd], orbit.u[nd:]), split=False)
    x1 = np.concatenate([one.z[-1], one.v[-1]])
    flip = np.tile([1.0, 1.0, -1.0], 2 * nd // 3)
    end = np.concatenate([run.z[-1], run.v[-1]])
    size = float(np.abs(orbit.u).max())
    state_error = min(float(np.abs(end - c).max()) for c in (orbit.u, x1, flip * orbit.u, flip * x1)) / size
    fine = [simulate(eom, integ, 2 * T, T / 4000, s0=eom.initial_state(u[:nd], u[nd:]), split=False)
            for u in (end, orbit.u)]
    w_hist, w_orbit = (float(np.abs(h.z[:, w_index]).max()) for h in fine)
    return {
        "omega": omega, "periods": periods, "cpu_s": cpu,
        "planar_out_of_plane_multiplier": float(np.abs(planar.evaluation.multipliers).max()),
        "orbit_largest_multiplier": float(np.abs(orbit.evaluation.multipliers).max()),
        "state_error": state_error, "max_w_history": w_hist, "max_w_orbit": w_orbit,
        "max_w_error": abs(w_hist / w_orbit - 1),
        "t": run.t, "w": run.z[:, w_index],
    }


def study(case_data: dict, node: int, omega: float, periods: int) -> dict:
    t0 = time.process_time()
    result = run_continuation(case_from_dict(case_data))
    cpu = time.process_time() - t0
    pds = sorted((b for b in result.bifurcations if b.kind == "period-doubling" and b.plane == "out-of-plane"),
                 key=lambda b: b.omega)
    child = nonplanar_child(result, pds[0])
    planar = next(b for b in result.branches if b.period == 1)
    check = confirm_by_history(case_data, planar, child, omega, periods, node)
    return {"result": result, "cpu_s": cpu, "doublings": [b.omega for b in pds],
            "folds": [b.omega for b in result.bifurcations if b.kind == "fold" and b.period == 2],
            "check": check}


def draw_response(ax, result, channel: int, title: str, ylabel: str, mm: bool):
    k = 1e3 if mm else 1.0
    for b in result.branches:
        style = dict(color="0.2") if b.planar or b.period == 1 else dict(color="tab:red")
        label = "planar" if b.period == 1 else ("nonplanar period 2" if not b.planar else "planar period 2")
        a = b.amplitude[:, channel] * k
        # runs joined at the change of stability (no gap where the line changes style)
        for mask, ls, lw, what in ((b.stable, "-", 1.6, "stable"), (~b.stable, "--", 1.0, "unstable")):
            for lo, hi in stability_runs(mask):
                ax.plot(b.omega[lo:hi], a[lo:hi], ls, lw=lw, label=f"{label}, {what}", **style)
    for bif in result.bifurcations:
        if bif.kind == "period-doubling" and bif.plane == "out-of-plane":
            ax.axvline(bif.omega, color="tab:blue", lw=0.6, ls=":")
    handles, labels = ax.get_legend_handles_labels()
    seen = dict(zip(labels, handles))
    ax.legend(seen.values(), seen.keys(), fontsize=7, loc="upper left")
    ax.set(title=title, xlabel="forcing frequency ω (rad/s)", ylabel=ylabel)
    ax.grid(alpha=0.3)


def draw_history(ax, check: dict, title: str, mm: bool):
    k = 1e3 if mm else 1.0
    ax.plot(check["t"], check["w"] * k, lw=0.3, color="0.3", label="time history, from the planar orbit + 1 mm")
    ax.axhline(check["max_w_orbit"] * k, color="tab:red", lw=1.0, ls="--", label="nonplanar orbit: largest |w|")
    ax.axhline(-check["max_w_orbit"] * k, color="tab:red", lw=1.0, ls="--")
    ax.set(title=title, xlabel="time t (s)", ylabel="out-of-plane displacement w (mm)" if mm else "w (m)")
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(alpha=0.3)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=str(REPO / "docs" / "out-of-plane.png"))
    ap.add_argument("--json", default=str(REPO / "docs" / "out-of-plane.json"))
    args = ap.parse_args()
    paper = study(paper_case(), node=1, omega=5.5, periods=2600)
    stay = study(STAY, node=2, omega=11.94, periods=6000)
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5), constrained_layout=True)
    draw_response(axes[0, 0], paper["result"], 1, "Paper's cable, spatial: out-of-plane response of node 1",
                  "largest |w| of node 1 (m)", mm=False)
    draw_history(axes[0, 1], paper["check"], f"Paper's cable at ω = {paper['check']['omega']} rad/s", mm=False)
    draw_response(axes[1, 0], stay["result"], 1, "Stay, anchorage moving 2 mm along the chord: node 2",
                  "largest |w| of node 2 (mm)", mm=True)
    draw_history(axes[1, 1], stay["check"], f"Stay at ω = {stay['check']['omega']} rad/s", mm=True)
    fig.suptitle("Out of the plane: out-of-plane period doublings (dotted) and the nonplanar period-2 "
                 "branches born there, confirmed by time histories", fontsize=11)
    fig.savefig(args.output, dpi=110)
    numbers = {}
    for name, s in (("paper", paper), ("stay", stay)):
        numbers[name] = {"continuation_cpu_s": s["cpu_s"], "out_of_plane_doublings_rad_s": s["doublings"],
                         "period_2_folds_rad_s": s["folds"],
                         **{k: v for k, v in s["check"].items() if k not in ("t", "w")}}
    Path(args.json).write_text(json.dumps(numbers, indent=2) + "\n")
    print(json.dumps(numbers, indent=2))
    print(f"wrote {args.output} and {args.json}")


if __name__ == "__main__":
    main()
