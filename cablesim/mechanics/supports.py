"""Harmonic motion of the supports, and the damping it brings.

A support may move about its position at the forcing frequency: ``A(t) = A + uA sin(w t + phA)``
(likewise B), with the amplitude ``uA`` a tuple of ``DIM`` components (m) and the phase ``phA``
(rad) in the :class:`~cablesim.mechanics.model.CableModel`. The motion enters the resisting force
through the first and last segments (the assembly takes the supports' current positions and
velocities).

Damping (``docs/theory.md``, section 7): the mass-proportional part ``a0 M y'`` acts on absolute
velocities, the stiffness-proportional part on the rate of deformation,
``a1 (K0 y' + K0s s')`` with ``K0s = dP/ds`` at the static state, so that it never damps a rigid
motion. ``K0s s'`` has two parts: ``-k_first s_A'`` at the first node and ``-k_last s_B'`` at the
last (``k`` the tangent block of the first or last segment at the equilibrium);
``CableModel.cA`` and ``cB`` hold ``a1 k_first`` and ``a1 k_last``.

Every function is written for ``DIM = len(model.A)`` components.
"""

from __future__ import annotations

import math

from ..jit import njit
from .vectors import mvec, vadd, vadd_to, vscale


@njit(inline="always")
def support_positions(model, t):
    """``(A(t), B(t))``, m."""
    if not model.moving:
        return model.A, model.B
    w = model.omega
    return (vadd(model.A, vscale(model.uA, math.sin(w * t + model.phA))),
            vadd(model.B, vscale(model.uB, math.sin(w * t + model.phB))))


@njit(inline="always")
def support_velocities(model, t):
    """``(A'(t), B'(t))``, m/s."""
    if not model.moving:  # no trigonometry in the time loop of supports at rest
        return vscale(model.uA, 0.0), vscale(model.uB, 0.0)
    w = model.omega
    return (vscale(model.uA, w * math.cos(w * t + model.phA)), vscale(model.uB, w * math.cos(w * t + model.phB)))


@njit(inline="always")
def support_accelerations(model, t):
    """``(A''(t), B''(t))``, m/s^2."""
    if not model.moving:
        return vscale(model.uA, 0.0), vscale(model.uB, 0.0)
    w = model.omega
    return (vscale(model.uA, -w * w * math.sin(w * t + model.phA)),
            vscale(model.uB, -w * w * math.sin(w * t + model.phB)))


@njit(inline="always")
def add_support_damping(model, rA, rB, out, sign):
    """``out += sign (cA rA)`` at the first node and ``sign (cB rB)`` at the last: with the
    supports' velocities ``rA, rB`` and ``sign = -1``, the support part of the damping force
    ``a1 K0s s'`` (with accelerations, its rate)."""
    dim = len(model.A)
    nd = model.mass.size
    vadd_to(out, 0, mvec(model.cA, rA), sign)
    vadd_to(out, nd - dim, mvec(model.cB, rB), sign)
