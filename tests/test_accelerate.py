"""Steady states by shooting from the transient (``sweep.accelerate``): the same answers as
integration alone, sooner.

The reference is the package's plain steady-state detection (integration until the
stroboscopic samples repeat and the orbit is stable), an independent decision procedure: the
accelerated one must give the same period, the same steady/not-steady/failed flag and the same
amplitudes (1e-3 relative) at every point, and must never accept an unstable orbit.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import cablesim
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.dynamics.integrators import DOPRI5
from cablesim.dynamics.steady import SteadyCriterion, steady_response
from cablesim.orbits.accelerate import (
    Orbit,
    accelerated_steady_response,
    check_interval,
    in_linear_neighbourhood,
    slowest_decay_rate,
    strobe_noise,
)
from cablesim.orbits.shooting import Shooting, solve_orbit
from cablesim.orbits.systems import cable_system
from helpers_sweep import do_sweep
from helpers_slack import Reference

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
CHANNELS = np.array([1, 3])


@pytest.fixture(scope="module")
def paper():
    case = cablesim.load_case(CONFIG)
    return case, run_static(case)


def _both(paper, w, criterion=SteadyCriterion(), scale=1.0, slack=None):
    case, static = paper
    eom = build_equations(case, static, omega=w, load_scale=scale, slack=slack)
    integ = make_integrator(case.integrator, eom, max(w, float(eom.frequencies[0])))
    return (steady_response(eom, integ, CHANNELS, criterion),
            accelerated_steady_response(eom, integ, CHANNELS, criterion))


@pytest.mark.parametrize("w", [0.6, 1.26, 2.3, 2.48, 3.5, 5.0, 5.1, 5.5])
def test_same_answer_as_integration_alone(paper, w):
    plain, fast = _both(paper, w)
    assert fast.period == plain.period and fast.steady == plain.steady and fast.failed == plain.failed
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=1e-3)
    np.testing.assert_allclose(fast.halfrange, plain.halfrange, rtol=1e-3)
    assert fast.t_end <= plain.t_end


def test_most_points_are_decided_by_shooting_sooner(paper):
    decided, saved = [], []
    for w in (1.0, 2.0, 3.0, 4.0, 5.5):
        plain, fast = _both(paper, w)
        decided.append(fast.decided)
        saved.append(plain.t_end / fast.t_end)
    assert decided.count("shooting") >= 4, decided
    assert np.median(saved) > 3.0, saved


def test_late_jump_is_not_hidden(paper):
    """5.05 rad/s: the response lingers for ~1000 s near the small harmonic orbit, which is
    unstable (inside the period-doubling band); shooting finds it and rejects it, and the point
    ends on the large period-2 orbit after the jump, as integration alone finds."""
    plain, fast = _both(paper, 5.05, SteadyCriterion(cap=4000.0))
    assert plain.period == fast.period == 2 and fast.steady
    assert fast.t_end > 1500.0
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=1e-3)
    assert fast.multipliers is None or np.all(np.abs(fast.multipliers) < 1.0)


def test_slack_failure_stays_a_failure(paper):
    """A harmonic load that drives a segment slack: both stop, for the same reason, at the same
    instant to the transient's integration tolerance (rtol 1e-6 against the default 1e-8), with
    slack: stop."""
    plain, fast = _both(paper, 2.45, SteadyCriterion(cap=600.0), scale=10.0, slack="stop")
    assert plain.failed and fast.failed and fast.status == plain.status
    assert fast.t_end == pytest.approx(plain.t_end, rel=1e-6)


def test_slack_orbit_is_decided_by_shooting_with_the_orbits_snap_loads(paper):
    """FL x 13.5 at 2.45 rad/s: segment 3 goes slack once a period. The accelerated point is
    decided by shooting through slack (it was left to integration alone), and both points report
    the steady orbit's snap loads and slack fractions (they reported the transient's), checked
    against an independent event-driven integration (scipy DOP853, own tension-only segments) of
    one period from each point's final state, which must also close the orbit."""
    case, static = paper
    plain, fast = _both(paper, 2.45, SteadyCriterion(cap=600.0), scale=13.5)
    assert plain.decided == "integrated" and fast.decided == "shooting"
    assert fast.period == plain.period == 1 and fast.steady and plain.steady
    assert fast.t_end < 0.5 * plain.t_end
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=1e-5)
    np.testing.assert_allclose(fast.peak_tension, plain.peak_tension, rtol=1e-5)
    np.testing.assert_allclose(fast.slack_fraction, plain.slack_fraction, atol=1e-5)
    eom = build_equations(case, static, omega=2.45, load_scale=13.5)
    ref = Reference(eom)
    nd = eom.n_dof
    for point in (plain, fast):
        x0 = point.final_state[: 2 * nd]
        peaks = np.zeros(eom.cable.n_segments)
        x1, events = ref.flow(x0, rtol=1e-11, peaks=peaks)
        assert np.abs(x1 - x0).max() < 1e-5 * np.abs(x0).max()  # on the orbit
        np.testing.assert_allclose(point.peak_tension, peaks, rtol=1e-5)
        slack_time = np.zeros(eom.cable.n_segments)
        for (t_on, k_on, m_on), (t_off, k_off, m_off) in zip(events[::2], events[1::2]):
            assert k_on == k_off and (m_on, m_off) == (0.0, 1.0)  # an onset, then the re-tightening
            slack_time[k_on] += t_off - t_on
        assert slack_time[2] > 0.0 and slack_time[:2].max() == 0.0
        np.testing.assert_allclose(point.slack_fraction, slack_time / ref.T, atol=1e-6)


def test_sweep_records_how_points_were_decided(tmp_path):
    case = cablesim.load_case(CONFIG, overrides=["sweep.omega=[2.0, 3.0]", "sweep.channels=[z2]"])
    out = tmp_path / "s.h5"
    run = cablesim.sweep(case, jobs=1, output=out)
    d = run.result.data[0]
    assert list(d["decided"]) == ["shooting", "shooting"]
    assert np.all(np.abs(d["multipliers"]) < 1.0)
    import h5py

    with h5py.File(out) as f:
        assert [x.decode() for x in f["sweep/decided"][()]] == ["shooting", "shooting"]
        assert bool(f["sweep"].attrs["accelerate"]) is True


# ----------------------------------------------------------------------------------------------
# The acceptance rule, piece by piece
# ----------------------------------------------------------------------------------------------
def _orbit_of(monodromy, u, scale, period=1, phase=0):
    mu = np.linalg.eigvals(monodromy)
    ev = SimpleNamespace(monodromy=monodromy, multipliers=mu[np.argsort(-np.abs(mu))])
    return Orbit(period, u, ev, scale, phase)


def _rotation_map(rho=0.95, turn=0.4, fast=0.5):
    """A stable 4x4 monodromy: a slow pair rho e^(+-i turn), a fast pair of modulus ``fast``."""
    R = rho * np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    M = np.zeros((4, 4))
    M[:2, :2] = R
    M[2:, 2:] = fast * np.eye(2)
    Q = np.linalg.qr(np.random.default_rng(3).normal(size=(4, 4)))[0]
    return Q @ M @ Q.T


def _strobes(M, u, e0, period, phase, n, quadratic=0.0):
    """``n + 1`` strobes of a trajectory whose passages near ``u`` (strobes ``j = phase mod
    period``) follow ``e -> M e + quadratic |e|^2 (1, 0, 0, 0)``; the strobes in between are far
    away (the orbit's other phase points)."""
    out = np.tile(u + 10.0, (n + 1, 1))
    e = np.asarray(e0, dtype=float)
    for j in range(phase, n + 1, period):
        out[j] = u + e
        e = M @ e + quadratic * float(e @ e) * np.array([1.0, 0.0, 0.0, 0.0])
    return out


@pytest.mark.parametrize("period", [1, 2])
def test_linear_neighbourhood_accepts_the_linear_map_and_rejects_a_nonlinear_one(period):
    """Strobes generated by the linear map itself pass at any size of deviation; the same map
    with a quadratic term fails while the deviation is large, and passes once it has shrunk
    below the size where the quadratic term is a small part of the contraction margin."""
    M = _rotation_map()
    u = np.array([1.0, -2.0, 0.5, 3.0])
    orbit = _orbit_of(M, u, np.ones(4), period=period, phase=1)
    e0 = [0.3, -0.2, 0.1, 0.25]
    n = 1 + 80 * period
    lin = _strobes(M, u, e0, period, 1, n)
    quad = _strobes(M, u, e0, period, 1, n, quadratic=0.2)
    early = 1 + 3 * period  # the first strobe with three orbit periods of history
    assert in_linear_neighbourhood(lin, early, orbit)
    assert in_linear_neighbourhood(lin, n, orbit)
    assert not in_linear_neighbourhood(quad, early, orbit)  # quadratic part 0.2 |e| >> 0.5 (1 - 0.95)
    assert in_linear_neighbourhood(quad, n, orbit)  # |e| ~ 0.02 after 80 periods: 0.2 |e| < 0.025
    # between two passages the last one is used; too little history is never enough
    assert in_linear_neighbourhood(lin, n - 1, orbit)
    assert not in_linear_neighbourhood(lin, early - 1, orbit)


def test_linear_neighbourhood_uses_the_orbits_own_contraction_margin():
    """The same unexplained part is acceptable next to a strongly contracting orbit and not
    next to one with a multiplier near 1 (a fold or period doubling close by)."""
    u = np.zeros(4)
    e0 = [0.01, 0.0, 0.0, 0.0]
    for rho, ok in ((0.6, True), (0.995, False)):
        M = _rotation_map(rho=rho, fast=0.5 * rho)
        orbit = _orbit_of(M, u, np.ones(4))
        quad = _strobes(M, u, e0, 1, 0, 6, quadratic=0.5)  # unexplained 0.5 |e|^2 = 0.005 |e|
        assert in_linear_neighbourhood(quad, 6, orbit) is ok


def _transient(eom):
    """The accelerated sweep's transient integrator (rtol 1e-6, the default atol)."""
    return DOPRI5(rtol=1e-6, atol=1e-10 * eom.cable.chord_length)


def _strobed(eom, s0, periods):
    """States ``(z, y')`` at forcing phase 0 over ``periods`` forcing periods from ``s0``
    (DOPRI5 at the transient's tolerance)."""
    nd = eom.n_dof
    T = 2.0 * np.pi / eom.omega
    integ = _transient(eom)
    st = integ.start(eom, s0)
    out = np.empty((periods, 3 * nd))
    n, code = integ.advance(eom.model(), st, periods * T, T * np.arange(1, periods + 1), out)
    assert code == 0 and n == periods
    return np.vstack([s0[None, : 2 * nd], out[:, : 2 * nd]])


def _orbit_from(eom, x):
    sol = solve_orbit(Shooting(cable_system(eom), 1, 1, "omega"), x, eom.omega, tol=1e-10)
    assert sol.converged
    ev = sol.evaluation
    nd = eom.n_dof
    ext = np.maximum(np.abs(ev.xmax), np.abs(ev.xmin))
    scale = np.concatenate([np.full(nd, ext[:nd].max()), np.full(nd, ext[nd:].max())])
    return Orbit(1, sol.u, ev, scale, 0, strobe_noise(eom, _transient(eom), sol.u, 1, scale))


def test_unstable_orbit_is_never_accepted(paper):
    """5.05 rad/s, started on the small harmonic orbit (unstable: a multiplier of modulus
    1.004) with a tiny offset: for the 60 periods of the cap the trajectory follows the orbit's
    linearisation (so only the stability rule can refuse it), and the point ends at the cap,
    not steady, as integration alone ends it."""
    case, static = paper
    eom = build_equations(case, static, omega=5.05)
    x300 = _strobed(eom, eom.initial_state(), 240)[-1]  # ~300 s: lingering near the small orbit
    orbit = _orbit_from(eom, x300)
    assert orbit.rho > 1.0 and not orbit.stable
    s0 = eom.initial_state(z0=orbit.u[: eom.n_dof] * (1 + 1e-7), v0=orbit.u[eom.n_dof :])
    states = _strobed(eom, s0, 40)
    assert in_linear_neighbourhood(states, 40, orbit)
    cap = SteadyCriterion(cap=60 * 2 * np.pi / 5.05, window=10.0)
    integ = make_integrator(case.integrator, eom, 5.05)
    plain = steady_response(eom, integ, CHANNELS, cap, s0=s0)
    fast = accelerated_steady_response(eom, integ, CHANNELS, cap, s0=s0)
    assert not plain.steady and plain.period == 0
    assert not fast.steady and fast.period == 0 and fast.decided == "cap"


def test_transient_outside_the_neighbourhood_is_not_accepted(paper):
    """2.48 rad/s from rest (next to the softening resonance's fold): for the first ~60 periods
    the response is too far from its stable orbit for the linearisation to describe it, and the
    point is not decided while it is."""
    case, static = paper
    eom = build_equations(case, static, omega=2.48)
    states = _strobed(eom, eom.initial_state(), 200)
    orbit = _orbit_from(eom, states[-1])
    assert orbit.stable
    entered = next(k for k in range(3, 201) if in_linear_neighbourhood(states, k, orbit))
    assert 30 < entered < 150, entered
    assert all(in_linear_neighbourhood(states, k, orbit) for k in range(entered + 20, 201))
    integ = make_integrator(case.integrator, eom, 2.48)
    fast = accelerated_steady_response(eom, integ, CHANNELS, SteadyCriterion())
    assert fast.decided == "shooting"
    assert fast.t_end > (entered - 10) * 2 * np.pi / 2.48


# ----------------------------------------------------------------------------------------------
# Whole sweeps on reduced grids: chains (up/down), gamma axes, the subharmonic band's edges
# ----------------------------------------------------------------------------------------------
def _plain_and_fast(tmp_path, sweep):
    plain = do_sweep(tmp_path / "plain.h5", dict(sweep, accelerate=False))[2]
    fast = do_sweep(tmp_path / "fast.h5", dict(sweep, accelerate=True))[2]
    return plain, fast


def _assert_same_answers(plain, fast):
    assert len(plain.curves) == len(fast.curves)
    for c in plain.data:
        a, b = plain.data[c], fast.data[c]
        np.testing.assert_array_equal(b["period"], a["period"])
        np.testing.assert_array_equal(b["steady"], a["steady"])
        np.testing.assert_array_equal(b["failed"], a["failed"])
        both = a["steady"] & b["steady"]
        np.testing.assert_allclose(b["amplitude"][both], a["amplitude"][both], rtol=1e-3)


def test_up_and_down_sweeps_agree_across_the_jump(tmp_path):
    """gamma = 5: up and down sweeps differ at 2.2 rad/s (|z2| 4.3 m up, 30.1 m down); each
    point starts from the previous one's final state, and both chains give the same answers
    accelerated or not."""
    sweep = {"omega": [2.1, 2.2, 2.3, 2.4], "duration": 1500.0, "direction": "both", "channels": ["z2", "z4"],
             "gamma": [5.0]}
    plain, fast = _plain_and_fast(tmp_path, sweep)
    _assert_same_answers(plain, fast)
    up, down = fast.data[0], fast.data[1]
    assert down["amplitude"][1, 0] > 3.0 * up["amplitude"][1, 0]  # the two branches at 2.2 rad/s
    assert np.sum(np.concatenate([up["decided"], down["decided"]]) == "shooting") >= 6


def test_gamma_sweep_agrees_at_the_edges_of_the_subharmonic_band(tmp_path):
    """Just outside the period-doubling band (5.0212-5.0744 rad/s at gamma = 1, from the
    continuation), where the harmonic orbit is stable but its transient decays slowly (a
    multiplier of modulus 0.98-0.99), and at half the load, where there is no band."""
    sweep = {"omega": [4.95, 5.0, 5.1, 5.15], "duration": 3000.0, "channels": ["z2", "z4"], "gamma": [0.5, 1.0]}
    plain, fast = _plain_and_fast(tmp_path, sweep)
    _assert_same_answers(plain, fast)
    assert np.all(fast.data[1]["period"] == 1) and np.all(fast.data[1]["steady"])


def test_slowest_decay_rate_is_that_of_the_rayleigh_damped_modes(paper):
    """With Rayleigh damping ``a0 M + a1 K0`` mode i decays at ``xi_i w_i = (a0 + a1 w_i^2) / 2``
    (underdamped modes); the acceptance checks come every eighth of the slowest such time."""
    case, static = paper
    eom = build_equations(case, static, omega=2.0)
    w = np.asarray(eom.frequencies, dtype=float)
    rates = 0.5 * (eom.a0 + eom.a1 * w**2)
    assert np.all(rates < w)  # all underdamped here
    assert slowest_decay_rate(eom) == pytest.approx(rates.min(), rel=1e-9)
    T = 2 * np.pi / 2.0
    assert check_interval(eom) == max(1, min(10, round(1.0 / (8 * rates.min() * T))))
