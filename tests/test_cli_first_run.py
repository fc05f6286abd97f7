"""The first run: `cablesim check`, help texts with defaults and units, the notice while kernels
compile, sweep flags like history's, --quiet and --verbose."""

from __future__ import annotations

import sys
import time

import h5py
import pytest
import yaml

from helpers_cli import EXAMPLE, assert_refused, flat, result_like_files

COMMANDS = ["check", "static", "history", "free-vibration", "sweep", "plot", "stress"]


def test_check_prints_the_effective_case_and_each_commands_cost(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE)
    res = invoke_cli("check", case, "--set", "sweep.omega.num=11", "--set", "damping.ratio=0.02")
    assert res.returncode == 0, res.stderr
    body = yaml.safe_load(res.stdout)  # the comments are YAML comments: the output is a case file
    assert body["sweep"]["omega"]["num"] == 11 and body["damping"]["ratio"] == 0.02
    assert body["history"]["duration"] == 600.0 and body["sweep"]["tol"] == 1e-05  # defaults filled in
    assert "is valid" in res.stdout and "--set applied" in res.stdout
    out = flat(res.stdout)
    assert "# sweep: at most" in out and "11 points" in out and "refinement may add up to 62 more" in out
    assert "# history: about" in out
    assert result_like_files(tmp_path) == []


def test_check_estimates_a_history_given_in_the_case(invoke_cli, write_case):
    case = write_case(EXAMPLE.replace("  duration: 600.0 ", "  duration: 100.0 ", 1))
    res = invoke_cli("check", case)
    assert res.returncode == 0
    assert "# history: about" in flat(res.stdout) and "saved instants" in res.stdout


def test_check_refuses_a_bad_case_like_every_command(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE.replace("  H: 20.0", "  L: 1.0\n  H: 20.0"))
    assert_refused(invoke_cli("check", case), tmp_path, "appears twice", keep=(case,))


@pytest.mark.parametrize("command", COMMANDS)
def test_help_shows_defaults_and_units(command, invoke_cli):
    res = invoke_cli(command, "--help")
    assert res.returncode == 0
    text = flat(res.stdout)
    assert "default:" in text, text
    assert "[default: ...]" not in text
    if command in ("history", "free-vibration", "sweep"):
        assert "rad/s" in text or "m/s" in text
        assert ", s (default:" in text  # durations in seconds, with their default
        assert "--force" in text


def test_history_help_states_each_default(invoke_cli):
    text = flat(invoke_cli("history", "--help").stdout)
    for phrase in ("(default: history.omega in the case file)", "(default: history.duration, else 600)",
                   "(default: runs/<name>/history-w<omega>.h5)", "[default: plot]"):
        assert phrase in text, phrase


def _fresh_kernel():
    """A kernel numba has never seen (not cached): calling it compiles it."""
    from cablesim.jit import njit

    def kernel(x):
        return 2.0 * x + 1.0

    return njit(cache=False)(kernel)


def test_the_compile_notice_names_the_kernel_and_what_it_took():
    """Compilation was silent: the first history printed "simulated 60 s in 41.8 s"."""
    from cablesim import jit
    from cablesim.io.terminal import compiling

    lines = []
    with compiling(lines.append, delay=0.0) as notice:
        assert _fresh_kernel()(1.0) == 3.0
        time.sleep(0.2)  # the notice's timer
    assert notice.kernels() >= 1 and notice.seconds() > 0
    assert lines[0].startswith("compiling test_cli_first_run.kernel and the kernels it needs (first use on this machine")
    assert lines[-1].startswith(f"compiled {notice.kernels()} kernels in ") and "not counted in the run's times" in lines[-1]
    before = jit.kernels_compiled()
    quiet = []
    with compiling(quiet.append, delay=0.0):
        _fresh_kernel  # nothing compiles: nothing is said
    assert quiet == [] and jit.kernels_compiled() == before


def test_the_compile_notice_waits_so_a_quick_refusal_comes_alone():
    from cablesim.io.terminal import compiling

    lines = []
    with compiling(lines.append, delay=60.0):
        _fresh_kernel()(1.0)  # a compilation shorter than the delay, then a refusal: no notice
    assert lines == []


def test_sweep_takes_omega_duration_and_channels_like_history(invoke_cli, tmp_path):
    res = invoke_cli("sweep", "--omega", "3.0,4.0", "--duration", "300", "--set", "sweep.window=100",
                     "--channels", "z2", "--jobs", "1", "--no-plot", "-o", "s.h5")
    assert res.returncode == 0, res.stderr
    with h5py.File(tmp_path / "s.h5") as f:
        assert f["sweep/omega"][()].tolist() == [3.0, 4.0]
        assert f["sweep"].attrs["cap"] == 300.0
        assert [c.decode() for c in f["sweep"].attrs["channels"]] == ["z2"]
        assert "--omega 3.0,4.0" in f.attrs["command_line"]


def test_sweep_omega_grid_and_bad_spellings(invoke_cli, tmp_path):
    res = invoke_cli("sweep", "--omega", "3:4:2", "--duration", "300", "--set", "sweep.window=100",
                     "--set", "sweep.refine=false", "--jobs", "1",
                     "--no-plot", "-o", "g.h5")
    assert res.returncode == 0, res.stderr
    with h5py.File(tmp_path / "g.h5") as f:
        assert f["sweep/omega"][()].tolist() == [3.0, 4.0]
    (tmp_path / "g.h5").unlink()
    (tmp_path / "g.png").unlink(missing_ok=True)
    assert_refused(invoke_cli("sweep", "--omega", "fast", "--no-plot"), tmp_path, "--omega 'fast'", "START:STOP:NUM")
    assert_refused(invoke_cli("sweep", "--omega", "1:2", "--no-plot"), tmp_path, "--omega")
    assert_refused(invoke_cli("sweep", "--channels", "z99", "--no-plot"), tmp_path, "z99", "z1 to z4")


def test_channels_are_checked_before_the_run(invoke_cli, tmp_path):
    """--channels z99 was checked after the run and left the file behind."""
    assert_refused(invoke_cli("history", "--omega", "2.4", "--duration", "5", "--channels", "z99"), tmp_path,
                   "--channels", "z99", "out of range")
    assert_refused(invoke_cli("free-vibration", "--mode", "1", "--peak-velocity", "1", "--channels", "z2,,q"),
                   tmp_path, "--channels", "malformed")


def test_quiet_and_verbose_exclude_each_other(invoke_cli):
    res = invoke_cli("--quiet", "--verbose", "static")
    assert res.returncode == 2 and res.stderr.startswith("error: --quiet and --verbose exclude each other")
