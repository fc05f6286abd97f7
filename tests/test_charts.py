"""Design charts on the paper example: `cablesim continue` with `continuation.loci` (bifurcation
curves in omega and gamma, the stability chart) and `cablesim backbone` (free undamped orbits from
a linear mode), end to end through the command line and the Python API.

The numerics of the curves and backbones are tested in tests/test_orbits_loci.py and
tests/test_orbits_backbone.py against closed forms, harmonic balance, Floquet and independent
shooting. Here the stored results of the cable are checked against an independent formulation:
the resisting force written from the segment geometry and scipy's DOP853
(``helpers_dynamics._second_order_rhs``), which shares no code with the shooting kernels. A
stored orbit must come back to itself after its period, and its monodromy (finite differences
of that integration) must have the multiplier its curve says: -1 on a period-doubling curve, +1
on a fold curve.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
from helpers_dynamics import _second_order_rhs
from scipy.integrate import solve_ivp

import cablesim
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.io.charts import read_backbone
from cablesim.io.continuation import read_continuation

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
#: The period-doubling band near 2 w1, its curves continued down to gamma 0.8.
LOCI = ("continuation={omega: {start: 4.9, stop: 5.2}, channels: [z2, z4], loci: true, "
        "gamma: {start: 0.8, stop: 1.0, levels: [0.9]}}")
TIGHT = dict(method="DOP853", rtol=1e-12, atol=1e-14 * 300)


def _flow(case, omega: float, gamma: float, damped: bool = True, forced: bool = True):
    """The independent right-hand side ``(z, v) -> (v, v')`` of the case at (omega, gamma)."""
    static = run_static(case)
    eom = build_equations(case, static, omega=omega, load_scale=gamma)
    c = eom.cable
    nd = eom.n_dof
    C = eom.C if damped else np.zeros((nd, nd))
    FL = eom.FL if forced else np.zeros(nd)
    args = (np.ascontiguousarray(eom.y0), np.asarray(c.S, dtype=float), float(c.EA), float(c.L), float(c.H),
            np.ascontiguousarray(eom.mass), np.ascontiguousarray(C), np.ascontiguousarray(eom.F0),
            np.ascontiguousarray(FL), float(omega))
    return (lambda t, s: _second_order_rhs(t, s, *args)), nd


def _after(rhs, s0: np.ndarray, T: float) -> np.ndarray:
    sol = solve_ivp(rhs, (0.0, T), s0, **TIGHT)
    assert sol.success
    return sol.y[:, -1]


def _monodromy(rhs, s0: np.ndarray, T: float, scale: np.ndarray) -> np.ndarray:
    """Multipliers by central differences of the independent flow over ``T``."""
    cols = []
    for i in range(s0.size):
        h = 1e-5 * scale[i]
        e = np.zeros_like(s0)
        e[i] = h
        cols.append((_after(rhs, s0 + e, T) - _after(rhs, s0 - e, T)) / (2 * h))
    return np.linalg.eigvals(np.column_stack(cols))


# ----------------------------------------------------------------------------------------------
# Bifurcation curves and the stability chart
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def loci_run(tmp_path_factory):
    """`cablesim continue` with loci across the period-doubling band near 2 w1 (in-process)."""
    from typer.testing import CliRunner

    from cablesim.cli import app

    out = tmp_path_factory.mktemp("loci") / "band.h5"
    res = CliRunner().invoke(app, ["continue", str(CONFIG), "--set", LOCI, "-o", str(out)])
    assert res.exit_code == 0, (res.stdout, res.stderr, res.exception)
    return out, res.stdout


def test_loci_layout_and_summary(loci_run):
    out, stdout = loci_run
    with h5py.File(out) as f:
        lg = f["continuation/loci"]
        assert lg.attrs["gamma_start"] == 0.8 and lg.attrs["gamma_stop"] == 1.0
        assert lg.attrs["gamma_response"] == 1.0 and bool(lg.attrs["complete"])
        kinds = {name: lg[name].attrs["kind"] for name in lg}
        assert sorted(kinds.values()) == ["fold", "period-doubling"], kinds
        for name in lg:
            h = lg[name]
            n = h["omega"].shape[0]
            assert n >= 5 and h["gamma"].shape == (n,) and h["amplitude"].shape == (n, 2)
            assert h["state"].shape == (n, 8) and h["multipliers"].dtype.kind == "c"
            assert all(h[k].attrs["units"] for k in h)
            assert np.isfinite(h["omega"][()]).all() and np.isfinite(h["gamma"][()]).all()
        assert "codim2" in f["continuation"] and "kind" in f["continuation/codim2"]
        pd = next(lg[name] for name in lg if lg[name].attrs["kind"] == "period-doubling")
        crossings = pd["gamma"][()][[s == b"level" for s in pd["special"][()]]]
        np.testing.assert_allclose(crossings, [0.9, 0.9], rtol=1e-9)  # both edges of the tongue (measured 2e-11)
    assert "Bifurcation curves in (omega, gamma)" in stdout and "pd0-p1" in stdout
    chart = out.with_name(out.stem + "-chart.png")
    assert chart.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and chart.stat().st_size > 20_000


def test_period_doubling_curve_points_have_multiplier_minus_one_independently(loci_run):
    """Three points of the stored period-doubling curve, at three values of gamma: the period-1
    orbit (state, omega, gamma as stored) is periodic for the independent flow and its
    monodromy has a multiplier at -1; off the curve (2 % lower gamma at the same omega, the
    orbit re-found there) it has not, so the check can fail."""
    out, _ = loci_run
    d = read_continuation(out)
    pd = next(L for L in d["loci"]["loci"] if L["kind"] == "period-doubling")
    case = cablesim.load_case(CONFIG)
    assert pd["gamma"].min() < 0.9  # the tongue's tip lies inside the range of gamma
    for j in np.linspace(1, pd["omega"].size - 2, 3).astype(int):
        w, g = float(pd["omega"][j]), float(pd["gamma"][j])
        rhs, nd = _flow(case, w, g)
        s0 = pd["state"][j]
        T = 2 * np.pi / w
        scale = np.full(2 * nd, max(np.abs(s0[:nd]).max(), 1e-3))
        scale[nd:] *= w
        assert np.abs(_after(rhs, s0, T) - s0).max() < 1e-7 * scale.max()
        mu = _monodromy(rhs, s0, T, scale)
        assert np.abs(mu + 1.0).min() < 1e-5, (w, g, mu)


def test_fold_curve_of_the_subharmonic_points_have_multiplier_plus_one_independently(loci_run):
    """The fold curve of the period-2 orbits: at its points the period-2 orbit is periodic over
    2T for the independent flow, with a multiplier at +1; the curve started on the bound gamma
    = 1 names that end."""
    out, _ = loci_run
    d = read_continuation(out)
    fold = next(L for L in d["loci"]["loci"] if L["kind"] == "fold")
    assert fold["period"] == 2 and "reached the bound of gamma" in fold["ends"]
    case = cablesim.load_case(CONFIG)
    for j in (1, fold["omega"].size // 2):
        w, g = float(fold["omega"][j]), float(fold["gamma"][j])
        rhs, nd = _flow(case, w, g)
        s0 = fold["state"][j]
        T = 4 * np.pi / w
        scale = np.full(2 * nd, np.abs(s0[:nd]).max())
        scale[nd:] *= w
        assert np.abs(_after(rhs, s0, T) - s0).max() < 1e-7 * scale.max()
        mu = _monodromy(rhs, s0, T, scale)
        assert np.abs(mu - 1.0).min() < 1e-5, (w, g, mu)


def test_plot_redraws_the_response_and_its_chart(loci_run, invoke_cli, tmp_path):
    out, _ = loci_run
    res = invoke_cli("plot", out, "-o", tmp_path / "again.png")
    assert res.returncode == 0, res.stderr
    for png in (tmp_path / "again.png", tmp_path / "again-chart.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_curves_above_the_limits_are_refused_after_the_branches_and_traced_on_resume(loci_run, tmp_path):
    """With 100000 points allowed per curve direction, the curves' bound (made once the
    branches are traced: 3 curves, each point about 6 flows) is above the 1e8 steps allowed: the
    command stops with status 2 before any curve, the branches kept (file marked incomplete, and
    the journal), and names the command that traces the curves; that command, run as printed,
    gives the curves of the run with the default limit (they end on the bounds of gamma long
    before either limit)."""
    import shlex

    from typer.testing import CliRunner

    from cablesim.cli import app

    out = tmp_path / "band.h5"
    wide = LOCI.replace("loci: true,", "loci: true, max_points: 100000,")
    res = CliRunner().invoke(app, ["continue", str(CONFIG), "--set", wide, "-o", str(out), "--no-plot"])
    text = " ".join(res.stderr.split())
    assert res.exit_code == 2 and "Traceback" not in res.stderr, res.stderr
    assert "continuation.loci" in text and "were not traced" in text and "more than the 1e+08 allowed" in text
    d = read_continuation(out)
    assert not d["complete"] and not d.get("loci") and out.with_name("band.h5.journal").exists()
    words = shlex.split(res.stderr.strip().splitlines()[-1])
    assert words[:2] == ["cablesim", "continue"] and words[-2:] == ["--resume", "--force"], res.stderr
    res = CliRunner().invoke(app, words[1:])
    assert res.exit_code == 0, res.stderr
    got, want = read_continuation(out), read_continuation(loci_run[0])
    assert got["complete"] and not out.with_name("band.h5.journal").exists()
    assert [L["name"] for L in got["loci"]["loci"]] == [L["name"] for L in want["loci"]["loci"]]
    for a, b in zip(got["loci"]["loci"], want["loci"]["loci"]):
        for key in ("omega", "gamma", "state"):
            np.testing.assert_array_equal(a[key], b[key])


@pytest.mark.parametrize("setting, words", [
    ("continuation={omega: {start: 4.9, stop: 5.2}, loci: true}", "continuation.loci needs"),
    ("continuation={omega: {start: 4.9, stop: 5.2}, loci: true, gamma: {start: 0.5, stop: 1.0, at: 2.0}}",
     "continuation.gamma.at"),
    ("continuation={parameter: gamma, omega: 5.0, loci: true, gamma: {start: 0.5, stop: 1.0}}",
     "continuation.loci needs"),
    ("continuation={omega: {start: 4.9, stop: 5.2}, gamma: {start: 0.5, stop: 1.0}}", "add loci: true"),
    ("continuation={omega: {start: 4.9, stop: 5.2}, loci: true, gamma: {start: 0.5, stop: 1.0, levels: [3]}}",
     "continuation.gamma.levels"),
])
def test_bad_loci_settings_are_refused_cleanly(invoke_cli, setting, words):
    sets = [a for part in setting.split(";") for a in ("--set", part)]
    res = invoke_cli("continue", CONFIG, "-o", "x.h5", *sets)
    assert res.returncode == 2 and words in res.stderr and "Traceback" not in res.stderr
    assert not Path("x.h5").exists()


# ----------------------------------------------------------------------------------------------
# Backbones
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def backbone_file(tmp_path_factory):
    """The backbone of mode 1 to 1 m through the Python API."""
    case = cablesim.load_case(CONFIG)
    run = cablesim.backbone(case, mode=1, amplitude=1.0)
    out = run.to_hdf5(tmp_path_factory.mktemp("bb") / "bb1.h5")
    return case, run, out


def test_backbone_api_result_and_file(backbone_file):
    case, run, out = backbone_file
    r = run.result
    assert r.mode == 1 and r.complete and r.end.startswith("reached 1 m")
    assert r.amplitude.max() >= 1.0 and r.omega.size >= 5
    assert np.abs(r.delta).max() < 1e-9  # the artificial damping stays at zero
    static = run_static(case)
    # the linear frequency is the undamped cable's lowest modal frequency
    assert r.linear_omega == pytest.approx(float(static.modes.omega[0]), rel=1e-9)
    assert r.omega[-1] < r.linear_omega  # mode 1 of the sagging cable softens
    d = read_backbone(out)
    np.testing.assert_array_equal(d["omega"], r.omega)
    # the case's channels (backbone.channels, else the continuation's or the history's)
    names = list(case.backbone.channels or case.history.channels or ["z1", "z2", "z3", "z4"])
    assert r.channels == d["channels"] == names and d["amplitude"].shape == (r.omega.size, len(names))
    with h5py.File(out) as f:
        assert f.attrs["command"] == "backbone" and f["backbone/omega"].attrs["units"] == "rad/s"


def test_backbone_orbits_are_free_periodic_orbits_of_the_independent_flow(backbone_file):
    """The stored orbits, integrated over their period 2 pi / omega by the undamped, unforced
    independent flow, come back to themselves; with the frequency 0.1 % off they do not."""
    case, run, _ = backbone_file
    r = run.result
    rhs, nd = _flow(case, 1.0, 0.0, damped=False, forced=False)
    for j in (r.omega.size // 2, r.omega.size - 1):
        s0 = r.state[j]
        size = np.abs(s0[:nd]).max()
        T = 2 * np.pi / r.omega[j]
        scaled = np.r_[np.ones(nd), np.full(nd, 1.0 / r.omega[j])]  # (z, v / omega), m

        def miss(t):
            return np.abs((_after(rhs, s0, t) - s0) * scaled).max() / size

        assert miss(T) < 1e-8
        assert miss(1.001 * T) > 1e-3  # the state is at a turning point: the velocity shows it


def test_backbone_command_and_plot_over_a_response(backbone_file, invoke_cli, tmp_path):
    """`cablesim backbone --mode 1` writes its file and summary; `cablesim plot CONT.h5 BB.h5`
    draws the backbone over a frequency response."""
    res = invoke_cli("backbone", CONFIG, "--mode", "1", "--amplitude", "0.3", "-o", "bb.h5")
    assert res.returncode == 0, res.stderr
    assert "backbone of mode 1" in res.stdout and "softening" in res.stdout
    assert (tmp_path / "bb.png").stat().st_size > 20_000
    assert read_backbone(tmp_path / "bb.h5")["amplitude"].max() >= 0.3
    res = invoke_cli("continue", CONFIG, "--no-plot", "-o", "cont.h5", "--set",
                     "continuation={omega: {start: 2.5, stop: 2.55}, gamma: 0.05, channels: [z2, z4], max_points: 12}")
    assert res.returncode == 0, res.stderr
    res = invoke_cli("plot", "cont.h5", "bb.h5", "-o", "over.png")
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "over.png").stat().st_size > 20_000


def test_an_interrupted_backbone_keeps_its_orbits_and_never_replaces_a_complete_file(backbone_file, tmp_path):
    """Ctrl-C after four orbits: the API raises Interrupted with those orbits (marked
    incomplete); the command writes them beside a complete file of the same name, which stays
    as it was, and exits with status 130."""
    import typer

    from cablesim.analyses.charts import Interrupted
    from cablesim.cli_charts import interruptible
    from cablesim.io.hdf5 import is_complete_result

    case, _, complete = backbone_file
    seen = []

    def progress(p):
        seen.append(p)
        if len(seen) == 4:
            raise KeyboardInterrupt

    with pytest.raises(Interrupted) as exc:
        cablesim.backbone(case, mode=1, amplitude=1.0, progress=progress)
    part = exc.value.result
    assert not part.complete and part.omega.size == 4 and part.end == "interrupted"
    target = tmp_path / "bb.h5"
    target.write_bytes(complete.read_bytes())
    before = target.read_bytes()

    def compute():
        raise Interrupted(part)

    with pytest.raises(typer.Exit) as ex:
        interruptible(compute, case, target, "the orbits computed")
    assert ex.value.exit_code == 130
    assert target.read_bytes() == before and is_complete_result(target)
    kept = tmp_path / "bb.partial.h5"
    d = read_backbone(kept)
    assert not d["complete"] and d["omega"].size == 4 and not is_complete_result(kept)


@pytest.mark.slow  # the exact analysis' backbone tests above run in `make test`
def test_backbone_in_the_approximate_analysis_starts_on_higher_modes():
    """Mode 2 in the approximate analysis (whose flow map's round-off stalled Newton's
    corrections at 1e-9, so that the backbone never started): it starts at the approximate
    analysis's own linear frequency and follows the family."""
    case = cablesim.load_case(CONFIG)
    r = cablesim.backbone(case, mode=2, amplitude=0.2, analysis="approximate").result
    assert r.analysis == "approximate" and r.complete and r.end.startswith("reached 0.2 m")
    static = run_static(case, "approximate")
    assert r.linear_omega == pytest.approx(float(static.modes.omega[1]), rel=1e-9)
    assert r.omega[0] == pytest.approx(r.linear_omega, rel=1e-6)  # 0.002 m: still linear
    assert r.omega.size >= 5 and np.abs(r.delta).max() < 1e-9 and r.trusted.all()


def test_a_backbone_that_cannot_start_is_a_clear_error(invoke_cli, monkeypatch):
    from cablesim.analyses import charts
    from cablesim.orbits.backbone import Backbone

    monkeypatch.setattr(charts, "trace_backbone", lambda system, mode, *a, **k: Backbone(
        mode=mode, linear_omega=1.0, modes=np.ones(4), end="start failed"))
    res = invoke_cli("backbone", CONFIG, "--mode", "1", "-o", "x.h5")
    assert res.returncode == 2 and "could not start" in res.stderr and "Traceback" not in res.stderr
    assert not Path("x.h5").exists()


@pytest.mark.parametrize("args, words", [
    (["--mode", "9"], "--mode 9"),
    (["--mode", "0"], "--mode"),
    (["--amplitude", "-1"], "--amplitude"),
])
def test_bad_backbone_options_are_refused_cleanly(invoke_cli, args, words):
    res = invoke_cli("backbone", CONFIG, "-o", "x.h5", *args)
    assert res.returncode == 2 and words in res.stderr and "Traceback" not in res.stderr
    assert not Path("x.h5").exists()


# ----------------------------------------------------------------------------------------------
# The checks on the paper example (slow: several responses each)
# ----------------------------------------------------------------------------------------------
def _levels(result, kind: str, period: int) -> dict:
    """(gamma -> sorted omegas) of the crossings of the levels of gamma on the curves of a kind."""
    out: dict = {}
    for L in result.loci:
        if L.kind != kind or L.period != period:
            continue
        for k, sp in enumerate(L.special):
            if sp == "level":
                out.setdefault(round(float(L.gamma[k]), 9), []).append(float(L.omega[k]))
    return {g: sorted(w) for g, w in out.items()}


def _single_curve(setting: str, gamma: float, kind: str, period: int) -> list:
    case = cablesim.load_case(CONFIG, overrides=[setting.format(gamma=gamma)])
    bifs = cablesim.continuation(case).result.bifurcations
    return sorted(float(b.parameter) for b in bifs if b.kind == kind and b.period == period and b.located)


@pytest.mark.slow
@pytest.mark.parametrize("loci, single, kind, period, levels", [
    # the fold curve of the primary resonance, its two folds meeting at a cusp near gamma 1.12
    ("continuation={omega: {start: 2.2, stop: 2.8}, channels: [z2], loci: true, "
     "gamma: {start: 0.3, stop: 3.0, levels: [1.5, 2.0, 2.5]}}",
     "continuation={{omega: {{start: 2.2, stop: 2.8}}, gamma: {gamma}, channels: [z2]}}", "fold", 1, (1.5, 2.0, 2.5)),
    # the period-doubling tongue near 2 w1 and the fold curve of its period-2 orbits
    ("continuation={omega: {start: 4.9, stop: 5.2}, channels: [z2], loci: true, "
     "gamma: {start: 0.8, stop: 1.0, levels: [0.9, 0.95]}}",
     "continuation={{omega: {{start: 4.9, stop: 5.2}}, gamma: {gamma}, channels: [z2]}}", "period-doubling", 1,
     (0.9, 0.95)),
    ("continuation={omega: {start: 4.9, stop: 5.2}, channels: [z2], loci: true, "
     "gamma: {start: 0.8, stop: 1.0, levels: [0.95]}}",
     "continuation={{omega: {{start: 4.9, stop: 5.2}}, gamma: {gamma}, channels: [z2]}}", "fold", 2, (0.95,)),
])
def test_points_of_single_curves_lie_on_the_continued_curves(loci, single, kind, period, levels):
    """The bifurcations that `cablesim continue` locates on single response curves at several
    values of gamma (each its own continuation in omega) are where the continued curves cross
    those values of gamma, to 1e-6 in omega (relative; measured 4e-12 to 1.6e-10)."""
    res = cablesim.continuation(cablesim.load_case(CONFIG, overrides=[loci])).result
    on_curves = _levels(res, kind, period)
    for g in levels:
        found = _single_curve(single, g, kind, period)
        assert found, (kind, g)
        assert len(on_curves.get(round(g, 9), [])) == len(found), (g, found, on_curves)
        np.testing.assert_allclose(on_curves[round(g, 9)], found, rtol=1e-6)  # measured 2e-10 at most


@pytest.mark.slow
def test_backbone_passes_through_the_peaks_of_lightly_damped_responses():
    """The forced response's peak (omega_p, a_p) in z2 against the backbone's frequency at the
    amplitude a_p, for damping ratios 1 %, 0.5 % and 0.25 % with gamma proportional to the
    damping (peaks of about the same size, 2.2 m): the distance shrinks with the damping,
    about as its square as for a linear resonance (measured 1.4e-4, 3.1e-5, 5.5e-6 rad/s)."""
    from scipy.interpolate import CubicSpline

    bb = cablesim.backbone(cablesim.load_case(CONFIG), mode=1, amplitude=4.0).result
    a_bb = bb.amplitude[:, bb.channels.index("z2")]
    assert np.all(np.diff(a_bb) > 0)
    omega_bb = CubicSpline(a_bb, bb.omega)
    gaps = []
    for ratio in (0.01, 0.005, 0.0025):
        case = cablesim.load_case(CONFIG, overrides=[
            f"damping.ratio={ratio}", f"continuation={{omega: {{start: 2.45, stop: 2.56}}, gamma: {25 * ratio}, "
            "channels: [z2]}"])
        b = cablesim.continuation(case).result.branches[0]
        a = b.amplitude[:, 0]
        k = int(np.argmax(a))
        # the peak by a parabola through the three highest points
        c = np.polyfit(b.parameter[k - 1:k + 2], a[k - 1:k + 2], 2)
        w_p = -c[1] / (2 * c[0])
        a_p = np.polyval(c, w_p)
        assert a_bb[0] < a_p < a_bb[-1]
        gaps.append(abs(w_p - float(omega_bb(a_p))))
    assert gaps[1] < 0.6 * gaps[0] and gaps[2] < 0.6 * gaps[1]
    assert gaps[2] < 1e-3 * bb.linear_omega
