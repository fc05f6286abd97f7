"""Reproducible records: every HDF5 file says which command line, options, versions, platform and
commit produced it, and the units of its group attributes; default names encode parameters."""

from __future__ import annotations

import json
import platform
import sys

import h5py
import numpy as np
import pytest

from helpers_cli import EXAMPLE

VERSIONS = ("python_version", "numpy_version", "scipy_version", "numba_version", "h5py_version", "cablesim_version")


def _root(path):
    with h5py.File(path) as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def _units(path, group):
    with h5py.File(path) as f:
        return json.loads(f[group].attrs["units"])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A static, a history and a sweep file written by the command line, in-process."""
    from typer.testing import CliRunner

    from cablesim.cli import app

    root = tmp_path_factory.mktemp("prov")
    case = root / "case.yaml"
    case.write_text(EXAMPLE.replace("omega: {start: 0.5, stop: 6.0, num: 56}", "omega: [3.0]")
                    .replace("duration: 3000.0", "duration: 300.0").replace("window: 200.0", "window: 100.0"))
    runner = CliRunner()
    import os

    old = os.getcwd()
    os.chdir(root)
    try:
        for args in (["static", "case.yaml", "--no-plot", "-o", "s.h5", "--set", "damping.ratio=0.02"],
                     ["history", "case.yaml", "--omega", "2.4", "--duration", "5", "--no-plot"],
                     ["free-vibration", "case.yaml", "--mode", "3", "--peak-velocity", "1", "--duration", "2", "--no-plot"],
                     ["sweep", "case.yaml", "--no-plot", "--jobs", "1", "-o", "w.h5"]):
            res = runner.invoke(app, args)
            assert res.exit_code == 0, res.stderr
    finally:
        os.chdir(old)
    return {"static": root / "s.h5", "history": root / "runs/case/history-w2.4-d5.h5",
            "free-vibration": root / "runs/case/free-vibration-mode3-v1.h5", "sweep": root / "w.h5"}


@pytest.mark.parametrize("kind", ["static", "history", "free-vibration", "sweep"])
def test_every_file_records_the_command_line_options_versions_platform_and_commit(files, kind):
    attrs = _root(files[kind])
    assert attrs["command_line"].startswith(f"cablesim {kind} case.yaml")
    options = json.loads(attrs["options"])
    assert options["case_file"] == "case.yaml" and "output" in options
    assert attrs["python_version"] == platform.python_version()
    for key in VERSIONS:
        assert attrs[key] and attrs[key] != "not installed", key
    assert attrs["numpy_version"] == np.__version__ and attrs["h5py_version"] == h5py.__version__
    assert attrs["platform"] == platform.platform()
    assert len(attrs["git_commit"].split("-")[0]) == 40  # the tests run from a git checkout


def test_options_hold_the_effective_values(files):
    options = json.loads(_root(files["history"])["options"])
    assert options["omega"] == 2.4 and options["duration"] == 5.0 and options["plot"] is False
    assert options["integrator"]["name"] == "dopri5" and options["integrator"]["rtol"] == 1e-8
    assert options["output_step"] > 0
    assert json.loads(_root(files["static"])["options"])["overrides"] == ["damping.ratio=0.02"]
    assert "--set damping.ratio=0.02" in _root(files["static"])["command_line"]


def test_group_attributes_carry_their_units(files):
    assert _units(files["static"], "modal") == {"a0": "1/s", "a1": "s", "sole_inextensible_omega": "rad/s",
                                                "modes_computed": "1", "omega_max": "rad/s"}
    assert _units(files["static"], "static/approximate") == {"omega_c": "J", "omega_e": "J"}
    hist = _units(files["history"], "history")
    assert hist["omega"] == "rad/s" and hist["t_stop"] == "s" and hist["duration"] == "s" and hist["a1"] == "s"
    sweep = _units(files["sweep"], "sweep")
    assert sweep["cap"] == "s" and sweep["window"] == "s" and sweep["max_period"] == "forcing periods"


def test_default_names_encode_the_parameters(files):
    assert files["history"].is_file() and files["free-vibration"].is_file()


def test_the_api_writes_the_environment_too(tmp_path):
    import cablesim

    path = cablesim.static(cablesim.load_case()).to_hdf5(tmp_path / "api.h5")
    attrs = _root(path)
    assert attrs["python_version"] == sys.version.split()[0] and "command_line" in attrs
