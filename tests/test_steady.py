"""Steady-state detection in frequency sweeps: the closed-form linear response, a subharmonic
found only after a late jump, and what the Floquet check buys.

Every case is the paper example with its ``sweep:`` section replaced (``helpers_sweep``); the
sweeps run in-process (``linear`` and ``late`` are session fixtures in ``conftest.py``, shared
with the layout checks of ``test_sweep.py``).

Numbers measured on this model (exact analysis) that the tests rely on:

- linear regime (FL x 1e-4, xi = 0.05): steady after 140-390 s; amplitudes match the closed form
  ``|(K0 - w^2 M + i w C)^-1 FL|`` to 1e-4..3e-4 relative;
- w = 5.05, xi = 0.01: the small harmonic response (|z2| ~ 0.10 m) starts to grow at ~1000 s,
  jumps over 1500-2500 s to the 1/2 subharmonic (|z2| = 4.08 m at 2.525 rad/s), which the
  default criterion finds steady at t = 3113 s (a 3000 s cap finds it at its very last check,
  t = 3002 s; a 2800 s cap does not find it at all).
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers_sweep import LATE_SWEEP, LIN_GAMMA, LIN_W, closed_form, do_sweep


# ----------------------------------------------------------------------------------------------
# 1. Linear regime: closed-form amplitudes
# ----------------------------------------------------------------------------------------------
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


def test_floquet_off_same_result_at_default_tolerance(wdir):
    """At tol = 1e-5 the small orbit never repeats well enough before it starts to grow, so the
    periodicity test alone already waits for the jump: switching the Floquet check off changes
    nothing but the reported multiplier (the check never touches the trajectory). Without
    acceleration, whose shooting computes multipliers of its own."""
    plain = dict(LATE_SWEEP, omega=[5.05], accelerate=False)
    _, _, res = do_sweep(wdir / "late-plain.h5", plain, n_jobs=1)
    _, _, off = do_sweep(wdir / "late-nofloquet.h5", dict(plain, floquet=False), n_jobs=1)
    on, o = res.data[0], off.data[0]
    assert o["period"][0] == on["period"][0] == 2
    assert o["steady"][0]
    assert o["t_end"][0] == on["t_end"][0]
    np.testing.assert_array_equal(o["amplitude"][0], on["amplitude"][0])
    assert np.isnan(o["floquet"][0]) and on["floquet"][0] < 1.0
    assert on["decided"][0] == o["decided"][0] == "integrated"


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
# 3. What a point hands on to the next one of a chain
# ----------------------------------------------------------------------------------------------
def test_cap_reached_hands_on_the_state_at_forcing_phase_0():
    """A point that reaches the cap ends at its last whole forcing period: ``t_end`` is a whole
    number of periods and the final state (the start of the next point of an up/down sweep) has
    the ``y''`` that eq. 15 gives at forcing phase 0, where ``F = F0``. An adaptive integrator's
    own state steps past that instant; handed on, its ``y''`` would belong to another phase, and
    since the third-order equations keep ``M y'' + C y' + P(y) - F`` constant, every later point
    of the chain would carry the mismatch as a constant force (measured: 0.46 m/s^2 at 5.05 rad/s
    with DOPRI5 at rtol 1e-6, a 20 % amplitude error on the next points)."""
    from pathlib import Path

    import cablesim
    from cablesim.analyses.setup import build_equations
    from cablesim.analyses.static import run_static
    from cablesim.dynamics.integrators import DOPRI5
    from cablesim.dynamics.steady import SteadyCriterion, steady_response

    case = cablesim.load_case(Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml")
    eom = build_equations(case, run_static(case), omega=5.05)
    nd, T = eom.n_dof, 2 * np.pi / 5.05
    integ = DOPRI5(rtol=1e-6, atol=1e-8 * eom.cable.chord_length)
    r = steady_response(eom, integ, np.array([1, 3]), SteadyCriterion(cap=100.0, window=20.0))
    assert r.decided == "cap"
    assert r.t_end / T == pytest.approx(round(r.t_end / T), abs=1e-9)
    s = r.final_state
    consistent = eom.initial_state(z0=s[:nd], v0=s[nd : 2 * nd])[2 * nd :]
    force_offset = np.abs(eom.mass * (s[2 * nd :] - consistent)).max()  # N
    assert force_offset < 1e-4 * np.abs(case.FL).max()
