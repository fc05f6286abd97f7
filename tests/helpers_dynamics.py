"""The independent reference for the time-history tests (docs/theory.md, sections 1 and 2).

Nothing here comes from cablesim's dynamics: the resisting force P, the tangent stiffness K and
the energy are written from the segment geometry, and scipy integrates the second-order
equations of motion ``M y'' + C y' + P(y) = F(t)``:

- :func:`reference_history`: scipy's DOP853 (Hairer's Fortran code through
  ``scipy.integrate.ode``: the same method as ``solve_ivp(method="DOP853")`` at a quarter of the
  cost; rtol 1e-11) from the static equilibrium at rest, or from a given state;
- :func:`stiff_reference`: scipy's Radau with the own tangent as Jacobian, for stiff cables.

Also the shared settings of the forced runs (paper example near its fundamental) and
:func:`forced_run`, a memo so that the modules share one ``simulate()`` per integrator.
Imported by the test modules as ``helpers_dynamics`` (pytest puts ``tests/`` on ``sys.path``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.integrate import ode, solve_ivp

from cablesim.dynamics.simulate import simulate

OMEGA = 2.45  # forcing near the fundamental (2.524 rad/s): several metres of response
DURATION = 200.0  # s, for the accuracy comparison
SHORT = 30.0  # s, for the convergence orders
OUT_STEP = 0.1  # s, a multiple of every fixed step used below (no interpolation error)
APPROX_DURATION = 60.0  # s, for the approximate analysis


# ----------------------------------------------------------------------------------------------
# The independent reference: second-order equations of motion, own geometry, scipy DOP853
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _own_force(y, S, EA, L, H):
    """P_r = T_r e_r - T_{r+1} e_{r+1}, T = EA (l - S) / S (docs/theory.md, section 1)."""
    nd = y.size
    n = nd // 2
    P = np.zeros(nd)
    for r in range(n + 1):
        xa = 0.0 if r == 0 else y[2 * r - 2]
        ya = 0.0 if r == 0 else y[2 * r - 1]
        xb = L if r == n else y[2 * r]
        yb = H if r == n else y[2 * r + 1]
        dx = xb - xa
        dy = yb - ya
        l = math.sqrt(dx * dx + dy * dy)
        T = EA * (l - S[r]) / S[r]
        if r < n:
            P[2 * r] += T * dx / l
            P[2 * r + 1] += T * dy / l
        if r > 0:
            P[2 * r - 2] -= T * dx / l
            P[2 * r - 1] -= T * dy / l
    return P


@njit(cache=True)
def _second_order_rhs(t, s, y0, S, EA, L, H, M, C, F0, FL, w):
    """d/dt (z, v) with M v' = F0 + FL sin(w t) - C v - P(y0 + z)."""
    nd = y0.size
    out = np.empty(2 * nd)
    P = _own_force(y0 + s[:nd], S, EA, L, H)
    sn = math.sin(w * t)
    for i in range(nd):
        out[i] = s[nd + i]
        cv = 0.0
        for j in range(nd):
            cv += C[i, j] * s[nd + j]
        out[nd + i] = (F0[i] + FL[i] * sn - cv - P[i]) / M[i]
    return out


@njit(cache=True)
def _own_stiffness(y, S, EA, L, H):
    """K = sum_r [(EA/S_r) e e^T + (T_r/l_r)(I - e e^T)] assembled (docs/theory.md, section 2)."""
    nd = y.size
    n = nd // 2
    K = np.zeros((nd, nd))
    for r in range(n + 1):
        xa = 0.0 if r == 0 else y[2 * r - 2]
        ya = 0.0 if r == 0 else y[2 * r - 1]
        xb = L if r == n else y[2 * r]
        yb = H if r == n else y[2 * r + 1]
        dx = xb - xa
        dy = yb - ya
        l = math.sqrt(dx * dx + dy * dy)
        e = np.array([dx / l, dy / l])
        T = EA * (l - S[r]) / S[r]
        k = (EA / S[r]) * np.outer(e, e) + (T / l) * (np.eye(2) - np.outer(e, e))
        i = r - 1
        j = r
        if i >= 0:
            K[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] += k
        if j < n:
            K[2 * j : 2 * j + 2, 2 * j : 2 * j + 2] += k
        if i >= 0 and j < n:
            K[2 * i : 2 * i + 2, 2 * j : 2 * j + 2] -= k
            K[2 * j : 2 * j + 2, 2 * i : 2 * i + 2] -= k
    return K


def own_force(cable, y):
    return _own_force(np.asarray(y, dtype=float), np.asarray(cable.S, dtype=float), cable.EA, cable.L, cable.H)


def own_energy(cable, F0, y0, z, v):
    """E = 1/2 v.M.v + sum_r EA/(2 S_r) (l_r - S_r)^2 - F0.y, per saved instant."""
    M = cable.mass_diagonal
    kinetic = 0.5 * np.sum(M * v * v, axis=1)
    y = y0 + z
    m, nd = y.shape
    pts = np.zeros((m, nd // 2 + 2, 2))
    pts[:, 1:-1] = y.reshape(m, -1, 2)
    pts[:, -1] = [cable.L, cable.H]
    d = np.diff(pts, axis=1)
    l = np.hypot(d[..., 0], d[..., 1])
    strain = np.sum(cable.EA / (2.0 * cable.S) * (l - cable.S) ** 2, axis=1)
    return kinetic + strain - y @ F0


def reference_history(eom, t_out, s0=None, rtol=1e-11):
    """z(t) at ``t_out`` (t_out[0] = 0) from scipy's DOP853 on the second-order form."""
    c = eom.cable
    nd = eom.n_dof
    args = (
        np.ascontiguousarray(eom.y0), np.asarray(c.S, dtype=float), float(c.EA), float(c.L), float(c.H),
        np.ascontiguousarray(eom.mass), np.ascontiguousarray(eom.C), np.ascontiguousarray(eom.F0),
        np.ascontiguousarray(eom.FL), float(eom.omega),
    )
    x0 = np.zeros(2 * nd) if s0 is None else np.asarray(s0[: 2 * nd], dtype=float)
    solver = ode(lambda t, s: _second_order_rhs(t, s, *args))
    solver.set_integrator("dop853", rtol=rtol, atol=1e-13 * c.chord_length, nsteps=10**8)
    solver.set_initial_value(x0, 0.0)
    out = np.empty((t_out.size, 2 * nd))
    out[0] = x0
    for k in range(1, t_out.size):
        out[k] = solver.integrate(t_out[k])
        assert solver.successful()
    return out[:, :nd], out[:, nd:]


def stiff_reference(eom, t_out, rtol=1e-7):
    """Like reference_history, for stiff cables: scipy Radau with the tangent as Jacobian."""
    c = eom.cable
    nd = eom.n_dof
    S = np.asarray(c.S, dtype=float)
    args = (
        np.ascontiguousarray(eom.y0), S, float(c.EA), float(c.L), float(c.H), np.ascontiguousarray(eom.mass),
        np.ascontiguousarray(eom.C), np.ascontiguousarray(eom.F0), np.ascontiguousarray(eom.FL), float(eom.omega),
    )

    def jac(t, s):
        J = np.zeros((2 * nd, 2 * nd))
        J[:nd, nd:] = np.eye(nd)
        J[nd:, :nd] = -_own_stiffness(eom.y0 + s[:nd], S, c.EA, c.L, c.H) / eom.mass[:, None]
        J[nd:, nd:] = -eom.C / eom.mass[:, None]
        return J

    sol = solve_ivp(
        lambda t, s: _second_order_rhs(t, s, *args), (0.0, t_out[-1]), np.zeros(2 * nd), method="Radau",
        rtol=rtol, atol=1e-10 * c.chord_length, t_eval=t_out, jac=jac,
    )
    assert sol.status == 0, sol.message
    return sol.y[:nd].T


def rel_error(z, zref):
    return float(np.max(np.abs(z - zref)) / np.max(np.abs(zref)))


def _all_finite(hist):
    arrays = [hist.t, hist.z, hist.v, hist.T, hist.residual]
    arrays += [a for a in (hist.zc, hist.ze) if a is not None]
    return all(np.all(np.isfinite(a)) for a in arrays)


# ----------------------------------------------------------------------------------------------
# Shared runs
# ----------------------------------------------------------------------------------------------
_runs: dict = {}


def forced_run(eom, integ, duration):
    """Module-level memo: one simulate() per (integrator, duration)."""
    key = (eom.analysis, repr(integ), duration)
    if key not in _runs:
        _runs[key] = simulate(eom, integ, duration, OUT_STEP)
    return _runs[key]
