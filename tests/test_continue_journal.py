"""The continuation journal: a killed (SIGKILL) ``cablesim continue -o`` keeps every finished
orbit, and ``--resume`` finishes it with the orbits of an uninterrupted run, bit for bit.

The case is the paper's two-node example across its period-doubling pair near 2 w1 (the
period-1 branch, and the period-2 branch switched at the first period doubling, which merges at
the second): two branches, about a hundred orbits, a second or two of computing. The reference
is the same continuation run in-process without a journal; a resumed run must give the same
arrays exactly (the dense shooting and the continuation are deterministic).
"""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import cablesim
from cablesim.io import journal as journal_module
from cablesim.io.continuation import read_continuation
from cablesim.io.terminal import StatusLine
from helpers_cli import assert_refused, flat
from helpers_sweep import finish_cli, start_cli

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
NEAR_2W1 = "continuation={omega: {start: 4.9, stop: 5.2}, channels: [z2, z4]}"
#: Arrays of each branch that must agree exactly.
FIELDS = ("parameter", "omega", "amplitude", "halfrange", "stable", "trusted", "multipliers", "state")


def near_case():
    return cablesim.load_case(CONFIG, [NEAR_2W1])


@pytest.fixture(scope="module")
def reference():
    """The uninterrupted continuation, without a journal."""
    return cablesim.continuation(near_case()).result


def assert_same_branches(branches: dict, ref) -> None:
    """``branches`` (name -> arrays, from a file or a result) equal those of ``ref``."""
    assert list(branches) == [b.name for b in ref.branches]
    for b in ref.branches:
        for f in FIELDS:
            got = np.asarray(branches[b.name][f])
            want = getattr(b, f)
            assert got.shape == want.shape and np.array_equal(got, want), (b.name, f)


def result_branches(res) -> dict:
    return {b.name: {f: getattr(b, f) for f in FIELDS} for b in res.branches}


def file_branches(path: Path) -> dict:
    with h5py.File(path, "r") as f:
        g = f["continuation/branches"]
        names = sorted(g, key=lambda k: int(g[k].attrs["index"]))
        return {k: {f: g[k][f][()] for f in FIELDS} for k in names}


def records(journal: Path) -> list[dict]:
    """The complete records of a journal (a torn last line left out)."""
    out = []
    for line in journal.read_text().split("\n")[1:]:
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            pass
    return out


@pytest.fixture(scope="module")
def kept_journal(tmp_path_factory, reference):
    """The lines of the journal of a complete run (kept instead of removed at the end)."""
    out = tmp_path_factory.mktemp("journal") / "full.h5"
    close = journal_module.Journal.close
    journal_module.Journal.close = lambda self, remove: close(self, False)
    try:
        res = cablesim.continuation(near_case(), output=out).result
    finally:
        journal_module.Journal.close = close
    assert_same_branches(result_branches(res), reference)  # the journal changes nothing
    return out.with_name(out.name + ".journal").read_text().split("\n")


def test_journal_records_every_orbit_and_the_state_to_go_on(kept_journal, reference):
    recs = [json.loads(line) for line in kept_journal[1:] if line]
    orbits = [r for r in recs if r["record"] == "orbit"]
    assert len(orbits) == reference.n_points - 1  # the period-2 branch starts at the parent's orbit
    steps = [r for r in recs if r["record"] == "step"]
    assert steps and all(len(s["tangent"]) == len(s["u"]) + 1 and s["ds"] > 0 for s in steps)
    starts = {r["run"]: r for r in recs if r["record"] == "run"}
    assert [s["period"] for s in starts.values()][:2] == [1, 2]
    assert {r["run"] for r in recs if r["record"] == "end"} == set(starts)


@pytest.mark.parametrize("where", ["first branch", "switched branch", "last record torn"])
def test_resume_from_any_record_gives_the_uninterrupted_orbits(tmp_path, kept_journal, reference, where):
    """The journal as a kill at that moment leaves it (a torn last line), then --resume."""
    recs = [json.loads(line) for line in kept_journal[1:] if line]
    runs = [r["run"] for r in recs]
    cut = {"first branch": 1 + runs.index(0) + 25, "switched branch": 1 + runs.index(1) + 30,
           "last record torn": len(kept_journal) - 2}[where]
    out = tmp_path / "cut.h5"
    journal = out.with_name(out.name + ".journal")
    journal.write_text("\n".join(kept_journal[:cut]) + "\n" + kept_journal[cut][:40])
    res = cablesim.continuation(near_case(), output=out, resume=True).result
    assert_same_branches(result_branches(res), reference)
    assert [(b.kind, b.parameter) for b in res.bifurcations] == [(b.kind, b.parameter) for b in reference.bifurcations]
    assert not journal.exists()  # removed once complete
    assert_same_branches(file_branches(out), reference)


def wait_for_orbits(proc, journal: Path, n: int, timeout: float = 120.0) -> None:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if journal.exists() and journal.read_text().count('"record": "orbit"') >= n:
            return
        if proc.poll() is not None:
            pytest.fail(f"the continuation ended (status {proc.returncode}) before {n} orbits:\n{proc.communicate()[1]}")
        time.sleep(0.005)
    os.killpg(proc.pid, signal.SIGKILL)
    pytest.fail(f"fewer than {n} orbits journaled after {timeout} s")


def test_sigkill_keeps_the_orbits_and_resume_completes_them(tmp_path, reference):
    args = ["continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--no-plot"]
    out, journal = tmp_path / "out.h5", tmp_path / "out.h5.journal"
    proc = start_cli(args, tmp_path)
    wait_for_orbits(proc, journal, 15)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    kept = [r for r in records(journal) if r["record"] == "orbit" and r["run"] == 0]
    assert len(kept) >= 15
    first = reference.branches[0]
    for r in kept:  # the journal holds the orbits finished before the kill, exactly
        assert np.array_equal(r["point"]["state"], first.state[r["at"]])
    if out.exists():  # a snapshot written before the kill opens, marked incomplete
        d = read_continuation(out)
        assert not d["complete"]

    code, stdout, stderr = finish_cli(start_cli([*args, "--resume"], tmp_path))
    assert code == 0, stderr
    assert "Traceback" not in stderr and "note: replacing" not in stderr
    assert not journal.exists() and not list(tmp_path.glob("*.part*"))
    assert_same_branches(file_branches(out), reference)
    assert read_continuation(out)["complete"]

    code, stdout, _ = finish_cli(start_cli([*args, "--resume"], tmp_path))  # nothing left to do
    assert code == 0 and "Nothing to do" in flat(stdout)


@pytest.mark.slow  # about 20 s: four runs of a 300-orbit continuation (the fast test above kills the same way)
def test_a_killed_run_beside_a_complete_result_keeps_a_snapshot_and_resumes_twice(tmp_path):
    """The paper's cable in space over 0.5 - 6 rad/s (several seconds, longer than the 3 s
    between snapshots: the planar case can finish before its first): killed once the first
    snapshot is written (the complete result of another range at the same name untouched, the
    snapshot beside it), then killed again while the period-2 branch is traced, then finished."""
    args = ["continue", CONFIG, "-o", "out.h5", "--no-plot", "--set", "spatial=true"]
    out, journal, beside = tmp_path / "out.h5", tmp_path / "out.h5.journal", tmp_path / "out.partial.h5"
    cablesim.continuation(near_case(), output=out)
    before = out.read_bytes()
    reference = cablesim.continuation(cablesim.load_case(CONFIG, overrides=["spatial=true"])).result
    proc = start_cli(args, tmp_path)
    t0 = time.monotonic()
    while not beside.exists() and proc.poll() is None and time.monotonic() - t0 < 120:
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    assert out.read_bytes() == before  # a complete result is never replaced by an incomplete one
    d = file_branches(beside)
    assert not read_continuation(beside)["complete"]
    for name, arrays in d.items():  # the snapshot's orbits are the uninterrupted run's first ones
        ref = next(b for b in reference.branches if b.name == name)
        k = arrays["state"].shape[0]
        assert k and np.array_equal(arrays["state"], ref.state[:k])

    proc = start_cli([*args, "--resume"], tmp_path)
    wait_for_orbits(proc, journal, reference.branches[0].parameter.size + 10)  # into the period-2 branch
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    code, _, stderr = finish_cli(start_cli([*args, "--resume"], tmp_path))
    assert code == 0, stderr
    assert not journal.exists() and not beside.exists()
    assert_same_branches(file_branches(out), reference)


def test_a_damaged_or_foreign_journal_is_refused(tmp_path, invoke_cli):
    journal = tmp_path / "out.h5.journal"
    journal.write_bytes(b"\x00\xff garbage")
    res = invoke_cli("continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--resume")
    assert_refused(res, tmp_path, "is damaged", "without --resume", keep=(journal,))
    # a journal of another range (another fingerprint)
    other = tmp_path / "other.h5"
    close = journal_module.Journal.close
    journal_module.Journal.close = lambda self, remove: close(self, False)
    try:
        cablesim.continuation(cablesim.load_case(CONFIG, ["continuation={omega: {start: 4.9, stop: 4.95}}"]),
                              output=other)
    finally:
        journal_module.Journal.close = close
    journal.write_text(other.with_name(other.name + ".journal").read_text())
    res = invoke_cli("continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--resume")
    keep = (journal, other, other.with_name(other.name + ".journal"))
    assert_refused(res, tmp_path, "belongs to a different case or different settings", keep=keep)


def test_records_that_do_not_fit_the_case_are_refused(tmp_path, invoke_cli, kept_journal):
    """A journal with this case's fingerprint whose orbits are of another size (forged)."""
    lines = list(kept_journal[:40])
    k = next(i for i, line in enumerate(lines) if '"record": "orbit"' in line)
    rec = json.loads(lines[k])
    rec["point"]["state"] = rec["point"]["state"][:3]
    lines[k] = json.dumps(rec)
    journal = tmp_path / "out.h5.journal"
    journal.write_text("\n".join(lines) + "\n")
    res = invoke_cli("continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--resume")
    assert_refused(res, tmp_path, "does not fit this case", "without --resume", keep=(journal,))


def test_resume_with_nothing_to_resume_says_so(tmp_path, invoke_cli):
    res = invoke_cli("continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--resume")
    assert_refused(res, tmp_path, "no interrupted continuation to resume", "without --resume")


def test_progress_lines_when_standard_error_is_not_a_terminal(monkeypatch, capsys):
    clock = iter([0.0, 1.0, 4.0, 5.5, 6.0, 11.0])
    monkeypatch.setattr("cablesim.io.terminal.time.monotonic", lambda: next(clock))
    monkeypatch.setattr("sys.stderr.isatty", lambda: False, raising=False)
    with StatusLine(every=5.0) as status:  # created at t = 0
        for text in ("a", "b", "c", "d", "e"):  # at t = 1, 4, 5.5, 6, 11
            status(text)
    assert capsys.readouterr().err.split("\n") == ["c", "e", ""]


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_run_names_the_command_that_finishes_it(tmp_path, reference, signum, code):
    """Ctrl-C or SIGTERM once orbits are journaled: the message says what was kept, and the
    command it prints, run as printed, completes the branches of an uninterrupted run."""
    import shlex

    args = ["continue", CONFIG, "--set", NEAR_2W1, "-o", "out.h5", "--no-plot"]
    out, journal = tmp_path / "out.h5", tmp_path / "out.h5.journal"
    proc = start_cli(args, tmp_path)
    wait_for_orbits(proc, journal, 15)
    proc.send_signal(signum)
    status, _, stderr = finish_cli(proc)
    assert status == code, stderr
    assert "Traceback" not in stderr and "Finish the continuation with:" in flat(stderr)
    words = shlex.split(stderr.strip().splitlines()[-1])
    assert words[:2] == ["cablesim", "continue"] and words[-1] == "--resume", stderr
    assert len([r for r in records(journal) if r["record"] == "orbit"]) >= 15
    status, _, stderr = finish_cli(start_cli(words[1:], tmp_path))
    assert status == 0, stderr
    assert read_continuation(out)["complete"] and not journal.exists()
    assert_same_branches(file_branches(out), reference)
