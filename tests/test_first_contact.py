"""First contact: the README's "Use" block runs as written on the file `cablesim example`
writes, and the everyday paths tell the truth (the shipped cases, result names, figures that go
with their results, flags placed anywhere, errors that name the flag, the API's ranges, the
check's estimates, an interrupted history that exits at once)."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

import cablesim
from helpers_cli import EXAMPLE, assert_refused, flat

REPO = Path(__file__).resolve().parents[1]
CLI = Path(sys.executable).with_name("cablesim")


def _use_block() -> list[str]:
    text = (REPO / "README.md").read_text()
    block = text.split("\n## Use\n", 1)[1].split("```sh\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def _start(line: str, cwd: Path) -> subprocess.Popen:
    words = shlex.split(line, comments=True)
    assert words[0] == ".venv/bin/cablesim", line
    out = None
    if ">" in words:  # `cablesim example > my-case.yaml`
        k = words.index(">")
        words, out = words[:k], open(cwd / words[k + 1], "w")
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.Popen([str(CLI), *words[1:]], cwd=cwd, stdout=out or subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


@pytest.mark.slow
def test_the_readmes_use_block_runs_as_written(tmp_path):
    """The walkthrough failed on the file `cablesim example` writes: `continue` (with and without
    a file), `history` without --omega and `free-vibration` without --mode all refused."""
    lines = _use_block()
    assert len(lines) >= 10 and lines[0].startswith(".venv/bin/cablesim example > my-case.yaml")
    # the lines that read another line's results wait for all the lines before them
    reads = [any(w.startswith("runs/") for w in shlex.split(x, comments=True)) for x in lines]
    stages = [lines[:1], [x for x, r in zip(lines[1:], reads[1:]) if not r], [x for x, r in zip(lines[1:], reads[1:]) if r]]
    for stage in stages:
        procs = [(line, _start(line, tmp_path)) for line in stage]
        for line, proc in procs:
            out, err = proc.communicate(timeout=600)
            assert proc.returncode == 0, (line, (out or "")[-1500:], err[-1500:])
    assert (tmp_path / "runs" / "my-case" / "sweep.h5").is_file()
    assert (tmp_path / "runs" / "my-case" / "continuation.png").is_file()
    assert (tmp_path / "runs" / "paper-example" / "static.h5").is_file()


#: Appended to the lines of the Use block that cost the most, for the quick version of its test.
QUICK = {"sweep": ["--set", "sweep.omega=[2.4, 2.5]", "--duration", "200", "--window", "50"],
         "continue": ["--set", "continuation.omega={start: 2.40, stop: 2.45}"],
         "check": ["--set", "continuation.omega={start: 2.40, stop: 2.45}"]}


@pytest.mark.slow(reason="about 24 s: every command of the README's use block; its results block runs in "
                        "test_views_readme")
def test_the_readmes_use_block_runs_with_short_sweeps(tmp_path):
    """The same block, its sweep and continuation over a short range (the test above runs it
    as written)."""
    lines = _use_block()
    for k, line in enumerate(lines):
        words = shlex.split(line, comments=True)
        extra = QUICK.get(words[1], [])
        proc = _start(shlex.join(words + extra) if extra else line, tmp_path)
        out, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, (line, (out or "")[-1500:], err[-1500:])
    assert (tmp_path / "runs" / "my-case" / "history-w2.4-d600-snapshots.png").is_file()


def test_example_lists_and_prints_the_shipped_cases(invoke_cli, tmp_path):
    listed = invoke_cli("example", "--list")
    assert listed.returncode == 0 and "heavy-span" in listed.stdout and "paper-example" in listed.stdout
    heavy = invoke_cli("example", "--name", "heavy-span")
    assert heavy.returncode == 0 and heavy.stdout == (REPO / "configs" / "heavy-span.yaml").read_text()
    assert_refused(invoke_cli("example", "--name", "no-such"), tmp_path, "no shipped case named 'no-such'",
                   "heavy-span, paper-example")
    every = {"history", "free_vibration", "sweep", "continuation", "integrator", "outputs", "modal"}
    assert every <= set(re.findall(r"^#? ?(\w+):", EXAMPLE, re.M))  # every section, the optional ones commented


def test_quiet_and_verbose_go_after_the_command_too(invoke_cli):
    quiet = invoke_cli("static", "--no-plot", "-o", "q.h5", "--quiet")
    assert quiet.returncode == 0 and quiet.stdout == ""
    verbose = invoke_cli("static", "--no-plot", "-o", "v.h5", "-v")
    assert verbose.returncode == 0 and "effective options: output = v.h5" in verbose.stderr


def test_a_flag_that_makes_the_window_too_long_is_named(invoke_cli, tmp_path):
    """`--duration 100` was reported as "sweep.window longer than sweep.duration" in the case file."""
    res = invoke_cli("sweep", "--omega", "1,2", "--duration", "100", "--no-plot")
    msg = assert_refused(res, tmp_path, "--duration 100 s is shorter than the case's sweep.window (200 s)",
                         "--window")
    assert "Case file" not in msg
    assert_refused(invoke_cli("sweep", "--omega", "1,2", "--duration", "300", "--window", "400", "--no-plot"),
                   tmp_path, "--window 400 s is longer than --duration 300 s")
    assert_refused(invoke_cli("sweep", "--omega", "1,2", "--window", "4000", "--no-plot"), tmp_path,
                   "--window 4000 s is longer than the case's sweep.duration (3000 s)")
    ok = invoke_cli("sweep", "--omega", "1,2", "--duration", "100", "--window", "20", "--jobs", "1", "--no-plot",
                    "-o", "w.h5")
    assert ok.returncode == 0, ok.stderr
    with h5py.File(tmp_path / "w.h5") as f:
        assert f["sweep"].attrs["window"] == 20.0 and f["sweep"].attrs["cap"] == 100.0


def test_error_paragraphs_never_cut_a_file_path(invoke_cli, tmp_path):
    deep = tmp_path / ("a-rather-long-folder-name-" * 4) / "case-file-with-a-long-name.yaml"
    res = invoke_cli("static", deep)
    assert res.returncode == 2
    assert str(deep) in res.stderr  # whole, on one line


def test_the_api_checks_its_numbers_and_names_its_own_arguments():
    """The API accepted omega=1e5, answered omega=-1 about --omega, raised a raw ValueError for NaN."""
    case = cablesim.load_case(None)
    for w in (1e5, -1.0, float("nan")):
        with pytest.raises(cablesim.errors.CablesimError, match=r"^omega must be from 0.0001 to 10000 rad/s"):
            cablesim.history(case, omega=w, duration=1.0)
    with pytest.raises(cablesim.errors.CablesimError, match="^damping_ratio must be"):
        cablesim.free_vibration(case, damping_ratio=1.5)
    with pytest.raises(cablesim.errors.CablesimError, match="--jobs must be"):
        cablesim.sweep(case, jobs=0)


def test_dir_lists_the_api():
    assert {"load_case", "static", "history", "free_vibration", "sweep", "continuation", "plot",
            "compile_kernels"} <= set(dir(cablesim))


def test_a_jpeg_output_is_refused_in_a_whole_sentence(invoke_cli, tmp_path):
    static = invoke_cli("static", "--no-plot", "-o", "s.h5")
    assert static.returncode == 0
    msg = assert_refused(invoke_cli("plot", "s.h5", "-o", "x.jpg"), tmp_path, keep=(tmp_path / "s.h5",))
    assert "names a figure, so its name must end in .png, .pdf or .svg (or have no suffix" in msg
    assert ".jpg files are not written" in msg and "-o x.png" in msg


def test_the_license_is_a_spdx_string():
    """The table form `{text = "MIT"}` drew a deprecation warning at every install."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert project["project"]["license"] == "MIT"
    assert any(r.startswith("setuptools>=77") for r in project["build-system"]["requires"])


def test_check_fills_in_what_cablesim_chooses_and_estimates_in_seconds(invoke_cli, write_case):
    """`check` printed `integrator: {}` as "every default filled in", gave no estimate for
    `continue`, and never a time."""
    res = invoke_cli("check", write_case(EXAMPLE))
    assert res.returncode == 0, res.stderr
    out = flat(res.stdout)
    assert "integrator: {}" not in res.stdout and "modal: {}" not in res.stdout
    assert "# integrator: none given: dopri5 (rtol = 1e-08" in out and "for a history at 2.4 rad/s" in out
    assert re.search(r"# history: about [\d.]+ (s|min) on this machine", out)
    assert re.search(r"# continue: about \d+ orbits on the first branch, .*about [\d.]+ (s|min) on this machine", out)
    assert re.search(r"# backbone: at most \d+ orbits, at most [\d.e+]+ Runge-Kutta steps", out)
    assert re.search(r"# sweep: at most [\d.]+ (s|min|h) of one core", out)


def test_names_differ_with_the_flags_and_a_replaced_result_is_named(invoke_cli, tmp_path):
    """Default names left out the integrator and the analysis; results were replaced silently,
    and --no-plot left the old figures beside the new file."""
    args = ["history", "--omega", "2.4", "--duration", "5"]
    assert invoke_cli(*args).returncode == 0
    folder = tmp_path / "runs" / "paper-example"
    pngs = sorted(folder.glob("history-w2.4-d5-*.png"))
    assert len(pngs) == 5
    rk4 = invoke_cli(*args, "--integrator", "rk4", "--no-plot")
    assert rk4.returncode == 0 and (folder / "history-w2.4-d5-rk4.h5").is_file()
    again = invoke_cli(*args, "--no-plot")
    assert again.returncode == 0
    assert f"note: replacing {Path('runs/paper-example/history-w2.4-d5.h5')}, a complete history result of 5 s" \
        in flat(again.stderr)
    assert not any(p.exists() for p in pngs)  # the old figures went with the old result
    assert invoke_cli("static", "--analysis", "approximate", "--no-plot").returncode == 0
    assert (folder / "static-approximate.h5").is_file()


def test_a_sweep_of_other_frequencies_does_not_replace_the_sweep(invoke_cli, tmp_path):
    """A 2-point sweep replaced a complete 56-point sweep.h5."""
    res = invoke_cli("sweep", "--omega", "2.0,3.0", "--duration", "100", "--window", "20", "--jobs", "1", "--no-plot")
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "runs" / "paper-example" / "sweep-w2,3.h5").is_file()
    assert not (tmp_path / "runs" / "paper-example" / "sweep.h5").exists()


def test_the_sweep_summary_of_many_channels_stays_short():
    """A 200-channel case printed 206 lines."""
    from cablesim.analyses.sweep import new_sweep_result
    from cablesim.analyses.sweep_points import SweepPoint
    from cablesim.io.report import sweep_summary

    case = cablesim.load_case(REPO / "configs" / "heavy-span.yaml", ["sweep={omega: [2.0, 2.2], duration: 10.0, "
                                                                      "window: 5.0}"])
    res = new_sweep_result(case, case.text)
    C = len(res.channels)
    assert C == 200
    for w in res.omega:
        res.add(SweepPoint.from_json({"curve": 0, "omega": float(w), "amplitude": [0.1] * C, "halfrange": [0.1] * C,
                                      "response_frequency": [float(w)] * C, "period": 1, "steady": True, "t_end": 10.0,
                                      "floquet": None, "code": 0}, C, res.n_dof))
    short = sweep_summary(case, res, 1.0)
    assert len(short.splitlines()) < 30 and "(190 more channels)" in short
    assert len(sweep_summary(case, res, 1.0, full=True).splitlines()) > 200


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_sigterm_stops_a_history_without_drawing_its_figures(tmp_path):
    """SIGTERM took 8.7 s: five PNGs were drawn after it."""
    log = tmp_path / "err.txt"
    with open(log, "w") as err_file:
        proc = subprocess.Popen([str(CLI), "history", "--omega", "2.4", "--integrator", "rk4", "--set",
                                 "integrator.dt=1e-5", "--force", "--duration", "2000", "-o", "h.h5"], cwd=tmp_path,
                                stdout=subprocess.DEVNULL, stderr=err_file, text=True,
                                env=dict(os.environ, MPLBACKEND="Agg"))
    try:
        end = time.monotonic() + 120
        while "simulating" not in log.read_text() and time.monotonic() < end and proc.poll() is None:
            time.sleep(0.1)
        time.sleep(1.0)  # well into the integration
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    err = log.read_text()
    assert proc.returncode == 143, err
    assert not list(tmp_path.glob("*.png")) and "No figures were drawn" in flat(err)
    with h5py.File(tmp_path / "h.h5") as f:
        assert f["history"].attrs["status"].startswith("interrupted")


def test_free_vibration_lasts_as_long_as_its_motion():
    """The README's free vibration drew 20 s of flat line for 0.6 s of motion."""
    case = cablesim.load_case(None)
    run = cablesim.free_vibration(case)  # mode 3, 1 m/s, xi = 0.2: from the example's section
    t, a = run.history.t, np.abs(run.history.z).max(axis=1)
    moving = t[a > 0.01 * a.max()]
    assert t[-1] < 2.0 and moving[-1] > 0.4 * t[-1]  # the motion fills the record ...
    assert a[t > 0.75 * t[-1]].max() < 0.01 * a.max()  # ... which ends once it has died out
