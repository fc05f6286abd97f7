"""Every run bounded and interruptible: cost estimates before long runs (refused above the limits
unless --force), compiled loops that return to Python often, SIGTERM handled like Ctrl-C, sweep
workers that end with their driver, and the tracebacks once seen on malformed runs.

The signal tests run the real command in a subprocess and wait for events (a progress bar, a
journal record), never for a measured time.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from helpers_cli import EXAMPLE, assert_refused, flat

ENV = dict(os.environ, MPLBACKEND="Agg", COLUMNS="200")


# ----------------------------------------------------------------------------------------------
# cost estimates
# ----------------------------------------------------------------------------------------------
COSTLY = {
    "rk4-dt-1e-9": (["history", "--omega", "2.4", "--integrator", "rk4", "--set", "integrator.dt=1e-9"],
                    ["6e+11 time steps", "rk4, dt = 1e-09 s over 600 s", "--force"]),
    "output-step-1e-9": (["history", "--omega", "2.4", "--output-step", "1e-9"],
                         ["cannot run on this machine", "saved instants", "memory"]),
    "sweep-of-a-million-points": (["sweep", "--set", "sweep.omega.num=1000000"],
                                  ["1000000 points", "time steps", "--force"]),
    "sweep-omega-flag": (["sweep", "--omega", "0.5:6:1000000"], ["1000000 points", "--force"]),
    "sweep-point-too-fast": (["sweep", "--omega", "1e4"], ["time steps for one point", "GB of memory", "--force"]),
    "free-vibration-dt-1e-9": (["free-vibration", "--mode", "1", "--peak-velocity", "1", "--integrator", "newmark",
                                "--set", "integrator.dt=1e-9", "--duration", "1e6"], ["time steps", "--force"]),
}


@pytest.mark.parametrize("name", COSTLY)
def test_runs_above_the_limits_are_refused_before_they_start(name, invoke_cli, tmp_path):
    args, needles = COSTLY[name]
    assert_refused(invoke_cli(*args, "--no-plot", "-o", "x.h5"), tmp_path, *needles)


def test_verbose_prints_the_estimate_and_quiet_prints_nothing(invoke_cli, tmp_path):
    res = invoke_cli("--verbose", "history", "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "v.h5")
    assert res.returncode == 0, res.stderr
    assert "estimate: history: about" in res.stderr and "saved instants" in res.stderr
    assert "command: cablesim history --omega 2.4 --duration 5.0 --output v.h5 --no-plot" in res.stderr
    res = invoke_cli("--quiet", "history", "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "q.h5")
    assert res.returncode == 0 and res.stdout == "" and res.stderr == ""
    assert (tmp_path / "q.h5").is_file()


# ----------------------------------------------------------------------------------------------
# states that cannot start, and the causes named
# ----------------------------------------------------------------------------------------------
#: The example starts its free vibration from mode 3: a start from z0 replaces that.
NO_MODE = ("--set", "free_vibration.mode=null", "--set", "free_vibration.peak_velocity=null")


def _node1_at(fraction: float) -> str:
    """z0 moving node 1 a fraction of the way to support A (1: onto it)."""
    from cablesim.analyses.static import run_static
    from cablesim.case import load_case

    y0 = run_static(load_case(None)[0], all_models=False).y0
    return f"free_vibration.z0=[{-fraction * float(y0[0])!r}, {-fraction * float(y0[1])!r}, 0.0, 0.0]"


def test_an_initial_state_that_is_not_finite_is_refused(invoke_cli, tmp_path):
    res = invoke_cli("free-vibration", *NO_MODE, "--set", _node1_at(1.0), "--no-plot", "-o", "fv.h5")
    assert_refused(res, tmp_path, "initial state at t = 0 is not finite", "free_vibration.z0")


def test_an_initial_displacement_that_slackens_a_segment_is_refused(invoke_cli, tmp_path):
    res = invoke_cli("free-vibration", *NO_MODE, "--set", _node1_at(0.8), "--no-plot", "-o", "fv.h5")
    assert_refused(res, tmp_path, "free_vibration.z0 leaves segment 1 slack at t = 0", "smaller initial displacement")


def test_rk4_beyond_its_stability_limit_names_the_step_in_a_sweep(invoke_cli, tmp_path):
    res = invoke_cli("sweep", "--omega", "2.4", "--duration", "100", "--set", "sweep.window=50", "--integrator",
                     "rk4", "--set", "integrator.dt=0.5", "--jobs", "1", "--no-plot", "-o", "s.h5")
    assert res.returncode == 3, res.stderr
    text = flat(res.stdout + res.stderr)
    assert "dt = 0.5 s exceeds rk4's stability limit" in text and "inner solve failed" not in text
    with h5py.File(tmp_path / "s.h5") as f:
        status = f["sweep/status"][()][0].decode()
    assert "stability limit" in status


# ----------------------------------------------------------------------------------------------
# compiled loops return to Python often
# ----------------------------------------------------------------------------------------------
def test_advance_in_chunks_bounds_the_steps_of_each_compiled_call(paper, exact_static):
    from cablesim.analyses.setup import build_equations
    from cablesim.dynamics.integrators import RK4
    from cablesim.dynamics.simulate import advance_in_chunks

    eom = build_equations(paper, exact_static, omega=2.4)
    calls = []

    class Counting(RK4):
        def advance(self, prm, state, t_end, t_out, out):
            i0 = state.extra["i"]
            res = super().advance(prm, state, t_end, t_out, out)
            calls.append(state.extra["i"] - i0)
            return res

    integ, plain = Counting(dt=1e-4), RK4(dt=1e-4)
    t_out = np.array([0.5, 1.0])
    out, ref = np.empty((2, 3 * eom.n_dof)), np.empty((2, 3 * eom.n_dof))
    state = integ.start(eom, eom.initial_state())
    n, code = advance_in_chunks(integ, eom.model(), state, 1.0, t_out, out, max_steps=1000)
    assert (n, code) == (2, 0) and len(calls) == 10 and max(calls) <= 1000
    ref_state = plain.start(eom, eom.initial_state())
    plain.advance(eom.model(), ref_state, 1.0, t_out, ref)
    assert np.array_equal(out, ref)  # the same steps as one call


# ----------------------------------------------------------------------------------------------
# real signals
# ----------------------------------------------------------------------------------------------
def _command() -> list[str]:
    script = Path(sys.executable).with_name("cablesim")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "cablesim.cli"]


def _start(args, cwd: Path, err: Path) -> subprocess.Popen:
    with open(err, "w") as f:  # the child keeps its own descriptor
        return subprocess.Popen([*_command(), *map(str, args)], cwd=cwd, env=ENV, stdout=subprocess.DEVNULL,
                                stderr=f, start_new_session=True)


def _wait_for(proc, condition, what: str, deadline: float = 120.0):
    end = time.monotonic() + deadline
    while not condition():
        assert proc.poll() is None, f"the command ended before {what}"
        assert time.monotonic() < end, f"no {what} within {deadline} s"
        time.sleep(0.1)


def _warm_kernels():
    """Compile (or load) the kernels these runs use, so that the signals land in time loops."""
    from cablesim import api

    case = api.load_case(None)
    api.history(case, omega=2.4, duration=1.0)
    api.history(case, omega=2.4, duration=0.01, integrator="rk4")


def test_sigterm_stops_a_history_like_ctrl_c(tmp_path):
    _warm_kernels()
    err = tmp_path / "err.txt"
    proc = _start(["history", "--omega", "2.4", "--duration", "100000", "--no-plot", "-o", "x.h5"], tmp_path, err)
    try:
        _wait_for(proc, lambda: "simulating" in err.read_text(), "progress bar")
        time.sleep(1.0)
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    text = err.read_text()
    assert code == 143, text
    assert "Traceback" not in text and "interrupted" in text
    with h5py.File(tmp_path / "x.h5") as f:
        status = f["history"].attrs["status"]
        assert status.startswith("interrupted at t =") and "SIGTERM" in status
        assert not f["history"].attrs["completed"]
    assert not list(tmp_path.glob("*.part"))


def test_ctrl_c_acts_inside_a_long_compiled_loop(tmp_path):
    """rk4 at dt = 1e-7: one 10-second chunk was 1e8 steps, minutes without a look at Ctrl-C."""
    _warm_kernels()
    err = tmp_path / "err.txt"
    proc = _start(["history", "--omega", "2.4", "--duration", "100", "--integrator", "rk4", "--set",
                   "integrator.dt=1e-7", "--force", "--no-plot", "-o", "x.h5"], tmp_path, err)
    try:
        _wait_for(proc, lambda: "simulating" in err.read_text(), "progress bar")
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert code == 130, err.read_text()
    with h5py.File(tmp_path / "x.h5") as f:
        assert f["history"].attrs["status"].startswith("interrupted")


def _sweep_case(tmp_path) -> Path:
    case = tmp_path / "case.yaml"
    case.write_text(EXAMPLE.replace("num: 56}", "num: 6}"))
    return case


# Points of about 3e8 rk4 steps each: minutes per point, so a sweep is always mid-point.
SLOW = ["--integrator", "rk4", "--set", "integrator.dt=1e-5", "--force", "--jobs", "2", "--no-plot"]


def _children(pid: int) -> list[int]:
    kids = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:  # a process may end between the listing and these reads
                fields = Path(f"/proc/{d}/stat").read_text().rsplit(")", 1)[1].split()
                command = Path(f"/proc/{d}/cmdline").read_text()
                # loky workers, or workers forked from the driver (which carry its command line)
                if int(fields[1]) == pid and ("loky" in command or "cablesim" in command):
                    kids.append(int(d))
            except OSError:
                continue
    return kids


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_sigterm_stops_a_sweep_with_a_snapshot_and_the_whole_resume_command(tmp_path):
    case = _sweep_case(tmp_path)
    err = tmp_path / "err.txt"
    proc = _start(["sweep", case.name, "--set", "sweep.window=150", "--analysis", "exact", *SLOW, "-o", "out.h5"],
                  tmp_path, err)
    try:
        _wait_for(proc, lambda: len(_children(proc.pid)) >= 2, "worker processes")
        time.sleep(2.0)
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    text = err.read_text()
    assert code == 143, text
    assert "interrupted (SIGTERM)" in flat(text) and "Traceback" not in text
    hint = [line for line in text.splitlines() if line.startswith("cablesim sweep")]
    assert len(hint) == 1, text
    for word in ("case.yaml", "--set sweep.window=150", "--set integrator.dt=1e-5", "--analysis exact",
                 "--integrator rk4", "--output out.h5", "--resume"):
        assert word in hint[0], (word, hint[0])
    assert (tmp_path / "out.h5").is_file() and (tmp_path / "out.h5.journal").is_file()
    assert not (tmp_path / "out.h5.lock").exists()


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_sweep_workers_end_when_their_driver_is_killed(tmp_path):
    case = _sweep_case(tmp_path)
    err = tmp_path / "err.txt"
    proc = _start(["sweep", case.name, *SLOW, "-o", "out.h5"], tmp_path, err)
    kids = []
    try:
        _wait_for(proc, lambda: len(_children(proc.pid)) >= 2, "worker processes")
        kids = _children(proc.pid)
        time.sleep(2.0)  # the workers are inside their first point
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        end = time.monotonic() + 30
        while any(Path(f"/proc/{k}").exists() for k in kids) and time.monotonic() < end:
            time.sleep(0.2)
        alive = [k for k in kids if Path(f"/proc/{k}").exists()]
    finally:
        for k in kids:
            try:
                os.kill(k, signal.SIGKILL)
            except OSError:
                pass
    assert alive == [], "orphaned workers kept running"
