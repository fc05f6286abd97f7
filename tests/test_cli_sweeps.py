"""Clear outcomes for sweeps: failed points named (exit 3), never taken as peaks, their status
stored; damaged journals refused or their bad records skipped on --resume, never trusted.
"""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from cablesim.case import load_case
from cablesim.io.journal import fingerprint
from cablesim.io.sweeps import sweep_summary_rows
from helpers_cli import EXAMPLE, assert_refused, example_with, flat

SMALL = example_with(("omega: {start: 0.5, stop: 6.0, num: 56}", "omega: [3.0, 4.0]"),
                     ("duration: 3000.0", "duration: 300.0"), ("window: 200.0", "window: 100.0"))
FL10 = "loads.FL=[-60000.0, 220000.0, -180000.0, 1200000.0]"  # ten times the example's
ARGS = ["-o", "out.h5", "--jobs", "1", "--no-plot"]


def test_a_failed_point_is_named_exit_3_and_never_a_peak(invoke_cli, tmp_path):
    # slack: stop, so that a point fails (the default, continue, runs through slack segments)
    res = invoke_cli("sweep", "--omega", "2.5,6.0", "--duration", "200", "--set", "sweep.window=50", "--set", FL10,
                     "--slack", "stop", *ARGS)
    assert res.returncode == 3, res.stderr
    out = flat(res.stdout)
    assert "1 point(s) failed" in out and "w = 2.5 rad/s: stopped at t =" in out and "went slack" in out
    assert "1 of 2 sweep points stopped early" in flat(res.stderr)
    with h5py.File(tmp_path / "out.h5") as f:
        status = [s.decode() for s in f["sweep/status"][()]]
        failed = f["sweep/failed"][()]
        assert f["sweep"].attrs["points_failed"] == 1
    assert failed.tolist() == [True, False]
    assert "went slack" in status[0] and status[1] in ("steady", "cap reached")
    rows = sweep_summary_rows(tmp_path / "out.h5")
    assert {r["omega"] for r in rows} == {6.0}  # the partial values at 2.5 rad/s are never the peak


def test_a_sweep_whose_every_point_failed_exits_3_without_a_peak(invoke_cli, tmp_path):
    fl50 = "loads.FL=[-300000.0, 1100000.0, -900000.0, 6000000.0]"
    res = invoke_cli("sweep", "--omega", "2.4,0.8", "--duration", "200", "--set", "sweep.window=50", "--set", fl50,
                     "--slack", "stop", *ARGS)
    assert res.returncode == 3, res.stderr
    assert "no point ran to its end" in res.stdout and "2 point(s) failed" in res.stdout
    assert all(np.isnan(r["value"]) for r in sweep_summary_rows(tmp_path / "out.h5"))


# ----------------------------------------------------------------------------------------------
# damaged journals
# ----------------------------------------------------------------------------------------------
@pytest.fixture
def small(write_case):
    path = write_case(SMALL)
    return path, fingerprint(load_case(path)[0].text, None, None)


def _record(fp, **changes):
    rec = {"curve": 0, "index": 0, "omega": 3.0, "amplitude": [999.0] * 2, "halfrange": [999.0] * 2,
           "response_frequency": [3.0] * 2, "period": 1, "steady": True, "t_end": 10.0, "floquet": 0.5,
           "status": "steady", "code": 0, "final_state": None, "wall": 0.1, "fingerprint": fp}
    rec.update(changes)
    return json.dumps({k: v for k, v in rec.items() if v != "DROP"})


REFUSED_JOURNALS = {
    "header-not-json": (lambda fp: "garbage\n", ["damaged", "first line is not a JSON record", "without --resume"]),
    "header-without-fingerprint": (lambda fp: '{"x": 1}\n', ["damaged", "does not name the sweep's settings"]),
    "empty": (lambda fp: "", ["damaged", "empty"]),
    "binary": (lambda fp: b"\xff\xfe\x00garbage", ["damaged", "not text"]),
    "other-settings": (lambda fp: '{"fingerprint": "0123456789abcdef"}\n', ["different case", "without --resume"]),
}


@pytest.mark.parametrize("kind", REFUSED_JOURNALS)
def test_a_journal_with_a_damaged_header_is_refused(kind, small, invoke_cli, tmp_path):
    case, fp = small
    make, needles = REFUSED_JOURNALS[kind]
    journal = tmp_path / "out.h5.journal"
    body = make(fp)
    journal.write_bytes(body if isinstance(body, bytes) else body.encode())
    res = invoke_cli("sweep", case, *ARGS, "--resume")
    assert_refused(res, tmp_path, *needles, keep=(case, journal))


def test_a_sound_record_is_taken_as_computed(small, invoke_cli, tmp_path):
    """The control for the cases below: the same record unchanged is trusted."""
    case, fp = small
    journal = tmp_path / "out.h5.journal"
    journal.write_text(json.dumps({"fingerprint": fp}) + "\n" + _record(fp) + "\n")
    res = invoke_cli("sweep", case, *ARGS, "--resume")
    assert res.returncode == 0 and "warning" not in res.stderr, res.stderr
    with h5py.File(tmp_path / "out.h5") as f:
        assert f["sweep/amplitude"][()][0].tolist() == [999.0, 999.0]


SKIPPED_RECORDS = {
    "index-minus-1": dict(index=-1, omega=4.0),
    "index-out-of-range": dict(index=7),
    "missing-keys": dict(amplitude="DROP", code="DROP"),
    "wrong-types": dict(amplitude="big"),
    "wrong-channel-count": dict(amplitude=[1.0, 2.0, 3.0]),
    "curve-out-of-range": dict(curve=3),
    "wrong-frequency": dict(omega=3.5),
    "other-fingerprint": dict(fingerprint="0123456789abcdef"),
    "no-fingerprint": dict(fingerprint="DROP"),
    "unknown-status-code": dict(code=77),
}


@pytest.mark.parametrize("kind", SKIPPED_RECORDS)
def test_bad_journal_records_are_skipped_and_recomputed(kind, small, invoke_cli, tmp_path):
    case, fp = small
    journal = tmp_path / "out.h5.journal"
    journal.write_text(json.dumps({"fingerprint": fp}) + "\n" + _record(fp, **SKIPPED_RECORDS[kind]) + "\n")
    res = invoke_cli("sweep", case, *ARGS, "--resume")
    assert res.returncode == 0, res.stderr
    assert "warning: journal line 2" in flat(res.stderr) and "computed again" in flat(res.stderr)
    with h5py.File(tmp_path / "out.h5") as f:
        amp = f["sweep/amplitude"][()]
        assert f["sweep"].attrs["complete"]
    assert np.all(amp < 100.0)  # the bad record's 999 m entered no point
    assert not journal.exists()


def test_a_torn_middle_record_is_skipped_and_the_rest_kept(small, invoke_cli, tmp_path):
    case, fp = small
    journal = tmp_path / "out.h5.journal"
    good = _record(fp, index=1, omega=4.0, amplitude=[0.5, 0.5])
    journal.write_text(json.dumps({"fingerprint": fp}) + "\n" + '{"curve": 0, "ind\n' + good + "\n")
    res = invoke_cli("sweep", case, *ARGS, "--resume")
    assert res.returncode == 0, res.stderr
    assert "journal line 2 is not a JSON record" in flat(res.stderr)
    with h5py.File(tmp_path / "out.h5") as f:
        assert f["sweep/amplitude"][()][1].tolist() == [0.5] * 2  # the good record was kept


def test_resume_without_an_interrupted_sweep_says_so(small, invoke_cli, tmp_path):
    case, _ = small
    assert_refused(invoke_cli("sweep", case, *ARGS, "--resume"), tmp_path, "no interrupted sweep",
                   "without --resume", keep=(case,))


def test_an_interrupted_sweep_never_replaces_a_complete_result(small, invoke_cli, tmp_path, monkeypatch):
    case, _ = small
    assert invoke_cli("sweep", case, *ARGS).returncode == 0
    out = tmp_path / "out.h5"
    before = out.read_bytes()
    from cablesim.io.journal import SweepFile

    point = SweepFile.point

    def interrupted(self, record, result):
        point(self, record, result)
        raise KeyboardInterrupt  # Ctrl-C after the first point

    monkeypatch.setattr(SweepFile, "point", interrupted)
    args = [case, "--set", "sweep.tol=2.0e-5", *ARGS]
    res = invoke_cli("sweep", *args)
    assert res.returncode == 130, res.stderr
    assert out.read_bytes() == before
    partial = tmp_path / "out.partial.h5"
    assert partial.is_file() and "out.partial.h5" in flat(res.stderr) and "is untouched" in flat(res.stderr)
    assert "--resume" in res.stderr.splitlines()[-1]
    monkeypatch.setattr(SweepFile, "point", point)
    done = invoke_cli("sweep", *args, "--resume")
    assert done.returncode == 0, done.stderr
    assert not partial.exists() and not (tmp_path / "out.h5.journal").exists()
    with h5py.File(out) as f:
        assert f["sweep"].attrs["complete"] and f["sweep"].attrs["tol"] == 2.0e-5
