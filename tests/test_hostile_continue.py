"""A user trying to break the newer commands (``continue``, ``plot``, ``check --set``, charts,
resumes, slack histories), written from the README: every refusal is one paragraph with exit
status 2 and no traceback, nothing computed is lost, and nothing is computed for an input that
is refused.

The cases are tiny (a one-node cable, short ranges), so that each test takes a few seconds.
File-system faults use a real tmpfs where this machine allows mounting one (skipped elsewhere).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import uuid
from pathlib import Path

import h5py
import numpy as np
import pytest

from helpers_cli import ONE_NODE, assert_refused, flat


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A sweep, a continuation and a history of the one-node cable, written once."""
    import cablesim

    root = tmp_path_factory.mktemp("results")
    (root / "one.yaml").write_text(ONE_NODE)
    case = cablesim.load_case(root / "one.yaml")
    files = {"case": root / "one.yaml", "sweep": root / "sweep.h5", "continuation": root / "cont.h5",
             "history": root / "hist.h5"}
    cablesim.sweep(case, jobs=1).to_hdf5(files["sweep"])
    cablesim.continuation(case).to_hdf5(files["continuation"])
    cablesim.history(case, omega=3.0, duration=2.0).to_hdf5(files["history"])
    return files


@pytest.fixture
def here(results, tmp_path):
    """Copies of the results in the test's folder (the command line runs there)."""
    return {k: Path(shutil.copy(p, tmp_path / p.name)) for k, p in results.items()}


@pytest.fixture
def no_compute(monkeypatch):
    """Fail the test if a continuation is started."""
    import cablesim.api

    def computed(*a, **k):
        raise AssertionError("the continuation ran before the input was refused")

    monkeypatch.setattr(cablesim.api, "run_continuation", computed)


def _mount(where: Path, options: str) -> None:
    where.mkdir(exist_ok=True)
    try:
        res = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True,
                             timeout=10)
    except (OSError, subprocess.SubprocessError) as exc:
        pytest.skip(f"cannot mount a tmpfs here ({exc})")
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({res.stderr.decode().strip()})")


@pytest.fixture
def tmpfs(tmp_path):
    """``mount(name, size, read_only=False, fill=None)``: a small tmpfs under tmp_path (skipped where
    mounting is not allowed), unmounted afterwards; ``fill`` files are copied in before a
    read-only remount."""
    mounted = []

    def mount(name: str, size: str = "1m", read_only: bool = False, fill=()) -> Path:
        where = tmp_path / name
        _mount(where, f"size={size}")
        mounted.append(where)
        for p in fill:
            shutil.copy(p, where / Path(p).name)
        if read_only:
            subprocess.run(["mount", "-o", "remount,ro", str(where)], check=True, timeout=10)
        return where

    yield mount
    for where in mounted:
        subprocess.run(["umount", "-l", str(where)], capture_output=True, timeout=10)


# ----------------------------------------------------------------------------------------------
# 1. Inputs before compute
# ----------------------------------------------------------------------------------------------
def test_continue_refuses_an_output_that_is_its_overlay(invoke_cli, here, tmp_path, no_compute):
    before = here["sweep"].read_bytes()
    msg = assert_refused(invoke_cli("continue", here["case"], "-o", here["sweep"], "--overlay", here["sweep"]),
                         tmp_path, "is this run's input", keep=tuple(here.values()))
    assert "sweep.h5" in msg
    assert here["sweep"].read_bytes() == before


def test_continue_refuses_a_png_beside_the_output_that_is_its_overlay(invoke_cli, here, tmp_path, no_compute):
    png = tmp_path / "fig.png"
    shutil.copy(here["sweep"], png)  # an overlay under the name the plot would take
    assert_refused(invoke_cli("continue", here["case"], "-o", "fig.h5", "--overlay", png), tmp_path,
                   "is this run's input", keep=(*here.values(), png))


def _truncated(here, tmp_path):
    p = tmp_path / "truncated.h5"
    p.write_bytes(here["sweep"].read_bytes()[:3000])
    return p


def _text(here, tmp_path):
    p = tmp_path / "notes.h5"
    p.write_text("omega amplitude\n2.2 0.001\n")
    return p


def _other_cable(here, tmp_path):
    p = tmp_path / "other-cable.h5"
    shutil.copy(here["sweep"], p)
    with h5py.File(p, "a") as f:
        text = f.attrs["case_yaml"]
        text = text.decode() if isinstance(text, bytes) else str(text)
        assert "EA: 1.0e6" in text
        f.attrs["case_yaml"] = text.replace("EA: 1.0e6", "EA: 3.0e6")
    return p


@pytest.mark.parametrize("make, needle", [
    (_text, "not an HDF5 file"),
    (_truncated, "not an HDF5 file"),
    (lambda here, tmp: here["history"], "time-history file, not a sweep file"),
    (lambda here, tmp: here["continuation"], "continuation file, not a sweep file"),
    (_other_cable, "a sweep of another cable"),
], ids=["text", "truncated", "history", "continuation", "other-cable"])
def test_a_bad_overlay_is_refused_before_the_continuation_runs(invoke_cli, here, tmp_path, no_compute, make, needle):
    overlay = make(here, tmp_path)
    keep = tuple(p for p in (*here.values(), overlay) if p.exists())
    msg = assert_refused(invoke_cli("continue", here["case"], "-o", "c.h5", "--overlay", overlay), tmp_path,
                         needle, "--overlay", keep=keep)
    assert "Nothing was computed" in msg


def test_an_overlay_with_other_loads_is_drawn_with_a_warning_said_first(invoke_cli, here, tmp_path, monkeypatch):
    overlay = tmp_path / "other-loads.h5"
    shutil.copy(here["sweep"], overlay)
    with h5py.File(overlay, "a") as f:
        text = f.attrs["case_yaml"]
        text = text.decode() if isinstance(text, bytes) else str(text)
        f.attrs["case_yaml"] = text.replace("FL: [0.0, 100.0]", "FL: [0.0, 150.0]")
    import cablesim.cli_guard

    said = []
    real = cablesim.cli_guard.run_continue
    monkeypatch.setattr(cablesim.cli_guard, "run_continue",
                        lambda *a, **k: said.append(True) or real(*a, **k))
    res = invoke_cli("continue", here["case"], "-o", "c.h5", "--overlay", overlay)
    assert res.returncode == 0, res.stderr
    assert "other loads" in flat(res.stderr) and said
    assert (tmp_path / "c.png").is_file()


def test_plot_stamp_with_math_notation_is_drawn_as_written(invoke_cli, here, tmp_path):
    from PIL import Image

    res = invoke_cli("plot", here["continuation"], "-o", "stamped.png", "--stamp", r"$\undefinedmacro$ {x}")
    assert res.returncode == 0, (res.stderr, res.exception)
    assert Image.open(tmp_path / "stamped.png").text["Stamp"] == r"$\undefinedmacro$ {x}"


def test_plot_into_a_read_only_folder_is_one_message(invoke_cli, here, tmp_path, tmpfs):
    ro = tmpfs("ro", read_only=True, fill=[here["continuation"]])
    res = invoke_cli("plot", ro / here["continuation"].name)
    assert res.returncode == 2 and isinstance(res.exception, SystemExit), (res.stderr, res.exception)
    assert "Traceback" not in res.stderr and "Read-only file system" in flat(res.stderr)
    assert_refused(invoke_cli("plot", here["continuation"], "-o", ro / "x.png"), tmp_path / "none",
                   "cannot be written", "read-only")


def _forge(here, tmp_path, edit) -> Path:
    p = tmp_path / "forged.h5"
    shutil.copy(here["continuation"], p)
    with h5py.File(p, "a") as f:
        edit(f)
    return p


def _first_branch(f):
    return f["continuation/branches"][next(iter(f["continuation/branches"]))]


@pytest.mark.parametrize("edit", [
    lambda f: _first_branch(f).__delitem__("amplitude"),
    lambda f: f["continuation"].attrs.__delitem__("parameter"),
    lambda f: f["continuation"].__delitem__("bifurcations"),
    lambda f: (_first_branch(f).__delitem__("stable"), _first_branch(f).create_dataset("stable", data=[1, 0])),
], ids=["no-amplitude", "no-parameter", "no-bifurcations", "short-stable"])
def test_a_forged_continuation_file_is_refused_in_one_paragraph(invoke_cli, here, tmp_path, edit):
    forged = _forge(here, tmp_path, edit)
    assert_refused(invoke_cli("plot", forged), tmp_path, "forged.h5", "not a continuation file as cablesim",
                   keep=(*here.values(), forged))


def test_a_result_named_with_a_space_and_no_case_name_is_redrawn(invoke_cli, here, tmp_path):
    import yaml

    import cablesim

    data = yaml.load(ONE_NODE, Loader=yaml.SafeLoader)
    data.pop("name")
    data["cable"]["EA"] = 1.0e6
    case = cablesim.load_case(data)
    target = tmp_path / "my run.h5"
    cablesim.history(case, omega=3.0, duration=2.0).to_hdf5(target)
    res = invoke_cli("plot", target)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "my run-waveforms.png").is_file()


# ----------------------------------------------------------------------------------------------
# 2. Keeping results
# ----------------------------------------------------------------------------------------------
def _signal_after(monkeypatch, orbits: int, signum: int) -> list:
    """Send ``signum`` to this process when the continuation reports its ``orbits``-th orbit; the
    orbits reported are recorded in the returned list."""
    import cablesim.cli_charts

    seen: list = []

    def status(line):
        def progress(p):
            seen.append(p)
            if len(seen) == orbits:
                os.kill(os.getpid(), signum)
        return progress

    monkeypatch.setattr(cablesim.cli_charts, "branch_status", status)
    return seen


@pytest.mark.parametrize("signum, code, name", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")])
def test_a_signal_during_continue_keeps_the_orbits_computed(invoke_cli, here, tmp_path, monkeypatch, signum, code,
                                                             name):
    seen = _signal_after(monkeypatch, 4, signum)
    res = invoke_cli("continue", here["case"], "-o", "c.h5")
    assert res.returncode == code, (res.stderr, res.exception)
    assert "Traceback" not in res.stderr
    with h5py.File(tmp_path / "c.h5") as f:
        assert not f["continuation"].attrs["complete"]
        branches = f["continuation/branches"]
        kept = sum(branches[b]["omega"].size for b in branches)
        ends = [str(branches[b].attrs["end"]) for b in branches]
    assert kept >= 4 and kept == len(seen)  # every orbit reported is in the file
    assert "interrupted" in ends[-1]
    msg = flat(res.stderr)
    assert name in msg and f"the {kept} periodic orbits" in msg and "c.h5" in msg and "incomplete" in msg
    assert invoke_cli("plot", "c.h5").returncode == 0
    assert (tmp_path / "c.png").is_file()


def test_an_interrupted_continue_never_replaces_a_complete_result(invoke_cli, here, tmp_path, monkeypatch):
    before = here["continuation"].read_bytes()
    _signal_after(monkeypatch, 3, signal.SIGINT)
    res = invoke_cli("continue", here["case"], "-o", here["continuation"])
    assert res.returncode == 130, res.stderr
    assert here["continuation"].read_bytes() == before
    partial = here["continuation"].with_name("cont.partial.h5")
    with h5py.File(partial) as f:
        assert not f["continuation"].attrs["complete"]
    assert "untouched" in flat(res.stderr)


def test_a_signal_while_a_slack_history_is_evaluated_keeps_it(invoke_cli, write_case, tmp_path, monkeypatch):
    """The instants of a history with slack episodes take seconds to evaluate after the time loop:
    a second Ctrl-C there lost the whole run."""
    import cablesim.dynamics.simulate as sim

    case = write_case(ONE_NODE.replace("FL: [0.0, 100.0]", "FL: [0.0, 30000.0]"))
    real = sim._slack_record

    def late_signal(*a, **k):
        os.kill(os.getpid(), signal.SIGINT)
        return real(*a, **k)

    monkeypatch.setattr(sim, "_slack_record", late_signal)
    res = invoke_cli("history", case, "--omega", "3.0", "--duration", "5", "-o", "h.h5")
    assert res.returncode == 130, (res.stderr, res.exception)
    assert "Traceback" not in res.stderr
    with h5py.File(tmp_path / "h.h5") as f:
        assert f["history"].attrs["completed"]
        assert f["history/events/t"].size > 0  # it went slack
        assert f["history/t"][-1] == pytest.approx(5.0)
    assert "holds the whole run" in flat(res.stderr)
    assert not list(tmp_path.glob("*.png"))  # an interrupted command draws nothing


def test_a_full_disk_while_the_continuation_is_written_is_one_message(invoke_cli, here, tmp_path, tmpfs, monkeypatch):
    import cablesim.cli_guard

    full = tmpfs("full", size="20k")
    monkeypatch.setattr(cablesim.cli_guard, "continue_room", lambda figures: 0.0)  # the disk fills meanwhile
    res = invoke_cli("continue", here["case"], "-o", full / "c.h5", "--no-plot")
    assert res.returncode == 2 and isinstance(res.exception, SystemExit), (res.stderr, res.exception)
    msg = flat(res.stderr)
    assert "Traceback" not in res.stderr and msg.startswith("error: Could not write")
    assert "disk" in msg and "\n\n" not in res.stderr.strip()
    # no result file; the journal keeps the orbits, and the message says how to finish from it
    assert list(full.iterdir()) == [full / "c.h5.journal"]
    assert "c.h5.journal" in msg and "--resume" in msg


def test_the_atomic_writer_turns_an_hdf5_flush_error_into_a_message(tmp_path, tmpfs):
    from cablesim.errors import CablesimError
    from cablesim.io.hdf5 import atomic_h5

    full = tmpfs("tiny", size="16k")
    with pytest.raises(CablesimError, match="Could not write") as err:
        with atomic_h5(full / "x.h5") as f:
            f.create_dataset("x", data=np.random.default_rng(0).random(4000))
    assert "Free some space" in str(err.value)
    assert list(full.iterdir()) == []


def test_the_room_check_counts_the_figures_of_a_history(invoke_cli, write_case, tmp_path, tmpfs):
    case = write_case(ONE_NODE)
    small = tmpfs("small", size="400k")
    assert_refused(invoke_cli("history", case, "--omega", "3.0", "--duration", "20", "-o", small / "h.h5"),
                   small, "MB free", "another disk")
    ok = invoke_cli("history", case, "--omega", "3.0", "--duration", "20", "--no-plot", "-o", small / "h.h5")
    assert ok.returncode == 0, ok.stderr  # without the figures it fits


def test_continue_checks_its_room_first(invoke_cli, here, tmp_path, tmpfs, no_compute):
    small = tmpfs("small", size="100k")
    assert_refused(invoke_cli("continue", here["case"], "-o", small / "c.h5"), small, "MB free")


# ----------------------------------------------------------------------------------------------
# 3. Flags: results that mean nothing are said to, in the message and in the file
# ----------------------------------------------------------------------------------------------
def test_an_empty_continuation_says_why_and_fails(invoke_cli, write_case, tmp_path):
    """Loads that make the cable slack from the first orbit: no silent exit 0 with "0 branch(es)"."""
    case = write_case(ONE_NODE.replace("FL: [0.0, 100.0]", "FL: [0.0, 30000.0]"))
    msg = assert_refused(invoke_cli("continue", case, "-o", "c.h5"), tmp_path, "found no periodic orbit",
                         "slack", "loads.FL", keep=(case,))
    assert "0 branch" not in msg


def _stored_warnings(path) -> list:
    import json

    with h5py.File(path) as f:
        return json.loads(f["history"].attrs["warnings"])


def test_strains_beyond_the_model_are_warned_and_stored(invoke_cli, write_case, tmp_path):
    from helpers_cli import EXAMPLE

    case = write_case(EXAMPLE)
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "h.h5",
                     "--set", "loads.FL=[0.0, 1.0e9, 0.0, 1.0e9]")
    assert res.returncode == 0, res.stderr
    assert "warning: the strain T/EA" in flat(res.stderr) and "small strains" in flat(res.stderr)
    stored = _stored_warnings(tmp_path / "h.h5")
    assert any("strain T/EA" in w for w in stored)
    ok = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--no-plot", "-o", "ok.h5")
    assert ok.returncode == 0 and "warning" not in ok.stderr and _stored_warnings(tmp_path / "ok.h5") == []


def test_a_drift_of_eq_15_beyond_its_bound_is_warned_and_stored(invoke_cli, write_case, tmp_path):
    from helpers_cli import EXAMPLE

    case = write_case(EXAMPLE)
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "60", "--no-plot", "-o", "h.h5",
                     "--integrator", "newmark", "--dt", "0.5")
    assert res.returncode == 0, res.stderr
    assert "warning: the drift of eq. 15" in flat(res.stderr)
    assert any("drift of eq. 15" in w for w in _stored_warnings(tmp_path / "h.h5"))
    from cablesim.io.hdf5 import read_history

    assert any("drift of eq. 15" in w for w in read_history(tmp_path / "h.h5").warnings)  # read back


# ----------------------------------------------------------------------------------------------
# 4. Strictness: the YAML rules in every section and in --set
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("setting, needles", [
    ("continuation.period='2'", ("continuation.period", "not text")),
    ("continuation={omega: {start: true, stop: 3.0}}", ("continuation.omega.start", "not true/false")),
    ("continuation={omega: {start: 1.0e-9, stop: 3.0}}", ("continuation.omega.start", "0.0001 to 10000 rad/s")),
    ("continuation={omega: {start: 2.0, stop: 1.0e300}}", ("continuation.omega.stop", "0.0001 to 10000 rad/s")),
    ("continuation={parameter: gamma, omega: 2.5, gamma: {start: 0.5, stop: 1.0e12}}",
     ("continuation.gamma.stop", "at most 1e+06")),
    ("continuation.segments=1.5", ("continuation.segments", "whole number")),
    ("continuation.max_points=yes", ("continuation.max_points", "not true/false")),
    ("continuation.channels=!!set {z1, z2}", ("--set continuation.channels", "!!set")),
    ("continuation.period=" + "7" * 5000, ("--set continuation.period", "5000 digits")),
], ids=["period-text", "start-bool", "omega-tiny", "omega-huge", "gamma-huge", "segments-real", "points-yes", "set-tag",
        "huge-int"])
def test_check_refuses_what_the_case_file_rules_refuse(invoke_cli, write_case, tmp_path, setting, needles):
    case = write_case(ONE_NODE)
    msg = assert_refused(invoke_cli("check", case, "--set", setting), tmp_path, *needles, keep=(case,))
    assert len(msg) < 600  # one paragraph, not the value echoed back


def test_a_set_tag_in_the_case_file_is_refused_with_its_line(invoke_cli, write_case, tmp_path):
    case = write_case(ONE_NODE.replace("channels: [z1, z2]}", "channels: !!set {z1, z2}}"))
    assert_refused(invoke_cli("continue", case), tmp_path, "line 6", "!!set", keep=(case,))


def test_check_estimates_what_continue_takes(invoke_cli, write_case):
    case = write_case(ONE_NODE)
    res = invoke_cli("check", case)
    assert res.returncode == 0, res.stderr
    line = next(x for x in res.stdout.splitlines() if x.startswith("#   continue:"))
    assert "on this machine" in line and " s " in line + " "


# ----------------------------------------------------------------------------------------------
# Resumes: journal records are checked like new results
# ----------------------------------------------------------------------------------------------
@pytest.fixture
def interrupted_sweep(invoke_cli, write_case, tmp_path, monkeypatch):
    """A sweep of the one-node cable stopped by Ctrl-C after its first point: (case, journal)."""
    import cablesim.cli
    from cablesim.io.terminal import LazyBar

    class Stop(LazyBar):
        def set(self, done, length=None):
            super().set(done, length)
            if done >= 1:
                os.kill(os.getpid(), signal.SIGINT)

    case = write_case(ONE_NODE)
    with monkeypatch.context() as m:
        m.setattr(cablesim.cli, "LazyBar", Stop)
        res = invoke_cli("sweep", case, "-o", "s.h5", "--jobs", "1", "--no-plot")
    assert res.returncode == 130, (res.stderr, res.exception)
    journal = tmp_path / "s.h5.journal"
    assert len([x for x in journal.read_text().splitlines() if x.strip()]) == 2  # settings and one point
    return case, journal


@pytest.mark.parametrize("value", ["NaN", "-0.5", "1e300", "Infinity"])
def test_a_resumed_journal_record_with_an_impossible_amplitude_is_computed_again(invoke_cli, interrupted_sweep,
                                                                                tmp_path, value):
    import json

    case, journal = interrupted_sweep
    head, rec = journal.read_text().splitlines()[:2]
    point = json.loads(rec)
    good = point["amplitude"][1]
    text = rec.replace(json.dumps(point["amplitude"]), f"[{point['amplitude'][0]}, {value}]", 1)
    assert text != rec
    journal.write_text(head + "\n" + text + "\n")
    res = invoke_cli("sweep", case, "-o", "s.h5", "--jobs", "1", "--no-plot", "--resume")
    assert res.returncode == 0, (res.stderr, res.exception)
    assert "journal line 2 was skipped" in flat(res.stderr) and "computed again" in flat(res.stderr)
    with h5py.File(tmp_path / "s.h5") as f:
        amp = f["sweep/amplitude"][()]
        omega = f["sweep/omega"][()]
    k = int(np.argmin(np.abs(omega - point["omega"])))
    assert np.isfinite(amp).all() and amp[k, 1] == pytest.approx(good, rel=1e-6)


def test_a_signal_while_the_orbit_kernel_compiles_is_acted_on_after_it(invoke_cli, here, tmp_path, monkeypatch):
    """The orbit kernel's entry point is compiled (or loaded from the cache) on its first use in a
    process; Ctrl-C inside numba's compiler left it broken (RuntimeError, a traceback, exit
    status 1)."""
    from cablesim.orbits import kernels

    real, done = kernels.flow_segment.compile, []

    def compile_(sig):
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C as the compilation starts
        out = real(sig)
        done.append(sig)
        return out

    monkeypatch.setattr(kernels.flow_segment, "compile", compile_)
    monkeypatch.setattr(kernels, "_ENTRIES", {})  # as in a fresh process
    res = invoke_cli("continue", here["case"], "-o", "c.h5")
    assert done, "the compilation was cut short by the signal"
    assert res.returncode == 130, (res.stderr, res.exception)
    assert "before any orbit was computed" in flat(res.stderr) and not (tmp_path / "c.h5").exists()


def test_sigterm_during_backbone_keeps_the_orbits_and_says_how_to_draw_them(invoke_cli, write_case, tmp_path,
                                                                            monkeypatch):
    import cablesim.cli_charts
    from cablesim.io.terminal import StatusLine

    class Stop(StatusLine):
        calls = 0

        def __call__(self, text):
            super().__call__(text)
            Stop.calls += 1
            if Stop.calls == 3:
                os.kill(os.getpid(), signal.SIGTERM)

    monkeypatch.setattr(cablesim.cli_charts, "StatusLine", Stop)
    case = write_case(ONE_NODE)
    res = invoke_cli("backbone", case, "--mode", "1", "--amplitude", "0.05", "-o", "bb.h5")
    assert res.returncode == 143, (res.stderr, res.exception)
    assert "SIGTERM" in res.stderr and "Traceback" not in res.stderr and "incomplete" in flat(res.stderr)
    with h5py.File(tmp_path / "bb.h5") as f:
        assert not f["backbone"].attrs["complete"] and f["backbone/omega"].size >= 3
    assert invoke_cli("plot", "bb.h5").returncode == 0
