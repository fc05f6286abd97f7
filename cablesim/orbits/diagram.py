"""The results of a branch tracing: points, branches, bifurcations and the response diagram.

Filled by :func:`cablesim.orbits.branches.trace_branches` (:mod:`cablesim.orbits.branches`
documents the amplitudes, the stability and the *trusted* flag of every point); also importable
from there.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from .shooting import FlowStatus


class BranchEnd(IntEnum):
    """Why a branch ended (the continuation's :class:`~cablesim.orbits.continuation.Status`
    plus :attr:`MERGED`)."""

    BOUND_REACHED = 0
    MAX_POINTS = 1
    STEP_TOO_SMALL = 2
    STOPPED_BY_CALLBACK = 3
    START_FAILED = 4
    MERGED = 5
    INTERRUPTED = 6


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
        Residual and Liouville checks passed (:mod:`cablesim.orbits.branches`).
    residual : float
        Scaled Newton residual (max norm).
    liouville : float
        ``|log det(monodromy) - int tr J dt|``.
    special : str or None
        ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"``, ``"branch-point"`` at a located
        bifurcation, else None.
    located : bool
        For a special point: whether the location converged.
    planes : tuple of str or None
        On a planar orbit of a mirror-symmetric system (:mod:`cablesim.orbits.symmetry`): the
        block of every multiplier, ``"in-plane"`` or ``"out-of-plane"``; special points are then
        also ``"pitchfork"``, ``"out-of-plane period-doubling"`` or
        ``"out-of-plane neimark-sacker"``.
    whirl : Whirling or None
        On a nonplanar orbit of a spatial cable whose equilibrium lies in a plane: the signed
        area of every node's path across the plane, its largest ``|w|`` and the tilt of the
        orbit's mean plane (:func:`~cablesim.orbits.symmetry.whirling_measures`).
    measure : float or None
        The tracing's ``measure`` of the orbit (:func:`~cablesim.orbits.branches.trace_branches`:
        for the cable its largest strain), taken on the steps of the flow that converged; None
        where it was not taken then (an orbit restored from a journal, or no ``measure``).
    neutral : Neutral or None
        The multiplier forced to +1 by a rotation symmetry of the system, excluded from the
        bifurcation tests and the stability (:mod:`cablesim.orbits.rotation`; among
        ``multipliers``, of the out-of-plane block on a planar orbit), with its residual
        ``|M g - g| / |g|``; None where no multiplier was excluded.
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
    planes: tuple | None = None
    whirl: object = None
    measure: float | None = None
    neutral: object = None


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
    plane : str or None
        Which block of a split monodromy the critical multiplier belongs to (``"in-plane"`` or
        ``"out-of-plane"``; :mod:`cablesim.orbits.symmetry`), None on an orbit whose monodromy
        is not split.
    frequency_ratio : float or None
        ``|arg(mu)| / 2 pi`` of the critical multiplier: 0 at a fold or pitchfork, 1/2 at a
        period doubling, between them at a Neimark-Sacker point (the ratio of the new frequency
        to the orbit's).
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
    plane: str | None = None
    frequency_ratio: float | None = None


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
    planar : bool
        Its orbits lie in the mirror plane of a symmetric system, and their monodromy is split
        into in-plane and out-of-plane blocks (:mod:`cablesim.orbits.symmetry`).
    mirror_image : bool
        A nonplanar branch born at a pitchfork: its mirror image through the plane
        (``w -> -w``) is a branch too, not computed. It ends (:attr:`BranchEnd.MERGED`) where
        it returns to the plane.
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
    planar: bool = False
    mirror_image: bool = False

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
        """(points, k): a matrix-free branch keeps the leading multipliers only, as many as each
        point needs; the rows are padded with NaN to the longest."""
        k = max((p.multipliers.size for p in self.points), default=0)
        out = np.full((len(self.points), k), np.nan, dtype=complex)
        for i, p in enumerate(self.points):
            out[i, : p.multipliers.size] = p.multipliers
        return out


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


class BranchesInterrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM while branches were traced: ``diagram`` holds every orbit computed until
    then (the branch being traced ends :attr:`BranchEnd.INTERRUPTED`)."""

    def __init__(self, diagram: ResponseDiagram):
        super().__init__("interrupted")
        self.diagram = diagram
        if diagram.branches:
            diagram.branches[-1].end = BranchEnd.INTERRUPTED
