"""The cable's equations of motion in *mechanical form*, for the matrix-free kernels.

The matrix-free shooting (:mod:`cablesim.orbits.directional`, :mod:`cablesim.orbits.radau`) never
forms the Jacobian of the first-order field. It needs the field through four compiled functions
of a second-order system ``M z'' + C z' + P(z) = F(theta; prm)`` on the state ``x = (z, v)``
(``z`` displacements from the static equilibrium, ``v`` velocities, ``nd`` each):

``balance(theta, x, model, prm, work, geo, out) -> status``
    ``out = P(z) - F(theta)`` (the resisting force minus the applied load, N), and the state of
    the tangent stiffness at ``z`` into ``geo`` (a float array whose shape the system chooses);
``stiffness_times(geo, model, w, out, row)``
    ``out[row + i] += (K w[:nd])_i``: the tangent stiffness ``K = dP/dz`` at the state saved in
    ``geo`` times the displacement part of ``w``, without forming ``K``;
``stiffness_band(geo, model, Kb)``
    ``K`` in general band storage (:mod:`cablesim.mechanics.banded`, ``Kb[h + i - j, j]``);
``load_derivative(theta, model, prm, ipar, out)``
    ``out = dF/dprm[ipar]``, N.

``model.mass`` is the diagonal of ``M`` and ``model.C`` the damping, dense or banded (read
through :func:`cablesim.mechanics.banded.damping_row`; the matrix-free products cost O(n) when
it is banded). The first-order field is then ``f(x) = (v, M^-1 (F - P(z) - C v))`` with
``J w = (w_v, -M^-1 (K w_z + C w_v))``.

The cable (exact analysis, fixed supports): ``P`` in displacement form as in
:func:`cablesim.mechanics.assembly.displaced_force_and_stiffness` (the stretch of each segment
from the change of its vector, so small orbits keep full relative precision), summed in the same
order, so that ``f`` is bitwise the vector field :func:`cablesim.orbits.cablefield.exact_field`
computes; ``geo[k] = (e_k, ka_k, kg_k)`` holds each segment's unit vector and the coefficients of
its tangent block ``kg I + (ka - kg) e e^T`` (:mod:`cablesim.mechanics.segments`, the only place
the segment law is written), ``(n + 1, DIM + 2)`` values. Everything is O(n) and written for any
number of components per node (``DIM = len(model.A)``).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..mechanics.segments import (block_coefficients, block_entry, block_times, displaced_stretch, length, node,
                                  segment_vector, tension_of_stretch, zero_rate)
from ..mechanics.vectors import vadd, vadd_to, vdiv, vrow, vsub
from .cablefield import GAMMA
from .kernels import OK, SLACK

__all__ = ["cable_balance", "cable_load_derivative", "cable_stiffness_band", "cable_stiffness_times",
           "geometry_shape"]


def geometry_shape(n_nodes: int, dim: int) -> tuple[int, int]:
    """Shape of the cable's ``geo`` array: one row per segment, ``(e, ka, kg)``."""
    return (n_nodes + 1, dim + 2)


@njit
def cable_balance(theta, x, model, prm, work, geo, out):
    """``out = P(z) - F0 - gamma FL sin(theta)`` of the exact analysis and the segments'
    geometry into ``geo``; ``SLACK`` if a segment is not longer than its natural length
    (module docstring). ``work`` is unused (the exact analysis has no inner solve)."""
    A, B, S, EA, y0 = model.A, model.B, model.S, model.EA, model.y0
    dim = len(A)
    n = S.size - 1
    nd = n * dim
    zA = zero_rate(A)
    for i in range(nd):
        out[i] = 0.0
    for k in range(n + 1):
        d0 = segment_vector(y0, k, n, A, B)
        dd = vsub(node(x, k, n, zA, zA), node(x, k - 1, n, zA, zA))
        dvec = vadd(d0, dd)
        l = length(dvec)
        T = tension_of_stretch(displaced_stretch(d0, dd, l, S[k]), S[k], EA)
        if T <= 0.0:
            return SLACK
        e = vdiv(dvec, l)
        ka, kg = block_coefficients(l, T, S[k], EA, 1.0)
        for c in range(dim):
            geo[k, c] = e[c]
        geo[k, dim] = ka
        geo[k, dim + 1] = kg
        if k < n:
            vadd_to(out, dim * k, e, T)
        if k > 0:
            vadd_to(out, dim * (k - 1), e, -T)
    sn = np.sin(theta)
    g = prm[GAMMA]
    F0, FL = model.F0, model.FL
    for i in range(nd):
        # -(F - P) rounds exactly as P - F: the field's F - P is recovered bit for bit
        out[i] = -((F0[i] + g * FL[i] * sn) - out[i])
    return OK


@njit
def cable_stiffness_times(geo, model, w, out, row):
    """``out[row + i] += (K w[:nd])_i`` from the segments' geometry in ``geo``, O(n)."""
    A = model.A
    dim = len(A)
    n = geo.shape[0] - 1
    zA = zero_rate(A)
    for k in range(n + 1):
        e = vrow(geo, k, A)
        dw = vsub(node(w, k, n, zA, zA), node(w, k - 1, n, zA, zA))
        r = block_times(geo[k, dim], geo[k, dim + 1], e, dw)
        if k < n:
            vadd_to(out, row + dim * k, r, 1.0)
        if k > 0:
            vadd_to(out, row + dim * (k - 1), r, -1.0)


@njit
def cable_stiffness_band(geo, model, Kb):
    """``K`` from the geometry in ``geo`` into general band storage ``Kb`` (shape
    ``(2 h + 1, nd)``, ``h = 2 DIM - 1``), assembled as
    :func:`cablesim.mechanics.assembly.force_and_stiffness_band` does."""
    A = model.A
    dim = len(A)
    hb = 2 * dim - 1
    n = geo.shape[0] - 1
    Kb[:, :] = 0.0
    for k in range(n + 1):
        e = vrow(geo, k, A)
        ka, kg = geo[k, dim], geo[k, dim + 1]
        a, b = dim * (k - 1), dim * k
        for r in range(dim):
            for c in range(dim):
                kk = block_entry(ka, kg, e, r, c)
                if k < n:
                    Kb[hb + r - c, b + c] += kk
                if k > 0:
                    Kb[hb + r - c, a + c] += kk
                if 0 < k < n:
                    Kb[hb + (a + r) - (b + c), b + c] -= kk
                    Kb[hb + (b + r) - (a + c), a + c] -= kk


@njit
def cable_load_derivative(theta, model, prm, ipar, out):
    """``out = dF/dprm[ipar]``: ``FL sin(theta)`` for ``gamma``, else zero."""
    sn = np.sin(theta)
    for i in range(out.size):
        out[i] = model.FL[i] * sn if ipar == GAMMA else 0.0
