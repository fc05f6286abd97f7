"""The :class:`~cablesim.orbits.diagram.OrbitPoint` of a converged point of a continuation (its
amplitudes, multipliers, stability, checks and measures) and the
:class:`~cablesim.orbits.diagram.Bifurcation` of a special one."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..modal import OUT_OF_PLANE
from . import stability
from .diagram import Bifurcation, OrbitPoint
from .problems import labelled_multipliers
from .shooting import Evaluation, Shooting
from .splitleading import labelled_leading
from .symmetry import Mirror, orbit_whirling
from .systems import OdeSystem

#: Samples per forcing period of a nonplanar orbit for its whirling measures.
WHIRL_SAMPLES = 256


def orbit_point(system: OdeSystem, shooting: Shooting, cp, branch: int, index: int, residual_tol: float,
                liouville_tol: float, mirror: Mirror | None = None, measure: Callable | None = None) -> OrbitPoint:
    """The orbit of continuation point ``cp`` (:class:`~cablesim.orbits.continuation.Point`) as
    the ``index``-th point of branch ``branch``: trusted when its residual is within
    ``10 residual_tol`` and Liouville's formula within ``liouville_tol`` (matrix-free: the
    leading eigenpairs' residuals); on a planar orbit the multipliers of both blocks with their
    labels, on a nonplanar one of a spatial cable its whirling measures; ``measure`` (a function
    of the orbit's steps) taken if the flow recorded them."""
    ev: Evaluation = cp.evaluation
    d = system.displacements
    xmax, xmin = ev.xmax[d], ev.xmin[d]
    mu, planes, whirl = ev.multipliers, None, None
    # the orbit at its steps, if its flow recorded them: used here and released (a branch keeps
    # its evaluations while it is traced); without them the measures integrate the orbit again
    steps, value = getattr(ev, "steps", None), None
    if steps is not None:
        ev.steps = None
        value = float(measure(steps)) if measure is not None else None
    if mirror is not None:  # the blocks of the dense monodromy, or the leading multipliers of each
        mu, planes = labelled_multipliers(mirror, ev) if ev.monodromy is not None \
            else labelled_leading(mirror, ev.split, ev.neutral)
    elif getattr(system, "frame", None) is not None and hasattr(shooting, "trajectory"):
        # a nonplanar orbit of a spatial cable (of a symmetric one, or one forced out of its plane)
        whirl = orbit_whirling(system.frame, shooting, cp.u, cp.lam, WHIRL_SAMPLES, steps=steps)
    # Liouville's formula needs the whole spectrum; the leading multipliers' eigenpair residuals
    # are the check of a matrix-free orbit
    check = ev.liouville <= liouville_tol if ev.monodromy is not None or ev.leading is None \
        else ev.leading.residual <= liouville_tol
    trusted = bool(cp.residual <= 10.0 * residual_tol and check and np.all(np.isfinite(mu)))
    # a multiplier forced to +1 by a rotation symmetry is reported but judged neutral: the
    # orbit's stability is that of the others (as an autonomous orbit's, orbital stability)
    nt = ev.neutral or None
    seen = mu if nt is None else np.concatenate([nt.multipliers, _in_plane(ev)] if mirror is not None else
                                                [nt.multipliers])
    return OrbitPoint(
        branch=branch, index=index, parameter=float(cp.lam), omega=ev.omega, period=shooting.period,
        state=cp.u[: shooting.n].copy(), u=cp.u.copy(), amplitude=np.maximum(np.abs(xmax), np.abs(xmin)),
        halfrange=0.5 * (xmax - xmin), multipliers=mu.copy(), stable=stability.is_stable(seen), trusted=trusted,
        residual=float(cp.residual), liouville=float(ev.liouville), special=cp.special, located=cp.located,
        planes=planes, whirl=whirl, measure=value, neutral=nt,
    )


def _in_plane(ev: Evaluation) -> np.ndarray:
    """The in-plane multipliers of a planar orbit: of the dense monodromy's block, or the leading
    ones of the matrix-free block."""
    return ev.blocks_mu[0] if ev.monodromy is not None else ev.split.in_plane.multipliers


def bifurcation_at(p: OrbitPoint, branch: int) -> Bifurcation:
    """The bifurcation at special point ``p`` of branch ``branch`` (on a planar branch of a
    symmetric system: its kind and the block of the critical multiplier)."""
    kind, plane, mu = p.special, None, p.multipliers
    if p.planes is not None:
        kind, plane = stability.SPLIT_KINDS[p.special]
        mu = p.multipliers[np.array(p.planes) == plane]
    if p.neutral is not None and (p.planes is None or plane == OUT_OF_PLANE):
        mu = p.neutral.multipliers  # the critical one is never the neutral multiplier
    crit = stability.critical_multiplier(kind, mu)
    return Bifurcation(
        kind=kind, parameter=p.parameter, branch=branch, period=p.period,
        amplitude=p.amplitude, halfrange=p.halfrange, state=p.state,
        multiplier=crit, multipliers=p.multipliers,
        located=p.located, trusted=p.trusted, point=p.index, plane=plane,
        frequency_ratio=stability.frequency_ratio(crit),
    )
