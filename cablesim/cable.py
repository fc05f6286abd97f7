"""The cable model: geometry, axial rigidity, lumped masses and the degree-of-freedom order.

A planar cable (``dim = 2``) has two degrees of freedom per node, ordered
``[x1, x2, x3, x4, ...]`` = (horizontal, vertical) of node 1, then of node 2, and so on; the
vertical axis points down. A spatial cable (``dim = 3``) has three per node, ``(x, v, w)``: along
the span, vertical down, and horizontal out of the vertical plane through the span. Segment
``r`` (1-based in the paper, ``r - 1`` here) joins node ``r - 1`` to node ``r``, node 0 being
support A at the origin and node ``n + 1`` support B = (L, H) or (L, H, W).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Cable:
    """A weightless cable with ``n`` interior nodes and ``n + 1`` straight segments.

    Parameters
    ----------
    L : float
        Horizontal distance from support A to support B, m.
    H : float
        Vertical distance from A to B, m, positive downwards (B below A).
    S : array_like, shape (n + 1,)
        Natural (unstretched) segment lengths ``S_r``, m.
    EA : float
        Axial rigidity, N. ``numpy.inf`` gives the inextensible cable.
    masses : array_like, shape (n,)
        Lumped nodal masses ``M_r``, kg, acting in every direction.
    W : float
        Out-of-plane distance from A to B, m (spatial cables only; 0 for a planar one).
    dim : int
        Components per node: 2 (planar) or 3 (spatial).
    """

    L: float
    H: float
    S: np.ndarray
    EA: float
    masses: np.ndarray
    W: float = 0.0
    dim: int = 2

    def __post_init__(self):
        S = np.asarray(self.S, dtype=float).copy()
        m = np.asarray(self.masses, dtype=float).copy()
        S.setflags(write=False)
        m.setflags(write=False)
        object.__setattr__(self, "S", S)
        object.__setattr__(self, "masses", m)
        object.__setattr__(self, "L", float(self.L))
        object.__setattr__(self, "H", float(self.H))
        object.__setattr__(self, "EA", float(self.EA))
        object.__setattr__(self, "W", float(self.W))
        object.__setattr__(self, "dim", int(self.dim))
        if self.dim not in (2, 3):
            raise ValueError("dim must be 2 (planar) or 3 (spatial)")
        if self.dim == 2 and self.W != 0.0:
            raise ValueError("a planar cable has W = 0 (support B in the plane of the span)")
        if S.ndim != 1 or S.size < 2:
            raise ValueError("S must hold n + 1 >= 2 segment lengths")
        if m.shape != (S.size - 1,):
            raise ValueError("masses must hold n = len(S) - 1 values")

    @property
    def n_nodes(self) -> int:
        """Number of interior (moving) nodes ``n``."""
        return self.S.size - 1

    @property
    def n_segments(self) -> int:
        """Number of segments ``n + 1``."""
        return self.S.size

    @property
    def n_dof(self) -> int:
        """Number of degrees of freedom ``dim n``."""
        return self.dim * self.n_nodes

    @property
    def chord(self) -> np.ndarray:
        """Vector from support A to support B, ``(L, H)`` or ``(L, H, W)``, m."""
        return np.array([self.L, self.H] if self.dim == 2 else [self.L, self.H, self.W])

    @property
    def support_A(self) -> tuple:
        """Support A as a tuple of ``dim`` coordinates (the origin), m."""
        return (0.0,) * self.dim

    @property
    def support_B(self) -> tuple:
        """Support B as a tuple of ``dim`` coordinates, m."""
        return tuple(float(c) for c in self.chord)

    @property
    def chord_length(self) -> float:
        """Straight-line distance between the supports, m."""
        return float(np.hypot(self.L, self.H)) if self.dim == 2 else float(np.sqrt(self.L**2 + self.H**2 + self.W**2))

    @property
    def total_length(self) -> float:
        """Sum of the natural segment lengths, m."""
        return float(self.S.sum())

    @property
    def spans_slack(self) -> bool:
        """Whether the natural length exceeds the chord by more than round-off (relative 1e-12),
        so that an inextensible cable of these segments can sag between the supports. A cable
        within 1e-12 of its chord is taken as straight (pretensioned): its inextensible tension
        would be set by the rounding of the sum of its segments."""
        return self.total_length > self.chord_length * (1.0 + 1e-12)

    @property
    def compliance(self) -> float:
        """Axial compliance ``1 / EA``, 1/N (zero for the inextensible cable)."""
        return 0.0 if np.isinf(self.EA) else 1.0 / self.EA

    @property
    def mass_diagonal(self) -> np.ndarray:
        """Diagonal of the lumped mass matrix ``M = diag(M1, M1, M2, M2, ...)`` (each mass
        repeated ``dim`` times), kg."""
        return np.repeat(self.masses, self.dim)

    @property
    def mass_matrix(self) -> np.ndarray:
        """The lumped mass matrix ``M``, kg, shape (dim n, dim n)."""
        return np.diag(self.mass_diagonal)

    def inextensible(self) -> "Cable":
        """The same cable with ``EA = inf``."""
        return self.with_EA(np.inf)

    def with_EA(self, EA: float) -> "Cable":
        """The same cable with another axial rigidity."""
        return Cable(self.L, self.H, self.S, EA, self.masses, self.W, self.dim)

    def spatial(self) -> "Cable":
        """The same cable with three components per node (support B at ``(L, H, W)``)."""
        return Cable(self.L, self.H, self.S, self.EA, self.masses, self.W, 3)


def nodes_with_supports(cable: Cable, y: np.ndarray) -> np.ndarray:
    """Node coordinates including both supports.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (dim n,)
        Interior node coordinates in DOF order.

    Returns
    -------
    ndarray, shape (n + 2, dim)
        Rows are A, node 1, ..., node n, B.
    """
    pts = np.empty((cable.n_nodes + 2, cable.dim))
    pts[0] = 0.0
    pts[1:-1] = np.asarray(y, dtype=float).reshape(-1, cable.dim)
    pts[-1] = cable.chord
    return pts
