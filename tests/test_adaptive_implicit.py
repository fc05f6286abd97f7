"""Error-controlled steps of newmark and generalized-alpha (cablesim/dynamics/integrators/adaptive.py).

Checked against independent references (scipy's DOP853 on the second-order form with the
geometry written in the tests, helpers_dynamics.py; through slack, scipy's event location,
test_slack.py):

1. the local error estimate is the step's true local error to leading order;
2. the error follows the tolerance (halving rtol halves it) and meets it on the paper example;
3. through slack episodes: every transition found, located, and the tolerance met;
4. a heavy (banded) cable;
5. a dt keeps a fixed step; the settings, the finite-difference and transient versions;
6. the command line's --dt and --rtol.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_dynamics import own_force, reference_history
from test_slack import _own_lengths, slack_reference

from cablesim.analyses.cost import steps_per_second
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics.integrators import DOPRI5, GeneralizedAlpha, Newmark
from cablesim.dynamics.integrators.adaptive import error_constant
from cablesim.dynamics.integrators.newmark import galpha_step, step_scratch
from cablesim.dynamics.integrators.settings import IMPLICIT_RTOL, make
from cablesim.dynamics.simulate import simulate
from cablesim.dynamics.status import OK

SCHEMES = ("newmark", "generalized-alpha")


@pytest.fixture(scope="module")
def forced(paper, exact_static):
    """The paper example forced at 2.4 rad/s (near its fundamental, 2.52 rad/s)."""
    return build_equations(paper, exact_static, omega=2.4)


def _acceleration(eom, t, z, v):
    """``y''`` from eq. 15 with the tests' own resisting force."""
    P = own_force(eom.cable, eom.y0 + z)
    return (eom.F0 + eom.FL * math.sin(eom.omega * t) - eom.C @ v - P) / eom.mass


# ----------------------------------------------------------------------------------------------
# 1. The estimate is the local error
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("integ", [
    pytest.param(Newmark(dt=1.0), marks=pytest.mark.slow(reason="about 18 s; generalized-alpha is the fast check")),
    GeneralizedAlpha(dt=1.0, rho_inf=0.8)], ids=SCHEMES)
def test_local_error_estimate_is_the_true_local_error(forced, integ):
    """One step from the reference's state at t = 20 s: ``(beta + (am - af)/2 - 1/6) h^2 (a1 - a)``
    against ``z1 - z_ref(t + h)``; the ratio tends to 1 as h falls (generalized-alpha starts
    from its acceleration variable, y'' at ``t + (am - af) h``)."""
    eom = forced
    coef = np.array(integ._coefficients())
    lag = coef[0] - coef[1]
    tn, ratios = 20.0, []
    for h in (0.02, 0.01, 0.005):
        times = np.array(sorted({0.0, tn + lag * h, tn, tn + h}))
        z, v = reference_history(eom, times)
        at = {float(t): k for k, t in enumerate(times)}
        zn, vn = z[at[tn]], v[at[tn]]
        k_lag = at[float(tn + lag * h)]
        a = _acceleration(eom, tn + lag * h, z[k_lag], v[k_lag])
        st = integ.start(eom, eom.initial_state())
        wk, awk = st.wk
        nd = eom.n_dof
        z1, v1, a1, P1 = (np.empty(nd) for _ in range(4))
        P_n = own_force(eom.cable, eom.y0 + zn)
        code = galpha_step(eom.model(), zn, vn, a, P_n, st.warm, wk, awk, tn + h, h, coef, 1e-12 * 300.0, 0.0, 25,
                           z1, v1, a1, P1, step_scratch(eom.model()))
        assert code == OK
        true = z1 - z[at[tn + h]]
        estimate = error_constant(coef) * h * h * (a1 - a)
        ratios.append(np.abs(estimate).max() / np.abs(true).max())
        assert np.abs(estimate - true).max() < 0.3 * np.abs(true).max(), (h, ratios)
    assert abs(ratios[-1] - 1.0) < abs(ratios[0] - 1.0) + 1e-3 and abs(ratios[-1] - 1.0) < 0.1, ratios


# ----------------------------------------------------------------------------------------------
# 2. The tolerance: proportional, and met
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def paper_reference(forced):
    t = np.arange(0, 1201) * 0.05  # 60 s
    return t, reference_history(forced, t)[0]


@pytest.mark.parametrize("name", [
    pytest.param("newmark", marks=pytest.mark.slow(reason="about 9 s; generalized-alpha is the fast check")),
    "generalized-alpha"])
def test_error_follows_and_meets_the_tolerance(forced, paper_reference, name):
    t, zref = paper_reference
    errs = []
    for rtol in (1e-4, 1e-5):
        integ = make(name, forced, 2.4, {"rtol": rtol})
        hist = simulate(forced, integ, t[-1], 0.05, split=False)
        assert hist.completed and not integ.fixed_step
        errs.append(np.abs(hist.z - zref).max() / np.abs(zref).max())
        assert errs[-1] <= rtol, (rtol, errs)
    assert 5.0 < errs[0] / errs[1] < 20.0, errs  # proportional to rtol: ten times tighter, ten times closer


def test_default_tolerance_beats_todays_fixed_step(forced, paper_reference):
    """The default run of each implicit scheme against its old default, 100 steps per period."""
    t, zref = paper_reference
    for name in SCHEMES:
        default = make(name, forced, 2.4)
        assert default.rtol == IMPLICIT_RTOL
        err = np.abs(simulate(forced, default, t[-1], 0.05, split=False).z - zref).max() / np.abs(zref).max()
        old = make(name, forced, 2.4, {"dt": 2.0 * np.pi / 2.4 / 100})
        err_old = np.abs(simulate(forced, old, t[-1], 0.05, split=False).z - zref).max() / np.abs(zref).max()
        assert err <= 1e-5 < err_old, (name, err, err_old)


# ----------------------------------------------------------------------------------------------
# 3. Through slack
# ----------------------------------------------------------------------------------------------
def own_tensions(eom, z):
    """Segment tensions ``EA max(l - S, 0) / S`` (N) at every saved instant, from the geometry."""
    c = eom.cable
    return np.array([c.EA * np.maximum(_own_lengths(eom.y0 + zk, c.L, c.H)[1] - c.S, 0.0) / c.S for zk in z])


@pytest.fixture(scope="module")
def snapping(paper, exact_static):
    """FL x 10 at 2.45 rad/s over 22 s: the three segments go slack and snap taut again, 16
    transitions between 14.4 and 20.1 s (scipy's event location)."""
    eom = build_equations(paper, exact_static, omega=2.45, load_scale=10.0)
    t = np.arange(0, 881) * 0.025
    z, events = slack_reference(eom, t)
    assert len(events) >= 12 and {e[1] for e in events} == {1, 2, 3}
    return eom, t, z, events


@pytest.mark.parametrize("name", SCHEMES)
def test_adaptive_steps_locate_every_slack_event_and_meet_the_tolerance(snapping, name):
    """Every transition found in order, at the reference's instant to within the scheme's own
    error, and z and the tensions (snap loads included) within the tolerance of their peaks."""
    eom, t, zref, events = snapping
    Tref = own_tensions(eom, zref)
    for rtol in (1e-4, 1e-5):
        hist = simulate(eom, make(name, eom, 2.45, {"rtol": rtol}), t[-1], 0.025, split=False)
        r = hist.slack
        assert hist.completed and len(r.t) == len(events)
        assert list(r.segment) == [e[1] for e in events] and list(r.kind) == [e[2] for e in events]
        assert np.abs(r.t - [e[0] for e in events]).max() < rtol
        err_z = np.abs(hist.z - zref).max() / np.abs(zref).max()
        err_T = np.abs(own_tensions(eom, hist.z) - Tref).max() / Tref.max()
        # rtol bounds z; the snap tensions, EA / S times an elongation error, come out about 17
        # times less accurate relative to their peak (measured 1.7e-4 at rtol 1e-4)
        assert err_z <= rtol and err_T <= 30.0 * rtol, (rtol, err_z, err_T)


# ----------------------------------------------------------------------------------------------
# 4. A heavy cable (banded Newton solves)
# ----------------------------------------------------------------------------------------------
def _heavy(n):
    """bench_heavy's cable: 100 m span, EA 2e8 N, 10 kg/m, 1 kN at a third of the span, 2 rad/s."""
    case = parse_case(
        f"cable: {{L: 100.0, H: 0.0, length: 102.5, nodes: {n}, EA: 2.0e8, mass_per_length: 10.0}}\n"
        f"loads: {{gravity: 9.81, point: [{{node: {n // 3}, FL: [0.0, 1.0e3]}}]}}\n"
    )
    return case, build_equations(case, run_static(case, all_models=False), omega=2.0)


def test_heavy_cable_default_is_error_controlled_and_accurate():
    case, eom = _heavy(30)
    assert eom.C_band is not None
    default = make_integrator(case.integrator, eom, 2.0)
    assert default.name == "generalized-alpha" and not default.fixed_step
    ref = simulate(eom, DOPRI5(rtol=1e-11, atol=1e-13 * eom.cable.chord_length), 4.0, 0.05, split=False)
    got = simulate(eom, default, 4.0, 0.05, split=False)
    assert got.completed and ref.completed
    assert np.abs(got.z - ref.z).max() <= default.rtol * np.abs(ref.z).max()
    assert np.abs(got.T - ref.T).max() <= default.rtol * np.abs(ref.T).max()


@pytest.fixture(scope="module")
def heavy_200():
    """200 nodes (400 DOF; stiffness-proportional damping puts the fastest damped root at
    1.2e6 1/s), 1 s from rest, and cablesim's dopri5 at rtol 1e-11 as the reference (its step is
    held by stability to ~3e-6 s: some 6 minutes on a shared core)."""
    case, eom = _heavy(200)
    ref = simulate(eom, DOPRI5(rtol=1e-11, atol=1e-13 * eom.cable.chord_length), 1.0, 0.05, split=False)
    assert ref.completed
    return eom, ref


@pytest.mark.slow
@pytest.mark.parametrize("name", SCHEMES)
def test_200_node_heavy_cable_meets_the_tolerance(heavy_200, name):
    eom, ref = heavy_200
    for rtol in (1e-4, 1e-5):
        got = simulate(eom, make(name, eom, 2.0, {"rtol": rtol}), 1.0, 0.05, split=False)
        assert got.completed
        err_z = np.abs(got.z - ref.z).max() / np.abs(ref.z).max()
        err_T = np.abs(got.T - ref.T).max() / np.abs(ref.T).max()
        assert err_z <= rtol and err_T <= rtol, (rtol, err_z, err_T)


# ----------------------------------------------------------------------------------------------
# 5. Fixed steps, settings, the versions for finite differences and transients
# ----------------------------------------------------------------------------------------------
def test_a_dt_keeps_the_fixed_step_grid(forced):
    dt = 2.0 * np.pi / 2.4 / 200
    for name in SCHEMES:
        integ = make(name, forced, 2.4, {"dt": dt})
        st = integ.start(forced, forced.initial_state())
        out = np.empty((1, 3 * forced.n_dof))
        integ.advance(forced.model(), st, 1.0, np.array([1.0]), out)
        assert integ.fixed_step and st.extra["i"] == math.ceil(1.0 / dt - 1e-9)
        assert st.t == pytest.approx(st.extra["i"] * dt, rel=1e-12)
        assert st.extra["steps"].sum() == 0  # the error-controlled loop never ran


def test_versions_for_finite_differences_and_transients(forced):
    integ = make("generalized-alpha", forced, 2.4)
    fd = integ.for_finite_differences()
    period = 2.0 * np.pi / 2.4
    assert fd.fixed_step and period / fd.dt == pytest.approx(round(period / fd.dt), rel=1e-9)
    loose = integ.for_transient(1e-3)
    assert not loose.fixed_step and loose.rtol == 1e-3 and integ.for_transient(1e-9) is integ
    assert fd.for_finite_differences() is fd and fd.for_transient(1e-3) is fd
    measuring = integ.for_measuring(integ.dt_max / 4)
    assert measuring.dt_max == integ.dt_max / 4 and integ.for_measuring(1e3) is integ and fd.for_measuring(1e-3) is fd
    with pytest.raises(ValueError, match="dt must be positive"):
        Newmark(dt=0.0)


def test_steps_are_counted_and_never_above_the_largest(forced):
    integ = make("newmark", forced, 2.4, {"rtol": 1e-2})
    st = integ.start(forced, forced.initial_state())
    t_out = np.arange(1, 401) * 0.05
    out = np.empty((t_out.size, 3 * forced.n_dof))
    assert integ.advance(forced.model(), st, 20.0, t_out, out) == (t_out.size, OK)
    accepted = st.extra["steps"][0]
    assert accepted >= math.ceil(20.0 / integ.dt_max) and st.extra["h"] <= integ.dt_max * (1 + 1e-12)


@pytest.mark.parametrize("name", SCHEMES)
def test_cost_estimate_counts_the_error_controlled_steps(forced, name):
    """The estimate printed before a run (and checked against the step limit) is that of the
    implicit error control, not dopri5's stability and accuracy rule."""
    integ = make(name, forced, 2.4)
    st = integ.start(forced, forced.initial_state())
    t_out = np.arange(1, 401) * 0.05
    assert integ.advance(forced.model(), st, 20.0, t_out, np.empty((t_out.size, 3 * forced.n_dof)))[1] == OK
    predicted = steps_per_second(forced, integ, 2.4) * 20.0
    assert 0.25 < predicted / st.extra["steps"][0] < 4.0, (predicted, st.extra["steps"])


# ----------------------------------------------------------------------------------------------
# 6. The command line
# ----------------------------------------------------------------------------------------------
def _settings(path):
    import h5py

    with h5py.File(path, "r") as f:
        return {k: v for k, v in f["history"].attrs.items() if k.startswith("integrator_")}


def test_dt_and_rtol_flags_on_history(tmp_path, paper_case, write_case, invoke_cli):
    case = write_case(paper_case)
    common = ["history", str(case), "--omega", "2.4", "--duration", "2", "--no-plot"]
    code, _, err, _ = invoke_cli(*common, "--integrator", "newmark", "--dt", "0.01", "-o", "a.h5")
    assert code == 0, err
    assert _settings(tmp_path / "a.h5")["integrator_dt"] == 0.01
    code, _, err, _ = invoke_cli(*common, "--integrator", "generalized-alpha", "--rtol", "1e-4", "-o", "b.h5")
    assert code == 0, err
    got = _settings(tmp_path / "b.h5")
    assert got["integrator_rtol"] == 1e-4 and "integrator_dt" not in got
    code, _, err, _ = invoke_cli(*common, "--dt", "0.01", "-o", "c.h5")  # no scheme named: dopri5 has no dt
    assert code == 2 and "--dt" in err and "--integrator" in err and not (tmp_path / "c.h5").exists()
    code, _, err, _ = invoke_cli(*common, "--integrator", "newmark", "--dt", "0.01", "--rtol", "1e-4")
    assert code == 2 and "exclude each other" in err
    code, _, err, _ = invoke_cli(*common, "--integrator", "rk4", "--rtol", "1e-4")
    assert code == 2 and "integrator.rtol" in err
    code, _, err, _ = invoke_cli(*common, "--integrator", "newmark", "--dt", "-1")
    assert code == 2 and "--dt" in err


def test_dt_flag_overrides_a_case_tolerance(tmp_path, paper_case, write_case, invoke_cli):
    paper_case["integrator"] = {"name": "newmark", "rtol": 1e-4}
    case = write_case(paper_case)
    code, _, err, _ = invoke_cli("free-vibration", str(case), "--mode", "1", "--peak-velocity", "1", "--duration", "2",
                                 "--dt", "0.02", "--no-plot", "-o", "fv.h5")
    assert code == 0, err
    got = _settings(tmp_path / "fv.h5")
    assert got["integrator_dt"] == 0.02 and "integrator_rtol" not in got


def test_rtol_flag_on_sweep_is_recorded(tmp_path, paper_case, write_case, invoke_cli):
    import h5py

    case = write_case(paper_case)
    code, _, err, _ = invoke_cli("sweep", str(case), "--omega", "1.0", "--duration", "20", "--integrator", "newmark",
                                 "--rtol", "1e-3", "--jobs", "1", "--set", "sweep.window=10", "--no-plot", "-o", "s.h5")
    assert code in (0, 3), err
    with h5py.File(tmp_path / "s.h5", "r") as f:
        text = f.attrs["case_yaml"] if "case_yaml" in f.attrs else str(dict(f.attrs))
    assert "rtol: 0.001" in str(text) or "1.0e-03" in str(text) or "0.001" in str(text)
