"""Slack (tension-only) segments in motion (docs/theory.md, section 6).

A segment cannot push: ``T = EA max(l - S, 0) / S``. The exact analysis continues through slack
episodes by default (``slack: continue``), locating every slack onset and re-tightening;
``slack: stop`` keeps the old behaviour (the run stops where a segment first goes slack).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cablesim.analyses.setup import build_equations
from cablesim.dynamics.integrators import DOPRI5, RK4, GeneralizedAlpha, Newmark
from cablesim.dynamics.simulate import simulate
from cablesim.case import case_from_dict
from cablesim.errors import CablesimError
from helpers_dynamics import rel_error


# ----------------------------------------------------------------------------------------------
# 1. The setting
# ----------------------------------------------------------------------------------------------
def test_slack_setting_defaults_to_continue_and_reaches_the_equations(paper_case, exact_static, approx_static):
    case = case_from_dict(paper_case)
    assert case.slack == "continue"
    eom = build_equations(case, exact_static)
    assert eom.slack == "continue" and eom.continues_slack
    assert eom.model().slack == 1
    stop = build_equations(case, exact_static, slack="stop")
    assert not stop.continues_slack and stop.model().slack == 0
    paper_case["slack"] = "stop"
    case_stop = case_from_dict(paper_case)
    assert build_equations(case_stop, exact_static).slack == "stop"
    # the approximate analysis never continues through slack segments
    assert not build_equations(case, approx_static).continues_slack


def test_slack_setting_is_validated(paper_case):
    paper_case["slack"] = "ignore"
    with pytest.raises(CablesimError, match="slack"):
        case_from_dict(paper_case)


def test_slack_flag_on_the_command_line(tmp_path, paper_case, write_case, invoke_cli):
    """``--slack stop`` is the case's ``slack: stop``: a run that goes slack stops, exit 3."""
    paper_case["loads"]["FL"] = [50 * x for x in paper_case["loads"]["FL"]]
    case = write_case(paper_case)
    r = invoke_cli("history", str(case), "--omega", "2.4", "--duration", "20", "--no-plot", "--slack", "stop",
                   "-o", str(tmp_path / "stop.h5"))
    assert r.returncode == 3, (r.returncode, r.stdout, r.stderr)
    assert "slack" in r.stderr


# ----------------------------------------------------------------------------------------------
# 2. Running through slack episodes
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def violent(paper, exact_static):
    """FL x 50 (vertical load amplitude 6 MN > F0): every segment goes slack and re-tightens."""
    return build_equations(paper, exact_static, omega=2.45, load_scale=50.0)


@pytest.mark.parametrize("integ", [DOPRI5(rtol=1e-8, atol=1e-10), RK4(dt=0.002)], ids=["dopri5", "rk4"])
def test_runs_through_slack_episodes(violent, integ):
    hist = simulate(violent, integ, 10.0, 0.05)
    assert hist.completed, hist.message
    assert all(np.all(np.isfinite(a)) for a in (hist.t, hist.z, hist.v, hist.T, hist.residual))
    assert np.all(hist.T >= 0.0) and np.any(hist.T == 0.0)
    r = hist.slack
    assert r.t.size >= 6 and np.all(np.diff(r.t) >= 0)
    assert set(r.kind) == {"slack", "taut"} and set(r.segment) <= {1, 2, 3}
    for k in (1, 2, 3):  # kinds alternate per segment, starting with an onset (all taut at rest)
        kinds = r.kind[r.segment == k]
        assert kinds.size and kinds[0] == "slack"
        assert np.all(kinds[1:] != kinds[:-1])
        assert r.episodes[k - 1] == np.sum(kinds == "slack")
    assert np.all(r.slack_time > 0) and np.all(r.slack_time < 10.0)
    # the peak tracked at every step is at least the largest saved tension
    assert np.all(r.peak_tension >= hist.T.max(axis=0) * (1 - 1e-12))
    # the residual of eq. 15 (tension-only P) stays at the integration's level through the kinks
    assert np.max(hist.residual) < (1e-4 if integ.name == "dopri5" else 1e-2)
    # the saved tensions vanish exactly between the recorded onset and re-tightening
    for k in (1, 2, 3):
        tt = r.t[r.segment == k]
        kinds = r.kind[r.segment == k]
        for a, b in zip(tt[kinds == "slack"], tt[kinds == "taut"]):
            inside = (hist.t > a + 1e-9) & (hist.t < b - 1e-9)
            assert np.all(hist.T[inside, k - 1] == 0.0)


# ----------------------------------------------------------------------------------------------
# 3. Against an independent reference: scipy's DOP853 on the second-order equations, own
#    geometry, tension-only by segment modes, restarted at each transition its events locate
# ----------------------------------------------------------------------------------------------
def _own_lengths(y, L, H):
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [L, H]])
    d = np.diff(pts, axis=0)
    return d, np.hypot(d[:, 0], d[:, 1])


def _own_force(y, taut, S, EA, L, H):
    """P_r = T_r e_r - T_{r+1} e_{r+1} with T = EA (l - S) / S for the segments taken as taut."""
    d, l = _own_lengths(y, L, H)
    f = (taut * EA * (l - S) / S / l)[:, None] * d  # T e per segment
    return (f[:-1] - f[1:]).ravel()


def slack_reference(eom, t_out, rtol=1e-12, s0=None):
    """z(t) at ``t_out`` and the transitions ``[(t, segment 1-based, kind)]``."""
    c = eom.cable
    S, EA, L, H = np.asarray(c.S, float), float(c.EA), float(c.L), float(c.H)
    nd = eom.n_dof
    M, C, F0, FL, w, y0 = eom.mass, eom.C, eom.F0, eom.FL, eom.omega, eom.y0
    x = np.zeros(2 * nd) if s0 is None else np.asarray(s0[: 2 * nd], float)
    taut = (_own_lengths(y0 + x[:nd], L, H)[1] > S).astype(float)
    t, t_end = 0.0, float(t_out[-1])
    out = np.full((t_out.size, nd), np.nan)
    events = []

    def rhs(t, s):
        return np.concatenate([s[nd:], (F0 + FL * np.sin(w * t) - C @ s[nd:] - _own_force(y0 + s[:nd], taut, S, EA, L, H)) / M])

    def gap(k):
        ev = lambda t, s: _own_lengths(y0 + s[:nd], L, H)[1][k] - S[k]  # noqa: E731
        ev.terminal = True
        ev.direction = -1.0 if taut[k] else 1.0  # taut: length falls through S; slack: rises
        return ev

    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), x, method="DOP853", rtol=rtol, atol=1e-13 * c.chord_length,
                        events=[gap(k) for k in range(S.size)], dense_output=True)
        assert sol.status >= 0, sol.message
        t_new = sol.t[-1]
        pick = (t_out >= t) & (t_out <= t_new)
        if pick.any():  # an event may follow the last one before the next output instant
            out[pick] = sol.sol(t_out[pick])[:nd].T
        if sol.status == 1:
            k = min((k for k in range(S.size) if sol.t_events[k].size), key=lambda k: sol.t_events[k][0])
            t_new, x = sol.t_events[k][0], sol.y_events[k][0]
            taut[k] = 1.0 - taut[k]
            events.append((t_new, k + 1, "taut" if taut[k] else "slack"))
        t = t_new
    return out, events


@pytest.fixture(scope="module")
def snapping(paper, exact_static):
    """FL x 15 at 5 rad/s: segment 3 goes slack at 0.94 s, re-tightens at 1.19 s, again 2.04-2.49 s."""
    eom = build_equations(paper, exact_static, omega=5.0, load_scale=15.0)
    t = np.linspace(0.0, 3.0, 61)
    z, events = slack_reference(eom, t)
    assert len(events) >= 4 and {e[2] for e in events} == {"slack", "taut"}
    return eom, t, z, events


def _errors(eom, integ, t, z_ref, events):
    hist = simulate(eom, integ, t[-1], t[1] - t[0])
    assert hist.completed, hist.message
    r = hist.slack
    assert len(r.t) == len(events), (r.t, events)
    assert list(r.segment) == [e[1] for e in events] and list(r.kind) == [e[2] for e in events]
    dt_event = float(np.max(np.abs(r.t - np.array([e[0] for e in events]))))
    return rel_error(hist.z, z_ref), dt_event


@pytest.mark.parametrize(
    "make, steps, order",
    [
        pytest.param(lambda h: RK4(dt=h), (2e-3, 1e-3), 4, id="rk4"),
        pytest.param(lambda h: Newmark(dt=h), (1e-3, 5e-4), 2, id="newmark"),
        pytest.param(lambda h: GeneralizedAlpha(dt=h, rho_inf=0.8), (1e-3, 5e-4), 2, id="generalized-alpha"),
    ],
)
def test_fixed_step_schemes_converge_through_slack_at_their_order(snapping, make, steps, order):
    eom, t, z_ref, events = snapping
    (e1, te1), (e2, te2) = (_errors(eom, make(h), t, z_ref, events) for h in steps)
    rate = np.log2(e1 / e2)
    print(f"{make(1.0).name}: errors {e1:.3g}, {e2:.3g} (order {rate:.2f}); event times within {te1:.2g}, {te2:.2g} s")
    assert rate > order - 0.4
    assert te2 < 1e-6 if order == 4 else te2 < 1e-4


def test_dopri5_converges_through_slack_with_its_tolerance(snapping):
    eom, t, z_ref, events = snapping
    (e1, te1), (e2, te2) = (_errors(eom, DOPRI5(rtol=r, atol=r * 1e-2), t, z_ref, events) for r in (1e-7, 1e-9))
    print(f"dopri5: errors {e1:.3g} (rtol 1e-7), {e2:.3g} (1e-9); event times within {te1:.2g}, {te2:.2g} s")
    assert e2 < 1e-6 and e2 < e1 / 10.0
    assert te2 < 1e-7


def test_unstable_explicit_step_through_slack_still_stops_cleanly(paper, exact_static):
    """rk4 far beyond its stability limit: with slack: continue the blow-up passes through slack
    states and ends non-finite; the record up to there is finite and the message names the step."""
    eom = build_equations(paper, exact_static, omega=2.45)
    hist = simulate(eom, RK4(dt=0.2), 200.0, 0.2)
    assert not hist.completed and "stab" in hist.message and "dt" in hist.message
    assert all(np.all(np.isfinite(a)) for a in (hist.t, hist.z, hist.v, hist.T, hist.residual))


# ----------------------------------------------------------------------------------------------
# 4. Energy through slack episodes; a fully slack cable
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def thrown(paper, exact_static):
    """No damping, no forcing; both nodes thrown up at 30 m/s: every segment goes slack (the
    whole cable at once, in flight under F0), then snaps taut again, a dozen times in 5 s."""
    eom = build_equations(paper, exact_static, omega=0.0, load_scale=0.0, damping_ratio=0.0)
    assert not np.any(eom.C)
    return eom, eom.initial_state(v0=np.array([0.0, -30.0, 0.0, -30.0]))


def _energy(eom, hist):
    """Kinetic + strain energy of the taut segments - F0.y, own geometry."""
    c = eom.cable
    y = eom.y0 + hist.z
    l = np.array([_own_lengths(row, c.L, c.H)[1] for row in y])
    strain = np.sum(c.EA / (2.0 * c.S) * np.maximum(l - c.S, 0.0) ** 2, axis=1)
    return 0.5 * np.sum(eom.mass * hist.v**2, axis=1) + strain - y @ eom.F0


@pytest.mark.parametrize(
    "integs, bound, order",
    [
        pytest.param((DOPRI5(rtol=1e-8, atol=1e-10), DOPRI5(rtol=1e-10, atol=1e-12)), 1e-7, None, id="dopri5"),
        pytest.param((RK4(dt=1e-3), RK4(dt=5e-4)), 1e-7, 4, id="rk4"),
        pytest.param((Newmark(dt=1e-3), Newmark(dt=5e-4)), 2e-6, 2, id="newmark"),
    ],
)
def test_energy_is_conserved_through_slack_episodes(thrown, integs, bound, order):
    eom, s0 = thrown
    ke0 = 0.5 * np.sum(eom.mass * s0[eom.n_dof : 2 * eom.n_dof] ** 2)
    drift = []
    for integ in integs:
        hist = simulate(eom, integ, 5.0, 0.01, s0=s0)
        assert hist.completed, hist.message
        assert np.all(hist.slack.episodes >= 8), hist.slack.episodes
        E = _energy(eom, hist)
        drift.append((E.max() - E.min()) / ke0)
    print(f"{integs[0].name}: energy drift / initial kinetic energy {drift[0]:.3g}, {drift[1]:.3g}")
    assert drift[1] < bound
    if order is not None:  # halving the step
        assert drift[0] / drift[1] > 2.0 ** (order - 0.5)
    else:  # a hundredth of the tolerance
        assert drift[0] / drift[1] > 10.0


@pytest.mark.parametrize("integ", [DOPRI5(), RK4(dt=1e-3), Newmark(dt=1e-3), GeneralizedAlpha(dt=1e-3)],
                         ids=["dopri5", "rk4", "newmark", "generalized-alpha"])
def test_fully_slack_cable_neither_crashes_nor_gives_nan(thrown, integ):
    eom, s0 = thrown
    hist = simulate(eom, integ, 3.0, 0.01, s0=s0)
    assert hist.completed, hist.message
    every = np.all(hist.T == 0.0, axis=1)
    assert every.sum() > 10  # instants with every segment slack
    assert all(np.all(np.isfinite(a)) for a in (hist.t, hist.z, hist.v, hist.T, hist.residual))
    # in flight the nodes fall freely under F0: y'' = F0 / M (no damping, no forcing); the
    # acceleration of generalized-alpha is its algorithmic one, which lags after each snap
    assert np.max(hist.residual) < (0.1 if integ.name == "generalized-alpha" else 1e-3)


# ----------------------------------------------------------------------------------------------
# 5. The record: HDF5, summary, plot
# ----------------------------------------------------------------------------------------------
def test_slack_record_round_trips_and_is_reported(tmp_path, violent, paper):
    from cablesim.io.hdf5 import read_history, write_history
    from cablesim.io.report import history_summary
    from cablesim.plots.history import plot_history, slack_intervals

    hist = simulate(violent, DOPRI5(), 5.0, 0.05)
    path = write_history(tmp_path / "h.h5", hist, "", "history")
    back = read_history(path)
    r, b = hist.slack, back.slack
    np.testing.assert_array_equal(b.t, r.t)
    np.testing.assert_array_equal(b.segment, r.segment)
    assert list(b.kind) == list(r.kind)
    for name in ("peak_tension", "peak_time", "slack_time", "episodes"):
        np.testing.assert_array_equal(getattr(b, name), getattr(r, name))
    assert b.handling == r.handling and "chatter" in b.handling
    # slack intervals from the events add up to the time slack
    for k in (1, 2, 3):
        spans = slack_intervals(r, k, float(hist.t[-1]))
        assert len(spans) == r.episodes[k - 1]
        assert sum(e - s for s, e in spans) == pytest.approx(r.slack_time[k - 1])
    text = history_summary(paper, back, DOPRI5(), 1.0)
    assert "peak tension (kN)" in text and "slack episodes" in text
    pngs = plot_history(back, str(tmp_path / "h"), "test")
    assert any(p.name.endswith("tensions.png") and p.exists() for p in pngs)


# ----------------------------------------------------------------------------------------------
# 6. Sweeps: peak tension and slack fraction per point and segment
# ----------------------------------------------------------------------------------------------
def test_sweep_records_peak_tension_and_slack_fraction(tmp_path):
    import h5py

    from helpers_sweep import do_sweep

    sweep = {"omega": [2.0, 5.0], "duration": 40.0, "window": 20.0, "gamma": [1.0, 15.0], "accelerate": False,
             "floquet": False}
    case, _, res = do_sweep(tmp_path / "s.h5", sweep, n_jobs=1)
    with h5py.File(tmp_path / "s.h5") as f:
        peak = f["sweep/peak_tension"][()]
        frac = f["sweep/slack_fraction"][()]
        assert f["sweep/peak_tension"].attrs["units"] == "N"
    assert peak.shape == frac.shape == (2, 2, 3)  # gamma, omega, segment
    assert np.all(np.isfinite(peak)) and np.all((frac >= 0) & (frac <= 1))
    assert np.all(frac[0] == 0.0)  # the paper's loads: always taut
    assert frac[1, 1, 2] > 0.0  # FL x 15 at 5 rad/s: segment 3 goes slack
    assert np.all(peak[1] > peak[0])
    np.testing.assert_array_equal(res.data[1]["slack_fraction"], frac[1])
    from cablesim.io.report import sweep_summary

    text = sweep_summary(case, res, 1.0)
    assert "slack fraction" in text and "peak tension" in text


# ----------------------------------------------------------------------------------------------
# 7. Chatter; statics unchanged
# ----------------------------------------------------------------------------------------------
def test_chattering_segment_is_held_not_stalled(forced_eom):
    """Transitions of a segment within the chatter window of its previous one hold its mode for
    the window; a mismatch found after it is taken at the window's end, not located again."""
    from cablesim.dynamics.integrators.events import CHATTER_WINDOW, locate_event, transition

    eom = forced_eom
    assert eom.continues_slack
    st = RK4(dt=1e-3).start(eom, eom.initial_state())
    t = 1.0
    transition(st, 2, t)  # slack
    assert st.extra["chatter_holds"] == 0
    transition(st, 2, t + 1e-7)  # taut again at once: chatter
    transition(st, 2, t + 2e-7)  # and slack
    assert st.extra["chatter_holds"] == 2
    hold = st.extra["evw"][0]
    assert hold[2] == pytest.approx(t + 2e-7 + CHATTER_WINDOW)
    assert [e[2] for e in st.extra["events"]] == ["slack", "taut", "slack"]
    # segment 3 is physically taut (the equilibrium) but now in the slack mode: the mismatch is
    # ignored during the hold and taken at its end
    s = st.s.copy()
    te, k = locate_event(eom.model(), t + 2e-7, t + 1e-3, s, s, st.wk[0].taut, st.extra["evw"])
    assert k == 2 and te == pytest.approx(hold[2], abs=1e-15)
    # a step inside the hold finds nothing
    te, k = locate_event(eom.model(), t + 2e-7, t + 1e-6, s, s, st.wk[0].taut, st.extra["evw"])
    assert k == -1


def test_statically_slack_segment_is_still_refused(paper_case):
    """slack: continue is about motion: a case with a segment slack under F0 is refused as before."""
    from cablesim.analyses.static import run_static

    paper_case["loads"]["F0"] = [1000e3, 0.0, -1000e3, 0.0]  # nodes pushed towards each other
    case = case_from_dict(paper_case)
    assert case.slack == "continue"
    for analysis in ("exact", "approximate"):
        with pytest.raises(CablesimError, match=r"Segment 2.*slack"):
            run_static(case, analysis, all_models=False)


def test_command_line_continues_through_slack_and_reports_it(tmp_path, paper_case, write_case, invoke_cli):
    import h5py

    paper_case["loads"]["FL"] = [50 * x for x in paper_case["loads"]["FL"]]
    case = write_case(paper_case)
    r = invoke_cli("history", str(case), "--omega", "2.45", "--duration", "5", "--no-plot", "-o", str(tmp_path / "go.h5"))
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
    assert "peak tension (kN)" in r.stdout and "slack episodes" in r.stdout and "transitions located" in r.stdout
    with h5py.File(tmp_path / "go.h5") as f:
        assert set(f["history/events"]) == {"t", "segment", "kind"}
        assert f["history/events/t"].size >= 6
        assert set(f["history/segments"]) == {"peak_tension", "peak_time", "slack_time", "slack_episodes"}
        assert f["history"].attrs["slack"] == "continue"
