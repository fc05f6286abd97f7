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
from .extremes import hermite_extreme

#: Samples of the gaps per step (the peak search brackets sign changes of g' between them).
PEAK_SAMPLES = 4
#: Width (s) below which a located peak's time is accepted.
T_TOL_PEAK = 1e-12


@njit
def gap_and_rate(ta, tb, sa, sb, y0, S, L, H, k, t):
    """``(g, g')`` of segment ``k`` at ``t`` on the cubic Hermite interpolant of ``z`` between
    ``(ta, sa)`` and ``(tb, sb)`` (``sa``, ``sb`` start with ``(z, y')``)."""
    nd = y0.size
    n = S.size - 1
    h = tb - ta
    s = (t - ta) / h
    s2 = s * s
    s3 = s2 * s
    w0, w1, w2, w3 = 2.0 * s3 - 3.0 * s2 + 1.0, (s3 - 2.0 * s2 + s) * h, -2.0 * s3 + 3.0 * s2, (s3 - s2) * h
    d0, d1, d2, d3 = (6.0 * s2 - 6.0 * s) / h, 3.0 * s2 - 4.0 * s + 1.0, (-6.0 * s2 + 6.0 * s) / h, 3.0 * s2 - 2.0 * s
    px = py = vx = vy = 0.0
    for side in range(2):
        node = k - 1 + side  # 0-based interior node at this end of the segment, or a support
        if node < 0:
            x, y, u, v = 0.0, 0.0, 0.0, 0.0
        elif node >= n:
            x, y, u, v = L, H, 0.0, 0.0
        else:
            i, j = 2 * node, 2 * node + 1
            x = y0[i] + w0 * sa[i] + w1 * sa[nd + i] + w2 * sb[i] + w3 * sb[nd + i]
            y = y0[j] + w0 * sa[j] + w1 * sa[nd + j] + w2 * sb[j] + w3 * sb[nd + j]
            u = d0 * sa[i] + d1 * sa[nd + i] + d2 * sb[i] + d3 * sb[nd + i]
            v = d0 * sa[j] + d1 * sa[nd + j] + d2 * sb[j] + d3 * sb[nd + j]
        sg = 1.0 if side == 1 else -1.0
        px += sg * x
        py += sg * y
        vx += sg * u
        vy += sg * v
    l = np.sqrt(px * px + py * py)
    return l - S[k], (px * vx + py * vy) / l


@njit
def _locate_max(ta, tb, sa, sb, y0, S, L, H, k, lo, g_lo, r_lo, hi, g_hi, r_hi):
    """``(t, g)`` of the maximum of g in ``[lo, hi]`` (``r_lo > 0 >= r_hi``) on the interpolant."""
    t_best, g_best = (lo, g_lo) if g_lo >= g_hi else (hi, g_hi)
    t_prev = np.inf
    for _ in range(60):
        w = hi - lo
        s, _v = hermite_extreme(g_lo, g_hi, r_lo, r_hi, np.nan, np.nan, w, 1.0)
        tc = lo + s * w if 0.0 < s < 1.0 else 0.5 * (lo + hi)
        gc, rc = gap_and_rate(ta, tb, sa, sb, y0, S, L, H, k, tc)
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
def _end_gap(y0, sv, nd, n, S, L, H, k):
    """``(g, g')`` of segment k in the state ``sv`` (starting with ``(z, y')``) itself."""
    if k == 0:
        xa = ya = ua = va = 0.0
    else:
        p, q = 2 * k - 2, 2 * k - 1
        xa, ya, ua, va = y0[p] + sv[p], y0[q] + sv[q], sv[nd + p], sv[nd + q]
    if k == n:
        xb, yb, ub, vb = L, H, 0.0, 0.0
    else:
        p, q = 2 * k, 2 * k + 1
        xb, yb, ub, vb = y0[p] + sv[p], y0[q] + sv[q], sv[nd + p], sv[nd + q]
    dx, dy = xb - xa, yb - ya
    l = np.sqrt(dx * dx + dy * dy)
    return l - S[k], (dx * (ub - ua) + dy * (vb - va)) / l


@njit
def _raise(peak, peak_t, k, EA, S, t, g):
    T = EA * max(g, 0.0) / S[k]
    if T > peak[k]:
        peak[k] = T
        peak_t[k] = t


@njit
def step_peaks(ta, t_end, tb, sa, sb, y0, S, EA, L, H, peak, peak_t):
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
    nd = y0.size
    n = S.size - 1
    for k in range(S.size):
        g0, r0 = _end_gap(y0, sa, nd, n, S, L, H, k)
        if t_end == tb:
            g1, r1 = _end_gap(y0, sb, nd, n, S, L, H, k)
        else:
            g1, r1 = gap_and_rate(ta, tb, sa, sb, y0, S, L, H, k, t_end)
        if max(g0, g1) > 0.0 and r0 > 0.0 and r1 <= 0.0:
            tm, gm = _locate_max(ta, tb, sa, sb, y0, S, L, H, k, ta, g0, r0, t_end, g1, r1)
            _raise(peak, peak_t, k, EA, S, tm, gm)
            continue
        _raise(peak, peak_t, k, EA, S, t_end, g1)
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
            ga, ra = (g1, r1) if i == PEAK_SAMPLES else gap_and_rate(ta, tb, sa, sb, y0, S, L, H, k, t1)
            if max(g0, ga) > 0.0 and r0 > 0.0 and ra <= 0.0:
                tm, gm = _locate_max(ta, tb, sa, sb, y0, S, L, H, k, t0, g0, r0, t1, ga, ra)
                _raise(peak, peak_t, k, EA, S, tm, gm)
            else:
                _raise(peak, peak_t, k, EA, S, t1, ga)
            t0, g0, r0 = t1, ga, ra


def tension_rates(y: np.ndarray, v: np.ndarray, S: np.ndarray, EA: float, L: float, H: float) -> np.ndarray:
    """``dT/dt`` of every segment at saved states (tension-only: zero where slack).

    Parameters
    ----------
    y, v : ndarray (m, 2n)
        Absolute configurations (m) and velocities (m/s).
    S : ndarray (n + 1,)
        Natural lengths, m.
    EA : float
        Axial rigidity, N.
    L, H : float
        Support B's position, m.

    Returns
    -------
    ndarray (m, n + 1)
        Tension rates, N/s.
    """
    m = y.shape[0]
    pts = np.concatenate([np.zeros((m, 1, 2)), y.reshape(m, -1, 2), np.broadcast_to([L, H], (m, 1, 2))], axis=1)
    vel = np.concatenate([np.zeros((m, 1, 2)), v.reshape(m, -1, 2), np.zeros((m, 1, 2))], axis=1)
    d = np.diff(pts, axis=1)
    dv = np.diff(vel, axis=1)
    l = np.sqrt((d**2).sum(axis=2))
    rate = EA / S * (d * dv).sum(axis=2) / l
    return np.where(l > S, rate, 0.0)
