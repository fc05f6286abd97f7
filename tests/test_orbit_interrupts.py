"""Ctrl-C and SIGTERM inside the orbits' compiled flows: one flow is one compiled call, which
runs for many seconds at a long forcing period (the paper's cable at 1e-4 rad/s: millions of
steps), so every orbit kernel reads the interruption flag once a step and stops.

- Each kernel, with the flag set before the call, stops with the status ``INTERRUPTED``, which
  its entry point turns into ``KeyboardInterrupt``; with the flag clear the same call completes.
- A real signal, in this process and to the command line in a subprocess, stops a flow that
  would take far longer within about a second: the command ends with its interruption message
  and exit status (130, 143), no traceback.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from cablesim import api
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics import interrupts
from cablesim.orbits import Shooting, cable_system, linear_response_state
from cablesim.orbits import kernels as ok
from cablesim.orbits.matrixfree import MatrixFreeShooting

#: Forcing frequency (rad/s) at which one period of the paper's cable is millions of rk8 steps.
SLOW_OMEGA = 1e-4

HEAVY = """\
cable: {L: 300.0, H: 10.0, length: 300.7, nodes: 5, EA: 3.3e7, mass_per_length: 1.628}
loads: {gravity: 9.81, point: [{node: 1, FL: [0.0, 200.0]}]}
analysis: exact
damping: {ratio: 0.005, modes: [1, 2]}
"""


def paper(omega: float):
    case = api.load_case(None)
    eom = build_equations(case, run_static(case), omega=omega)
    return eom, cable_system(eom)


@pytest.fixture
def flag_set(monkeypatch):
    """The flag set as by a signal before a kernel starts, and left set as it starts (its entry
    point clears a flag raised before it, which the signal handlers have acted on)."""
    monkeypatch.setattr(interrupts, "clear", lambda: None)
    interrupts.STOP[0] = 1
    yield
    interrupts.STOP[0] = 0


def test_the_dense_flow_kernel_returns_interrupted_on_the_flag():
    eom, sysm = paper(2.4)
    sh = Shooting(sysm)
    x0 = linear_response_state(eom, 2.4)
    n = sysm.dim
    ns = sh.segment_steps(2.4)
    T = 2.0 * np.pi / 2.4
    codes, ends = [], []
    for flag in (1, 0):
        xend, G, dp = np.full(n, np.nan), np.empty((n, n)), np.zeros(n)
        xmax, xmin, info = np.empty(n), np.empty(n), np.zeros(4)
        code = ok.flow_segment(sysm.field, sysm.model, sysm.prm, ok.copy_work(sysm.work), x0, 0.0, 2.4, T, ns, sh._A,
                               sh._b, sh._c, -1, ok.PARAM_OMEGA, True, *sh._whole, xend, G, dp, xmax, xmin,
                               np.zeros((0, 0)), info, np.array([flag], dtype=np.int64))
        codes.append(code)
        ends.append(xend)
    assert codes == [ok.INTERRUPTED, ok.OK]
    assert np.isnan(ends[0]).all()  # stopped before its first step: nothing written
    assert np.isfinite(ends[1]).all()


def test_the_dense_shooting_raises_keyboard_interrupt_on_the_flag(flag_set):
    eom, sysm = paper(2.4)
    sh = Shooting(sysm)
    with pytest.raises(KeyboardInterrupt):
        sh.evaluate(linear_response_state(eom, 2.4), 2.4)


def _heavy():
    case = parse_case(HEAVY)
    eom = build_equations(case, run_static(case), omega=1.5)
    return eom, cable_system(eom)


@pytest.mark.parametrize("scheme, mechanical", [("rk8", True), ("rk8", False), ("radau", True)])
def test_each_matrix_free_kernel_stops_on_the_flag(monkeypatch, scheme, mechanical):
    """flow_mechanical, flow_dense_directions (a system without its mechanical form), and
    radau_orbit with the replay of its tape, radau_directions."""
    eom, sysm = _heavy()
    if not mechanical:
        sysm = dataclasses.replace(sysm, mechanical=None)
    mf = MatrixFreeShooting(sysm, scheme=scheme)
    u0 = linear_response_state(eom, 1.5)
    ev = mf.evaluate(u0, 1.5)  # the flag clear: every kernel completes
    assert ev.status == ok.OK
    X = np.eye(sysm.dim)[:, :3]
    assert np.isfinite(mf.monodromy_apply(ev, X)).all()
    monkeypatch.setattr(interrupts, "clear", lambda: None)
    interrupts.STOP[0] = 1
    try:
        with pytest.raises(KeyboardInterrupt):  # the directions of an evaluated orbit (the replay for radau)
            mf.monodromy_apply(ev, X)
        with pytest.raises(KeyboardInterrupt):
            mf.evaluate(u0, 1.5)
    finally:
        interrupts.STOP[0] = 0


def test_a_signal_stops_a_long_flow_in_this_process():
    eom, sysm = paper(2.4)
    sh = Shooting(sysm)
    sh.segment(0, linear_response_state(eom, 2.4), 2.4)  # the kernel loaded
    assert sh.segment_steps(SLOW_OMEGA) > 1e6  # tens of seconds of flow
    x0 = linear_response_state(eom, SLOW_OMEGA)
    interrupts.install()
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    try:
        t0 = time.monotonic()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            sh.segment(0, x0, SLOW_OMEGA)
        took = time.monotonic() - t0
    finally:
        timer.cancel()
        interrupts.restore()
    assert interrupts.received() == signal.SIGINT
    assert took < 5.0, f"the flow went on for {took:.1f} s"
    interrupts.clear()


def test_a_wakeup_descriptor_set_by_another_is_left_alone():
    a, b = socket.socketpair()
    b.setblocking(False)
    try:
        signal.set_wakeup_fd(b.fileno())
        interrupts.install()
        assert signal.set_wakeup_fd(b.fileno()) == b.fileno()  # unchanged by install
        interrupts.restore()
        assert signal.set_wakeup_fd(b.fileno()) == b.fileno()  # and by restore
    finally:
        interrupts.restore()
        signal.set_wakeup_fd(-1)
        a.close()
        b.close()


# ----------------------------------------------------------------------------------------------
# the command line, in a subprocess
# ----------------------------------------------------------------------------------------------
def _command() -> list[str]:
    script = Path(sys.executable).with_name("cablesim")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "cablesim.cli"]


@pytest.mark.parametrize("signum, code, name", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")])
def test_continue_stops_within_a_second_inside_a_long_flow(tmp_path, signum, code, name):
    """``continue`` over a range whose every orbit flow is millions of steps (a minute each):
    the signal comes while the first flow runs and the command ends about a second later."""
    eom, sysm = paper(2.4)
    Shooting(sysm).segment(0, linear_response_state(eom, 2.4), 2.4)  # in the cache: no compilation in the run
    err = tmp_path / "err.txt"
    args = ["--verbose", "continue", "--set", f"continuation.omega={{start: {SLOW_OMEGA}, stop: {1.1 * SLOW_OMEGA}}}",
            "--no-plot", "-o", "c.h5"]
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="200")
    with open(err, "w") as f:
        proc = subprocess.Popen([*_command(), *args], cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=f,
                                start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while "effective options" not in err.read_text():  # the case is read: the run starts
            assert proc.poll() is None, err.read_text()
            assert time.monotonic() < deadline, "the command did not start"
            time.sleep(0.05)
        time.sleep(3.0)  # the statics, the start and the kernel's load are done: the first flow runs
        assert proc.poll() is None, err.read_text()
        sent = time.monotonic()
        proc.send_signal(signum)
        try:
            status = proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            status = None
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    text = err.read_text()
    assert status is not None, f"still running 10 s after {name}"
    assert status == code, text
    assert took < 3.0, f"ended {took:.1f} s after {name}"
    assert f"interrupted ({name})" in " ".join(text.split()) and "Traceback" not in text
    assert not (tmp_path / "c.h5").exists()


def test_a_flag_raised_while_a_compiled_loop_runs_is_seen():
    """:func:`~cablesim.dynamics.interrupts.stop_requested` reads the flag from memory at every
    step: set from another thread 50 ms into a loop of tens of millions of steps (some 0.3 s),
    it ends the loop at once. (A plain ``flag[0]`` in such a loop was hoisted out of it by the
    compiler: a long orbit flow of a continuation ran to its end after Ctrl-C;
    tests/test_api_interrupts.py.)"""
    import numba

    @numba.njit(nogil=True)
    def watched(flag, n):
        s = 0.0
        for k in range(n):
            if interrupts.stop_requested(flag):
                return k, s
            s += np.sin(k * 1e-3)
        return -1, s

    n = 30_000_000
    flag = np.zeros(1, dtype=np.int64)
    watched(flag, 10)  # compiled
    timer = threading.Timer(0.05, flag.__setitem__, (0, 1))
    timer.start()
    end = watched(flag, n)[0]
    timer.join()
    assert 0 < end < n
