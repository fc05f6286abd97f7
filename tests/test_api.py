"""The Python API: the README's example runs, and each run writes what the command writes."""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest

import cablesim
from cablesim.dynamics.status import Status
from cablesim.errors import CablesimError

README = Path(__file__).resolve().parents[1] / "README.md"


def _readme_example() -> str:
    text = README.read_text()
    section = text[text.index("## Python API"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(_readme_example(), "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "completed" in out
    with h5py.File(tmp_path / "runs" / "api-example" / "history.h5") as f:
        assert f.attrs["command"] == "history" and f["history/z"].shape[1] == 4


def test_import_is_light():
    """`import cablesim` does not load numba, scipy, h5py or matplotlib."""
    import subprocess
    import sys

    code = "import sys, cablesim; print(sorted(m for m in ('numba', 'scipy', 'h5py', 'matplotlib') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_load_case_from_dict_equals_file():
    a = cablesim.load_case()
    data = a.model_dump(exclude_none=True)
    b = cablesim.load_case(data)
    assert b.model_dump() == a.model_dump() and "cable:" in b.text
    with pytest.raises(CablesimError, match="cable"):
        cablesim.load_case({"loads": {"F0": [1.0, 2.0]}})


def test_runs_write_the_files_the_cli_writes(tmp_path, invoke_cli):
    case = cablesim.load_case()
    st = cablesim.static(case)
    a = st.to_hdf5(tmp_path / "api.h5")
    res = invoke_cli("static", "-o", tmp_path / "cli.h5", "--no-plot")
    assert res.returncode == 0, res.stderr
    with h5py.File(a) as fa, h5py.File(tmp_path / "cli.h5") as fb:
        for name in ("static/exact/y", "static/exact/T", "modal/omega"):
            np.testing.assert_array_equal(fa[name][()], fb[name][()])
        assert fa.attrs["case_yaml"] == fb.attrs["case_yaml"]


def test_history_status_is_data():
    case = cablesim.load_case(None, overrides=["loads.FL=[-60e3, 220e3, -180e3, 1200e3]", "slack=stop"])
    h = cablesim.history(case, omega=2.4, duration=200.0)
    assert h.history.status is Status.SLACK and not h.history.completed
    assert h.history.t_stop is not None and abs(h.history.t[-1] - h.history.t_stop) < 0.2
    assert "segment" in h.history.message
