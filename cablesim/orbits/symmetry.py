"""The mirror symmetry of a spatial cable whose equilibrium, loads and support motions lie in one
plane, and the split of a planar orbit's monodromy into its in-plane and out-of-plane blocks.

Reflection through the plane, ``S = I - 2 n n^T`` at every node (``n`` the plane's unit normal),
maps motions onto motions: the field is equivariant, ``f(S x) = S f(x)``. In the orthogonal basis
``Q = [Q_e, Q_o]`` of the state whose first columns span the *even* coordinates (the two in-plane
components of every node's displacement and velocity) and whose last ``2 n`` the *odd* ones (the
components along ``n``), ``S = Q diag(I, -I) Q^T``. An orbit that lies in the plane is fixed by
``S``, so its variational equations commute with ``S`` and the monodromy ``Phi`` is block
diagonal in that basis::

    Q^T Phi Q = [[Phi_e, 0], [0, Phi_o]]

``Phi_e`` is the planar cable's monodromy (the in-plane multipliers: folds, period doublings and
Neimark-Sacker points of the planar branch), ``Phi_o`` the monodromy of the out-of-plane
linearisation about the planar orbit (the string whose tensions the orbit modulates):

- an out-of-plane multiplier through +1 is a symmetry-breaking pitchfork: two nonplanar branches,
  mirror images ``w -> -w`` of each other, are born (never a fold of the planar branch);
- through -1 an out-of-plane period doubling;
- a complex pair through the unit circle an out-of-plane Neimark-Sacker point, with frequency
  ratio ``arg(mu) / 2 pi``.

:func:`cable_mirror` is the one place that decides whether a cable has the symmetry (the plane
rule is :func:`cablesim.modal.mirror_plane`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.extremes import peak_and_half_range
from ..modal import IN_PLANE, OUT_OF_PLANE, equilibrium_plane, mirror_plane, plane_basis
from .stability import sort_multipliers

#: Largest scaled out-of-plane state of an orbit that counts as lying in the plane.
PLANAR_TOL = 1e-9


@dataclass(frozen=True)
class Mirror:
    """The mirror symmetry of a state space (module docstring).

    Attributes
    ----------
    Q : ndarray (N, N)
        Orthogonal; the first ``N - n_odd`` columns span the even coordinates, the rest the odd.
    n_odd : int
        Number of odd coordinates (components along the plane's normal).
    labels : tuple of str
        Names of the even and odd blocks: ``("in-plane", "out-of-plane")``.
    normal : ndarray (3,)
        The plane's unit normal.
    frame : ndarray (3, 3)
        Columns: the in-plane axis along the chord, the in-plane axis across it and the normal
        (:func:`~cablesim.modal.plane_basis`).
    """

    Q: np.ndarray
    n_odd: int
    labels: tuple = (IN_PLANE, OUT_OF_PLANE)
    normal: np.ndarray | None = None
    frame: np.ndarray | None = None

    @property
    def dim(self) -> int:
        return int(self.Q.shape[0])

    @property
    def even(self) -> np.ndarray:
        """``Q_e``: columns spanning the even (in-plane) coordinates."""
        return self.Q[:, : self.dim - self.n_odd]

    @property
    def odd(self) -> np.ndarray:
        """``Q_o``: columns spanning the odd (out-of-plane) coordinates."""
        return self.Q[:, self.dim - self.n_odd :]

    def reflect(self, x: np.ndarray) -> np.ndarray:
        """``S x``: the mirror image of a state (the odd coordinates change sign)."""
        x = np.asarray(x, dtype=float)
        return x - 2.0 * self.odd @ (self.odd.T @ x)

    def odd_size(self, x: np.ndarray, scale: np.ndarray) -> float:
        """Largest scaled odd component of state ``x`` (``scale``: typical size of each state
        component, or of each odd coordinate)."""
        scale = np.asarray(scale, dtype=float)
        s_odd = np.abs(self.odd.T) @ scale if scale.size == self.dim else scale
        return float(np.abs(self.odd.T @ np.asarray(x, dtype=float) / s_odd).max())

    def is_planar(self, x: np.ndarray, scale: np.ndarray, tol: float = PLANAR_TOL) -> bool:
        """Whether state ``x`` lies in the plane (scaled odd part at most ``tol``)."""
        return self.odd_size(x, scale) <= tol

    def blocks(self, monodromy: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """``(Phi_e, Phi_o, off)``: the even and odd diagonal blocks of ``Q^T Phi Q`` and the
        largest entry of its off-diagonal blocks relative to the largest entry of ``Phi``
        (round-off for an orbit in the plane)."""
        B = self.Q.T @ monodromy @ self.Q
        k = self.dim - self.n_odd
        big = max(float(np.abs(B).max()), 1e-300)
        off = max(float(np.abs(B[:k, k:]).max(initial=0.0)), float(np.abs(B[k:, :k]).max(initial=0.0))) / big
        return B[:k, :k], B[k:, k:], off

    def labelled(self, mu_even: np.ndarray, mu_odd: np.ndarray) -> tuple[np.ndarray, tuple]:
        """The multipliers of both blocks sorted together
        (:func:`~cablesim.orbits.stability.sort_multipliers`), and the block of each."""
        mu = np.concatenate([np.asarray(mu_even, dtype=complex), np.asarray(mu_odd, dtype=complex)])
        labels = np.array([self.labels[0]] * np.size(mu_even) + [self.labels[1]] * np.size(mu_odd))
        order = np.lexsort((-mu.imag, -np.abs(mu)))
        return mu[order], tuple(str(x) for x in labels[order])


    def coordinate_blocks(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(rows, bounds)``: the state components of the even block (``rows[:bounds[1]]``)
        and of the odd one (``rows[bounds[1]:]``), each ascending, when the plane's normal is a
        coordinate axis (every odd column of ``Q`` a signed unit vector of the state, so that
        the even columns span the other components); else None. On an orbit in the plane the
        variational equations then never couple the two sets of components, and are integrated
        on the two blocks alone (:func:`~cablesim.orbits.kernels.flow_segment`)."""
        odd = self.odd
        if not (np.count_nonzero(odd, axis=0) == 1).all() or not np.all(np.abs(odd[odd != 0.0]) == 1.0):
            return None
        is_odd = np.zeros(self.dim, dtype=bool)
        is_odd[np.argmax(odd != 0.0, axis=0)] = True
        rows = np.concatenate([np.flatnonzero(~is_odd), np.flatnonzero(is_odd)]).astype(np.int64)
        return rows, np.array([0, self.dim - self.n_odd, self.dim], dtype=np.int64)


def split_multipliers(mirror: Mirror, monodromy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The in-plane and out-of-plane Floquet multipliers of a planar orbit, each sorted by
    decreasing modulus (conjugate pairs with positive imaginary part first)."""
    Pe, Po, _ = mirror.blocks(monodromy)
    return sort_multipliers(np.linalg.eigvals(Pe)), sort_multipliers(np.linalg.eigvals(Po))


def state_mirror(normal: np.ndarray, chord: np.ndarray, n_nodes: int) -> Mirror:
    """The :class:`Mirror` of the state ``(z, v)`` of ``n_nodes`` nodes with three components
    each, for the plane with unit normal ``normal`` (in-plane axes from
    :func:`~cablesim.modal.plane_basis`)."""
    R = plane_basis(np.asarray(normal, dtype=float), np.asarray(chord, dtype=float))
    nd = 3 * n_nodes
    N = 2 * nd
    even, odd = [], []
    for half in (0, nd):  # displacements, then velocities
        for i in range(n_nodes):
            for a in range(3):
                col = np.zeros(N)
                col[half + 3 * i : half + 3 * i + 3] = R[:, a]
                (odd if a == 2 else even).append(col)
    Q = np.column_stack(even + odd)
    return Mirror(Q=Q, n_odd=len(odd), normal=R[:, 2].copy(), frame=R)


@dataclass(frozen=True)
class Whirling:
    """How a spatial orbit leaves its plane (:func:`whirling_measures`).

    Attributes
    ----------
    area : ndarray (n_nodes,)
        Signed area enclosed by each node's path in its cross-section plane ``(w, v)`` (``w``
        along the normal, ``v`` the in-plane axis across the chord), m^2: positive when the node
        goes round counter-clockwise in those axes, which is counter-clockwise as seen from
        support A looking towards B (:func:`rotation_sense`); zero for a motion in the plane or
        along a line.
    tilt : float
        Angle between the plane of symmetry and the orbit's mean plane of motion, degrees: the
        principal direction of all nodes' ``(v, w)`` displacements over the orbit, from the
        ``v`` axis (0 for a planar orbit, 90 for a motion straight across the plane).
    max_w : ndarray (n_nodes,)
        Largest out-of-plane displacement ``|w|`` of each node over the orbit, m (located
        between the samples on the cubic Hermite interpolant of ``w`` and ``w'``).
    """

    area: np.ndarray
    tilt: float
    max_w: np.ndarray | None = None


def in_plane_whirling(n_nodes: int) -> Whirling:
    """The whirling measures of an orbit in the plane: no area, no tilt, no ``|w|``."""
    return Whirling(area=np.zeros(n_nodes), tilt=0.0, max_w=np.zeros(n_nodes))


#: Senses of rotation of a node's path, as seen from support A looking towards B.
COUNTER_CLOCKWISE, CLOCKWISE, NO_ROTATION, NOT_MEASURED = "counter-clockwise", "clockwise", "none", "not measured"
#: Smallest enclosed area, relative to ``max_w^2``, that counts as going round (below it: a
#: motion along a line or in the plane, its area round-off).
ROTATION_TOL = 1e-9


def rotation_sense(area, max_w) -> np.ndarray:
    """The sense in which each node goes round, seen from support A looking towards B.

    The right-handed frame of the plane is ``(e1, e2, n)``, ``e1`` along the chord from A to B,
    so a viewer at A looking along ``e1`` sees the ``(w, v)`` axes turned by half a turn from
    the usual drawing (``w`` to the left, ``v`` down), which keeps the sense: a positive area
    ``1/2 oint (w dv - v dw)`` (angular momentum along ``-e1``, towards the viewer) is
    counter-clockwise.

    Parameters
    ----------
    area : array_like
        Signed enclosed areas :attr:`Whirling.area`, m^2.
    max_w : array_like
        The nodes' largest ``|w|``, m (same shape): an area below :data:`ROTATION_TOL`
        ``max_w^2`` is no rotation.

    Returns
    -------
    ndarray of str
        ``"counter-clockwise"``, ``"clockwise"`` or ``"none"`` per entry (none: no net area,
        a motion along a line or a figure of eight whose lobes go round opposite ways;
        ``"not measured"`` where the area is NaN).
    """
    area = np.asarray(area, dtype=float)
    small = np.abs(area) <= ROTATION_TOL * np.square(np.asarray(max_w, dtype=float))
    out = np.where(area > 0.0, COUNTER_CLOCKWISE, CLOCKWISE).astype(object)
    out[small | (area == 0.0)] = NO_ROTATION
    out[~np.isfinite(area)] = NOT_MEASURED
    return out.astype(str)


def largest_w(mirror: Mirror, steps: list, period: float) -> np.ndarray:
    """Each node's largest ``|w|`` over an orbit (m), ``w`` along the plane's normal, from the
    orbit at its integration steps (:meth:`~cablesim.orbits.shooting.Shooting.steps`: per
    segment the times and the state ``(z, y')`` with its rate ``(y', y'')``), located between
    the steps on the quintic Hermite interpolant of ``w``, ``w'``, ``w''`` as the orbit's
    amplitudes are (:mod:`cablesim.dynamics.extremes`)."""
    dur = period / len(steps)
    t = np.concatenate([k * dur + ts[:-1] for k, (ts, _) in enumerate(steps)])  # one period, each step once
    rec = np.concatenate([r[:-1] for _, r in steps])
    nd = rec.shape[1] // 4
    normal = mirror.frame[:, 2]
    w, dw, ddw = (rec[:, a : a + nd].reshape(len(t), -1, 3) @ normal for a in (0, nd, 3 * nd))
    return np.asarray(peak_and_half_range(t, w, dw, ddw, period=period)[0], dtype=float)


def whirling_measures(mirror: Mirror, x: np.ndarray, dt: float, max_w: np.ndarray | None = None) -> Whirling:
    """Whirling measures of an orbit sampled uniformly in time at ``x`` (samples, 6 n): states
    ``(z, y')`` over one closed orbit (first and last samples the same state), ``dt`` s apart.

    The area is ``1/2 oint (w v' - v w') dt`` by the trapezoidal rule, which is spectrally
    accurate for a smooth periodic integrand (a polygon through the samples would be short by
    about ``(2 pi / N)^2 / 6`` of it); the largest ``|w|`` is ``max_w`` if given
    (:func:`largest_w`), else located between the samples on the Hermite interpolant of
    ``(w, w')``."""
    n = x.shape[1] // 6
    R = mirror.frame
    q = np.asarray(x, dtype=float).reshape(x.shape[0], 2, n, 3) @ R  # (chord, across, normal) per node
    v, w, dv, dw = q[:, 0, :, 1], q[:, 0, :, 2], q[:, 1, :, 1], q[:, 1, :, 2]
    integrand = w * dv - v * dw
    area = 0.5 * dt * np.sum(integrand[:-1], axis=0)
    if max_w is None:
        t = np.arange(x.shape[0] - 1) * dt  # one period, without the repeated last sample
        max_w, _ = peak_and_half_range(t, w[:-1], dw[:-1], period=(x.shape[0] - 1) * dt)
    dv, dw = v - v.mean(axis=0), w - w.mean(axis=0)
    cov = np.array([[np.sum(dv * dv), np.sum(dv * dw)], [np.sum(dv * dw), np.sum(dw * dw)]])
    vals, vecs = np.linalg.eigh(cov)
    e = vecs[:, -1]
    tilt = float(np.degrees(np.arctan2(abs(e[1]), abs(e[0])))) if vals[-1] > 0 else 0.0
    return Whirling(area=area, tilt=tilt, max_w=np.asarray(max_w, dtype=float))


def orbit_whirling(frame: Mirror, shooting, u: np.ndarray, lam: float, samples: int = 256,
                   steps: list | None = None) -> Whirling:
    """The whirling measures of the orbit through the shooting unknowns ``u`` at parameter
    ``lam`` (a :class:`~cablesim.orbits.shooting.Shooting`), integrated once (unless its
    ``steps`` are given, :meth:`~cablesim.orbits.shooting.Shooting.steps`): ``samples`` per
    forcing period for the area and tilt, the steps themselves for the largest ``|w|``."""
    steps = shooting.steps(u, lam) if steps is None else steps
    t, x = shooting.trajectory(u, lam, samples_per_period=samples, steps=steps)
    return whirling_measures(frame, x, float(t[1] - t[0]), largest_w(frame, steps, float(t[-1])))


def component_frequencies(eom, mirror: Mirror | None) -> np.ndarray:
    """The fundamental frequency of each displacement component of a cable, rad/s (n_dof,):
    the lowest modal frequency ``w1`` for every component, unless the cable has a mirror
    symmetry. Then the in-plane and the out-of-plane motions are separate linear problems
    (:func:`~cablesim.modal.planar_modes`), and component ``i`` gets
    ``sqrt(sum_b |P_b e_i|^2 w_b^2)``: ``P_b`` the projection onto the displacements of block
    ``b`` (even, odd), ``w_b`` the lowest frequency of that block; for a plane whose normal is a
    coordinate axis, the in-plane components get the planar cable's ``w1`` and the normal one
    the lowest out-of-plane frequency.

    Why: the velocity scales of a continuation are the displacement scale times these. A
    planar orbit of a symmetric spatial cable moves in the in-plane components alone; scaled
    with the lowest frequency of all modes (often an out-of-plane one, lower) its velocities
    would weigh more in the arclength than on the planar cable, and the same curve would be
    traced in smaller steps."""
    w = np.asarray(eom.frequencies, dtype=float)
    nd = int(eom.n_dof)
    if mirror is None:
        return np.full(nd, float(w[0]))
    mass = np.asarray(eom.mass, dtype=float)
    K0 = np.asarray(eom.K0, dtype=float)
    sq = np.zeros(nd)
    for cols in (mirror.even[:nd], mirror.odd[:nd]):
        B = cols[:, np.abs(cols).max(axis=0) > 0.0]  # the block's displacement coordinates
        # lowest eigenvalue of (B^T K0 B) q = w^2 (B^T M B) q; B^T M B is diagonal (isotropic
        # nodal masses, orthonormal columns node by node)
        m = np.einsum("ik,i,ik->k", B, mass, B)
        r = 1.0 / np.sqrt(m)
        lam = float(np.linalg.eigvalsh(r[:, None] * (B.T @ K0 @ B) * r[None, :])[0])
        sq += np.einsum("ik,ik->i", B, B) * max(lam, 0.0)
    return np.sqrt(sq)


def cable_frame(eom) -> Mirror | None:
    """The :class:`Mirror` of the plane of a spatial cable's equilibrium, whether or not its
    loads lie in it (the frame of the whirling measures of a cable without the symmetry), or
    None (a planar cable, or an equilibrium not in one plane)."""
    cable = eom.cable
    if cable.dim != 3:
        return None
    points = np.vstack([cable.support_A, np.reshape(eom.y0, (-1, 3)), cable.support_B])
    normal = equilibrium_plane(points, np.asarray(cable.chord, dtype=float))
    return None if normal is None else state_mirror(normal, cable.chord, cable.n_nodes)


def cable_mirror(eom) -> Mirror | None:
    """The mirror of a spatial cable's equations of motion, or None (a planar cable, or a
    spatial one whose equilibrium, sustained and harmonic loads and support motions do not lie
    in one plane)."""
    cable = eom.cable
    if cable.dim != 3:
        return None
    points = np.vstack([cable.support_A, np.reshape(eom.y0, (-1, 3)), cable.support_B])
    normal = mirror_plane(points, np.asarray(cable.chord, dtype=float), (eom.F0, eom.FL, eom.uA, eom.uB))
    if normal is None:
        return None
    return state_mirror(normal, cable.chord, cable.n_nodes)
