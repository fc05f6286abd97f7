"""Shared helpers of the sweep tests (``test_steady``, ``test_sweep``, ``test_sweep_journal``).

Every case is the paper example (``cablesim.case.example_text()``) with its ``sweep:`` section
replaced (:func:`case_text`). Sweeps run in-process through :func:`run_sweep` (the sweep as
``cablesim sweep -o out`` runs it); a few end-to-end checks run the real command in a
subprocess (:func:`start_cli`, :func:`finish_cli`). :func:`read_sweep` reads every dataset of a
sweep file with h5py directly, independently of :mod:`cablesim.io.sweeps`.

The sweeps shared between modules (``LIN_SWEEP``, ``LATE_SWEEP``) run once per session: their
fixtures ``linear`` and ``late`` live in ``conftest.py``. Imported by the test modules as
``helpers_sweep`` (pytest puts ``tests/`` on ``sys.path``).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

from cablesim import api
from cablesim.analyses.static import run_static
from cablesim.case import example_text, parse_case

BASE = example_text()
HEAD = BASE[: BASE.index("\nsweep:") + 1]  # everything before the sweep section
RESULT_FIELDS = ("amplitude", "halfrange", "period", "steady", "response_frequency", "t_end", "floquet", "done")
PER_CHANNEL = ("amplitude", "halfrange", "response_frequency")
UNITS = {
    "amplitude": "m",
    "halfrange": "m",
    "response_frequency": "rad/s",
    "period": "forcing periods",
    "steady": "1",
    "t_end": "s",
    "floquet": "1",
    "done": "1",
}
#: A tight DOPRI5 so that a tiny (linear) response is accurate to well below 1e-3 of itself.
TIGHT = {"name": "dopri5", "rtol": 1.0e-10, "atol": 1.0e-14}

# The sweeps of the session fixtures ``linear`` and ``late`` (conftest.py).
LIN_W = [1.0, 2.3, 2.52, 2.7, 4.0, 6.0]  # fundamental 2.524 rad/s; mode 2 at 13.0 rad/s
LIN_GAMMA = [1.0e-4, 2.0e-4]
LIN_SWEEP = {"omega": LIN_W, "duration": 1500.0, "window": 100.0, "channels": ["z1", "z2", "z3", "z4"], "gamma": LIN_GAMMA}
LATE_SWEEP = {"omega": [5.0, 5.05], "duration": 4000.0, "channels": ["z2", "z4"]}


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------
def run_sweep(case, text, out, n_jobs=1, resume=False, progress=None, backend=None, scheduler=None):
    """The sweep as ``cablesim sweep -o out`` runs it: journal and HDF5 file kept current."""
    assert case.text == text
    return api.sweep(case, jobs=n_jobs, output=out, resume=resume, backend=backend, scheduler=scheduler,
                     progress=progress).result


def case_text(sweep: dict | None, *, xi: float | None = None, integrator: dict | None = None,
              slack: str | None = None) -> str:
    """The paper example with its sweep section replaced (None: no sweep section)."""
    head = HEAD
    if slack is not None:
        head, n = re.subn(r"^slack: continue\b", f"slack: {slack}", head, flags=re.M)
        assert n == 1
    if xi is not None:
        head, n = re.subn(r"ratio: 0\.01\b", f"ratio: {xi}", head)
        assert n == 1
    if integrator is not None:
        head += yaml.safe_dump({"integrator": integrator}, default_flow_style=None)
    if sweep is None:
        return head
    return head + yaml.safe_dump({"sweep": sweep}, default_flow_style=None, sort_keys=False)


def do_sweep(out: Path, sweep: dict, n_jobs: int = 2, **kw):
    text = case_text(sweep, **kw)
    case = parse_case(text)
    res = run_sweep(case, text, out, n_jobs=n_jobs)
    return case, text, res


def read_sweep(path: Path) -> dict:
    """Every dataset of a sweep file, by path relative to /sweep ("amplitude", "up/amplitude")."""
    data = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                data[name] = obj[()]

        f["sweep"].visititems(visit)
        data["/attrs"] = dict(f["sweep"].attrs)
    return data


def assert_same_results(a: dict, b: dict) -> None:
    """Same datasets with the same values (NaN == NaN); the wall-clock times may differ."""
    keys = {k for k in a if k != "/attrs" and not k.endswith("wall")}
    assert keys == {k for k in b if k != "/attrs" and not k.endswith("wall")}
    for k in sorted(keys):
        assert a[k].shape == b[k].shape, k
        text = a[k].dtype.kind in "OSU"  # the per-point status in words
        assert np.array_equal(a[k], b[k], equal_nan=not text), (k, a[k], b[k])


def closed_form(case, omega, gamma) -> np.ndarray:
    """|H(w) gamma FL| per DOF, rows = frequencies, H = (K0 - w^2 M + i w C)^-1."""
    st = run_static(case, None, all_models=False)
    M = np.diag(np.repeat(np.array(case.cable.masses), 2))
    C = st.a0 * M + st.a1 * st.K0
    return np.array([np.abs(np.linalg.solve(st.K0 - w * w * M + 1j * w * C, gamma * case.FL)) for w in omega])


def _cli_command() -> list[str]:
    script = Path(sys.executable).with_name("cablesim")
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, "-m", "cablesim.cli"]


def start_cli(args, cwd: Path) -> subprocess.Popen:
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    return subprocess.Popen(
        [*_cli_command(), *map(str, args)], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env=env, start_new_session=True,
    )


def finish_cli(proc: subprocess.Popen, timeout: float = 180.0) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise
    return proc.returncode, out, err


def journal_records(path: Path) -> int:
    """Complete records in a journal (lines after the header that end with a newline)."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return 0
    return max(text.count("\n") - 1, 0)


def wait_for_records(proc: subprocess.Popen, journal: Path, n: int, timeout: float = 120.0, until=None) -> int:
    """Wait until ``n`` points are journalled (and ``until()`` holds, unless ``n + 8`` are)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        k = journal_records(journal)
        if k >= n and (until is None or until() or k >= n + 8):
            return k
        if proc.poll() is not None:
            _, err = proc.communicate()
            pytest.fail(f"the sweep ended (status {proc.returncode}) before {n} points were done:\n{err}")
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    pytest.fail(f"fewer than {n} points done after {timeout} s")


class Stop(Exception):
    """Raised from a progress callback to interrupt a sweep in-process."""


def stop_after(n: int):
    def progress(done, total):
        if done >= n:
            raise Stop

    return progress

