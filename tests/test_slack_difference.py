"""The matrix-free shooting through slack (:mod:`cablesim.orbits.slackdifference`): the action of
the monodromy by central differences of the flow through slack, against the dense shooting's
variational monodromy cut at the events and against the independent event-driven reference
(``helpers_slack.Reference``: scipy DOP853, own tension-only segments, its own
finite-difference monodromy). The orbit: the paper's cable, load x 13.5 at 2.45 rad/s (segment 3
slack once a period; the orbit of tests/test_orbits_slack.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.orbits.accelerate import newton_mf
from cablesim.orbits.matrixfree import orbit_leading
from cablesim.orbits.shooting import Shooting, solve_orbit
from cablesim.orbits.slackdifference import SlackDifferenceShooting
from cablesim.orbits.systems import cable_system

from helpers_slack import Reference

OMEGA, SCALE = 2.45, 13.5
START = np.array([-4.334, 7.088, -2.68, -3.665, -18.247, 26.177, -14.215, -21.179])


@pytest.fixture(scope="module")
def slack_case(paper, exact_static):
    eom = build_equations(paper, exact_static, omega=OMEGA, load_scale=SCALE)
    system = cable_system(eom, gamma=1.0)
    sol = solve_orbit(Shooting(system, through_slack=True), START)
    assert sol.converged and sol.evaluation.events.shape[0] == 2  # one slack episode
    return eom, system, sol


def test_differenced_action_is_the_variational_monodromy_through_slack(slack_case):
    """``M X`` by differences against the dense shooting's monodromy (variational equations cut
    at the events) on the orbit: to 1e-7 of ``|M X|`` column by column (measured 1.2e-8 at
    most; plain central differences at the same step were 1.2e-5 off); the differences cross
    both events, since the orbit goes slack once a period."""
    _, system, sol = slack_case
    sh = SlackDifferenceShooting(system)
    ev = sh.evaluate(sol.u, OMEGA, jac=False)
    assert ev.status == 0 and np.abs(ev.r - sol.evaluation.r).max() == 0.0  # the same flow
    X = np.random.default_rng(3).standard_normal((sh.n, 4)) * np.abs(sol.u)[:, None]
    MX = sh.monodromy_apply(ev, X)
    dense = sol.evaluation.monodromy @ X
    for j in range(X.shape[1]):
        assert np.abs(MX[:, j] - dense[:, j]).max() < 1e-7 * np.abs(dense[:, j]).max()
    J = sh.jacobian_apply(ev, X)
    np.testing.assert_allclose(J, MX - X, rtol=0, atol=1e-12 * np.abs(MX).max())


def test_newton_and_leading_multipliers_through_slack_match_the_reference(slack_case):
    """The matrix-free Newton of the sweep's acceleration through slack, from the rough start:
    the orbit to 1e-7 of each half's extent and its leading multipliers to 1e-5 of the
    independent reference's finite-difference monodromy (scipy DOP853 through the events)."""
    eom, system, _ = slack_case
    sh = SlackDifferenceShooting(system)
    ev = newton_mf(eom, sh, START.copy())
    assert ev is not None and ev.leading is not None
    ref = Reference(eom)
    x_ref, M_ref = ref.orbit(START.copy())
    nd = eom.n_dof
    for part in (slice(0, nd), slice(nd, 2 * nd)):
        assert np.abs(ev.u[part] - x_ref[part]).max() < 1e-7 * np.abs(x_ref[part]).max()
    mu_ref = np.linalg.eigvals(M_ref)
    for mu in ev.leading.multipliers:
        assert np.abs(mu_ref - mu).min() < 1e-5
    assert ev.leading.multipliers.size >= 1
    # the largest reference multiplier is among the leading ones
    top = mu_ref[np.argmax(np.abs(mu_ref))]
    assert np.abs(ev.leading.multipliers - top).min() < 1e-5


def test_a_system_that_cannot_go_slack_is_refused(slack_case):
    """A system without slack functions (the approximate analysis, moving supports) is refused
    with a message saying so."""
    _, system, _ = slack_case
    with pytest.raises(ValueError, match="cannot follow slack"):
        SlackDifferenceShooting(dataclasses.replace(system, slack=None))


@pytest.mark.parametrize("dense_dof", [None, 0])
def test_sweep_point_decided_matrix_free_through_slack_as_the_dense_one(paper, exact_static, monkeypatch, dense_dof):
    """FL x 13.5 at 2.45 rad/s shot matrix-free (forced: the cable is small enough for the dense
    shooting, which decides it too): the matrix-free Newton meets the slack segment and the
    point's orbits are shot through slack, densely (a cable within ``DENSE_DOF``) or, with
    ``DENSE_DOF`` set to 0 as for a cable above it, by differences. Either way the point is
    decided by shooting with the dense decision's period, amplitudes and snap loads (1e-6), much
    sooner than integration alone. Before, the matrix-free path left it to integration (to 228 s
    of simulated time, against 84.6 s)."""
    from cablesim.analyses.setup import make_integrator
    from cablesim.dynamics.steady import SteadyCriterion, steady_response
    from cablesim.orbits import accelerate as acc

    eom = build_equations(paper, exact_static, omega=OMEGA, load_scale=SCALE)
    integ = make_integrator(paper.integrator, eom, max(OMEGA, float(eom.frequencies[0])))
    channels, crit = np.array([1, 3]), SteadyCriterion(cap=600.0)
    dense = acc.accelerated_steady_response(eom, integ, channels, crit, matrix_free=False)
    if dense_dof is not None:
        monkeypatch.setattr(acc, "DENSE_DOF", dense_dof)
    made = []
    original = SlackDifferenceShooting.evaluate
    monkeypatch.setattr(SlackDifferenceShooting, "evaluate", lambda self, *a, **k: made.append(1) or original(self, *a, **k))
    mf = acc.accelerated_steady_response(eom, integ, channels, crit, matrix_free=True)
    assert bool(made) == (dense_dof == 0)  # shot by differences only above DENSE_DOF
    plain = steady_response(eom, integ, channels, crit)
    assert dense.decided == mf.decided == "shooting" and plain.decided == "integrated"
    assert mf.period == dense.period == 1 and mf.steady
    assert mf.t_end < 0.5 * plain.t_end
    np.testing.assert_allclose(mf.amplitude, dense.amplitude, rtol=1e-6)
    np.testing.assert_allclose(mf.peak_tension, dense.peak_tension, rtol=1e-6)
    np.testing.assert_allclose(mf.slack_fraction, dense.slack_fraction, atol=1e-6)
