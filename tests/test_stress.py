"""Stability under stress (``cablesim stress``): the reduced sweep, run in-process.

Every run of the reduced sweep must either succeed within its tolerances or stop cleanly with a
message that names the cause; none may produce NaN or a silently wrong answer. The harness itself
is checked too: it must flag a wrong answer and NaN in the outputs as FAILED.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import cablesim.stress as stress
from cablesim.dynamics.status import Status
from cablesim.stress import AXES, FAILED, OK, STOPPED, format_summary, run_stress, write_report
from cablesim.stress import cases as stress_cases
from cablesim.stress import run as stress_run


@pytest.fixture(scope="module")
def rows():
    return run_stress(reduced=True)


def test_no_run_failed(rows):
    failed = [r for r in rows if r["outcome"] == FAILED]
    assert not failed, format_summary(rows)


def test_outcomes_are_consistent(rows):
    for r in rows:
        assert r["outcome"] in (OK, STOPPED, FAILED)
        if r["outcome"] == OK:
            assert r["checks"]["finite"] == "ok" and r["checks"]["run"] == "ok"
            assert r["drift_pos"] <= r["drift_tol"]
            assert r["agreement"] <= r["agree_tol"]
        if r["outcome"] == STOPPED:
            assert r["message"], r
            assert r["checks"]["finite"] in ("ok", "na")


def test_every_axis_is_covered(rows):
    assert {r["axis"] for r in rows} == set(AXES)
    assert {r["analysis"] for r in rows} == {"exact", "approximate"}
    kinds = {r["integrator"].split()[0] for r in rows}
    assert {"dopri5", "rk4", "generalized-alpha"} <= kinds


def test_rk4_beyond_its_stability_limit_stops_cleanly(rows):
    beyond = [r for r in rows if r["axis"] == "step" and float(r["value"]) > 1.0]
    assert beyond
    clean = [r for r in beyond if r["outcome"] == STOPPED]
    assert clean, [(r["label"], r["outcome"], r["message"]) for r in beyond]
    for r in clean:
        assert r["message"].startswith("stopped at t =")
        assert r["checks"]["finite"] == "ok"
        assert re.search(r"step|stability", r["message"]), r["message"]


def test_rk4_beyond_its_limit_leaves_no_nan_anywhere():
    """Independently of the harness: every output array of such a run is finite."""
    from cablesim.dynamics.simulate import simulate
    from cablesim.dynamics.integrators import RK4

    case = next(c for c in stress_cases.build_cases(True) if c.axis == "step" and float(c.value) > 1.0)
    prep = stress_run._prepare(case, "exact", {})
    w_max = float(prep.static.modes.omega[-1])
    hist = simulate(prep.eom, RK4(dt=4.0 * stress_cases.RK4_LIMIT / w_max), case.duration, prep.output_step)
    assert hist.status is Status.SLACK and hist.message.startswith("stopped at t =")
    for name in ("t", "z", "v", "zc", "ze", "T", "residual"):
        assert np.all(np.isfinite(getattr(hist, name))), name


def test_slack_driving_load_stops_cleanly_naming_a_segment(rows):
    slack = [r for r in rows if r["axis"] == "slack" and r["outcome"] == STOPPED]
    named = [r for r in slack if re.search(r"[Ss]egment \d+", r["message"])]
    assert named, [(r["label"], r["message"]) for r in slack]
    dynamic = [r for r in named if r["message"].startswith("stopped at t =")]
    assert dynamic, "a time history driven slack by FL must stop with a message naming the segment"
    for r in dynamic:
        assert r["checks"]["diagnostic"] == "ok" and r["checks"]["finite"] == "ok"


def test_report_is_written(rows, tmp_path):
    md, png = write_report(rows, tmp_path / "docs" / "stability.md", tmp_path / "docs" / "stability.png", wall=1.0)
    text = md.read_text()
    assert "](stability.png)" in text
    for axis in AXES:
        assert f"### {stress_cases.AXIS_TITLES[axis]}" in text
    assert text.count("\n| ") >= len(rows)
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def _paper_case(duration=60.0):
    return stress_cases.StressCase("paper", "EA", "1e9", stress_cases._spec(), duration, (("exact", stress_cases.DOPRI),))


def test_harness_flags_a_silently_wrong_answer(monkeypatch):
    """A completed run 1 % off the reference must be FAILED, not ok."""
    from dataclasses import replace

    real = stress_run.simulate

    def wrong(eom, integ, *args, **kwargs):
        hist = real(eom, integ, *args, **kwargs)
        if integ.name == "dopri5" and integ.rtol == 1e-8:
            hist = replace(hist, z=hist.z * 1.01)
        return hist

    monkeypatch.setattr(stress_run, "simulate", wrong)
    row = stress_run.run_one(_paper_case(), "exact", stress_cases.DOPRI)
    assert row["outcome"] == FAILED and "silently wrong" in row["reason"]


def test_harness_flags_nan_in_outputs(monkeypatch):
    from dataclasses import replace

    real = stress_run.simulate

    def nan(eom, integ, *args, **kwargs):
        hist = real(eom, integ, *args, **kwargs)
        if integ.name == "dopri5" and integ.rtol == 1e-8:
            T = hist.T.copy()
            T[-1, 0] = np.nan
            hist = replace(hist, T=T)
        return hist

    monkeypatch.setattr(stress_run, "simulate", nan)
    row = stress_run.run_one(_paper_case(), "exact", stress_cases.DOPRI)
    assert row["outcome"] == FAILED and "non-finite" in row["reason"]


def test_cli_exit_status(rows, invoke_cli, monkeypatch, tmp_path):
    """Exit 0 when no run FAILED, 1 (with a message) otherwise; table, summary and files written."""
    good = [r for r in rows if r["outcome"] != FAILED]
    monkeypatch.setattr(stress, "run_stress", lambda reduced, jobs=1, progress=None: good)
    res = invoke_cli("stress", "--reduced", "--md", tmp_path / "s.md", "--png", tmp_path / "s.png")
    assert res.returncode == 0, res.stderr
    assert "runs:" in res.stdout and "### " in res.stdout
    assert (tmp_path / "s.md").is_file() and (tmp_path / "s.png").is_file()

    bad = good + [dict(good[0], outcome=FAILED, reason="injected")]
    monkeypatch.setattr(stress, "run_stress", lambda reduced, jobs=1, progress=None: bad)
    res = invoke_cli("stress", "--reduced", "--md", tmp_path / "s.md", "--png", tmp_path / "s.png")
    assert res.returncode == 1
    assert "FAILED" in res.stderr
