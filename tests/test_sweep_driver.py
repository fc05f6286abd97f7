"""The sweep driver: sizes from the cable (not from the modes kept), the statics solved once
and handed to the workers, a point as one typed record from worker to file, and the worker
pool started only when it pays."""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from cablesim import api
from cablesim.analyses import pool
from cablesim.analyses.sweep_points import BadRecord, SweepPoint

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "paper-example.yaml"
HEAVY = REPO / "configs" / "heavy-span.yaml"


def _amplitudes(path: Path) -> np.ndarray:
    with h5py.File(path) as f:
        return f["sweep/amplitude"][()]


def test_a_sweep_keeping_two_modes_completes_and_agrees_with_every_mode(invoke_cli, tmp_path):
    """`--set modal.modes=2` ended in a traceback: the per-point arrays were sized from the
    number of modal frequencies (3 kept: the lowest 2 and the highest), not from the cable."""
    args = ["sweep", EXAMPLE, "--omega", "1,2", "--duration", "100", "--set", "sweep.window=50", "--jobs", "1",
            "--no-plot"]
    few = invoke_cli(*args, "--set", "modal.modes=2", "-o", "few.h5")
    assert few.returncode == 0 and few.exception is None, (few.stderr, few.exception)
    every = invoke_cli(*args, "-o", "every.h5")
    assert every.returncode == 0, every.stderr
    with h5py.File(tmp_path / "few.h5") as f:
        assert f["modal/omega"].size == 3  # the two modes asked for and the example's free_vibration.mode 3
        assert f["sweep/multipliers"].shape == (2, 8) and f["sweep/peak_tension"].shape == (2, 3)
    np.testing.assert_allclose(_amplitudes(tmp_path / "few.h5"), _amplitudes(tmp_path / "every.h5"), rtol=1e-9)


@pytest.mark.slow  # the two-modes sweep above keeps the sizing rule in `make test`
def test_a_sweep_of_301_nodes_completes_and_agrees_with_every_mode(tmp_path):
    """Above 300 nodes only the lowest 100 modes are kept by default: every such sweep failed."""
    base = ["cable.nodes=301", "sweep={omega: [2.3], duration: 3.0, window: 1.5, channels: [node20.v, node150.v]}"]
    default = api.sweep(api.load_case(HEAVY, base), jobs=1, output=tmp_path / "default.h5").result
    every = api.sweep(api.load_case(HEAVY, [*base, "modal.modes=602"]), jobs=1).result
    assert default.modal_omega.size == 100 and every.modal_omega.size == 602
    a, b = default.table(0), every.table(0)
    assert a.done.all() and a.peak_tension.shape == (1, 302) and a.multipliers.shape == (1, 1204)
    np.testing.assert_allclose(a.amplitude, b.amplitude, rtol=1e-9)
    # the default scheme controls its error, and its first step follows the highest frequency it
    # is given: the two runs agree to the scheme's accuracy (measured 6e-8 in the tensions)
    np.testing.assert_allclose(a.peak_tension, b.peak_tension, rtol=1e-6)


def test_the_statics_are_solved_once_per_sweep_and_never_in_a_worker(monkeypatch, tmp_path):
    """The driver solved the statics three times, and every worker once more."""
    from cablesim.analyses import sweep as sweep_module

    calls = tmp_path / "calls.txt"
    real = sweep_module.run_static

    def counted(*args, **kwargs):
        with open(calls, "a") as f:
            f.write("x\n")
        return real(*args, **kwargs)

    monkeypatch.setattr(sweep_module, "run_static", counted)
    monkeypatch.setattr(pool, "choose_workers", lambda requested, work, points, method=None: 2)
    case = api.load_case(None, ["sweep.omega=[1.0, 2.0, 3.0, 4.0]", "sweep.duration=200", "sweep.window=50"])
    api.sweep_cost(case)  # as the command line does: the estimate, then the sweep
    res = api.sweep(case, jobs=2).result
    assert res.complete and res.settings["workers"] == 2
    assert calls.read_text().count("x") == 1


def test_a_point_travels_as_one_record_and_its_journal_form_reads_back():
    case = api.load_case(None, ["sweep.omega=[2.0]", "sweep.duration=200", "sweep.window=50", "sweep.channels=[z2, z4]"])
    res = api.sweep(case, jobs=1).result
    (point,) = res.points.values()
    assert isinstance(point, SweepPoint) and point.decided in ("integrated", "shooting")
    back = SweepPoint.from_json(point.to_json(), n_channels=2, n_dof=4)
    assert back.to_json() == point.to_json()
    assert back.final_state == point.final_state and back.multipliers == point.multipliers
    table = res.table(0)
    assert table.amplitude[0].tolist() == list(point.amplitude) and table["period"][0] == point.period
    with pytest.raises(BadRecord, match="final state is not a list of 12 numbers"):
        SweepPoint.from_json(dict(point.to_json(), final_state=[0.0] * 3), n_channels=2, n_dof=4)
    with pytest.raises(BadRecord, match="per-channel values are not 3 numbers"):
        SweepPoint.from_json(point.to_json(), n_channels=3, n_dof=4)
    assert math.isnan(SweepPoint.from_json(dict(point.to_json(), floquet=None), 2, 4).floquet)


def test_the_pool_starts_only_when_the_work_pays_for_it(monkeypatch):
    """A 2-point sweep took 8.4 s with the default --jobs against 0.21 s with --jobs 1."""
    monkeypatch.setattr(pool, "cores", lambda: 2)
    for method in ("fork", "loky"):
        assert pool.choose_workers(-1, work_seconds=0.05, points=2, method=method) == 1  # two quick points
        assert pool.choose_workers(-1, work_seconds=600.0, points=56, method=method) == 2
        assert pool.choose_workers(1, work_seconds=600.0, points=56, method=method) == 1  # --jobs 1
        assert pool.choose_workers(-1, work_seconds=600.0, points=1, method=method) == 1  # one point at a time
    # a loky worker imports the package and loads the kernels first: it must save more
    assert pool.choose_workers(-1, work_seconds=5.0, points=56, method="fork") == 2
    assert pool.choose_workers(-1, work_seconds=5.0, points=56, method="loky") == 1
