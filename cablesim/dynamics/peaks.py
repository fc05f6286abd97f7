"""Peak tensions (snap loads) located on a step's interpolant, and tension rates of saved states.

Inside a step the configuration is the cubic Hermite interpolant of ``z`` through its values and
velocities at the step's ends (the interpolant the slack events are located on,
:mod:`cablesim.dynamics.integrators.events`). A segment's gap ``g = l - S`` and its rate
``g' = (d . d') / l`` (``d`` the segment's difference vector) are sampled on it; where ``g'``
changes sign from positive to negative between two samples the maximum of ``g`` is located on
the interpolant by iterating :func:`cablesim.dynamics.extremes.hermite_extreme` on
``(g, g')`` over a shrinking bracket (each iterate is the vertex of the cubic through the
bracket's ends, a safeguarded secant-like step of high order), to :data:`T_TOL_PEAK` s. A step
whose end values show no turn of ``g`` is searched further only where the cubic through them
turns inside it (:func:`step_peaks`). The
peak tension is ``EA g / S`` there: the snap load and its time are then as accurate as the
interpolant, not limited to the samples.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..mechanics import segments as sg
from ..mechanics.supports import support_positions, support_velocities
from ..mechanics.vectors import vadd, vdot, vload, vscale, vsub
from .extremes import hermite_extreme

#: Samples of the gaps per step (the peak search brackets sign changes of g' between them).
PEAK_SAMPLES = 4
#: Width (s) below which a located peak's time is accepted.
T_TOL_PEAK = 1e-12


@njit(inline="always")
def _node_state(model, j, t, ta, tb, sa, sb, w, d):
    """Position and velocity of node ``j`` (``-1``: A, ``n``: B) at ``t`` on the interpolant
    (``w``, ``d``: the Hermite weights of the values and of the rates at ``t``)."""
    n = model.S.size - 1
    nd = model.mass.size
    if j < 0 or j >= n:
        A, B = support_positions(model, t)
        vA, vB = support_velocities(model, t)
        return (A, vA) if j < 0 else (B, vB)
    i = len(model.A) * j
    z = vadd(vadd(vscale(vload(sa, i, model.A), w[0]), vscale(vload(sa, nd + i, model.A), w[1])),
             vadd(vscale(vload(sb, i, model.A), w[2]), vscale(vload(sb, nd + i, model.A), w[3])))
    v = vadd(vadd(vscale(vload(sa, i, model.A), d[0]), vscale(vload(sa, nd + i, model.A), d[1])),
             vadd(vscale(vload(sb, i, model.A), d[2]), vscale(vload(sb, nd + i, model.A), d[3])))
    return vadd(vload(model.y0, i, model.A), z), v


@njit
def gap_and_rate(model, ta, tb, sa, sb, k, t):
    """``(g, g')`` of segment ``k`` at ``t`` on the cubic Hermite interpolant of ``z`` between
    ``(ta, sa)`` and ``(tb, sb)`` (``sa``, ``sb`` start with ``(z, y')``), the supports where
    they are at ``t``."""
    h = tb - ta
    s = (t - ta) / h
    s2 = s * s
    s3 = s2 * s
    w = (2.0 * s3 - 3.0 * s2 + 1.0, (s3 - 2.0 * s2 + s) * h, -2.0 * s3 + 3.0 * s2, (s3 - s2) * h)
    d = ((6.0 * s2 - 6.0 * s) / h, 3.0 * s2 - 4.0 * s + 1.0, (-6.0 * s2 + 6.0 * s) / h, 3.0 * s2 - 2.0 * s)
    pa, va = _node_state(model, k - 1, t, ta, tb, sa, sb, w, d)
    pb, vb = _node_state(model, k, t, ta, tb, sa, sb, w, d)
    dv = vsub(pb, pa)
    l = sg.length(dv)
    return l - model.S[k], vdot(dv, vsub(vb, va)) / l


@njit
def _locate_max(model, ta, tb, sa, sb, k, lo, g_lo, r_lo, hi, g_hi, r_hi):
    """``(t, g)`` of the maximum of g in ``[lo, hi]`` (``r_lo > 0 >= r_hi``) on the interpolant."""
    t_best, g_best = (lo, g_lo) if g_lo >= g_hi else (hi, g_hi)
    t_prev = np.inf
    for _ in range(60):
        w = hi - lo
        s, _v = hermite_extreme(g_lo, g_hi, r_lo, r_hi, np.nan, np.nan, w, 1.0)
        tc = lo + s * w if 0.0 < s < 1.0 else 0.5 * (lo + hi)
        gc, rc = gap_and_rate(model, ta, tb, sa, sb, k, tc)
        if gc > g_best:
            t_best, g_best = tc, gc
        if abs(tc - t_prev) <= T_TOL_PEAK or w <= T_TOL_PEAK:
            break
        t_prev = tc
        if rc > 0.0:
            lo, g_lo, r_lo = tc, gc, rc
        else:
            hi, g_hi, r_hi = tc, gc, rc
    return t_best, g_best


@njit
def _end_gap(model, sv, t, k):
    """``(g, g')`` of segment k in the state ``sv`` (starting with ``(z, y')``) at ``t`` itself."""
    n = model.S.size - 1
    nd = model.mass.size
    A, B = support_positions(model, t)
    vA, vB = support_velocities(model, t)
    dim = len(model.A)
    if k == 0:
        pa, va = A, vA
    else:
        i = dim * (k - 1)
        pa, va = vadd(vload(model.y0, i, A), vload(sv, i, A)), vload(sv, nd + i, A)
    if k == n:
        pb, vb = B, vB
    else:
        i = dim * k
        pb, vb = vadd(vload(model.y0, i, A), vload(sv, i, A)), vload(sv, nd + i, A)
    d = vsub(pb, pa)
    l = sg.length(d)
    return l - model.S[k], vdot(d, vsub(vb, va)) / l


@njit
def _raise(peak, peak_t, k, model, t, g):
    T = sg.tension_of_stretch(max(g, 0.0), model.S[k], model.EA)
    if T > peak[k]:
        peak[k] = T
        peak_t[k] = t


@njit
def step_peaks(model, ta, t_end, tb, sa, sb, peak, peak_t):
    """Raise ``peak[k]`` (N) and ``peak_t[k]`` (s) with segment k's largest tension over
    ``[ta, t_end]`` of the step ``[ta, tb]`` (``t_end <= tb``: the step may end at an event),
    located on the step's interpolant (module docstring).

    The ends first: where ``g'`` falls through zero between them the maximum is located at once;
    where the cubic through ``(g, g')`` at the ends has an interior maximum (the gap may turn
    within the step without the ends showing it) the step is searched at
    :data:`PEAK_SAMPLES` samples; otherwise ``g`` is monotone over the step and its ends are
    its extremes (so most steps cost two evaluations a segment, from the states themselves).
    """
    if not t_end > ta:
        return
    for k in range(model.S.size):
        g0, r0 = _end_gap(model, sa, ta, k)
        if t_end == tb:
            g1, r1 = _end_gap(model, sb, tb, k)
        else:
            g1, r1 = gap_and_rate(model, ta, tb, sa, sb, k, t_end)
        if max(g0, g1) > 0.0 and r0 > 0.0 and r1 <= 0.0:
            tm, gm = _locate_max(model, ta, tb, sa, sb, k, ta, g0, r0, t_end, g1, r1)
            _raise(peak, peak_t, k, model, tm, gm)
            continue
        _raise(peak, peak_t, k, model, t_end, g1)
        w = t_end - ta
        slope = (g1 - g0) / w
        if slope != 0.0 and 0.0 <= r0 / slope <= 3.0 and 0.0 <= r1 / slope <= 3.0:
            continue  # the cubic is monotone (Fritsch and Carlson's sufficient condition)
        s, _v = hermite_extreme(g0, g1, r0, r1, np.nan, np.nan, w, 1.0)
        if s < 0.0:
            continue
        t0 = ta
        for i in range(1, PEAK_SAMPLES + 1):
            t1 = t_end if i == PEAK_SAMPLES else ta + (t_end - ta) * i / PEAK_SAMPLES
            ga, ra = (g1, r1) if i == PEAK_SAMPLES else gap_and_rate(model, ta, tb, sa, sb, k, t1)
            if max(g0, ga) > 0.0 and r0 > 0.0 and ra <= 0.0:
                tm, gm = _locate_max(model, ta, tb, sa, sb, k, t0, g0, r0, t1, ga, ra)
                _raise(peak, peak_t, k, model, tm, gm)
            else:
                _raise(peak, peak_t, k, model, t1, ga)
            t0, g0, r0 = t1, ga, ra


@njit
def tension_rates(model, t, s, out):
    """``dT/dt`` of every segment at the saved states ``s`` (rows ``(z, y', ...)``) at times ``t``
    (tension-only: zero where slack), N/s, into ``out`` (m, n + 1)."""
    for i in range(t.size):
        for k in range(model.S.size):
            g, r = _end_gap(model, s[i], t[i], k)
            out[i, k] = sg.tension_of_stretch(r, model.S[k], model.EA) if g > 0.0 else 0.0
