"""``cablesim continue`` bounded before it starts, orbits beyond the model's strains flagged, and
an interrupted first branch keeping the bifurcations it located.

The cases are small (one- and two-node cables, short ranges) so that each test takes seconds.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from helpers_cli import ONE_NODE, assert_refused, flat

#: A stiff cable at the lowest frequencies: a forcing period of 3e4 to 6e4 s, integrated at the
#: step of a 2000 rad/s axial mode, takes 5e7 to 9e7 steps per orbit.
SLOW = ["--set", "continuation.omega={start: 1.0e-4, stop: 2.0e-4}", "--set", "cable.EA=1.0e9"]


# ----------------------------------------------------------------------------------------------
# 1. The cost of a continuation, before it starts
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("omega", [2.0, 0.05])
def test_the_budget_counts_the_steps_the_kernel_takes(omega):
    """The budget's steps per orbit are those the shooting kernel counts when it integrates one."""
    import cablesim
    from cablesim.analyses.continuation import prepare_continuation
    from cablesim.orbits.budget import orbit_budget
    from cablesim.orbits.shooting import Shooting
    from cablesim.orbits.starting import linear_response_state
    from cablesim.orbits.systems import cable_system

    case = cablesim.load_case(None, overrides=[f"continuation.omega={{start: {omega}, stop: 6.0}}",
                                               "continuation.segments=2"])
    start = prepare_continuation(case)
    budget = orbit_budget(start.eom, "omega", omega, 6.0, period=1, segments=2)
    sh = Shooting(cable_system(start.eom), period=1, segments=2)
    u = sh.spread(linear_response_state(start.eom, omega, 1.0, 1.0), omega)
    before = sh.steps_taken
    sh.evaluate(u, omega)
    assert budget.steps[0] == sh.steps_taken - before
    assert not budget.matrix_free and budget.states == 8


def test_the_memory_of_the_variational_state_grows_as_the_square_of_the_states():
    import cablesim
    from cablesim.analyses.continuation import prepare_continuation
    from cablesim.orbits.budget import orbit_budget

    working = {}
    for nodes in (2, 4):
        case = cablesim.load_case(None, overrides=[
            f"cable={{L: 300.0, H: 20.0, length: 340.0, nodes: {nodes}, EA: 1.0e9, mass_per_length: 70.0}}",
            f"loads={{gravity: 9.81, FL: {[0.0, 1.0e4] * nodes}}}"])
        start = prepare_continuation(case)
        working[nodes] = orbit_budget(start.eom, "omega", 0.5, 6.0, matrix_free=False).working
    assert 3.0 < working[4] / working[2] < 4.5  # (2 n_dof)^2 blocks: 16 against 8 states


def test_continue_above_the_limits_is_refused_before_any_orbit(invoke_cli, write_case, tmp_path, monkeypatch):
    import cablesim.analyses.estimates as est
    import cablesim.api

    def computed(*a, **k):
        raise AssertionError("an orbit was computed before the refusal")

    monkeypatch.setattr(est, "trace", computed)  # not even the probe
    monkeypatch.setattr(cablesim.api, "run_continuation", computed)
    case = write_case(ONE_NODE)
    msg = assert_refused(invoke_cli("continue", case, "-o", "c.h5", *SLOW), tmp_path, "Runge-Kutta steps",
                         "more than the 1e+08 allowed", "shorter range", "continuation.max_points", "cable.nodes",
                         "--force", keep=(case,))
    assert "at least" in msg  # the least the range can take, not a guess


def test_force_runs_a_continuation_above_the_limits(invoke_cli, write_case, tmp_path, monkeypatch):
    import cablesim.api
    from cablesim.errors import CablesimError

    def started(*a, **k):
        raise CablesimError("the continuation was started")

    monkeypatch.setattr(cablesim.api, "run_continuation", started)
    case = write_case(ONE_NODE)
    res = invoke_cli("continue", case, "-o", "c.h5", *SLOW, "--force")
    assert res.returncode == 2 and "the continuation was started" in res.stderr, res.stderr
    assert "estimate: continuation: at least" in flat(res.stderr)  # a long run's estimate, printed


def test_check_gives_the_same_refusal(invoke_cli, write_case):
    case = write_case(ONE_NODE)
    res = invoke_cli("check", case, *SLOW)
    assert res.returncode == 0, res.stderr
    line = flat(next(x for x in res.stdout.split("\n#") if x.strip().startswith("continue:")))
    assert "needs --force" in line and "more than the 1e+08 allowed" in line


def test_the_estimate_is_printed_and_near_the_run(invoke_cli, write_case, tmp_path):
    case = write_case(ONE_NODE)
    res = invoke_cli("--verbose", "continue", case, "-o", "c.h5", "--no-plot")
    assert res.returncode == 0, res.stderr
    line = next(x for x in res.stderr.splitlines() if x.startswith("estimate: continuation:"))
    expected = float(line.split("about ")[1].split()[0])
    with h5py.File(tmp_path / "c.h5") as f:
        orbits = f["continuation/branches/b0-p1/omega"].size
    assert orbits / 2 <= expected <= 2 * orbits, (line, orbits)
    assert "on this machine" in line


# ----------------------------------------------------------------------------------------------
# 2. Orbits beyond the model's strains
# ----------------------------------------------------------------------------------------------
def _phase_zero_strain(case_text: str, state: np.ndarray) -> float:
    """The largest (l - S) / S of the orbit's configuration at forcing phase 0, from the node
    positions of the static equilibrium and the stored displacements (written here)."""
    import yaml

    import cablesim

    case = cablesim.load_case(yaml.safe_load(case_text))
    y = cablesim.static(case).result.exact.y + state[: 2 * case.cable.n_nodes]
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [case.cable.L, case.cable.H]])
    lengths = np.hypot(*np.diff(pts, axis=0).T)
    return float(np.max(lengths / np.asarray(case.cable.S) - 1.0))


def test_orbits_strained_beyond_the_model_are_warned_and_flagged(invoke_cli, write_case, tmp_path):
    absurd = ONE_NODE.replace("EA: 1.0e6", "EA: 1.0e5").replace("F0: [0.0, 2000.0], FL: [0.0, 100.0]",
                                                                 "F0: [0.0, 1.0e4], FL: [0.0, 4.0e3]")
    case = write_case(absurd)
    res = invoke_cli("continue", case, "-o", "c.h5", "--no-plot")
    assert res.returncode == 0, res.stderr
    err = flat(res.stderr)
    assert "orbits (on b0-p1) goes beyond the 5 % of the model's small strains" in err, err
    with h5py.File(tmp_path / "c.h5") as f:
        b = f["continuation/branches/b0-p1"]
        strain, strained, state = b["strain"][()], b["strained"][()], b["state"][()]
        stored = json.loads(f["continuation"].attrs["warnings"])
    assert any("small strains" in w and "orbit" in w for w in stored)
    assert np.array_equal(strained, strain > 0.05) and strained.any()
    for k in (0, strain.size - 1):  # the largest over the orbit is at least that at phase 0
        assert strain[k] >= _phase_zero_strain(absurd, state[k]) - 1e-12


def test_orbits_within_the_model_are_not_flagged(invoke_cli, write_case, tmp_path):
    case = write_case(ONE_NODE)
    res = invoke_cli("continue", case, "-o", "c.h5", "--no-plot")
    assert res.returncode == 0 and "strain" not in res.stderr, res.stderr
    with h5py.File(tmp_path / "c.h5") as f:
        b = f["continuation/branches/b0-p1"]
        strain, strained, state = b["strain"][()], b["strained"][()], b["state"][()]
    assert not strained.any() and np.all(np.isfinite(strain))
    assert strain[0] >= _phase_zero_strain(ONE_NODE, state[0]) - 1e-12
    assert strain[0] < 0.05


# ----------------------------------------------------------------------------------------------
# 3. An interrupted first branch keeps its bifurcations
# ----------------------------------------------------------------------------------------------
#: The paper example around its period doublings near 2 w1: the first branch locates the one at
#: 5.0212 rad/s after a dozen orbits and the other at 5.0744 rad/s later.
DOUBLING = ["--set", "continuation.omega={start: 4.9, stop: 5.2}"]


def _signal_after_first_bifurcation(monkeypatch, signum: int, later: int = 2) -> list:
    import cablesim.cli_charts

    seen: list = []

    def status(line):
        def progress(p):
            seen.append(p)
            special = [q for q in seen if q.special is not None]
            if special and len(seen) == seen.index(special[0]) + 1 + later:
                os.kill(os.getpid(), signum)
        return progress

    monkeypatch.setattr(cablesim.cli_charts, "branch_status", status)
    return seen


def _kept(path: Path) -> tuple[list, list, list]:
    with h5py.File(path) as f:
        g = f["continuation"]
        assert not g.attrs["complete"]
        kinds = [k.decode() for k in g["bifurcations/kind"][()]]
        where = list(g["bifurcations/parameter"][()])
        orbits = list(g["branches/b0-p1/parameter"][()])
    return kinds, where, orbits


@pytest.mark.parametrize("signum, code, name", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")])
def test_an_interrupted_first_branch_keeps_its_located_bifurcations(invoke_cli, tmp_path, monkeypatch, signum, code,
                                                                     name):
    seen = _signal_after_first_bifurcation(monkeypatch, signum)
    res = invoke_cli("continue", *DOUBLING, "-o", "c.h5", "--no-plot")
    assert res.returncode == code, (res.stderr, res.exception)
    kinds, where, orbits = _kept(tmp_path / "c.h5")
    located = [p for p in seen if p.special is not None]
    assert kinds == ["period-doubling"] and len(located) == 1
    assert where[0] == pytest.approx(located[0].parameter, abs=0) and where[0] in orbits
    assert 5.0 < where[0] < 5.05 and len(orbits) == len(seen)
    msg = flat(res.stderr)
    assert name in msg and f"the {len(seen)} periodic orbits" in msg and "the 1 bifurcation located" in msg


def test_sigterm_to_a_continue_process_keeps_the_bifurcations(tmp_path):
    """A real process: the signal comes from the operating system and the exit status is the
    process's own."""
    script = f"""
import os, signal, sys
import cablesim.cli_charts
seen = []
def status(line):
    def progress(p):
        seen.append(p)
        if p.special is not None:
            os.kill(os.getpid(), signal.SIGTERM)
    return progress
cablesim.cli_charts.branch_status = status
from cablesim.cli import app
sys.argv = ["cablesim", "continue", *{DOUBLING!r}, "-o", "c.h5", "--no-plot"]
app()
"""
    res = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert res.returncode == 143, res.stderr
    assert "Traceback" not in res.stderr and "the 1 bifurcation located" in flat(res.stderr)
    kinds, where, orbits = _kept(tmp_path / "c.h5")
    assert kinds == ["period-doubling"] and where[0] == orbits[-1]


def test_the_estimate_of_a_continuation_with_loci_says_what_each_curve_adds():
    """The bifurcation curves are traced after the branches, from the bifurcations found: their
    number is not known before the run, so the estimate says what each one may add."""
    from cablesim import api

    case = api.load_case(Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml", overrides=[
        "continuation={omega: {start: 4.9, stop: 5.2}, loci: true, gamma: {start: 0.8, stop: 1.0}}"])
    text = api.continuation_cost(case).text()
    assert f"each bifurcation curve adds up to {2 * case.continuation.max_points} points" in text, text
    plain = api.load_case(Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml", overrides=[
        "continuation={omega: {start: 4.9, stop: 5.2}}"])
    assert "bifurcation curve" not in api.continuation_cost(plain).text()
