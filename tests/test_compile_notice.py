"""The compile notice speaks only once compiling itself has lasted its delay: a run that loads
its kernels from the cache, with a few short compiles of numba's own helpers spread over its first
second, printed "compiling numba.np.arrayobj.impl ... (first use on this machine)" on every run."""

from __future__ import annotations

import time

from cablesim import jit
from cablesim.io import terminal


def _notice(monkeypatch, compiled: list[float], now: list[str | None]):
    monkeypatch.setattr(jit, "compile_seconds", lambda: compiled[0])
    monkeypatch.setattr(jit, "compiling_now", lambda: now[0])
    said: list[str] = []
    return terminal.CompileNotice(said.append, delay=0.2, tty=False), said


def test_short_compiles_over_a_longer_wall_time_say_nothing(monkeypatch):
    compiled, now = [0.0], ["impl"]
    notice, said = _notice(monkeypatch, compiled, now)
    notice.started("impl")
    compiled[0] = 0.05  # 50 ms of compiling, still under way when the delay has passed in wall time
    time.sleep(0.45)
    assert said == []
    now[0] = None  # it ends below the delay: nothing is ever said
    time.sleep(0.3)
    assert said == []


def test_compiling_that_lasts_the_delay_is_said_with_the_kernel(monkeypatch):
    compiled, now = [0.0], ["field.rate"]
    notice, said = _notice(monkeypatch, compiled, now)
    notice.started("field.rate")
    compiled[0] = 0.1
    time.sleep(0.3)
    assert said == []  # 0.1 s of 0.2
    compiled[0] = 0.25
    time.sleep(0.4)
    assert len(said) == 1 and "compiling field.rate" in said[0] and "first use on this machine" in said[0]
