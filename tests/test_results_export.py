"""Stored results read back and taken away: ``cablesim.load_result`` (every kind of result
file), ``ResultFile.to_xarray``, ``cablesim export --format csv`` and ``cablesim rerun``.

Every check reads the HDF5 file itself with h5py (every dataset, visited) and compares the
numbers: the loaded arrays, the CSV files read back with the csv module, the xarray variables
and the rerun's datasets against the original's.
"""

from __future__ import annotations

import csv
import hashlib
import sys

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

import cablesim
from cablesim.cli import app
from cablesim.errors import CablesimError
from helpers_cli import assert_refused

#: One small run of each command (the paper's 2-node example, short durations).
RUNS = {
    "static": ["static", "--no-plot"],
    "history": ["history", "--duration", "4", "--no-plot"],
    "free-vibration": ["free-vibration", "--mode", "1", "--peak-velocity", "0.5", "--duration", "2", "--no-plot"],
    "sweep": ["sweep", "--omega", "2.0,3.0", "--duration", "20", "--window", "5", "--no-plot"],
    "continue": ["continue", "--set", "continuation={omega: {start: 2.0, stop: 2.1}, max_points: 8}", "--no-plot"],
    "backbone": ["backbone", "--set", "backbone={mode: 1, max_points: 6}", "--no-plot"],
}
KINDS = {"static": "static", "history": "history", "free-vibration": "history", "sweep": "sweep",
         "continue": "continuation", "backbone": "backbone"}


def cli(*args):
    res = CliRunner().invoke(app, [str(a) for a in args])
    return res.exit_code, res.stdout, res.stderr, res.exception


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("results")
    out = {}
    for name, args in RUNS.items():
        path = root / f"{name}.h5"
        res = cli(*args, "-o", path)
        assert res[0] == 0, res
        out[name] = path
    return out


def stored(path) -> dict:
    """Every dataset of an HDF5 file: path -> (values, units), strings decoded."""
    data = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            v = obj[()]
            if v.dtype.kind in "SO":
                v = np.array([x.decode() if isinstance(x, bytes) else str(x) for x in np.ravel(v)]).reshape(v.shape)
            data[name] = (np.asarray(v), obj.attrs.get("units", ""))

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return data


def same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind in "fc":
        return a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
    return a.shape == b.shape and np.array_equal(a, b)


@pytest.mark.parametrize("name", list(RUNS))
def test_load_result_reads_every_dataset_of_every_kind(files, name):
    r = cablesim.load_result(files[name])
    assert r.kind == KINDS[name] and r.command == name
    data = stored(files[name])
    assert set(r.arrays) == set(data)
    for path, (values, units) in data.items():
        assert same(r[path], values), path
        assert r.arrays[path].units == units and len(r.arrays[path].axes) == values.ndim
    assert r.case.cable.n_nodes == 2 and r.case.name == "paper-example"
    if r.kind == "history":
        assert same(r.data.z, data["history/z"][0]) and same(r.data.t, data["history/t"][0])
    if r.kind == "sweep":
        assert same(r.data.omega, data["sweep/omega"][0])
    if r.kind in ("continuation", "backbone"):
        assert isinstance(r.data, dict)


def _read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], list(zip(*rows[1:])) if len(rows) > 1 else [() for _ in rows[0]]


def _parse(cells, like: np.ndarray) -> np.ndarray:
    kind = like.dtype.kind
    if kind == "b":
        return np.array([c == "True" for c in cells], dtype=bool)
    if kind in "iu":
        return np.array([int(c) for c in cells], dtype=like.dtype)
    if kind == "f":
        return np.array([float(c) for c in cells])
    return np.array(cells, dtype=str)


@pytest.mark.parametrize("name", list(RUNS))
def test_exported_csv_reads_back_equal_to_the_hdf5_data(files, name, tmp_path):
    folder = tmp_path / "csv"
    res = cli("export", files[name], "--format", "csv", "-o", folder)
    assert res[0] == 0, res
    data = stored(files[name])
    index = {row[1]: row for row in csv.reader(open(folder / "index.csv"))}
    for path, (values, units) in data.items():
        header, columns = _read_csv(folder / (path.replace("/", "_") + ".csv"))
        dataset = path.rsplit("/", 1)[-1]
        suffix = f" ({units})" if units else ""
        if values.dtype.kind == "c":
            assert header[-2:] == [f"{dataset} real{suffix}", f"{dataset} imag{suffix}"]
            back = _parse(columns[-2], values.real) + 1j * _parse(columns[-1], values.real)
        else:
            assert header[-1] == f"{dataset}{suffix}", (path, header)
            back = _parse(columns[-1], values)
        assert len(header) == values.ndim + (2 if values.dtype.kind == "c" else 1)
        assert same(back.reshape(values.shape), values), path
        assert index["/" + path][4] == units
    if name == "history":  # the axis columns: time (s) and dof, one row per value, time first
        header, columns = _read_csv(folder / "history_z.csv")
        t, z = data["history/t"][0], data["history/z"][0]
        assert header == ["time (s)", "dof", "z (m)"]
        assert same(_parse(columns[0], t), np.repeat(t, z.shape[1]))
        assert same(_parse(columns[1], np.zeros(1, int)), np.tile(np.arange(1, z.shape[1] + 1), t.size))
    attrs = {(row[0], row[1]): row for row in csv.reader(open(folder / "attributes.csv"))}
    with h5py.File(files[name]) as f:
        assert attrs[("/", "command_line")][2] == f.attrs["command_line"]


def test_to_xarray_labels_time_dof_omega_and_channels(files):
    xr = pytest.importorskip("xarray")
    h = cablesim.load_result(files["history"]).to_xarray()
    data = stored(files["history"])
    assert isinstance(h, xr.Dataset)
    assert same(h["time"].values, data["history/t"][0]) and h["time"].attrs["units"] == "s"
    assert same(h["z"].sel(dof=4).values, data["history/z"][0][:, 3]) and h["z"].attrs["units"] == "m"
    assert same(h["T"].sel(segment=2).values, data["history/T"][0][:, 1])
    assert h.attrs["command_line"].startswith("cablesim history")
    s = cablesim.load_result(files["sweep"]).to_xarray()
    sw = stored(files["sweep"])
    assert list(s["channel"].values) == ["z2", "z4"]
    assert same(s["amplitude"].sel(channel="z4").values, sw["sweep/amplitude"][0][:, 1])
    assert same(s["omega"].values, sw["sweep/omega"][0])
    modal = cablesim.load_result(files["static"]).to_xarray("modal")
    with h5py.File(files["static"]) as f:
        assert same(modal["shapes"].sel(mode=1).values, f["modal/shapes"][:, 0])


def test_to_xarray_without_xarray_says_how_to_install_it(files, monkeypatch):
    monkeypatch.setitem(sys.modules, "xarray", None)  # import xarray now fails
    with pytest.raises(CablesimError, match=r"pip install 'cablesim\[xarray\]'"):
        cablesim.load_result(files["history"]).to_xarray()


def test_export_refuses_other_folders_and_files(files, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    assert_refused(cli("export", files["static"], "-o", tmp_path / "mine"), tmp_path, "mine", "not a cablesim CSV export")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"
    (tmp_path / "x.h5").write_text("not hdf5")
    res = cli("export", tmp_path / "x.h5")
    assert res[0] == 2 and "not an HDF5 file" in " ".join(res[2].split())  # however the long path wraps


def _digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize("name", ["static", "history", "sweep"])
def test_rerun_writes_beside_the_original_and_its_data_equal_the_originals(files, name):
    original = files[name]
    before = _digest(original)
    res = cli("rerun", original)
    assert res[0] == 0, res
    again = original.with_name(f"{original.stem}-rerun.h5")
    assert again.is_file() and _digest(original) == before  # beside it, the original untouched
    a, b = stored(original), stored(again)
    timing = {"sweep/wall"}  # seconds each point took: the only dataset a rerun may change
    assert set(a) == set(b)
    for path in set(a) - timing:
        assert same(a[path][0], b[path][0]), path
    with h5py.File(original) as f, h5py.File(again) as g:
        assert g.attrs["command"] == f.attrs["command"] and g.attrs["case_yaml"] == f.attrs["case_yaml"]
        assert g.attrs["command_line"].startswith(f"cablesim {name} {again.with_suffix('.case.yaml')}")
    assert cablesim.load_result(again).case == cablesim.load_result(original).case


def test_rerun_never_replaces_a_file(files, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    original = files["free-vibration"]
    assert cli("rerun", original)[0] == 0
    assert cli("rerun", original)[0] == 0
    first, second = (original.with_name(f"{original.stem}-rerun{k}.h5") for k in ("", "2"))
    assert first.is_file() and second.is_file()
    assert same(stored(first)["history/z"][0], stored(second)["history/z"][0])
    before = _digest(original)
    assert_refused(cli("rerun", original, "-o", original), tmp_path, "never replaces it")
    assert _digest(original) == before
    out = tmp_path / "chosen.h5"
    assert cli("rerun", original, "-o", out)[0] == 0 and same(stored(out)["history/z"][0], stored(original)["history/z"][0])


def _readme_section() -> str:
    from conftest import REPO

    text = (REPO / "README.md").read_text()
    return text[text.index("### Stored results"):text.index("## Python API")]


def test_readme_results_examples_run(tmp_path, monkeypatch, capsys):
    import re
    import shlex

    monkeypatch.chdir(tmp_path)
    section = _readme_section()
    for line in re.search(r"```sh\n(.*?)```", section, re.S).group(1).splitlines():
        words = shlex.split(line, comments=True)
        assert words[0] == ".venv/bin/cablesim"
        res = cli(*words[1:])
        assert res[0] == 0, (line, res)
    assert (tmp_path / "runs/demo/history-csv/history_z.csv").is_file()
    a, b = stored(tmp_path / "runs/demo/history.h5"), stored(tmp_path / "runs/demo/history-rerun.h5")
    assert all(same(a[k][0], b[k][0]) for k in a)
    exec(compile(re.search(r"```python\n(.*?)```", section, re.S).group(1), "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "history (" in out and "('time', 'dof')" in out


def test_a_run_of_the_api_gives_the_same_dataset_as_its_file(tmp_path):
    xr = pytest.importorskip("xarray")
    case = cablesim.load_case(None)
    run = cablesim.history(case, duration=2.0)
    ds = run.to_xarray()
    assert isinstance(ds, xr.Dataset) and ds["z"].dims == ("time", "dof")
    np.testing.assert_array_equal(ds["z"].values, run.history.z)
    np.testing.assert_array_equal(ds["time"].values, run.history.t)
    from_file = cablesim.load_result(run.to_hdf5(tmp_path / "h.h5")).to_xarray()
    xr.testing.assert_equal(ds, from_file)  # values, axes and coordinates (attributes aside: the times differ)


def test_rerun_refuses_a_file_without_a_command_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = cablesim.static(cablesim.load_case(None)).to_hdf5(tmp_path / "api.h5")  # the API records no command
    assert_refused(cli("rerun", path), tmp_path, "records no command line", keep=(path,))


def test_the_api_exports_and_reruns_like_the_command_line(files, tmp_path):
    original = files["history"]
    written = cablesim.export_csv(original, tmp_path / "api-csv")
    assert {p.name for p in written} >= {"history_z.csv", "index.csv", "attributes.csv"}
    header, columns = _read_csv(tmp_path / "api-csv" / "history_z.csv")
    z = stored(original)["history/z"][0]
    assert header[-1] == "z (m)" and same(_parse(columns[-1], z).reshape(z.shape), z)
    again = cablesim.rerun(original, tmp_path / "api-rerun.h5")
    assert again.path == tmp_path / "api-rerun.h5" and again.kind == "history"
    a, b = stored(original), stored(again.path)
    assert set(a) == set(b) and all(same(a[k][0], b[k][0]) for k in a)
    with pytest.raises(cablesim.errors.CablesimError, match="never replaces"):
        cablesim.rerun(original, original)


def test_the_runs_of_the_api_return_their_figures():
    """The runs' plot methods wrote PNGs only; a notebook wants the figures themselves."""
    import matplotlib.figure

    case = cablesim.load_case(None)
    static = cablesim.static(case)
    figs = static.figures()
    assert figs and all(isinstance(f, matplotlib.figure.Figure) for f in figs)
    # the cable drawn is the static shape of the run (the first figure: the cable under F0)
    y = static.result.exact.y
    drawn = [line.get_xydata() for ax in figs[0].axes for line in ax.get_lines() if len(line.get_xydata()) == y.size // 2 + 2]
    assert any(np.allclose(xy[1:-1].ravel(), y) for xy in drawn)
    history = cablesim.history(case, duration=5.0)
    titles = [t.get_text() for f in history.figures() for t in f.texts]
    assert len(history.figures()) >= 3 and any(case.name in t for t in titles)
