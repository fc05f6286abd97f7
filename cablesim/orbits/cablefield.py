"""The cable's equations of motion as a first-order vector field on the physical state.

``M y'' + C y' + P(y) = F0 + gamma FL sin(theta)``, ``theta = omega t``, written for the state
``x = (z, v)`` with ``z = y - y0`` (displacement from the static equilibrium) and ``v = y'``::

    z' = v
    v' = M^-1 (F0 + gamma FL sin(theta) - C v - P(y0 + z))

with Jacobian ``[[0, I], [-M^-1 K, -M^-1 C]]``, ``K = dP/dy``. Its trace is ``-tr(M^-1 C)``,
constant, in both analyses.

- Exact analysis: ``P(y)`` and ``K(y)`` of the deformed configuration in displacement form
  (:func:`cablesim.mechanics.assembly.displaced_force_and_stiffness`): the segment stretch is
  computed from the equilibrium segment vector and its change, so the force follows a small
  ``z`` with full relative precision instead of the round-off of ``y0 + z`` (about 1e-14 of the
  coordinates). A slack segment stops the integration with ``SLACK``, unless the flow tracks
  the segments' modes (``work``'s ``track[0] = 1``, set by the kernel of
  :mod:`cablesim.orbits.slackflow`): the segments then count as their modes ``taut`` say (a
  slack one: no force, no stiffness), as in the time histories, and :func:`exact_gaps` gives
  the gaps the kernel checks the modes against.
- Approximate analysis: ``P`` is defined implicitly by ``y = x(P) + u(P)``; an inner damped
  Newton iteration ``P <- P + a N(P)^-1 (y - x(P) - u(P))`` (``N = D + f = dy/dP``; the step
  is ``K r`` by the factored stiffness of :mod:`cablesim.mechanics.flexibility`, O(n), no solve),
  warm-started from the previous call, converges to round-off (:func:`solve_loads`); from too
  far away (the first call of an integration starts at the equilibrium's ``F0``) it walks from
  the warm start's configuration to ``y`` in 16 steps. Then ``K = N^-1`` from the same factors.
  Each inner step solves the inextensible closure for ``x(P)`` to round-off
  (:func:`cablesim.mechanics.closure.polish`), so the flow map does not depend on the warm
  starts beyond round-off.

  Round-off of the inner solve: ``x(P)`` is a sum of ``S_k e_k`` in absolute coordinates, so the
  residual ``y - x(P) - u(P)`` is resolved only to a few ulps of the cable's length (measured up
  to 5 ulps of ``sum S``), and the loads only to ``|N^-1|`` (about ``EA / S_k``) times that:
  some ``EA`` machine epsilons (1e-6 N for ``EA = 1e9`` N), an absolute level independent of
  the loads. Relative to ``|P|`` it is 6e-13 on the paper's example but 1e-11 on
  ``configs/paper/fig6.yaml`` (the same ``EA``, a thirteenth of the loads): a stopping test on
  the correction relative to ``|P|`` alone cannot be met on light loads, and a line search that
  insists on a decreasing residual fails on the floor. The iteration therefore stops when the
  residual reaches its round-off level (:data:`FLOOR_ULPS` ulps of the length,
  :func:`residual_floor`) or the correction is small, whichever comes first, and takes one more
  full step (at quadratic convergence that leaves P at its round-off level wherever it
  stopped); a damped step that lands on the floor is accepted.

The vector fields follow the contract of :mod:`cablesim.orbits.kernels`: the model's constants
are a :class:`~cablesim.mechanics.model.CableModel` (with a dense damping matrix), ``prm`` holds
the continuation parameter ``gamma`` (:data:`GAMMA`), ``work`` the scratch space and warm starts.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..jit import njit
from ..mechanics import assembly as asm
from ..mechanics import closure as cl
from ..mechanics import flexibility as fx
from ..mechanics import segments as sg
from ..mechanics.banded import band_rows
from ..mechanics.model import ApproximateWorkspace, approximate_workspace
from ..mechanics.supports import add_support_damping
from ..mechanics.vectors import mvec, vadd, vnorm, vscale, vsub
from .kernels import INNER_SOLVE, IPAR_OMEGA, OK, SLACK

#: Round-off level of the approximate analysis' inner residual ``y - x(P) - u(P)``, in ulps of
#: the cable's length (measured up to 5 on ``configs/paper/fig6.yaml``, 1.5 on the paper's
#: example; :func:`residual_floor`). The final Newton step from there leaves P at its own
#: round-off level, so the margin costs no accuracy.
FLOOR_ULPS = 32.0
#: Index of ``gamma`` in ``prm``: the multiplier of FL and of the supports' motion.
GAMMA = 0
#: Index of the multiplier of the supports' motion alone (``continuation.parameter: support``).
SUPPORT = 1


class ApproximateWork(NamedTuple):
    """Scratch space and warm starts of :func:`approximate_field`."""

    P: np.ndarray  # loads of the last call (warm start), N
    F1: np.ndarray  # its inextensible segment-1 force, N
    y: np.ndarray
    r: np.ndarray
    d: np.ndarray
    Pt: np.ndarray
    Pw: np.ndarray
    yt: np.ndarray
    F1t: np.ndarray
    F1w: np.ndarray
    Kb: np.ndarray  # band scratch of the dense stiffness
    U: np.ndarray
    awk: ApproximateWorkspace


def exact_work(eom) -> tuple:
    """Scratch space of :func:`exact_field`: the resisting force ``P``, the support terms of
    the acceleration, the segment modes ``taut`` (1 taut, 0 slack; all taut) and ``track``
    (``track[0] = 1`` while a flow tracks the modes; 0: a slack segment stops the flow)."""
    return (np.zeros(eom.n_dof), np.zeros(eom.n_dof), np.ones(eom.cable.n_nodes + 1), np.zeros(1))


def approximate_work(eom) -> ApproximateWork:
    """Scratch space and warm starts of :func:`approximate_field` (``P`` starts at ``F0`` and
    the inextensible closure at the equilibrium's segment-1 force ``F1``)."""
    nd, n, dim = eom.n_dof, eom.cable.n_nodes, eom.cable.dim
    v = [np.zeros(nd) for _ in range(6)]
    return ApproximateWork(np.array(eom.F0, dtype=float), np.array(eom.F1, dtype=float), *v,
                           np.zeros(dim), np.zeros(dim), np.zeros((band_rows(dim), nd)), np.zeros((nd, dim)),
                           approximate_workspace(n, dim))


@njit
def _second_order(theta, x, model, prm, P, dx, J, dp, ipar, nd, extra):
    """Fill dx, the lower blocks of J (K already in ``J[nd:, :nd]``) and dp for ``gamma``'s part
    through FL (``extra``: the supports' terms of the force, added when supports move)."""
    sn = np.sin(theta)
    g = prm[GAMMA]
    m, C, F0, FL = model.mass, model.C, model.F0, model.FL
    for i in range(nd):
        dx[i] = x[nd + i]
        rm = 1.0 / m[i]
        acc = F0[i] + g * FL[i] * sn - P[i]
        if model.moving:
            acc += extra[i]
        for j in range(nd):
            cij = C[i, j]
            acc -= cij * x[nd + j]
            J[nd + i, nd + j] = -cij * rm
            J[nd + i, j] = -J[nd + i, j] * rm
            J[i, j] = 0.0
            J[i, nd + j] = 0.0
        J[i, nd + i] = 1.0
        dx[nd + i] = acc * rm
    if ipar == GAMMA:
        for i in range(nd):
            dp[i] = 0.0
            dp[nd + i] = FL[i] * sn / m[i]
    elif ipar >= 0:
        for i in range(2 * nd):
            dp[i] = 0.0


@njit
def _support_motion(theta, omega, model, scale):
    """The supports' displacements and velocities at phase ``theta``, their motion scaled by
    ``scale``: ``(zA, zB, vA, vB)``."""
    return (vscale(model.uA, scale * np.sin(theta + model.phA)), vscale(model.uB, scale * np.sin(theta + model.phB)),
            vscale(model.uA, scale * omega * np.cos(theta + model.phA)),
            vscale(model.uB, scale * omega * np.cos(theta + model.phB)))


@njit
def _support_derivatives(theta, omega, x, model, prm, dp, ipar, zA, zB):
    """The supports' share of the derivatives of the field with respect to the multipliers and
    to ``omega`` (added to ``dp``, after :func:`_second_order`): per unit multiplier the
    displacement ``u sin`` pulls the end node through its segment, ``k(y) u sin``, and the
    velocity ``u w cos`` pushes it through the damping, ``c u w cos``; at fixed phase only the
    velocity's factor ``w`` depends on ``omega``, ``c u cos``."""
    nd = model.mass.size
    dim = len(model.A)
    if ipar == IPAR_OMEGA:  # (dp for the other parameters was just set by _second_order)
        for i in range(2 * nd):
            dp[i] = 0.0
        dA, dB, wA, wB = _support_motion(theta, 1.0, model, prm[GAMMA] * prm[SUPPORT])
        rA, rB = mvec(model.cA, wA), mvec(model.cB, wB)
    elif ipar == GAMMA or ipar == SUPPORT:
        per = prm[SUPPORT] if ipar == GAMMA else prm[GAMMA]
        dA, dB, wA, wB = _support_motion(theta, omega, model, per)
        kA = asm.displaced_block(x, model.y0, 0, model.S, model.EA, model.A, model.B, zA, zB, 1.0)
        kB = asm.displaced_block(x, model.y0, model.S.size - 1, model.S, model.EA, model.A, model.B, zA, zB, 1.0)
        rA = vadd(mvec(kA, dA), mvec(model.cA, wA))
        rB = vadd(mvec(kB, dB), mvec(model.cB, wB))
    else:
        return
    for d in range(dim):
        dp[nd + d] += rA[d] / model.mass[d]
        dp[2 * nd - dim + d] += rB[d] / model.mass[nd - dim + d]


@njit(borrowed=True)  # called at every stage: no reference counting (cablesim.jit)
def exact_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    """Exact analysis (module docstring)."""
    nd = model.mass.size
    P, extra, taut, track = work
    if model.moving:  # extra: minus the supports' part of the damping force, a1 K0s s'
        zA, zB, vA, vB = _support_motion(theta, omega, model, prm[GAMMA] * prm[SUPPORT])
        extra[:] = 0.0
        add_support_damping(model, vA, vB, extra, 1.0)
    else:
        zA = zB = sg.zero_rate(model.A)
    slack = asm.displaced_force_and_stiffness(x, model.y0, model.S, model.EA, model.A, model.B, zA, zB, taut, P, J,
                                              nd, 0)
    if slack >= 0 and track[0] == 0.0:
        return SLACK
    _second_order(theta, x, model, prm, P, dx, J, dp, ipar, nd, extra)
    if model.moving:
        _support_derivatives(theta, omega, x, model, prm, dp, ipar, zA, zB)
    return OK


@njit
def exact_gaps(theta, omega, x, model, prm, work, g):
    """The gaps ``g[k] = l_k - S_k`` (m) at state ``x`` of the exact analysis' segments, in the
    stretches :func:`exact_field` uses (supports at rest: the slack-tracking flows are offered
    for fixed supports only, :func:`cablesim.orbits.systems.cable_system`)."""
    z = sg.zero_rate(model.A)
    asm.displaced_gaps(x, model.y0, model.S, model.A, model.B, z, z, g)


@njit
def exact_modes(work):
    """The segment modes and the tracking flag of :func:`exact_field`'s ``work``:
    ``(taut, track)``."""
    return work[2], work[3]


@njit
def _inner_state(model, P, F1, awk):
    """Inextensible closure (to round-off), factors and ``x, u, T`` at loads P; False if it
    fails (no closure, or a slack segment)."""
    c = vsub(model.B, model.A)
    cl.cumulative_loads(P, awk.Q, model.A)
    if cl.minimise(model.S, awk.Q, 0.0, c, F1, model.tol, 60) < 0:
        return False
    cl.polish(model.S, awk.Q, c, F1, 2)
    if not fx.segment_factors(model.S, model.EA, awk.Q, F1, awk.T, awk.fac, awk.gi, model.A):
        return False
    fx.natural_and_elastic(model.S, model.EA, awk.fac, awk.gi, awk.T, awk.x, awk.u, model.A)
    for k in range(awk.T.size):
        if not awk.T[k] > 0.0:
            return False
    return True


@njit
def _residual(yt, awk, r):
    big = 0.0
    for i in range(yt.size):
        r[i] = yt[i] - awk.x[i] - awk.u[i]
        big = max(big, abs(r[i]))
    return big


@njit
def residual_floor(model):
    """Round-off level of the residual ``y - x(P) - u(P)``: :data:`FLOOR_ULPS` ulps of the
    cable's length (module docstring)."""
    return FLOOR_ULPS * np.finfo(np.float64).eps * max(np.sum(model.S), vnorm(vsub(model.B, model.A)))


@njit
def solve_loads(model, yt, P, F1, w, maxit):
    """Damped Newton for the loads ``P`` with ``x(P) + u(P) = yt``, from ``(P, F1)`` (updated).

    The step ``d = N(P)^-1 r`` is the factored stiffness times the residual. It is halved until
    the residual decreases (the configuration ``x(P)`` turns fast with the direction of P: full
    steps from far away overshoot). Converged when the residual is at its round-off level
    (:func:`residual_floor`), or once a full step is below 1e-9 of ``|P|``; one more full step
    is then taken (quadratic convergence: P to round-off). Near the floor the residual cannot
    decrease reliably, so a step that lands on it is accepted. The factors (and ``x, u, T``) in
    ``w.awk`` belong to the last iterate before that final step. Returns True on convergence.
    """
    nd = P.size
    awk, r, d, Pt, F1t = w.awk, w.r, w.d, w.Pt, w.F1t
    if not _inner_state(model, P, F1, awk):
        return False
    floor = residual_floor(model)
    rn = _residual(yt, awk, r)
    done = False
    for it in range(maxit):
        fx.stiffness_product(awk.fac, awk.gi, r, d, awk.scratch, model.A)
        dmax = 0.0
        pmax = 0.0
        for i in range(nd):
            dmax = max(dmax, abs(d[i]))
            pmax = max(pmax, abs(P[i]))
        if not np.isfinite(dmax):
            return False
        if done or rn <= floor or dmax <= 1e-12 * pmax:
            for i in range(nd):
                P[i] += d[i]
            return True
        a = 1.0
        accepted = False
        for ls in range(30):
            for i in range(nd):
                Pt[i] = P[i] + a * d[i]
            F1t[:] = F1
            if _inner_state(model, Pt, F1t, awk):
                rt = _residual(yt, awk, r)
                if rt < (1.0 - 0.25 * a) * rn or rt <= floor:
                    accepted = True
                    rn = rt
                    break
            a *= 0.5
        if not accepted:
            return False
        P[:] = Pt
        F1[:] = F1t
        if a == 1.0 and dmax <= 1e-9 * pmax:
            done = True
    return False


@njit
def _walk_to_loads(model, w):
    """Loads at ``w.y`` from far away: restart from the warm start ``(w.Pw, w.F1w)`` and walk
    from its own configuration to ``y`` in 16 steps, each solved by :func:`solve_loads`; False
    if any step fails."""
    nd = w.P.size
    w.P[:] = w.Pw
    w.F1[:] = w.F1w
    if not _inner_state(model, w.P, w.F1, w.awk):
        return False
    for i in range(nd):
        w.Pw[i] = w.awk.x[i] + w.awk.u[i]  # y of the warm start (Pw reused)
    K = 16
    for k in range(1, K + 1):
        f = k / K
        for i in range(nd):
            w.yt[i] = w.Pw[i] + f * (w.y[i] - w.Pw[i])
        if not solve_loads(model, w.yt, w.P, w.F1, w, 40):
            return False
    return True


@njit
def approximate_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    """Approximate analysis (module docstring)."""
    nd = model.mass.size
    w = work
    for i in range(nd):
        w.y[i] = model.y0[i] + x[i]
        w.Pw[i] = w.P[i]
    w.F1w[:] = w.F1
    if not solve_loads(model, w.y, w.P, w.F1, w, 40):
        if not _walk_to_loads(model, w):
            return INNER_SOLVE
    for k in range(w.awk.T.size):
        if w.awk.T[k] <= 0.0:
            return SLACK
    fx.dense_stiffness(w.awk.fac, w.awk.gi, J, nd, 0, w.Kb, w.U, model.A)  # K = N^-1 into J[nd:, :nd]
    _second_order(theta, x, model, prm, w.P, dx, J, dp, ipar, nd, w.d)  # (supports fixed: d unused)
    return OK
