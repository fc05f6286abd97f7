"""Ctrl-C in a script that calls the Python API: it reaches the compiled flow of an orbit (one
compiled call, seconds long at a long forcing period) without the script installing anything,
and the script's own signal handlers are left as they were.

The command line installs its handlers itself (tests/test_orbit_interrupts.py); here nothing is
installed: :func:`cablesim.continuation` runs under :func:`cablesim.dynamics.interrupts.watching`,
which only has the interpreter write each signal to a socket whose reader sets the flag the
kernels poll. A flow that ends just after the signal, long before its length, is the evidence
that the signal reached it while it ran (Python's own handler acts only between bytecodes, after
the kernel returns).
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import cablesim
from cablesim.analyses.charts import Interrupted
from cablesim.dynamics import interrupts
from cablesim.orbits import kernels

#: The paper's cable at this forcing frequency: a period of 628 s, some 26 000 rk8 steps per flow
#: with its variational equations (a few tenths of a second), so a signal lands inside a flow.
SLOW = "continuation={omega: {start: 0.01, stop: 0.012}, channels: [z2]}"


def test_ctrl_c_reaches_the_orbit_kernel_of_an_api_continuation(monkeypatch):
    """The signal is sent 50 ms into a flow once two orbits exist: the flow it lands in must
    end within a small fraction of a flow's length (without the watcher it runs to its end,
    some 0.2 s here, and Python's handler acts after it)."""
    case = cablesim.load_case(None, [SLOW])
    handler = signal.getsignal(signal.SIGINT)
    armed, flows, sent = [], [], []
    call = kernels.EntryPoint.__call__

    def progress(point):
        armed.append(point.parameter)

    def fire():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    def timed_call(self, *args):  # every kernel call: its start, its end, and whether interrupted
        if len(armed) >= 2 and not sent and len(flows) >= 3:
            threading.Timer(0.05, fire).start()
        t0 = time.monotonic()
        try:
            out = call(self, *args)
        except KeyboardInterrupt:
            flows.append((t0, time.monotonic(), True))
            raise
        flows.append((t0, time.monotonic(), False))
        return out

    monkeypatch.setattr(kernels.EntryPoint, "__call__", timed_call)
    with pytest.raises(Interrupted) as caught:
        cablesim.continuation(case, progress=progress)
    stopped = [f for f in flows if f[2]]
    assert sent and len(stopped) == 1, (sent, flows)
    t0, t1, _ = stopped[0]
    typical = float(np.median([b - a for a, b, hit in flows if not hit and a < t0]))
    assert t0 < sent[0] < t1  # the signal came while this flow ran
    assert t1 - sent[0] < 0.25 * typical, f"the flow went on {t1 - sent[0]:.3f} s after the signal (flows: {typical:.3f} s)"
    assert caught.value.result.n_points >= 2 and not caught.value.result.complete
    assert signal.getsignal(signal.SIGINT) is handler  # the script's handler is untouched
    assert signal.set_wakeup_fd(-1) == -1  # and no wakeup descriptor is left behind


def test_watching_nests_and_leaves_another_wakeup_descriptor_alone():
    import socket

    with interrupts.watching():
        fd = signal.set_wakeup_fd(-1)
        assert fd != -1  # in force
        signal.set_wakeup_fd(fd)
        with interrupts.watching():
            assert signal.set_wakeup_fd(fd) == fd  # the inner use shares the outer's
        assert signal.set_wakeup_fd(fd) == fd  # still in force after the inner one ends
    assert signal.set_wakeup_fd(-1) == -1  # the outermost removed it
    a, b = socket.socketpair()
    b.setblocking(False)
    try:
        signal.set_wakeup_fd(b.fileno())
        with interrupts.watching():
            assert signal.set_wakeup_fd(b.fileno()) == b.fileno()  # someone else's: left in place
        assert signal.set_wakeup_fd(-1) == b.fileno()
    finally:
        a.close()
        b.close()
