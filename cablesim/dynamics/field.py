"""The compiled vector field every integrator calls: the paper's third-order equation (17).

``M y''' + C y'' + K y' = F'`` with ``F(t) = F0 + FL sin(w t)`` and ``K`` the tangent stiffness
of the analysis in use:

- exact analysis: ``K = K(y)`` of the deformed configuration, the segments counting as their
  modes say (taut or slack);
- approximate analysis: ``K = N(P)^-1`` with ``P = F - C y' - M y''`` (eq. 15) and ``x(P)`` the
  inextensible equilibrium, solved at every evaluation from the previous one (the warm start).

The state integrated is ``s = (z, y', y'')`` with ``z = y - y(0)`` measured from the static
equilibrium (so tolerances act on the displacement, not on absolute coordinates). The kernels
take the model's constants as a :class:`~cablesim.mechanics.model.CableModel` and their scratch
space as a :class:`~cablesim.mechanics.model.Workspace` and, in the approximate analysis, an
:class:`~cablesim.mechanics.model.ApproximateWorkspace` (None for the exact analysis: numba then
compiles a version without the approximate branch). They return a status code
(:class:`cablesim.dynamics.status.Status`) instead of raising.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..mechanics import assembly as asm
from ..mechanics import banded as bd
from ..mechanics import closure as cl
from ..mechanics import flexibility as fx
from ..mechanics import segments as sg
from ..mechanics.model import APPROXIMATE, EXACT, STOP
from ..mechanics.supports import add_support_damping, support_accelerations, support_positions, support_velocities
from ..mechanics.vectors import vadd_to, vsub
from .status import INNER_SOLVE, NONFINITE, OK, SLACK


@njit
def load(model, t):
    """``F(t) = F0 + FL sin(w t)`` (allocates; for code outside the hot loop)."""
    return model.F0 + model.FL * np.sin(model.omega * t)


@njit(inline="always")
def chord(model):
    """``B - A``, the tuple the closure closes on."""
    return vsub(model.B, model.A)


@njit
def approximate_stiffness(model, P, warm, awk):
    """Solve the inextensible closure at loads P (warm start ``warm``) and factor ``K = N^-1``.

    Fills ``awk`` (O(n)): Q, T and the factors of
    :func:`cablesim.mechanics.flexibility.segment_factors`; returns ``OK`` or ``INNER_SOLVE``.
    The states x and u follow from :func:`natural_state` (outputs only).
    """
    return closure_and_factors(model.S, model.EA, model.tol, model.A, chord(model), P, warm, awk)


@njit
def stiffness_on_chord(model, P, warm, awk, c):
    """:func:`approximate_stiffness` for the chord ``c`` (the supports where they are now)."""
    return closure_and_factors(model.S, model.EA, model.tol, model.A, c, P, warm, awk)


@njit
def closure_and_factors(S, EA, tol, A, c, P, warm, awk):
    """:func:`approximate_stiffness` from the model's constants it needs (``S``, ``EA``, the
    closure tolerance ``tol``, support ``A``, chord ``c``). The vector field calls this one: each
    compiled call that takes the whole model costs about a tenth of a microsecond, a tenth of
    the vector field of a 2-node cable."""
    for i in range(P.size):
        if not abs(P[i]) < 1e100:  # a blown-up state (or NaN): the closure's products would underflow
            return INNER_SOLVE
    cl.cumulative_loads(P, awk.Q, A)
    if cl.minimise(S, awk.Q, 0.0, c, warm, tol, 60) < 0:
        return INNER_SOLVE
    if not fx.segment_factors(S, EA, awk.Q, warm, awk.T, awk.fac, awk.gi, A):
        return INNER_SOLVE
    return OK


@njit
def natural_state(model, awk):
    """``x(P)`` and ``u(P)`` into ``awk.x``, ``awk.u`` after :func:`approximate_stiffness`."""
    fx.natural_and_elastic(model.S, model.EA, awk.fac, awk.gi, awk.T, awk.x, awk.u, model.A)


@njit
def resisting_from_eq15(model, t, v, a, P):
    """``P = F(t) - C y' - M y''`` (eq. 15) into P."""
    m, F0, FL = model.mass, model.F0, model.FL
    sw = np.sin(model.omega * t)
    bd.damping_product(model.C, model.Cr, v, 0, P)
    for i in range(m.size):
        P[i] = F0[i] + FL[i] * sw - m[i] * a[i] - P[i]


@njit(borrowed=True)  # called at every stage: no reference counting (cablesim.jit)
def exact_force_and_rate(model, t, y, v, wk):
    """``P(y)`` into ``wk.P`` and ``K(y) v`` into ``wk.Kv`` (with moving supports, the whole rate
    ``K y' + Ks s'``) for the segment modes ``wk.taut`` at time ``t``; the first segment not
    longer than its natural length, or -1."""
    if model.moving:
        A, B = support_positions(model, t)
        vA, vB = support_velocities(model, t)
        return asm.force_and_rate(y, v, model.S, model.EA, A, B, vA, vB, wk.taut, wk.P, wk.Kv)
    z = sg.zero_rate(model.A)
    return asm.force_and_rate(y, v, model.S, model.EA, model.A, model.B, z, z, wk.taut, wk.P, wk.Kv)


@njit
def damping_force(model, t, v, out):
    """``C y' + a1 K0s s'`` (the support part only with moving supports) into ``out``, N."""
    bd.damping_product(model.C, model.Cr, v, 0, out)
    if model.moving:
        vA, vB = support_velocities(model, t)
        add_support_damping(model, vA, vB, out, -1.0)


@njit
def rate(model, t, s, warm, ds, wk, awk):
    """Right-hand side of the third-order system: ``ds = (velocity, acceleration, jerk)``.

    In the exact analysis the segments count as the modes ``wk.taut`` say (taut or slack); with
    ``slack: stop`` a segment not longer than its natural length returns ``SLACK``.
    """
    m, FL = model.mass, model.FL
    y, v = wk.y, wk.v
    nd = m.size
    for i in range(nd):
        ds[i] = s[nd + i]
        ds[nd + i] = s[2 * nd + i]
        v[i] = s[nd + i]  # contiguous copy: slicing here costs more than the physics
    if awk is None:
        for i in range(nd):
            y[i] = model.y0[i] + s[i]
        if exact_force_and_rate(model, t, y, v, wk) >= 0 and model.slack == STOP:
            return SLACK
    else:  # K(P) y' with P from eq. 15 (written out here: see closure_and_factors)
        resisting_from_eq15(model, t, s[nd : 2 * nd], s[2 * nd :], wk.P)
        st = closure_and_factors(model.S, model.EA, model.tol, model.A, chord(model), wk.P, warm, awk)
        if st != OK:
            return st
        fx.stiffness_product(awk.fac, awk.gi, v, wk.Kv, awk.scratch, model.A)
    wc = model.omega * np.cos(model.omega * t)
    Ca = wk.Cx
    Kv = wk.Kv
    bd.damping_product(model.C, model.Cr, s, 2 * nd, Ca)
    if model.moving:  # the rate of the supports' part of the damping
        aA, aB = support_accelerations(model, t)
        add_support_damping(model, aA, aB, Ca, -1.0)
    for i in range(nd):
        acc = (FL[i] * wc - Kv[i] - Ca[i]) / m[i]
        if not np.isfinite(acc):
            return NONFINITE
        ds[2 * nd + i] = acc
    return OK


@njit
def consistent_acceleration(model, t, s, wk):
    """Exact analysis: set ``y''`` in ``s`` from eq. 15 with the segment modes ``wk.taut``,
    ``y'' = M^-1 (F(t) - C y' - P(y))`` (eq. 19 at a restart)."""
    m, F0, FL = model.mass, model.F0, model.FL
    y, v = wk.y, wk.v
    nd = m.size
    for i in range(nd):
        y[i] = model.y0[i] + s[i]
        v[i] = s[nd + i]
    exact_force_and_rate(model, t, y, v, wk)
    sw = np.sin(model.omega * t)
    damping_force(model, t, v, wk.Cx)
    for i in range(nd):
        s[2 * nd + i] = (F0[i] + FL[i] * sw - wk.P[i] - wk.Cx[i]) / m[i]


@njit
def equilibrium_factors(model, warm, awk):
    """The factors of the approximate analysis' ``K0 = K(F0)`` (copies of ``awk.fac``, ``awk.gi``
    after :func:`approximate_stiffness` at F0), for :func:`observe`'s drift: computed once per
    record. NaN for the exact analysis or if the closure at F0 fails (the drift is then NaN)."""
    fac0, gi0 = np.full_like(awk.fac, np.nan), np.full_like(awk.gi, np.nan)
    if model.kind == APPROXIMATE and approximate_stiffness(model, model.F0, warm.copy(), awk) == OK:
        fac0[:, :] = awk.fac
        gi0[:] = awk.gi
    return fac0, gi0


@njit
def _force_scale(f0norm, T):
    """What the drift is relative to: ``|F0|``, or the largest tension when there are no
    sustained loads (a weightless taut cable)."""
    if f0norm > 0.0:
        return f0norm
    top = 0.0
    for k in range(T.size):
        top = max(top, T[k])
    return top if top > 0.0 else 1.0


@njit
def observe(model, t, s, warm, zc, ze, T, segment_state, awk, split, k0):
    """Derived outputs at one instant: ``z_c``, ``z_e``, tensions and the drift of eq. 15.

    ``segment_state`` receives the index of a slack segment (exact) or -1; tensions follow the
    tension-only law ``EA max(l - S, 0) / S``. Returns the drift residual
    ``|M y'' + C y' + P - F| / |F0|`` (exact analysis) or, for the approximate analysis where
    eq. 15 defines P, the mismatch between the integrated ``y`` and ``x(P) + u(P)`` expressed as
    a force through ``K0`` (its factors ``k0`` from :func:`equilibrium_factors`), also relative
    to ``|F0|`` (to the largest tension when F0 = 0). NaN if the inner solve fails. Without ``split`` the exact analysis skips the
    inner solve (``zc``, ``ze`` set to zero).
    """
    m = model.mass
    nd = m.size
    z = s[:nd]
    v = s[nd : 2 * nd]
    a = s[2 * nd :]
    F = load(model, t)
    f0norm = np.sqrt(np.sum(model.F0 ** 2))
    if model.kind == EXACT:
        y = model.y0 + z
        P = np.empty(nd)
        Kv = np.empty(nd)
        taut = np.empty(model.S.size)
        A, B = support_positions(model, t)
        vA, vB = support_velocities(model, t)
        sg.taut_modes(y, model.S, A, B, taut)
        segment_state[0] = asm.force_and_rate(y, v, model.S, model.EA, A, B, vA, vB, taut, P, Kv)
        sg.tensions(y, model.S, model.EA, A, B, T)
        for k in range(model.S.size):
            T[k] *= taut[k]
        if not split:
            zc[:] = 0.0
            ze[:] = 0.0
        elif stiffness_on_chord(model, P, warm, awk, vsub(B, A)) != OK:
            zc[:] = np.nan
            ze[:] = np.nan
        else:
            natural_state(model, awk)  # x(P) from support A where it is now
            dim = len(A)
            for j in range(nd // dim):
                vadd_to(awk.x, dim * j, A, 1.0)
            zc[:] = awk.x - model.x0
            ze[:] = z - zc
        Cv = np.empty(nd)
        damping_force(model, t, v, Cv)
        r = m * a + P - F + Cv
        return np.sqrt(np.sum(r * r)) / _force_scale(f0norm, T)
    P = np.empty(nd)
    resisting_from_eq15(model, t, v, a, P)
    segment_state[0] = -1
    if approximate_stiffness(model, P, warm, awk) != OK:
        zc[:] = np.nan
        ze[:] = np.nan
        T[:] = np.nan
        return np.nan
    T[:] = awk.T
    natural_state(model, awk)
    zc[:] = awk.x - model.x0
    ze[:] = awk.u - model.u0
    mismatch = z - zc - ze
    d = np.empty(nd)
    fx.stiffness_product(k0[0], k0[1], mismatch, d, awk.scratch, model.A)
    return np.sqrt(np.sum(d * d)) / _force_scale(f0norm, T)
