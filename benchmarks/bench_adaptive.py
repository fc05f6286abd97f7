"""Error-controlled implicit steps against today's fixed steps, and every integrator's default.

Part 1, the scenes (exact analysis, from rest at the static equilibrium):

- ``paper``: the paper example at 2.4 rad/s, 120 s;
- ``slack-10``: its harmonic loads x 10 at 2.45 rad/s, 60 s (16 slack transitions, 14-20 s);
- ``slack-15``: its harmonic loads x 15 at 5 rad/s, 60 s (only with ``--scene``);
- ``heavy-200``: bench_heavy's cable (100 m span, EA = 2e8 N, 10 kg/m, 1 kN at a third of the
  span, 2 rad/s) with 200 nodes, 1 s (its explicit reference is held by stability to ~3e-6 s
  steps).

For each, ``newmark`` and ``generalized-alpha`` at their fixed step of today (100 steps per period
of interest as named schemes; 1600 for generalized-alpha as the default of a stiff cable) and
error-controlled at their default tolerance (and at 10 times it, to show that the error follows
the tolerance). Errors against an independent reference written without cablesim's dynamics:
scipy's DOP853 on the second-order form with the geometry, tension-only segments and, through
slack, scipy's event location of the tests (``tests/helpers_dynamics.py``, ``tests/test_slack.py``);
for the heavy cable bench_heavy's compiled DOP853 reference. ``z``: max |z - z_ref| over the
saved instants and DOF over max |z_ref|; ``T``: the same for the segment tensions (from z by the
reference's geometry) over the peak tension; ``snap``: the largest error in a segment's peak
tension at the saved instants, over the peak; ``events``: slack transitions found / in the
reference. Cost: median wall and CPU seconds of ``--repeats`` runs, the schemes timed in turn
(round robin) so that the machine's load hits them alike; the ratio is adaptive over fixed.

Part 2 (``--defaults``): every integrator at its defaults (``cablesim history CASE --integrator
NAME``) on the shipped examples with a history section and on the paper example at 2.4 rad/s,
against dopri5 at rtol 1e-12 (and dopri5 itself against rk4 at a twentieth of its default step,
or its stable step), or, for a stiff planar case (one whose default scheme is generalized-alpha),
against scipy's Radau at rtol :data:`STIFF_RTOL` on the second-order form written in the tests
(``tests/helpers_dynamics.py``): the errors in z and T relative to the peaks.

Usage::

    .venv/bin/python benchmarks/bench_adaptive.py             # part 1
    .venv/bin/python benchmarks/bench_adaptive.py --defaults  # part 2
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the test suite's independent references
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_heavy import CASE as HEAVY_CASE  # noqa: E402
from bench_heavy import SecondOrder, reference  # noqa: E402
from helpers_dynamics import reference_history, stiff_reference  # noqa: E402
from test_slack import slack_reference  # noqa: E402

from cablesim.analyses.dynamic import plan_history  # noqa: E402
from cablesim.analyses.setup import build_equations, frequency_of_interest  # noqa: E402
from cablesim.analyses.static import run_static  # noqa: E402
from cablesim.case import load_case, parse_case  # noqa: E402
from cablesim.dynamics.integrators import DOPRI5, RK4  # noqa: E402
from cablesim.dynamics.integrators.settings import default_scheme, make, rk4_default_step, rk4_stable_step  # noqa: E402
from cablesim.dynamics.simulate import simulate  # noqa: E402

PAPER = ROOT / "configs" / "paper-example.yaml"
SCENES = {  # name: (case text, omega, load scale, duration)
    "paper": (PAPER.read_text(), 2.4, 1.0, 120.0),
    "slack-10": (PAPER.read_text(), 2.45, 10.0, 60.0),
    "slack-15": (PAPER.read_text(), 5.0, 15.0, 60.0),
    "heavy-200": (HEAVY_CASE.format(n=200, k=66), 2.0, 1.0, 1.0),
}
#: The examples of part 2: the paper's at 2.4 rad/s, and the shipped ones at their history section.
EXAMPLES = ("paper", "heavy-span", "spatial-span", "stay-anchorage", "stay-parametric")
#: The scenes run by default (``make bench``); ``--scene`` picks others.
DEFAULT_SCENES = ("paper", "slack-10", "heavy-200")


def own_tensions(eom, z):
    """Segment tensions ``EA max(l - S, 0) / S`` at every saved instant, from the geometry."""
    c = eom.cable
    m = z.shape[0]
    pts = np.zeros((m, c.n_nodes + 2, 2))
    pts[:, 1:-1] = (eom.y0 + z).reshape(m, -1, 2)
    pts[:, -1] = (c.L, c.H)
    d = np.diff(pts, axis=1)
    length = np.hypot(d[..., 0], d[..., 1])
    return c.EA * np.maximum(length - c.S, 0.0) / c.S


def scene(name):
    text, w, g, dur = SCENES[name]
    case = parse_case(text)
    eom = build_equations(case, run_static(case, all_models=False), omega=w, load_scale=g)
    w_int = frequency_of_interest(eom, w)
    out = 2.0 * np.pi / w_int / 40.0
    out = dur / math.ceil(dur / out)
    return eom, w_int, dur, out


def independent_reference(name, eom, dur, out):
    """(z, T, number of slack transitions) of the independent reference at the saved instants."""
    t = np.arange(0, round(dur / out) + 1) * out
    if name.startswith("heavy"):
        z = reference(SecondOrder(eom), t, 1e-11)
        events = 0
    elif name.startswith("slack"):
        z, ev = slack_reference(eom, t)
        events = len(ev)
    else:
        z, _ = reference_history(eom, t)
        events = 0
    return z, own_tensions(eom, z), events


def errors(eom, hist, zref, Tref):
    m = min(hist.z.shape[0], zref.shape[0])
    if m < zref.shape[0] or not np.all(np.isfinite(hist.z)):
        return math.inf, math.inf, math.inf
    T = own_tensions(eom, hist.z[:m])
    ez = np.abs(hist.z[:m] - zref[:m]).max() / np.abs(zref).max()
    eT = np.abs(T - Tref[:m]).max() / Tref.max()
    snap = np.abs(T.max(axis=0) - Tref[:m].max(axis=0)).max() / Tref.max()
    return float(ez), float(eT), float(snap)


def runs_of(eom, w_int, stiff_fixed):
    """(label, integrator) of the runs of a scene: today's fixed steps, then error control."""
    period = 2.0 * np.pi / w_int
    runs = [("newmark fixed 100/period", make("newmark", eom, w_int, {"dt": period / 100})),
            ("g-alpha fixed 100/period", make("generalized-alpha", eom, w_int, {"dt": period / 100}))]
    if stiff_fixed:
        runs.append(("g-alpha fixed 1600/period", make("generalized-alpha", eom, w_int, {"dt": period / 1600})))
    for name, short in (("newmark", "newmark"), ("generalized-alpha", "g-alpha")):
        default = make(name, eom, w_int)
        runs.append((f"{short} rtol {default.rtol:g} (default)", default))
        runs.append((f"{short} rtol {10 * default.rtol:g}", make(name, eom, w_int, {"rtol": 10 * default.rtol})))
    return runs


def timed(eom, integ, dur, out):
    w0, c0 = time.perf_counter(), time.process_time()
    h = simulate(eom, integ, dur, out, split=False)
    return h, time.perf_counter() - w0, time.process_time() - c0


def part1(names, repeats):
    print("scene      | run                          |    z err |    T err |  snap err | events  |  wall s |   CPU s "
          "| wall/fixed")
    for name in names:
        eom, w_int, dur, out = scene(name)
        t0 = time.perf_counter()
        zref, Tref, n_ref = independent_reference(name, eom, dur, out)
        print(f"# {name}: reference {time.perf_counter() - t0:.0f} s, {n_ref} slack transitions", flush=True)
        runs = runs_of(eom, w_int, name.startswith("heavy"))
        for _, integ in runs:  # warm-up: compile once
            simulate(eom, integ, min(dur, 0.5), min(out, 0.5), split=False)
        walls = {lab: [] for lab, _ in runs}
        cpus = {lab: [] for lab, _ in runs}
        hists = {}
        for _ in range(repeats):
            for lab, integ in runs:
                h, w, c = timed(eom, integ, dur, out)
                walls[lab].append(w)
                cpus[lab].append(c)
                hists[lab] = h
        base = {"newmark": float(np.median(walls[runs[0][0]])), "g-alpha": float(np.median(walls[runs[1][0]]))}
        if name.startswith("heavy"):
            base["g-alpha"] = float(np.median(walls["g-alpha fixed 1600/period"]))
        for lab, _ in runs:
            h = hists[lab]
            ez, eT, snap = errors(eom, h, zref, Tref)
            n_ev = len(h.slack.t) if h.slack is not None else 0
            wall, cpu = float(np.median(walls[lab])), float(np.median(cpus[lab]))
            print(f"{name:10s} | {lab:28s} | {ez:8.2e} | {eT:8.2e} | {snap:9.2e} | {n_ev:3d}/{n_ref:<3d} | {wall:7.3f} "
                  f"| {cpu:7.3f} | {wall / base[lab.split()[0]]:6.2f}", flush=True)


#: Relative tolerance of the stiff cases' reference (scipy Radau on the second-order form with the
#: tests' own geometry and tangent; the 100-node heavy span: 676 s of CPU, against hours for an
#: explicit reference held to its stable step).
STIFF_RTOL = 1e-9


class _Reference:
    """z and T at the saved instants, as a history has them (``z``, ``T``)."""

    def __init__(self, eom, z):
        self.z, self.T = z, own_tensions(eom, z)


def stiff_run(eom, dur, out):
    t = np.arange(0, round(dur / out) + 1) * out
    return _Reference(eom, stiff_reference(eom, t, rtol=STIFF_RTOL))


def part2(examples):
    """Every integrator as ``cablesim history CASE --integrator NAME`` runs it (the case's
    disturbance included: a history plan), against the references from the same start."""
    cases = [("paper-example (2.4 rad/s, 600 s)", load_case(PAPER)[0], 2.4, 600.0)] if "paper" in examples else []
    for f in (e for e in examples if e != "paper"):
        case = load_case(ROOT / "configs" / f"{f}.yaml")[0]
        cases.append((f"{f} ({case.history.omega} rad/s, {case.history.duration:g} s)", case, case.history.omega,
                      case.history.duration))
    print("example                            | integrator         | settings                        |    z err |    T err | wall s")
    for label, case, w, dur in cases:
        try:
            base = plan_history(case, omega=w, duration=dur)
        except Exception as exc:  # noqa: BLE001 - stated, not hidden
            print(f"{label:34s} | cannot run: {exc}")
            continue
        eom, w_int, out, s0 = base.eom, base.omega_interest, base.output_step, base.s0
        if default_scheme(eom, w_int) != "dopri5" and eom.cable.dim == 2 and s0 is None:
            # explicit references are held to the stable step (the tests' Radau one is planar, from rest)
            ref = ref_rk = stiff_run(eom, dur, out)
            zs, Ts = np.abs(ref.z).max(), np.abs(ref.T).max()
            print(f"{label:34s} | reference          | scipy Radau, rtol {STIFF_RTOL:g}        |          |          |",
                  flush=True)
        else:
            ref = simulate(eom, DOPRI5(rtol=1e-12, atol=1e-14 * eom.cable.chord_length), dur, out, s0=s0, split=False)
            rk_dt = min(rk4_default_step(eom, w_int) / 20.0, rk4_stable_step(eom))
            ref_rk = simulate(eom, RK4(dt=(2 * np.pi / w) / math.ceil((2 * np.pi / w) / rk_dt)), dur, out, s0=s0,
                              split=False)
            zs, Ts = np.abs(ref.z).max(), np.abs(ref.T).max()
            print(f"{label:34s} | references         | dopri5 1e-12 vs rk4 dt {ref_rk.settings['integrator_dt']:.2g}  | "
                  f"{np.abs(ref.z - ref_rk.z).max() / zs:8.2e} | {np.abs(ref.T - ref_rk.T).max() / Ts:8.2e} |", flush=True)
        for name in (None, "rk4", "dopri5", "newmark", "generalized-alpha"):
            plan = plan_history(case, omega=w, duration=dur, integrator=name)
            integ = plan.integrator
            w0, c0 = time.perf_counter(), time.process_time()
            h = simulate(plan.eom, integ, dur, plan.output_step, s0=plan.s0, split=False)
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            r = ref_rk if integ.name == "dopri5" else ref
            ez = np.abs(h.z - r.z).max() / zs if h.z.shape == r.z.shape else math.inf
            eT = np.abs(h.T - r.T).max() / Ts if h.T.shape == r.T.shape else math.inf
            sets = ", ".join(f"{k} {v:.3g}" for k, v in integ.settings().items() if k in ("dt", "rtol", "rho_inf"))
            who = f"{integ.name}{' (default)' if name is None else ''}"
            print(f"{label:34s} | {who:18s} | {sets:31s} | {ez:8.2e} | {eT:8.2e} | {wall:6.1f} | CPU {cpu:6.1f}",
                  flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", action="append", choices=sorted(SCENES), help="scenes of part 1 (default: all)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--defaults", action="store_true", help="part 2: every integrator's default on the examples")
    ap.add_argument("--example", action="append", choices=EXAMPLES, help="examples of part 2 (default: all)")
    args = ap.parse_args(argv)
    if args.defaults:
        part2(args.example or list(EXAMPLES))
    else:
        part1(args.scene or list(DEFAULT_SCENES), args.repeats)


if __name__ == "__main__":
    main()
