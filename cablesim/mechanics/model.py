"""The compiled physics' constants and scratch space, by name.

Every compiled kernel of the dynamics and of the orbits takes the model's constants as one
:class:`CableModel` and its scratch space as a :class:`Workspace` (plus an
:class:`ApproximateWorkspace` in the approximate analysis): named tuples, which numba passes
without copying and reads by name. ``DIM`` is the length of the support tuples ``A`` and ``B``,
so that a kernel compiled for a planar model and one for a spatial model are different
specialisations of the same source (:mod:`cablesim.mechanics.vectors`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .flexibility import factor_workspace

#: ``CableModel.kind``: the exact or the approximate analysis.
EXACT = 0
APPROXIMATE = 1
#: ``CableModel.slack``: whether the exact analysis stops where a segment goes slack or continues.
STOP = 0
CONTINUE = 1


class CableModel(NamedTuple):
    """Constants of the equations of motion about a static equilibrium.

    Attributes
    ----------
    kind : int
        :data:`EXACT` or :data:`APPROXIMATE`.
    S : ndarray (n + 1,)
        Natural segment lengths, m.
    EA : float
        Axial rigidity, N.
    A, B : tuple of DIM floats
        Support positions, m.
    mass : ndarray (n DIM,)
        Diagonal of the mass matrix ``M``, kg.
    C : ndarray
        Damping ``C``, N s/m: dense (n DIM, n DIM) or in general band storage
        (:mod:`cablesim.mechanics.banded`); with ``Cr`` the whole damping is ``C - U G U^T``.
    Cr : ndarray (n DIM + r, r)
        ``[U; G]``, the damping's low-rank part (r = 0 in the exact analysis, DIM in the
        approximate one).
    F0, FL : ndarray (n DIM,)
        Sustained and peak harmonic loads, N.
    omega : float
        Forcing frequency, rad/s.
    y0 : ndarray (n DIM,)
        Static equilibrium, m.
    x0, u0 : ndarray (n DIM,)
        Natural state ``x(F0)`` and elastic displacement ``y0 - x0`` there, m.
    tol : float
        Closure tolerance of the inner solves, m.
    slack : int
        :data:`STOP` or :data:`CONTINUE`.
    moving : bool
        Whether a support moves (:mod:`cablesim.mechanics.supports`).
    uA, uB : tuple of DIM floats
        Amplitudes of the supports' harmonic motion, m.
    phA, phB : float
        Their phases, rad: ``A(t) = A + uA sin(w t + phA)``.
    cA, cB : tuple of DIM * DIM floats
        ``a1`` times the tangent blocks of the first and last segments at the equilibrium (the
        support part of the stiffness-proportional damping), N s/m, row-major.
    """

    kind: int
    S: np.ndarray
    EA: float
    A: tuple
    B: tuple
    mass: np.ndarray
    C: np.ndarray
    Cr: np.ndarray
    F0: np.ndarray
    FL: np.ndarray
    omega: float
    y0: np.ndarray
    x0: np.ndarray
    u0: np.ndarray
    tol: float
    slack: int
    moving: bool
    uA: tuple
    uB: tuple
    phA: float
    phB: float
    cA: tuple
    cB: tuple


class Workspace(NamedTuple):
    """Scratch arrays of the vector field (no allocation inside a time loop).

    Attributes
    ----------
    y, P, Kv, v, Cx : ndarray (n DIM,)
        A configuration, the resisting force, ``K v``, a velocity and a damping product.
    taut : ndarray (n + 1,)
        Segment modes, 1 (taut) or 0 (slack); all taut to start.
    """

    y: np.ndarray
    P: np.ndarray
    Kv: np.ndarray
    v: np.ndarray
    taut: np.ndarray
    Cx: np.ndarray


class ApproximateWorkspace(NamedTuple):
    """Scratch arrays of the approximate analysis' inner solves, O(n) memory.

    Attributes
    ----------
    Q : ndarray (n + 1, DIM)
        Cumulative loads.
    x, u : ndarray (n DIM,)
        Natural state and elastic displacement.
    T : ndarray (n + 1,)
        Tensions.
    fac, gi, scratch
        The stiffness factors of :func:`cablesim.mechanics.flexibility.segment_factors` and the
        products' scratch (:func:`~cablesim.mechanics.flexibility.factor_workspace`).
    """

    Q: np.ndarray
    x: np.ndarray
    u: np.ndarray
    T: np.ndarray
    fac: np.ndarray
    gi: np.ndarray
    scratch: tuple


def workspace(n: int, dim: int = 2) -> Workspace:
    """A :class:`Workspace` for ``n`` nodes of ``dim`` components."""
    nd = dim * n
    return Workspace(np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.ones(n + 1), np.empty(nd))


def approximate_workspace(n: int, dim: int = 2) -> ApproximateWorkspace:
    """An :class:`ApproximateWorkspace` for ``n`` nodes of ``dim`` components."""
    nd = dim * n
    fac, gi, scratch = factor_workspace(n, dim)
    return ApproximateWorkspace(np.empty((n + 1, dim)), np.empty(nd), np.empty(nd), np.empty(n + 1), fac, gi, scratch)
