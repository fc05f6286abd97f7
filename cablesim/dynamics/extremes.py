"""Extremes of sampled signals, located between the samples on their Hermite interpolant.

Every extreme cablesim reports (a sweep point's peak ``|z|`` and half range, the largest ``|z|``
over a periodic orbit, a segment's peak tension in a sweep or a time history) is the extreme of
a signal known at samples together with its rate there: the displacements with the velocities,
the state of an orbit with its vector field, a segment's gap ``g = l - S`` with ``g'``. Between
two samples ``t_a``, ``t_b = t_a + h`` the signal is taken to be the cubic Hermite interpolant
through ``(x_a, x'_a)`` and ``(x_b, x'_b)``, whose stationary points solve a quadratic
(:func:`hermite_stationary`); where the curvatures ``x''`` are known too (a sweep's samples
carry ``y''``) the quintic Hermite interpolant refines the stationary point by Newton's method
(:func:`hermite_extreme`). The extreme of a record is the largest of its samples and of these
interior stationary values (:func:`record_extremes`). The error is that of the interpolant at
its vertex: ``h^4 |x''''| / 384`` for the cubic, ``h^6 |x^(6)| / 46080`` for the quintic, so a
sinusoid sampled 128 times a period is located to 1.5e-8 and 3e-13 of its amplitude, whatever
the phase of the samples, and without bias.

A parabola through the largest sample and its two neighbours is exact only to O(h^2), and the
vertex formula must carry its factor ``1/8``: ``b - (a - c)^2 / (8 (a - 2b + c))`` (with ``1/4`` it
doubles the correction and overshoots by up to 3e-4 of the amplitude at 128 samples a period,
always upwards). :func:`parabola_vertex` keeps the correct formula for signals known without
their rates.

The functions are compiled (numba), so that the integrators' event kernels and the shooting
kernels call the same code as the Python drivers.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit


@njit
def hermite_stationary(xa, xb, da, db, h):
    """Stationary points of the cubic Hermite interpolant, as fractions ``s`` of the interval.

    Parameters
    ----------
    xa, xb : float
        Values at the ends of the interval.
    da, db : float
        Rates (time derivatives) there.
    h : float
        Length of the interval (time).

    Returns
    -------
    (float, float)
        The two roots of ``p'(s) = 0`` (``-1`` where there is none).
    """
    ha = h * da
    hb = h * db
    # p'(s) = a s^2 + b s + c on s in [0, 1]
    a = 6.0 * xa + 3.0 * ha - 6.0 * xb + 3.0 * hb
    b = -6.0 * xa - 4.0 * ha + 6.0 * xb - 2.0 * hb
    c = ha
    r0 = -1.0
    r1 = -1.0
    scale = abs(a) + abs(b) + abs(c)
    if scale == 0.0:
        return r0, r1
    if abs(a) <= 1e-12 * scale:
        if b != 0.0:
            r0 = -c / b
    else:
        disc = b * b - 4.0 * a * c
        if disc >= 0.0:
            sq = np.sqrt(disc)
            q = -0.5 * (b + sq) if b >= 0.0 else -0.5 * (b - sq)
            r0 = q / a
            if q != 0.0:
                r1 = c / q
    return r0, r1


@njit
def hermite_value(xa, xb, da, db, h, s):
    """The cubic Hermite interpolant at the fraction ``s`` of the interval."""
    s2 = s * s
    s3 = s2 * s
    return ((2.0 * s3 - 3.0 * s2 + 1.0) * xa + (s3 - 2.0 * s2 + s) * h * da
            + (-2.0 * s3 + 3.0 * s2) * xb + (s3 - s2) * h * db)


@njit
def _quintic_slope(xa, xb, da, db, ca, cb, h, s):
    """``(p'(s), p''(s))`` (per unit s) of the quintic Hermite interpolant."""
    ha, hb = h * da, h * db
    qa, qb = h * h * ca, h * h * cb
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    d = ((-30.0 * s2 + 60.0 * s3 - 30.0 * s4) * (xa - xb) + (1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4) * ha
         + (-12.0 * s2 + 28.0 * s3 - 15.0 * s4) * hb + (s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4) * qa
         + (1.5 * s2 - 4.0 * s3 + 2.5 * s4) * qb)
    dd = ((-60.0 * s + 180.0 * s2 - 120.0 * s3) * (xa - xb) + (-36.0 * s + 96.0 * s2 - 60.0 * s3) * ha
          + (-24.0 * s + 84.0 * s2 - 60.0 * s3) * hb + (1.0 - 9.0 * s + 18.0 * s2 - 10.0 * s3) * qa
          + (3.0 * s - 12.0 * s2 + 10.0 * s3) * qb)
    return d, dd


@njit
def _quintic_value(xa, xb, da, db, ca, cb, h, s):
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    s5 = s4 * s
    return ((1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5) * xa + (10.0 * s3 - 15.0 * s4 + 6.0 * s5) * xb
            + (s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5) * h * da + (-4.0 * s3 + 7.0 * s4 - 3.0 * s5) * h * db
            + 0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5) * h * h * ca + 0.5 * (s3 - 2.0 * s4 + s5) * h * h * cb)


@njit
def hermite_extreme(xa, xb, da, db, ca, cb, h, sign):
    """The largest interior stationary value of ``sign * x`` between two samples.

    Parameters
    ----------
    xa, xb, da, db, h : float
        As in :func:`hermite_stationary`.
    ca, cb : float
        Second derivatives at the ends, or NaN when they are not known: the cubic's stationary
        point is then the answer; otherwise Newton's method refines it on the quintic Hermite
        interpolant (kept only if it stays inside the interval).
    sign : float
        ``1.0`` for a maximum, ``-1.0`` for a minimum.

    Returns
    -------
    (float, float)
        ``(s, x(s))``: the fraction of the interval and the value there (the value itself, not
        ``sign`` times it); ``(-1.0, NaN)`` when no interior stationary point is an extreme of
        that kind.
    """
    r0, r1 = hermite_stationary(xa, xb, da, db, h)
    best_s = -1.0
    best = -np.inf
    for r in range(2):
        s = r0 if r == 0 else r1
        if 0.0 < s < 1.0:
            v = sign * hermite_value(xa, xb, da, db, h, s)
            if v > best:
                best, best_s = v, s
    if best_s < 0.0:
        return -1.0, np.nan
    if np.isfinite(ca) and np.isfinite(cb):
        s = best_s
        for _ in range(8):
            d, dd = _quintic_slope(xa, xb, da, db, ca, cb, h, s)
            if dd == 0.0:
                break
            step = d / dd
            s -= step
            if not (0.0 < s < 1.0):
                s = best_s  # Newton left the interval: keep the cubic's point
                break
            if abs(step) < 1e-15:
                break
        return s, _quintic_value(xa, xb, da, db, ca, cb, h, s)
    return best_s, sign * best


@njit
def record_extremes(t, x, dx, ddx, period):
    """Largest and smallest value of a sampled signal, with their times.

    Parameters
    ----------
    t : ndarray (m,)
        Sample times, ascending, s.
    x, dx : ndarray (m,)
        Values and their time derivatives.
    ddx : ndarray (m,) or (0,)
        Second derivatives (empty when not known).
    period : float
        For a periodic record (``x(t + period) = x(t)``, the samples spanning one period with the
        first sample after the last one's image), the interval from the last sample to the first
        one's next image is searched too; 0 for a record that is not periodic.

    Returns
    -------
    (xmax, t_max, xmin, t_min) : floats
    """
    m = x.size
    xmax, tmax = x[0], t[0]
    xmin, tmin = x[0], t[0]
    for i in range(1, m):
        if x[i] > xmax:
            xmax, tmax = x[i], t[i]
        if x[i] < xmin:
            xmin, tmin = x[i], t[i]
    curv = ddx.size == m
    last = m if period > 0.0 else m - 1
    for i in range(last):
        j = i + 1 if i + 1 < m else 0
        ta = t[i]
        h = (t[j] if j > 0 else t[0] + period) - ta
        if not h > 0.0:
            continue
        ca = ddx[i] if curv else np.nan
        cb = ddx[j] if curv else np.nan
        s, v = hermite_extreme(x[i], x[j], dx[i], dx[j], ca, cb, h, 1.0)
        if s > 0.0 and v > xmax:
            xmax, tmax = v, ta + s * h
        s, v = hermite_extreme(x[i], x[j], dx[i], dx[j], ca, cb, h, -1.0)
        if s > 0.0 and v < xmin:
            xmin, tmin = v, ta + s * h
    return xmax, tmax, xmin, tmin


def signal_extremes(t, x, dx, ddx=None, period: float = 0.0):
    """Extremes of each column of a sampled signal (see :func:`record_extremes`).

    Parameters
    ----------
    t : array_like (m,)
        Sample times, s.
    x, dx : array_like (m,) or (m, c)
        Values and their time derivatives (columns: channels).
    ddx : array_like, optional
        Second derivatives, same shape (refines each extreme on the quintic interpolant).
    period : float
        The record's period, s, when it spans exactly one (0: not periodic).

    Returns
    -------
    xmax, t_max, xmin, t_min : ndarray (c,)
        Largest and smallest values and when they occur.
    """
    t = np.ascontiguousarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    col = x.ndim == 1
    X = x.reshape(x.shape[0], -1)
    D = np.asarray(dx, dtype=float).reshape(X.shape)
    C = None if ddx is None else np.asarray(ddx, dtype=float).reshape(X.shape)
    none = np.empty(0)
    out = np.empty((4, X.shape[1]))
    for c in range(X.shape[1]):
        out[:, c] = record_extremes(t, np.ascontiguousarray(X[:, c]), np.ascontiguousarray(D[:, c]),
                                    none if C is None else np.ascontiguousarray(C[:, c]), float(period))
    if col:
        return tuple(float(v) for v in out[:, 0])
    return out[0], out[1], out[2], out[3]


def peak_and_half_range(t, z, v, a=None, period: float = 0.0):
    """Peak ``|z|`` and half the peak-to-peak range of each column, located between samples.

    Parameters
    ----------
    t : array_like (m,)
        Sample times, s.
    z, v : array_like (m, c)
        Displacements (m) and velocities (m/s).
    a : array_like (m, c), optional
        Accelerations (m/s^2).
    period : float
        The record's period, s, when it spans exactly one orbit (0: not periodic).

    Returns
    -------
    amplitude, halfrange : ndarray (c,)
    """
    zmax, _, zmin, _ = signal_extremes(t, np.asarray(z).reshape(len(t), -1), np.asarray(v).reshape(len(t), -1),
                                       None if a is None else np.asarray(a).reshape(len(t), -1), period)
    return np.maximum(np.abs(zmax), np.abs(zmin)), 0.5 * (zmax - zmin)


def parabola_vertex(a: float, b: float, c: float) -> tuple[float, float]:
    """Vertex of the parabola through ``(-1, a)``, ``(0, b)``, ``(1, c)``: ``(offset, value)``.

    For signals known only at equally spaced samples (no rates); exact for a parabola, O(h^2)
    otherwise. Returns ``(0, b)`` when the three points are collinear.
    """
    den = a - 2.0 * b + c
    if den == 0.0:
        return 0.0, b
    s = 0.5 * (a - c) / den
    return s, b - 0.125 * (a - c) ** 2 / den
