"""Accelerated sweep points above the matrix-free crossover (``sweep.accelerate`` on heavy cables).

References, none from the matrix-free code under test:

- the package's plain steady-state detection (integration until the strobes repeat), the same
  case with acceleration off: same period, same flags, amplitudes within the sweep's periodicity
  tolerance;
- an independent integration of the accepted orbit (dopri5 at rtol 1e-11, not the shooting's
  scheme): it must close after one orbit period;
- the dense shooting on a cable small enough for both (its whole monodromy and every
  multiplier): the same orbits, the same multipliers above the bound, the same acceptance
  decision at every check.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.dynamics.integrators import DOPRI5
from cablesim.dynamics.simulate import advance_in_chunks
from cablesim.dynamics.steady import SteadyCriterion, steady_response
from cablesim.orbits import accelerate as acc
from cablesim.orbits.floquet import Leading
from cablesim.orbits.mfproblem import MATRIX_FREE_DOF

CASE = Path(__file__).resolve().parents[1] / "configs" / "heavy-span.yaml"
CRITERION = SteadyCriterion()


def heavy(n: int, omega: float):
    """``configs/heavy-span.yaml`` with ``n`` interior nodes (its point loads stay at 150 m and
    60 m), its integrator and two channels at midspan."""
    case = parse_case(CASE.read_text().replace("nodes: 100", f"nodes: {n}"))
    eom = build_equations(case, run_static(case), omega=omega)
    integ = make_integrator(case.integrator, eom, max(omega, float(eom.frequencies[0])))
    return eom, integ, np.array([eom.n_dof // 2, eom.n_dof // 2 + 1])


class Recorder:
    """The accelerated point's hook, keeping the strobes it was last given."""

    def __init__(self, shooter):
        self.shooter, self.states = shooter, None

    def __call__(self, k, s, strobes):
        nd = self.shooter.eom.n_dof
        self.states = strobes * np.concatenate([np.ones(nd), np.full(nd, self.shooter.eom.omega)])
        return self.shooter(k, s, strobes)


def shoot(eom, integ, channels, matrix_free: bool, scheme: str = "auto"):
    """The accelerated point as :func:`accelerated_steady_response` runs it, with its shooter."""
    transient = integ.for_transient(acc.TRANSIENT_RTOL)
    every = acc.check_interval(eom)
    shooter = acc._Shooter(eom, integ, transient, channels, CRITERION, every, matrix_free=matrix_free, scheme=scheme)
    rec = Recorder(shooter)
    r = steady_response(eom, transient, channels, CRITERION, decide=rec, decide_every=every)
    return r, shooter, rec


def closing_error(eom, orbit) -> float:
    """Scaled ``|x(pT) - x(0)|`` of the orbit under dopri5 at rtol 1e-11."""
    T = orbit.period * 2.0 * np.pi / eom.omega
    ref = DOPRI5(rtol=1e-11, atol=1e-13 * eom.cable.chord_length)
    state = ref.start(eom, eom.initial_state(z0=orbit.u[: eom.n_dof], v0=orbit.u[eom.n_dof :]))
    out = np.empty((1, 3 * eom.n_dof))
    n, code = advance_in_chunks(ref, eom.model(), state, T, np.array([T]), out)
    assert code == 0 and n == 1
    return float(np.abs(out[0, : orbit.u.size] - orbit.u).max() / orbit.scale.max())


@pytest.fixture(scope="module")
def above():
    """11 nodes (44 states, just above the crossover) at 2.0 rad/s, below the first mode."""
    eom, integ, ch = heavy(11, 2.0)
    assert 2 * eom.n_dof > MATRIX_FREE_DOF
    return eom, integ, ch, steady_response(eom, integ, ch, CRITERION)


def test_above_the_crossover_the_point_agrees_with_integration_alone(above):
    eom, integ, ch, plain = above
    fast = acc.accelerated_steady_response(eom, integ, ch, CRITERION)
    assert plain.steady and plain.decided == "integrated"
    assert fast.decided == "shooting" and fast.steady and fast.period == plain.period
    assert acc.uses_matrix_free(acc.cable_system(eom), None)  # shot matrix-free by default
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=CRITERION.tol)
    np.testing.assert_allclose(fast.halfrange, plain.halfrange, rtol=CRITERION.tol)
    assert fast.t_end < plain.t_end


def test_an_orbit_accepted_matrix_free_closes_under_an_independent_integration(above):
    """The accepted orbit (the automatic scheme: Radau IIA for this stiff cable) closes to 1e-7 of
    its extent (the Newton tolerance) under dopri5; its leading multipliers come with a bound
    below 1 on the others."""
    eom, integ, ch, plain = above
    r, shooter, _ = shoot(eom, integ, ch, matrix_free=True)
    assert r.decided == "shooting"
    orbit = next(o for o in shooter.orbits if o.stable)
    assert orbit.shooting is not None and orbit.evaluation.monodromy is None
    assert closing_error(eom, orbit) < acc.NEWTON_TOL
    assert orbit.evaluation.leading.discarded < orbit.evaluation.leading.bound < 1.0


def test_matrix_free_decision_is_the_dense_one():
    """12 nodes (48 states: the monodromy used through its action only), both paths forced, the same rk8 map: the same accepted orbit to 1e-8 of its extent, the same
    multipliers above the bound, and at every check from the first possible one to the
    acceptance the same answer of the linearisation test."""
    eom, integ, ch = heavy(12, 2.0)
    rd, dense, rec_d = shoot(eom, integ, ch, matrix_free=False)
    rm, mf, rec_m = shoot(eom, integ, ch, matrix_free=True, scheme="rk8")
    assert rd.decided == rm.decided == "shooting"
    assert rd.t_end == rm.t_end and rd.period == rm.period
    od = next(o for o in dense.orbits if o.stable)
    om = next(o for o in mf.orbits if o.stable)
    assert om.shooting is not None and od.shooting is None
    assert np.abs((om.u - od.u) / od.scale).max() < 1e-8
    lead = om.evaluation.leading
    mu, nu = od.evaluation.multipliers, lead.multipliers
    kept, found = mu[np.abs(mu) > lead.bound], nu[np.abs(nu) > lead.bound]
    assert found.size == kept.size and lead.discarded < lead.bound
    np.testing.assert_allclose(np.sort_complex(found), np.sort_complex(kept), atol=1e-8)
    assert abs(om.rho - od.rho) < 1e-8
    k_end = rec_m.states.shape[0] - 1
    decisions = [(acc.in_linear_neighbourhood(rec_m.states, k, od), acc.in_linear_neighbourhood(rec_m.states, k, om))
                 for k in range(acc.LINEAR_PERIODS * od.period, k_end + 1)]
    assert [d for d, _ in decisions] == [m for _, m in decisions]
    assert decisions[-1] == (True, True) and not all(d for d, _ in decisions)


def _truncated(mu, residual=1e-12, discarded=0.3, bound=0.5, products=50, complete=False):
    mu = np.asarray(mu, dtype=complex)
    lead = Leading(mu, np.full(mu.size, residual), np.zeros((4, mu.size)), np.zeros((4, 1)), np.zeros((1, 1)),
                   discarded, bound, products, complete)
    return acc.Orbit(1, np.zeros(4), SimpleNamespace(leading=lead, monodromy=None), np.ones(4), 0,
                     shooting=SimpleNamespace())


def test_truncated_spectrum_is_stable_only_with_a_bound_below_one():
    assert _truncated([0.9, 0.6j, -0.6j]).stable
    assert _truncated([0.9]).rho == pytest.approx(0.9) and _truncated([]).rho == pytest.approx(0.3)
    assert not _truncated([1.01, 0.6]).stable  # a leading multiplier outside
    assert not _truncated([0.99999999999], residual=1e-10).stable  # inside only within its residual
    assert not _truncated([0.9], discarded=0.999, bound=1.0).stable  # no bound below 1 on the rest
    assert not _truncated([0.9], products=200).stable  # the search stopped at its cap, not converged


@pytest.mark.slow(reason="a 50-node heavy span integrated alone to its steady state: minutes")
def test_fifty_nodes_agree_with_integration_alone():
    eom, integ, ch = heavy(50, 2.0)
    plain = steady_response(eom, integ, ch, CRITERION)
    assert acc.uses_matrix_free(acc.cable_system(eom), None)  # the default for this cable
    r, shooter, _ = shoot(eom, integ, ch, matrix_free=True)
    assert plain.steady and r.decided == "shooting" and r.period == plain.period
    np.testing.assert_allclose(r.amplitude, plain.amplitude, rtol=CRITERION.tol)
    orbit = next(o for o in shooter.orbits if o.stable)
    assert closing_error(eom, orbit) < acc.NEWTON_TOL
