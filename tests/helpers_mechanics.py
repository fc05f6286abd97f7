"""An independent reference for the cable's mechanics in any number of components per node.

Written from docs/theory.md alone, with numpy and scipy: the resisting force of a configuration
(eq. 2 with the tension-only law), the inextensible and elastic closure problems solved by
scipy's root finder on the closure error, the elastic displacements ``u = dOmega_e/dP`` by a
complex step, and derivatives by central differences. Nothing here calls cablesim's mechanics.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import root


def nodes(y, chord, dim):
    """Coordinates of A, the interior nodes and B, shape (n + 2, dim)."""
    pts = np.zeros((len(y) // dim + 2, dim), dtype=np.result_type(y, float))
    pts[1:-1] = np.reshape(y, (-1, dim))
    pts[-1] = chord
    return pts


def resisting_force(y, S, EA, chord, dim, taut=None):
    """``P_r = T_r e_r - T_(r+1) e_(r+1)``, ``T = EA (l - S) / S`` for the taut segments."""
    d = np.diff(nodes(y, chord, dim), axis=0)
    l = np.sqrt((d * d).sum(axis=1))
    T = EA * (l - S) / S
    if taut is not None:
        T = T * taut
    F = (T / l)[:, None] * d
    return (F[:-1] - F[1:]).ravel()


def jacobian(fun, x, h):
    """Central differences of ``fun`` at ``x`` with step ``h`` (a scalar or per component)."""
    x = np.asarray(x, float)
    h = np.broadcast_to(h, x.shape)
    cols = []
    for j in range(x.size):
        e = np.zeros_like(x)
        e[j] = h[j]
        cols.append((fun(x + e) - fun(x - e)) / (2.0 * h[j]))
    return np.column_stack(cols)


def segment_forces(F1, P, dim):
    """``F_k = F_1 - sum_{j<k} P_j`` (n + 1, dim), complex-safe."""
    Pn = np.reshape(P, (-1, dim))
    Fk = np.empty((Pn.shape[0] + 1, dim), dtype=np.result_type(F1, P))
    Fk[0] = F1
    Fk[1:] = F1 - np.cumsum(Pn, axis=0)
    return Fk


def closure_error(F1, P, S, chord, dim, EA=np.inf):
    """``sum_k l_k e_k - chord`` with ``l_k = S_k (1 + T_k / EA)`` (complex-safe: no abs)."""
    Fk = segment_forces(F1, P, dim)
    T = np.sqrt((Fk * Fk).sum(axis=1))
    lk = S * (1.0 + T / EA)
    return (lk[:, None] * Fk / T[:, None]).sum(axis=0) - chord


def solve_closure(P, S, chord, dim, EA=np.inf, F_start=None):
    """The segment-1 force of the closed polygon, by scipy's hybrid root finder (then Newton with
    complex-step Jacobians to round-off)."""
    F = np.asarray(F_start if F_start is not None else np.asarray(chord, float) * np.abs(P).sum() / np.linalg.norm(chord), float)
    sol = root(lambda f: closure_error(f, P, S, chord, dim, EA).real, F, method="hybr", tol=1e-14)
    F = sol.x
    for _ in range(3):  # Newton with a complex-step Jacobian: quadratic, to round-off
        h = 1e-30 * max(1.0, np.abs(F).max())
        J = np.column_stack([closure_error(F + 1j * h * np.eye(dim)[j], P, S, chord, dim, EA).imag / h
                             for j in range(dim)])
        F = F - np.linalg.solve(J, closure_error(F, P, S, chord, dim, EA).real)
    return F


def inextensible_state(P, S, chord, dim, F_start=None):
    """``(x(P), T(P), F_1)`` of the inextensible cable."""
    F1 = solve_closure(P, S, chord, dim, F_start=F_start)
    Fk = segment_forces(F1, P, dim)
    T = np.sqrt((Fk * Fk).sum(axis=1))
    x = np.cumsum(S[:, None] * Fk / T[:, None], axis=0)[:-1].ravel()
    return x, T, F1


def elastic_energy(P, S, EA, chord, dim, F1):
    """``Omega_e = sum T_k^2 S_k / (2 EA)`` of the inextensible solution, complex-safe in P
    (one Newton step in complex arithmetic from the real solution ``F1``)."""
    h = 1e-30 * max(1.0, np.abs(F1).max())
    J = np.column_stack([closure_error(F1 + 1j * h * np.eye(dim)[j], P.real, S, chord, dim).imag / h
                         for j in range(dim)])
    F = F1 - np.linalg.solve(J, closure_error(F1, P, S, chord, dim))  # exact to first order in Im P
    Fk = segment_forces(F, P, dim)
    T2 = (Fk * Fk).sum(axis=1)
    return (T2 * S).sum() / (2.0 * EA)


def elastic_displacement(P, S, EA, chord, dim, F1):
    """``u = dOmega_e/dP`` (eq. 7) by complex steps."""
    h = 1e-30 * max(1.0, np.abs(P).max())
    return np.array([elastic_energy(P + 1j * h * np.eye(P.size)[j], S, EA, chord, dim, F1).imag / h
                     for j in range(P.size)])


def exact_equilibrium(P, S, EA, chord, dim, y_start):
    """The deformed configuration with ``P(y) = P``, by scipy's root finder from ``y_start``."""
    sol = root(lambda y: resisting_force(y, S, EA, chord, dim) - P, y_start, method="hybr", tol=1e-14)
    assert sol.success, sol.message
    return sol.x


def rotation_about_vertical(a):
    """Rotation by ``a`` about the vertical (v) axis of the (x, v, w) frame."""
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


class SecondOrder:
    """``M y'' + a0 M y' + a1 (K0 y' + K0s s') + P(y, s) = F0 + FL sin(w t)`` with supports
    ``A + uA sin(w t + phA)``, ``B + uB sin(w t + phB)`` (docs/theory.md, section 8): the state
    ``(y, y')``, own assembly, ``K0`` and ``K0s = dP/ds`` at the equilibrium by central
    differences, for scipy's ``solve_ivp``."""

    def __init__(self, S, EA, chord, dim, mass, F0, FL, omega, y0, a0, a1, uA, uB, phA=0.0, phB=0.0):
        self.S, self.EA, self.chord, self.dim = np.asarray(S, float), float(EA), np.asarray(chord, float), dim
        self.mass, self.F0, self.FL, self.w = np.asarray(mass, float), np.asarray(F0, float), np.asarray(FL, float), omega
        self.y0, self.a0, self.a1 = np.asarray(y0, float), a0, a1
        self.uA, self.uB, self.phA, self.phB = np.asarray(uA, float), np.asarray(uB, float), phA, phB
        h = 1e-6 * np.linalg.norm(self.chord)
        self.K0 = jacobian(lambda y: self.force(y, np.zeros(dim), self.chord), self.y0, h)
        self.K0A = jacobian(lambda a: self.force(self.y0, a, self.chord), np.zeros(dim), h)
        self.K0B = jacobian(lambda b: self.force(self.y0, np.zeros(dim), b), self.chord, h)

    def force(self, y, A, B):
        d = np.diff(np.vstack([A, np.reshape(y, (-1, self.dim)), B]), axis=0)
        l = np.sqrt((d * d).sum(axis=1))
        F = (self.EA * (l - self.S) / self.S / l)[:, None] * d
        return (F[:-1] - F[1:]).ravel()

    def supports(self, t):
        w = self.w
        A = self.uA * np.sin(w * t + self.phA)
        B = self.chord + self.uB * np.sin(w * t + self.phB)
        vA = self.uA * w * np.cos(w * t + self.phA)
        vB = self.uB * w * np.cos(w * t + self.phB)
        return A, B, vA, vB

    def rhs(self, t, q):
        nd = self.y0.size
        y, v = q[:nd], q[nd:]
        A, B, vA, vB = self.supports(t)
        damping = self.a0 * self.mass * v + self.a1 * (self.K0 @ v + self.K0A @ vA + self.K0B @ vB)
        acc = (self.F0 + self.FL * np.sin(self.w * t) - damping - self.force(y, A, B)) / self.mass
        return np.concatenate([v, acc])

    def tensions(self, t, y):
        A, B, _, _ = self.supports(t)
        d = np.diff(np.vstack([A, np.reshape(y, (-1, self.dim)), B]), axis=0)
        return self.EA * (np.sqrt((d * d).sum(axis=1)) - self.S) / self.S


def moving_support_reference(eom, t_out, z0=None, rtol=1e-11):
    """``(z, T)`` at ``t_out`` of :class:`SecondOrder` built from an ``EquationsOfMotion``'s numbers
    (cable, loads, damping, supports' motion), started at rest from the displacement ``z0``
    (default none), by scipy's DOP853: the displacements from the equilibrium and the segment
    tensions, for comparison with cablesim's history of the same case."""
    from scipy.integrate import solve_ivp

    c = eom.cable
    ref = SecondOrder(c.S, c.EA, np.asarray(c.support_B, dtype=float), c.dim, eom.mass, eom.F0, eom.FL, eom.omega,
                      eom.y0, eom.a0, eom.a1, eom.uA, eom.uB, eom.phA, eom.phB)
    nd = eom.n_dof
    z0 = np.zeros(nd) if z0 is None else np.asarray(z0, dtype=float)
    sol = solve_ivp(ref.rhs, (0.0, float(t_out[-1])), np.concatenate([eom.y0 + z0, np.zeros(nd)]), method="DOP853",
                    rtol=rtol, atol=1e-13 * c.chord_length, t_eval=t_out)
    assert sol.success, sol.message
    y = sol.y[:nd].T
    return y - eom.y0, np.array([ref.tensions(t, yi) for t, yi in zip(t_out, y)])


def planned_history_reference(case_path, duration):
    """A case's history plan over ``duration`` (s), as ``cablesim history`` makes it (the case's
    start included), and :func:`moving_support_reference`'s displacements at its saved instants
    from the same start: ``(plan, z_ref)``."""
    from cablesim.analyses.dynamic import plan_history
    from cablesim.case import load_case

    plan = plan_history(load_case(case_path)[0], duration=duration)
    t = np.arange(0, int(round(duration / plan.output_step)) + 1) * plan.output_step
    z0 = None if plan.s0 is None else plan.s0[: plan.eom.n_dof]
    return plan, moving_support_reference(plan.eom, t, z0)[0]


def controlled_history_error(plan, z_ref, name, rtol):
    """The largest ``|z - z_ref|`` over the peak of ``|z_ref|`` of the plan's history by the
    implicit scheme ``name`` at ``rtol``, its atol a millionth of rtol times the chord (the
    default's ratio: the step is rtol's to set)."""
    from cablesim.dynamics.integrators.settings import make
    from cablesim.dynamics.simulate import simulate

    eom = plan.eom
    integ = make(name, eom, plan.omega_interest, {"rtol": rtol, "atol": 1e-6 * rtol * eom.cable.chord_length})
    hist = simulate(eom, integ, plan.duration, plan.output_step, s0=plan.s0, split=False)
    assert hist.completed and hist.z.shape == z_ref.shape
    return np.abs(hist.z - z_ref).max() / np.abs(z_ref).max()
