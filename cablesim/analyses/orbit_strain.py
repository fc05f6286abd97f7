"""The largest strain of every orbit of a continuation, and the warning for orbits beyond the model.

The strain ``(l - S) / S`` of every segment is taken at every integration step of the orbit
from the node positions ``y0 + z``: on the steps of the flow that converged, recorded while the
orbit was traced (:func:`strain_measure`, the tracing's ``measure``), or, for an orbit traced
without them (restored from a journal, or shot matrix-free), on the steps of one more
integration from its shooting unknowns without the variational equations (the same numbers:
the state's arithmetic does not depend on them). in the exact analysis this
is ``T / EA``; in the approximate one it is the stretch of the displaced cable (the supports
taken at their places at rest: a moving support's own motion is not counted). Orbits whose
largest strain is beyond the model's small strains
(:func:`~cablesim.analyses.static.beyond_small_strains`, the rule of the static and history
warnings) are flagged in the result and the file, and the continuation warns of them.
"""

from __future__ import annotations

import numpy as np

from ..orbits.shooting import Shooting
from ..orbits.systems import cable_system
from .static import SMALL_STRAINS_TEXT, beyond_small_strains


def strain_measure(eom):
    """The largest strain ``(l - S) / S`` of an orbit of ``eom`` from its steps (a function of
    :meth:`~cablesim.orbits.shooting.Shooting.steps`; the ``measure`` of
    :func:`~cablesim.orbits.continue_branches`)."""
    nd, cable, y0 = eom.n_dof, eom.cable, eom.y0

    def largest(steps: list) -> float:
        z = np.concatenate([rec[:, :nd] for _, rec in steps])
        return float(np.max(segment_strains(cable, y0 + z)))

    return largest


def orbit_strains(eom, branch, parameter: str, gamma: float, support: float) -> np.ndarray:
    """The largest strain ``(l - S) / S`` over each orbit of ``branch`` (an
    :class:`~cablesim.orbits.diagram.OrbitBranch`): its :attr:`~cablesim.orbits.diagram.OrbitPoint.measure`
    if the tracing took it (:func:`strain_measure`), else from the steps of one more
    integration; NaN where the orbit cannot be integrated again.

    Parameters
    ----------
    eom : EquationsOfMotion
        The equations the branch was traced with.
    branch : OrbitBranch
    parameter : str
        The continuation parameter (``omega``, ``gamma`` or ``support``).
    gamma, support : float
        Their values when they are not the parameter.
    """
    if not branch.points:
        return np.zeros(0)
    out = np.full(len(branch.points), np.nan)
    todo = [i for i, p in enumerate(branch.points) if p.measure is None]
    for i, p in enumerate(branch.points):
        if p.measure is not None:
            out[i] = p.measure
    if not todo:
        return out
    g0 = branch.points[0].parameter if parameter == "gamma" else gamma
    s0 = branch.points[0].parameter if parameter == "support" else support
    system = cable_system(eom, gamma=g0, support=s0)
    # the orbit's own period and segments; a dense flow whatever shot it (no variational equations)
    segments = max(1, branch.points[-1].u.size // system.dim)
    sh = Shooting(system, period=branch.period, segments=segments, parameter=parameter)
    largest = strain_measure(eom)
    for i in todo:
        p = branch.points[i]
        if p.u.size != segments * system.dim:
            continue
        try:
            out[i] = largest(sh.steps(p.u, p.parameter))
        except FloatingPointError:
            continue
    return out


def segment_strains(cable, y: np.ndarray) -> np.ndarray:
    """``(l - S) / S`` of every segment (columns) of the configurations ``y`` (rows of node
    coordinates, ``dim n`` each), the supports at their places at rest."""
    y = np.atleast_2d(y)
    dim = cable.dim
    ends = (np.broadcast_to(np.asarray(cable.support_A, dtype=float), (y.shape[0], 1, dim)),
            np.broadcast_to(np.asarray(cable.support_B, dtype=float), (y.shape[0], 1, dim)))
    nodes = np.concatenate([ends[0], y.reshape(y.shape[0], -1, dim), ends[1]], axis=1)
    lengths = np.linalg.norm(np.diff(nodes, axis=1), axis=2)
    return lengths / np.asarray(cable.S, dtype=float) - 1.0


def strain_warning(names: list, strains: list, parameter: str, values: list) -> list:
    """The warning of a continuation whose orbits go beyond the model's small strains (one
    paragraph; empty if none do). ``names``, ``strains`` and ``values``: per branch, its name,
    its orbits' largest strains and their parameter values."""
    flagged = [(n, s, v) for n, s, v in zip(names, strains, values) if np.any(beyond_small_strains(s))]
    if not flagged:
        return []
    count = sum(int(np.sum(beyond_small_strains(s))) for _, s, _ in flagged)
    name, s, v = max(flagged, key=lambda f: np.nanmax(f[1]))
    k = int(np.nanargmax(s))
    return [f"the strain T/EA of {count} orbit{'s' if count != 1 else ''} (on {', '.join(n for n, _, _ in flagged)}) "
            f"goes beyond {SMALL_STRAINS_TEXT}, up to {100 * s[k]:.3g} % on {name} at {parameter} = {v[k]:.6g}: "
            "these are not the motions of a real cable (they are flagged in the file, dataset `strained` of each "
            "branch). Check the loads (loads.FL, continuation.gamma) and cable.EA."]
