"""The continuous symmetry of a cable that lies straight along its chord: rotation about the chord.

A spatial cable whose equilibrium lies on the chord line (a taut stay without gravity sag), whose
sustained and harmonic loads and support motions are all along the chord and whose stiffness and
damping at the equilibrium commute with rotations about it, is invariant under every rotation
``R_theta`` about the chord through support A: the field is equivariant, ``f(R x) = R f(x)``, so
the rotation of a periodic orbit is again a periodic orbit. Differentiating
``P(R_theta x*) = R_theta x*`` (``P`` the period map, ``x*`` the orbit's start) at ``theta = 0``::

    M g = g,   g = d/dtheta R_theta x* = (e x (y0 + z - A), e x v) at every node

(``e`` the chord's unit vector, ``M = DP(x*)`` the monodromy): the generator ``g`` is an
eigenvector with multiplier exactly +1, forced by the symmetry, as the trivial multiplier of an
autonomous system is by time shifts. On an orbit that is moved by the rotation (``g != 0``: an orbit
that leaves the chord line, such as the period-2 branches born at a stay's parametric resonance)
this multiplier is neutral for every parameter value. A bifurcation test watching multipliers
through +1 would take its round-off wobble about 1 for branch points (a pitchfork test on a
planar branch, whose out-of-plane block holds it, the branch-point test on a nonplanar one). The
tests therefore run on the monodromy deflated by it (:func:`deflate`: the multiplier +1 moved
to :data:`NEUTRAL_SHIFT`, every other multiplier kept); the orbit still reports every
multiplier, with the excluded one and the residual ``|M g - g| / |g|`` recorded
(:class:`Neutral`). On an orbit along the chord (``g = 0``, the axial response) nothing is
excluded.

The rotations of an orbit they move are orbits too, so the periodicity condition of a shooting
is singular along the generator; :class:`RotationPhase` replaces its equation along ``g`` by a
phase condition (on the dense path in the formed Jacobian, :func:`with_phase`; on the
matrix-free one in the Jacobian's action, :func:`phased_action`). The matrix-free path deflates
the monodromy's action (:func:`deflated_action`) before its leading multipliers are computed and
records the neutral one from the action (:func:`action_neutral`).

:func:`cable_rotation` decides from the model whether a cable has the symmetry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..modal import PLANE_TOL
from .stability import sort_multipliers

#: Largest scaled size of the generator ``g`` of an orbit that the rotation leaves in place (an
#: orbit along the chord): below it no multiplier is excluded.
MOVED_TOL = 1e-9
#: Largest ``|K0 W - W K0| / |K0|`` (and for ``C``) of a cable that counts as axisymmetric
#: (``W`` the infinitesimal rotation of every node's displacement).
COMMUTE_TOL = 1e-10


@dataclass(frozen=True)
class Rotation:
    """Rotations about a cable's chord (module docstring).

    Attributes
    ----------
    axis : ndarray (3,)
        ``e``: unit vector along the chord, from A to B.
    origin : ndarray (3,)
        A point of the axis (support A at rest), m.
    rest : ndarray (n, 3)
        The nodes' equilibrium positions ``y0``, m (the state's ``z`` is measured from them).
    """

    axis: np.ndarray
    origin: np.ndarray
    rest: np.ndarray

    def generator(self, x: np.ndarray) -> np.ndarray:
        """``g = (e x (y0 + z - A), e x v)`` of the state ``x = (z, v)`` (6 n)."""
        n = self.rest.shape[0]
        x = np.asarray(x, dtype=float)
        z, v = x[: 3 * n].reshape(n, 3), x[3 * n : 6 * n].reshape(n, 3)
        return np.concatenate([np.cross(self.axis, self.rest + z - self.origin).ravel(),
                               np.cross(self.axis, v).ravel()])

    def moved(self, x: np.ndarray, scale: np.ndarray) -> np.ndarray | None:
        """The generator at ``x`` if the rotation moves the orbit (its scaled size, with the
        state's typical sizes ``scale``, above :data:`MOVED_TOL`), else None."""
        g = self.generator(x)
        return g if float(np.abs(g / np.asarray(scale, dtype=float)).max()) > MOVED_TOL else None


@dataclass(frozen=True)
class Neutral:
    """The multiplier forced to +1 by the rotation symmetry and excluded from the tests.

    Attributes
    ----------
    multiplier : complex
        The Rayleigh quotient ``g^T M g / g^T g`` (+1 to the monodromy's accuracy).
    residual : float
        ``|M g - g| / |g|``.
    multipliers : ndarray complex
        The multipliers the tests see: those of the deflated matrix, the excluded one moved to
        :data:`NEUTRAL_SHIFT` (of the out-of-plane block on a planar orbit, of the monodromy
        otherwise); on the matrix-free path the leading ones of the deflated action, the
        excluded one moved to :data:`LEADING_SHIFT` and so left out unless the block is
        computed whole.
    matrix : ndarray or None
        The deflated matrix (:func:`deflate`); None on the matrix-free path, which forms none
        (:func:`action_neutral`).
    """

    multiplier: complex
    residual: float
    multipliers: np.ndarray
    matrix: np.ndarray | None


#: Where :func:`deflate` moves the neutral multiplier: inside the unit circle, away from +1 and
#: -1, and of order one, so that the determinant of the deflated matrix (the step rule's model
#: check, :func:`~cablesim.orbits.stability.interpolated_step_ratio`) stays that of the rest
#: times a constant.
NEUTRAL_SHIFT = 0.5


def deflate(P: np.ndarray, g: np.ndarray, shift: float = NEUTRAL_SHIFT) -> np.ndarray:
    """``P - (1 - c) P g g^T / g^T g`` (Wielandt's deflation, ``c`` = ``shift``): with
    ``P g = g``, the same multipliers as ``P`` except the +1 of ``g``, which becomes ``c`` (every
    left eigenvector ``y`` of another multiplier has ``y . g = 0``, so ``y^T`` is still one).
    Smooth in ``P`` and ``g``, so the step rule may interpolate it between the points of a
    branch."""
    g = np.asarray(g, dtype=float)
    return P - (1.0 - shift) * np.outer(P @ g, g) / float(g @ g)


def _quotient(Pg: np.ndarray, g: np.ndarray) -> tuple[complex, float]:
    """The Rayleigh quotient ``g^T P g / g^T g`` and the residual ``|P g - g| / |g|``."""
    gg = float(g @ g)
    return complex(float(g @ Pg) / gg), float(np.linalg.norm(Pg - g) / np.sqrt(gg))


def neutral(P: np.ndarray, g: np.ndarray) -> Neutral:
    """The :class:`Neutral` multiplier of ``P`` along ``g`` and the deflated multipliers."""
    multiplier, residual = _quotient(P @ g, g)
    D = deflate(P, g)
    return Neutral(multiplier=multiplier, residual=residual, multipliers=sort_multipliers(np.linalg.eigvals(D)),
                   matrix=D)


#: Where the matrix-free path moves the neutral multiplier (:func:`deflated_action`): to zero,
#: below every bound of the leading multipliers (:mod:`cablesim.orbits.floquet`), so that it is
#: never among those kept and the kept ones are the others (at :data:`NEUTRAL_SHIFT`, the default
#: bound's value, the iteration could not tell it from the largest discarded modulus). The
#: truncated tests and step rule see only the kept multipliers, so no determinant needs it.
LEADING_SHIFT = 0.0


def deflated_action(apply, g: np.ndarray, w: np.ndarray, shift: float = LEADING_SHIFT):
    """The action ``X -> P (X - (1 - c) g w^T X)`` of Wielandt's deflation of ``P`` from its
    action ``apply(X) = P X`` on blocks (``c`` = ``shift``, ``P g = g``, ``w . g = 1``): the
    multipliers of ``P`` except the +1 of ``g``, which becomes ``c`` (every left eigenvector ``y``
    of another multiplier has ``y . g = 0``). :func:`deflate` is the case ``w = g / g^T g``;
    in the coordinates ``x / d`` of the matrix-free shooting ``g / d`` and ``w = d g / g^T g``
    give a matrix similar to it. No product more than the action's: the deflation acts on the
    input."""
    g = np.asarray(g, dtype=float)
    w = np.asarray(w, dtype=float)

    def deflated(X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        return apply(X - (1.0 - shift) * np.outer(g, w @ X))
    return deflated


def action_neutral(apply, g: np.ndarray, multipliers: np.ndarray) -> Neutral:
    """The :class:`Neutral` multiplier along ``g`` of an operator known by its action
    ``apply(X) = P X`` (one product), with ``multipliers`` those the tests see (of the deflated
    action, :func:`deflated_action`); no matrix."""
    g = np.asarray(g, dtype=float)
    multiplier, residual = _quotient(apply(g[:, None])[:, 0], g)
    return Neutral(multiplier=multiplier, residual=residual, multipliers=sort_multipliers(multipliers), matrix=None)


#: The phase of a problem with a rotation symmetry before its first evaluation.
UNSET = object()


def phase_direction(rotation: Rotation | None, u: np.ndarray, scale: np.ndarray, n: int, m: int) -> np.ndarray | None:
    """``q = g / |g|``: the generator of the orbit through the stacked segment states ``u``
    (``m`` of ``n`` values, typical sizes ``scale``) over its segments, normalised; None without
    a rotation symmetry or for an orbit the rotation leaves in place."""
    if rotation is None:
        return None
    g = [rotation.moved(u[k * n : (k + 1) * n], scale[k * n : (k + 1) * n]) for k in range(m)]
    if any(x is None for x in g):
        return None
    q = np.concatenate(g)
    return q / np.linalg.norm(q)


def without(v: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``(I - q q^T) v``: ``v`` without its component along the unit vector ``q``."""
    return v - q * float(q @ v)


def phased_jacobian(J: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``(I - q q^T) J + q q^T``: the Jacobian ``J`` of the periodicity condition with its
    equation along ``q`` replaced by the phase condition (:func:`phased_action` as a matrix)."""
    return J - np.outer(q, q @ J) + np.outer(q, q)


def phased_step(J: np.ndarray, r: np.ndarray, q: np.ndarray | None) -> np.ndarray:
    """Newton's correction ``du`` of the periodicity condition ``r = 0`` with Jacobian ``J``:
    ``J du = -r``, or, on an orbit a rotation moves (``q`` from :func:`phase_direction`), that
    system with its equation along ``q`` replaced by ``q . du = 0`` (``J`` holds the generator in
    its null space, so the plain system is singular and its solution runs along the family of
    rotated orbits)."""
    if q is None:
        return np.linalg.solve(J, -r)
    return np.linalg.solve(phased_jacobian(J, q), -without(r, q))


def with_phase(ev, u_ref: np.ndarray, q: np.ndarray) -> None:
    """The periodicity condition of the evaluation ``ev`` with its equation along ``q`` replaced
    by the phase condition ``q . (u - u_ref) = 0`` (:meth:`RotationPhase.anchor`), in place: its
    residual, its parameter derivative and its Jacobian if formed."""
    ev.r = without(ev.r, q) + q * float(q @ (ev.u - u_ref))
    if ev.J_u is not None:
        ev.J_u = phased_jacobian(ev.J_u, q)
    if ev.J_lam is not None:
        ev.J_lam = without(ev.J_lam, q)


def phased_action(JX: np.ndarray, X: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``J' X = (I - q q^T) J X + q q^T X`` from ``J X``: the action of the Jacobian of the
    periodicity condition with its equation along ``q`` replaced by the phase condition
    (:func:`with_phase`'s ``J_u``)."""
    return JX - np.outer(q, q @ JX) + np.outer(q, q @ X)


class RotationPhase:
    """The phase condition of a shooting problem whose system may be invariant under rotations
    (a mixin of the dense and the matrix-free orbit problems, which set :attr:`rotation` and
    :attr:`phase` with :meth:`init_phase` and have ``shooting`` and ``u_scale``)."""

    rotation: Rotation | None = None
    phase: object = None

    def init_phase(self) -> None:
        """The system's rotation symmetry, if any, and the phase anchored at the first
        evaluation."""
        #: The system's rotation symmetry, if any (its neutral multiplier is excluded).
        self.rotation = getattr(self.shooting.system, "rotation", None)
        #: ``(u_ref, q)`` of the phase condition that picks one orbit of a family of rotated
        #: orbits (:meth:`anchor`); None: none; UNSET: anchored at the first evaluation.
        self.phase = UNSET if self.rotation is not None else None

    def anchor(self, u: np.ndarray) -> None:
        """Fix the rotation's phase at the orbit through ``u`` (called at every accepted point).

        The rotations of an orbit they move are orbits too, so ``J_u`` of the periodicity
        condition ``r(u) = 0`` has the generator ``g`` (tiled over the segments) in its null
        space besides the branch's tangent, and Newton's bordered systems are singular. The
        equation along ``q = g / |g|`` is replaced by the phase condition
        ``q . (u - u_ref) = 0``: ``r' = (I - q q^T) r + q q^T (u - u_ref)``. Near the branch
        ``(I - q q^T) r = 0`` with the phase condition is ``r = 0`` with it (both define one
        curve through the solutions, ``[(I - q q^T) J_u, (I - q q^T) J_lam; q^T, 0]`` being of
        full rank where ``q`` is not orthogonal to the left null vector of ``J_u``), so the
        orbits found are the periodic ones; the phase is moved to every accepted point so that
        ``q`` follows the branch's shape."""
        if self.rotation is None:
            return
        n, m = self.shooting.n, self.shooting.segments
        u = np.asarray(u, dtype=float)
        q = phase_direction(self.rotation, u, self.u_scale, n, m)
        self.phase = None if q is None else (u[: m * n].copy(), q)

    def phased(self, ev, u: np.ndarray):
        """``ev`` (the evaluation at ``u``) with the phase condition, anchored at ``u`` if not
        yet (in place)."""
        if self.phase is UNSET:
            self.anchor(u)
        if self.phase is not None:
            with_phase(ev, *self.phase)
        return ev

    def generator(self, ev) -> np.ndarray | None:
        """The rotation's generator at the orbit of ``ev`` (its first segment's start) if the
        rotation moves it, else None."""
        if self.rotation is None:
            return None
        n = self.shooting.n
        return self.rotation.moved(ev.u[:n], self.u_scale[:n])


def _parallel(vectors: np.ndarray, axis: np.ndarray) -> bool:
    """Whether every row of ``vectors`` lies along ``axis``, to :data:`PLANE_TOL` of the largest."""
    v = np.reshape(np.asarray(vectors, dtype=float), (-1, 3))
    if not v.size:
        return True
    across = v - np.outer(v @ axis, axis)
    return bool(np.abs(across).max() <= PLANE_TOL * max(float(np.abs(v).max()), 1e-300))


def _commutes(A: np.ndarray | None, W: np.ndarray) -> bool:
    if A is None:
        return True
    A = np.asarray(A, dtype=float)
    big = max(float(np.abs(A).max()), 1e-300)
    return bool(np.abs(A @ W - W @ A).max() <= COMMUTE_TOL * big)


def cable_rotation(eom) -> Rotation | None:
    """The :class:`Rotation` about the chord of a spatial cable's equations of motion, or None.

    The cable has the symmetry when its equilibrium nodes lie on the chord line, every sustained
    and harmonic nodal load and both supports' motions lie along the chord, its nodal masses are
    the same in the three directions and its stiffness ``K0`` and damping ``C`` at the
    equilibrium commute with the infinitesimal rotation of the nodes (the internal forces of the
    segments depend on their lengths only, so the nonlinear field is then equivariant too)."""
    cable = eom.cable
    if cable.dim != 3:
        return None
    A = np.asarray(cable.support_A, dtype=float)
    chord = np.asarray(cable.chord, dtype=float)
    e = chord / np.linalg.norm(chord)
    rest = np.reshape(np.asarray(eom.y0, dtype=float), (-1, 3))
    off = rest - A - np.outer((rest - A) @ e, e)
    if np.abs(off).max(initial=0.0) > PLANE_TOL * float(cable.chord_length):
        return None
    vectors = [eom.F0, eom.FL] + [u for u in (eom.uA, eom.uB) if u is not None]
    if not all(_parallel(v, e) for v in vectors):
        return None
    mass = np.reshape(np.asarray(eom.mass, dtype=float), (-1, 3))
    if np.abs(mass - mass[:, :1]).max() > PLANE_TOL * float(mass.max()):
        return None
    cross = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])  # e x
    W = np.kron(np.eye(rest.shape[0]), cross)
    if not (_commutes(eom.K0, W) and _commutes(eom.C, W)):
        return None
    return Rotation(axis=e, origin=A, rest=rest.copy())
