"""Point loads and masses placed by position (``loads.point`` items with ``x`` or ``s``).

A node's position along the cable is known before the statics only through its natural length
from support A: node ``i`` lies at the fraction ``s_i = (S_1 + ... + S_i) / sum(S)`` of the
natural length, and is taken at ``x_i = s_i L`` along the span (on the chord, in proportion to
the natural length). An item at ``s`` or ``x`` goes on the interior node nearest that position
(of two equally near, the one nearer support A); the distance between the two, the snap
distance, is stated with the case (``cablesim check``, ``cablesim static``, and the result
file's ``/case/point_loads`` table).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class Placement:
    """Where one item of ``loads.point`` went.

    Attributes
    ----------
    item : int
        Its place in ``loads.point``, from 1.
    given : str
        How it was given: ``"node 20"``, ``"x = 150 m"`` or ``"s = 0.5"``.
    node : int
        The interior node it was placed on, from 1 at support A.
    node_s : float
        That node's fraction of the natural length from support A.
    node_x : float
        That node's position along the span, m (``node_s * L``).
    snap : float
        Distance from the given position to the node's, m: along the span for ``x``, along the
        natural length for ``s``, 0 for a node given by number.
    """

    item: int
    given: str
    node: int
    node_s: float
    node_x: float
    snap: float


def node_fractions(S) -> np.ndarray:
    """Each interior node's fraction of the natural length from support A (``n`` values)."""
    S = np.asarray(S, dtype=float)
    return np.cumsum(S)[:-1] / S.sum()


def place(item: int, point, S, L: float) -> Placement:
    """Place item ``item`` (from 1) of ``loads.point`` on the cable of segments ``S`` (m) and span
    ``L`` (m): on its node, or on the interior node nearest its ``x`` or ``s``.

    Raises
    ------
    ValueError
        If the node number exceeds the cable's nodes or ``x`` lies beyond the span.
    """
    frac = node_fractions(S)
    n, total = frac.size, float(np.sum(S))
    if point.node is not None:
        if point.node > n:
            raise ValueError(f"`loads.point[{item}].node` is {point.node}, but this cable has n = {n} interior "
                             f"nodes; count them from 1 at support A")
        i = point.node - 1
        return Placement(item, point.position, point.node, float(frac[i]), float(frac[i] * L), 0.0)
    if point.x is not None and point.x > L:
        raise ValueError(f"`loads.point[{item}].x` is {point.x:g} m, beyond the span L = {L:g} m; give the "
                         f"horizontal distance from support A, from 0 to {L:g} m (or s, a fraction of the natural length)")
    if point.x is not None:
        distance, scale = np.abs(frac * L - point.x), L
    else:
        distance, scale = np.abs(frac - point.s) * total, total
    i = int(np.flatnonzero(distance <= distance.min() + 1e-9 * scale)[0])  # a tie: the node nearer A
    return Placement(item, point.position, i + 1, float(frac[i]), float(frac[i] * L), float(distance[i]))


def placements_text(placements, equilibrium=None, dim: int = 2) -> str:
    """The lines that state where the items of ``loads.point`` given by position went ("" if none).

    Parameters
    ----------
    placements : sequence of Placement
    equilibrium : ndarray, optional
        The static node coordinates (DOF order), m: each node's horizontal position under F0 is
        stated beside the one taken for placing it.
    dim : int
        Components per node of ``equilibrium`` (2 planar, 3 spatial).
    """
    rows = [p for p in placements if not p.given.startswith("node")]
    if not rows:
        return ""
    lines = ["Point loads placed by position (on the nearest node; a node's position along the span is taken",
             "as its fraction s of the natural length times L):"]
    for p in rows:
        at = "" if equilibrium is None else f"; under F0 at x = {equilibrium[dim * (p.node - 1)]:.6g} m"
        lines.append(f"  loads.point[{p.item}] at {p.given}: node {p.node} (s = {p.node_s:.6g}, x = {p.node_x:.6g} m), "
                     f"snap distance {p.snap:.4g} m{at}")
    return "\n".join(lines)


#: Marks, in the case text stored with results (the shorthand expanded into explicit lists),
#: where each item of ``loads.point`` was placed, so that a rerun states it again.
PLACED_MARK = "# cablesim placed loads.point:"


def placement_lines(placements) -> str:
    """The lines that record ``placements`` in a stored case text ("" if none)."""
    return "".join(f"{PLACED_MARK} {json.dumps(asdict(p))}\n" for p in placements)


def read_placements(text: str) -> tuple[Placement, ...]:
    """The placements a stored case text records (:func:`placement_lines`; none if it records
    none, or records them in a form this version does not read)."""
    out = []
    for line in text.splitlines():
        if line.startswith(PLACED_MARK):
            try:
                out.append(Placement(**json.loads(line[len(PLACED_MARK):])))
            except (ValueError, TypeError):
                return ()
    return tuple(out)
