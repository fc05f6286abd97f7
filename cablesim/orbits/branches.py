"""Branches of periodic orbits: continuation, stability, bifurcations and branch switching.

:func:`trace_branches` works on any :class:`~cablesim.orbits.systems.OdeSystem`;
:func:`continue_branches` is the cable's entry point (it builds the system from the equations
of motion, picks the scales and starts from the linear response).

For every branch, every point carries the orbit's state at forcing phase 0, the amplitudes
(largest ``|x_i|`` over the orbit and half the peak-to-peak range, for the system's displacement
components, from the cubic Hermite interpolant between integration steps), the Floquet
multipliers, a stability flag and a *trusted* flag: False when the Newton residual is above
tolerance or Liouville's formula ``det(monodromy) = exp(int tr J dt)`` is violated by more than
``liouville_tol`` (relative), i.e. when the integration is too coarse for the multipliers to be
believed.

Bifurcations (fold, period doubling, Neimark-Sacker, branch point) are located on the branch
(:mod:`cablesim.orbits.continuation`). At every located period doubling of a period-``p``
branch (``2p <= max_period``) the period-``2p`` branch is started from the critical
eigenvector ``v`` (multiplier -1): the ``2p`` unknowns are the parent's segment states perturbed
by ``+eps w_k`` on the first lap and ``-eps w_k`` on the second (``w_0 = v``,
``w_{k+1} = G_k w_k``), corrected on the hyperplane normal to that direction, and continued away
from the parent; if that start fails, ``-eps`` is tried (the two signs give the same orbit
shifted by ``p`` forcing periods, so one of them suffices). A ``2p`` branch whose two laps come
back together (or whose lap difference reverses between two points: the step went through the
branch point onto the mirror image) has rejoined a period-``p`` orbit at the other period
doubling of a pair: it ends there (:attr:`BranchEnd.MERGED`, the parent's period doubling as
its last point) and that period doubling is not switched at again.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from enum import IntEnum
from typing import Callable

import numpy as np

from . import kernels as ok
from . import stability
from .continuation import Settings, continuation
from .shooting import Evaluation, FlowStatus, Shooting, solve_orbit
from .starting import integrate_to_steady, linear_response, linear_response_state
from .systems import OdeSystem, cable_system


class BranchEnd(IntEnum):
    """Why a branch ended (the continuation's :class:`~cablesim.orbits.continuation.Status`
    plus :attr:`MERGED`)."""

    BOUND_REACHED = 0
    MAX_POINTS = 1
    STEP_TOO_SMALL = 2
    STOPPED_BY_CALLBACK = 3
    START_FAILED = 4
    MERGED = 5


@dataclass
class OrbitPoint:
    """One periodic orbit on a branch.

    Attributes
    ----------
    branch : int
        Index of its branch in :attr:`ResponseDiagram.branches`.
    index : int
        Position on the branch.
    parameter : float
        Value of the continuation parameter.
    omega : float
        Forcing frequency, rad/s.
    period : int
        Orbit period in forcing periods.
    state : ndarray (n,)
        State at forcing phase 0 (for the cable ``(z, v)``).
    u : ndarray (m n,)
        All shooting unknowns (segment start states).
    amplitude : ndarray
        Largest ``|x_i|`` over the orbit, per displacement component.
    halfrange : ndarray
        Half the peak-to-peak range, per displacement component.
    multipliers : ndarray (n,) complex
        Floquet multipliers, by decreasing modulus.
    stable : bool
        All multipliers inside the unit circle.
    trusted : bool
        Residual and Liouville checks passed (module docstring).
    residual : float
        Scaled Newton residual (max norm).
    liouville : float
        ``|log det(monodromy) - int tr J dt|``.
    special : str or None
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"``, ``"branch-point"`` at a located
        bifurcation, else None.
    located : bool
        For a special point: whether the location converged.
    """

    branch: int
    index: int
    parameter: float
    omega: float
    period: int
    state: np.ndarray
    u: np.ndarray
    amplitude: np.ndarray
    halfrange: np.ndarray
    multipliers: np.ndarray
    stable: bool
    trusted: bool
    residual: float
    liouville: float
    special: str | None = None
    located: bool = True


@dataclass
class Bifurcation:
    """A located bifurcation.

    Attributes
    ----------
    kind : str
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` or ``"branch-point"``.
    parameter : float
    branch : int
        Branch on which it was found.
    period : int
        Period (forcing periods) of the orbit that bifurcates.
    amplitude, halfrange : ndarray
        Of that orbit, per displacement component.
    state : ndarray
    multiplier : complex
        The critical multiplier (near +1, -1 or on the unit circle).
    multipliers : ndarray
    located : bool
    trusted : bool
    point : int
        Index of the point on its branch.
    child : int or None
        Branch started here (period doubling), if any.
    """

    kind: str
    parameter: float
    branch: int
    period: int
    amplitude: np.ndarray
    halfrange: np.ndarray
    state: np.ndarray
    multiplier: complex
    multipliers: np.ndarray
    located: bool
    trusted: bool
    point: int
    child: int | None = None


@dataclass
class OrbitBranch:
    """A branch of periodic orbits of one period.

    Attributes
    ----------
    index, period, parameter
        Position in the diagram, orbit period (forcing periods), continuation parameter.
    points : list of OrbitPoint
        In continuation order (located bifurcations included, flagged by ``special``).
    end : BranchEnd
        Why the branch ended.
    parent : int or None
        Branch it was switched from (period doubling), with ``origin`` the bifurcation.
    evaluations : int
        Shooting evaluations spent on it.
    segments : int
        Shooting segments used.
    merged_at : OrbitPoint or None
        For a period-doubled branch that rejoined its parent: the parent's period doubling.
    failure : FlowStatus or None
        When the step fell below its minimum or the start failed: why the last refused flow
        failed (a slack segment, a failed inner solve), if a flow failed at all.
    """

    index: int
    period: int
    parameter: str
    points: list = field(default_factory=list)
    end: BranchEnd = BranchEnd.MAX_POINTS
    parent: int | None = None
    origin: Bifurcation | None = None
    evaluations: int = 0
    segments: int = 1
    merged_at: OrbitPoint | None = None
    failure: FlowStatus | None = None

    @property
    def values(self) -> np.ndarray:
        """Parameter values of the points."""
        return np.array([p.parameter for p in self.points])

    @property
    def amplitude(self) -> np.ndarray:
        """(points, components) largest |x| per displacement component."""
        return np.array([p.amplitude for p in self.points])

    @property
    def halfrange(self) -> np.ndarray:
        return np.array([p.halfrange for p in self.points])

    @property
    def stable(self) -> np.ndarray:
        return np.array([p.stable for p in self.points], dtype=bool)

    @property
    def trusted(self) -> np.ndarray:
        return np.array([p.trusted for p in self.points], dtype=bool)

    @property
    def states(self) -> np.ndarray:
        return np.array([p.state for p in self.points])

    @property
    def multipliers(self) -> np.ndarray:
        return np.array([p.multipliers for p in self.points])


@dataclass
class ResponseDiagram:
    """Every branch and bifurcation found, with cost counters.

    ``stats``: ``evaluations`` (shooting residual + Jacobian evaluations), ``segments``
    (segment integrations), ``steps`` (Runge-Kutta steps), ``points``, ``seconds``.
    """

    parameter: str
    branches: list = field(default_factory=list)
    bifurcations: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)

    def of_kind(self, kind: str) -> list:
        return [b for b in self.bifurcations if b.kind == kind]


class OrbitProblem:
    """The periodicity condition of a :class:`Shooting` as a continuation problem."""

    test_names = stability.TEST_NAMES
    fold_tests = stability.FOLD_TESTS

    def __init__(self, shooting: Shooting, state_scale: np.ndarray, lam_scale: float):
        self.shooting = shooting
        #: Status of the last flow that failed (why a step was refused), if any.
        self.last_failure: FlowStatus | None = None
        self.u_scale = np.tile(np.asarray(state_scale, dtype=float), shooting.segments)
        self.lam_scale = float(lam_scale)

    def evaluate(self, u, lam):
        ev = self.shooting.evaluate(u, lam)
        if ev.status != ok.OK:
            self.last_failure = ev.status
            return None
        return ev

    def test_functions(self, ev: Evaluation) -> np.ndarray:
        return stability.test_functions(ev.multipliers)

    def confirm(self, name: str, ev: Evaluation) -> str | None:
        return stability.confirm(name, ev.multipliers)

    def step_ratio(self, ev_a: Evaluation, ev_b: Evaluation) -> float:
        return stability.step_ratio(ev_a.multipliers, ev_b.multipliers)


def _orbit_point(system: OdeSystem, shooting: Shooting, cp, branch: int, index: int, residual_tol: float,
                 liouville_tol: float) -> OrbitPoint:
    ev: Evaluation = cp.evaluation
    d = system.displacements
    xmax, xmin = ev.xmax[d], ev.xmin[d]
    mu = ev.multipliers
    trusted = bool(cp.residual <= 10.0 * residual_tol and ev.liouville <= liouville_tol and np.all(np.isfinite(mu)))
    return OrbitPoint(
        branch=branch, index=index, parameter=float(cp.lam), omega=ev.omega, period=shooting.period,
        state=cp.u[: shooting.n].copy(), u=cp.u.copy(), amplitude=np.maximum(np.abs(xmax), np.abs(xmin)),
        halfrange=0.5 * (xmax - xmin), multipliers=mu.copy(), stable=stability.is_stable(mu), trusted=trusted,
        residual=float(cp.residual), liouville=float(ev.liouville), special=cp.special, located=cp.located,
    )


def _lap_difference(u: np.ndarray, n: int, m_parent: int, scale: np.ndarray) -> np.ndarray:
    """Scaled difference between the two laps of a period-doubled orbit's unknowns."""
    S = u.reshape(2 * m_parent, n)
    return ((S[:m_parent] - S[m_parent:]) / scale).ravel()


def _separation(u: np.ndarray, n: int, m_parent: int, scale: np.ndarray) -> float:
    """Scaled max difference between the two laps of a period-doubled orbit's unknowns."""
    return float(np.abs(_lap_difference(u, n, m_parent, scale)).max())


def trace_branches(
    system: OdeSystem,
    u0: np.ndarray,
    parameter: str,
    start: float,
    stop: float,
    period: int = 1,
    segments: int = 1,
    state_scale: np.ndarray | None = None,
    lam_scale: float | None = None,
    switch_branches: bool = True,
    max_period: int | None = None,
    callback: Callable[[OrbitPoint], bool | None] | None = None,
    settings: Settings | None = None,
    scheme: str = "rk8",
    steps_per_period: int | None = None,
    step_rate: float | None = None,
    liouville_tol: float = 1e-3,
    switch_size: float = 0.02,
) -> ResponseDiagram:
    """Continue the period-``period`` branch through ``u0`` from ``start`` to ``stop`` and the
    branches born at its period doublings (module docstring).

    Parameters
    ----------
    system : OdeSystem
    u0 : ndarray
        Guess of the orbit's state at forcing phase 0 at ``parameter = start`` (refined by
        Newton's method first).
    parameter : str
        ``"omega"`` or a name in ``system.parameters``.
    start, stop : float
        Parameter range; the branch starts at ``start`` and runs towards ``stop``, following
        folds, until it leaves ``[min, max]``.
    period : int
        Period of the first branch, in forcing periods.
    segments : int
        Shooting segments over one orbit of the first branch (multiple shooting for long or
        strongly unstable orbits); doubled with the period on switched branches, so that a
        segment always spans the same time.
    state_scale : ndarray (n,), optional
        Typical size of each state component (default: from ``u0``).
    lam_scale : float, optional
        Typical parameter change (default ``|stop - start|``).
    switch_branches : bool
        Start the period-``2p`` branches at period doublings.
    max_period : int, optional
        Largest period followed (default ``2 * period``).
    callback : callable, optional
        ``callback(point)`` for every converged :class:`OrbitPoint`; True stops that branch.
    settings : Settings, optional
        Continuation settings (the bounds are set from ``start``, ``stop``).
    scheme, steps_per_period, step_rate
        Integration settings (:class:`~cablesim.orbits.shooting.Shooting`).
    liouville_tol : float
        Largest ``|log det - int tr J|`` of a trusted point.
    switch_size : float
        Scaled size of the perturbation that starts a period-doubled branch.

    Returns
    -------
    ResponseDiagram
    """
    t_start = time.perf_counter()
    n = system.dim
    max_period = 2 * period if max_period is None else int(max_period)
    lo, hi = min(start, stop), max(start, stop)
    base = settings if settings is not None else Settings()
    st = replace(base, lam_min=lo, lam_max=hi)
    if lam_scale is None:
        lam_scale = abs(stop - start) if stop != start else max(abs(start), 1.0)
    if state_scale is None:
        amp = float(np.abs(u0).max()) if np.size(u0) else 1.0
        state_scale = np.full(n, max(amp, 1e-12))
    state_scale = np.asarray(state_scale, dtype=float)
    diagram = ResponseDiagram(parameter=parameter)
    shootings: dict = {}

    def make_shooting(p, m):
        key = (p, m)
        if key not in shootings:
            shootings[key] = Shooting(system, period=p, segments=m, parameter=parameter, scheme=scheme,
                                      steps_per_period=steps_per_period, step_rate=step_rate)
        return shootings[key]

    def run_branch(sh, u_start, lam_start, tangent, parent, origin, prefix):
        idx = len(diagram.branches)
        br = OrbitBranch(index=idx, period=sh.period, parameter=parameter, parent=parent, origin=origin)
        br.segments = sh.segments
        diagram.branches.append(br)
        problem = OrbitProblem(sh, state_scale, lam_scale)
        m_parent = sh.segments // 2 if parent is not None else 0
        partners = [] if parent is None else [q for q in diagram.branches[parent].points
                                              if q.special == "period-doubling"]
        track = {"far": False, "D": None, "pending": []}
        merged = [None]
        for p in prefix:
            p.branch, p.index = idx, len(br.points)
            br.points.append(p)

        def deliver(op) -> bool:
            op.index = len(br.points)
            br.points.append(op)
            return bool(callback(op)) if callback is not None else False

        def cb(cp):
            op = _orbit_point(system, sh, cp, idx, -1, st.residual_tol, liouville_tol)
            if parent is not None:
                # A doubled branch that comes back to a period-p orbit (its two laps coincide)
                # rejoins the parent at a period doubling: end it there rather than continue
                # through that branch point. Seen as the two laps nearly coinciding, or as their
                # difference reversing between consecutive points (the step went through the
                # branch point onto the mirror image: the same orbits shifted by p periods).
                # Special points found in the step that crossed are artefacts of the pitchfork
                # (a fold test trips there) and are dropped.
                D = _lap_difference(cp.u, n, m_parent, state_scale)
                sep = float(np.abs(D).max())
                track["far"] = track["far"] or sep > 2.0 * switch_size
                flipped = track["D"] is not None and float(D @ track["D"]) < 0.0
                if track["far"] and partners and (flipped or sep < 0.5 * switch_size):
                    q = min(partners, key=lambda q: abs(q.parameter - cp.lam))
                    keep = [] if flipped else track["pending"] + ([op] if cp.special is None else [])
                    for o in keep:
                        deliver(o)
                    end = replace(q, branch=idx, period=sh.period, u=np.concatenate([q.u, q.u]),
                                  multipliers=stability.sort_multipliers(q.multipliers**2))
                    deliver(end)
                    merged[0] = q
                    return True
                if cp.special is not None:
                    track["pending"].append(op)  # delivered with the next regular point
                    return False
                track["D"] = D
            stop_now = False
            for o in track["pending"] + [op]:
                stop_now = deliver(o) or stop_now
            track["pending"] = []
            return stop_now

        res = continuation(problem, u_start, lam_start, st, callback=cb,
                           direction=np.sign(stop - start) or 1.0, tangent=tangent)
        br.evaluations = res.evaluations
        br.end = BranchEnd.MERGED if merged[0] is not None else BranchEnd(int(res.status))
        br.merged_at = merged[0]
        if br.end in (BranchEnd.STEP_TOO_SMALL, BranchEnd.START_FAILED):
            br.failure = problem.last_failure
        return br

    def switch(br: OrbitBranch, p: OrbitPoint, bif: Bifurcation):
        """Start the period-doubled branch at period doubling ``p`` of branch ``br``."""
        m1 = br.segments
        ev = make_shooting(br.period, m1).evaluate(p.u, p.parameter)
        if ev.status != ok.OK:
            return None
        mu, V = np.linalg.eig(ev.monodromy)
        j = int(np.argmin(np.abs(mu + 1.0)))
        W = [np.real(V[:, j])]
        for kk in range(m1 - 1):
            W.append(ev.G[kk] @ W[-1])
        W = np.array(W)
        dirn = np.concatenate([W.ravel(), -W.ravel()])
        eps = switch_size / np.linalg.norm(dirn / np.tile(state_scale, 2 * m1))
        sh2 = make_shooting(2 * br.period, 2 * m1)
        base = np.concatenate([p.u, p.u])
        for sign in (1.0, -1.0):
            doubled = replace(p, period=2 * br.period, u=base.copy(), special="period-doubling",
                              multipliers=stability.sort_multipliers(p.multipliers**2))
            child = run_branch(sh2, base + sign * eps * dirn, p.parameter, np.concatenate([sign * dirn, [0.0]]),
                               br.index, bif, [doubled])
            if child.end != BranchEnd.START_FAILED and len(child.points) > 1 \
                    and _separation(child.points[1].u, n, m1, state_scale) > 0.1 * switch_size:
                return child
            diagram.branches.pop()  # a failed attempt leaves no branch behind
        return None

    # first branch
    sh = make_shooting(period, segments)
    sol = solve_orbit(sh, u0, start, scale=state_scale)
    if not sol.converged:
        x = integrate_to_steady(sh, np.asarray(u0, dtype=float)[:n], start, periods=100)
        if x is not None:
            sol = solve_orbit(sh, x, start, scale=state_scale)
    if not sol.converged:
        diagram.branches.append(OrbitBranch(index=0, period=period, parameter=parameter, end=BranchEnd.START_FAILED,
                                            failure=sol.flow_status if sol.flow_status != FlowStatus.OK else None))
    else:
        run_branch(sh, sol.u, start, None, None, None, [])

    # bifurcations and branch switching, breadth first
    done_pd: set = set()
    k = 0
    while k < len(diagram.branches):
        br = diagram.branches[k]
        k += 1
        for p in list(br.points):
            if p.special is None:
                continue
            if p.index == 0 and br.origin is not None:
                continue  # the branch's own origin, recorded on the parent
            if br.end == BranchEnd.MERGED and (p is br.points[-1] or (
                    p.index >= len(br.points) - 4
                    and _separation(p.u, n, br.segments // 2, state_scale) < 2.0 * switch_size)):
                # where a doubled branch rejoins its parent (recorded on the parent); the
                # pitchfork there may also have tripped the fold test just before
                continue
            bif = Bifurcation(
                kind=p.special, parameter=p.parameter, branch=br.index, period=p.period,
                amplitude=p.amplitude, halfrange=p.halfrange, state=p.state,
                multiplier=stability.critical_multiplier(p.special, p.multipliers), multipliers=p.multipliers,
                located=p.located, trusted=p.trusted, point=p.index,
            )
            diagram.bifurcations.append(bif)
            if not (switch_branches and p.special == "period-doubling" and 2 * br.period <= max_period):
                continue
            if (br.index, p.index) in done_pd:
                continue
            child = switch(br, p, bif)
            if child is not None:
                bif.child = child.index
                if child.merged_at is not None:
                    done_pd.add((br.index, child.merged_at.index))
    diagram.stats = {
        "evaluations": sum(b.evaluations for b in diagram.branches),
        "segments": sum(sh.calls for sh in shootings.values()),
        "steps": sum(sh.steps_taken for sh in shootings.values()),
        "points": sum(len(b.points) for b in diagram.branches),
        "seconds": time.perf_counter() - t_start,
    }
    return diagram


def cable_scales(eom, parameter: str, start: float, stop: float, gamma: float = 1.0):
    """State and parameter scales of the cable problem.

    Displacements: the largest linear-response amplitude over the parameter range (a grid of
    64 values), floored at 1e-6 of the chord; velocities: that times the fundamental frequency.
    """
    w1 = float(eom.frequencies[0])
    if parameter == "omega":
        grid = np.linspace(min(start, stop), max(start, stop), 64)
        amp = max(float(np.abs(linear_response(eom, w, gamma)).max()) for w in grid)
    else:
        amp = float(np.abs(linear_response(eom, eom.omega, max(abs(start), abs(stop)))).max())
    amp = max(amp, 1e-6 * eom.cable.chord_length)
    nd = eom.n_dof
    scale = np.concatenate([np.full(nd, amp), np.full(nd, amp * w1)])
    lam_scale = abs(stop - start) if stop != start else 1.0
    return scale, lam_scale


def continue_branches(
    eom,
    parameter: str,
    start: float,
    stop: float,
    period: int = 1,
    switch_branches: bool = True,
    callback: Callable[[OrbitPoint], bool | None] | None = None,
    gamma: float = 1.0,
    initial_state: np.ndarray | None = None,
    segments: int = 1,
    max_period: int | None = None,
    settings: Settings | None = None,
    scheme: str = "rk8",
    steps_per_period: int | None = None,
    step_rate: float | None = None,
    liouville_tol: float = 1e-3,
) -> ResponseDiagram:
    """Periodic responses of the cable over a range of forcing frequency or load factor.

    Parameters
    ----------
    eom : EquationsOfMotion
        Exact or approximate analysis. With ``parameter="gamma"`` its ``omega`` is the forcing
        frequency.
    parameter : str
        ``"omega"`` (forcing frequency, rad/s) or ``"gamma"`` (multiplier of ``FL``).
    start, stop : float
        Range of the parameter; continuation starts at ``start``.
    period : int
        Period of the first branch in forcing periods.
    switch_branches : bool
        Follow the period-doubled branches born at period doublings.
    callback : callable, optional
        Receives every converged :class:`OrbitPoint`; returning True ends that branch.
    gamma : float
        Multiplier of ``FL`` when continuing in ``omega``.
    initial_state : ndarray, optional
        Guess of ``(z, y')`` (or ``(z, y', y'')``) at forcing phase 0 at ``start`` (default:
        the linear response).
    segments, max_period, settings, scheme, steps_per_period, step_rate, liouville_tol
        See :func:`trace_branches`.

    Returns
    -------
    ResponseDiagram
        Amplitudes per DOF (``z``), in DOF order.
    """
    if parameter not in ("omega", "gamma"):
        raise ValueError("parameter must be 'omega' or 'gamma'")
    g0 = start if parameter == "gamma" else gamma
    system = cable_system(eom, gamma=g0)
    w0 = start if parameter == "omega" else eom.omega
    if not w0 > 0:
        raise ValueError("the forcing frequency must be positive")
    nd = eom.n_dof
    if initial_state is None:
        u0 = linear_response_state(eom, w0, g0)
    else:
        u0 = np.asarray(initial_state, dtype=float)[: 2 * nd]
    scale, lam_scale = cable_scales(eom, parameter, start, stop, gamma)
    return trace_branches(
        system, u0, parameter, start, stop, period=period, segments=segments, state_scale=scale,
        lam_scale=lam_scale, switch_branches=switch_branches, max_period=max_period, callback=callback,
        settings=settings, scheme=scheme, steps_per_period=steps_per_period, step_rate=step_rate,
        liouville_tol=liouville_tol,
    )
