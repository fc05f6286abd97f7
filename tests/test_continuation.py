"""`cablesim continue`: the command, its file layout, and its bifurcations checked independently.

The numerics of shooting and continuation are tested in tests/test_orbits_*.py against closed
forms and independent integrations; here the case-level analysis, the HDF5 layout, the plot and
the messages, and the located bifurcations against the package's own time integrator (a
different scheme: adaptive DOPRI5 on the third-order equations, finite-difference monodromy).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

import cablesim
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.dynamics.integrators import DOPRI5
from cablesim.dynamics.steady import monodromy_multipliers
from cablesim.io.continuation import read_continuation

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
NEAR_2W1 = "continuation={omega: {start: 4.9, stop: 5.2}, channels: [z2, z4]}"


@pytest.fixture(scope="module")
def near_2w1(tmp_path_factory):
    """The paper example continued across its period-doubling band near 2 w1 (CLI in-process)."""
    from typer.testing import CliRunner

    from cablesim.cli import app

    out = tmp_path_factory.mktemp("cont") / "near.h5"
    res = CliRunner().invoke(app, ["continue", str(CONFIG), "--set", NEAR_2W1, "-o", str(out)])
    assert res.exit_code == 0, (res.stdout, res.stderr, res.exception)
    return out, res.stdout


def test_layout_follows_the_documented_one(near_2w1):
    out, _ = near_2w1
    with h5py.File(out) as f:
        assert f.attrs["command"] == "continue"
        g = f["continuation"]
        assert g.attrs["parameter"] == "omega"
        names = list(g["branches"])
        assert {"b0-p1", "b1-p2"} <= set(names)
        for name in names:
            b = g["branches"][name]
            n = b["omega"].shape[0]
            assert b["amplitude"].shape == (n, 2) and b["halfrange"].shape == (n, 2)
            assert b["stable"].dtype == bool and b["multipliers"].dtype.kind == "c"
            assert b["state"].shape == (n, 8)
            assert b.attrs["period"] in (1, 2) and [c.decode() for c in b.attrs["channels"]] == ["z2", "z4"]
            for ds in b.values():
                assert ds.attrs["units"]
        bif = g["bifurcations"]
        kinds = sorted(k.decode() for k in bif["kind"][()])
        assert kinds == ["fold", "period-doubling", "period-doubling"]
        assert bif["amplitude"].shape == (3, 2)
        assert "modal/omega" in f


def test_summary_names_the_bifurcations(near_2w1):
    _, stdout = near_2w1
    assert "period-doubling" in stdout and "fold" in stdout and "b1-p2" in stdout


def test_period_doublings_are_where_an_independent_monodromy_has_multiplier_minus_one(near_2w1):
    """At each located period doubling the period-1 orbit (stored state) has a multiplier at -1
    by a finite-difference monodromy through the adaptive third-order integrator; slightly off
    the point the multiplier is clearly away from -1, so the check can fail."""
    out, _ = near_2w1
    d = read_continuation(out)
    case = cablesim.load_case(CONFIG)
    static = run_static(case)
    b0 = next(b for b in d["branches"] if b["period"] == 1)
    pd = [k for k, kind in enumerate(d["bifurcations"]["kind"]) if kind == "period-doubling"]
    assert len(pd) == 2
    for k in pd:
        w = float(d["bifurcations"]["omega"][k])
        j = int(np.argmin(np.abs(b0["omega"] - w)))
        assert abs(b0["omega"][j] - w) < 1e-9  # the located point is stored on the branch
        eom = build_equations(case, static, omega=w)
        s = eom.initial_state(z0=b0["state"][j, :4], v0=b0["state"][j, 4:])
        mu = monodromy_multipliers(eom, DOPRI5(rtol=1e-11, atol=1e-13 * 300), s, 1, 1e-6)
        assert np.min(np.abs(mu + 1.0)) < 2e-3, mu
    # between the two period doublings the period-1 orbit is unstable, outside it is stable
    inside = (b0["omega"] > d["bifurcations"]["omega"][pd].min() + 1e-3) & (b0["omega"] < d["bifurcations"]["omega"][pd].max() - 1e-3)
    assert inside.any() and not b0["stable"][inside].any()
    assert b0["stable"][b0["omega"] < 4.99].all() and b0["stable"][b0["omega"] > 5.09].all()


def test_products_of_multipliers_obey_liouville(near_2w1):
    """det(monodromy) = exp(-trace(M^-1 C) T) on every trusted orbit (exact analysis)."""
    out, _ = near_2w1
    d = read_continuation(out)
    case = cablesim.load_case(CONFIG)
    static = run_static(case)
    eom = build_equations(case, static, omega=5.0)
    rate = float(np.trace(eom.C / eom.mass[:, None]))
    for b in d["branches"]:
        T = 2.0 * np.pi * b["period"] / b["omega"]
        det = np.prod(b["multipliers"], axis=1).real
        ok = b["trusted"].astype(bool)
        np.testing.assert_allclose(det[ok], np.exp(-rate * T[ok]), rtol=1e-4)


def test_plot_redraws_from_the_file(near_2w1, invoke_cli, tmp_path):
    out, _ = near_2w1
    res = invoke_cli("plot", out, "-o", tmp_path / "again.png")
    assert res.returncode == 0, res.stderr
    data = (tmp_path / "again.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_plot_draws_a_continuation_with_a_sweep_on_top(near_2w1, tmp_path, monkeypatch):
    """`cablesim plot CONT.h5 SWEEP.h5 --stamp TEXT`: the continuation with the sweep's points on
    top (as `continue --overlay` draws it), stamped."""
    from matplotlib.figure import Figure
    from test_plot_sweep import _results, two_channel, write_sweep

    from cablesim.plots.redraw import redraw

    out, _ = near_2w1
    omega = np.linspace(4.9, 5.2, 7)
    sweep = write_sweep(tmp_path / "sweep.h5", omega, {None: _results(omega, two_channel(omega))})
    legends = []
    real = Figure.savefig

    def spy(self, *args, **kwargs):
        legends.append([t.get_text() for lg in self.legends for t in lg.get_texts()] + [t.get_text() for t in self.texts])
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    (png,) = redraw([out, sweep], tmp_path / "both.png", stamp="preview")
    assert png == tmp_path / "both.png" and png.stat().st_size > 20_000
    assert "time integration: steady response" in legends[-1] and "preview" in legends[-1]


def test_continuation_in_gamma_finds_the_softening_folds():
    """At 2.44 rad/s the harmonic response folds over as FL grows (jumps, hysteresis): two folds
    in gamma, and between them the middle orbits are unstable with a real multiplier > 1."""
    case = cablesim.load_case(CONFIG, overrides=["continuation={parameter: gamma, omega: 2.44, "
                                                  "gamma: {start: 0.5, stop: 3.0}, channels: [z2]}"])
    run = cablesim.continuation(case)
    folds = [b for b in run.result.bifurcations if b.kind == "fold"]
    assert len(folds) == 2, [(b.kind, b.parameter) for b in run.result.bifurcations]
    b0 = run.result.branches[0]
    unstable = ~b0.stable
    assert unstable.any()
    mu = b0.multipliers[unstable][:, 0]
    assert np.all(np.abs(mu.imag) < 1e-9) and np.all(mu.real > 1.0)


@pytest.mark.parametrize("setting, words", [
    ("continuation=null", "no `continuation:` section"),
    ("continuation={omega: 2.0}", "must be a range"),
    ("continuation={omega: {start: 1, stop: 1}}", "start and stop must differ"),
    ("continuation={parameter: gamma, omega: {start: 1, stop: 2}, gamma: {start: 1, stop: 2}}", "must be a single value"),
])
def test_bad_sections_are_refused_cleanly(invoke_cli, setting, words):
    args = ["continue", CONFIG, "-o", "x.h5"] + (["--set", setting] if setting else [])
    res = invoke_cli(*args)
    assert res.returncode == 2 and words in " ".join(res.stderr.split()) and "Traceback" not in res.stderr
    assert not Path("x.h5").exists()


def test_branch_ends_at_a_grazing_orbit_where_a_segment_goes_slack():
    """Forced ten times harder near the primary resonance the harmonic branch folds and then
    reaches orbits on which a segment's tension falls to zero: the branch stops there and records
    a grazing point. Independently, the last orbit integrated over one period by the time
    integrator (slack: stop) comes within a few per cent of zero tension."""
    from cablesim.dynamics.simulate import simulate
    from cablesim.analyses.setup import make_integrator

    case = cablesim.load_case(CONFIG, overrides=[
        "continuation={omega: {start: 2.0, stop: 3.0}, gamma: 10.0, channels: [z2, z4]}", "slack=stop"])
    run = cablesim.continuation(case)
    graze = [b for b in run.result.bifurcations if b.kind == "grazing"]
    assert len(graze) == 1 and "slack" in run.result.branches[graze[0].branch].end
    b = run.result.branches[graze[0].branch]
    j = int(np.argmin(np.abs(b.parameter - graze[0].parameter)))
    static = run_static(case)
    eom = build_equations(case, static, omega=float(b.omega[j]), load_scale=10.0)
    s0 = eom.initial_state(z0=b.state[j, :4], v0=b.state[j, 4:])
    T = 2.0 * np.pi / float(b.omega[j])
    hist = simulate(eom, make_integrator(case.integrator, eom, float(b.omega[j])), T, T / 400, s0=s0)
    assert hist.T.min() < 0.05 * static.T0.min()
