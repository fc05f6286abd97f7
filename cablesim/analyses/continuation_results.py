"""The results of a continuation (:mod:`cablesim.analyses.continuation`): plain arrays per
branch in the case's channels, the bifurcations found, and what is needed to store and draw them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..modal import IN_PLANE
from .orbit_slack import BranchSlack, Grazing
from .static import beyond_small_strains


@dataclass(frozen=True)
class BranchResult:
    """One branch of periodic responses.

    Attributes
    ----------
    name : str
        ``"b<k>-p<period>"``.
    period : int
        Response period in forcing periods.
    parameter : ndarray (points,)
        Value of the continuation parameter (omega in rad/s, gamma, or the support multiplier s).
    omega : ndarray (points,)
        Forcing frequency, rad/s.
    gamma : ndarray (points,)
        Scale of FL (and of the supports' motion).
    amplitude, halfrange : ndarray (points, channels)
        Largest ``|z|`` over the orbit and half its peak-to-peak range, m.
    stable, trusted : ndarray of bool (points,)
        All Floquet multipliers inside the unit circle; multipliers that passed the accuracy
        checks (Newton residual and Liouville's formula).
    multipliers : ndarray complex (points, 2 n_dof)
        Floquet multipliers, by decreasing modulus.
    state : ndarray (points, 2 n_dof)
        ``(z, y')`` at forcing phase 0, m and m/s.
    parent : int or None
        Branch it was switched from (period doubling).
    end : str
        Why the branch ended.
    planes : ndarray of str (points, 2 n_dof) or None
        The block of every multiplier, ``in-plane`` or ``out-of-plane``, on a branch of planar
        orbits of a spatial cable symmetric about its plane (``coupled`` on a nonplanar branch
        of a spatial cable, ``in-plane`` for a planar cable).
    planar : bool
        Whether its orbits lie in the plane of a mirror-symmetric spatial cable.
    mirror_image : bool
        A nonplanar branch born at a pitchfork: its mirror image ``w -> -w`` exists too.
    whirl_area : ndarray (points, n_nodes) or None
        Spatial cable: the signed area of each node's path in its cross-section plane ``(w, v)``
        over the orbit, m^2 (positive counter-clockwise as seen from support A looking towards
        B; zero on a planar orbit, NaN where not measured).
    tilt : ndarray (points,) or None
        Spatial cable: the angle of the orbit's mean plane of motion from the cable's plane, deg.
    support : ndarray (points,) or None
        The support motion multiplier s: the supports move by ``gamma s`` times the amplitudes of
        ``supports:`` (None: 1 throughout).
    max_w : ndarray (points, n_nodes) or None
        Spatial cable: each node's largest out-of-plane displacement ``|w|`` over the orbit
        (along the normal of the equilibrium's plane), m.
    whirl_sense : ndarray of str (points, n_nodes) or None
        Spatial cable: the sense in which each node goes round, seen from support A looking
        towards B: ``counter-clockwise``, ``clockwise`` or ``none``
        (:func:`~cablesim.orbits.symmetry.rotation_sense`).
    strain : ndarray (points,) or None
        The largest strain ``(l - S) / S`` over each orbit (:mod:`cablesim.analyses.orbit_strain`;
        NaN: not measured), which :attr:`strained` judges.
    neutral_residual : ndarray (points,) or None
        A cable symmetric about rotations of its chord (a taut stay without sag): on orbits that
        the rotation moves, one multiplier is +1 by the symmetry and is excluded from the
        bifurcation tests and the stability (:mod:`cablesim.orbits.rotation`); here
        ``|M g - g| / |g|`` of its eigenvector ``g`` (NaN: nothing excluded at that point).
        None if no point of the branch excluded one.
    slack : BranchSlack or None
        Through slack: every orbit's slack episodes, slack fraction and snap loads per segment
        (:mod:`cablesim.analyses.orbit_slack`).
    """

    name: str
    period: int
    parameter: np.ndarray
    omega: np.ndarray
    gamma: np.ndarray
    amplitude: np.ndarray
    halfrange: np.ndarray
    stable: np.ndarray
    trusted: np.ndarray
    multipliers: np.ndarray
    state: np.ndarray
    parent: int | None
    end: str
    planes: np.ndarray | None = None
    planar: bool = False
    mirror_image: bool = False
    whirl_area: np.ndarray | None = None
    tilt: np.ndarray | None = None
    support: np.ndarray | None = None
    max_w: np.ndarray | None = None
    whirl_sense: np.ndarray | None = None
    strain: np.ndarray | None = None
    neutral_residual: np.ndarray | None = None
    slack: BranchSlack | None = None

    @property
    def strained(self) -> np.ndarray:
        """Orbits whose largest strain is beyond the model's small strains
        (:func:`~cablesim.analyses.static.beyond_small_strains`; False where not measured)."""
        if self.strain is None:
            return np.zeros(self.parameter.size, dtype=bool)
        return beyond_small_strains(np.nan_to_num(self.strain, nan=0.0))

    @property
    def nonplanar(self) -> bool:
        """A branch of a spatial cable whose orbits leave the plane (whirling)."""
        return self.tilt is not None and not self.planar


@dataclass(frozen=True)
class BifurcationResult:
    """A located bifurcation: ``kind`` (``fold``, ``period-doubling``, ``neimark-sacker``,
    ``branch-point``, or ``grazing``: the last orbit before a segment goes slack), where (``parameter``, ``omega``), on which ``branch`` (index), the orbit's
    ``period`` and ``amplitude`` per channel (m), the critical ``multiplier``, and whether the
    location converged (``located``) and its multipliers passed the accuracy checks (``trusted``);
    ``plane``: the block of the critical multiplier (``in-plane``, ``out-of-plane``; ``coupled``
    on a nonplanar orbit of a spatial cable), where an out-of-plane multiplier through +1 is a
    ``pitchfork``; ``frequency_ratio``: ``|arg(mu)| / 2 pi`` of the critical multiplier (0 at a fold or
    pitchfork, 1/2 at a period doubling, the new frequency over the orbit's at a Neimark-Sacker
    point); ``gamma`` and ``support`` (the multiplier s of the supports' amplitudes) there;
    ``grazing``: through slack, the located grazing orbit (segment, episode counts and
    multipliers on both sides, :class:`~cablesim.analyses.orbit_slack.Grazing`)."""

    kind: str
    parameter: float
    omega: float
    branch: int
    period: int
    amplitude: np.ndarray
    multiplier: complex
    located: bool
    trusted: bool
    plane: str = IN_PLANE
    frequency_ratio: float = 0.0
    gamma: float = 1.0
    support: float = 1.0
    grazing: Grazing | None = None


@dataclass
class ContinuationResult:
    """Every branch and bifurcation found, with what is needed to store and draw them."""

    parameter: str
    start: float
    stop: float
    fixed: float
    channels: list[str]
    branches: list[BranchResult]
    bifurcations: list[BifurcationResult]
    analysis: str
    modal_omega: np.ndarray
    case_name: str
    case_text: str
    stats: dict = field(default_factory=dict)
    #: With ``continuation.loci``: the bifurcation curves in (omega, gamma) or (omega, s), their
    #: codimension-two points (:mod:`cablesim.analyses.charts`), the curves' second parameter
    #: (``gamma`` or ``support``) and its range.
    loci: list = field(default_factory=list)
    codim2: list = field(default_factory=list)
    loci_range: tuple | None = None
    loci_parameter: str = "gamma"
    #: False when an interruption came while the branches or the curves were traced (what was
    #: done is kept).
    complete: bool = True
    #: Why no orbit could be computed at the start of the range ("" if one was).
    start_failure: str = ""
    #: Plausibility warnings (one paragraph each), also stored in the result file.
    warnings: list = field(default_factory=list)
    #: The kind of failure of the first orbit: ``SLACK``, ``NONFINITE``, ``INNER_SOLVE``, or
    #: ``NEWTON`` (no convergence), "" when it was computed.
    start_cause: str = ""
    #: gamma when it is not the parameter (with the support parameter, ``fixed`` is omega).
    fixed_gamma: float = 1.0
    #: The support multiplier s when it is not the parameter (with loci in s: the response's).
    fixed_support: float = 1.0
    #: The amplitude (m, one component per axis) of each moving support at support multiplier
    #: s = 1 and gamma = 1, as ``supports:`` gives it: ``{"A": array, ...}``.
    support_amplitudes: dict = field(default_factory=dict)
    #: Components per node of the cable: 2 (planar) or 3 (spatial), which the DOF of
    #: ``channels`` count in.
    components: int = 2
    #: The orbits were followed through slack (``continuation.through_slack``).
    through_slack: bool = False

    @property
    def n_points(self) -> int:
        """Points over all branches."""
        return int(sum(b.parameter.size for b in self.branches))
