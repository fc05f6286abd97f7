"""Slack onsets and re-tightenings of the exact analysis, located inside the integrators.

A segment is taut or slack (its *mode*, ``taut`` of the :class:`~cablesim.mechanics.model.Workspace`):
within a step the vector field of the current modes is smooth, a taut segment acting as a linear
spring and a slack one contributing nothing. After every step the gap ``g = l - S`` of each
segment is sampled on the step's cubic Hermite interpolant of ``z`` (``NSAMP`` points). Where a
taut segment's gap turns negative or a slack one's positive, the crossing is located by the
Illinois method on the interpolant to :data:`T_TOL` s, the step is cut there and the integration
restarts in the new modes, so no step straddles the kink of ``T = EA max(l - S, 0) / S``.

Chatter: a segment that changes mode again within :data:`CHATTER_WINDOW` of its previous
transition keeps its new mode for that window (its transitions there are not located; the
first transition found after the window is taken at the window's end). Such holds are counted.
"""

from __future__ import annotations

import numpy as np
from ...jit import njit

from ...mechanics import segments as sg
from ...mechanics.supports import support_positions
from ..peaks import step_peaks
from .base import hermite_weights

#: Samples of the gaps per step.
NSAMP = 4
#: Width of the bracket at which a located event is accepted, s.
T_TOL = 1e-10
#: A segment changing mode again within this time (s) of its last transition keeps its mode for it.
CHATTER_WINDOW = 1e-6
#: How chattering segments are handled, in words (stored with every result).
CHATTER_TEXT = (
    f"chatter: a segment changing mode within {CHATTER_WINDOW:g} s of its previous transition keeps its new mode "
    f"for {CHATTER_WINDOW:g} s (transitions in that window are not located; one found after it is taken "
    "at the window's end)"
)


@njit
def _config_at(model, t, ta, tb, sa, sb, y):
    """``y = y0 + z(t)`` from the cubic Hermite interpolant of z (values and velocities)."""
    nd = y.size
    h00, h10, h01, h11 = hermite_weights(ta, tb, t)
    y0 = model.y0
    for i in range(nd):
        y[i] = y0[i] + h00 * sa[i] + h10 * sa[nd + i] + h01 * sb[i] + h11 * sb[nd + i]


@njit
def _signed_gap(model, t, ta, tb, sa, sb, k, y, sign):
    _config_at(model, t, ta, tb, sa, sb, y)
    A, B = support_positions(model, t)
    return sign * sg.gap(y, k, model.S, A, B)


@njit
def _root(model, ta, tb, sa, sb, k, lo, hi, y, sign):
    """Illinois on ``sign * g_k`` (>= 0 at lo, < 0 at hi); returns the bracket's end past the root."""
    flo = _signed_gap(model, lo, ta, tb, sa, sb, k, y, sign)
    if flo < 0.0:
        return lo  # already across at the start of the bracket (end of a chatter hold)
    fhi = _signed_gap(model, hi, ta, tb, sa, sb, k, y, sign)
    side = 0
    for _ in range(200):
        if hi - lo <= T_TOL:
            break
        c = (lo * fhi - hi * flo) / (fhi - flo)
        if not (lo < c < hi):
            c = 0.5 * (lo + hi)
        fc = _signed_gap(model, c, ta, tb, sa, sb, k, y, sign)
        if fc < 0.0:
            hi, fhi = c, fc
            if side == -1:
                flo *= 0.5
            side = -1
        else:
            lo, flo = c, fc
            if side == 1:
                fhi *= 0.5
            side = 1
    return hi


@njit
def locate_event(model, ta, tb, sa, sb, taut, evw):
    """The first mode change in ``(ta, tb]`` on the step's interpolant: ``(t_event, segment)``,
    or ``(tb, -1)``. ``sa``, ``sb`` start with ``(z, y')``; ``evw`` is :func:`event_workspace`.
    Peak tensions ``EA max(g, 0) / S`` up to the event are located on the interpolant
    (:func:`cablesim.dynamics.peaks.step_peaks`)."""
    hold, y, g, peak, peak_t = evw
    S = model.S
    t_prev = ta
    for i in range(1, NSAMP + 1):
        ts = tb if i == NSAMP else ta + (tb - ta) * i / NSAMP
        _config_at(model, ts, ta, tb, sa, sb, y)
        A, B = support_positions(model, ts)
        sg.gaps(y, S, A, B, g)
        best_t = np.inf
        best_k = -1
        for k in range(S.size):
            sign = 1.0 if taut[k] > 0.5 else -1.0
            if hold[k] < ts and sign * g[k] < -1e-14 * S[k]:
                te = _root(model, ta, tb, sa, sb, k, max(t_prev, hold[k]), ts, y, sign)
                if te < best_t:
                    best_t, best_k = te, k
        if best_k >= 0:
            step_peaks(model, ta, best_t, tb, sa, sb, peak, peak_t)
            return best_t, best_k
        t_prev = ts
    step_peaks(model, ta, tb, tb, sa, sb, peak, peak_t)
    return tb, -1


def event_workspace(n_segments: int, n_dof: int):
    """``(hold, y, g, peak, peak_t)``: chatter holds (s), scratch configuration and gaps, and the
    peak tension of each segment (N) with its time (s)."""
    return (np.full(n_segments, -np.inf), np.empty(n_dof), np.empty(n_segments),
            np.zeros(n_segments), np.zeros(n_segments))


def start_events(eom, state) -> bool:
    """Set up slack tracking in ``state`` (modes from the initial gaps); whether it is on."""
    c = eom.cable
    taut = state.wk[0].taut
    taut[:] = 1.0
    evw = event_workspace(c.n_segments, eom.n_dof)
    on = eom.continues_slack
    if on:
        A, B = support_positions(eom.model(), float(state.t))
        y = eom.y0 + state.s[: eom.n_dof]
        sg.taut_modes(y, c.S, A, B, taut)
        g = np.empty(c.n_segments)
        sg.gaps(y, c.S, A, B, g)
        evw[3][:] = [sg.tension_of_stretch(max(gk, 0.0), Sk, c.EA) for gk, Sk in zip(g, c.S)]
        evw[4][:] = state.t
    state.extra.update(track=on, evw=evw, events=[], last_event=np.full(c.n_segments, -np.inf),
                       chatter_holds=0, initially_slack=taut < 0.5)
    return on


def transition(state, k: int, t: float) -> None:
    """Segment ``k`` (0-based) changes mode at ``t``: flip it, record the event, hold a chatterer."""
    ex = state.extra
    taut = state.wk[0].taut
    taut[k] = 0.0 if taut[k] > 0.5 else 1.0
    ex["events"].append((float(t), int(k), "taut" if taut[k] > 0.5 else "slack"))
    if t - ex["last_event"][k] < CHATTER_WINDOW:
        ex["evw"][0][k] = t + CHATTER_WINDOW
        ex["chatter_holds"] += 1
    ex["last_event"][k] = t
