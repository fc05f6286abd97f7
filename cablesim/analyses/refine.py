"""Where a sweep's grid is too coarse: the frequencies to add between neighbouring points.

A grid of forcing frequencies samples the response; a peak narrower than the step, a jump or a
band of another response period (the 1/2 subharmonic near twice a natural frequency) can fall
between two points that agree. After each round of points, every interval between neighbours
is halved (its midpoint computed next) where, on any curve,

1. the two points differ in outcome: response period, steady or not, stopped early or not;
2. their amplitudes differ by more than :data:`RESOLUTION` of the curve's largest (the curve
   is not resolved: a steep flank, a jump);
3. one is a local maximum of a channel's amplitude and the other is more than
   :data:`PEAK_TOLERANCE` below it (the peak is not yet pinned down);
4. one has a Floquet multiplier within :data:`NEAR_UNIT` of +1 or -1 (a fold or a period
   doubling may lie between them; multipliers are known where shooting decided the point),
   while the interval is at least eight times the finest step (the first halvings);

until the step has been halved ``levels`` times (``sweep.refine``) or the sweep has gained
:data:`BUDGET` times as many points as its grid had, and :data:`BUDGET_FLOOR` more (the widest
flagged intervals first).
The rules read only results, so a resumed sweep adds exactly the points the uninterrupted one
adds.
"""

from __future__ import annotations

import numpy as np

#: Neighbours whose amplitudes differ by more than this fraction of the curve's largest are
#: refined (rule 2).
RESOLUTION = 0.05
#: A peak is refined until its neighbours are within this fraction of it (rule 3).
PEAK_TOLERANCE = 0.005
#: Local maxima below this fraction of the curve's largest are not peaks (numerical ripple).
PEAK_FLOOR = 0.02
#: A multiplier this close to +1 or -1 marks a possible bifurcation (rule 4).
NEAR_UNIT = 0.05
#: Refinement adds at most this many times the grid's points, and this many more.
BUDGET = 2
BUDGET_FLOOR = 40


def finest_step(grid: np.ndarray, levels: int) -> float:
    """The smallest interval refinement may create: the grid's smallest step over 2**levels."""
    steps = np.diff(np.unique(grid))
    return float(steps.min()) / 2.0 ** levels if steps.size and levels > 0 else np.inf


def _outcome(table, i: int) -> tuple:
    return bool(table.failed[i]), bool(table.steady[i]), int(table.period[i])


def _near_unit(table, i: int) -> bool:
    mu = table.multipliers[i]
    mu = mu[np.isfinite(mu)]
    return bool(mu.size) and float(np.min(np.minimum(np.abs(mu - 1.0), np.abs(mu + 1.0)))) < NEAR_UNIT


def _flagged(table, omega: np.ndarray, wide: np.ndarray) -> np.ndarray:
    """Which intervals ``(omega[i], omega[i + 1])`` of one curve the rules ask to halve."""
    n = omega.size
    flag = np.zeros(max(n - 1, 0), dtype=bool)
    done, valid = table.done, table.valid
    amp = np.where(valid[:, None], table.amplitude, np.nan)
    top = np.nanmax(np.abs(amp), axis=0) if valid.any() else np.zeros(amp.shape[1])
    for i in range(n - 1):
        if not (done[i] and done[i + 1]):
            continue
        if _outcome(table, i) != _outcome(table, i + 1):
            flag[i] = True
        elif valid[i] and valid[i + 1] and np.any(np.abs(amp[i] - amp[i + 1]) > RESOLUTION * top):
            flag[i] = True
        elif wide[i] and (_near_unit(table, i) or _near_unit(table, i + 1)):
            flag[i] = True
    for c in range(amp.shape[1]):
        a = amp[:, c]
        for k in range(1, n - 1):
            lo, mid, hi = a[k - 1], a[k], a[k + 1]
            if not np.isfinite([lo, mid, hi]).all() or mid < PEAK_FLOOR * top[c] or mid < lo or mid < hi:
                continue
            flag[k - 1] |= mid - lo > PEAK_TOLERANCE * mid
            flag[k] |= mid - hi > PEAK_TOLERANCE * mid
    return flag


def refinements(omega: np.ndarray, tables, finest: float, budget: int) -> np.ndarray:
    """The frequencies to compute next: midpoints of the flagged intervals of any curve.

    Parameters
    ----------
    omega : ndarray
        The sweep's frequencies so far, ascending, rad/s.
    tables : sequence of CurveTable
        Each curve's columns over ``omega``.
    finest : float
        The smallest interval allowed (:func:`finest_step`), rad/s.
    budget : int
        Most frequencies to add (the midpoints of the widest flagged intervals first when more
        are flagged).

    Returns
    -------
    ndarray
        New frequencies, ascending (empty when the sweep is resolved).
    """
    if omega.size < 2 or budget <= 0 or not np.isfinite(finest):
        return np.empty(0)
    width = np.diff(omega)
    halvable = width >= 2.0 * finest * (1.0 - 1e-9)
    wide = width >= 8.0 * finest * (1.0 - 1e-9)
    flag = np.zeros(omega.size - 1, dtype=bool)
    for table in tables:
        flag |= _flagged(table, omega, wide)
    flag &= halvable
    mids = 0.5 * (omega[:-1] + omega[1:])
    chosen = np.flatnonzero(flag)
    chosen = chosen[np.argsort(-width[chosen], kind="stable")][:budget]
    return np.sort(mids[chosen])
