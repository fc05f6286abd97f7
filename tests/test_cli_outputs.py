"""Output safety at the command line: every output is checked before anything is computed,
written atomically, and an incomplete run never replaces a complete result.

Every refusal: exit status 2, one paragraph naming the path and the fix, and no file written or
changed (in-process runs through the ``invoke_cli`` fixture).
"""

from __future__ import annotations

import errno
import os
import socket

import h5py
import pytest

from helpers_cli import EXAMPLE, assert_refused, flat


@pytest.fixture
def case(write_case):
    return write_case(EXAMPLE)


def test_output_equal_to_the_case_file_is_refused(invoke_cli, case, tmp_path):
    before = case.read_text()
    assert_refused(invoke_cli("static", case, "-o", case), tmp_path, "must end in .h5", keep=(case,))
    assert case.read_text() == before


def test_output_that_is_the_input_under_an_h5_name(invoke_cli, tmp_path):
    case = tmp_path / "case.h5"
    case.write_text(EXAMPLE)
    res = invoke_cli("static", case, "-o", case, "--no-plot")
    assert_refused(res, tmp_path, "is this run's input", keep=(case,))
    assert case.read_text() == EXAMPLE


def test_png_as_the_hdf5_output_is_refused(invoke_cli, case, tmp_path):
    assert_refused(invoke_cli("static", case, "-o", "result.png"), tmp_path, "-o result.png", "must end in .h5",
                   "result.h5", keep=(case,))


def test_a_device_as_the_output_is_refused(invoke_cli, case, tmp_path):
    dev = tmp_path / "null.h5"
    dev.symlink_to("/dev/null")
    assert_refused(invoke_cli("static", case, "-o", dev, "--no-plot"), tmp_path, "device or special file",
                   keep=(case,))
    assert dev.is_symlink() and os.path.realpath(dev) == "/dev/null"


def test_a_folder_as_the_output_is_refused(invoke_cli, case, tmp_path):
    (tmp_path / "out.h5").mkdir()
    assert_refused(invoke_cli("static", case, "-o", "out.h5"), tmp_path, "is a folder", keep=(case,))


def test_an_output_inside_a_file_is_refused(invoke_cli, case, tmp_path):
    assert_refused(invoke_cli("static", case, "-o", f"{case}/out.h5"), tmp_path, "is a file", keep=(case,))


def test_an_unwritable_folder_is_refused_before_the_run(invoke_cli, case, tmp_path, monkeypatch):
    ro = tmp_path / "ro"
    ro.mkdir()
    real = os.access
    monkeypatch.setattr("cablesim.io.paths.os.access", lambda p, mode: False if os.fspath(p) == os.fspath(ro) else real(p, mode))
    assert_refused(invoke_cli("history", case, "--omega", "2.4", "-o", ro / "h.h5"), tmp_path, "cannot be written",
                   keep=(case,))


def test_a_full_disk_is_refused_before_the_run(invoke_cli, case, tmp_path, monkeypatch):
    import shutil

    monkeypatch.setattr("cablesim.io.paths.shutil.disk_usage", lambda p: shutil._ntuple_diskusage(1, 1, 0))
    assert_refused(invoke_cli("history", case, "--omega", "2.4", "--duration", "30", "-o", "h.h5"), tmp_path,
                   "MB free", "another disk", keep=(case,))


def test_a_write_that_fails_after_the_run_leaves_nothing(invoke_cli, case, tmp_path, monkeypatch):
    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("cablesim.io.hdf5.h5py.File", full)
    assert_refused(invoke_cli("static", case, "-o", "s.h5", "--no-plot"), tmp_path, "Could not write s.h5",
                   "No space left on device", keep=(case,))


def test_a_killed_writers_part_file_is_removed_on_the_next_start(invoke_cli, case, tmp_path):
    (tmp_path / "s.h5.part").write_bytes(b"half an HDF5 file")
    res = invoke_cli("static", case, "-o", "s.h5", "--no-plot")
    assert res.returncode == 0, res.stderr
    assert not (tmp_path / "s.h5.part").exists()
    assert (tmp_path / "s.h5").is_file()


def test_an_interrupted_history_never_replaces_a_complete_result(invoke_cli, case, tmp_path, monkeypatch):
    ok = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "h.h5")
    assert ok.returncode == 0, ok.stderr
    before = (tmp_path / "h.h5").read_bytes()
    from cablesim.dynamics import interrupts

    monkeypatch.setattr(interrupts.Deferred, "__enter__", lambda self: setattr(self, "hit", True) or self)
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "h.h5")
    assert res.returncode == 130, (res.stdout, res.stderr)
    assert (tmp_path / "h.h5").read_bytes() == before
    assert "was kept" in flat(res.stderr) and "h.partial.h5" in flat(res.stderr)
    with h5py.File(tmp_path / "h.partial.h5") as f:
        assert not f["history"].attrs["completed"]


def test_stress_writes_under_runs_by_default_and_checks_its_outputs_first(invoke_cli, tmp_path):
    res = invoke_cli("stress", "--help")
    assert "runs/stress/stability.md" in res.stdout and "runs/stress/stability.png" in res.stdout
    assert_refused(invoke_cli("stress", "--reduced", "--md", "docs/table.txt"), tmp_path, "--md", "must end in .md")
    (tmp_path / "blocker").write_text("a file")
    assert_refused(invoke_cli("stress", "--reduced", "--md", "blocker/stability.md"), tmp_path, "is a file",
                   keep=(tmp_path / "blocker",))


def test_plot_refuses_to_draw_over_its_input(invoke_cli, case, tmp_path):
    ok = invoke_cli("static", case, "-o", "s.h5", "--no-plot")
    assert ok.returncode == 0
    before = (tmp_path / "s.h5").read_bytes()
    assert_refused(invoke_cli("plot", "s.h5", "-o", "s.h5"), tmp_path, keep=(case, tmp_path / "s.h5"))
    assert (tmp_path / "s.h5").read_bytes() == before


def test_a_second_sweep_on_the_same_output_is_refused_naming_the_first(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE.replace("num: 56}", "num: 3}"))
    lock = tmp_path / "out.h5.lock"
    lock.write_text('{"pid": 1, "host": "%s", "time": 0, "command": "cablesim sweep other.yaml -o out.h5"}'
                    % socket.gethostname())
    res = invoke_cli("sweep", case, "-o", "out.h5", "--no-plot")
    msg = assert_refused(res, tmp_path, "being written by another run", "process 1", "other.yaml",
                         keep=(case, lock))
    assert "delete" in msg


def test_a_stale_lock_is_taken_over(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE.replace("omega: {start: 0.5, stop: 6.0, num: 56}", "omega: [3.0]")
                      .replace("duration: 3000.0", "duration: 300.0").replace("window: 200.0", "window: 100.0"))
    (tmp_path / "out.h5.lock").write_text('{"pid": 999999999, "host": "%s", "time": 0}' % socket.gethostname())
    res = invoke_cli("sweep", case, "-o", "out.h5", "--no-plot", "--jobs", "1")
    assert res.returncode == 0, res.stderr
    assert not (tmp_path / "out.h5.lock").exists()


def test_a_root_folder_as_the_output_is_refused(invoke_cli, case, tmp_path):
    assert_refused(invoke_cli("static", case, "-o", "/"), tmp_path, "-o /: names a folder", keep=(case,))


@pytest.mark.parametrize("blocker", ["s.png", "s.h5.journal", "s.h5.lock"])
def test_a_folder_where_a_companion_file_goes_is_refused(blocker, invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE.replace("num: 56}", "num: 2}"))
    (tmp_path / blocker).mkdir()
    assert_refused(invoke_cli("sweep", case, "-o", "s.h5"), tmp_path, f"the file {blocker} written beside it is a "
                   "folder", keep=(case,))


def test_a_malformed_history_file_is_refused_by_plot(invoke_cli, case, tmp_path):
    ok = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "h.h5")
    assert ok.returncode == 0, ok.stderr
    with h5py.File(tmp_path / "h.h5", "a") as f:
        del f["history/t"]
        f["history/t"] = [1.0, 2.0]
    assert_refused(invoke_cli("plot", "h.h5", "-o", "h.png"), tmp_path, "is malformed", "do not match",
                   keep=(case, tmp_path / "h.h5"))
