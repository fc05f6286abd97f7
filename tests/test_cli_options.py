"""Command-line flags: ranges, conflicts and the messages that name the real cause and fix.

Every refusal: exit status 2, one paragraph, no traceback, no file left (in-process runs).
"""

from __future__ import annotations

import pytest

from helpers_cli import EXAMPLE, assert_refused

H = ["history", "--no-plot", "-o", "h.h5"]
FV = ["free-vibration", "--no-plot", "-o", "fv.h5"]

FLAGS = {
    "omega-0": (H + ["--omega", "0"], ["--omega must be from 0.0001 to 10000 rad/s", "got 0.0"]),
    "omega-nan": (H + ["--omega", "nan"], ["--omega must be", "got nan"]),
    "omega-negative": (H + ["--omega", "-2"], ["--omega must be"]),
    "duration-nan": (H + ["--omega", "2.4", "--duration", "nan"], ["--duration must be"]),
    "duration-inf": (H + ["--omega", "2.4", "--duration", "inf"], ["--duration must be", "got inf"]),
    "duration-1e308": (H + ["--omega", "2.4", "--duration", "1e308"], ["--duration must be greater than 0 and at most 1e+07 s"]),
    "output-step-0": (H + ["--omega", "2.4", "--output-step", "0"], ["--output-step must be greater than 0"]),
    "no-omega": (H + ["--set", "history.omega=null"], ["No forcing frequency", "--omega W", "history.omega"]),
    "mode-alone": (FV + ["--mode", "1", "--set", "free_vibration.peak_velocity=null"],
                   ["Mode 1", "--peak-velocity V too", "m/s"]),
    "peak-velocity-0": (FV + ["--mode", "1", "--peak-velocity", "0"], ["--peak-velocity must be greater than 0"]),
    "damping-ratio-1": (FV + ["--mode", "1", "--peak-velocity", "1", "--damping-ratio", "1"], ["--damping-ratio must be"]),
    "mode-0": (FV + ["--mode", "0", "--peak-velocity", "1"], ["--mode must be"]),
    "scheduler-without-dask": (["sweep", "--scheduler", "tcp://localhost:8786", "--no-plot"],
                               ["--scheduler", "only with --backend dask"]),
    "jobs-0": (["sweep", "--jobs", "0", "--no-plot"], ["--jobs must be a number of processes from 1 to"]),
}


@pytest.mark.parametrize("name", FLAGS)
def test_flags_out_of_range_or_conflicting(name, invoke_cli, tmp_path):
    args, needles = FLAGS[name]
    assert_refused(invoke_cli(*args), tmp_path, *needles)


def test_example_history_without_omega_says_what_to_give(invoke_cli, tmp_path):
    """`cablesim example > case.yaml; cablesim history case.yaml` once failed with a TypeError."""
    res = invoke_cli("example")
    assert res.returncode == 0
    (tmp_path / "case.yaml").write_text(res.stdout.replace("\n  omega: 2.4 ", "\n  # omega: 2.4 ", 1))
    assert_refused(invoke_cli("history", "case.yaml"), tmp_path, "No forcing frequency", "--omega",
                   keep=(tmp_path / "case.yaml",))


def test_rtol_in_the_file_conflicts_with_a_fixed_step_integrator(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE + "integrator:\n  rtol: 1.0e-6\n")
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--integrator", "rk4", "--no-plot")
    assert_refused(res, tmp_path, "--integrator rk4 conflicts", "integrator.rtol", "ignored", keep=(case,))


def test_dt_in_the_file_conflicts_with_dopri5(invoke_cli, write_case, tmp_path):
    case = write_case(EXAMPLE + "integrator:\n  name: rk4\n  dt: 0.01\n")
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--integrator", "dopri5", "--no-plot")
    assert_refused(res, tmp_path, "--integrator dopri5 conflicts", "integrator.dt", keep=(case,))


USAGE = {
    "not-a-number": (["history", "--omega", "abc"], ["Invalid value for '--omega'", "cablesim history --help"]),
    "unknown-option": (["history", "--bogus"], ["No such option: --bogus", "cablesim history --help"]),
    "unknown-command": (["frobnicate"], ["No such command 'frobnicate'", "cablesim --help"]),
    "unknown-choice": (["static", "--analysis", "foo"], ["'foo' is not one of 'exact', 'approximate'"]),
    "extra-argument": (["example", "x"], ["unexpected extra argument"]),
    "missing-value": (["history", "--omega"], ["--omega"]),
    "jobs-too-many": (["sweep", "--jobs", "100000", "--no-plot"], ["--jobs must be a number of processes from 1 to"]),
}


@pytest.mark.parametrize("name", USAGE)
def test_usage_errors_are_one_paragraph_with_exit_2(name, invoke_cli, tmp_path):
    args, needles = USAGE[name]
    assert_refused(invoke_cli(*args), tmp_path, *needles)


def test_cablesim_alone_prints_the_help(invoke_cli):
    res = invoke_cli()
    assert res.returncode == 0 and "Commands:" in res.stdout and "check" in res.stdout


def test_a_closed_output_pipe_is_no_traceback(tmp_path):
    import subprocess
    import sys

    cmd = f"{sys.executable} -m cablesim.cli example | head -c 10"
    res = subprocess.run(cmd, shell=True, cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert res.stdout == "# cablesim" and "Traceback" not in res.stderr and "Error" not in res.stderr


def test_a_displacement_beyond_the_cable_is_refused(invoke_cli, tmp_path):
    res = invoke_cli("free-vibration", "--set", "free_vibration.mode=null", "--set", "free_vibration.peak_velocity=null",
                     "--set", "free_vibration.z0=[1.0e5, 0.0, 0.0, 0.0]",
                     "--no-plot")
    assert_refused(res, tmp_path, "free_vibration.z0 moves a node by more than the cable's whole length (340 m)")


def test_plot_channels_outside_the_kept_ones_are_refused_before_the_run(invoke_cli, write_case, tmp_path):
    """--channels z1 with outputs.channels [z2] failed in the plot, after the file was written."""
    case = write_case(EXAMPLE + "outputs:\n  channels: [z2]\n")
    res = invoke_cli("history", case, "--omega", "2.4", "--duration", "5", "--channels", "z1", "-o", "h.h5")
    assert_refused(res, tmp_path, "--channels z1", "keeps only z2 (outputs.channels)", keep=(case,))
