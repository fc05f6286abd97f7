"""`cablesim history` and `free-vibration` take a spatial case's own out-of-plane channels."""

from __future__ import annotations

import pytest

SPATIAL = {
    "spatial": True,
    "cable": {"L": 300.0, "H": 20.0, "S": [130.0, 100.0, 110.0], "EA": 1.0e9, "masses": [8000.0, 14000.0]},
    "loads": {"F0": [300.0e3, 1100.0e3, 0.0, 450.0e3, 2000.0e3, 0.0],
              "FL": [-6.0e3, 22.0e3, 5.0e3, -18.0e3, 120.0e3, 5.0e3]},
    "damping": {"ratio": 0.01, "modes": [1, 2]},
    "history": {"omega": 2.4, "duration": 2.0, "channels": ["node1.w", "z6"]},
    "free_vibration": {"mode": 1, "peak_velocity": 0.1, "duration": 2.0, "channels": ["node2.w"]},
    "outputs": {"split": False},
}


@pytest.mark.parametrize("command", ["history", "free-vibration"])
def test_spatial_channels_are_accepted(command, invoke_cli, write_case, tmp_path):
    path = write_case(SPATIAL)
    res = invoke_cli(command, path, "--no-plot")
    assert res.returncode == 0, res.stdout + res.stderr
    res = invoke_cli(command, path, "--channels", "node2.w,z3", "--no-plot", "-o", tmp_path / "flag.h5")
    assert res.returncode == 0, res.stdout + res.stderr
