"""Shared fixtures.

Command-line and case-file tests:

- ``run_cli``: run the real ``cablesim`` command in a subprocess (cwd = the test's tmp_path) and
  return ``(returncode, stdout, stderr)``. Each process start costs about a second, so the tests
  use it only for a few end-to-end checks.
- ``invoke_cli``: run the same Typer app in-process (``typer.testing.CliRunner``), cwd =
  tmp_path; fast, used for most error cases.
- ``write_case``: write a case (a dict, dumped as YAML, or YAML text as is) into tmp_path.
- ``paper_case``: a fresh, mutable dict of the shipped ``configs/paper-example.yaml``.

Time histories (session-scoped; the independent reference is in ``helpers_dynamics.py``):

- ``paper`` (the example case), ``exact_static``, ``approx_static``;
- ``forced_eom`` / ``approx_eom``: equations of motion forced at ``helpers_dynamics.OMEGA``;
- ``reference``: ``(t, z, v)`` of the independent scipy reference for ``forced_eom``;
- ``approx_tight``: a tight DOPRI5 run of ``approx_eom``.

Sweeps (session-scoped; helpers in ``helpers_sweep.py``): ``wdir`` (a working folder),
``linear`` and ``late`` (sweeps read by more than one module).
"""

from __future__ import annotations

import copy
import os
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
CONFIG_EXAMPLE = REPO / "configs" / "paper-example.yaml"


class CliResult(NamedTuple):
    returncode: int
    stdout: str
    stderr: str


def _cablesim_command() -> list[str]:
    """The console script beside the running interpreter, else ``python -m cablesim.cli``."""
    script = Path(sys.executable).with_name("cablesim")
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, "-m", "cablesim.cli"]


def _start(args, cwd: Path) -> subprocess.Popen:
    env = dict(os.environ)
    env.setdefault("MPLBACKEND", "Agg")
    env["COLUMNS"] = "100"  # stable wrapping of any help text
    return subprocess.Popen(
        [*_cablesim_command(), *map(str, args)],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _finish(proc: subprocess.Popen, timeout: float = 120.0) -> CliResult:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise
    return CliResult(proc.returncode, out, err)


def _run(args, cwd: Path, timeout: float = 120.0) -> CliResult:
    return _finish(_start(args, cwd), timeout)


def _run_many(jobs, timeout: float = 120.0) -> list[CliResult]:
    """Run several ``(args, cwd)`` commands concurrently (process start-up dominates)."""
    procs = [_start(args, cwd) for args, cwd in jobs]
    return [_finish(p, timeout) for p in procs]


@pytest.fixture(scope="session")
def cablesim_subprocess():
    """``run(args, cwd)`` -> CliResult; session-scoped so module fixtures can use it."""
    return _run


@pytest.fixture(scope="session")
def cablesim_subprocesses():
    """``run_many([(args, cwd), ...])`` -> [CliResult, ...], run concurrently."""
    return _run_many


@pytest.fixture
def run_cli(tmp_path):
    """Run ``cablesim *args`` in a subprocess with cwd = tmp_path."""

    def run(*args, cwd: Path | None = None, timeout: float = 120.0) -> CliResult:
        return _run(args, cwd if cwd is not None else tmp_path, timeout)

    return run


class InvokeResult(NamedTuple):
    returncode: int
    stdout: str
    stderr: str
    exception: BaseException | None


@pytest.fixture
def invoke_cli(tmp_path, monkeypatch):
    """Run the ``cablesim`` Typer app in-process with cwd = tmp_path.

    Returns ``(returncode, stdout, stderr, exception)``; ``exception`` is what the runner caught
    (``SystemExit`` for a clean exit with a non-zero status, None for status 0, anything else is
    an uncaught error, which the command line would have shown as a traceback).
    """
    from typer.testing import CliRunner

    from cablesim.cli import app

    monkeypatch.chdir(tmp_path)
    runner = CliRunner()

    def invoke(*args) -> InvokeResult:
        res = runner.invoke(app, [str(a) for a in args])
        return InvokeResult(res.exit_code, res.stdout, res.stderr, res.exception)

    return invoke


def dump_case(case) -> str:
    """YAML text of a case given as a dict (or the text itself)."""
    if isinstance(case, str):
        return case
    return yaml.safe_dump(case, sort_keys=False)


@pytest.fixture
def write_case(tmp_path):
    """``write(case, name="case.yaml") -> Path``: a dict is dumped as YAML, a str written as is."""

    def write(case, name: str = "case.yaml") -> Path:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(dump_case(case))
        return path

    return write


def _numbers(obj):
    """Plain YAML 1.1 reads ``2.0e11`` as a string: turn such strings back into floats."""
    if isinstance(obj, dict):
        return {k: _numbers(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_numbers(v) for v in obj]
    if isinstance(obj, str):
        try:
            return float(obj)
        except ValueError:
            return obj
    return obj


@pytest.fixture(scope="session")
def _paper_case_dict() -> dict:
    return _numbers(yaml.safe_load(CONFIG_EXAMPLE.read_text()))


@pytest.fixture
def paper_case(_paper_case_dict) -> dict:
    """A fresh deep copy of configs/paper-example.yaml as a dict (safe to mutate)."""
    return copy.deepcopy(_paper_case_dict)


# ----------------------------------------------------------------------------------------------
# Time histories (test_equations, test_integrators, test_simulate): the paper example, its
# static equilibria and the forced runs, once per session. The independent reference they are
# checked against is in helpers_dynamics.py.
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def paper():
    from cablesim.case import load_case

    case, _ = load_case(None)
    return case


@pytest.fixture(scope="session")
def exact_static(paper):
    from cablesim.analyses.static import run_static

    return run_static(paper, "exact", all_models=False)


@pytest.fixture(scope="session")
def approx_static(paper):
    from cablesim.analyses.static import run_static

    return run_static(paper, "approximate", all_models=False)


@pytest.fixture(scope="session")
def forced_eom(paper, exact_static):
    from cablesim.analyses.setup import build_equations
    from helpers_dynamics import OMEGA

    return build_equations(paper, exact_static, omega=OMEGA)


@pytest.fixture(scope="session")
def reference(forced_eom):
    import numpy as np
    from helpers_dynamics import DURATION, OUT_STEP, reference_history

    t = np.arange(0, round(DURATION / OUT_STEP) + 1) * OUT_STEP
    z, v = reference_history(forced_eom, t)
    return t, z, v


@pytest.fixture(scope="session")
def approx_eom(paper, approx_static):
    from cablesim.analyses.setup import build_equations
    from helpers_dynamics import OMEGA

    return build_equations(paper, approx_static, omega=OMEGA)


@pytest.fixture(scope="session")
def approx_tight(approx_eom):
    from cablesim.dynamics.integrators import DOPRI5
    from cablesim.dynamics.simulate import simulate
    from helpers_dynamics import APPROX_DURATION, OUT_STEP

    hist = simulate(approx_eom, DOPRI5(rtol=1e-10, atol=1e-12), APPROX_DURATION, OUT_STEP)
    assert hist.completed, hist.message
    return hist


# ----------------------------------------------------------------------------------------------
# Sweeps (test_steady, test_sweep, test_sweep_journal): one working folder, and the sweeps more
# than one module reads, once per session. Helpers and settings are in helpers_sweep.py.
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def wdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("sweep")


@pytest.fixture(scope="session")
def linear(wdir):
    """LIN_SWEEP (linear regime, two gammas, tight DOPRI5): ``(case, result, path)``."""
    from helpers_sweep import LIN_SWEEP, TIGHT, do_sweep

    out = wdir / "linear.h5"
    case, text, res = do_sweep(out, LIN_SWEEP, xi=0.05, integrator=TIGHT)
    return case, res, out


@pytest.fixture(scope="session")
def late(wdir):
    """LATE_SWEEP (5.0 and 5.05 rad/s, 4000 s cap: the late jump): ``(result, path)``."""
    from helpers_sweep import LATE_SWEEP, do_sweep

    out = wdir / "late.h5"
    _, _, res = do_sweep(out, LATE_SWEEP)
    return res, out
