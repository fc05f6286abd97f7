"""Frequency sweeps: steady-state detection, subharmonics and late jumps, hysteresis of up/down
sweeps, the journal and --resume, settings errors, the Dask backend and the HDF5 layout.

Every case is the paper example (``cablesim.case.example_text()``) with its ``sweep:`` section
replaced. Sweeps run in-process through ``run_sweep`` (module-scoped fixtures, small grids); a
few end-to-end checks run the real command in a subprocess (kill, Ctrl-C, Dask).

Numbers measured on this model (exact analysis) that the tests rely on:

- linear regime (FL x 1e-4, xi = 0.05): steady after 140-390 s; amplitudes match the closed form
  ``|(K0 - w^2 M + i w C)^-1 FL|`` to 1e-4..3e-4 relative;
- w = 5.05, xi = 0.01: the small harmonic response (|z2| ~ 0.10 m) starts to grow at ~1000 s,
  jumps over 1500-2500 s to the 1/2 subharmonic (|z2| = 4.08 m at 2.525 rad/s), which the
  default criterion finds steady at t = 3113 s (a 3000 s cap finds it at its very last check,
  t = 3002 s; a 2800 s cap does not find it at all);
- gamma = 5, xi = 0.01: up and down sweeps differ between 2.2 and 2.3 rad/s (e.g. |z2| = 4.3 m
  up vs 30.1 m down at 2.2 rad/s); they agree to 1e-4 at 2.0-2.1 and 2.4-2.7 rad/s.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

from cablesim.analyses.static import run_static
from cablesim import api
from cablesim.case import example_text, parse_case
from cablesim.errors import CablesimError

BASE = example_text()
HEAD = BASE[: BASE.index("\nsweep:") + 1]  # everything before the sweep section
RESULT_FIELDS = ("amplitude", "halfrange", "period", "steady", "response_frequency", "t_end", "floquet", "done")
PER_CHANNEL = ("amplitude", "halfrange", "response_frequency")
UNITS = {
    "amplitude": "m",
    "halfrange": "m",
    "response_frequency": "rad/s",
    "period": "forcing periods",
    "steady": "1",
    "t_end": "s",
    "floquet": "1",
    "done": "1",
}
#: A tight DOPRI5 so that a tiny (linear) response is accurate to well below 1e-3 of itself.
TIGHT = {"name": "dopri5", "rtol": 1.0e-10, "atol": 1.0e-14}


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------
def run_sweep(case, text, out, n_jobs=1, resume=False, progress=None):
    """The sweep as ``cablesim sweep -o out`` runs it: journal and HDF5 file kept current."""
    assert case.text == text
    return api.sweep(case, jobs=n_jobs, output=out, resume=resume, progress=progress).result


def case_text(sweep: dict | None, *, xi: float | None = None, integrator: dict | None = None) -> str:
    """The paper example with its sweep section replaced (None: no sweep section)."""
    head = HEAD
    if xi is not None:
        head, n = re.subn(r"ratio: 0\.01\b", f"ratio: {xi}", head)
        assert n == 1
    if integrator is not None:
        head += yaml.safe_dump({"integrator": integrator}, default_flow_style=None)
    if sweep is None:
        return head
    return head + yaml.safe_dump({"sweep": sweep}, default_flow_style=None, sort_keys=False)


def do_sweep(out: Path, sweep: dict, n_jobs: int = 2, **kw):
    text = case_text(sweep, **kw)
    case = parse_case(text)
    res = run_sweep(case, text, out, n_jobs=n_jobs)
    return case, text, res


def read_sweep(path: Path) -> dict:
    """Every dataset of a sweep file, by path relative to /sweep ("amplitude", "up/amplitude")."""
    data = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                data[name] = obj[()]

        f["sweep"].visititems(visit)
        data["/attrs"] = dict(f["sweep"].attrs)
    return data


def assert_same_results(a: dict, b: dict) -> None:
    """Same datasets with the same values (NaN == NaN); the wall-clock times may differ."""
    keys = {k for k in a if k != "/attrs" and not k.endswith("wall")}
    assert keys == {k for k in b if k != "/attrs" and not k.endswith("wall")}
    for k in sorted(keys):
        assert a[k].shape == b[k].shape, k
        assert np.array_equal(a[k], b[k], equal_nan=True), (k, a[k], b[k])


def closed_form(case, omega, gamma) -> np.ndarray:
    """|H(w) gamma FL| per DOF, rows = frequencies, H = (K0 - w^2 M + i w C)^-1."""
    st = run_static(case, None, all_models=False)
    M = np.diag(np.repeat(np.array(case.cable.masses), 2))
    C = st.a0 * M + st.a1 * st.K0
    return np.array([np.abs(np.linalg.solve(st.K0 - w * w * M + 1j * w * C, gamma * case.FL)) for w in omega])


def _cli_command() -> list[str]:
    script = Path(sys.executable).with_name("cablesim")
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, "-m", "cablesim.cli"]


def start_cli(args, cwd: Path) -> subprocess.Popen:
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    return subprocess.Popen(
        [*_cli_command(), *map(str, args)], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env=env, start_new_session=True,
    )


def finish_cli(proc: subprocess.Popen, timeout: float = 180.0) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise
    return proc.returncode, out, err


def journal_records(path: Path) -> int:
    """Complete records in a journal (lines after the header that end with a newline)."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return 0
    return max(text.count("\n") - 1, 0)


def wait_for_records(proc: subprocess.Popen, journal: Path, n: int, timeout: float = 120.0, until=None) -> int:
    """Wait until ``n`` points are journalled (and ``until()`` holds, unless ``n + 8`` are)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        k = journal_records(journal)
        if k >= n and (until is None or until() or k >= n + 8):
            return k
        if proc.poll() is not None:
            _, err = proc.communicate()
            pytest.fail(f"the sweep ended (status {proc.returncode}) before {n} points were done:\n{err}")
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    pytest.fail(f"fewer than {n} points done after {timeout} s")


class Stop(Exception):
    """Raised from a progress callback to interrupt a sweep in-process."""


def stop_after(n: int):
    def progress(done, total):
        if done >= n:
            raise Stop

    return progress


@pytest.fixture(scope="module")
def wdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("sweep")


# ----------------------------------------------------------------------------------------------
# 1. Linear regime: closed-form amplitudes
# ----------------------------------------------------------------------------------------------
LIN_W = [1.0, 2.3, 2.52, 2.7, 4.0, 6.0]  # fundamental 2.524 rad/s; mode 2 at 13.0 rad/s
LIN_GAMMA = [1.0e-4, 2.0e-4]
LIN_SWEEP = {"omega": LIN_W, "duration": 1500.0, "window": 100.0, "channels": ["z1", "z2", "z3", "z4"], "gamma": LIN_GAMMA}


@pytest.fixture(scope="module")
def linear(wdir):
    out = wdir / "linear.h5"
    case, text, res = do_sweep(out, LIN_SWEEP, xi=0.05, integrator=TIGHT)
    return case, res, out


def test_linear_amplitudes_match_closed_form(linear):
    case, res, _ = linear
    assert res.complete and len(res.curves) == 2
    for g, gamma in enumerate(LIN_GAMMA):
        d = res.data[g]
        ref = closed_form(case, LIN_W, gamma)
        assert np.all(d["steady"]), d
        assert np.all(d["period"] == 1)
        # steady well before the cap: the criterion stopped the run
        assert np.all(d["t_end"] < 500.0), d["t_end"]
        assert np.all(d["floquet"] < 1.0)
        np.testing.assert_allclose(d["response_frequency"], np.repeat(np.array(LIN_W)[:, None], 4, axis=1), rtol=1e-9)
        np.testing.assert_allclose(d["amplitude"], ref, rtol=1e-3)
        np.testing.assert_allclose(d["halfrange"], ref, rtol=1e-3)
    # linear in the load: doubling gamma doubles every amplitude
    np.testing.assert_allclose(res.data[1]["amplitude"], 2.0 * res.data[0]["amplitude"], rtol=2e-4)
    # the resonance is where the closed form puts it: the largest z2 is at 2.52 rad/s
    assert LIN_W[int(np.argmax(res.data[0]["amplitude"][:, 1]))] == 2.52


def test_default_integrator_finds_moderate_linear_response_steady(wdir):
    """With the default DOPRI5 (atol = 1e-10 * chord = 3.0e-8 m) a response of ~1e-3..2e-2 m
    (FL x 1e-2) is detected as steady and still matches the closed form."""
    sweep = {"omega": [2.52, 4.0], "duration": 600.0, "window": 100.0, "channels": ["z2", "z4"], "gamma": [1.0e-2]}
    case, _, res = do_sweep(wdir / "moderate.h5", sweep, xi=0.05)
    d = res.data[0]
    assert np.all(d["steady"]) and np.all(d["period"] == 1), d
    ref = closed_form(case, [2.52, 4.0], 1.0e-2)[:, [1, 3]]
    np.testing.assert_allclose(d["halfrange"], ref, rtol=1e-3)
    np.testing.assert_allclose(d["amplitude"], ref, rtol=2e-3)  # includes the O(FL^2) mean drift


def test_default_integrator_finds_small_linear_response_steady(wdir):
    sweep = {"omega": [2.52, 4.0], "duration": 600.0, "window": 100.0, "channels": ["z2", "z4"], "gamma": [1.0e-4]}
    case, _, res = do_sweep(wdir / "small.h5", sweep, xi=0.05)
    d = res.data[0]
    assert np.all(d["steady"]) and np.all(d["period"] == 1), (d["steady"], d["period"], d["t_end"])
    np.testing.assert_allclose(d["amplitude"], closed_form(case, [2.52, 4.0], 1.0e-4)[:, [1, 3]], rtol=1e-3)


# ----------------------------------------------------------------------------------------------
# 2. Subharmonic, late jump, Floquet check
# ----------------------------------------------------------------------------------------------
LATE_SWEEP = {"omega": [5.0, 5.05], "duration": 4000.0, "channels": ["z2", "z4"]}


@pytest.fixture(scope="module")
def late(wdir):
    out = wdir / "late.h5"
    _, _, res = do_sweep(out, LATE_SWEEP)
    return res, out


def test_late_jump_to_half_subharmonic(late):
    res, _ = late
    d = res.data[0]
    assert res.gamma is None and len(res.curves) == 1
    i = 1  # 5.05 rad/s
    assert d["period"][i] == 2
    assert d["steady"][i]
    assert d["response_frequency"][i, 0] == pytest.approx(5.05 / 2, rel=1e-9)  # z2 at w/2
    assert d["t_end"][i] > 2000.0  # the jump (from ~1000 s on) was not hidden by an early stop
    assert d["amplitude"][i, 0] == pytest.approx(4.08, abs=0.05)  # large response, z2 ~ 4 m
    assert d["floquet"][i] < 1.0


def test_no_false_subharmonic_at_5_0(late):
    res, _ = late
    d = res.data[0]
    i = 0  # 5.0 rad/s: a slowly decaying mode-1 transient near w/2, but no subharmonic
    assert d["period"][i] == 1
    assert d["steady"][i]
    np.testing.assert_allclose(d["response_frequency"][i], [5.0, 5.0], rtol=1e-9)
    assert d["amplitude"][i, 0] < 0.3
    assert d["floquet"][i] < 1.0


def test_floquet_off_same_result_at_default_tolerance(wdir, late):
    """At tol = 1e-5 the small orbit never repeats well enough before it starts to grow, so the
    periodicity test alone already waits for the jump: switching the Floquet check off changes
    nothing but the reported multiplier (the check never touches the trajectory)."""
    res, _ = late
    _, _, off = do_sweep(wdir / "late-nofloquet.h5", dict(LATE_SWEEP, omega=[5.05], floquet=False), n_jobs=1)
    on, o = res.data[0], off.data[0]
    assert o["period"][0] == on["period"][1] == 2
    assert o["steady"][0]
    assert o["t_end"][0] == on["t_end"][1]
    np.testing.assert_array_equal(o["amplitude"][0], on["amplitude"][1])
    assert np.isnan(o["floquet"][0])


def test_floquet_check_keeps_late_jump_at_loose_tolerance(wdir):
    """What the Floquet check buys: with tol = 1e-3 the small unstable orbit passes the
    periodicity test at ~180 s; without the check the point stops there (|z2| = 0.10 m, the late
    jump hidden); with it the orbit is rejected (multiplier 1.008) and the jump is found."""
    sweep = {"omega": [5.05], "duration": 4000.0, "channels": ["z2", "z4"], "tol": 1.0e-3}
    _, _, on = do_sweep(wdir / "loose-on.h5", sweep, n_jobs=1)
    _, _, off = do_sweep(wdir / "loose-off.h5", dict(sweep, floquet=False), n_jobs=1)
    a, b = on.data[0], off.data[0]
    assert b["steady"][0] and b["t_end"][0] < 500.0 and b["amplitude"][0, 0] < 0.3  # hidden jump
    assert a["steady"][0] and a["period"][0] == 2 and a["t_end"][0] > 2000.0
    assert a["amplitude"][0, 0] > 3.5
    assert a["response_frequency"][0, 0] == pytest.approx(2.525, rel=1e-9)


# ----------------------------------------------------------------------------------------------
# 3. Up and down sweeps across a jump (softening)
# ----------------------------------------------------------------------------------------------
HYST_W = [2.0, 2.1, 2.2, 2.25, 2.3, 2.35, 2.4, 2.5, 2.6, 2.7]
HYST_SWEEP = {"omega": HYST_W, "duration": 1500.0, "direction": "both", "channels": ["z2", "z4"], "gamma": [5.0]}


@pytest.fixture(scope="module")
def hysteresis(wdir):
    out = wdir / "both.h5"
    _, _, res = do_sweep(out, HYST_SWEEP)
    return res, out


def test_up_and_down_sweeps_differ_across_the_jump(hysteresis):
    res, _ = hysteresis
    assert [(c.gamma_index, c.direction) for c in res.curves] == [(0, "up"), (0, "down")]
    up, down = res.data[0], res.data[1]
    for d in (up, down):
        assert d["done"].all() and d["steady"].all() and np.all(d["period"] == 1), d
    a_up, a_down = up["amplitude"][:, 0], down["amplitude"][:, 0]
    w = np.array(HYST_W)
    inside = (w >= 2.19) & (w <= 2.31)  # 2.2, 2.25, 2.3
    far = (w <= 2.11) | (w >= 2.39)
    # hysteresis: the down sweep stays on the large branch, the up sweep on the small one
    assert np.all(a_down[inside] > 2.5 * a_up[inside]), (a_up, a_down)
    assert a_down[w == 2.2][0] > 5.0 * a_up[w == 2.2][0]
    # far from the resonance both reach the same (unique) orbit
    np.testing.assert_allclose(a_up[far], a_down[far], rtol=1e-3)
    # softening: the up sweep jumps up between 2.3 and 2.35 rad/s
    j = int(np.flatnonzero(w == 2.3)[0])
    assert a_up[j + 1] > 2.5 * a_up[j]


def test_chain_does_not_continue_from_a_failed_point(wdir):
    # gamma = 10: the cable goes slack (a segment shorter than its natural length) at 2.15 rad/s
    sweep = {"omega": [2.15, 2.2, 2.3], "duration": 600.0, "window": 100.0, "direction": "up",
             "channels": ["z2", "z4"], "gamma": [10.0]}
    _, _, res = do_sweep(wdir / "slack.h5", sweep, n_jobs=1)
    d = res.data[0]
    assert not d["steady"][0] and 0.0 < d["t_end"][0] < 600.0  # the slack failure itself
    # every later point must have been integrated, not copied from the failed state
    assert np.all(d["t_end"][1:] > 0.0), (d["t_end"], d["amplitude"])


# ----------------------------------------------------------------------------------------------
# 4. Journal, kill, Ctrl-C and --resume
# ----------------------------------------------------------------------------------------------
N_RESUME = 16
RESUME_SWEEP = {"omega": {"start": 1.5, "stop": 4.2, "num": N_RESUME}, "duration": 1500.0, "window": 100.0, "channels": ["z2", "z4"]}


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
    done_idx = {r["index"] for r in recs}
    if not out.exists():
        return
    d = read_sweep(out)
    done = d["done"]
    assert done.shape == (N_RESUME,)
    assert set(np.flatnonzero(done)) <= done_idx  # a snapshot never runs ahead of the journal
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
    before = {json.loads(x)["index"]: json.loads(x)["wall"] for x in journal.read_text().split("\n")[1:] if x.strip()}

    code, stdout, stderr = finish_cli(start_cli([*args, "--resume"], tmp_path))
    assert code == 0, stderr
    assert "Traceback" not in stderr
    assert not journal.exists()  # removed once complete
    assert not list(tmp_path.glob("*.part"))
    got = read_sweep(out)
    assert_same_results(got, ref)
    assert got["/attrs"]["complete"] and got["/attrs"]["points_done"] == N_RESUME
    # the journalled points were kept, not recomputed
    for i, wall in before.items():
        assert got["wall"][i] == wall


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
    # finish it (in-process) and compare
    case = parse_case(text)
    res = run_sweep(case, text, out, n_jobs=2, resume=True)
    assert res.complete and not journal.exists()
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


# ----------------------------------------------------------------------------------------------
# 5. Bad sweep settings
# ----------------------------------------------------------------------------------------------
GOOD = {"omega": [2.0, 3.0], "duration": 300.0, "window": 100.0}
BAD_SETTINGS = {
    "empty list": ({"omega": []}, "sweep.omega", "empty"),
    "empty grid": ({"omega": {"start": 1.0, "stop": 2.0, "num": 0}}, "sweep.omega", "num"),
    "negative list": ({"omega": [-1.0, 2.0]}, "sweep.omega", "positive"),
    "negative grid": ({"omega": {"start": -1.0, "stop": 2.0, "num": 5}}, "sweep.omega", "start"),
    "zero frequency": ({"omega": [0.0, 2.0]}, "sweep.omega", "positive"),
    "reversed grid": ({"omega": {"start": 3.0, "stop": 2.0, "num": 5}}, "sweep.omega", "greater than start"),
    "window > duration": ({"duration": 100.0, "window": 200.0}, "sweep.window", "longer than"),
    "unknown direction": ({"direction": "sideways"}, "sweep.direction", "sideways"),
    "gamma zero": ({"gamma": [0.0]}, "sweep.gamma", "positive"),
}


def _check_user_error(res, *needles):
    assert res.returncode == 2, (res.stdout, res.stderr, res.exception)
    assert isinstance(res.exception, SystemExit), res.exception  # anything else: a traceback
    assert "Traceback" not in res.stderr
    assert "error:" in res.stderr
    flat = " ".join(res.stderr.split())
    for n in needles:
        assert n in flat, (n, res.stderr)


@pytest.mark.parametrize("label", list(BAD_SETTINGS))
def test_bad_sweep_settings_are_clear_errors(label, invoke_cli, write_case):
    change, field, hint = BAD_SETTINGS[label]
    write_case(case_text(dict(GOOD, **change)))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--no-plot"), field, hint)


def test_case_without_sweep_section(invoke_cli, write_case, tmp_path):
    write_case(case_text(None))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--no-plot"), "sweep:")
    case = parse_case(case_text(None))
    with pytest.raises(CablesimError) as err:
        run_sweep(case, case_text(None), tmp_path / "x.h5")
    assert err.value.field == "sweep"


def test_bad_command_line_flags(invoke_cli, write_case, tmp_path):
    write_case(case_text(GOOD))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "0"), "--jobs")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "-3"), "--jobs")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--resume", "--no-plot"), "resume", "out.h5.journal")
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--backend", "dask", "--no-plot"), "--scheduler")
    assert not (tmp_path / "out.h5").exists()


def test_resume_of_a_complete_sweep(invoke_cli, write_case, tmp_path):
    write_case(case_text(dict(GOOD, omega=[3.0])))
    res = invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--jobs", "1", "--no-plot")
    assert res.returncode == 0, res.stderr
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--resume", "--no-plot"), "already complete")


def test_settings_error_leaves_no_journal(invoke_cli, write_case, tmp_path):
    write_case(case_text(GOOD))
    _check_user_error(invoke_cli("sweep", "case.yaml", "-o", "out.h5", "--backend", "dask", "--no-plot"), "--scheduler")
    assert not (tmp_path / "out.h5.journal").exists()


# ----------------------------------------------------------------------------------------------
# 6. Dask backend
# ----------------------------------------------------------------------------------------------
DASK_SWEEP = {"omega": [2.0, 3.0, 4.0], "duration": 600.0, "window": 100.0, "channels": ["z2", "z4"]}


@pytest.fixture(scope="module")
def dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        yield cluster
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def dask_reference(wdir):
    text = case_text(DASK_SWEEP)
    out = wdir / "dask-local.h5"
    run_sweep(parse_case(text), text, out, n_jobs=1)
    return text, read_sweep(out)


def test_dask_backend_matches_local(wdir, dask_cluster, dask_reference):
    """In-process through run_sweep's own Dask set-up."""
    text, ref = dask_reference
    out = wdir / "dask.h5"
    res = run_sweep(parse_case(text), text, out, backend="dask", scheduler=dask_cluster.scheduler_address)
    assert res.complete
    assert_same_results(read_sweep(out), ref)
    assert not out.with_name(out.name + ".journal").exists()


def test_dask_backend_from_the_command_line(tmp_path, dask_cluster, dask_reference):
    text, ref = dask_reference
    (tmp_path / "case.yaml").write_text(text)
    code, _, stderr = finish_cli(start_cli(
        ["sweep", "case.yaml", "-o", "out.h5", "--no-plot", "--backend", "dask", "--scheduler", dask_cluster.scheduler_address],
        tmp_path,
    ))
    assert code == 0 and "Traceback" not in stderr, stderr[-2000:]
    assert_same_results(read_sweep(tmp_path / "out.h5"), ref)


# ----------------------------------------------------------------------------------------------
# 7. HDF5 layout
# ----------------------------------------------------------------------------------------------
def _check_group(g: h5py.Group, lead: tuple, C: int) -> None:
    for name, unit in UNITS.items():
        assert name in g, name
        ds = g[name]
        assert ds.attrs["units"] == unit, (name, ds.attrs["units"])
        shape = (*lead, C) if name in PER_CHANNEL else lead
        assert ds.shape == shape, (name, ds.shape, shape)
    assert g["done"].dtype == bool and g["steady"].dtype == bool
    assert np.issubdtype(g["period"].dtype, np.integer)
    assert g["done"][()].all()


def test_layout_independent_without_gamma(late):
    _, out = late
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        assert "gamma" not in g and "up" not in g and "down" not in g
        np.testing.assert_array_equal(g["omega"][()], [5.0, 5.05])
        assert g["omega"].attrs["units"] == "rad/s"
        _check_group(g, (2,), 2)
        assert [c.decode() for c in g.attrs["channels"]] == ["z2", "z4"]
        assert g.attrs["direction"] == "independent" and g.attrs["complete"]
        assert g.attrs["cap"] == 4000.0 and g.attrs["floquet_check"]
        assert f["modal/omega"].attrs["units"] == "rad/s"
        assert f["modal/omega"][0] == pytest.approx(2.524, abs=1e-3)
        assert f.attrs["command"] == "sweep"
        assert "sweep:" in f.attrs["case_yaml"]


def test_layout_with_gamma_axis(linear):
    _, res, out = linear
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        np.testing.assert_array_equal(g["gamma"][()], LIN_GAMMA)
        assert g["gamma"].attrs["units"] == "1"
        _check_group(g, (2, len(LIN_W)), 4)
        np.testing.assert_array_equal(g["amplitude"][1], res.data[1]["amplitude"])
        assert [c.decode() for c in g.attrs["channels"]] == ["z1", "z2", "z3", "z4"]


def test_layout_both_directions(hysteresis):
    res, out = hysteresis
    with h5py.File(out, "r") as f:
        g = f["sweep"]
        assert g.attrs["direction"] == "both"
        assert "amplitude" not in g  # results live under up/ and down/
        np.testing.assert_array_equal(g["omega"][()], HYST_W)
        for k, sub in enumerate(("up", "down")):
            _check_group(g[sub], (1, len(HYST_W)), 2)  # gamma given: leading G = 1 axis
            np.testing.assert_array_equal(g[sub]["amplitude"][0], res.data[k]["amplitude"])
        assert "omega" in f["modal"]
