"""An orbit's slack pattern and snap loads: per segment the slack intervals within the period
and the peak tension over it.

The events come from the shooting's flows (:attr:`cablesim.orbits.shooting.Evaluation.events`,
located by :mod:`cablesim.orbits.slackflow`); the peak tension of each segment is located on
the cubic Hermite interpolant of the orbit's steps by
:func:`cablesim.dynamics.peaks.step_peaks`, the time histories' snap-load search, on the orbit
integrated once more with :data:`PEAK_REFINEMENT` times as many steps: the interpolant's error,
``h^4 |z^(4)| / 384``, left the snap load of the paper's cable at FL x 13.5 (6.3 MN) 1.4e-6 low
at the shooting's own steps, and divides by 256 on the finer ones.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from ..dynamics.peaks import step_peaks
from .shooting import Shooting

__all__ = ["PEAK_REFINEMENT", "SlackPattern", "fine_shooting", "slack_intervals", "slack_pattern"]

#: Steps of the snap-load search per step of the shooting (module docstring).
PEAK_REFINEMENT = 4


@dataclass
class SlackPattern:
    """Slack intervals and snap loads of one periodic orbit.

    Attributes
    ----------
    intervals : list of ndarray (k, 2)
        Per segment, its slack episodes as ``(onset, re-tightening)`` times, s from the orbit's
        start (phase 0): the onset in ``[0, T)``, the re-tightening after it (beyond ``T`` for
        an episode that runs through the period's end); ``[[0, T]]`` for a segment slack
        throughout, empty for one taut throughout.
    peak_tension : ndarray (n + 1,)
        Largest tension of each segment over the orbit (its snap load), N.
    peak_time : ndarray (n + 1,)
        When it occurs, s from the orbit's start.
    T : float
        The orbit's period, s.
    """

    intervals: list
    peak_tension: np.ndarray
    peak_time: np.ndarray
    T: float

    @property
    def episodes(self) -> np.ndarray:
        """Slack episodes per segment and period."""
        return np.array([len(iv) for iv in self.intervals], dtype=int)


#: The shootings at PEAK_REFINEMENT times the steps, by the shooting they refine (built once:
#: a new shooting resolves its kernels' signatures again on its first flows).
_FINE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def fine_shooting(shooting: Shooting) -> Shooting:
    """The shooting through slack of ``shooting``'s orbits at :data:`PEAK_REFINEMENT` times its
    steps (the snap loads' search)."""
    if shooting not in _FINE:
        _FINE[shooting] = Shooting(shooting.system, shooting.period, shooting.segments, shooting.parameter,
                                   shooting.scheme, shooting.steps_per_period * PEAK_REFINEMENT,
                                   shooting.step_rate / PEAK_REFINEMENT, through_slack=True)
    return _FINE[shooting]


def slack_intervals(events: np.ndarray, T: float, start_taut: np.ndarray) -> list:
    """Per segment, the slack episodes ``(onset, re-tightening)`` of an orbit of period ``T``
    (s) from its events (rows ``(t, segment, new mode)`` in time order) and the segments' modes
    at its start ``start_taut`` (1 taut, 0 slack): see :attr:`SlackPattern.intervals`."""
    out = []
    for j in range(len(start_taut)):
        ev = events[events[:, 1] == j]
        onsets = list(ev[ev[:, 2] == 0.0, 0])
        ends = list(ev[ev[:, 2] == 1.0, 0])
        if not start_taut[j]:  # slack at the start: its episode began in the previous period
            if not onsets:
                out.append(np.array([[0.0, T]]) if not ends else np.array([[0.0, ends[0]]]))
                continue
            ends = ends[1:] + [ends[0] + T]
        out.append(np.array(list(zip(onsets, ends)), dtype=float).reshape(-1, 2))
    return out


def slack_pattern(shooting, u: np.ndarray, lam: float, evaluation=None, fine_steps: list | None = None) -> SlackPattern:
    """The slack pattern and snap loads of the orbit ``u`` at parameter ``lam`` of a cable's
    :class:`~cablesim.orbits.shooting.Shooting` (its system has ``slack`` functions).

    Parameters
    ----------
    shooting : Shooting
    u : ndarray
        The orbit's unknowns.
    lam : float
        Parameter value.
    evaluation : Evaluation, optional
        The orbit's evaluation, if at hand (else the orbit is integrated for its events).
    fine_steps : list, optional
        The orbit's :meth:`~cablesim.orbits.shooting.Shooting.steps` at :data:`PEAK_REFINEMENT`
        times the shooting's steps (:func:`fine_shooting`), if at hand.
    """
    system = shooting.system
    if system.slack is None:
        raise ValueError("this system does not follow slack segments (exact analysis, supports at rest and "
                         "slack: continue only)")
    gaps, _modes = system.slack
    model = system.model
    n, m = shooting.n, shooting.segments
    if evaluation is None:
        evaluation = Shooting(system, shooting.period, m, shooting.parameter, shooting.scheme, shooting.steps_per_period,
                              shooting.step_rate, through_slack=True).evaluate(u, lam, jac=False)
    ev = evaluation
    T = shooting.period * 2.0 * np.pi / shooting.omega_of(lam)
    g = np.empty(model.S.size)
    gaps(0.0, shooting.omega_of(lam), np.ascontiguousarray(u[:n], dtype=float), model, system.prm, system.work, g)
    intervals = slack_intervals(ev.events, T, (g > 0.0).astype(float))
    peak = np.zeros(model.S.size)
    peak_t = np.zeros(model.S.size)
    dur = T / m
    pieces = fine_shooting(shooting).steps(u, lam) if fine_steps is None else fine_steps
    for k, (ts, rec) in enumerate(pieces):
        t = ts + k * dur
        for i in range(t.size - 1):
            step_peaks(model, t[i], t[i + 1], t[i + 1], rec[i, :n], rec[i + 1, :n], peak, peak_t)
    return SlackPattern(intervals, peak, peak_t, T)
