"""Bifurcation curves traced from located bifurcations: :func:`trace_locus` and :func:`trace_loci`.

:func:`trace_locus` continues one fold, period-doubling or Neimark-Sacker point in two parameters
(:mod:`cablesim.orbits.loci`) in both directions from where it was located, until the curve
leaves the ranges of the parameters (its last point is solved on the bound it crosses), ends at a
strong resonance (a Neimark-Sacker curve at ``1:1`` or ``1:2``), or cannot be followed (a flow
fails: for a cable, a segment goes slack). :func:`trace_loci` does this for every bifurcation of
a :class:`~cablesim.orbits.diagram.ResponseDiagram`, once per curve: a curve that comes back to
the diagram's value of ``p2`` at another bifurcation of the same kind and period (the two edges
of a period-doubling tongue, the two folds of a hysteresis) covers it.

Both work on any :class:`~cablesim.orbits.systems.OdeSystem`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from . import bordered as bd
from .continuation import Settings, continuation
from .loci import CODIM2_TESTS, LocusEvaluation, LocusProblem, TwoParameterFlows
from .shooting import Shooting, solve_orbit
from .systems import OdeSystem

#: Kinds of bifurcation that have curves.
CURVE_KINDS = tuple(bd.RANK_DEFECT)
#: Largest ``|mu + 1|`` of the half-period orbit where a curve of period-2p folds counts as ending
#: on its period-doubling curve.
GPD_TOL = 1e-3


class LociInterrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM while tracing curves: ``loci`` holds the curves traced until then, the
    last one as far as it got (its ends ``"interrupted"``)."""

    def __init__(self, loci: list):
        super().__init__("interrupted")
        self.loci = loci


@dataclass
class LocusPoint:
    """One orbit on a bifurcation curve.

    Attributes
    ----------
    index : int
        Position on the curve.
    p1, p2 : float
        The two parameters (for the cable ``omega`` in rad/s and ``gamma`` or ``support``).
    kappa : float
        ``cos`` of the critical pair's angle (Neimark-Sacker), else NaN.
    state : ndarray (n,)
        State at forcing phase 0.
    u : ndarray (m n,)
        All shooting unknowns.
    amplitude, halfrange : ndarray
        Largest ``|x_i|`` and half the range over the orbit, per displacement component.
    multipliers : ndarray complex
    trusted : bool
        Newton residual and Liouville checks passed.
    special : str or None
        A codimension-two point (:data:`~cablesim.orbits.loci.CODIM2_TESTS`), ``"turning point"``
        (an extremum of ``p2``), ``"level"`` (a crossing of a requested ``p2``), ``"bound"``
        (the end solved on a bound of ``p1``), or None.
    located : bool
    """

    index: int
    p1: float
    p2: float
    kappa: float
    state: np.ndarray
    u: np.ndarray
    amplitude: np.ndarray
    halfrange: np.ndarray
    multipliers: np.ndarray
    trusted: bool
    special: str | None = None
    located: bool = True


@dataclass
class Locus:
    """A bifurcation curve in two parameters.

    Attributes
    ----------
    index : int
    kind : str
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` or ``"pitchfork"`` (of a planar orbit).
    period : int
        Period of the orbits in forcing periods.
    parameters : (str, str)
    points : list of LocusPoint
        In order along the curve.
    ends : (str, str)
        Why the curve ends at its first and at its last point, in words.
    origin : (float, float)
        ``(p1, p2)`` of the bifurcation it was started from.
    evaluations : int
        Locus evaluations (each: the shooting with both parameter derivatives and the displaced
        flows of the second derivatives).
    segments : int
        Segment integrations.
    seconds : float
    """

    index: int
    kind: str
    period: int
    parameters: tuple
    points: list = field(default_factory=list)
    ends: tuple = ("", "")
    origin: tuple = (np.nan, np.nan)
    evaluations: int = 0
    segments: int = 0
    seconds: float = 0.0

    def values(self, name: str) -> np.ndarray:
        """An attribute of every point as an array (``"p1"``, ``"p2"``, ``"amplitude"``, ...)."""
        return np.array([getattr(p, name) for p in self.points])

    @property
    def codim2(self) -> list:
        """The codimension-two points on the curve."""
        return [p for p in self.points if p.special in CODIM2_TESTS[self.kind]]


class _Half:
    """The points of one direction of a curve, with the range of ``p1`` watched."""

    def __init__(self, problem: LocusProblem, system: OdeSystem, p1_range, liouville_tol: float,
                 callback: Callable | None, start: LocusEvaluation | None = None):
        self.problem, self.system = problem, system
        self.lo, self.hi = min(p1_range), max(p1_range)
        self.liouville_tol = liouville_tol
        self.callback = callback
        self.points: list[LocusPoint] = []
        self.cps: list = []
        self.end = ""

    def point(self, ev: LocusEvaluation, u: np.ndarray, special, located, residual: float) -> LocusPoint:
        orb = ev.orbit
        d = self.system.displacements
        xmax, xmin = orb.xmax[d], orb.xmin[d]
        trusted = bool(residual <= 1e-8 and orb.liouville <= self.liouville_tol and np.all(np.isfinite(orb.multipliers)))
        return LocusPoint(index=len(self.points), p1=ev.p1, p2=ev.p2,
                          kappa=ev.kappa if self.problem.extra else np.nan, state=u[: self.problem.n].copy(),
                          u=u[: self.problem.N].copy(), amplitude=np.maximum(np.abs(xmax), np.abs(xmin)),
                          halfrange=0.5 * (xmax - xmin), multipliers=orb.multipliers.copy(), trusted=trusted,
                          special=special, located=located)

    def on_point(self, cp) -> bool:
        ev: LocusEvaluation = cp.evaluation
        special = cp.special
        if special == "fold":
            special = "turning point"
        elif special is not None and special.startswith("level "):
            special = "level"
        self.problem.accept(ev)
        self.points.append(self.point(ev, cp.u, special, cp.located, cp.residual))
        self.cps.append(cp)
        if not self.lo <= ev.p1 <= self.hi:
            self.end = "bound"
            return True
        if special in ("1:1 resonance", "1:2 resonance") and self.problem.kind == "neimark-sacker":
            self.end = f"ends at a {special} (the multiplier pair reaches the real axis)"
            return True
        if self.callback is not None and self.callback(self.points[-1]):
            self.end = "stopped by callback"
            return True
        return False

    def finish(self, status, settings: Settings) -> None:
        """Solve the end on the bound of ``p1`` it crossed, and say why the half ended."""
        if self.end == "bound" and len(self.cps) >= 2:
            a, b = self.cps[-2], self.cps[-1]
            bound = self.hi if b.evaluation.p1 > self.hi else self.lo
            out = _on_bound(self.problem, a, b, bound, settings)
            self.points.pop()
            self.cps.pop()
            if out is not None:
                U, ev, res = out
                self.points.append(self.point(ev, U, "bound", True, res))
            name = self.problem.flows.p1
            self.end = f"reached {name} = {bound:g}" if out is not None else f"left the {name} range"
        elif not self.end:
            name = self.problem.flows.p2
            texts = {0: f"reached the bound of {name}", 1: "most points reached", 2: "step too small",
                     3: "stopped", 4: "start failed"}
            self.end = texts.get(int(status), str(status))
            failure = self.problem.last_failure
            if int(status) in (2, 4) and failure is not None:
                self.end += f" (the flow failed: {failure.name.lower()})"


def _on_bound(problem: LocusProblem, a, b, bound: float, st: Settings):
    """The curve's point with ``p1 = bound`` between the continuation points a and b: Newton on
    the locus equations with ``p1`` fixed, from the linear interpolation; ``(U, evaluation,
    scaled residual)`` or None."""
    N = problem.N
    us, ls, rs = problem.u_scale, problem.lam_scale, problem.r_scale
    f = (bound - a.u[N]) / (b.u[N] - a.u[N])
    U = a.u + f * (b.u - a.u)
    lam = a.lam + f * (b.lam - a.lam)
    U[N] = bound
    for _ in range(st.max_newton + 4):
        ev = problem.evaluate(U, lam)
        if ev is None:
            return None
        R = ev.r / rs
        J = np.hstack([ev.J_u * (us[None, :] / rs[:, None]), (ev.J_lam * ls / rs)[:, None]])
        J = np.delete(J, N, axis=1)  # p1 is held on the bound
        try:
            dv = np.linalg.solve(J, -R)
        except np.linalg.LinAlgError:
            return None
        step = np.insert(dv[:-1], N, 0.0) * us
        res = float(np.abs(R).max())
        if float(np.abs(dv).max()) <= st.newton_tol and res <= st.residual_tol:
            return U, ev, res
        U = U + step
        lam = lam + dv[-1] * ls
    return None


def trace_locus(
    system: OdeSystem,
    kind: str,
    u0: np.ndarray,
    x1: float,
    x2: float,
    p1_range: tuple[float, float],
    p2_range: tuple[float, float],
    parameters: tuple[str, str] = ("omega", "gamma"),
    period: int = 1,
    segments: int = 1,
    kappa: float = 0.0,
    state_scale: np.ndarray | None = None,
    scales: tuple[float, float] | None = None,
    levels=(),
    settings: Settings | None = None,
    subspace: np.ndarray | None = None,
    integration: dict | None = None,
    liouville_tol: float = 1e-3,
    callback: Callable[[LocusPoint], bool | None] | None = None,
    index: int = 0,
    mirror=None,
    plane: str | None = None,
) -> Locus:
    """Continue a bifurcation in two parameters (module docstring).

    Parameters
    ----------
    system : OdeSystem
    kind : str
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` or ``"pitchfork"`` (of a planar orbit).
    u0 : ndarray (m n,)
        Shooting unknowns of the bifurcating orbit (a located point of a branch).
    x1, x2 : float
        Its parameter values.
    p1_range, p2_range : (float, float)
        Ranges of the parameters; the curve ends where it leaves them.
    parameters : (str, str)
        Names of ``p1`` (``"omega"`` or a parameter of ``system.prm``) and ``p2`` (a parameter
        of ``system.prm``).
    period, segments : int
        Of the orbit (forcing periods; shooting segments).
    kappa : float
        Neimark-Sacker: ``Re`` of the critical multiplier at the start.
    state_scale : ndarray (n,), optional
        Default: the largest ``|u0|``.
    scales : (float, float), optional
        Typical sizes of ``p1`` and ``p2`` (default: their largest bounds).
    levels : sequence of float
        Values of ``p2`` at which the curve's crossings are located (``special = "level"``).
    settings : Settings, optional
        Continuation settings (the bounds of ``p2`` are set from ``p2_range``).
    subspace : ndarray (n, q), optional
        See :class:`~cablesim.orbits.loci.LocusProblem`.
    mirror : Mirror, optional
    plane : str, optional
        For a curve of planar orbits of a mirror-symmetric system, and the block of the
        critical multiplier (:class:`~cablesim.orbits.loci.LocusProblem`; required for
        ``"pitchfork"``).
    integration : dict, optional
        ``scheme``, ``steps_per_period``, ``step_rate`` of the shootings.
    liouville_tol : float
        Largest Liouville mismatch of a trusted point.
    callback : callable, optional
        Receives every point; True ends that direction.
    index : int
        The curve's index (for the result).

    Returns
    -------
    Locus
    """
    t0 = time.perf_counter()
    n = system.dim
    if state_scale is None:
        state_scale = np.full(n, max(float(np.abs(u0).max()), 1e-12))
    if scales is None:
        scales = (max(abs(p1_range[0]), abs(p1_range[1])), max(abs(p2_range[0]), abs(p2_range[1])))
    flows = TwoParameterFlows(system, period, segments, parameters, integration)
    problem = LocusProblem(flows, kind, state_scale, scales, subspace, levels, mirror=mirror, plane=plane)
    U0 = problem.start(np.asarray(u0, dtype=float), x1, x2, kappa)
    B0, C0 = problem.borders()
    st = replace(settings or Settings(), lam_min=min(p2_range), lam_max=max(p2_range))
    halves = []
    locus = Locus(index=index, kind=kind, period=period, parameters=tuple(parameters), origin=(float(x1), float(x2)))
    try:
        for direction in (-1.0, 1.0):
            problem.set_borders(B0, C0)
            half = _Half(problem, system, p1_range, liouville_tol, callback)
            halves.append(half)
            res = continuation(problem, U0, x2, st, callback=half.on_point, direction=direction)
            half.finish(res.status, st)
            if half.end.startswith("step too small") and kind == "fold" and period % 2 == 0 and segments % 2 == 0:
                _generalized_period_doubling(half, flows, integration)
    except KeyboardInterrupt:
        halves[-1].end = "interrupted"
        if len(halves) == 1:
            halves.append(_Half(problem, system, p1_range, liouville_tol, None))
            halves[-1].end = "interrupted"
        _assemble(locus, halves, kind, scales, (x1, x2), problem, flows, t0)
        raise LociInterrupted([locus]) from None
    return _assemble(locus, halves, kind, scales, (x1, x2), problem, flows, t0)


def _assemble(locus: Locus, halves: list, kind: str, scales, origin, problem, flows, t0: float) -> Locus:
    """The two halves as one curve (the first reversed), with its ends and cost."""
    first, second = halves
    tail = [p for p in second.points[1:] if not _same(p, second.points[0], scales)] if second.points else []
    if not first.points:  # interrupted before the first point
        first.points = second.points[:1]
    locus.points = first.points[::-1] + tail
    locus.points = _drop_duplicates(locus.points, kind, scales, origin)
    for k, p in enumerate(locus.points):
        p.index = k
    # a curve started on a bound of p2 has no second half: its origin is that end
    locus.ends = (first.end, second.end or first.end)
    locus.evaluations = problem.evaluations
    locus.segments = flows.calls
    locus.seconds = time.perf_counter() - t0
    return locus


def _generalized_period_doubling(half: _Half, flows: TwoParameterFlows, integration: dict | None) -> None:
    """A curve of folds of period-2p orbits that cannot be followed further may be ending on the
    period-doubling curve of the period-p orbits, at a generalized period doubling (where that
    period doubling changes from sub- to supercritical, and the period-2p branch born there
    starts to fold): the two curves meet tangentially and the defining system of the fold
    degenerates as the period-2p orbit shrinks onto the doubled period-p one. The end is named
    so when the period-p orbit at the last point (from the mean of the two laps) has a multiplier
    within :data:`GPD_TOL` of -1; the point is approximate (``located`` False)."""
    if not half.points:
        return
    last = half.points[-1]
    m, n = flows.m, flows.n
    S = last.u.reshape(m, n)
    guess = 0.5 * (S[: m // 2] + S[m // 2 :]).ravel()
    flows.set(last.p1, last.p2)
    sh = Shooting(flows.sh1.system, flows.sh1.period // 2, m // 2, parameter=flows.p1, **(integration or {}))
    sol = solve_orbit(sh, guess, last.p1, scale=np.tile(half.problem.scale, 1))
    if not sol.converged or np.abs(sol.evaluation.multipliers + 1.0).min() > GPD_TOL:
        return
    half.points.append(replace(last, index=len(half.points), special="generalized period doubling", located=False))
    half.end = (f"ends on the period-doubling curve of the period-{flows.sh1.period // 2} orbits "
                "(generalized period doubling)")


def _same(p: LocusPoint, q: LocusPoint, scales, tol: float = 1e-9) -> bool:
    return abs(p.p1 - q.p1) <= tol * scales[0] and abs(p.p2 - q.p2) <= tol * scales[1]


def _drop_duplicates(points: list, kind: str, scales, origin) -> list:
    """Without the turning points that coincide with a located cusp (both tests locate the same
    point) and without level points at the start itself."""
    cusps = [p for p in points if p.special == "cusp"]
    o = LocusPoint(0, origin[0], origin[1], np.nan, None, None, None, None, None, True)
    out = []
    for p in points:
        if p.special == "turning point" and any(_same(p, c, scales, 1e-6) for c in cusps):
            continue
        if p.special == "level" and _same(p, o, scales, 1e-8):
            continue
        out.append(p)
    return out


def _covered(loci: list, kind: str, period: int, x1: float, x2: float, scales) -> bool:
    """Whether a curve already traced passes through the bifurcation ``(x1, x2)``."""
    for loc in loci:
        if loc.kind != kind or loc.period != period:
            continue
        if abs(loc.origin[0] - x1) <= 1e-6 * scales[0] and abs(loc.origin[1] - x2) <= 1e-9 * scales[1]:
            return True
        for p in loc.points:
            if p.special in ("level", "bound", None) and abs(p.p2 - x2) <= 1e-7 * scales[1] \
                    and abs(p.p1 - x1) <= 1e-6 * scales[0]:
                return True
    return False


def trace_loci(
    system: OdeSystem,
    diagram,
    x2: float,
    p1_range: tuple[float, float],
    p2_range: tuple[float, float],
    parameters: tuple[str, str] = ("omega", "gamma"),
    state_scale: np.ndarray | None = None,
    scales: tuple[float, float] | None = None,
    levels=(),
    kinds=CURVE_KINDS,
    settings: Settings | None = None,
    integration: dict | None = None,
    liouville_tol: float = 1e-3,
    callback: Callable[[Locus, LocusPoint], bool | None] | None = None,
) -> list[Locus]:
    """The bifurcation curves through every located, trusted fold, period doubling and
    Neimark-Sacker point of a response diagram (module docstring).

    Parameters
    ----------
    system : OdeSystem
        The system the diagram was traced on.
    diagram : ResponseDiagram
        Traced in ``parameters[0]`` at ``parameters[1] = x2``.
    x2 : float
        The diagram's value of the second parameter.
    p1_range, p2_range, parameters, state_scale, scales, settings, integration, liouville_tol
        See :func:`trace_locus`.
    levels : sequence of float
        Values of ``p2`` whose crossings are located (``x2`` is always one).
    kinds : sequence of str
        Kinds of bifurcation followed.
    callback : callable, optional
        ``callback(locus, point)`` for every point (the locus still being traced); True ends
        that direction of that curve.

    Returns
    -------
    list of Locus
        One per curve, in the order of the diagram's bifurcations that started them.
    """
    if diagram.parameter != parameters[0]:
        raise ValueError(f"the diagram is traced in {diagram.parameter}, not in {parameters[0]}")
    if scales is None:
        scales = (max(abs(p1_range[0]), abs(p1_range[1])), max(abs(p2_range[0]), abs(p2_range[1])))
    levels = tuple(dict.fromkeys([float(x2), *map(float, levels)]))
    loci: list[Locus] = []
    for b in diagram.bifurcations:
        if b.kind not in kinds or not (b.located and b.trusted):
            continue
        mirror = getattr(system, "mirror", None)
        if b.kind == "pitchfork" and mirror is None:
            continue
        if _covered(loci, b.kind, b.period, b.parameter, x2, scales):
            continue
        br = diagram.branches[b.branch]
        p = br.points[b.point]
        index = len(loci)
        shell = Locus(index=index, kind=b.kind, period=b.period, parameters=tuple(parameters))
        cb = None if callback is None else (lambda q, shell=shell: callback(shell, q))
        try:
            loc = trace_locus(system, b.kind, p.u, b.parameter, x2, p1_range, p2_range, parameters=parameters,
                              period=b.period, segments=br.segments, kappa=float(np.real(b.multiplier)),
                              state_scale=state_scale, scales=scales, levels=levels, settings=settings,
                              integration=integration, liouville_tol=liouville_tol, callback=cb, index=index,
                              mirror=mirror if br.planar else None, plane=b.plane)
        except FloatingPointError:
            continue
        except LociInterrupted as exc:
            raise LociInterrupted(loci + [L for L in exc.loci if L.points]) from None
        except KeyboardInterrupt:
            raise LociInterrupted(loci) from None
        loci.append(loc)
    return loci
