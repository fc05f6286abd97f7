"""Design charts of a case: bifurcation curves in (omega, gamma) or (omega, s) and backbone curves.

- :func:`case_loci`: every fold, period doubling and Neimark-Sacker point of a case's frequency
  response, continued in the forcing frequency omega and a second parameter: the load factor
  gamma over ``continuation.gamma``, or the support motion multiplier s over
  ``continuation.support`` (:func:`cablesim.orbits.curves.trace_loci`), with the
  codimension-two points found on the curves; :func:`~cablesim.analyses.continuation.run_continuation`
  calls it when ``continuation.loci`` is set.
- :func:`run_backbone`: the backbone of a linear mode, the unforced, undamped cable's periodic
  orbits from the mode to a given amplitude (:func:`cablesim.orbits.backbone.trace_backbone`).

Case in, result out: plain arrays in the case's channels, ready to be written and drawn. An
interruption (Ctrl-C, SIGTERM) raises :class:`Interrupted`, which carries everything computed so
far, so that the caller can keep it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..case import Case
from ..channels import channel_index
from ..errors import CablesimError, ConvergenceError
from ..orbits import cable_scales, cable_system
from ..orbits.backbone import BackbonePoint, linear_modes, trace_backbone
from ..orbits.conservative import conservative_cable_system
from ..orbits.budget import orbit_budget
from ..orbits.continuation import Settings
from ..orbits.curves import CURVE_KINDS, Locus, LociInterrupted, trace_loci
from .cost import ContinuationCost
from .setup import build_equations
from .static import run_static

#: Short names of the kinds of curves (HDF5 group names ``<short><k>-p<period>``).
SHORT = {"fold": "fold", "period-doubling": "pd", "neimark-sacker": "ns", "pitchfork": "pf"}
#: Fraction of the chord that is the default largest amplitude of a backbone.
DEFAULT_BACKBONE_AMPLITUDE = 0.02
#: Scaled Newton correction at which a backbone orbit counts as converged, per analysis. The
#: approximate analysis's flow map carries round-off of about 1e-13 of the chord (absolute
#: coordinates, inner solves), which the nearly singular direction of the conservative family
#: (the artificial damping) amplifies into corrections of 1e-9 that do not shrink: its start
#: never converged at 1e-9 on modes 2 to 4 of the paper example. Newton converges
#: quadratically, so a correction of 1e-7 leaves an error at the round-off level.
BACKBONE_NEWTON_TOL = {"exact": 1e-9, "approximate": 1e-7}
#: Flows one point of a bifurcation curve takes (the orbit with both parameters' derivatives and
#: the directional flows of its defining function, over a couple of Newton steps).
LOCUS_FLOWS = 6


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM during a chart: ``result`` holds everything computed until then."""

    def __init__(self, result):
        super().__init__("interrupted")
        self.result = result


class CurvesRefused(CablesimError):
    """The bifurcation curves of a traced response diagram would cost more than the limits
    (:func:`loci_cost`): ``result`` holds the branches (``complete`` False), ``cost`` the
    estimate that refused them."""

    def __init__(self, result, cost: ContinuationCost, why: str, second: str = "gamma"):
        super().__init__(f"continuation.loci: the bifurcation curves of the {len(result.branches)} branches traced would "
                         f"take {cost.text().split(': ', 1)[1]}, more than allowed ({why}). Narrow "
                         f"continuation.{second} or "
                         "continuation.omega, or lower continuation.max_points (points per curve direction); "
                         "force=True traces them anyway.", field="continuation.loci")
        self.result = result
        self.cost = cost
        self.why = why
        self.second = second


@dataclass(frozen=True)
class LocusResult:
    """A bifurcation curve in (omega, gamma) or (omega, s).

    Attributes
    ----------
    name : str
        ``"<kind><k>-p<period>"`` (``fold0-p1``, ``pd1-p1``, ...).
    kind : str
        ``fold``, ``period-doubling`` or ``neimark-sacker``.
    period : int
        Period of the bifurcating orbits, in forcing periods.
    omega, gamma, support : ndarray (points,)
        Forcing frequency (rad/s), load factor gamma and support motion multiplier s along the
        curve (the one that is not :attr:`second` constant, at its value in the response).
    kappa : ndarray (points,) or None
        Neimark-Sacker curves: ``cos`` of the angle of the critical multipliers.
    amplitude, halfrange : ndarray (points, channels)
        Largest ``|z|`` and half the range over the bifurcating orbit, m.
    multipliers : ndarray complex (points, 2 n_dof)
    state : ndarray (points, 2 n_dof)
        ``(z, y')`` at forcing phase 0, m and m/s.
    trusted : ndarray of bool (points,)
    special : list of str
        Per point: ``""``, a codimension-two point, ``turning point``, ``level``, ``bound``.
    ends : (str, str)
        Why the curve ends at its first and last point.
    origin : (float, float)
        (omega, second parameter) of the bifurcation it was started from.
    plane : str
        ``out-of-plane`` for a curve of a planar response's out-of-plane bifurcation (a spatial
        cable symmetric about its plane, the critical multiplier in the out-of-plane block of the
        monodromy), else ``in-plane``.
    second : str
        The second parameter of the curve, ``gamma`` or ``support`` (s).
    """

    name: str
    kind: str
    period: int
    omega: np.ndarray
    gamma: np.ndarray
    kappa: np.ndarray | None
    amplitude: np.ndarray
    halfrange: np.ndarray
    multipliers: np.ndarray
    state: np.ndarray
    trusted: np.ndarray
    special: list
    ends: tuple
    origin: tuple
    plane: str = "in-plane"
    support: np.ndarray | None = None
    second: str = "gamma"

    @property
    def values2(self) -> np.ndarray:
        """The second parameter along the curve (:attr:`gamma` or :attr:`support`)."""
        return getattr(self, self.second)


@dataclass(frozen=True)
class Codim2Result:
    """A codimension-two point on a curve: ``kind`` (``cusp``, ``fold-flip``, ``1:1 resonance``,
    ``1:2 resonance``, ``1:3 resonance``, ``1:4 resonance``, ``fold-neimark-sacker``,
    ``flip-neimark-sacker``, ``generalized period doubling``), where (``omega`` rad/s,
    ``gamma``, ``support`` s), on which ``locus`` (index), the orbit's ``amplitude`` per channel
    (m) and whether it was ``located`` (the secant converged); ``second``: the curve's second
    parameter (``gamma`` or ``support``)."""

    kind: str
    omega: float
    gamma: float
    locus: int
    amplitude: np.ndarray
    located: bool
    support: float = 1.0
    second: str = "gamma"

    @property
    def value2(self) -> float:
        """The second parameter there (:attr:`gamma` or :attr:`support`)."""
        return getattr(self, self.second)


def _locus_plane(loc: Locus, diagram) -> str:
    """The block of the critical multiplier of the bifurcation a curve was started from."""
    for b in diagram.bifurcations:
        if b.kind == loc.kind and b.period == loc.period and abs(b.parameter - loc.origin[0]) <= 1e-9 * abs(
                loc.origin[0]):
            return b.plane or "in-plane"
    return "in-plane"


def _along(loc: Locus, second: str, fixed: dict) -> dict:
    """``omega``, ``gamma`` and ``support`` along a curve whose second parameter is ``second``
    (the other at its value ``fixed`` in the response)."""
    p2 = loc.values("p2").astype(float)
    out = {k: np.full(p2.size, float(v)) for k, v in fixed.items()}
    out[second] = p2
    out["omega"] = loc.values("p1").astype(float)
    return out


def _locus_result(loc: Locus, idx: np.ndarray, plane: str, second: str, fixed: dict) -> LocusResult:
    pts = loc.points
    nch = idx.size
    return LocusResult(plane=plane, second=second, **_along(loc, second, fixed),
        name=f"{SHORT[loc.kind]}{loc.index}-p{loc.period}", kind=loc.kind, period=int(loc.period),
        kappa=loc.values("kappa").astype(float) if loc.kind == "neimark-sacker" else None,
        amplitude=np.array([p.amplitude[idx] for p in pts]).reshape(len(pts), nch),
        halfrange=np.array([p.halfrange[idx] for p in pts]).reshape(len(pts), nch),
        multipliers=np.array([p.multipliers for p in pts]), state=np.array([p.state for p in pts]),
        trusted=np.array([p.trusted for p in pts], dtype=bool), special=[p.special or "" for p in pts],
        ends=tuple(loc.ends), origin=tuple(float(x) for x in loc.origin))


def _codim2(loci: list, idx: np.ndarray, second: str, fixed: dict) -> list:
    out = []
    for k, loc in enumerate(loci):
        for p in loc.codim2 + [p for p in loc.points if p.special == "generalized period doubling"]:
            at = {**fixed, second: float(p.p2)}
            out.append(Codim2Result(kind=p.special, omega=float(p.p1), gamma=at["gamma"], support=at["support"],
                                    second=second, locus=k, amplitude=np.asarray(p.amplitude)[idx],
                                    located=bool(p.located)))
    return out


def _results(case: Case, loci: list, diagram, idx: np.ndarray) -> tuple[list, list]:
    """The curves and their codimension-two points as results, in the case's channels."""
    spec = case.continuation
    second = spec.loci_parameter
    fixed = {"gamma": spec.fixed_gamma, "support": spec.fixed_support}
    return ([_locus_result(L, idx, _locus_plane(L, diagram), second, fixed) for L in loci],
            _codim2(loci, idx, second, fixed))


def case_loci(case: Case, eom, diagram, idx: np.ndarray, progress: Callable | None = None):
    """The bifurcation curves of a case's frequency response (module docstring).

    Parameters
    ----------
    case : Case
        ``continuation.loci`` set; ``continuation.gamma`` or ``continuation.support`` the range
        of the curves' second parameter (its ``levels``: the values whose crossings are located
        on every curve).
    eom : EquationsOfMotion
        Of the case (its ``FL`` is what gamma multiplies; its support amplitudes ``uA``, ``uB``
        what gamma and s multiply).
    diagram : ResponseDiagram
        The frequency response at the second parameter's ``at`` (the other at its value).
    idx : ndarray of int
        DOF indices of the channels reported.
    progress : callable, optional
        ``progress(locus, point)`` for every point of every curve.

    Returns
    -------
    (list of LocusResult, list of Codim2Result, dict)
        The curves, their codimension-two points and the cost counters.

    Raises
    ------
    LociInterrupted
        On Ctrl-C or SIGTERM, with the curves traced until then (the last one partial).
    """
    spec = case.continuation
    second, g, w = spec.loci_parameter, spec.loci_range, spec.omega
    g0, s0 = spec.fixed_gamma, spec.fixed_support
    system = cable_system(eom, gamma=g0, support=s0)
    top = max(g.start, g.stop)
    # the state scale at the largest forcing the curves may reach
    scale, w_scale = (cable_scales(eom, "omega", w.start, w.stop, top, s0) if second == "gamma" else
                      cable_scales(eom, "omega", w.start, w.stop, g0, top))
    g_scale = max(abs(g.start), abs(g.stop))
    loci = trace_loci(system, diagram, spec.loci_response, (w.start, w.stop), (g.start, g.stop),
                      parameters=("omega", second), state_scale=scale, scales=(w_scale, g_scale), levels=g.levels,
                      settings=Settings(max_points=spec.max_points), callback=progress)
    stats = {"loci_evaluations": sum(L.evaluations for L in loci), "loci_points": sum(len(L.points) for L in loci),
             "loci_seconds": sum(L.seconds for L in loci)}
    return (*_results(case, loci, diagram, idx), stats)


def loci_cost(case: Case, eom, diagram) -> ContinuationCost:
    """The most the bifurcation curves of ``diagram`` (traced, with ``continuation.loci``) can
    take, before they start: a curve from every located, trusted bifurcation of a kind that is
    followed (some turn out to be covered by another's curve: an upper bound), each up to
    ``continuation.max_points`` points in both directions, each point about
    :data:`LOCUS_FLOWS` flows of its orbit's period (the shooting's own step rule over the
    omega range); seconds from the branches' pace, steps per second."""
    spec = case.continuation
    w = spec.omega
    budget = orbit_budget(eom, "omega", w.start, w.stop, 1, spec.segments, spec.fixed_gamma, spec.fixed_support)
    starts = [b for b in diagram.bifurcations if b.kind in CURVE_KINDS and b.located and b.trusted]
    points = 2 * spec.max_points * len(starts)
    steps = 2.0 * spec.max_points * LOCUS_FLOWS * budget.mean_steps * sum(b.period for b in starts)
    taken, seconds = diagram.stats.get("steps", 0), diagram.stats.get("seconds", 0.0)
    pace = seconds / taken if taken > 0 and seconds > 0 else float("nan")
    return ContinuationCost("bifurcation curves", steps, points, budget.working + budget.per_orbit * points, 0.0,
                            f"{len(starts)} curves of up to {2 * spec.max_points} points, each about {LOCUS_FLOWS} "
                            f"flows of {budget.mean_steps:.3g} steps per forcing period", seconds=pace * steps,
                            most=True)


def finish_loci(case: Case, eom, diagram, idx: np.ndarray, progress=None):
    """:func:`case_loci`, keeping what was traced when interrupted: ``(loci, codim2, stats,
    interrupted)``."""
    try:
        return (*case_loci(case, eom, diagram, idx, progress), False)
    except LociInterrupted as exc:
        return (*_results(case, exc.loci, diagram, idx), {}, True)


# ----------------------------------------------------------------------------------------------
# Backbones
# ----------------------------------------------------------------------------------------------
@dataclass
class BackboneResult:
    """A backbone curve of the case.

    Attributes
    ----------
    mode : int
        Linear mode it starts from (1-based).
    linear_omega : float
        Its linear frequency, rad/s.
    modal_omega : ndarray
        All linear frequencies of the undamped cable, rad/s.
    channels : list of str
    amplitude_max : float
        The largest amplitude asked for, m.
    omega : ndarray (points,)
        Frequency of the free periodic orbit, rad/s.
    amplitude, halfrange : ndarray (points, channels)
        Largest ``|z|`` and half the range over the orbit, m.
    multipliers : ndarray complex (points, 2 n_dof)
    ratios : ndarray (points, modes - 1)
        Frequency of each other mode about the orbit over the orbit's frequency.
    stable, trusted : ndarray of bool (points,)
    state : ndarray (points, 2 n_dof)
        ``(z, y')`` at ``t = 0`` (a turning point of the mode's largest displacement).
    delta : ndarray (points,)
        The artificial damping, 1/s (zero up to round-off: a check).
    resonances : list of dict
        Internal resonances met: ``kind``, ``omega``, ``amplitude`` (channels), ``mode``
        (the other mode), ``located``.
    end : str
        Why the backbone ended.
    complete : bool
        False when interrupted.
    """

    mode: int
    linear_omega: float
    modal_omega: np.ndarray
    channels: list
    amplitude_max: float
    omega: np.ndarray
    amplitude: np.ndarray
    halfrange: np.ndarray
    multipliers: np.ndarray
    ratios: np.ndarray
    stable: np.ndarray
    trusted: np.ndarray
    state: np.ndarray
    delta: np.ndarray
    resonances: list
    end: str
    analysis: str
    case_name: str
    case_text: str
    complete: bool = True
    stats: dict = field(default_factory=dict)
    #: Components per node of the cable (2 planar, 3 spatial), which the channels' DOF count in.
    components: int = 2

    @property
    def other_modes(self) -> list[int]:
        """The modes of :attr:`ratios`, 1-based."""
        return [k + 1 for k in range(self.modal_omega.size) if k != self.mode - 1]


def backbone_channels(case: Case) -> tuple[list[str], np.ndarray]:
    """Channel names and DOF indices of a backbone: ``backbone.channels``, else the
    continuation's or the history's, else every DOF."""
    dim = case.dim
    n_dof = dim * case.cable.n_nodes
    spec = case.continuation
    names = (case.backbone.channels or (spec.channels if spec is not None else None) or case.history.channels
             or [f"z{i + 1}" for i in range(n_dof)])
    idx = np.array([channel_index(c, n_dof, dim) for c in names], dtype=int)
    return [f"z{i + 1}" for i in idx], idx


def _backbone_result(points: list, bb_meta: dict, names, idx, end: str, complete: bool) -> BackboneResult:
    n = len(points)
    nch = idx.size
    res = [dict(kind=p.special, omega=float(p.omega), amplitude=p.amplitude[idx], located=bool(p.located),
                mode=int(p.special.rsplit(" ", 1)[-1])) for p in points if p.special]
    return BackboneResult(
        omega=np.array([p.omega for p in points], dtype=float),
        amplitude=np.array([p.amplitude[idx] for p in points]).reshape(n, nch),
        halfrange=np.array([p.halfrange[idx] for p in points]).reshape(n, nch),
        multipliers=np.array([p.multipliers for p in points]).reshape(n, -1),
        ratios=np.array([p.ratios for p in points]).reshape(n, -1),
        stable=np.array([p.stable for p in points], dtype=bool),
        trusted=np.array([p.trusted for p in points], dtype=bool),
        state=np.array([p.state for p in points]).reshape(n, -1), delta=np.array([p.delta for p in points]),
        resonances=res, end=end, complete=complete, channels=names, **bb_meta)


def run_backbone(case: Case, mode: int | None = None, amplitude: float | None = None,
                 analysis: str | None = None, progress: Callable[[BackbonePoint], None] | None = None
                 ) -> BackboneResult:
    """The backbone of a linear mode of the case (module docstring).

    Parameters
    ----------
    case : Case
    mode : int, optional
        Linear mode (1-based; default ``backbone.mode``).
    amplitude : float, optional
        Follow the family until the largest ``|z|`` of the channels reaches this, m (default
        ``backbone.amplitude``, else 2 % of the chord).
    analysis : str, optional
        Overrides the case's analysis.
    progress : callable, optional
        Receives every orbit of the family.

    Raises
    ------
    CablesimError
        A mode the cable does not have.
    Interrupted
        On Ctrl-C or SIGTERM, with the orbits computed until then (``result.complete`` False).
    """
    spec = case.backbone
    k = int(mode if mode is not None else spec.mode)
    n_dof = case.dim * case.cable.n_nodes
    if not 1 <= k <= n_dof:
        raise CablesimError(f"--mode {k}: this cable has {n_dof} modes; give a mode from 1 to {n_dof}.",
                            field="backbone.mode")
    static = run_static(case, analysis, all_models=False)
    eom = build_equations(case, static, omega=float(static.modes.omega[0]), load_scale=1.0)
    a_max = float(amplitude if amplitude is not None else
                  spec.amplitude if spec.amplitude is not None else DEFAULT_BACKBONE_AMPLITUDE * eom.cable.chord_length)
    names, idx = backbone_channels(case)
    system = conservative_cable_system(eom)
    freqs, _ = linear_modes(system, "delta")
    points: list = []
    meta = dict(mode=k, linear_omega=float(freqs[k - 1]), modal_omega=freqs, amplitude_max=a_max,
                analysis=static.analysis, case_name=case.name, case_text=case.text, components=case.dim)

    def collect(p):
        points.append(p)
        if progress is not None:
            progress(p)

    t0 = time.perf_counter()
    try:
        settings = Settings(max_points=spec.max_points, newton_tol=BACKBONE_NEWTON_TOL[static.analysis])
        bb = trace_backbone(system, k, a_max, channels=np.searchsorted(system.displacements, idx),
                            settings=settings, max_ratio=spec.max_ratio, callback=collect)
    except KeyboardInterrupt:
        raise Interrupted(_backbone_result(points, meta, names, idx, "interrupted", False)) from None
    if not bb.points:
        raise ConvergenceError(
            f"The backbone of mode {k} could not start ({bb.end}): Newton's method did not converge on the "
            f"linear mode's orbit at {0.01 * a_max:.3g} m (1 % of the amplitude asked for). Try another "
            f"--amplitude, or the other analysis (--analysis).", field="backbone.amplitude")
    end = f"reached {a_max:g} m (the largest |z| of {', '.join(names)})" if bb.end.startswith("reached the amp") else bb.end
    out = _backbone_result(bb.points, meta, names, idx, end, True)
    out.stats = {"evaluations": bb.evaluations, "segments": bb.segments, "points": len(bb.points),
                 "seconds": bb.seconds, "wall": time.perf_counter() - t0}
    return out
