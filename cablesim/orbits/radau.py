"""The 3-stage Radau IIA scheme (order 5, L-stable) for orbits of stiff mechanical systems.

A finely divided cable is stiff: its axial modes grow as ``n`` and, with stiffness-proportional
damping, the real roots of its high modes as ``n^2``, so an explicit step is held to
``1 / rate`` however smooth the orbit (:mod:`cablesim.orbits.shooting`: 8300 rk8 steps per
forcing period for the 50-node heavy span at 2 rad/s, 36,000 for 100 nodes). An implicit,
L-stable scheme takes its step from the accuracy of the resolved motion alone, and damps the
unresolved stiff modes as the cable does (their multipliers stay near zero instead of landing
anywhere inside the unit circle).

The system is in mechanical form (:mod:`cablesim.orbits.mechanical`). With ``a_s`` the
displacement increments of the three stages over a step ``h`` from ``(z, v)``, the stage
velocities follow from the first-order stage equations, ``v_s = ((hA)^-1 a)_s``, and the stage
equations reduce to ``3 nd`` equations in ``a``::

    R(a) = M (hA)^-2 a + C (hA)^-1 a + [P(z + a_s) - F(theta_s)]_s - M (hA)^-1 1 v = 0

whose Jacobian ``Q = M (x) (hA)^-2 + C (x) (hA)^-1 + diag_s(K(z + a_s))`` is banded when the
stages of each node are numbered together (half bandwidth ``3 h + 2``, ``h`` that of ``K``) and
is factored by :mod:`cablesim.orbits.bandlu`. The new state is ``(z + a_3, v_3)`` (``c_3 = 1``:
stiffly accurate). Newton's method on ``R`` uses the factors of ``Q`` at the previous step's
stages and starts from the extrapolated collocation polynomial of that step; it iterates until
the correction is at the round-off level of ``a`` (or a thousandth of ``h`` times the system's
velocity noise), so that the discrete map is a smooth function of the start state to round-off.

Variational equations: the exact derivative of the discrete map follows from the same ``Q``,
factored at the converged stages (implicit function theorem): a direction ``(dz, dv)`` and the
parameter forcing ``g = (g_z, g_v)`` (``-f / omega`` or ``dF/dprm / M``) give::

    Q da = M (hA)^-1 (1 dv + g_z) - [K_s dz]_s + C g_z + M g_v
    (dz, dv) <- (dz + da_3, ((hA)^-1 da)_3 - g_z3)

one banded solve per direction and step, with no iteration. :func:`radau_orbit` records the
factors, the stages' geometry and rates on a *tape*; :func:`radau_directions` replays it for any
number of directions, so the action of the monodromy on a vector costs a solve per step and no
evaluation of the nonlinear field.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.interrupts import stop_requested
from ..jit import njit
from ..mechanics.banded import half_band, is_band
from . import bandlu
from .directional import mechanical_rate
from .kernels import INTERRUPTED, NONFINITE, OK, PARAM_NONE, PARAM_OMEGA, sample_step

__all__ = ["RADAU", "RadauTableau", "radau_directions", "radau_orbit", "q_bandwidth"]

#: Newton iterations per step before a step counts as failed.
MAX_NEWTON = 20


class RadauTableau:
    """Coefficients of the 3-stage Radau IIA scheme and what the kernels derive from them:
    ``W1 = A^-1``, ``W2 = A^-2`` and the extrapolation ``E`` of the previous step's collocation
    polynomial to the next step's stages (``a_s = sum_t E[s, t] a_t(previous)``)."""

    name = "radau"
    order = 5
    stages = 3

    def __init__(self):
        s6 = np.sqrt(6.0)
        self.A = np.array([
            [(88.0 - 7.0 * s6) / 360.0, (296.0 - 169.0 * s6) / 1800.0, (-2.0 + 3.0 * s6) / 225.0],
            [(296.0 + 169.0 * s6) / 1800.0, (88.0 + 7.0 * s6) / 360.0, (-2.0 - 3.0 * s6) / 225.0],
            [(16.0 - s6) / 36.0, (16.0 + s6) / 36.0, 1.0 / 9.0],
        ])
        self.c = np.array([(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0])
        self.b = self.A[2].copy()
        self.W1 = np.ascontiguousarray(np.linalg.inv(self.A))
        self.W2 = np.ascontiguousarray(self.W1 @ self.W1)
        nodes = np.concatenate([[0.0], self.c])
        E = np.zeros((3, 3))
        for s in range(3):
            tau = 1.0 + self.c[s]
            for t in range(3):
                others = np.delete(nodes, t + 1)
                E[s, t] = np.prod((tau - others) / (self.c[t] - others))
        E[:, 2] -= 1.0  # increments from the new step's start, u(1)
        self.E = E


RADAU = RadauTableau()


@njit
def q_bandwidth(k_half_band):
    """Half bandwidth of the stage matrix ``Q`` for a stiffness of half bandwidth ``h``."""
    return 3 * k_half_band + 2


@njit
def _build_q(stiffness_band, geo3, model, Kb3, h, W1, W2, AB, kl):
    """``Q`` (module docstring) in the band storage of :mod:`cablesim.orbits.bandlu`; row
    ``3 i + s`` is stage ``s`` of DOF ``i``."""
    m, C = model.mass, model.C
    nd = m.size
    hb = half_band(Kb3[0])
    band = is_band(C)
    hc = half_band(C) if band else 0
    kv = 2 * kl
    AB[:, :] = 0.0
    for s in range(3):
        stiffness_band(geo3[s], model, Kb3[s])
    rh = 1.0 / h
    rh2 = rh * rh
    for j in range(nd):
        for i in range(max(0, j - hb), min(nd, j + hb + 1)):
            if band:
                cij = C[hc + i - j, j] if abs(i - j) <= hc else 0.0
            else:
                cij = C[i, j]
            for t in range(3):
                col = AB[3 * j + t]
                for s in range(3):
                    val = cij * W1[s, t] * rh
                    if i == j:
                        val += m[i] * W2[s, t] * rh2
                    if s == t:
                        val += Kb3[s, hb + i - j, j]
                    col[kv + (3 * i + s) - (3 * j + t)] = val


@njit
def _damping_times(C, w, off, out, nd):
    """``out = C w[off:off + nd]`` (dense or banded ``C``)."""
    band = is_band(C)
    hc = half_band(C) if band else 0
    for i in range(nd):
        acc = 0.0
        if band:
            for j in range(max(0, i - hc), min(nd, i + hc + 1)):
                acc += C[hc + i - j, j] * w[off + j]
        else:
            for j in range(nd):
                acc += C[i, j] * w[off + j]
        out[i] = acc


@njit
def _residual(x, a, bal3, model, W1, W2, h, r, tmp):
    """``r = R(a)`` (module docstring), interleaved (``3 i + s``); ``bal3[s] = P - F`` at stage s."""
    m, C = model.mass, model.C
    nd = m.size
    rh = 1.0 / h
    for s in range(3):
        for i in range(nd):
            w1 = W1[s, 0] * a[0, i] + W1[s, 1] * a[1, i] + W1[s, 2] * a[2, i]
            tmp[i] = w1 * rh
        _damping_times(C, tmp, 0, tmp[nd:], nd)
        ws = W1[s, 0] + W1[s, 1] + W1[s, 2]
        for i in range(nd):
            w2 = W2[s, 0] * a[0, i] + W2[s, 1] * a[1, i] + W2[s, 2] * a[2, i]
            r[3 * i + s] = m[i] * (w2 * rh * rh - ws * rh * x[nd + i]) + tmp[nd + i] + bal3[s, i]


@njit
def _newton_stages(balance, model, prm, work, geo3, bal3, x, a, xs, theta0, omega, h, k, nsteps, c, W1, W2, AB, kl,
                   piv, r, tmp, vnoise, info):
    """Newton's method on the stage equations ``R(a) = 0`` of step ``k`` from ``x`` (``a`` holds the
    start and receives the solution), with the factors of ``Q`` in ``AB``; ``info`` as in
    :func:`radau_orbit`. Returns a status code (``NONFINITE`` if it does not converge)."""
    nd = x.size // 2
    eps = np.finfo(np.float64).eps
    last = np.inf
    for it in range(MAX_NEWTON):
        for s in range(3):
            for i in range(nd):
                xs[i] = x[i] + a[s, i]
            code = balance(theta0 + omega * h * (k + c[s]), xs, model, prm, work, geo3[s], bal3[s])
            if code != OK:
                return code
        _residual(x, a, bal3, model, W1, W2, h, r, tmp)
        bandlu.solve(AB, kl, kl, piv, r)
        worst = 0.0
        for s in range(3):
            for i in range(nd):
                d = r[3 * i + s]
                a[s, i] -= d
                worst = max(worst, abs(d) / (4.0 * eps * abs(a[s, i]) + 1e-3 * h * vnoise[i]))
        info[0] += 1.0
        if k == nsteps // 2 and info.size > 1 + it:
            info[1 + it] = worst
        if not np.isfinite(worst):
            return NONFINITE
        # converged, or stalled at the round-off floor (within a hundred of the tolerance)
        if worst <= 1.0 or (it >= 2 and worst <= 100.0 and worst > 0.5 * last):
            return OK
        last = worst
    return NONFINITE


@njit(nogil=True)
def radau_orbit(balance, stiffness_band, model, prm, work, geo3, Kb3, x0, theta0, omega, duration, nsteps, c,
                W1, W2, E, vnoise, taped, tape_AB, tape_piv, tape_geo, tape_rate, xend, xmax, xmin, rec, info, stop):
    """Integrate one segment by the Radau IIA scheme (module docstring).

    ``geo3`` (3, ...) and ``Kb3`` (3, 2 h + 1, nd) are scratch for the stages' geometry and
    stiffness bands. With ``taped``, step ``k``'s factors of ``Q`` at its converged stages go to
    ``tape_AB[k]``, ``tape_piv[k]``, the stages' geometry to ``tape_geo[k]`` and their rates
    ``f = (v_s, v'_s)`` to ``tape_rate[k]``. ``xend``, ``xmax``, ``xmin``, ``rec`` as in
    :func:`~cablesim.orbits.kernels.flow_segment`; ``info[0]`` receives the Newton iterations;
    ``stop``: the interruption flag, read once a step. Returns a status code (``NONFINITE`` also
    when the stage equations do not converge).
    """
    n = x0.size
    nd = n // 2
    N = 3 * nd
    h = duration / nsteps
    kl = q_bandwidth(half_band(Kb3[0]))
    AB = np.zeros((N, bandlu.band_rows(kl, kl)))
    piv = np.zeros(N, dtype=np.int64)
    x = x0.copy()
    xs = np.empty(n)
    rate = np.empty((1, n))
    rates = np.empty((3, n))
    bal3 = np.empty((3, nd))
    a = np.empty((3, nd))
    ap = np.empty((3, nd))
    r = np.empty(N)
    tmp = np.empty(2 * nd)
    xprev = np.empty(n)
    dprev = np.empty(n)
    info[0] = 0.0
    code = balance(theta0, x, model, prm, work, geo3[0], bal3[0])
    if code != OK:
        return code
    mechanical_rate(x, bal3[0], model, rate[0])
    for s in range(1, 3):
        geo3[s, :, :] = geo3[0]
    _build_q(stiffness_band, geo3, model, Kb3, h, W1, W2, AB, kl)
    if not bandlu.factor(AB, kl, kl, piv):
        return NONFINITE
    for s in range(3):
        for i in range(nd):
            ap[s, i] = c[s] * h * x[nd + i]  # the first step starts from the linear guess
    for k in range(nsteps + 1):
        if stop_requested(stop):
            return INTERRUPTED
        sample_step(k, x, rate, xprev, dprev, h, xmax, xmin, rec)
        if k == nsteps:
            break
        for i in range(n):
            xprev[i] = x[i]
            dprev[i] = rate[0, i]
        for s in range(3):
            for i in range(nd):
                a[s, i] = ap[s, i] if k == 0 else E[s, 0] * ap[0, i] + E[s, 1] * ap[1, i] + E[s, 2] * ap[2, i]
        code = _newton_stages(balance, model, prm, work, geo3, bal3, x, a, xs, theta0, omega, h, k, nsteps, c, W1,
                              W2, AB, kl, piv, r, tmp, vnoise, info)
        if code != OK:
            return code
        for s in range(3):
            for i in range(nd):
                xs[i] = x[i] + a[s, i]
                xs[nd + i] = (W1[s, 0] * a[0, i] + W1[s, 1] * a[1, i] + W1[s, 2] * a[2, i]) / h
            code = balance(theta0 + omega * h * (k + c[s]), xs, model, prm, work, geo3[s], bal3[s])
            if code != OK:
                return code
            mechanical_rate(xs, bal3[s], model, rates[s])
        for i in range(nd):
            x[i] = x[i] + a[2, i]
            x[nd + i] = rates[2, i]
        for i in range(n):
            rate[0, i] = rates[2, i]
            if not np.isfinite(x[i]) or not np.isfinite(rate[0, i]):
                return NONFINITE
        _build_q(stiffness_band, geo3, model, Kb3, h, W1, W2, AB, kl)
        if not bandlu.factor(AB, kl, kl, piv):
            return NONFINITE
        if taped:
            tape_AB[k] = AB
            tape_piv[k] = piv
            tape_geo[k] = geo3
            tape_rate[k] = rates
        ap[:, :] = a
    for i in range(n):
        xend[i] = x[i]
    return OK


@njit
def _plain_rhs(stiffness_times, model, geo3, W1, h, V, RHS, tmp):
    """Right-hand sides of the stage system for the directions ``V`` (q, n) into ``RHS`` (3 nd, q)."""
    m = model.mass
    nd = m.size
    rh = 1.0 / h
    for j in range(V.shape[0]):
        w = V[j]
        for s in range(3):
            ws = (W1[s, 0] + W1[s, 1] + W1[s, 2]) * rh
            for i in range(nd):
                tmp[nd + i] = 0.0
            stiffness_times(geo3[s], model, w, tmp, nd)
            for i in range(nd):
                RHS[3 * i + s, j] = m[i] * ws * w[nd + i] - tmp[nd + i]


@njit
def _parameter_rhs(stiffness_times, model, geo3, W1, h, w, gz, gv, rhs, tmp):
    """Right-hand side for the parameter derivative ``w`` with the forcing ``(gz, gv)``."""
    m, C = model.mass, model.C
    nd = m.size
    rh = 1.0 / h
    for s in range(3):
        ws = W1[s, 0] + W1[s, 1] + W1[s, 2]
        for i in range(nd):
            tmp[nd + i] = 0.0
        stiffness_times(geo3[s], model, w, tmp, nd)
        for i in range(nd):
            acc = ws * w[nd + i] + W1[s, 0] * gz[0, i] + W1[s, 1] * gz[1, i] + W1[s, 2] * gz[2, i]
            rhs[3 * i + s] = m[i] * acc * rh - tmp[nd + i]
        _damping_times(C, gz[s], 0, tmp, nd)
        for i in range(nd):
            rhs[3 * i + s] += tmp[i] + m[i] * gv[s, i]


@njit
def _update(w, da, col, W1, h, nd, gz, with_g):
    """``(dz, dv) <- (dz + da_3, ((hA)^-1 da)_3 - g_z3)`` from the solution column ``col``."""
    rh = 1.0 / h
    for i in range(nd):
        da0, da1, da2 = da[3 * i, col], da[3 * i + 1, col], da[3 * i + 2, col]
        w[i] += da2
        w[nd + i] = (W1[2, 0] * da0 + W1[2, 1] * da1 + W1[2, 2] * da2) * rh
        if with_g:
            w[nd + i] -= gz[2, i]


@njit(nogil=True)
def radau_directions(stiffness_times, load_derivative, model, prm, theta0, omega, duration, nsteps, c, W1,
                     tape_AB, tape_piv, tape_geo, tape_rate, kl, ipar, pmode, V, P, stop):
    """Replay the tape of :func:`radau_orbit`: ``V`` (k, n) becomes ``G V`` and, unless ``pmode``
    is ``PARAM_NONE``, ``P`` (zero on entry) the derivative of the segment's end state with
    respect to the parameter (``omega`` or ``prm[ipar]``). All directions share each step's
    banded solve; ``stop``: the interruption flag, read once a step. Returns a status code."""
    n = V.shape[1]
    nd = n // 2
    q = V.shape[0]
    with_p = pmode != PARAM_NONE
    h = duration / nsteps
    RHS = np.empty((3 * nd, q + (1 if with_p else 0)))
    prhs = np.empty(3 * nd)
    tmp = np.empty(2 * nd)
    gz = np.zeros((3, nd))
    gv = np.zeros((3, nd))
    ld = np.empty(nd)
    for k in range(nsteps):
        if stop_requested(stop):
            return INTERRUPTED
        AB, piv, geo3, rates = tape_AB[k], tape_piv[k], tape_geo[k], tape_rate[k]
        _plain_rhs(stiffness_times, model, geo3, W1, h, V, RHS, tmp)
        if with_p:
            for s in range(3):
                if pmode == PARAM_OMEGA:
                    for i in range(nd):
                        gz[s, i] = -rates[s, i] / omega
                        gv[s, i] = -rates[s, nd + i] / omega
                else:
                    load_derivative(theta0 + omega * h * (k + c[s]), model, prm, ipar, ld)
                    for i in range(nd):
                        gv[s, i] = ld[i] / model.mass[i]
            _parameter_rhs(stiffness_times, model, geo3, W1, h, P, gz, gv, prhs, tmp)
            for i in range(3 * nd):
                RHS[i, q] = prhs[i]
        bandlu.solve_many(AB, kl, kl, piv, RHS)
        for j in range(q):
            _update(V[j], RHS, j, W1, h, nd, gz, False)
        if with_p:
            _update(P, RHS, q, W1, h, nd, gz, True)
    for j in range(q):
        for i in range(n):
            if not np.isfinite(V[j, i]):
                return NONFINITE
    for i in range(n):
        if not np.isfinite(P[i]):
            return NONFINITE
    return OK
