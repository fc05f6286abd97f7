"""The scripts in examples/ run as shipped (in a fresh process, in an empty folder), and what they
print is what their result files hold (read back with h5py)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from PIL import Image

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run_example(name: str, cwd: Path) -> str:
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), "out"], cwd=cwd, capture_output=True, text=True,
                          timeout=600, env=env)
    assert proc.returncode == 0, (proc.stdout[-2000:], proc.stderr[-2000:])
    return proc.stdout


def test_statics_to_figures(tmp_path):
    out = run_example("statics_to_figures.py", tmp_path)
    folder = tmp_path / "out"
    for name in ("static.h5", "static.png", "static-modes.png", "static-report.html"):
        assert (folder / name).is_file(), name
    with h5py.File(folder / "static.h5", "r") as f:
        T, omega = f["static/exact/T"][()], f["modal/omega"][()]
    printed_T = [float(x) for x in re.findall(r"segment \d+: T = ([\d.]+) kN", out)]
    np.testing.assert_allclose(printed_T, T / 1e3, atol=0.05)
    printed_w = [float(x) for x in re.findall(r"mode \d+: ([\d.]+) rad/s", out)]
    np.testing.assert_allclose(printed_w, omega, atol=5e-5)
    assert "(4 panels)" in out


@pytest.mark.slow
def test_sweep_and_its_peak(tmp_path):
    out = run_example("sweep.py", tmp_path)
    folder = tmp_path / "out"
    with h5py.File(folder / "sweep.h5", "r") as f:
        w, amp = f["sweep/omega"][()], f["sweep/amplitude"][()][:, 0]
    peak = float(w[np.argmax(amp)])
    assert re.search(rf"omega = {peak:.3f} rad/s: .* <- largest", out)
    hist = folder / f"history-w{peak:g}.h5"
    with h5py.File(hist, "r") as f:
        assert float(f["history"].attrs["omega"]) == peak and f["history"].attrs["completed"]
    with Image.open(folder / f"history-w{peak:g}-animation.gif") as im:
        assert im.n_frames == int(re.search(r"animation: (\d+) frames", out).group(1)) <= 40
    assert (folder / "sweep-report.html").is_file() and (folder / "sweep.png").is_file()
