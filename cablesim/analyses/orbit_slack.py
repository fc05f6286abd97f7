"""Slack episodes, snap loads and grazing points of the orbits of a continuation through slack
(``continuation.through_slack``).

Every orbit of a branch gets its slack pattern (:func:`cablesim.orbits.slackpattern.slack_pattern`):
per segment the slack episodes within the period, the fraction of the period spent slack and
the peak tension ``T_max`` (the snap load). Where a segment's least tension (below) changes sign
between consecutive orbits of a branch, or its number of slack episodes changes, the branch has
passed a *grazing* orbit: one on which
that segment's tension just touches zero. It is located by Brent's method in the parameter on
the segment's least elastic tension over the orbit, ``T_min = EA min_t (l(t) - S) / S`` (N,
negative where the segment is slack: the tension it would carry if it could push), which is
continuous through grazing and crosses zero there. Each trial solves the orbit by Newton's
method from the nearer of the orbits already known in the bracket. Where a second (third, ...)
episode appears, the root is that of the ``(k + 1)``-th smallest local minimum of the elastic
tension over the orbit, ``k`` the smaller of the two counts (the ``k`` deeper minima lie inside
the episodes both sides have).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..orbits.shooting import FlowStatus, Shooting, solve_orbit
from ..orbits.slackpattern import fine_shooting, slack_pattern
from ..orbits.systems import cable_system
from .orbit_strain import segment_strains

#: Tolerance of a located grazing point in the parameter (Brent's bracket), absolute.
GRAZING_TOL = 1e-9


@dataclass(frozen=True)
class BranchSlack:
    """The slack pattern of every orbit of a branch (``P`` orbits, ``n + 1`` segments).

    Attributes
    ----------
    peak_tension : ndarray (P, n + 1)
        Largest tension of each segment over the orbit (its snap load), N.
    peak_time : ndarray (P, n + 1)
        When it occurs, s from forcing phase 0.
    episodes : ndarray of int (P, n + 1)
        Slack episodes per segment and orbit period.
    fraction : ndarray (P, n + 1)
        Fraction of the orbit's period the segment is slack.
    least_tension : ndarray (P, n + 1)
        ``T_min``: the least elastic tension ``EA (l - S) / S`` over the orbit, N (negative:
        the segment goes slack; zero at a grazing orbit).
    onset, end : ndarray (K,)
        Every slack episode's onset and re-tightening, s from forcing phase 0 (the
        re-tightening beyond the period for an episode running through its end), orbit by orbit
        and segment by segment within an orbit; ``episodes`` counts them.
    """

    peak_tension: np.ndarray
    peak_time: np.ndarray
    episodes: np.ndarray
    fraction: np.ndarray
    least_tension: np.ndarray
    onset: np.ndarray
    end: np.ndarray

    @property
    def slack(self) -> np.ndarray:
        """(P,) orbits on which some segment goes slack."""
        return self.episodes.sum(axis=1) > 0


@dataclass(frozen=True)
class Grazing:
    """A located grazing orbit of branch ``branch`` (of orbits of ``period`` forcing periods):
    between its orbits ``point`` and ``point + 1``, segment ``segment`` (1-based) goes from
    ``episodes[0]`` to ``episodes[1]`` slack episodes per orbit period.

    Attributes
    ----------
    parameter : float
        Where the segment's tension touches zero.
    located : bool
        Brent's bracket converged (to :data:`GRAZING_TOL`) with an orbit solved at every trial.
    amplitude : ndarray
        Largest ``|z|`` of the grazing orbit per displacement DOF, m.
    multiplier : complex
        Its Floquet multiplier of largest modulus.
    multipliers : ndarray
        Its multipliers.
    before, after : ndarray
        The multipliers of the branch's orbits on either side (in the continuation's order):
        the non-smooth monodromy's, whose change across grazing is not that of a smooth branch.
    least_tension : float
        ``T_min`` of the located orbit, N (zero up to the root finding's tolerance).
    state : ndarray
        The grazing orbit's state at forcing phase 0 (``(z, y')``, m and m/s).
    trusted : bool
        The grazing orbit's Newton residual and Liouville check passed.
    """

    branch: int
    period: int
    point: int
    segment: int
    episodes: tuple
    parameter: float
    omega: float
    located: bool
    amplitude: np.ndarray
    multiplier: complex
    multipliers: np.ndarray
    before: np.ndarray
    after: np.ndarray
    least_tension: float
    state: np.ndarray
    trusted: bool

    @property
    def jump(self) -> float:
        """Largest distance from a multiplier on one side to the nearest on the other."""
        d = np.abs(self.before[:, None] - self.after[None, :])
        return float(max(d.min(axis=0).max(), d.min(axis=1).max())) if d.size else 0.0


def branch_shooting(eom, branch, parameter: str, gamma: float, support: float) -> Shooting:
    """The dense shooting through slack of the orbits of ``branch`` (its period and segments)."""
    g0 = branch.points[0].parameter if parameter == "gamma" else gamma
    s0 = branch.points[0].parameter if parameter == "support" else support
    system = cable_system(eom, gamma=g0, support=s0)
    segments = max(1, branch.points[-1].u.size // system.dim)
    return Shooting(system, period=branch.period, segments=segments, parameter=parameter, through_slack=True)


def tension_minima(sh: Shooting, eom, u: np.ndarray, lam: float, pieces: list | None = None) -> list:
    """Per segment, the local minima of the elastic tension ``EA (l - S) / S`` over the orbit
    ``u`` at ``lam``, N, in increasing order; located on the orbit's cubic Hermite interpolant at
    :data:`~cablesim.orbits.slackpattern.PEAK_REFINEMENT` times the shooting's steps (the error of
    a minimum's value is that of the interpolant, its place being first-order irrelevant);
    ``pieces``: those steps (:func:`~cablesim.orbits.slackpattern.fine_shooting`), if at hand."""
    nd, cable, y0 = eom.n_dof, eom.cable, eom.y0
    EA = float(cable.EA)
    dur = sh.period * 2.0 * np.pi / sh.omega_of(lam) / sh.segments
    # the period's samples once each (a piece's last is the next one's first), periodic
    pieces = fine_shooting(sh).steps(u, lam) if pieces is None else pieces
    t = np.concatenate([ts[:-1] + k * dur for k, (ts, _) in enumerate(pieces)] + [[sh.segments * dur]])
    rec = np.concatenate([r[:-1] for _, r in pieces] + [pieces[0][1][:1]])
    e = EA * segment_strains(cable, y0 + rec[:, :nd])
    values = []
    for j in range(e.shape[1]):
        col = e[:-1, j]
        idx = np.flatnonzero((col <= np.roll(col, -1)) & (col < np.roll(col, 1)))
        found = [_refined_minimum(t, rec, i, nd, cable, y0, j, EA) for i in idx]
        values.append(np.sort(np.array(found or [float(col.min())], dtype=float)))
    return values


#: Samples per step of the interpolant around a discrete minimum (then a parabola through the
#: least three): the vertex's error, of the order of the third derivative times
#: ``(h / MINIMUM_SAMPLES)^3``, is far below the interpolant's own.
MINIMUM_SAMPLES = 64


def _refined_minimum(t, rec, i, nd, cable, y0, j, EA) -> float:
    """Least elastic tension of segment ``j`` on the two steps either side of sample ``i`` of the
    orbit's cubic Hermite interpolant of ``z`` (``t``, ``rec``: the period's samples, the last
    the first's repetition), N."""
    n = t.size - 1
    th = np.linspace(0.0, 1.0, MINIMUM_SAMPLES + 1)[:, None]
    th2, th3 = th * th, th * th * th
    out = np.inf
    for lo in ((i - 1) % n, i):
        h = t[lo + 1] - t[lo]
        z0, z1, v0, v1 = rec[lo, :nd], rec[lo + 1, :nd], rec[lo, nd:2 * nd], rec[lo + 1, nd:2 * nd]
        z = ((2 * th3 - 3 * th2 + 1) * z0 + (th3 - 2 * th2 + th) * h * v0 + (-2 * th3 + 3 * th2) * z1
             + (th3 - th2) * h * v1)
        T = EA * segment_strains(cable, y0 + z)[:, j]
        k = int(np.argmin(T))
        out = min(out, float(T[k]))
        if 0 < k < T.size - 1:  # the vertex of the parabola through the least three samples
            a, b, c = T[k - 1], T[k], T[k + 1]
            den = a - 2.0 * b + c
            if den > 0.0:
                out = min(out, float(b - 0.125 * (c - a) ** 2 / den))
    return out


def branch_slack(eom, branch, parameter: str, gamma: float, support: float) -> BranchSlack:
    """The slack pattern (:class:`BranchSlack`) of every orbit of ``branch`` (an
    :class:`~cablesim.orbits.diagram.OrbitBranch` traced through slack), from its shooting
    unknowns: the events of one flow, the snap loads and the least tensions on the orbit
    integrated again at four times the steps."""
    sh = branch_shooting(eom, branch, parameter, gamma, support)
    rows = [orbit_pattern(sh, eom, p.u, p.parameter) for p in branch.points]
    if not rows:
        m = np.asarray(eom.cable.S).size
        empty = np.zeros((0, m))
        return BranchSlack(empty, empty, empty.astype(int), empty, empty, np.zeros(0), np.zeros(0))
    pat = [r[0] for r in rows]
    intervals = [iv for p in pat for iv in p.intervals]
    flat = np.concatenate(intervals) if intervals else np.zeros((0, 2))
    return BranchSlack(
        peak_tension=np.array([p.peak_tension for p in pat]), peak_time=np.array([p.peak_time for p in pat]),
        episodes=np.array([p.episodes for p in pat], dtype=int),
        fraction=np.array([[float(np.sum(iv[:, 1] - iv[:, 0])) / p.T for iv in p.intervals] for p in pat]),
        least_tension=np.array([r[1] for r in rows]), onset=flat[:, 0].copy(), end=flat[:, 1].copy())


def orbit_pattern(sh: Shooting, eom, u: np.ndarray, lam: float):
    """The slack pattern (:class:`~cablesim.orbits.slackpattern.SlackPattern`) of the orbit
    ``u`` at ``lam`` of the shooting through slack ``sh`` and its segments' least elastic
    tensions, N, all from one flow at the refined steps (its events, located to 1e-10 s on its
    interpolant as on the shooting's own, and its steps)."""
    ev = fine_shooting(sh).evaluate(u, lam, jac=False, record=True)
    if ev.status != FlowStatus.OK:
        raise FloatingPointError(f"integration failed (status {ev.status.name})")
    pat = slack_pattern(sh, u, lam, ev, fine_steps=ev.steps)
    least = np.array([m[0] for m in tension_minima(sh, eom, u, lam, ev.steps)])
    return pat, least


class _NoOrbit(Exception):
    """Newton's method did not converge at a trial parameter of the grazing search."""


def locate_grazing(sh: Shooting, eom, branch, slack: BranchSlack, i: int, j: int, index: int) -> Grazing:
    """The grazing orbit of segment ``j`` (0-based) between orbits ``i`` and ``i + 1`` of
    ``branch`` (module docstring): Brent's method on the ``(k + 1)``-th smallest local minimum
    of the segment's elastic tension, every trial orbit solved by Newton's method from the
    nearer orbit known in the bracket."""
    a, b = branch.points[i], branch.points[i + 1]
    k = int(min(slack.episodes[i, j], slack.episodes[i + 1, j]))
    known = {float(a.parameter): (a.u, None), float(b.parameter): (b.u, None)}

    def measure(u, lam):
        minima = tension_minima(sh, eom, u, lam)[j]
        return float(minima[k]) if minima.size > k else float(minima[-1]) if minima.size else np.inf

    def f(lam):
        near = min(known, key=lambda x: abs(x - lam))
        sol = solve_orbit(sh, known[near][0], lam)
        if not sol.converged:
            raise _NoOrbit
        known[float(lam)] = (sol.u, sol)
        return measure(sol.u, lam)

    fa, fb = measure(a.u, a.parameter), measure(b.u, b.parameter)
    root, located = 0.5 * (a.parameter + b.parameter), False
    if np.isfinite(fa) and np.isfinite(fb) and fa * fb <= 0.0:
        try:
            root = brentq(f, a.parameter, b.parameter, xtol=GRAZING_TOL, rtol=4 * np.finfo(float).eps)
            located = True
        except (_NoOrbit, RuntimeError, ValueError):
            located = False
    near = min(known, key=lambda x: abs(x - root))
    sol = solve_orbit(sh, known[near][0], root)
    ev = sol.evaluation if sol.converged else None
    d = sh.system.displacements
    amp = np.maximum(np.abs(ev.xmax[d]), np.abs(ev.xmin[d])) if ev is not None else np.maximum(a.amplitude, 0.0)
    mu = ev.multipliers if ev is not None else a.multipliers
    return Grazing(
        branch=index, period=int(branch.period), point=i, segment=j + 1, episodes=(int(slack.episodes[i, j]), int(slack.episodes[i + 1, j])),
        parameter=float(root), omega=float(sh.omega_of(root)), located=bool(located and ev is not None),
        amplitude=amp, multiplier=complex(mu[0]), multipliers=np.asarray(mu).copy(), before=np.asarray(a.multipliers),
        after=np.asarray(b.multipliers), least_tension=measure(sol.u, root) if ev is not None else np.nan,
        state=np.asarray(sol.u[: sh.n]).copy(),
        trusted=bool(ev is not None and sol.residual <= 1e-8 and ev.liouville <= 1e-3))


def grazing_changes(slack: BranchSlack) -> list:
    """``(i, j)``: segment ``j`` grazes between orbits ``i`` and ``i + 1``. Where it goes from
    no slack episode to some (or back) that is where its least tension ``T_min`` changes sign,
    the episode counts notwithstanding: just past grazing an episode shorter than a step falls
    between the flow's steps, so an orbit there may show no episode with ``T_min < 0``
    (measured between the steps). Elsewhere, where its count of episodes changes."""
    e, least = slack.episodes, slack.least_tension
    out = []
    for i in range(e.shape[0] - 1):
        for j in range(e.shape[1]):
            if min(e[i, j], e[i + 1, j]) == 0:
                if (least[i, j] < 0.0) != (least[i + 1, j] < 0.0):
                    out.append((i, j))
            elif e[i, j] != e[i + 1, j]:
                out.append((i, j))
    return out


def branch_grazings(eom, branch, slack: BranchSlack, parameter: str, gamma: float, support: float,
                    index: int) -> list:
    """Every grazing orbit of ``branch`` (:func:`locate_grazing` between the consecutive orbits
    :func:`grazing_changes` finds), in the continuation's order."""
    changes = grazing_changes(slack)
    if not changes:
        return []
    sh = branch_shooting(eom, branch, parameter, gamma, support)
    return [locate_grazing(sh, eom, branch, slack, i, j, index) for i, j in changes]
