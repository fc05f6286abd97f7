"""Continuation in the support motion multiplier s (``continuation.parameter: support``).

- the orbit at s is the orbit of the same case with its support amplitudes multiplied by s,
  solved another way (a case written with the scaled amplitudes, continued in omega from the
  same frequency), on a case with harmonic loads FL too, so that s (the supports alone) and
  gamma (FL and the supports) differ;
- the threshold of parametric resonance of a taut stay excited along its chord, against the
  independent planar shooting and Hill multipliers of ``helpers_whirl_cases.PlanarBranch``;
- the HDF5 file read back with h5py, the figure's axis (what s = 1 stands for), the CSV export;
- the refusals, and the README's example as written.
"""

from __future__ import annotations

import csv
import re
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from scipy.optimize import brentq

import cablesim
from cablesim.errors import CablesimError
from helpers_cli import assert_refused
from helpers_figures import text_problems
from helpers_whirl import cable_from_case
from helpers_whirl_cases import STAY_CASE, PlanarBranch

REPO = Path(__file__).resolve().parents[1]
STAY = REPO / "configs" / "stay-parametric.yaml"
PAPER = REPO / "configs" / "paper-example.yaml"
#: Support A's amplitude of the small case, m, and its fixed forcing frequency, rad/s.
AMPLITUDE = (0.004, 0.008)
OMEGA = 3.0  # below the first natural frequency (8.7 rad/s)
GAMMA = 0.8


def small_case(amplitude, continuation: dict):
    """Two masses on a sagging cable, forced by FL and by support A's motion (phase 0.3 rad)."""
    return cablesim.load_case({
        "name": "small", "cable": {"L": 2.0, "H": 0.2, "S": [0.75, 0.7, 0.7], "EA": 2000.0, "masses": [1.0, 1.5]},
        "loads": {"gravity": 9.81, "FL": [0.2, 0.5, -0.1, 0.4]},
        "supports": {"A": {"amplitude": [float(a) for a in amplitude], "phase": 0.3}},
        "damping": {"ratio": 0.02}, "continuation": continuation})


@pytest.fixture(scope="module")
def in_support():
    """The small case continued in s from 0.2 to 1.5 at omega = 3 rad/s, gamma = 0.8."""
    case = small_case(AMPLITUDE, {"parameter": "support", "omega": OMEGA, "gamma": GAMMA,
                                  "support": {"start": 0.2, "stop": 1.5}, "switch_branches": False})
    return cablesim.continuation(case).result


def orbit_with_scaled_supports(s: float, gamma: float = GAMMA):
    """The first orbit of the small case written with its support amplitudes times ``s``,
    continued in omega from OMEGA (gamma fixed): ``(amplitude, state)``."""
    case = small_case(np.multiply(AMPLITUDE, s), {"omega": {"start": OMEGA, "stop": OMEGA * 1.0005},
                                                    "gamma": gamma, "switch_branches": False})
    b = cablesim.continuation(case).result.branches[0]
    assert b.omega[0] == OMEGA and np.all(b.support == 1.0)
    return b.amplitude[0], b.state[0]


def test_orbit_at_s_is_the_orbit_of_the_case_with_its_support_amplitudes_times_s(in_support):
    (b,) = in_support.branches
    assert b.end == "bound reached" and b.parameter.size > 5
    np.testing.assert_array_equal(b.support, b.parameter)
    assert np.all(b.omega == OMEGA) and np.all(b.gamma == GAMMA)
    assert b.support[0] == 0.2 and abs(b.support[-1] - 1.5) < 1e-12
    for k in (b.support.size // 3, b.support.size - 1):  # inside the range and at its end
        amplitude, state = orbit_with_scaled_supports(float(b.support[k]))
        np.testing.assert_allclose(b.amplitude[k], amplitude, rtol=1e-8)
        np.testing.assert_allclose(b.state[k], state, rtol=0, atol=1e-8 * np.abs(state).max())


def test_the_support_multiplier_is_not_gamma(in_support):
    """gamma multiplies FL and the supports' motion, s the supports alone: at equal values the
    orbits differ (FL enters at 0.8 in one and at 0.2 in the other), and the gamma continuation's
    support column is 1 throughout."""
    (b,) = in_support.branches
    case = small_case(AMPLITUDE, {"parameter": "gamma", "omega": OMEGA, "gamma": {"start": 0.2, "stop": 1.5},
                                  "switch_branches": False})
    (g,) = cablesim.continuation(case).result.branches
    assert np.all(g.support == 1.0) and g.parameter[0] == b.parameter[0] == 0.2
    assert np.abs(g.amplitude[0] / b.amplitude[0] - 1).max() > 0.1
    # the orbit of the gamma continuation at gamma = 0.2 is that of s = 1 at gamma = 0.2
    amplitude, _ = orbit_with_scaled_supports(1.0, gamma=0.2)
    np.testing.assert_allclose(g.amplitude[0], amplitude, rtol=1e-8)


def test_a_fixed_support_multiplier_in_omega_scales_the_supports_alone():
    """continuation.support as a single value, in an omega continuation: the orbits of the case
    written with its support amplitudes times that value."""
    case = small_case(AMPLITUDE, {"omega": {"start": OMEGA, "stop": OMEGA * 1.0005}, "gamma": GAMMA, "support": 0.35,
                                  "switch_branches": False})
    (b,) = cablesim.continuation(case).result.branches
    assert np.all(b.support == 0.35) and np.all(b.gamma == GAMMA)
    amplitude, state = orbit_with_scaled_supports(0.35)
    np.testing.assert_allclose(b.amplitude[0], amplitude, rtol=1e-8)
    assert np.abs(orbit_with_scaled_supports(1.0)[0] / amplitude - 1).max() > 0.1  # s matters here


def stay(nodes: int, omega: float, **continuation):
    data = yaml.safe_load(STAY_CASE.format(nodes=nodes, omega=omega))
    data["continuation"] = {"parameter": "support", "omega": omega, "switch_branches": False, **continuation}
    return cablesim.load_case(data)


def test_threshold_of_parametric_resonance_of_a_stay_is_an_out_of_plane_period_doubling():
    """At omega near twice the first natural frequency, the planar response of the stay loses
    stability out of its plane at s_c: an out-of-plane multiplier through -1, where the Hill
    multipliers of the independent planar orbit have modulus 1 (without gravity the stay is
    symmetric about its chord: an in-plane period doubling at the same s)."""
    omega = 12.0835669
    case = stay(6, omega, support={"start": 0.05, "stop": 0.5})
    res = cablesim.continuation(case).result
    out = [b for b in res.bifurcations if b.plane == "out-of-plane"]
    assert [b.kind for b in out] == ["period-doubling"], [(b.kind, b.plane, b.parameter) for b in res.bifurcations]
    (pd,) = out
    assert pd.located and pd.trusted and abs(pd.multiplier + 1) < 1e-9
    assert pd.support == pd.parameter and pd.omega == omega and pd.gamma == 1.0
    branch = PlanarBranch(cable_from_case(case))
    s_c = brentq(lambda g: abs(branch.out_of_plane(omega, g)[0]) - 1, 0.1, 0.5, xtol=1e-12)
    assert abs(pd.parameter - s_c) < 1e-6, (pd.parameter, s_c)  # measured 5e-12
    b = res.branches[0]
    away = np.abs(b.support - s_c) > 1e-6  # (the located point itself has |mu| = 1)
    assert b.stable[away & (b.support < s_c)].all() and not b.stable[away & (b.support > s_c)].any()


@pytest.fixture(scope="module")
def stay_file(tmp_path_factory):
    """The shipped stay example continued through the API and written as ``cablesim continue``
    writes it."""
    run = cablesim.continuation(cablesim.load_case(STAY))
    path = run.to_hdf5(tmp_path_factory.mktemp("stay") / "continuation.h5")
    return run, path


def test_file_holds_the_support_column_and_the_amplitude_it_multiplies(stay_file):
    run, path = stay_file
    res = run.result
    with h5py.File(path, "r") as f:
        g = f["continuation"]
        assert g.attrs["parameter"] == "support" and g.attrs["fixed"] == 12.0835669 and g.attrs["gamma"] == 1.0
        for b in res.branches:
            ds = g[f"branches/{b.name}/support"]
            np.testing.assert_array_equal(ds[()], b.support)
            np.testing.assert_array_equal(g[f"branches/{b.name}/parameter"][()], b.support)
            assert ds.attrs["units"] == "1" and "supports:" in ds.attrs["description"]
            np.testing.assert_array_equal(ds.attrs["amplitude_A"], [0.004, -0.003, 0.0])
            assert "amplitude_B" not in ds.attrs and ds.attrs["amplitude_units"] == "m"
        np.testing.assert_array_equal(g["support_amplitude"][()], [[0.004, -0.003, 0.0]])
        assert g["support_amplitude"].attrs["units"] == "m" and list(g["support_amplitude"].attrs["supports"]) == [b"A"]
        fb = g["bifurcations"]
        kinds = [k.decode() for k in fb["kind"][()]]
        planes = [p.decode() for p in fb["plane"][()]]
        k = planes.index("out-of-plane")
        assert kinds[k] == "period-doubling"
        ours = next(b for b in res.bifurcations if b.plane == "out-of-plane")
        assert fb["support"][k] == ours.support == fb["parameter"][k]
        assert abs(fb["support"][k] - 0.2407) < 1e-4 and fb["omega"][k] == 12.0835669
    exported = cablesim.export_csv(path, path.parent / "csv")
    column = next(p for p in exported if p.name == "continuation_branches_b0-p1_support.csv")
    with column.open() as fh:
        rows = list(csv.reader(line for line in fh if not line.startswith("#")))
    assert rows[0][-1].startswith("support") and "(1)" in rows[0][-1]
    np.testing.assert_allclose([float(r[-1]) for r in rows[1:]], res.branches[0].support, rtol=1e-15)


def test_plot_command_labels_the_axis_with_the_anchorage_amplitude(stay_file, invoke_cli, tmp_path, monkeypatch):
    """`cablesim plot` of the file: the x axis says what s = 1 stands for; each panel's DOF is
    named with three components per node (z8 of a spatial cable is node 3's vertical, which the
    planar numbering called node 4's)."""
    from matplotlib.figure import Figure

    _, path = stay_file
    drawn = {}
    real = Figure.savefig

    def spy(self, fname, *args, **kwargs):
        drawn["x"] = self.axes[-1].get_xlabel()
        drawn["y"] = [ax.get_ylabel() for ax in self.axes]
        drawn["problems"] = text_problems(self)
        return real(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    res = invoke_cli("plot", path, "-o", tmp_path / "stay.png")
    assert res.returncode == 0, (res.stdout, res.stderr, res.exception)
    assert (tmp_path / "stay.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert drawn["x"] == "support motion multiplier $s$ (s = 1: $|u_A|$ = 5.0 mm)"
    assert "node 3, horizontal" in drawn["y"][0] and "node 3, vertical (down +)" in drawn["y"][1], drawn["y"]
    assert drawn["problems"] == []


def test_summary_names_the_parameter_and_what_it_multiplies(stay_file):
    from cablesim.io.report import continuation_summary

    run, _ = stay_file
    text = continuation_summary(run.case, run.result, 1.0)
    first = text.splitlines()[0]
    assert "in support motion multiplier s from 0 to 0.5" in first
    assert "omega = 12.0836 rad/s, gamma = 1" in first and "s = 1: |u_A| = 5.0 mm" in first
    row = next(line for line in text.splitlines() if "out-of-plane" in line and "period-doubling" in line)
    assert re.search(r"\b0\.2407\d*\b", row)


def test_report_table_lists_each_bifurcation_at_its_s_and_plane(stay_file):
    from cablesim.io.report_tables import continuation_tables

    _, path = stay_file
    (_, table), _ = continuation_tables(path)
    assert table.columns[:4] == ["kind", "plane", "s", "ω (rad/s)"] and "|u_A| = 5.0 mm" in table.note
    with h5py.File(path, "r") as f:
        fb = f["continuation/bifurcations"]
        np.testing.assert_allclose([row[2].value for row in table.rows], fb["support"][()], rtol=1e-12)
        assert [row[1].text for row in table.rows] == [p.decode() for p in fb["plane"][()]]


CONT = "continuation={parameter: support, omega: 2.0, support: {start: 0.0, stop: 1.0}}"
MOVING = "supports={A: {amplitude: [0.1, 0.2]}}"


@pytest.mark.parametrize("case_file, args, needles", [
    (PAPER, ["--set", CONT], ["continuation.support", "no support of this case moves",
                              "`supports: {A: {amplitude: [0.004, -0.003]}}`"]),
    (STAY, ["--set", "continuation.parameter=omega", "--set", "continuation.omega={start: 11.0, stop: 13.0}"],
     ["continuation.support is a range, but the parameter is omega", "parameter: support"]),
    (STAY, ["--set", "continuation.gamma={start: 0.5, stop: 1.0}"],
     ["continuation.gamma must be a single value when the parameter is support"]),
    (STAY, ["--set", "continuation.support={start: -0.5, stop: 0.5}"], ["continuation.support.start", "from 0"]),
    (STAY, ["--set", "continuation.loci=true"], ["continuation.loci needs the response in omega",
                                                  "continuation.support"]),
    (PAPER, ["--set", MOVING, "--set", "continuation={omega: {start: 2.0, stop: 2.1}, gamma: {start: 0.5, "
             "stop: 1.0}, support: {start: 0.1, stop: 0.5}, loci: true}"],
     ["continuation.loci: both continuation.gamma and continuation.support are ranges", "single value"]),
    (PAPER, ["--set", "continuation={omega: {start: 2.0, stop: 2.1}, support: {start: 0.1, stop: 0.5}, "
             "loci: true}"], ["continuation.loci with continuation.support a range", "no support of this case moves",
                              "continuation.gamma"]),
    (STAY, ["--set", "continuation={omega: {start: 11.0, stop: 13.0}, support: {start: 0.1, stop: 0.5, at: 0.7}, "
            "loci: true}"], ["continuation.support.at (0.7) must lie between"]),
    (STAY, ["--set", "continuation.support={start: 0.1, stop: 0.5, levels: [0.3]}"],
     ["continuation.support.at and continuation.support.levels are used only with loci: true"]),
    (PAPER, ["--set", MOVING, "--set", CONT, "--analysis", "approximate"],
     ["supports: moving supports need the exact analysis", "--analysis approximate"]),
    (PAPER, ["--set", MOVING, "--set", CONT, "--set", "analysis=approximate"],
     ["supports: moving supports need the exact analysis; set analysis: exact"]),
], ids=["no-moving-support", "support-range-in-omega", "gamma-range-in-support", "negative", "loci-in-support",
        "loci-both-ranges", "loci-support-no-moving-support", "loci-support-at-outside", "support-levels-without-loci",
        "approximate-flag", "approximate-case"])
def test_refusals_name_the_field_and_the_fix(invoke_cli, tmp_path, case_file, args, needles):
    res = invoke_cli("continue", case_file, "-o", tmp_path / "c.h5", *args)
    assert_refused(res, tmp_path, *needles)


def test_approximate_analysis_flag_with_moving_supports_is_refused_by_every_command(invoke_cli, tmp_path):
    """`--analysis approximate` on a case with moving supports ended in a traceback from the
    equations of motion (exit status 1); the case file's `analysis: approximate` was refused."""
    res = invoke_cli("history", PAPER, "--set", MOVING, "--analysis", "approximate", "--duration", "1",
                     "-o", tmp_path / "h.h5")
    assert_refused(res, tmp_path, "supports: moving supports need the exact analysis")
    case = cablesim.load_case(PAPER, overrides=[MOVING, CONT])
    with pytest.raises(CablesimError, match="moving supports need the exact analysis"):
        cablesim.continuation(case, analysis="approximate")


def readme_section() -> str:
    text = (REPO / "README.md").read_text()
    return text.split("### Support excitation of stays")[1].split("\n### ")[0]


def test_readme_example_runs_as_written(invoke_cli, tmp_path):
    """The README's commands, run in a copy of the repository's configs; the bifurcation it
    quotes is the one the run finds."""
    shutil.copytree(REPO / "configs", tmp_path / "configs", ignore=shutil.ignore_patterns("paper"))
    section = readme_section()
    (block,) = re.findall(r"```sh\n(.*?)```", section, re.S)
    outputs = []
    for line in block.strip().splitlines():
        command = line.split("#")[0].split()
        assert command[0] == ".venv/bin/cablesim"
        res = invoke_cli(*command[1:])
        assert res.returncode == 0, (line, res.stdout, res.stderr, res.exception)
        outputs.append(res.stdout)
    assert (tmp_path / "runs/stay-parametric/continuation.h5").is_file()
    assert (tmp_path / "runs/stay-parametric/continuation.png").is_file()
    with h5py.File(tmp_path / "runs/stay-parametric/continuation.h5", "r") as f:
        fb = f["continuation/bifurcations"]
        planes = [p.decode() for p in fb["plane"][()]]
        s_c = float(fb["support"][planes.index("out-of-plane")])
    quoted = float(re.search(r"s_c = ([\d.]+)", section).group(1))
    assert abs(s_c - quoted) < 5e-5
    assert "s = 1: |u_A| = 5.0 mm" in outputs[0]
