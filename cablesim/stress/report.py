"""The stress report: a markdown table grouped by axis, a summary and a PNG map."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..plots.checks import plot_check_map
from .cases import (
    AGREE_SAFETY,
    AGREE_TOL_CAP,
    AGREE_TOL_FLOOR,
    AXES,
    AXIS_SHORT,
    AXIS_TITLES,
    DRIFT_TOL_EXPLICIT,
    DRIFT_TOL_IMPLICIT,
    FAILED,
    OK,
    OMEGA_FACTOR,
    SLACK_FRACTION,
    STOPPED,
)


MAP_COLUMNS = ("static", "finite", "run", "drift", "agreement", "diagnostic", "outcome")
MAP_TITLES = {
    "static": "statics",
    "finite": "no NaN/inf",
    "run": "ran to end",
    "drift": "drift eq. 15",
    "agreement": "agrees with\n2nd scheme",
    "diagnostic": "stop message\nnames cause",
    "outcome": "OUTCOME",
}


def _fmt(x: float, digits: int = 2) -> str:
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.{digits}e}"


def summary_counts(rows: list[dict]) -> dict:
    """Number of rows per outcome."""
    return {o: sum(r["outcome"] == o for r in rows) for o in (OK, STOPPED, FAILED)}


def format_table(rows: list[dict]) -> str:
    """Markdown table, one section per axis."""
    out = []
    for axis in AXES:
        sel = [r for r in rows if r["axis"] == axis]
        if not sel:
            continue
        out.append(f"### {AXIS_TITLES[axis]}\n")
        out.append("| case | analysis | integrator | outcome | drift (tol) | agreement (tol) | min T / T0 | wall s | t reached / duration s | stop message / reason |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in sel:
            msg = r["message"]
            if r["reason"]:
                msg = (msg + " **" if msg else "**") + r["reason"] + "**"
            msg = msg.replace("|", "/").replace("\n", " ")
            outcome = r["outcome"] if r["outcome"] != FAILED else "**FAILED**"
            stopped = r["checks"]["run"] == "stop"  # values up to the stop: information only
            dtol = "until stop" if stopped else f"{r['drift_tol']:.0e}"
            drift = "-" if not np.isfinite(r["drift"]) else f"{_fmt(r['drift'])} ({dtol})"
            if r["analysis"] == "approximate" and np.isfinite(r.get("drift_pos", np.nan)):
                drift = f"{_fmt(r['drift'])}, pos. {_fmt(r['drift_pos'])} ({dtol})"
            atol = "until stop" if stopped else f"{r['agree_tol']:.1e}"
            agree = "-" if not np.isfinite(r["agreement"]) else f"{_fmt(r['agreement'])} ({atol})"
            out.append(
                f"| {r['label']} | {r['analysis']} | {r['integrator']} | {outcome} | {drift} | {agree} | "
                f"{'-' if not np.isfinite(r['tmin_ratio']) else format(r['tmin_ratio'], '.3g')} | "
                f"{r['wall']:.2f} | {r['t_stop'] if np.isfinite(r['t_stop']) else 0:.6g} / {r['duration']:g} | {msg} |"
            )
        out.append("")
    return "\n".join(out)


def format_summary(rows: list[dict], wall: float | None = None) -> str:
    c = summary_counts(rows)
    text = f"{len(rows)} runs: {c[OK]} ok, {c[STOPPED]} stopped-clean, {c[FAILED]} FAILED"
    if wall is not None:
        text += f" ({wall:.0f} s wall time)"
    text += "."
    for r in rows:
        if r["outcome"] == FAILED:
            text += f"\n- FAILED: {r['label']} ({r['analysis']}, {r['integrator']}): {r['reason'] or r['message']}"
    return text


_METHOD = f"""\
## How to read this

Each row is one time history of a case built from the paper's example, varied along one axis at
a time, forced at `w = {OMEGA_FACTOR} w1` (clear of the primary, superharmonic and 1/2-subharmonic
resonances, so that two schemes can be compared meaningfully), from the static equilibrium at
rest, with Rayleigh damping `xi = 0.01` in modes 1 and 2. Checks (columns of the map):

- **statics**: the equilibrium under F0 exists; in the exact analysis `|P(y0) - F0| / |F0|` is
  within 10x what the static solver's closure tolerance allows (at least 1e-8). A
  `CablesimError` here (e.g. a slack segment) is a clean stop.
- **no NaN/inf**: every output array (`t, z, v, zc, ze, T, residual`) of the run and of its
  reference is finite.
- **drift of eq. 15**: the residual `|M y'' + C y' + P - F| / |F0|` that cablesim stores. Explicit
  schemes (third-order state): at most {DRIFT_TOL_EXPLICIT:.0e}, a spurious force of 1e-4 |F0|,
  about 0.2 % of the harmonic load (|FL| is 4-5 % of |F0| except on the slack axis); the
  residual of the third-order integration is neutral (nothing pulls it back), so this also bounds
  its accumulation. The implicit alpha-schemes satisfy eq. 15 at `t_(n+1-alpha_f)`, so at the
  saved instants the residual is their O(w h) equilibrium lag (2e-4 to 2e-3 here at 100 steps
  per period), which does not grow: at most
  {DRIFT_TOL_IMPLICIT:.0e}. In the approximate analysis the stored residual is the mismatch
  `y - x(P) - u(P)` multiplied by `K0`, which grows like EA for stiff cables; the check uses its
  position form `max |z - zc - ze| / max |z|` (the table shows both).
- **agreement with a second scheme**: relative `max |z - z_ref| / max |z_ref|` over the saved
  instants against an independent, far more accurate run of the same equations: classical RK4
  with `dt = min(0.5 x 2.8 / lambda_max, T / 400)` (T the period of interest; `lambda_max` the
  fastest rate of the damped linear system, see below) for dopri5 and the implicit schemes, and
  dopri5 with `rtol = 1e-10` for the rk4 rows. Tolerance: {AGREE_TOL_FLOOR:.0e} for dopri5
  (`rtol = 1e-8`: 1e4 times its tolerance, room for the accumulation of local errors over
  1e4-1e6 steps); for the fixed-step schemes {AGREE_SAFETY:g} x their own error measured by
  step halving (`|z_h - z_(h/2)| 2^p / (2^p - 1)`, p = 4 for rk4, 2 for newmark and
  generalized-alpha), between {AGREE_TOL_FLOOR:.0e} and {AGREE_TOL_CAP:.0e}. A completed run
  beyond its tolerance is **silently wrong**: its error is not the scheme's truncation error, or
  it is more than 5 % off.
- **stop message names cause**: a stop must say when and why (`stopped at t = ...: ...`). If the
  accurate reference of the same case runs to the end, the cause is numerical and the message
  must point at the numerics (step, tolerance, integrator); a message that blames the loads is
  misleading. If the reference stops too, the stop must be real: in the state where the run
  stopped some segment must carry less than {100 * SLACK_FRACTION:g} % of the smallest static
  tension (deformed-state tensions, and the inextensible state under the current resisting
  forces solved by the robust solver of `cablesim.statics`); otherwise the stop is spurious.

Outcome: **ok** = ran to the end within drift and agreement tolerances; **stopped-clean** = stopped
early (or refused up front with a `CablesimError`) with a clear, correct message and finite
outputs; **FAILED** = anything else (NaN, an unexpected exception, silently wrong, misleading or
spurious stop). `min T / T0` is the smallest segment tension at the saved instants relative to
the smallest static tension (how close the run came to slackness; a stop between two saved
instants is not in it).

**Explicit stability limit.** RK4 is stable for `|lambda| dt` up to about 2.8, where `lambda` runs
over the eigenvalues of the damped linear system: `lambda^2 + 2 xi_i w_i lambda + w_i^2 = 0` per
mode. With Rayleigh damping fitted to modes 1 and 2 the stiffness term overdamps the high modes
of a finely divided cable (`xi_i = a1 w_i / 2 > 1`), whose fast real root `~ a1 w_i^2` then
exceeds `omega_max` (3x at n = 50, 6.6x at n = 100), so `2.8 / omega_max` is not a safe step
there (row `rk4 0.5x limit (n=50)`).
"""


def write_report(rows: list[dict], md_path, png_path, wall: float | None = None, title: str = "Stability under stress") -> tuple[Path, Path]:
    """Write the markdown table (grouped by axis, with a summary) and the PNG map.

    Parameters
    ----------
    rows : list of dict
        From :func:`run_stress`.
    md_path, png_path : path
        Output files (folders are created); the markdown links the PNG by a relative path.
    wall : float, optional
        Total wall time of the stress run, s.

    Returns
    -------
    (Path, Path)
    """
    md_path, png_path = Path(md_path), Path(png_path)
    md_path.parent.mkdir(parents=True, exist_ok=True)
    plot_map(rows, png_path)
    rel = os.path.relpath(png_path, md_path.parent)
    text = (
        f"# {title}\n\n"
        "Generated by `cablesim stress` (`cablesim/stress/`); rerun it to refresh this page.\n\n"
        f"**Summary.** {format_summary(rows, wall)}\n\n"
        f"![stress map]({rel})\n\n"
        f"{_METHOD}\n"
        "## Runs by axis\n\n"
        f"{format_table(rows)}\n"
    )
    tmp = md_path.with_name(md_path.name + ".part")
    tmp.write_text(text)
    tmp.replace(md_path)
    return md_path, png_path


def plot_map(rows: list[dict], path) -> Path:
    """Grid of coloured cells: one row per run, one column per check and the outcome."""
    code = {"ok": 0, "stop": 1, "fail": 2, "na": 3}
    grid = np.zeros((len(rows), len(MAP_COLUMNS)), dtype=int)
    texts = [["" for _ in MAP_COLUMNS] for _ in rows]
    labels = []
    for i, r in enumerate(rows):
        for j, col in enumerate(MAP_COLUMNS):
            if col == "outcome":
                grid[i, j] = {OK: 0, STOPPED: 1, FAILED: 2}[r["outcome"]]
                texts[i][j] = r["outcome"]
            else:
                grid[i, j] = code[r["checks"][col]]
            if col == "drift" and np.isfinite(r["drift"]):
                texts[i][j] = f"{r.get('drift_pos', r['drift']):.0e}"
            elif col == "agreement" and np.isfinite(r["agreement"]):
                texts[i][j] = f"{r['agreement']:.0e}"
            elif col == "run" and r["checks"]["run"] == "stop":
                texts[i][j] = f"stop t={r['t_stop']:.3g}" if np.isfinite(r["t_stop"]) else "up front"
        labels.append(f"{AXIS_SHORT[r['axis']]:<8} | {r['label']:<28} | {r['analysis'][:6]:<6} | {r['integrator']:<28}")
    breaks = [i for i in range(1, len(rows)) if rows[i]["axis"] != rows[i - 1]["axis"]]
    c = summary_counts(rows)
    title = (
        f"cablesim stress: {len(rows)} runs, {c[OK]} ok, {c[STOPPED]} stopped-clean, {c[FAILED]} FAILED\n"
        "cells: drift = max eq.-15 residual (approximate: position form), agreement = rel. max |dz| vs reference"
    )
    legend = ("ok / passed", "stopped cleanly (clear message, finite outputs)", "FAILED", "not applicable")
    return plot_check_map(grid, texts, labels, [MAP_TITLES[c] for c in MAP_COLUMNS], breaks, title, legend, path)
