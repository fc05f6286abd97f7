"""Frequency sweeps, the driver: hysteresis of up/down sweeps (with a gamma axis), chains that
meet a failed point, settings errors, the Dask backend and the HDF5 layout.

Every case is the paper example with its ``sweep:`` section replaced (``helpers_sweep``). Sweeps
run in-process (small grids); the Dask checks run a local cluster, one of them through the real
command in a subprocess. Steady-state detection is in ``test_steady.py``, the journal and
``--resume`` in ``test_sweep_journal.py``; the layout checks here read the session sweeps
``linear`` and ``late`` (``conftest.py``).

Measured on this model (exact analysis): gamma = 5, xi = 0.01: up and down sweeps differ between
2.2 and 2.3 rad/s (e.g. |z2| = 4.3 m up vs 30.1 m down at 2.2 rad/s); they agree to 1e-4 at
2.0-2.1 and 2.4-2.7 rad/s.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from cablesim.case import parse_case
from cablesim.errors import CablesimError
from helpers_sweep import (
    LIN_GAMMA,
    LIN_W,
    PER_CHANNEL,
    UNITS,
    assert_same_results,
    case_text,
    do_sweep,
    finish_cli,
    read_sweep,
    run_sweep,
    start_cli,
)


# ----------------------------------------------------------------------------------------------
# 1. Up and down sweeps across a jump (softening)
# ----------------------------------------------------------------------------------------------
HYST_W = [2.0, 2.1, 2.2, 2.25, 2.3, 2.35, 2.4, 2.5, 2.6, 2.7]
HYST_SWEEP = {"omega": HYST_W, "duration": 1500.0, "direction": "both", "channels": ["z2", "z4"], "gamma": [5.0]}


@pytest.fixture(scope="module")
def hysteresis(wdir):
    out = wdir / "both.h5"
    _, _, res = do_sweep(out, HYST_SWEEP)
    return res, out


def test_up_and_down_sweeps_differ_across_the_jump(hysteresis):
    res, _ = hysteresis
    assert [(c.gamma_index, c.direction) for c in res.curves] == [(0, "up"), (0, "down")]
    up, down = res.data[0], res.data[1]
    for d in (up, down):
        assert d["done"].all() and d["steady"].all() and np.all(d["period"] == 1), d
    a_up, a_down = up["amplitude"][:, 0], down["amplitude"][:, 0]
    w = np.array(HYST_W)
    inside = (w >= 2.19) & (w <= 2.31)  # 2.2, 2.25, 2.3
    far = (w <= 2.11) | (w >= 2.39)
    # hysteresis: the down sweep stays on the large branch, the up sweep on the small one
    assert np.all(a_down[inside] > 2.5 * a_up[inside]), (a_up, a_down)
    assert a_down[w == 2.2][0] > 5.0 * a_up[w == 2.2][0]
    # far from the resonance both reach the same (unique) orbit
    np.testing.assert_allclose(a_up[far], a_down[far], rtol=1e-3)
    # softening: the up sweep jumps up between 2.3 and 2.35 rad/s
    j = int(np.flatnonzero(w == 2.3)[0])
    assert a_up[j + 1] > 2.5 * a_up[j]


def test_chain_does_not_continue_from_a_failed_point(wdir):
    # gamma = 10: the cable goes slack (a segment shorter than its natural length) at 2.15 rad/s,
    # which with slack: stop fails the point
    sweep = {"omega": [2.15, 2.2, 2.3], "duration": 600.0, "window": 100.0, "direction": "up",
             "channels": ["z2", "z4"], "gamma": [10.0]}
    _, _, res = do_sweep(wdir / "slack.h5", sweep, n_jobs=1, slack="stop")
    d = res.data[0]
    assert not d["steady"][0] and 0.0 < d["t_end"][0] < 600.0  # the slack failure itself
    # every later point must have been integrated, not copied from the failed state
    assert np.all(d["t_end"][1:] > 0.0), (d["t_end"], d["amplitude"])



# ----------------------------------------------------------------------------------------------
# 2. Bad sweep settings
# ----------------------------------------------------------------------------------------------
GOOD = {"omega": [2.0, 3.0], "duration": 300.0, "window": 100.0}
BAD_SETTINGS = {
    "empty list": ({"omega": []}, "sweep.omega", "empty"),
    "empty grid": ({"omega": {"start": 1.0, "stop": 2.0, "num": 0}}, "sweep.omega", "num"),
    "negative list": ({"omega": [-1.0, 2.0]}, "sweep.omega", "positive"),
    "negative grid": ({"omega": {"start": -1.0, "stop": 2.0, "num": 5}}, "sweep.omega", "start"),
    "zero frequency": ({"omega": [0.0, 2.0]}, "sweep.omega", "positive"),
    "reversed grid": ({"omega": {"start": 3.0, "stop": 2.0, "num": 5}}, "sweep.omega", "greater than start"),
    "window > duration": ({"duration": 100.0, "window": 200.0}, "sweep.window", "longer than"),
    "unknown direction": ({"direction": "sideways"}, "sweep.direction", "sideways"),
    "gamma zero": ({"gamma": [0.0]}, "sweep.gamma", "positive"),
}


def _check_user_error(res, *needles):
    assert res.returncode == 2, (res.stdout, res.stderr, res.exception)
    assert isinstance(res.exception, SystemExit), res.exception  # anything else: a traceback
    assert "Traceback" not in res.stderr
    assert "error:" in res.stderr
    flat = " ".join(res.stderr.split())
    for n in needles:
        assert n in flat, (n, res.stderr)


@pytest.mark.parametrize("label", list(BAD_SETTINGS))
def test_bad_sweep_settings_are_clear_errors(label, invoke_cli, write_case):
    change, field, hint = BAD_SETTINGS[label]
    write_case(case_text(dict(GOOD, **change)))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--no-plot"), field, hint)


def test_case_without_sweep_section(invoke_cli, write_case, tmp_path):
    write_case(case_text(None))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--no-plot"), "sweep:")
    case = parse_case(case_text(None))
    with pytest.raises(CablesimError) as err:
        run_sweep(case, case_text(None), tmp_path / "x.h5")
    assert err.value.field == "sweep"


def test_bad_command_line_flags(invoke_cli, write_case, tmp_path):
    write_case(case_text(GOOD))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "0"), "--jobs")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "-3"), "--jobs")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--resume", "--no-plot"), "resume", "out.h5.journal")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--backend", "dask", "--no-plot"), "--scheduler")
    assert not (tmp_path / "out.h5").exists()


def test_resume_of_a_complete_sweep(invoke_cli, write_case, tmp_path):
    write_case(case_text(dict(GOOD, omega=[3.0])))
    res = invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "1", "--no-plot")
    assert res.returncode == 0, res.stderr
    before = (tmp_path / "out.h5").read_bytes()
    again = invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--resume", "--no-plot")
    assert again.returncode == 0, again.stderr  # a finished sweep: nothing to do, not an error
    assert "Nothing to do" in again.stdout and "complete" in again.stdout
    assert (tmp_path / "out.h5").read_bytes() == before


def test_settings_error_leaves_no_journal(invoke_cli, write_case, tmp_path):
    write_case(case_text(GOOD))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--backend", "dask", "--no-plot"), "--scheduler")
    assert not (tmp_path / "out.h5.journal").exists()



# ----------------------------------------------------------------------------------------------
# 3. Dask backend
# ----------------------------------------------------------------------------------------------
DASK_SWEEP = {"omega": [2.0, 3.0, 4.0], "duration": 600.0, "window": 100.0, "channels": ["z2", "z4"]}


@pytest.fixture(scope="module")
def dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        yield cluster
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def dask_reference(wdir):
    text = case_text(DASK_SWEEP)
    out = wdir / "dask-local.h5"
    run_sweep(parse_case(text), text, out, n_jobs=1)
    return text, read_sweep(out)


def test_dask_backend_matches_local(wdir, dask_cluster, dask_reference):
    """In-process through run_sweep's own Dask set-up."""
    text, ref = dask_reference
    out = wdir / "dask.h5"
    res = run_sweep(parse_case(text), text, out, backend="dask", scheduler=dask_cluster.scheduler_address)
    assert res.complete
    assert_same_results(read_sweep(out), ref)
    assert not out.with_name(out.name + ".journal").exists()


def test_dask_backend_from_the_command_line(tmp_path, dask_cluster, dask_reference):
    text, ref = dask_reference
    (tmp_path / "case.yaml").write_text(text)
    code, _, stderr = finish_cli(start_cli(
        ["sweep", "case.yaml", "-o", "out.h5", "--no-plot", "--backend", "dask", "--scheduler", dask_cluster.scheduler_address],
        tmp_path,
    ))
    assert code == 0 and "Traceback" not in stderr, stderr[-2000:]
    assert_same_results(read_sweep(tmp_path / "out.h5"), ref)



# ----------------------------------------------------------------------------------------------
# 4. HDF5 layout
# ----------------------------------------------------------------------------------------------
def _check_group(g: h5py.Group, lead: tuple, C: int) -> None:
    for name, unit in UNITS.items():
        assert name in g, name
        ds = g[name]
        assert ds.attrs["units"] == unit, (name, ds.attrs["units"])
        shape = (*lead, C) if name in PER_CHANNEL else lead
        assert ds.shape == shape, (name, ds.shape, shape)
    assert g["done"].dtype == bool and g["steady"].dtype == bool
    assert np.issubdtype(g["period"].dtype, np.integer)
    assert g["done"][()].all()


def test_layout_independent_without_gamma(late):
    _, out = late
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        assert "gamma" not in g and "up" not in g and "down" not in g
        np.testing.assert_array_equal(g["omega"][()], [5.0, 5.05])
        assert g["omega"].attrs["units"] == "rad/s"
        _check_group(g, (2,), 2)
        assert [c.decode() for c in g.attrs["channels"]] == ["z2", "z4"]
        assert g.attrs["direction"] == "independent" and g.attrs["complete"]
        assert g.attrs["cap"] == 4000.0 and g.attrs["floquet_check"]
        assert f["modal/omega"].attrs["units"] == "rad/s"
        assert f["modal/omega"][0] == pytest.approx(2.524, abs=1e-3)
        assert f.attrs["command"] == "sweep"
        assert "sweep:" in f.attrs["case_yaml"]


def test_layout_with_gamma_axis(linear):
    _, res, out = linear
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        np.testing.assert_array_equal(g["gamma"][()], LIN_GAMMA)
        assert g["gamma"].attrs["units"] == "1"
        _check_group(g, (2, len(LIN_W)), 4)
        np.testing.assert_array_equal(g["amplitude"][1], res.data[1]["amplitude"])
        assert [c.decode() for c in g.attrs["channels"]] == ["z1", "z2", "z3", "z4"]


def test_layout_both_directions(hysteresis):
    res, out = hysteresis
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        assert g.attrs["direction"] == "both"
        assert "amplitude" not in g  # results live under up/ and down/
        np.testing.assert_array_equal(g["omega"][()], HYST_W)
        for k, sub in enumerate(("up", "down")):
            _check_group(g[sub], (1, len(HYST_W)), 2)  # gamma given: leading G = 1 axis
            np.testing.assert_array_equal(g[sub]["amplitude"][0], res.data[k]["amplitude"])
        assert "omega" in f["modal"]
