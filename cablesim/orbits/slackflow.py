"""Flow segments through slack: :func:`cablesim.orbits.kernels.flow_segment` with segment modes.

The cable's exact vector field is continuous where a segment goes slack or snaps taut again
(``T = EA max(l - S, 0) / S``: the force vanishes at the event from either side); only its
Jacobian jumps, the segment's block ``(EA / S) e e^T`` dropping to zero. Each segment therefore
carries a *mode* (taut or slack) in the field's work, as in the time histories
(:mod:`cablesim.dynamics.field`), and within a step the field is the smooth one of the current
modes: a taut segment acts as a linear spring even if it is a little shorter than ``S``, a slack
one contributes neither force nor stiffness (:func:`cablesim.orbits.cablefield.exact_field` with
``track[0] = 1``). A flow starts in the modes of its initial state's gaps (taut where
``g = l - S > 0``).

After every step the gaps at its end are checked against the modes. Where a taut segment's gap
is negative, or a slack one's positive, the step is retaken from its start with a shorter step,
its fraction ``tau`` found by the Illinois method (a bracketing secant) on the gap at the partial
step's end, to :data:`EVENT_TOL` of the step; the earliest such segment changes mode there and
the rest of the step is taken in the new modes (and checked the same way). No step straddles a
kink. The variational equations ``Y' = J Y`` follow the same partial steps with the Jacobian of
the current modes: the saltation matrix of a transversal event,
``S = I + (f+ - f-) n^T / (n^T f-)``, is the identity because ``f+ = f-`` at the event, so the
monodromy of an orbit through slack is the product of the smooth pieces' variational flows, cut
at the events (docs/theory.md, "Periodic orbits through slack"). The derivative of the event
time with respect to the state drops out for the same reason (up to the integration error).

Limits, stated: the gaps are checked at the steps' ends only, so an episode (slack or taut)
shorter than a step that begins and ends inside one step is not seen (near grazing, where
episodes shrink to nothing); a segment that changes mode twice within :data:`CHATTER_WINDOW`
seconds is chatter, which the time histories hold off by a rule but a periodic orbit does not
follow: the flow returns ``CHATTER``. Every event is recorded: ``events[i] = (t, k, mode)``,
``t`` from the segment's start (s), ``k`` the segment, ``mode`` the new one (0 slack: an onset;
1 taut: a re-tightening).

A system that tracks modes provides, beside its field, ``gaps(theta, omega, x, model, prm,
work, g)`` (the gaps ``l - S``, m) and ``modes(work) -> (taut, track)``
(:func:`cablesim.orbits.cablefield.exact_gaps`, :func:`~cablesim.orbits.cablefield.exact_modes`).
Without events the steps are bitwise those of :func:`~cablesim.orbits.kernels.flow_segment`.
"""

from __future__ import annotations

import numpy as np

from ..dynamics.status import CHATTER, INTERRUPTED, NONFINITE, OK
from ..jit import njit
from . import kernels as ok

#: Two mode changes of one segment closer than this (s) are chatter: the flow returns ``CHATTER``.
CHATTER_WINDOW = 1e-6
#: An event's fraction of its step is located to this.
EVENT_TOL = 1e-12
#: Events a flow segment can record per segment of the cable (more: ``CHATTER``).
EVENTS_PER_SEGMENT = 64

__all__ = ["CHATTER_WINDOW", "EVENT_TOL", "EVENTS_PER_SEGMENT", "flow_segment_modes"]


@njit
def _rates(field, model, prm, work, x, Yf, sc, tab, theta0, omega, h, k, a0, a1, ipar_f, pmode, jac, blk, info,
           nst):
    """Stage rates ``K`` (and ``KY`` with ``jac``) of the part ``[a0, a0 + a1]`` (in units of
    the step ``h``) of step ``k``, from ``x``; returns the field's status. With ``a0 = 0``,
    ``a1 = 1`` the sums of :func:`~cablesim.orbits.kernels.flow_segment`, bit for bit."""
    xs, K, dx, J, dp, Ysf, KYf, Jb, Ys2, KY2 = sc
    A, b, c = tab
    rows, bounds, ncol = blk
    hs = h * a1
    for st in range(nst):
        ok.stage_state(x, K, Yf, KYf, xs, Ysf, A, st, hs, jac)
        theta = theta0 + omega * h * (k + (a0 + a1 * c[st]))
        code = field(theta, omega, xs, model, prm, work, dx, J, dp, ipar_f)
        if code != OK:
            return code
        for i in range(x.size):
            if not np.isfinite(dx[i]):
                return NONFINITE
            K[st, i] = dx[i]
        if jac:
            if bounds.size == 2:
                tr = ok.variational_rate_whole(J, Ys2, dx, dp, KY2[st], omega, pmode)
            else:
                tr = ok.variational_rate(J, Ysf, dx, dp, KYf[st], omega, pmode, rows, bounds, ncol, Jb)
            info[0] += hs * b[st] * tr
    return OK


@njit
def _substep(field, model, prm, work, x, Yf, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, pmode, jac, blk,
             info, rated):
    """Advance ``x`` (and ``Y``) over the part ``[a0, a0 + a1]`` of step ``k`` (``rated``: its
    stage rates already in ``sc``); returns a status."""
    if not rated:
        code = _rates(field, model, prm, work, x, Yf, sc, tab, theta0, omega, h, k, a0, a1, ipar_f, pmode, jac, blk,
                      info, tab[1].size)
        if code != OK:
            return code
    if not ok.advance_state(x, sc[1], tab[1], h * a1, scr[0], scr[1]):
        return NONFINITE
    if jac:
        ok.advance_jacobian(Yf, sc[6], tab[1], h * a1)
    return OK


@njit
def _locate(field, gaps, model, prm, work, xa, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, blk, info, g, j,
            sgn, f_lo, f_hi):
    """Fraction ``tau`` of the part ``[a0, a0 + a1]`` of step ``k`` at which segment ``j``'s
    signed gap ``sgn g_j`` (non-negative while its mode holds) falls through zero: Illinois on
    the gap at the end of the partial step from ``xa``, ``f_lo >= 0`` at 0, ``f_hi < 0`` at 1;
    the bracket's crossed end (``-1.0`` if a partial step fails)."""
    xt = scr[2]
    lo, hi = 0.0, 1.0
    side = 0
    for _ in range(200):
        if hi - lo <= EVENT_TOL or f_lo == 0.0:
            break
        tau = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        if not lo < tau < hi:
            tau = 0.5 * (lo + hi)
        for i in range(xa.size):
            xt[i] = xa[i]
        if _substep(field, model, prm, work, xt, xt, sc, scr, tab, theta0, omega, h, k, a0, a1 * tau, ipar_f, 0,
                    False, blk, info, False) != OK:
            return -1.0
        gaps(theta0 + omega * h * (k + (a0 + a1 * tau)), omega, xt, model, prm, work, g)
        f = sgn * g[j]
        if f < 0.0:
            hi, f_hi = tau, f
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            lo, f_lo = tau, f
            if side == -1:
                f_hi *= 0.5
            side = -1
    return lo if f_lo == 0.0 else hi


@njit
def _crossing(gaps, model, prm, work, x, theta, omega, taut, g):
    """Whether some segment's gap at ``x`` contradicts its mode (``g`` receives the gaps)."""
    gaps(theta, omega, x, model, prm, work, g)
    for j in range(g.size):
        if (g[j] < 0.0) if taut[j] > 0.0 else (g[j] > 0.0):
            return True
    return False


@njit
def _earliest(field, gaps, model, prm, work, xa, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, blk, info, taut,
              g, ga):
    """``(tau, j)``: the earliest mode change within the part ``[a0, a0 + a1]`` of step ``k``
    (``g`` the gaps at its end), located from its start ``xa``; ``j = -1`` if a partial step
    failed."""
    gend = scr[3]
    for j in range(g.size):
        gend[j] = g[j]
    gaps(theta0 + omega * h * (k + a0), omega, xa, model, prm, work, ga)
    best, jbest = 2.0, -1
    for j in range(g.size):
        sgn = 1.0 if taut[j] > 0.0 else -1.0
        if sgn * gend[j] < 0.0:
            tau = _locate(field, gaps, model, prm, work, xa, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, blk,
                          info, g, j, sgn, max(sgn * ga[j], 0.0), sgn * gend[j])
            if tau < 0.0:
                return tau, -1
            if tau < best:
                best, jbest = tau, j
    return best, jbest


@njit
def _step(field, gaps, model, prm, work, x, Yf, sc, scr, tab, theta0, omega, h, k, ipar_f, pmode, jac, blk, info,
          taut, g, ga, tlast, events, nev, q0):
    """Step ``k`` from ``x`` (its stage rates already in ``sc``, the divergence integral
    ``q0`` before them), cut at every mode change (module docstring); returns a status."""
    Yfa = scr[4]
    xa = scr[5]
    a0, a1 = 0.0, 1.0
    rated = True
    for _ in range(4 * g.size + 4):
        for i in range(x.size):
            xa[i] = x[i]
        if jac:
            for i in range(Yf.size):
                Yfa[i] = Yf[i]
        if not rated:
            q0 = info[0]
        code = _substep(field, model, prm, work, x, Yf, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, pmode, jac,
                        blk, info, rated)
        if code != OK:
            return code
        if not _crossing(gaps, model, prm, work, x, theta0 + omega * h * (k + (a0 + a1)), omega, taut, g):
            return OK
        tau, j = _earliest(field, gaps, model, prm, work, xa, sc, scr, tab, theta0, omega, h, k, a0, a1, ipar_f, blk,
                           info, taut, g, ga)
        if j < 0:
            return NONFINITE
        # retake the part up to the event, with the variational equations, in the old modes
        for i in range(x.size):
            x[i] = xa[i]
        if jac:
            for i in range(Yf.size):
                Yf[i] = Yfa[i]
        info[0] = q0
        code = _substep(field, model, prm, work, x, Yf, sc, scr, tab, theta0, omega, h, k, a0, a1 * tau, ipar_f, pmode,
                        jac, blk, info, False)
        if code != OK:
            return code
        t_ev = h * (k + (a0 + a1 * tau))
        if t_ev - tlast[j] < CHATTER_WINDOW or nev[0] >= events.shape[0]:
            return CHATTER
        tlast[j] = t_ev
        taut[j] = 1.0 - taut[j]
        events[nev[0], 0], events[nev[0], 1], events[nev[0], 2] = t_ev, j, taut[j]
        nev[0] += 1
        if tau >= 1.0:
            return OK
        a0 = a0 + a1 * tau
        a1 = 1.0 - a0
        rated = False
    return CHATTER


@njit
def _start_modes(gaps, model, prm, work, x0, theta0, omega, taut, track, g):
    """Turn tracking on and set the modes from the gaps of the start state ``x0`` (taut where
    ``g > 0``)."""
    track[0] = 1.0
    gaps(theta0, omega, x0, model, prm, work, g)
    for j in range(g.size):
        taut[j] = 1.0 if g[j] > 0.0 else 0.0


@njit(nogil=True)
def flow_segment_modes(field, gaps, modes, model, prm, work, x0, theta0, omega, duration, nsteps, A, b, c, ipar,
                       pmode, jac, rows, bounds, xend, Mout, pout, xmax, xmin, rec, info, events, nev, stop):
    """:func:`cablesim.orbits.kernels.flow_segment` through slack (module docstring): the same
    arguments and outputs, with ``gaps`` and ``modes`` (the system's), and ``events`` (rows
    ``(t, segment, new mode)``) with their number ``nev[0]``. Returns a status (``CHATTER``
    where a segment changes mode twice within :data:`CHATTER_WINDOW` s or ``events`` is full)."""
    n = x0.size
    s = b.size
    h = duration / nsteps
    ncol = n + 1 if (jac and pmode != ok.PARAM_NONE) else n
    ipar_f = ipar if pmode == ok.PARAM_PRM else (ok.IPAR_OMEGA if pmode == ok.PARAM_OMEGA else -1)
    x = x0.copy()
    Y = np.zeros((n, ncol))
    nY = ok.compact_size(n, ncol, bounds)
    Yf = np.empty(nY)
    Ysf = np.empty(nY)
    KYf = np.empty((s, nY))
    Ys2 = Ysf.reshape((n, ncol)) if bounds.size == 2 else Y
    KY2 = KYf.reshape((s, n, ncol)) if bounds.size == 2 else KYf.reshape((s, 1, nY))
    K = np.empty((s, n))
    sc = (np.empty(n), K, np.empty(n), np.zeros((n, n)), np.zeros(n), Ysf, KYf, np.empty((n, n)), Ys2, KY2)
    taut, track = modes(work)
    nseg = taut.size
    g = np.empty(nseg)
    ga = np.empty(nseg)
    scr = (np.empty(n), np.empty(n), np.empty(n), np.empty(nseg), np.empty(nY), np.empty(n))
    tab = (A, b, c)
    blk = (rows, bounds, ncol)
    tmpM, tmpp, LU = np.empty((n, n)), np.empty(n), np.empty((n, n))
    xprev, dprev = np.empty(n), np.empty(n)
    _start_modes(gaps, model, prm, work, x, theta0, omega, taut, track, g)
    tlast = np.full(nseg, -np.inf)
    nev[0] = 0
    ok.start_segment(x, Y, xmax, xmin, info)
    if jac:
        ok.blocks_to_full(Yf, Y, rows, bounds, False)
    q_chunk = 0.0
    first_chunk = True
    for k in range(nsteps + 1):
        if stop[0] != 0:
            return INTERRUPTED
        last = k == nsteps
        q0 = info[0]
        code = _rates(field, model, prm, work, x, Yf, sc, tab, theta0, omega, h, k, 0.0, 1.0, ipar_f, pmode,
                      jac and not last, blk, info, s if not last else 1)
        if code != OK:
            return code
        ok.sample_step(k, x, K, xprev, dprev, h, xmax, xmin, rec)
        if last:
            break
        for i in range(n):
            xprev[i] = x[i]
            dprev[i] = K[0, i]
        code = _step(field, gaps, model, prm, work, x, Yf, sc, scr, tab, theta0, omega, h, k, ipar_f, pmode, jac, blk,
                     info, taut, g, ga, tlast, events, nev, q0)
        if code != OK:
            return code
        if jac and abs(info[0] - q_chunk) > ok.CHUNK_DIVERGENCE and k < nsteps - 1:
            ok.blocks_to_full(Yf, Y, rows, bounds, True)
            ok.close_chunk(Y, n, ncol, Mout, pout, tmpM, tmpp, LU, info, first_chunk)
            ok.blocks_to_full(Yf, Y, rows, bounds, False)
            first_chunk = False
            q_chunk = info[0]
    for i in range(n):
        xend[i] = x[i]
    if jac:
        ok.blocks_to_full(Yf, Y, rows, bounds, True)
        ok.close_chunk(Y, n, ncol, Mout, pout, tmpM, tmpp, LU, info, first_chunk)
    return OK
