"""The sweep journal: a killed (SIGKILL) or interrupted (Ctrl-C) sweep keeps every finished
point, its HDF5 snapshot agrees with the journal, and ``--resume`` finishes it with the
uninterrupted result; up/down chains continue where they stopped; a torn last record is skipped;
another case cannot continue a journal.

The kill and Ctrl-C checks run the real ``cablesim sweep`` in a subprocess; the others run
in-process and stop through a progress callback (``helpers_sweep.Stop``).
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from cablesim.case import parse_case
from cablesim.errors import CablesimError
from helpers_sweep import (
    Stop,
    assert_same_results,
    case_text,
    finish_cli,
    journal_records,
    read_sweep,
    run_sweep,
    start_cli,
    stop_after,
    wait_for_records,
)


# ----------------------------------------------------------------------------------------------
# Journal, kill, Ctrl-C and --resume
# ----------------------------------------------------------------------------------------------
N_RESUME = 16
RESUME_SWEEP = {"omega": {"start": 1.5, "stop": 4.2, "num": N_RESUME}, "duration": 1500.0, "window": 100.0,
                "channels": ["z2", "z4"], "refine": False}


@pytest.fixture(scope="module")
def resume_reference(wdir):
    """The resume case text and its uninterrupted in-process result file."""
    text = case_text(RESUME_SWEEP)
    out = wdir / "resume-reference.h5"
    run_sweep(parse_case(text), text, out, n_jobs=2)  # independent points: same values as serial
    return text, read_sweep(out)


def check_partial(out: Path, journal: Path, ref: dict) -> None:
    """An interrupted state: the HDF5 snapshot (if any) opens and agrees with the journal."""
    lines = journal.read_text().split("\n")
    recs = [json.loads(x) for x in lines[1:] if x.strip()]
    done_omega = {r["omega"] for r in recs}
    if not out.exists():
        return
    d = read_sweep(out)
    done = d["done"]
    assert done.shape == (N_RESUME,)
    assert set(d["omega"][done].tolist()) <= done_omega  # a snapshot never runs ahead of the journal
    assert not d["/attrs"]["complete"]
    assert d["/attrs"]["points_done"] == done.sum()
    for k in ("amplitude", "halfrange", "t_end"):
        assert np.all(np.isnan(d[k][~done])), k
        assert np.array_equal(d[k][done], ref[k][done]), k
    assert np.all(d["period"][~done] == 0)


def test_kill_then_resume_gives_the_uninterrupted_result(tmp_path, resume_reference):
    text, ref = resume_reference
    (tmp_path / "case.yaml").write_text(text)
    out, journal = tmp_path / "out.h5", tmp_path / "out.h5.journal"
    args = ["sweep", "case.yaml", "-o", "out.h5", "--jobs", "1", "--no-plot"]
    proc = start_cli(args, tmp_path)
    # kill once a snapshot has been written too (snapshots come every 3 s)
    wait_for_records(proc, journal, 3, until=out.exists)
    snapshot = out.exists()
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    n = journal_records(journal)
    assert 3 <= n < N_RESUME, n
    if snapshot:
        assert out.exists()
    check_partial(out, journal, ref)
    before = {json.loads(x)["omega"]: json.loads(x)["wall"] for x in journal.read_text().split("\n")[1:] if x.strip()}

    code, stdout, stderr = finish_cli(start_cli([*args, "--resume"], tmp_path))
    assert code == 0, stderr
    assert "Traceback" not in stderr
    assert not journal.exists()  # removed once complete
    assert not list(tmp_path.glob("*.part"))
    got = read_sweep(out)
    assert_same_results(got, ref)
    assert got["/attrs"]["complete"] and got["/attrs"]["points_done"] == N_RESUME
    # the journalled points were kept, not recomputed
    for w, wall in before.items():
        assert got["wall"][got["omega"].tolist().index(w)] == wall


def test_ctrl_c_exits_130_and_points_to_resume(tmp_path, resume_reference):
    text, ref = resume_reference
    (tmp_path / "case.yaml").write_text(text)
    out, journal = tmp_path / "out.h5", tmp_path / "out.h5.journal"
    proc = start_cli(["sweep", "case.yaml", "-o", "out.h5", "--jobs", "1", "--no-plot"], tmp_path)
    wait_for_records(proc, journal, 2)
    proc.send_signal(signal.SIGINT)
    code, stdout, stderr = finish_cli(proc, timeout=60)
    assert code == 130, stderr
    assert "--resume" in stderr and "Traceback" not in stderr
    assert journal.exists()
    assert out.exists()  # the final snapshot of an interrupted run
    check_partial(out, journal, ref)
    assert not list(tmp_path.glob("*.part"))
    # finish it as the message says (the command line records the case file's name in the case
    # text, so the journal belongs to the command's case, not to the bare text) and compare
    again = start_cli(["sweep", "case.yaml", "-o", "out.h5", "--jobs", "2", "--no-plot", "--resume"], tmp_path)
    code, stdout, stderr = finish_cli(again, timeout=600)
    assert code == 0, stderr
    assert not journal.exists()
    assert_same_results(read_sweep(out), ref)


CHAIN_SWEEP = {"omega": [2.0, 2.3, 2.6], "duration": 600.0, "window": 100.0, "direction": "both", "channels": ["z2", "z4"]}


def test_resume_continues_up_and_down_chains(wdir):
    text = case_text(CHAIN_SWEEP)
    case = parse_case(text)
    ref_out, out = wdir / "chain-ref.h5", wdir / "chain.h5"
    run_sweep(case, text, ref_out, n_jobs=1)
    with pytest.raises(Stop):
        run_sweep(case, text, out, n_jobs=1, progress=stop_after(3))  # mid-round: up 2, down 1
    journal = out.with_name(out.name + ".journal")
    assert journal_records(journal) == 3
    # another case cannot continue this journal, and the attempt leaves it intact
    other = case_text(dict(CHAIN_SWEEP, duration=700.0))
    with pytest.raises(CablesimError, match="different case"):
        run_sweep(parse_case(other), other, out, n_jobs=1, resume=True)
    assert journal_records(journal) == 3
    calls = []
    res = run_sweep(case, text, out, n_jobs=1, resume=True, progress=lambda d, t: calls.append(d))
    assert calls == [4, 5, 6]  # only the missing points were computed
    assert res.complete and not journal.exists()
    assert_same_results(read_sweep(out), read_sweep(ref_out))


def test_resume_skips_a_torn_last_record(wdir):
    sweep = {"omega": [2.0, 3.0, 4.0], "duration": 300.0, "window": 100.0, "channels": ["z2"]}
    text = case_text(sweep)
    case = parse_case(text)
    out = wdir / "torn.h5"
    journal = out.with_name(out.name + ".journal")
    with pytest.raises(Stop):
        run_sweep(case, text, out, n_jobs=1, progress=stop_after(2))
    with open(journal, "a") as f:
        f.write('{"curve": 0, "index": 2, "omega": 4.0, "ampl')  # killed mid-write
    calls = []
    res = run_sweep(case, text, out, n_jobs=1, resume=True, progress=lambda d, t: calls.append(d))
    assert calls == [3] and res.complete and not journal.exists()


def test_second_resume_after_a_torn_record_keeps_new_points(wdir):
    sweep = {"omega": [2.0, 3.0, 4.0, 5.0], "duration": 300.0, "window": 100.0, "channels": ["z2"]}
    text = case_text(sweep)
    case = parse_case(text)
    out = wdir / "torn2.h5"
    journal = out.with_name(out.name + ".journal")
    with pytest.raises(Stop):
        run_sweep(case, text, out, n_jobs=1, progress=stop_after(2))
    with open(journal, "a") as f:
        f.write('{"curve": 0, "index": 2, "omega": 4.0, "ampl')
    with pytest.raises(Stop):
        run_sweep(case, text, out, n_jobs=1, resume=True, progress=stop_after(3))
    calls = []
    run_sweep(case, text, out, n_jobs=1, resume=True, progress=lambda d, t: calls.append(d))
    assert calls == [4], calls  # got [3, 4]: the point done in the second run is recomputed

