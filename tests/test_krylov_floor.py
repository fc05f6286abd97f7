"""The corrector's Krylov solves stop at an absolute residual tied to the Newton tolerance.

A relative residual alone solves the last, convergence-checking Newton system of every point (a
right-hand side of 1e-12) to 1e-18, some ten GMRES iterations, each a monodromy action, for a
step whose size need only be told from the tolerance. References: the residual and the error
recomputed here from the formed matrix and ``numpy.linalg.solve``; the dense shooting's branch
(the same rk8 discrete flow, its Newton systems solved by LU).
"""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.orbits import Shooting, cable_system, linear_response_state
from cablesim.orbits.branches import cable_scales
from cablesim.orbits.continuation import Settings, continuation
from cablesim.orbits.krylov import gmres
from cablesim.orbits.matrixfree import Bordered, MatrixFreeShooting
from cablesim.orbits.mfproblem import MatrixFreeOrbitProblem
from cablesim.orbits.problems import OrbitProblem

from test_orbits_matrixfree import heavy


def system(n: int = 60, seed: int = 3):
    """A non-symmetric ``I - B`` with the spectrum of ``B`` within 0.6 of zero."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    T = np.triu(0.2 * rng.standard_normal((n, n)), 1) + np.diag(0.6 * rng.uniform(-1.0, 1.0, n))
    return np.eye(n) - Q @ T @ Q.T, rng.standard_normal(n)


@pytest.mark.parametrize("size", [1e-3, 1e-9])
def test_gmres_stops_at_the_absolute_residual(size):
    """``atol`` ends the iteration once the true residual (recomputed here) is below it, in fewer
    iterations than the relative tolerance alone, the error within the inverse's norm times it."""
    A, b = system()
    b *= size / np.linalg.norm(b)
    exact = np.linalg.solve(A, b)
    atol = 1e-12
    alone = gmres(lambda v: A @ v, b, tol=1e-8)
    floored = gmres(lambda v: A @ v, b, tol=1e-8, atol=atol)
    assert alone.converged and floored.converged
    assert np.linalg.norm(b - A @ alone.x) <= 1.01e-8 * size
    r = np.linalg.norm(b - A @ floored.x)
    assert r <= 1.01 * max(1e-8 * size, atol)
    assert np.linalg.norm(floored.x - exact) <= np.linalg.norm(np.linalg.inv(A), 2) * r * 1.01
    if 1e-8 * size < atol:
        assert floored.iterations < alone.iterations
    else:
        assert floored.iterations == alone.iterations


def test_gmres_with_a_right_hand_side_below_the_floor_takes_one_step():
    A, b = system()
    b *= 1e-14 / np.linalg.norm(b)
    sol = gmres(lambda v: A @ v, b, tol=1e-8, atol=1e-12)
    assert sol.converged and sol.iterations == 1
    assert np.linalg.norm(b - A @ sol.x) <= 1e-14


def test_the_corrector_checks_convergence_without_solving_to_round_off(monkeypatch):
    """A matrix-free branch of the 5-node heavy span (rk8): the solves that find the step below
    the Newton tolerance (the convergence checks) take at most 4 GMRES iterations (measured 1 to
    3; on the relative tolerance alone 5 to 12), and the points are the dense shooting's to 1e-9
    of the scale, parameters to 1e-10."""
    w = 1.5
    eom = heavy(5, w)
    sysm = cable_system(eom)
    scale, lam_scale = cable_scales(eom, "omega", 1.0, 3.0)
    u0 = linear_response_state(eom, w)
    settings = Settings(max_points=6)
    dense = continuation(OrbitProblem(Shooting(sysm, scheme="rk8"), scale, lam_scale), u0, w, settings)
    solves = []
    original = Bordered.solve

    def counted(self, normal, rhs, tol=None, atol=0.0):
        before = self.sh.krylov_iterations
        dv = original(self, normal, rhs, tol, atol)
        solves.append((self.sh.krylov_iterations - before, np.inf if dv is None else np.abs(dv).max()))
        return dv

    monkeypatch.setattr(Bordered, "solve", counted)
    problem = MatrixFreeOrbitProblem(MatrixFreeShooting(sysm, scheme="rk8"), scale, lam_scale)
    free = continuation(problem, u0, w, settings)
    assert len(free.points) == len(dense.points) == 6
    checks = [k for k, step in solves if step <= settings.newton_tol]
    assert len(checks) >= 6
    assert max(checks) <= 4
    for p, q in zip(dense.points, free.points):
        assert abs(p.lam - q.lam) <= 1e-10 * abs(p.lam)
        assert np.abs((p.u - q.u) / scale).max() <= 1e-9
