"""Matrix-free shooting of heavy cables, checked against the dense shooting and finite differences.

References (none from the matrix-free code under test):

- the vector field and its full Jacobian of :mod:`cablesim.orbits.cablefield` (the mechanical
  form must give the same rate bit for bit and the same stiffness products);
- the dense shooting (:class:`~cablesim.orbits.shooting.Shooting`): the same explicit scheme, so
  the residual is the same to the bit and ``J_u v`` the same to round-off; its Newton solutions
  and its eigenvalues of the whole monodromy;
- central finite differences of the Radau IIA flow map itself (its directions must be the exact
  derivative of that map), and the rk8 orbit (the Radau orbit converges to it as the step falls).
"""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.orbits import Shooting, cable_system, linear_response_state, solve_orbit
from cablesim.orbits.branches import cable_scales
from cablesim.orbits.directional import mechanical_rate
from cablesim.orbits.floquet import DISCARDED_TOL, leading_multipliers
from cablesim.orbits.kernels import copy_work
from cablesim.orbits.matrixfree import MatrixFreeShooting, orbit_leading, solve_orbit_mf

HEAVY = """\
cable: {{L: 300.0, H: 10.0, length: 300.7, nodes: {n}, EA: 3.3e7, mass_per_length: 1.628}}
loads: {{gravity: 9.81, point: [{{node: {k}, FL: [0.0, {load}]}}]}}
analysis: exact
damping: {{ratio: 0.005, modes: [1, 2]}}
"""


def heavy(n: int, omega: float, load: float = 200.0):
    """The heavy span of configs/heavy-span.yaml with ``n`` interior nodes (no marker ball), the
    harmonic load at a fifth of the span."""
    case = parse_case(HEAVY.format(n=n, k=max(1, n // 5), load=load))
    return build_equations(case, run_static(case), omega=omega)


@pytest.fixture(scope="module")
def small():
    """A 5-node heavy span at 1.5 rad/s: its orbit by the dense shooting."""
    w = 1.5
    eom = heavy(5, w)
    sysm = cable_system(eom)
    scale, _ = cable_scales(eom, "omega", 1.0, 3.0)
    sol = solve_orbit(Shooting(sysm), linear_response_state(eom, w), w, scale=scale)
    assert sol.converged
    return eom, sysm, scale, sol


def test_mechanical_form_is_the_field(small):
    """Rate bit for bit, stiffness product and band equal to the field's Jacobian block."""
    eom, sysm, _, sol = small
    mech = sysm.mechanical
    n = sysm.dim
    nd = n // 2
    rng = np.random.default_rng(1)
    x = sol.u + 1e-3 * rng.standard_normal(n) * np.abs(sol.u).max()
    dx, J, dp = np.empty(n), np.zeros((n, n)), np.zeros(n)
    assert sysm.field(0.7, sysm.omega, x, sysm.model, sysm.prm, copy_work(sysm.work), dx, J, dp, -1) == 0
    geo, bal, rate = np.empty(mech.geo_shape), np.empty(nd), np.empty(n)
    assert mech.balance(0.7, x, mech.model, sysm.prm, copy_work(sysm.work), geo, bal) == 0
    mechanical_rate(x, bal, mech.model, rate)
    assert np.array_equal(rate, dx)
    K = -mech.model.mass[:, None] * J[nd:, :nd]  # the field's -M^-1 K
    w = rng.standard_normal(n)
    out = np.zeros(n)
    mech.stiffness_times(geo, mech.model, w, out, nd)
    assert np.abs(out[nd:] - K @ w[:nd]).max() <= 1e-12 * np.abs(K).max() * np.abs(w).max()
    Kb = np.empty((mech.stiffness_rows, nd))
    mech.stiffness_band(geo, mech.model, Kb)
    hb = (mech.stiffness_rows - 1) // 2
    dense = np.zeros((nd, nd))
    for j in range(nd):
        for i in range(max(0, j - hb), min(nd, j + hb + 1)):
            dense[i, j] = Kb[hb + i - j, j]
    assert np.abs(dense - K).max() <= 1e-12 * np.abs(K).max()


def test_explicit_directions_are_the_dense_jacobian(small):
    """rk8: the same discrete map (residual bit for bit), ``J_u v`` for one vector and for a
    block equal to the dense ``J_u`` times it, ``J_lam`` equal."""
    eom, sysm, scale, sol = small
    mf = MatrixFreeShooting(sysm, scheme="rk8")
    dense = Shooting(sysm).evaluate(sol.u, 1.5)
    ev = mf.evaluate(sol.u, 1.5)
    assert np.array_equal(ev.r, dense.r)
    rng = np.random.default_rng(2)
    for q in (1, 3):  # one column: the action once overwrote its input (J v came out zero)
        X = rng.standard_normal((sysm.dim, q))
        X0 = X.copy()
        JX = mf.jacobian_apply(ev, X)
        assert np.array_equal(X, X0)
        ref = dense.J_u @ X
        assert np.abs(JX - ref).max() <= 1e-12 * np.abs(ref).max()
    assert np.abs(ev.J_lam - dense.J_lam).max() <= 1e-12 * np.abs(dense.J_lam).max()


@pytest.mark.slow  # the explicit directions' test covers the same contract in `make test`
def test_radau_directions_are_the_derivative_of_its_map(small):
    """Radau IIA: ``J_u v`` and ``J_lam`` against central differences of its own flow map."""
    eom, sysm, scale, sol = small
    mf = MatrixFreeShooting(sysm, scheme="radau")
    w = 1.5
    ev = mf.evaluate(sol.u, w)
    rng = np.random.default_rng(3)
    v = rng.standard_normal(sysm.dim) * scale
    h = 1e-6  # the truncation error of the differences goes as h^2: 7e-6 at 1e-4, 7e-10 here
    fd = (mf.evaluate(sol.u + h * v, w, jac=False).r - mf.evaluate(sol.u - h * v, w, jac=False).r) / (2 * h)
    Jv = mf.jacobian_apply(ev, v[:, None])[:, 0]
    assert np.abs(Jv - fd).max() <= 1e-8 * np.abs(fd).max()
    dw = 1e-6
    fdw = (mf.evaluate(sol.u, w + dw, jac=False).r - mf.evaluate(sol.u, w - dw, jac=False).r) / (2 * dw)
    assert np.abs(ev.J_lam - fdw).max() <= 1e-6 * np.abs(fdw).max()


@pytest.mark.parametrize("scheme", ["radau", "rk8"])
def test_orbit_extremes_are_those_of_its_samples(small, scheme):
    """The extremes of an orbit's components bracket its recorded steps and exceed them by no more
    than the interpolant's overshoot between steps (1 % of the range at 64 steps per period), and
    are the same at every evaluation (the Radau kernel only updates the arrays it is given: they
    must start from the start state, not from whatever memory held)."""
    eom, sysm, scale, sol = small
    mf = MatrixFreeShooting(sysm, scheme=scheme)
    for _ in range(3):
        np.empty(sysm.dim).fill(1e30)  # freed memory of the size of the extremes, full of garbage
        seg = mf.segment(0, sol.u, 1.5, record=True)
        x = seg["rec"][:, : sysm.dim]
        hi, lo = x.max(axis=0), x.min(axis=0)
        span = np.maximum(hi - lo, 1e-300)
        assert np.all(seg["xmax"] >= hi) and np.all(seg["xmin"] <= lo)
        assert np.all(seg["xmax"] - hi <= 1e-2 * span) and np.all(lo - seg["xmin"] <= 1e-2 * span)


def test_radau_orbit_converges_to_the_explicit_one(small):
    """The Radau orbit approaches the rk8 orbit as the step falls, at about the scheme's order."""
    eom, sysm, scale, sol = small
    errors = []
    for spp in (64, 128):
        mf = MatrixFreeShooting(sysm, scheme="radau", steps_per_period=spp, step_rate=1e9)
        s = solve_orbit_mf(mf, sol.u, 1.5, scale=scale)
        assert s.converged
        errors.append(np.abs((s.u - sol.u) / scale).max())
    assert errors[0] < 1e-6
    assert errors[0] / errors[1] > 2**4  # order 5 (measured ratio in the test's first run below)


@pytest.mark.parametrize("nodes, omega", [(2, 1.2), (5, 1.5), (12, 1.5), (5, 2.3)])
def test_newton_krylov_orbit_agrees_with_dense(nodes, omega):
    """Newton-GMRES on the rk8 map converges to the dense Newton solution to 1e-8 of the scale,
    near and away from resonance (2.3 rad/s is next to the first mode, 2.36)."""
    eom = heavy(nodes, omega)
    sysm = cable_system(eom)
    scale, _ = cable_scales(eom, "omega", 1.0, 3.0)
    u0 = linear_response_state(eom, omega)
    dense = solve_orbit(Shooting(sysm), u0, omega, scale=scale)
    if not dense.converged:  # next to resonance the linear guess is far: start both nearer
        from cablesim.orbits import integrate_to_steady
        u0 = integrate_to_steady(Shooting(sysm), u0, omega, periods=100)
        dense = solve_orbit(Shooting(sysm), u0, omega, scale=scale)
    assert dense.converged
    mf = MatrixFreeShooting(sysm, scheme="rk8")
    sol = solve_orbit_mf(mf, u0, omega, scale=scale)
    assert sol.converged
    assert np.abs((sol.u - dense.u) / scale).max() < 1e-8
    assert mf.krylov_iterations > 0 and mf.newton_steps >= sol.iterations


def test_leading_multipliers_are_the_dense_ones_above_the_bound():
    """12 nodes (48 states, above the size where the whole monodromy is formed): the kept
    multipliers are the dense eigenvalues above the bound, to 1e-10, none missing; the
    discarded modulus is the largest dense one below it; the residuals are small."""
    w = 1.5
    eom = heavy(12, w)
    sysm = cable_system(eom)
    scale, _ = cable_scales(eom, "omega", 1.0, 3.0)
    sh = Shooting(sysm)
    sol = solve_orbit(sh, linear_response_state(eom, w), w, scale=scale)
    assert sol.converged
    mu = sol.evaluation.multipliers
    mf = MatrixFreeShooting(sysm, scheme="rk8")
    ev = mf.evaluate(sol.u, w)
    for bound in (0.5, 0.9):
        ev.leading = None
        lead = orbit_leading(mf, ev, scale, bound=bound)
        above = mu[np.abs(mu) > bound]
        assert not lead.complete and lead.multipliers.size == above.size
        assert max(np.abs(above - m).min() for m in lead.multipliers) < 1e-10
        assert max(np.abs(lead.multipliers - m).min() for m in above) < 1e-10
        below = np.abs(mu[np.abs(mu) <= bound]).max()
        assert lead.discarded < bound and abs(lead.discarded - below) <= DISCARDED_TOL
        assert lead.residual < 1e-9
        assert lead.products < sysm.dim


def test_leading_multipliers_of_a_known_matrix():
    """A matrix with known eigenvalues (a random similarity of a block-diagonal form): the
    Krylov search finds exactly those above the bound."""
    rng = np.random.default_rng(5)
    n = 200
    mods = np.concatenate([[1.3, 0.95, -0.9, 0.7], 0.3 * rng.random(n - 8)])
    ang = np.array([0.4, 2.0])
    D = np.zeros((n, n))
    D[:4, :4] = np.diag(mods[:4])
    for k, (r, a) in enumerate(zip((0.8, 0.6), ang)):
        i = 4 + 2 * k
        D[i:i + 2, i:i + 2] = r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    D[8:, 8:] = np.diag(mods[4:n - 4])
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)  # not normal
    M = S @ D @ np.linalg.inv(S)
    lead = leading_multipliers(lambda X: M @ X, n, bound=0.5)
    expect = np.concatenate([mods[:4], 0.8 * np.exp([0.4j, -0.4j]), 0.6 * np.exp([2j, -2j])])
    assert not lead.complete and lead.products < n // 2
    assert lead.multipliers.size == expect.size
    assert max(np.abs(expect - m).min() for m in lead.multipliers) < 1e-9
    assert lead.discarded == pytest.approx(np.abs(mods[4:n - 4]).max(), abs=DISCARDED_TOL)


def test_leading_multipliers_with_a_complex_pair_below_the_bound():
    """The largest discarded multipliers a complex pair: the kept subspace's cut must not fall
    between the two (it did, and the ordered Schur form failed on the ambiguous pair)."""
    rng = np.random.default_rng(6)
    n = 120
    D = np.diag(np.concatenate([[1.2, -0.8, 0.0, 0.0], 0.2 * rng.random(n - 4)]))
    D[2:4, 2:4] = 0.45 * np.array([[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]])
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)
    M = S @ D @ np.linalg.inv(S)
    lead = leading_multipliers(lambda X: M @ X, n, bound=0.5)
    assert lead.multipliers.size == 2 and not lead.complete
    assert max(np.abs(np.array([1.2, -0.8]) - m).min() for m in lead.multipliers) < 1e-9
    assert lead.discarded == pytest.approx(0.45, abs=DISCARDED_TOL)
    assert np.abs(M @ lead.basis - lead.basis @ lead.schur).max() < DISCARDED_TOL


def _projector(V):
    Q, _ = np.linalg.qr(V)
    return Q @ Q.T


def test_kept_subspace_from_the_eigenvectors_is_the_ordered_schur_forms(monkeypatch):
    """The kept subspace taken from the Ritz vectors (a QR of a few columns) is the invariant
    subspace the ordered real Schur form of the projected matrix gives, to round-off, on a
    spectrum with real and complex leading multipliers, without forming that Schur form; the
    Schur form decides where the eigenvectors are near dependent (a defective multiplier)."""
    import scipy.linalg as sla

    import cablesim.orbits.floquet as fq

    calls = []
    schur = sla.schur

    def counted(*args, **kwargs):
        calls.append(args[0].shape)
        return schur(*args, **kwargs)

    monkeypatch.setattr(fq.sla, "schur", counted)
    rng = np.random.default_rng(11)
    m = 40
    D = np.diag(np.concatenate([[1.05, -0.8, 0.0, 0.0, 0.6], 0.3 * rng.random(m - 5)]))
    D[2:4, 2:4] = 0.9 * np.array([[np.cos(0.7), -np.sin(0.7)], [np.sin(0.7), np.cos(0.7)]])
    S = np.eye(m) + 0.3 * rng.standard_normal((m, m)) / np.sqrt(m)
    H = S @ D @ np.linalg.inv(S)
    Z, T = fq._leading_schur(H, 0.5)
    assert calls == []  # from the eigenvectors
    Ts, Zs, sdim = schur(H, output="real", sort=lambda x, y: np.hypot(x, y) > 0.5)
    assert sdim == 5 and Z.shape == (m, 5)
    assert np.abs(Z.T @ Z - np.eye(5)).max() < 1e-13
    assert np.abs(H @ Z - Z @ T).max() < 1e-12
    assert np.abs(_projector(Z) - _projector(Zs[:, :5])).max() < 1e-11
    assert np.sort_complex(np.linalg.eigvals(T)) == pytest.approx(np.sort_complex(np.linalg.eigvals(Ts[:5, :5])), abs=1e-12)
    # a Jordan block of 0.9 kept: its two eigenvectors agree to 1e-7, no basis of the subspace
    J = np.diag(np.concatenate([[0.9, 0.9], 0.3 * rng.random(m - 2)]))
    J[0, 1] = 1.0
    HJ = S @ J @ np.linalg.inv(S)
    ZJ, TJ = fq._leading_schur(HJ, 0.5)
    assert calls == [(m, m)]  # the ordered Schur form decided
    assert ZJ.shape == (m, 2) and np.abs(HJ @ ZJ - ZJ @ TJ).max() < 1e-12
    lead = fq.leading_multipliers(lambda X: HJ @ X, m, bound=0.5)
    assert np.abs(HJ @ lead.basis - lead.basis @ lead.schur).max() < DISCARDED_TOL


def test_leading_subspace_when_the_ordered_schur_form_fails(monkeypatch):
    """Where LAPACK's reordering fails (seen on a 20-node branch), the kept subspace comes from
    the eigenvectors and is still invariant."""
    import cablesim.orbits.floquet as fq

    def refuse(*args, **kwargs):
        raise np.linalg.LinAlgError("Leading eigenvalues do not satisfy sort condition.")

    rng = np.random.default_rng(7)
    n = 60
    D = np.diag(np.concatenate([[1.1, 0.9, -0.7], 0.2 * rng.random(n - 3)]))
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)
    M = S @ D @ np.linalg.inv(S)
    monkeypatch.setattr(fq.sla, "schur", refuse)
    monkeypatch.setattr(fq, "SPAN_TOL", -1.0)  # the eigenvectors' span refused: the Schur form's fallback
    lead = fq.leading_multipliers(lambda X: M @ X, n, bound=0.5)
    assert lead.multipliers.size == 3
    # the subspace holds one Ritz vector below the bound too, converged to DISCARDED_TOL only
    assert np.abs(M @ lead.basis - lead.basis @ lead.schur).max() < DISCARDED_TOL
