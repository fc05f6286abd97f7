"""HDF5 files (cablesim.io.hdf5, cablesim.io.sweeps): write/read round trips and atomic writes.

The expectations are independent of the readers: a result is written and read back, and what
comes back is compared with the object that was written (arrays bit for bit), or with values
chosen here by hand (a stopped history built from random arrays, a partly computed sweep filled
with hand-made point records); the files are also opened with h5py directly.

- time histories: a completed run (all DOF, and a subset of DOF) and stopped ones built by hand
  with every non-completed :class:`~cablesim.dynamics.status.Status`;
- sweeps: tiny real sweeps of the example (independent; up/down with a gamma axis) and partly
  computed ones built by hand (both directions with two gammas, a single down sweep, one gamma);
- ``atomic_h5``: no ``.part`` file is left behind, and a body that raises keeps the old file;
- every dataset of every writer carries a ``units`` attribute.
"""

from __future__ import annotations

from dataclasses import replace

import h5py
import numpy as np
import pytest

from cablesim import api
from cablesim.analyses.sweep import new_sweep_result
from cablesim.analyses.sweep_points import SweepPoint
from cablesim.dynamics.result import HistoryResult
from cablesim.dynamics.status import Status
from cablesim.io.hdf5 import atomic_h5, read_history, write_history, write_static
from cablesim.io.sweeps import read_sweep, write_sweep

#: Overrides that make the example's sweep tiny (3 points of 60 s).
TINY = ["sweep.omega.num=3", "sweep.duration=60", "sweep.window=20"]
HISTORY_ARRAYS = ("t", "z", "v", "zc", "ze", "T", "residual", "y0", "T0", "modal_omega")


def same_bits(a, b) -> bool:
    """Same dtype, shape and bytes (so -0.0 differs from 0.0, and NaN payloads count)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def datasets_without_units(path) -> list[str]:
    """Every dataset of the file that lacks a non-empty ``units`` attribute."""
    bad = []
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                units = obj.attrs.get("units")
                if isinstance(units, bytes):
                    units = units.decode()
                if not isinstance(units, str) or not units:
                    bad.append(name)

        f.visititems(visit)
    return bad


def count_datasets(path) -> int:
    n = []
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: n.append(name) if isinstance(obj, h5py.Dataset) else None)
    return len(n)


@pytest.fixture(scope="module")
def h5dir(tmp_path_factory):
    return tmp_path_factory.mktemp("hdf5")


# ----------------------------------------------------------------------------------------------
# 1. Time histories
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def completed_history(paper):
    hist = api.history(paper, omega=2.4, duration=5.0).history
    assert hist.completed and hist.status is Status.COMPLETED and hist.t_stop is None
    assert hist.zc is not None and hist.dof is None
    return hist


def stopped_history(status: Status) -> HistoryResult:
    """A free vibration of a 3-node cable that stopped at 1.2345 s, only DOF 2 and 5 kept, no
    split: random arrays with a few awkward values (-0.0, a subnormal, huge numbers)."""
    rng = np.random.default_rng(int(status))
    m = 13
    t = np.linspace(0.0, 1.2, m)
    z = rng.normal(scale=0.3, size=(m, 2))
    z[0] = [-0.0, 5e-324]
    v = rng.normal(size=(m, 2))
    v[-1, 1] = 1.0e300
    T = rng.uniform(1.0e3, 1.0e6, size=(m, 4))
    residual = rng.uniform(0.0, 1.0e-9, size=m)
    y0 = np.array([10.0, 3.0, 20.0, 4.5, 30.0, 2.0]) + rng.normal(scale=1e-3, size=6)
    T0 = rng.uniform(1.0e5, 1.0e6, size=4)
    return HistoryResult(
        t=t, z=z, v=v, zc=None, ze=None, T=T, residual=residual, y0=y0, T0=T0, omega=None,
        analysis="approximate", integrator="newmark", status=status,
        message=f"stopped at t = 1.2345 s: {status.text}; reduce the step", t_stop=1.2345,
        modal_omega=np.array([2.5, 13.0, 0.1 + 0.2]),
        settings={"integrator_dt": 0.01, "mode": 3, "peak_velocity": 1.5, "dt_max": np.inf, "note": "by hand"},
        dof=(2, 5),
    )


def check_history_round_trip(path, hist: HistoryResult, command: str) -> HistoryResult:
    write_history(path, hist, "# case text\n", command)
    assert not path.with_name(path.name + ".part").exists()
    back = read_history(path)
    for name in HISTORY_ARRAYS:
        a, b = getattr(hist, name), getattr(back, name)
        if a is None:
            assert b is None, name
        else:
            assert same_bits(a, b), name
    assert back.status is hist.status
    assert back.completed == hist.completed
    assert back.message == hist.message
    assert back.t_stop == hist.t_stop  # None, or the very same float
    assert back.dof == hist.dof
    assert back.dof_numbers == hist.dof_numbers
    assert back.omega == hist.omega
    assert (back.analysis, back.integrator) == (hist.analysis, hist.integrator)
    assert back.settings == hist.settings
    # and in the file itself
    with h5py.File(path, "r") as f:
        g = f["history"]
        assert g.attrs["status_code"] == int(hist.status)
        assert bool(g.attrs["completed"]) == hist.completed
        assert list(g["dof"][()]) == list(hist.dof_numbers)
        assert f.attrs["command"] == command
        assert ("zc" in g) == (hist.zc is not None)
    return back


@pytest.mark.parametrize("keep", [None, (2, 4)], ids=["all-dof", "dof-2-4"])
def test_completed_history_round_trip(h5dir, completed_history, keep):
    hist = completed_history if keep is None else completed_history.keep(keep)
    back = check_history_round_trip(h5dir / f"history-{keep is None}.h5", hist, "history")
    assert back.status is Status.COMPLETED and back.t_stop is None and back.omega == 2.4
    assert back.dof == keep


@pytest.mark.parametrize("status", [s for s in Status if s is not Status.COMPLETED], ids=lambda s: s.name.lower())
def test_stopped_history_round_trip(tmp_path, status):
    hist = stopped_history(status)
    back = check_history_round_trip(tmp_path / "stopped.h5", hist, "free-vibration")
    assert back.status is status and not back.completed
    assert back.t_stop == 1.2345
    assert back.omega is None
    assert back.dof == (2, 5) and back.zc is None and back.ze is None
    assert np.signbit(back.z[0, 0]) and back.z[0, 1] == 5e-324


# ----------------------------------------------------------------------------------------------
# 2. Sweeps
# ----------------------------------------------------------------------------------------------
def stored_curve(stored, gamma, direction):
    found = [c for c in stored.curves if c.gamma == gamma and c.direction == direction]
    assert len(found) == 1, (gamma, direction, [(c.gamma, c.direction) for c in stored.curves])
    return found[0]


def gamma_of(res, curve):
    return None if res.gamma is None else float(res.gamma[curve.gamma_index])


def check_sweep_file(path, res, expected: dict) -> None:
    """Read the file back (cablesim.io.sweeps.read_sweep and h5py) and compare with
    ``expected[k][field]`` for every curve k of ``res``."""
    stored = read_sweep(path)
    assert same_bits(stored.omega, res.omega)
    assert stored.direction == res.direction
    assert stored.channels == res.channels
    assert stored.analysis == res.analysis
    assert (stored.gamma is None) == (res.gamma is None)
    if res.gamma is not None:
        assert same_bits(stored.gamma, res.gamma)
    assert same_bits(stored.modal, np.sort(res.modal_omega))
    assert stored.attrs["cap"] == res.settings["cap"] and stored.attrs["window"] == res.settings["window"]
    assert len(stored.curves) == len(res.curves)
    for k, curve in enumerate(res.curves):
        got = stored_curve(stored, gamma_of(res, curve), curve.direction).data
        want = expected[k]
        for name in ("amplitude", "halfrange", "response_frequency"):
            assert got[name].shape == want[name].shape, name
            assert np.array_equal(got[name], want[name], equal_nan=True), (name, got[name], want[name])
        assert np.array_equal(got["period"], want["period"])
        assert np.array_equal(got["steady"], want["steady"])
        assert np.array_equal(got["done"], want["done"])
    # the datasets read_sweep leaves out, and the attributes, from the file itself
    dirs = sorted({c.direction for c in res.curves})
    with h5py.File(path, "r") as f:
        g = f["sweep"]
        assert bool(g.attrs["complete"]) == all(w["done"].all() for w in expected.values())
        assert g.attrs["points_done"] == sum(int(w["done"].sum()) for w in expected.values())
        assert g.attrs["points_total"] == len(res.curves) * res.omega.size
        for d in dirs:
            where = g if d == "independent" else g[d]
            ks = [k for k, c in enumerate(res.curves) if c.direction == d]
            for name in ("t_end", "floquet", "failed"):
                arr = where[name][()]
                for j, k in enumerate(ks):
                    row = arr[j] if res.gamma is not None else arr
                    assert np.array_equal(row, expected[k][name], equal_nan=True), (d, name)


@pytest.mark.parametrize(
    "overrides",
    [[], ["sweep.direction=both", "sweep.gamma=[0.5, 1.0]"]],
    ids=["independent", "both-gamma"],
)
def test_real_sweep_round_trip(h5dir, overrides):
    case = api.load_case(None, TINY + overrides)
    res = api.sweep(case, jobs=1).result
    assert res.complete
    path = write_sweep(h5dir / f"sweep-{len(overrides)}.h5", res)
    assert not path.with_name(path.name + ".part").exists()
    # the in-memory result is the expectation (copied, so nothing read can alias it)
    expected = {k: {name: np.array(v, copy=True) for name, v in d.items()} for k, d in res.data.items()}
    for d in expected.values():
        assert d["done"].all() and np.all(np.isfinite(d["amplitude"]))
    check_sweep_file(path, res, expected)


HAND_SWEEPS = {
    "both-two-gammas": ["sweep.direction=both", "sweep.gamma=[0.5, 1.0]"],
    "down-no-gamma": ["sweep.direction=down", "sweep.channels=[z1, z2, z4]"],
    "independent-one-gamma": ["sweep.gamma=[2.0]", "sweep.omega=[1.0, 2.0, 3.5, 5.0]"],
}


@pytest.mark.parametrize("label", list(HAND_SWEEPS))
def test_hand_built_partial_sweep_round_trip(tmp_path, label):
    """Some points done (one of them failed: slack, no response frequency), the rest not yet:
    the marked gaps (NaN, done = False) survive as well as the values."""
    case = api.load_case(None, TINY + HAND_SWEEPS[label])
    res = new_sweep_result(case, case.text)
    P, C = res.omega.size, len(res.channels)
    rng = np.random.default_rng(len(label))
    expected = {}
    for k in range(len(res.curves)):
        want = {
            "amplitude": np.full((P, C), np.nan), "halfrange": np.full((P, C), np.nan),
            "response_frequency": np.full((P, C), np.nan), "period": np.zeros(P, dtype=int),
            "steady": np.zeros(P, dtype=bool), "done": np.zeros(P, dtype=bool),
            "t_end": np.full(P, np.nan), "floquet": np.full(P, np.nan), "failed": np.zeros(P, dtype=bool),
        }
        for i in range(P):
            if (k + i) % 3 == 0:
                continue  # not computed yet
            failed = (k + i) % 4 == 1
            period = 0 if failed else 1 + (i % 2)
            amp = rng.uniform(0.01, 5.0, size=C)
            freq = None if failed else float(res.omega[i]) / period
            rec = {
                "curve": k, "index": i, "omega": float(res.omega[i]),
                "amplitude": amp.tolist(), "halfrange": (0.9 * amp).tolist(),
                "response_frequency": [freq] * C, "period": period, "steady": not failed,
                "t_end": 12.5 if failed else 60.0, "floquet": None if failed else 0.25 + 0.125 * i,
                "status": "stopped" if failed else "completed",
                "code": int(Status.SLACK if failed else Status.COMPLETED),
                "final_state": [0.0] * 12, "wall": 0.5,
            }
            res.add(SweepPoint.from_json(rec, len(res.channels), res.n_dof))
            want["amplitude"][i] = amp
            want["halfrange"][i] = 0.9 * amp
            want["response_frequency"][i] = np.nan if failed else freq
            want["period"][i] = period
            want["steady"][i] = not failed
            want["done"][i] = True
            want["t_end"][i] = rec["t_end"]
            want["floquet"][i] = np.nan if failed else rec["floquet"]
            want["failed"][i] = failed
        expected[k] = want
    assert 0 < res.n_done < res.n_total
    assert any(w["failed"].any() for w in expected.values())
    path = write_sweep(tmp_path / "partial.h5", res)
    assert not list(tmp_path.glob("*.part"))
    check_sweep_file(path, res, expected)


# ----------------------------------------------------------------------------------------------
# 3. atomic_h5
# ----------------------------------------------------------------------------------------------
def test_atomic_h5_writes_through_a_part_file(tmp_path):
    path = tmp_path / "new" / "out.h5"  # the folder is created too
    part = path.with_name("out.h5.part")
    with atomic_h5(path) as f:
        f.create_dataset("x", data=[1.0, 2.0])
        assert not path.exists()  # the real name appears only at the end (the file is built in memory)
    assert path.exists() and not part.exists()
    with h5py.File(path, "r") as f:
        assert list(f["x"][()]) == [1.0, 2.0]


def _old_file(path):
    with atomic_h5(path) as f:
        f.create_dataset("old", data=np.arange(5.0))
    return path.read_bytes()


@pytest.mark.parametrize("mode", ["w", "a"])
@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_atomic_h5_keeps_the_old_file_when_the_body_raises(tmp_path, mode, error):
    path = tmp_path / "out.h5"
    before = _old_file(path)
    with pytest.raises(error):
        with atomic_h5(path, mode) as f:
            f.create_dataset("new", data=np.ones(3))
            raise error("boom")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.h5"]  # no .part left
    with h5py.File(path, "r") as f:
        assert list(f) == ["old"]


def test_atomic_h5_failure_without_an_old_file_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_h5(tmp_path / "out.h5") as f:
            f.create_dataset("x", data=[1.0])
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_refused_nan_keeps_the_previous_history_file(tmp_path, completed_history):
    """A writer that fails midway (NaN refused) leaves the previous result as it was."""
    path = tmp_path / "history.h5"
    write_history(path, completed_history, "# case text\n", "history")
    before = path.read_bytes()
    z = completed_history.z.copy()
    z[3, 1] = np.nan
    bad = replace(completed_history, z=z)
    with pytest.raises(ValueError, match="non-finite"):
        write_history(path, bad, "# case text\n", "history")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["history.h5"]


# ----------------------------------------------------------------------------------------------
# 4. Units on every dataset
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def written_files(h5dir, paper, completed_history):
    files = {}
    files["static"] = write_static(h5dir / "units-static.h5", api.static(paper).result, paper.text)
    files["history"] = write_history(h5dir / "units-history.h5", completed_history, paper.text, "history")
    files["stopped history"] = write_history(
        h5dir / "units-stopped.h5", stopped_history(Status.SLACK), paper.text, "free-vibration"
    )
    for label, extra in [("sweep", []), ("sweep both gamma", HAND_SWEEPS["both-two-gammas"])]:
        case = api.load_case(None, TINY + extra)
        files[label] = write_sweep(h5dir / f"units-{label.replace(' ', '-')}.h5", api.sweep(case, jobs=1).result)
    files["empty sweep"] = write_sweep(h5dir / "units-empty-sweep.h5", new_sweep_result(case, case.text))
    return files


@pytest.mark.parametrize("kind", ["static", "history", "stopped history", "sweep", "sweep both gamma", "empty sweep"])
def test_every_dataset_has_units(written_files, kind):
    path = written_files[kind]
    assert count_datasets(path) >= 5
    assert datasets_without_units(path) == []
