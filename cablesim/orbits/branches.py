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
eigenvector (a perturbation of scaled size ``switch_size``, smaller where that guess is out of
reach of Newton's method) and continued away from the parent; a ``2p`` branch that rejoins a period-``p``
orbit at the other period doubling of a pair ends there (:attr:`BranchEnd.MERGED`, the parent's
period doubling as its last point) and that period doubling is not switched at again
(:mod:`cablesim.orbits.switching`).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

import numpy as np

from ..blas import one_blas_thread
from . import kernels as ok
from .continuation import Settings, continuation
from .matrixfree import MatrixFreeShooting, orbit_leading, solve_orbit_mf
from .mfproblem import MatrixFreeOrbitProblem, uses_matrix_free
from .orbitpoint import bifurcation_at, orbit_point
from .diagram import Bifurcation, BranchEnd, BranchesInterrupted, OrbitBranch, OrbitPoint, ResponseDiagram
from .problems import OrbitProblem, PlanarOrbitProblem
from .resume import TraceLog
from .rotation import phase_direction
from .shooting import FlowStatus, Shooting, solve_orbit
from .splitleading import PlanarMatrixFreeProblem, split_leading
from .starting import cable_scales, integrate_to_steady, linear_response_state
from .switching import (
    MergeWatch,
    PlaneWatch,
    doubled_point,
    doubling_direction,
    lap_separation,
    pitchfork_direction,
    start_factor,
)
from .symmetry import in_plane_whirling
from .systems import OdeSystem, cable_system


#: Perturbation sizes tried at a period doubling before giving up (each a quarter of the last).
SWITCH_ATTEMPTS = 3
#: The special point of a period doubling, by the plane of its critical multiplier (None: an
#: orbit whose monodromy is not split). An out-of-plane one is switched at like any other: the
#: eigenvector nearest -1 of the whole monodromy is then the out-of-plane one.
DOUBLINGS = {None: "period-doubling", "in-plane": "period-doubling",
             "out-of-plane": "out-of-plane period-doubling"}
class _Tracer:
    """The branches of one :func:`trace_branches` call: shootings (one per period and segment
    count, shared by the branches), the continuation of each branch and the switching at
    period doublings, all recorded in :attr:`diagram`."""

    def __init__(self, system: OdeSystem, parameter: str, settings: Settings, direction: float,
                 state_scale: np.ndarray, lam_scale: float, callback, integration: dict,
                 liouville_tol: float, switch_size: float, matrix_free: bool = False, log: TraceLog | None = None,
                 measure: Callable | None = None):
        self.system = system
        #: Where the runs are recorded as they come, and replayed from (:mod:`cablesim.orbits.resume`).
        self.log = log if log is not None else TraceLog()
        #: The branch being continued, if any.
        self.running: OrbitBranch | None = None
        self.matrix_free = matrix_free
        self.n = system.dim
        self.parameter = parameter
        self.settings = settings
        self.direction = direction
        self.state_scale = state_scale
        self.lam_scale = lam_scale
        self.callback = callback
        self.integration = integration
        self.liouville_tol = liouville_tol
        self.switch_size = switch_size
        #: The measure of every orbit (:func:`trace_branches`), or None.
        self.measure = measure
        self.diagram = ResponseDiagram(parameter=parameter)
        self.shootings: dict = {}
        #: Scaled size of the perturbation that started each period-doubled branch, by index.
        self.sizes: dict = {}

    def shooting(self, period: int, segments: int) -> Shooting:
        """The shooting of period-``period`` orbits on ``segments`` segments."""
        key = (period, segments)
        if key not in self.shootings:
            kind = MatrixFreeShooting if self.matrix_free else Shooting
            self.shootings[key] = kind(self.system, period=period, segments=segments, parameter=self.parameter,
                                           **self.integration)
        return self.shootings[key]

    def first_branch(self, u0: np.ndarray, start: float, period: int, segments: int) -> None:
        """Solve the orbit near ``u0`` at ``start`` (from a steady state of the time integration
        if Newton's method fails from ``u0``) and continue its branch (restored or resumed
        instead if the log replays it)."""
        sh = self.shooting(period, segments)
        if self.log.planar(0) is not None:
            self.run_branch(sh, None, start, None, None, None, [])
            return
        solve = solve_orbit_mf if self.matrix_free else solve_orbit
        sol = solve(sh, u0, start, scale=self.state_scale)
        if not sol.converged:
            x = integrate_to_steady(sh, np.asarray(u0, dtype=float)[: self.n], start, periods=100)
            if x is not None:
                sol = solve(sh, x, start, scale=self.state_scale)
        if not sol.converged:
            failure = sol.flow_status if sol.flow_status != FlowStatus.OK else None
            self.diagram.branches.append(OrbitBranch(index=0, period=period, parameter=self.parameter,
                                                     end=BranchEnd.START_FAILED, failure=failure))
        else:
            self.run_branch(sh, sol.u, start, None, None, None, [])

    def problem(self, sh: Shooting, br: OrbitBranch, u_start: np.ndarray | None):
        """The continuation problem of branch ``br`` and the mirror of its orbits (None unless
        planar); decides :attr:`OrbitBranch.planar` (the log's record of a replayed run)."""
        mirror = self.system.mirror
        replayed = self.log.planar(self.log.count)
        br.planar = replayed if replayed is not None else (
            mirror is not None and mirror.is_planar(u_start[: self.n], self.state_scale))
        if br.planar:  # the monodromy's blocks, dense or their leading multipliers
            kind = PlanarMatrixFreeProblem if self.matrix_free else PlanarOrbitProblem
            return kind(sh, self.state_scale, self.lam_scale, mirror), mirror
        if self.matrix_free:
            return MatrixFreeOrbitProblem(sh, self.state_scale, self.lam_scale), None
        return OrbitProblem(sh, self.state_scale, self.lam_scale), None

    def watch(self, br: OrbitBranch, sh: Shooting, size: float | None):
        """The watch of a switched branch for its return to its parent or to the plane (None for
        the first branch)."""
        if br.origin is not None and br.origin.kind == "pitchfork":
            size = self.switch_size if size is None else size
            return PlaneWatch(self.system.mirror, self.n, self.state_scale, size)
        if br.parent is None:
            return None
        size = self.switch_size if size is None else size
        self.sizes[br.index] = size
        kind = br.origin.plane if br.origin is not None else None
        partners = [q for q in self.diagram.branches[br.parent].points if q.special == DOUBLINGS.get(kind)]
        return MergeWatch(partners, br.index, sh.period, self.n, sh.segments // 2, self.state_scale, size)

    def run_branch(self, sh: Shooting, u_start: np.ndarray | None, lam_start: float, tangent: np.ndarray | None,
                   parent: int | None, origin: Bifurcation | None, prefix: list,
                   size: float | None = None) -> OrbitBranch:
        """Continue one branch from ``(u_start, lam_start)`` and append it to the diagram.

        ``tangent``, ``parent``, ``origin`` and ``size`` are given for a period-doubled branch
        (its start direction, the parent branch, the period doubling and the scaled size of the
        perturbation it started from); ``prefix`` are points recorded before the continuation's
        first (the parent's period doubling). A run the log replays is restored (finished) or
        goes on from its last checkpoint (:mod:`cablesim.orbits.resume`)."""
        idx = len(self.diagram.branches)
        br = OrbitBranch(index=idx, period=sh.period, parameter=self.parameter, parent=parent, origin=origin)
        br.segments = sh.segments
        self.diagram.branches.append(br)
        problem, mirror = self.problem(sh, br, u_start)
        # the dense flows keep their steps when an orbit's measures would integrate it again
        problem.record = not self.matrix_free and (self.measure is not None or (
            self.system.frame is not None and not br.planar))
        watch = self.watch(br, sh, size)
        for p in prefix:
            p.branch, p.index = idx, len(br.points)
            br.points.append(p)
        r, past = self.log.start(br)
        resume = None
        if past is not None:
            past.restore(br, self.n)
            if past.end is not None:
                past.finish(br, self.diagram.branches[parent] if parent is not None else None)
                return br
            resume = past.resume()
            if watch is not None:
                watch.resume(resume.u, bool(past.step["far"]))

        def deliver(op: OrbitPoint) -> bool:
            op.index = len(br.points)
            br.points.append(op)
            self.log.orbit(r, op)
            return bool(self.callback(op)) if self.callback is not None else False

        def on_point(cp) -> bool:
            getattr(problem, "anchor", lambda u: None)(cp.u)  # the rotation's phase at the accepted orbit, if the system has one
            op = orbit_point(self.system, sh, cp, idx, -1, self.settings.residual_tol, self.liouville_tol, mirror,
                              self.measure)
            return deliver(op) if watch is None else watch.observe(cp, op, deliver)

        def checkpoint(cp, ds: float, count: int) -> None:
            self.log.step(r, cp, ds, count, len(br.points), None if watch is None else bool(watch.far))

        self.running = br
        res = continuation(problem, u_start, lam_start, self.settings, callback=on_point, direction=self.direction,
                           tangent=tangent, checkpoint=checkpoint, resume=resume)
        self.running = None
        br.evaluations = res.evaluations
        br.merged_at = getattr(watch, "merged_at", None)
        returned = bool(getattr(watch, "returned", False))
        br.end = BranchEnd.MERGED if br.merged_at is not None or returned else BranchEnd(int(res.status))
        if br.end in (BranchEnd.STEP_TOO_SMALL, BranchEnd.START_FAILED):
            br.failure = problem.last_failure
        self.log.end(r, br)
        return br

    def switch(self, br: OrbitBranch, p: OrbitPoint, bif: Bifurcation) -> OrbitBranch | None:
        """Start the period-doubled branch at period doubling ``p`` of branch ``br``
        (:mod:`cablesim.orbits.switching`); None if no perturbation leads away from the parent.

        The perturbation has the scaled size ``switch_size``, or less where the guess is not
        within reach of Newton's method (:func:`~cablesim.orbits.switching.start_factor`); when
        both signs fail, it is tried again at a quarter of the size, at most
        ``SWITCH_ATTEMPTS`` times."""
        m1 = br.segments
        sh1 = self.shooting(br.period, m1)
        ev = sh1.evaluate(p.u, p.parameter)
        if ev.status != ok.OK:
            return None
        if self.matrix_free:
            self.leading(br, sh1, ev)
        dirn, eps = doubling_direction(ev, m1, self.state_scale, self.switch_size,
                                       self.system.mirror if br.planar else None, bif.plane, shooting=sh1)
        sh2 = self.shooting(2 * br.period, 2 * m1)
        base = np.concatenate([p.u, p.u])
        factor = start_factor(sh2, base, dirn, eps, p.parameter, np.tile(self.state_scale, 2 * m1))
        for _ in range(SWITCH_ATTEMPTS if factor is not None else 0):
            child = self.start_doubled(br, p, bif, sh2, base, dirn, factor * eps, factor * self.switch_size)
            if child is not None:
                return child
            factor *= 0.25
        return None

    def leading(self, br: OrbitBranch, sh: MatrixFreeShooting, ev) -> None:
        """The leading multipliers of a matrix-free orbit of branch ``br`` (of each block on a
        planar branch), for the eigenvector that starts a branch born there."""
        if br.planar:
            split_leading(sh, ev, self.system.mirror, self.state_scale)
        else:
            orbit_leading(sh, ev, self.state_scale)

    def switch_pitchfork(self, br: OrbitBranch, p: OrbitPoint, bif: Bifurcation) -> OrbitBranch | None:
        """Start the nonplanar branch at pitchfork ``p`` of planar branch ``br`` along the
        out-of-plane null vector (:func:`~cablesim.orbits.switching.pitchfork_direction`); its
        mirror image (``w -> -w``) is the other branch born there, not computed. The
        perturbation shrinks by quarters while the start fails."""
        sh = self.shooting(br.period, br.segments)
        ev = sh.evaluate(p.u, p.parameter)
        if ev.status != ok.OK:
            return None
        if self.matrix_free:
            self.leading(br, sh, ev)
        phase = phase_direction(self.system.rotation, p.u, np.tile(self.state_scale, br.segments), self.n, br.segments)
        dirn, eps = pitchfork_direction(ev, self.system.mirror, br.segments, self.state_scale, self.switch_size,
                                        shooting=sh, phase=phase)
        size = self.switch_size
        for _ in range(SWITCH_ATTEMPTS):
            first = replace(p, planes=None, whirl=in_plane_whirling(self.n // 6))  # the planar orbit
            child = self.run_branch(sh, p.u + eps * dirn, p.parameter, np.concatenate([dirn, [0.0]]), br.index,
                                    bif, [first], size)
            odd = self.system.mirror.odd_size(child.points[-1].state, self.state_scale) if child.points else 0.0
            if child.end != BranchEnd.START_FAILED and len(child.points) > 1 and odd > 0.1 * size:
                child.mirror_image = True
                return child
            self.diagram.branches.pop()
            self.sizes.pop(child.index, None)
            eps, size = 0.25 * eps, 0.25 * size
        return None

    def start_doubled(self, br: OrbitBranch, p: OrbitPoint, bif: Bifurcation, sh2: Shooting, base: np.ndarray,
                      direction: np.ndarray, eps: float, size: float) -> OrbitBranch | None:
        """The period-doubled branch started from ``base + eps direction`` or
        ``base - eps direction`` (``size`` its scaled size), if one leads away from the parent."""
        for sign in (1.0, -1.0):
            doubled = doubled_point(p, 2 * br.period, base.copy())
            child = self.run_branch(sh2, base + sign * eps * direction, p.parameter,
                                    np.concatenate([sign * direction, [0.0]]), br.index, bif, [doubled], size)
            if child.end != BranchEnd.START_FAILED and len(child.points) > 1 \
                    and lap_separation(child.points[1].u, self.n, br.segments, self.state_scale) > 0.1 * size:
                return child
            self.diagram.branches.pop()  # a failed attempt leaves no branch behind
            self.sizes.pop(child.index, None)
        return None

    def is_own_bifurcation(self, br: OrbitBranch, p: OrbitPoint) -> bool:
        """Whether special point ``p`` of ``br`` is a bifurcation recorded on ``br`` (the ends
        of a period-doubled branch are recorded on its parent)."""
        if p.special is None:
            return False
        if p.index == 0 and br.origin is not None:
            return False  # the branch's own origin
        if br.mirror_image:  # near its return to the plane the tests trip at the pitchfork there
            return not (br.end == BranchEnd.MERGED and p.index >= len(br.points) - 4 and self.system.mirror.odd_size(
                p.state, self.state_scale) < 2.0 * self.sizes.get(br.index, self.switch_size))
        if br.end == BranchEnd.MERGED and (p is br.points[-1] or (
                p.index >= len(br.points) - 4
                and lap_separation(p.u, self.n, br.segments // 2, self.state_scale)
                < 2.0 * self.sizes.get(br.index, self.switch_size))):
            # where a doubled branch rejoins its parent; the pitchfork there may also have
            # tripped the fold test just before
            return False
        return True

    def collect_bifurcations(self, switch_branches: bool, max_period: int) -> None:
        """Record the bifurcations of every branch, breadth first, switching at the period
        doublings (the new branches are visited in turn)."""
        done_pd: set = set()
        k = 0
        while k < len(self.diagram.branches):
            br = self.diagram.branches[k]
            k += 1
            for p in list(br.points):
                if not self.is_own_bifurcation(br, p):
                    continue
                bif = bifurcation_at(p, br.index)
                self.diagram.bifurcations.append(bif)
                if switch_branches and bif.kind == "pitchfork" and (br.index, p.index) not in done_pd:
                    child = self.switch_pitchfork(br, p, bif)
                    if child is not None:
                        bif.child = child.index
                        if child.end == BranchEnd.MERGED:  # back in the plane at another pitchfork
                            others = [q for q in br.points if q.special == "pitchfork" and q is not p]
                            if others:
                                q = min(others, key=lambda q: abs(q.parameter - child.points[-1].parameter))
                                done_pd.add((br.index, q.index))
                    continue
                if not (switch_branches and p.special in DOUBLINGS.values() and 2 * br.period <= max_period):
                    continue
                if (br.index, p.index) in done_pd:
                    continue
                child = self.switch(br, p, bif)
                if child is not None:
                    bif.child = child.index
                    if child.merged_at is not None:
                        done_pd.add((br.index, child.merged_at.index))

    def record_located(self, diagram: ResponseDiagram | None = None) -> None:
        """Record the bifurcations located on the branches that :meth:`collect_bifurcations` has
        not reached (an interruption: the first branch while it is traced, the rest of a
        branch whose period doubling was being switched at), without switching at them."""
        d = self.diagram if diagram is None else diagram
        done = {(b.branch, b.point) for b in d.bifurcations}
        d.bifurcations += [bifurcation_at(p, br.index) for br in d.branches for p in br.points
                           if (br.index, p.index) not in done and self.is_own_bifurcation(br, p)]

    def partial(self, seconds: float = 0.0) -> ResponseDiagram:
        """A copy of the diagram so far, as an interruption would leave it (the branch being
        continued ends :attr:`BranchEnd.INTERRUPTED`), for the file written while it runs."""
        branches = [replace(b, points=list(b.points), end=BranchEnd.INTERRUPTED if b is self.running else b.end)
                    for b in self.diagram.branches]
        d = ResponseDiagram(parameter=self.parameter, branches=branches, bifurcations=list(self.diagram.bifurcations))
        self.record_located(d)
        d.stats = self.stats(seconds)
        return d

    def stats(self, seconds: float) -> dict:
        """Cost counters of :attr:`ResponseDiagram.stats`."""
        return {
            "evaluations": sum(b.evaluations for b in self.diagram.branches),
            "segments": sum(sh.calls for sh in self.shootings.values()),
            "steps": sum(sh.steps_taken for sh in self.shootings.values()),
            "points": sum(len(b.points) for b in self.diagram.branches),
            "newton_steps": sum(getattr(sh, "newton_steps", 0) for sh in self.shootings.values()),
            "krylov_iterations": sum(getattr(sh, "krylov_iterations", 0) for sh in self.shootings.values()),
            "seconds": seconds,
        }


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
    matrix_free: bool | None = None,
    log: TraceLog | None = None,
    measure: Callable[[list], float] | None = None,
    through_slack: bool = False,
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
        Scaled size of the perturbation that starts a period-doubled branch (reduced where the
        guess would be out of reach of Newton's method, :mod:`cablesim.orbits.switching`).
    matrix_free : bool, optional
        Shoot matrix-free (:mod:`cablesim.orbits.matrixfree`: Newton-GMRES, the leading
        multipliers only, their eigenpair residuals as the check instead of Liouville's
        formula); default: for systems in mechanical form above
        :data:`~cablesim.orbits.mfproblem.MATRIX_FREE_DOF` states.
    log : TraceLog, optional
        Receives every run's records as they come (what the tracing needs to go on after a
        kill), and replays those of an interrupted tracing of the same system and settings
        (:mod:`cablesim.orbits.resume`); its ``partial`` is set to give the diagram so far.
    measure : callable, optional
        ``measure(steps)`` of every orbit traced by dense shooting, from the steps of the flow
        that converged (:meth:`~cablesim.orbits.shooting.Shooting.steps`), in
        :attr:`OrbitPoint.measure` (for the cable: its largest strain, without integrating the
        orbit again).
    through_slack : bool
        Follow the flows through slack segments (``Shooting(through_slack=True)``, the dense
        shooting: the matrix-free one stops at them), so that branches go on where a segment goes
        slack; the system must have ``slack`` functions.

    Returns
    -------
    ResponseDiagram

    Raises
    ------
    BranchesInterrupted
        Ctrl-C or SIGTERM: its ``diagram`` holds the orbits computed until then and the
        bifurcations located on them.
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
    integration = dict(scheme=scheme, steps_per_period=steps_per_period, step_rate=step_rate)
    if through_slack:
        if system.slack is None or matrix_free:
            raise ValueError("through_slack needs a system with slack functions and the dense shooting")
        integration["through_slack"], matrix_free = True, False
    mf = uses_matrix_free(system, matrix_free)
    tracer = _Tracer(system, parameter, st, np.sign(stop - start) or 1.0, state_scale, lam_scale, callback,
                     integration, liouville_tol, switch_size, mf, log, measure)
    tracer.log.partial = lambda: tracer.partial(time.perf_counter() - t_start)
    try:
        with one_blas_thread():  # small dense matrices: a second thread only spins (cablesim.blas)
            tracer.first_branch(u0, start, period, segments)
            tracer.collect_bifurcations(switch_branches, max_period)
    except KeyboardInterrupt:  # keep every orbit and every bifurcation located so far
        tracer.record_located()
        tracer.diagram.stats = tracer.stats(time.perf_counter() - t_start)
        raise BranchesInterrupted(tracer.diagram) from None
    tracer.diagram.stats = tracer.stats(time.perf_counter() - t_start)
    return tracer.diagram


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
    matrix_free: bool | None = None,
    support: float = 1.0,
    log: TraceLog | None = None,
    measure: Callable[[list], float] | None = None,
    through_slack: bool = False,
) -> ResponseDiagram:
    """Periodic responses of the cable over a range of forcing frequency, load factor or support
    motion multiplier.

    Parameters
    ----------
    eom : EquationsOfMotion
        Exact or approximate analysis. With ``parameter="gamma"`` its ``omega`` is the forcing
        frequency.
    parameter : str
        ``"omega"`` (forcing frequency, rad/s), ``"gamma"`` (multiplier of ``FL`` and of the
        supports' motion) or ``"support"`` (multiplier ``s`` of the supports' motion alone, the
        amplitudes ``uA``, ``uB`` of ``eom``).
    start, stop : float
        Range of the parameter; continuation starts at ``start``.
    period : int
        Period of the first branch in forcing periods.
    switch_branches : bool
        Follow the period-doubled branches born at period doublings.
    callback : callable, optional
        Receives every converged :class:`OrbitPoint`; returning True ends that branch.
    gamma : float
        Multiplier of ``FL`` (and of the supports' motion) unless it is the parameter.
    initial_state : ndarray, optional
        Guess of ``(z, y')`` (or ``(z, y', y'')``) at forcing phase 0 at ``start`` (default:
        the linear response).
    segments, max_period, settings, scheme, steps_per_period, step_rate, liouville_tol, matrix_free, log, measure
    through_slack
        See :func:`trace_branches` (the exact analysis with the supports at rest and ``slack:
        continue`` only).
    support : float
        Multiplier ``s`` of the supports' motion when continuing in ``omega`` or ``gamma``.

    Returns
    -------
    ResponseDiagram
        Amplitudes per DOF (``z``), in DOF order.
    """
    if parameter not in ("omega", "gamma", "support") or (parameter == "support" and not eom.moving_supports):
        raise ValueError("parameter must be 'omega', 'gamma' or (with a moving support) 'support'")
    g0 = start if parameter == "gamma" else gamma
    system = cable_system(eom, gamma=g0, support=start if parameter == "support" else support)
    w0 = start if parameter == "omega" else eom.omega
    if not w0 > 0:
        raise ValueError("the forcing frequency must be positive")
    nd = eom.n_dof
    s0 = start if parameter == "support" else support
    u0 = linear_response_state(eom, w0, g0, s0) if initial_state is None else np.asarray(initial_state, float)[: 2 * nd]
    scale, lam_scale = cable_scales(eom, parameter, start, stop, gamma, support)
    return trace_branches(
        system, u0, parameter, start, stop, period=period, segments=segments, state_scale=scale,
        lam_scale=lam_scale, switch_branches=switch_branches, max_period=max_period, callback=callback,
        settings=settings, scheme=scheme, steps_per_period=steps_per_period, step_rate=step_rate,
        liouville_tol=liouville_tol, matrix_free=matrix_free, log=log, measure=measure, through_slack=through_slack,
    )
