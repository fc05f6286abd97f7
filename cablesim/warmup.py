"""``cablesim compile``: every compiled kernel compiled (or loaded from numba's cache) at once,
by tiny runs through the public API, so that no later run spends time compiling.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Callable

from . import jit
from .api import StaticRun, continuation, free_vibration, history, load_case, static, sweep
from .case import example_text, parse_case


#: The tiny runs :func:`compile_kernels` makes: every analysis, integrator and kind of run, so that
#: each compiled kernel is compiled (or loaded) once.
_SMALL = ["sweep.omega=[2.0, 5.0]", "sweep.duration=40.0", "sweep.window=10.0", "sweep.refine=false",
          "continuation={omega: {start: 2.40, stop: 2.42}, channels: [z2]}"]
_SLACKENING = ["loads.FL=[-0.3e6, 1.1e6, -0.9e6, 6.0e6]"]  # a segment goes slack within seconds
_HEAVY = ["cable.nodes=60", "history.duration=1.0"]
#: segment 3 slack once a period on the steady orbit at 2.45 rad/s, which is shot through slack
_SLACK_ORBIT = ["loads.FL=[-81.0e3, 297.0e3, -243.0e3, 1620.0e3]", "sweep.omega=[2.45]", "sweep.duration=200.0",
                "sweep.window=20.0", "sweep.refine=false"]


def _written(run: StaticRun) -> None:
    """Write a static result to a scratch file: the writer asks for ``B = dT/dP``, a kernel of
    its own."""
    with tempfile.TemporaryDirectory() as scratch:
        run.to_hdf5(Path(scratch) / "static.h5")


def _warm_up_runs() -> list[tuple[str, Callable[[], object]]]:
    base = load_case(None, _SMALL)
    heavy = parse_case(example_text("heavy-span"), source="(the shipped heavy-span case)", default_name="heavy-span",
                       overrides=_HEAVY)
    runs: list[tuple[str, Callable[[], object]]] = [
        ("statics", lambda: [_written(static(base, a, all_models=True)) for a in ("exact", "approximate")]),
    ]
    for analysis in ("exact", "approximate"):
        for integ in ("dopri5", "rk4", "newmark", "generalized-alpha"):
            runs.append((f"history: {analysis} analysis, {integ}",
                         lambda a=analysis, i=integ: history(base, omega=2.4, duration=3.0, analysis=a, integrator=i)))
        runs.append((f"free vibration: {analysis} analysis",
                     lambda a=analysis: free_vibration(base, mode=3, peak_velocity=1.0, duration=1.0, analysis=a)))
    slack = load_case(None, [*_SMALL, *_SLACKENING])
    for integ in ("dopri5", "rk4", "newmark", "generalized-alpha"):
        runs.append((f"history through slack segments: {integ}",
                     lambda i=integ: history(slack, omega=2.45, duration=6.0, integrator=i)))
    fixed = [*_SMALL, "integrator={name: generalized-alpha, dt: 0.01}"]  # the implicit fixed-step loop
    for analysis in ("exact", "approximate"):
        runs.append((f"history: {analysis} analysis, generalized-alpha at a fixed step",
                     lambda a=analysis: history(load_case(None, fixed), omega=2.4, duration=1.0, analysis=a)))
    runs.append(("history through slack segments: generalized-alpha at a fixed step",
                 lambda: history(load_case(None, [*fixed, *_SLACKENING]), omega=2.45, duration=6.0)))
    z0 = load_case(None, [*_SMALL, "free_vibration={z0: [0.01, 0.01, 0.0, 0.0], duration: 0.5}"])
    runs += [
        ("free vibration from a displacement", lambda: free_vibration(z0)),
        ("heavy cable: exact analysis", lambda: history(heavy)),
        ("heavy cable: approximate analysis", lambda: history(heavy, duration=0.2, analysis="approximate")),
        ("sweep: shooting and Floquet multipliers", lambda: sweep(base, jobs=1)),
        ("sweep: integration alone, up and down", lambda: sweep(load_case(None, [
            *_SMALL, "sweep.accelerate=false", "sweep.direction=both"]), jobs=1)),
        ("sweep: shooting through slack segments", lambda: sweep(load_case(None, [*_SMALL, *_SLACK_ORBIT]), jobs=1)),
        ("continuation: exact analysis", lambda: continuation(base)),
        ("continuation: approximate analysis", lambda: continuation(base, "approximate")),
    ]
    return runs


def compile_kernels(progress: Callable[[int, int, str], None] | None = None) -> float:
    """Compile every compiled kernel now (or load it from numba's on-disk cache), so that no
    later run spends time compiling: what ``cablesim compile`` and ``make install`` do.

    Runs tiny cases through the public analyses (every analysis, integrator, slack handling,
    free vibration, a heavy cable, sweeps and continuation); numba compiles each kernel the
    first time it runs and caches it for every later process on this machine.

    Parameters
    ----------
    progress : callable, optional
        Called as ``progress(done, total, what)`` before each run.

    Returns
    -------
    float
        Seconds spent compiling (0 when every kernel was in the cache).
    """
    before = jit.compile_seconds()
    runs = _warm_up_runs()
    for k, (what, run) in enumerate(runs):
        if progress is not None:
            progress(k, len(runs), what)
        run()
    if progress is not None:
        progress(len(runs), len(runs), "done")
    return jit.compile_seconds() - before
