"""Nothing compiles silently: on a machine whose kernel cache is empty (a fresh numba cache
folder), a first run says that it compiles and prints a simulation time without the
compilation; after ``cablesim compile`` (what ``make install`` runs) no command compiles any
kernel at all (numba's compile events counted in each process).

Slow (a full compilation, minutes): run by ``make test-all``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

#: A command line in a fresh process, then the number of kernels that process compiled.
PROBE = """
import sys
from typer.testing import CliRunner
from cablesim import jit
from cablesim.cli import app
res = CliRunner().invoke(app, sys.argv[1:])
assert res.exit_code in (0, 3), (res.stdout[-800:], res.stderr[-800:], res.exception)
print("KERNELS COMPILED", jit.kernels_compiled())
"""

#: The commands after `make install`: the README's, each integrator and analysis, a heavy cable,
#: slack segments, sweeps and continuation, the stress test.
COMMANDS = [
    ["static", "my-case.yaml", "--no-plot"],
    ["history", "my-case.yaml", "--duration", "20", "--no-plot"],
    *[["history", "my-case.yaml", "--duration", "20", "--integrator", i, "--no-plot", "-o", f"h-{i}.h5"]
      for i in ("rk4", "newmark", "generalized-alpha")],
    ["history", "my-case.yaml", "--duration", "20", "--analysis", "approximate", "--no-plot", "-o", "ha.h5"],
    ["history", "my-case.yaml", "--omega", "2.45", "--duration", "20", "--no-plot", "-o", "slack.h5",
     "--set", "loads.FL=[-60.0e3, 220.0e3, -180.0e3, 1200.0e3]"],
    ["free-vibration", "my-case.yaml", "--no-plot"],
    ["history", "heavy.yaml", "--duration", "2", "--no-plot"],
    ["sweep", "my-case.yaml", "--omega", "2.4,5.05", "--duration", "300", "--window", "50", "--jobs", "1", "--no-plot"],
    ["continue", "my-case.yaml", "--set", "continuation.omega={start: 5.0, stop: 5.1}", "--no-plot"],
    ["continue", "my-case.yaml", "--analysis", "approximate", "--set", "continuation.omega={start: 2.3, stop: 2.4}",
     "--no-plot"],
    ["stress", "--reduced", "--jobs", "1", "--md", "s.md", "--png", "s.png"],
]


def _run(args, cwd: Path, env) -> subprocess.CompletedProcess:
    return subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=3600)


@pytest.mark.slow
def test_nothing_compiles_silently_and_after_cablesim_compile_nothing_compiles(tmp_path):
    from cablesim.case import example_text

    env = dict(os.environ, MPLBACKEND="Agg", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    (tmp_path / "my-case.yaml").write_text(example_text())
    (tmp_path / "heavy.yaml").write_text(example_text("heavy-span"))
    cli = str(Path(sys.executable).with_name("cablesim"))
    # a first use on an empty cache: said, and not counted as simulation
    first = _run([cli, "history", "my-case.yaml", "--duration", "60", "--no-plot", "-o", "first.h5"], tmp_path, env)
    assert first.returncode == 0, first.stderr
    assert "(first use on this machine" in first.stderr
    took = float(re.search(r"compiled \d+ kernels in ([\d.]+) s", first.stderr).group(1))
    printed = float(re.search(r"simulated 60 s in ([\d.e+-]+) s wall time", first.stdout).group(1))
    assert took > 5.0 and printed < 0.2 * took, (took, printed)
    # make install's step, then every command
    ahead = _run([cli, "compile"], tmp_path, env)
    assert ahead.returncode == 0, ahead.stderr
    for args in COMMANDS:
        res = _run([sys.executable, "-c", PROBE, *args], tmp_path, env)
        assert res.returncode == 0, (args, res.stdout[-1500:], res.stderr[-1500:])
        assert "KERNELS COMPILED 0" in res.stdout, (args, res.stdout[-500:])
