"""Compiled flow of one segment with a few directions of its variational equations.

Beside :func:`cablesim.orbits.kernels.flow_segment`, which carries the whole Jacobian of the
discrete flow (one column per state variable), the kernels here carry only ``k`` chosen
directions ``V`` (rows of a ``(k, n)`` array) and, optionally, the derivative with respect to
the parameter: the action ``G V`` of the segment's Jacobian ``G`` on them. The scheme and the
state's arithmetic are those of :func:`~cablesim.orbits.kernels.flow_segment` (same stage
states, same vector field evaluations, same extremes on the same interpolant), so the orbit is
the same discrete orbit and ``G V`` the exact derivative of the same discrete map:

- :func:`flow_mechanical`: the system in mechanical form (:mod:`cablesim.orbits.mechanical`),
  whose Jacobian is never formed: each direction costs O(n) per stage for a banded damping (the
  cable), instead of the O(n^2) per stage of each of the ``n`` columns of the full Jacobian;
- :func:`flow_dense_directions`: any vector field of the contract of
  :mod:`cablesim.orbits.kernels` (it forms ``J`` and multiplies), for small systems.

The parameter derivative ``eta`` follows ``eta' = J eta + g`` with ``g = -f / omega`` for
``omega`` (:data:`~cablesim.orbits.kernels.PARAM_OMEGA`) or ``g = df/dprm[ipar]``
(:data:`~cablesim.orbits.kernels.PARAM_PRM`), as in
:func:`~cablesim.orbits.kernels.flow_segment`.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.interrupts import stop_requested
from ..jit import njit
from ..mechanics.banded import half_band, is_band
from .kernels import INTERRUPTED, NONFINITE, OK, PARAM_NONE, PARAM_OMEGA, advance_state, sample_step

__all__ = ["flow_dense_directions", "flow_mechanical", "mechanical_rate", "mechanical_jac_times"]


@njit
def mechanical_rate(x, bal, model, dx):
    """``dx = (v, M^-1 (F - P - C v))`` from ``bal = P - F``; the damping is subtracted one
    entry at a time in column order, as :func:`cablesim.orbits.cablefield.exact_field` does, so
    that the rate is bitwise the same."""
    m, C = model.mass, model.C
    nd = m.size
    band = is_band(C)
    hb = half_band(C) if band else 0
    for i in range(nd):
        dx[i] = x[nd + i]
        rm = 1.0 / m[i]
        acc = -bal[i]
        if band:
            for j in range(max(0, i - hb), min(nd, i + hb + 1)):
                acc -= C[hb + i - j, j] * x[nd + j]
        else:
            for j in range(nd):
                acc -= C[i, j] * x[nd + j]
        dx[nd + i] = acc * rm


@njit
def mechanical_jac_times(stiffness_times, geo, model, w, out):
    """``out = J w = (w_v, -M^-1 (K w_z + C w_v))``, ``K`` from ``geo``."""
    m, C = model.mass, model.C
    nd = m.size
    band = is_band(C)
    hb = half_band(C) if band else 0
    for i in range(nd):
        out[i] = w[nd + i]
        out[nd + i] = 0.0
    stiffness_times(geo, model, w, out, nd)
    for i in range(nd):
        acc = out[nd + i]
        if band:
            for j in range(max(0, i - hb), min(nd, i + hb + 1)):
                acc += C[hb + i - j, j] * w[nd + j]
        else:
            for j in range(nd):
                acc += C[i, j] * w[nd + j]
        out[nd + i] = -acc / m[i]


@njit
def _stage_of(x, K, A, st, h, xs):
    """``xs = x + h sum_r A[st, r] K[r]`` (the arithmetic of the full-Jacobian kernel)."""
    for i in range(x.size):
        xs[i] = x[i]
    for r in range(st):
        a = h * A[st, r]
        if a != 0.0:
            for i in range(x.size):
                xs[i] += a * K[r, i]


@njit
def _stage_directions(W, KW, A, st, h, Ws):
    """``Ws[j] = W[j] + h sum_r A[st, r] KW[r, j]`` for every direction ``j``."""
    for j in range(W.shape[0]):
        for i in range(W.shape[1]):
            Ws[j, i] = W[j, i]
        for r in range(st):
            a = h * A[st, r]
            if a != 0.0:
                for i in range(W.shape[1]):
                    Ws[j, i] += a * KW[r, j, i]


@njit
def _advance_directions(W, KW, b, h):
    for st in range(b.size):
        hb = h * b[st]
        if hb != 0.0:
            for j in range(W.shape[0]):
                for i in range(W.shape[1]):
                    W[j, i] += hb * KW[st, j, i]


@njit
def _load_directions(V, P, pmode, n):
    """The directions to carry: ``V`` and, with a parameter, ``P`` as the last row."""
    k = V.shape[0]
    extra = 1 if pmode != PARAM_NONE else 0
    W = np.empty((k + extra, n))
    for j in range(k):
        for i in range(n):
            W[j, i] = V[j, i]
    if extra:
        for i in range(n):
            W[k, i] = P[i]
    return W


@njit
def _store_directions(W, V, P, pmode):
    k = V.shape[0]
    for j in range(k):
        for i in range(V.shape[1]):
            V[j, i] = W[j, i]
    if pmode != PARAM_NONE:
        for i in range(P.size):
            P[i] = W[k, i]


@njit
def _parameter_forcing(KWp, dx, g, omega, pmode):
    """Add the parameter forcing ``g`` (or ``-f / omega``) to the parameter row's rate."""
    if pmode == PARAM_OMEGA:
        for i in range(dx.size):
            KWp[i] -= dx[i] / omega
    else:
        for i in range(dx.size):
            KWp[i] += g[i]


@njit(nogil=True)
def flow_mechanical(balance, stiffness_times, load_derivative, model, prm, work, geo, x0, theta0, omega, duration,
                    nsteps, A, b, c, ipar, pmode, V, P, xend, xmax, xmin, rec, stop):
    """Integrate one segment of a system in mechanical form with the directions ``V`` (updated
    in place to ``G V``) and, unless ``pmode`` is ``PARAM_NONE``, the parameter derivative ``P``
    (zero on entry; ``dPhi/dlambda`` on return). ``xend``, ``xmax``, ``xmin`` and ``rec`` as in
    :func:`~cablesim.orbits.kernels.flow_segment`, and ``stop`` its interruption flag. Returns a
    status code."""
    n = x0.size
    nd = n // 2
    s = b.size
    h = duration / nsteps
    x = x0.copy()
    xs = np.empty(n)
    K = np.empty((s, n))
    bal = np.empty(nd)
    dp = np.zeros(n)
    xprev = np.empty(n)
    dprev = np.empty(n)
    W = _load_directions(V, P, pmode, n)
    nw = W.shape[0]
    Ws = np.empty((nw, n))
    KW = np.empty((s, nw, n))
    for i in range(n):
        xmax[i] = x[i]
        xmin[i] = x[i]
    for k in range(nsteps + 1):
        if stop_requested(stop):
            return INTERRUPTED
        last = k == nsteps
        for st in range(s if not last else 1):
            _stage_of(x, K, A, st, h, xs)
            theta = theta0 + omega * h * (k + c[st])
            code = balance(theta, xs, model, prm, work, geo, bal)
            if code != OK:
                return code
            mechanical_rate(xs, bal, model, K[st])
            for i in range(n):
                if not np.isfinite(K[st, i]):
                    return NONFINITE
            if not last and nw > 0:
                _stage_directions(W, KW, A, st, h, Ws)
                for j in range(nw):
                    mechanical_jac_times(stiffness_times, geo, model, Ws[j], KW[st, j])
                if pmode != PARAM_NONE:
                    if pmode != PARAM_OMEGA:
                        load_derivative(theta, model, prm, ipar, dp[nd:])
                        for i in range(nd):
                            dp[nd + i] = dp[nd + i] / model.mass[i]
                    _parameter_forcing(KW[st, nw - 1], K[st], dp, omega, pmode)
        sample_step(k, x, K, xprev, dprev, h, xmax, xmin, rec)
        if last:
            break
        if not advance_state(x, K, b, h, xprev, dprev):
            return NONFINITE
        _advance_directions(W, KW, b, h)
    for i in range(n):
        xend[i] = x[i]
    _store_directions(W, V, P, pmode)
    return OK


@njit(nogil=True)
def flow_dense_directions(field, model, prm, work, x0, theta0, omega, duration, nsteps, A, b, c, ipar, pmode, V, P,
                          xend, xmax, xmin, rec, stop):
    """:func:`flow_mechanical` for any vector field of the :mod:`cablesim.orbits.kernels`
    contract: the Jacobian is formed at every stage and multiplied by each direction (O(n^2)
    per direction and stage: for small systems)."""
    n = x0.size
    s = b.size
    h = duration / nsteps
    x = x0.copy()
    xs = np.empty(n)
    K = np.empty((s, n))
    dx = np.empty(n)
    dp = np.zeros(n)
    J = np.zeros((n, n))
    xprev = np.empty(n)
    dprev = np.empty(n)
    W = _load_directions(V, P, pmode, n)
    nw = W.shape[0]
    Ws = np.empty((nw, n))
    KW = np.empty((s, nw, n))
    ipar_f = ipar if (pmode != PARAM_NONE and pmode != PARAM_OMEGA) else -1
    for i in range(n):
        xmax[i] = x[i]
        xmin[i] = x[i]
    for k in range(nsteps + 1):
        if stop_requested(stop):
            return INTERRUPTED
        last = k == nsteps
        for st in range(s if not last else 1):
            _stage_of(x, K, A, st, h, xs)
            theta = theta0 + omega * h * (k + c[st])
            code = field(theta, omega, xs, model, prm, work, dx, J, dp, ipar_f)
            if code != OK:
                return code
            for i in range(n):
                if not np.isfinite(dx[i]):
                    return NONFINITE
                K[st, i] = dx[i]
            if not last and nw > 0:
                _stage_directions(W, KW, A, st, h, Ws)
                for j in range(nw):
                    for i in range(n):
                        acc = 0.0
                        for r in range(n):
                            acc += J[i, r] * Ws[j, r]
                        KW[st, j, i] = acc
                if pmode != PARAM_NONE:
                    _parameter_forcing(KW[st, nw - 1], dx, dp, omega, pmode)
        sample_step(k, x, K, xprev, dprev, h, xmax, xmin, rec)
        if last:
            break
        if not advance_state(x, K, b, h, xprev, dprev):
            return NONFINITE
        _advance_directions(W, KW, b, h)
    for i in range(n):
        xend[i] = x[i]
    _store_directions(W, V, P, pmode)
    return OK
