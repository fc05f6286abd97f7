"""Branch switching at period doublings, and the return of a period-doubled branch to its parent.

At a located period doubling of a period-``p`` branch, the period-``2p`` branch is started from
the critical eigenvector ``v`` (multiplier -1): the ``2p`` unknowns are the parent's segment
states perturbed by ``+eps w_k`` on the first lap and ``-eps w_k`` on the second (``w_0 = v``,
``w_{k+1} = G_k w_k``; :func:`doubling_direction`), corrected on the hyperplane normal to that
direction, and continued away from the parent; if that start fails, ``-eps`` is tried (the two
signs give the same orbit shifted by ``p`` forcing periods, so one of them suffices).

The perturbation has the scaled size ``switch_size`` unless the guess is out of reach of
Newton's method there (:func:`start_factor`): the state scale is a property of the case (for a
cable, the linear response at its primary resonance), and an orbit born far from that resonance
can be much smaller than it. On a stiff cable (EA = 1e12 N, near ``2 w1``) ``switch_size``
times the scale is larger than the orbit itself and stretches the nearly inextensible segments
by more than their static stretch: the perturbed guess goes slack and the flow cannot even be
evaluated. The size is halved until both signs' guesses can be integrated and their residual
(the flow's nonlinear remainder along the critical direction) is a small fraction of the
perturbation; the thresholds that judge the new branch (its separation from the parent, the
merge) scale with the size used.

A ``2p`` branch whose two laps come back together (or whose lap difference reverses between two
points: the step went through the branch point onto the mirror image) has rejoined a
period-``p`` orbit at the other period doubling of a pair (:class:`MergeWatch`): it ends there,
with the parent's period doubling as its last point, and that period doubling is not switched
at again.

The continuation runs and the branch bookkeeping belong to :mod:`cablesim.orbits.branches`; this
module holds the geometry of the two laps and the watch for the merge.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np

from .rotation import deflate, without
from .shooting import Evaluation, FlowStatus


def lap_difference(u: np.ndarray, n: int, m_parent: int, scale: np.ndarray) -> np.ndarray:
    """Scaled difference between the two laps of a period-doubled orbit's unknowns.

    Parameters
    ----------
    u : ndarray (2 m_parent n,)
        Shooting unknowns of the period-doubled orbit (segment start states).
    n : int
        State dimension.
    m_parent : int
        Shooting segments of the parent orbit (one lap).
    scale : ndarray (n,)
        Typical size of each state component.

    Returns
    -------
    ndarray (m_parent n,)
    """
    S = u.reshape(2 * m_parent, n)
    return ((S[:m_parent] - S[m_parent:]) / scale).ravel()


def lap_separation(u: np.ndarray, n: int, m_parent: int, scale: np.ndarray) -> float:
    """Scaled max difference between the two laps of a period-doubled orbit's unknowns (the
    arguments of :func:`lap_difference`)."""
    return float(np.abs(lap_difference(u, n, m_parent, scale)).max())


def doubling_direction(ev: Evaluation, segments: int, state_scale: np.ndarray,
                       switch_size: float, mirror=None, plane: str | None = None,
                       shooting=None) -> tuple[np.ndarray, float]:
    """Direction into the period-doubled branch at a period doubling, and the step along it.

    On a planar orbit of a mirror-symmetric cable (``mirror`` and the ``plane`` of the critical
    multiplier given) the eigenvector is taken from that block of the monodromy
    (:meth:`~cablesim.orbits.symmetry.Mirror.blocks`): where an in-plane and an out-of-plane
    multiplier pass -1 together (a taut stay, whose two transverse directions have one
    frequency), the whole monodromy's eigenvectors at -1 mix the planes and lead to neither
    doubled branch.

    Parameters
    ----------
    ev : Evaluation
        Shooting evaluation of the parent orbit at its period doubling.
    segments : int
        Shooting segments of the parent orbit.
    state_scale : ndarray (n,)
        Typical size of each state component.
    switch_size : float
        Scaled size of the perturbation.
    mirror : Mirror, optional
        The cable's mirror symmetry, for a planar parent orbit.
    plane : str, optional
        The block of the critical multiplier (``"in-plane"`` or ``"out-of-plane"``).
    shooting : MatrixFreeShooting, optional
        The shooting of a matrix-free orbit of several segments, whose segment Jacobians
        ``G_k`` are applied to carry the eigenvector (:func:`segment_images`).

    Returns
    -------
    direction : ndarray (2 segments n,)
        ``(w_0, ..., w_{m-1}, -w_0, ..., -w_{m-1})`` (module docstring).
    eps : float
        Step along ``direction`` of scaled size ``switch_size``.
    """
    W = np.array(segment_images(ev, _critical_vector(ev, state_scale, mirror, plane), segments, shooting))
    direction = np.concatenate([W.ravel(), -W.ravel()])
    eps = switch_size / np.linalg.norm(direction / np.tile(state_scale, 2 * segments))
    return direction, eps


def segment_images(ev: Evaluation, w0: np.ndarray, segments: int, shooting=None) -> list:
    """``[w_0, G_0 w_0, G_1 G_0 w_0, ...]`` (``segments`` vectors): a vector at the orbit's start
    carried through its shooting segments, by the formed segment Jacobians ``ev.G`` of a dense
    evaluation or by their action ``shooting.segment_apply`` on a matrix-free one."""
    W = [np.asarray(w0, dtype=float)]
    if segments > 1 and ev.monodromy is None and shooting is None:
        raise ValueError("a matrix-free orbit of several segments needs its shooting to carry a vector through them")
    for k in range(segments - 1):
        W.append(ev.G[k] @ W[-1] if ev.monodromy is not None else shooting.segment_apply(ev, k, W[-1][:, None])[:, 0])
    return W


def _critical_vector(ev: Evaluation, state_scale: np.ndarray, mirror, plane: str | None) -> np.ndarray:
    """The real eigenvector of multiplier -1 at a period doubling (:func:`doubling_direction`):
    of the monodromy's block ``plane`` or of the whole, its dense eigenvectors or, on a
    matrix-free orbit, the leading ones (of the block: :mod:`cablesim.orbits.splitleading`)."""
    scale = np.asarray(state_scale, dtype=float)
    if mirror is not None and plane in mirror.labels:
        basis = mirror.even if plane == mirror.labels[0] else mirror.odd
        if ev.monodromy is None:
            w = ev.split.vector(plane, -1.0) * scale
            return basis @ (basis.T @ w)  # in the block's subspace to round-off: exactly there
        Pe, Po, _ = mirror.blocks(ev.monodromy)
        mu, V = np.linalg.eig(Pe if plane == mirror.labels[0] else Po)
        return basis @ np.real(V[:, int(np.argmin(np.abs(mu + 1.0)))])
    if ev.monodromy is None:  # the leading eigenvectors, in coordinates x / state_scale
        mu, V = ev.leading.multipliers, ev.leading.vectors * scale[:, None]
    else:
        mu, V = np.linalg.eig(ev.monodromy)
    return np.real(V[:, int(np.argmin(np.abs(mu + 1.0)))])


def start_factor(shooting, base: np.ndarray, direction: np.ndarray, eps: float, lam: float,
                 scale: np.ndarray, linear_tol: float = 0.1, max_halvings: int = 12) -> float | None:
    """The largest ``2^-k`` (``k <= max_halvings``) for which the perturbed guesses
    ``base +- 2^-k eps direction`` of the period-doubled orbit are within reach of Newton's
    method, or None if none is.

    Within reach: the flow over both laps can be integrated from either guess (a cable may go
    slack when a displacement perturbation stretches its segments) and the guess's residual
    is at most ``linear_tol`` times the perturbation (scaled max norms). At the period doubling
    ``direction`` is a null vector of the Jacobian (:func:`doubling_direction`), so the residual
    is the nonlinear remainder of the flow along it, of second order in the perturbation: the
    test sizes the perturbation by how fast the branch bends away from its tangent. Evaluations
    without variational equations.

    Parameters
    ----------
    shooting : Shooting
        Of the period-doubled orbit.
    base : ndarray
        The parent orbit's unknowns repeated over both laps.
    direction, eps : ndarray, float
        From :func:`doubling_direction`.
    lam : float
        Parameter value at the period doubling.
    scale : ndarray
        Scale of every unknown (``state_scale`` tiled over the segments).
    """
    for k in range(max_halvings + 1):
        factor = 0.5**k
        step = factor * eps * direction
        size = float(np.abs(step / scale).max())
        ok = True
        for sign in (1.0, -1.0):
            ev = shooting.evaluate(base + sign * step, lam, jac=False)
            if ev.status != FlowStatus.OK or not float(np.abs(ev.r / scale).max()) <= linear_tol * size:
                ok = False
                break
        if ok:
            return factor
    return None


def doubled_point(p, period: int, u: np.ndarray, **changes):
    """A period doubling ``p`` (an :class:`~cablesim.orbits.diagram.OrbitPoint`) of a
    period-``period / 2`` branch seen as a period-``period`` orbit (two laps of unknowns ``u``,
    multipliers squared): the first or last point of the doubled branch; ``changes`` replace
    further fields."""
    mu = p.multipliers**2
    order = np.lexsort((-mu.imag, -np.abs(mu)))  # the order of stability.sort_multipliers
    planes = None if p.planes is None else tuple(p.planes[k] for k in order)
    # its measure is of the orbit of one lap, taken on its steps: the doubled orbit's is taken anew
    return replace(p, period=period, u=u, special="period-doubling", multipliers=mu[order], planes=planes,
                   **{"measure": None, **changes})


class MergeWatch:
    """Watches a period-doubled branch for its return to a period-``p`` orbit (module docstring).

    Special points are held back until the next regular point: those found in the step that
    crosses the branch point are artefacts of the pitchfork (a fold test trips there) and are
    dropped with it.

    Parameters
    ----------
    partners : list of OrbitPoint
        The parent's period doublings (where the branch may rejoin it).
    branch, period : int
        Index and period of the doubled branch.
    n, m_parent : int
        State dimension and shooting segments of one lap.
    state_scale : ndarray (n,)
    switch_size : float
        Scaled size of the perturbation that started the branch.
    """

    def __init__(self, partners: list, branch: int, period: int, n: int, m_parent: int,
                 state_scale: np.ndarray, switch_size: float):
        self.partners = partners
        self.branch = branch
        self.period = period
        self.n = n
        self.m_parent = m_parent
        self.state_scale = state_scale
        self.switch_size = switch_size
        #: The laps have been well apart (a merge is only looked for after that).
        self.far = False
        #: Lap difference at the last regular point.
        self.previous: np.ndarray | None = None
        #: Special points waiting for the next regular point.
        self.pending: list = []
        #: The parent's period doubling where the branch rejoined it, if it did.
        self.merged_at = None

    def resume(self, u: np.ndarray, far: bool) -> None:
        """The state after the regular point of unknowns ``u`` (a resumed branch), ``far``
        as it was then."""
        self.far, self.previous = far, lap_difference(u, self.n, self.m_parent, self.state_scale)

    def observe(self, cp, op, deliver: Callable[[object], bool]) -> bool:
        """Pass the continuation point ``cp`` (as orbit point ``op``) on to ``deliver``, or hold
        it back, or end the branch at the parent; True ends the branch."""
        D = lap_difference(cp.u, self.n, self.m_parent, self.state_scale)
        sep = float(np.abs(D).max())
        self.far = self.far or sep > 2.0 * self.switch_size
        # past the branch point the step lands on the mirror image: the lap difference reverses
        flipped = self.previous is not None and float(D @ self.previous) < 0.0
        if self.far and self.partners and (flipped or sep < 0.5 * self.switch_size):
            q = min(self.partners, key=lambda q: abs(q.parameter - cp.lam))
            keep = [] if flipped else self.pending + ([op] if cp.special is None else [])
            for o in keep:
                deliver(o)
            deliver(doubled_point(q, self.period, np.concatenate([q.u, q.u]), branch=self.branch))
            self.merged_at = q
            return True
        if cp.special is not None:
            self.pending.append(op)  # delivered with the next regular point
            return False
        self.previous = D
        stop_now = False
        for o in self.pending + [op]:
            stop_now = deliver(o) or stop_now
        self.pending = []
        return stop_now


# ----------------------------------------------------------------------------------------------
# Symmetry-breaking pitchforks of planar orbits (cablesim.orbits.symmetry)
# ----------------------------------------------------------------------------------------------
def pitchfork_direction(ev: Evaluation, mirror, segments: int, state_scale: np.ndarray, switch_size: float,
                        shooting=None, phase: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Direction into the nonplanar branch at a pitchfork of a planar orbit, and the step.

    The critical eigenvector of the out-of-plane block ``Phi_o`` (multiplier +1) is ``w_0 = Q_o
    e``; carried through the segments, ``w_{k+1} = G_k w_k`` (:func:`segment_images`), it is a
    null vector of the shooting Jacobian that lies in the odd subspace. On a matrix-free orbit it
    is the out-of-plane block's leading eigenvector (:mod:`cablesim.orbits.splitleading`). The
    branch leaves the planar one along it with no change of the parameter (a pitchfork's
    parabola); ``-eps`` gives the mirror image.

    On a planar orbit that a rotation symmetry moves (:mod:`cablesim.orbits.rotation`), the
    generator ``g`` is odd and ``Phi_o`` holds its multiplier +1 besides the critical one: the
    eigenvector nearest +1 could be ``g``, which leads to the rotated planar orbit, not off the
    plane. The block is then deflated along ``g`` (:func:`~cablesim.orbits.rotation.deflate`, as
    the tests that located the pitchfork saw it; the matrix-free block is computed on the
    deflated action already), and the direction is taken without its component along the
    stacked generator ``q`` (still a null vector: ``G_k g_k = g_(k+1)``), so that it satisfies
    the phase condition ``q . du = 0``.

    Parameters
    ----------
    ev : Evaluation
        Shooting evaluation of the planar orbit at its pitchfork.
    mirror : Mirror
        The cable's mirror symmetry.
    segments : int
        Shooting segments of the orbit.
    state_scale : ndarray (n,)
        Typical size of each state component.
    switch_size : float
        Scaled size of the perturbation.
    shooting : MatrixFreeShooting, optional
        The shooting of a matrix-free orbit of several segments (:func:`segment_images`).
    phase : ndarray (segments n,), optional
        ``q = g / |g|``: the unit generator of the rotation over the segments
        (:func:`~cablesim.orbits.rotation.phase_direction`), on an orbit the rotation moves.

    Returns
    -------
    direction : ndarray (segments n,)
    eps : float
        Step along ``direction`` of scaled size ``switch_size``.
    """
    n = mirror.dim
    if ev.monodromy is None:  # matrix-free: the out-of-plane block's leading eigenvectors (ev.split)
        w = ev.split.vector(mirror.labels[1], 1.0) * np.asarray(state_scale, dtype=float)
        w0 = mirror.odd @ (mirror.odd.T @ w)  # in the odd subspace to round-off: exactly there
    else:
        _, Po, _ = mirror.blocks(ev.monodromy)
        if phase is not None:
            Po = deflate(Po, mirror.odd.T @ phase[:n])
        mu, V = np.linalg.eig(Po)
        w0 = mirror.odd @ np.real(V[:, int(np.argmin(np.abs(mu - 1.0)))])
    direction = np.concatenate(segment_images(ev, w0, segments, shooting))
    if phase is not None:
        direction = without(direction, phase)
    eps = switch_size / np.linalg.norm(direction / np.tile(state_scale, segments))
    return direction, eps


class PlaneWatch:
    """Watches a nonplanar branch born at a pitchfork for its return to the plane: where its
    out-of-plane part, once well away, falls back below half the start's (or reverses: the step
    went through the plane onto the mirror image), the branch ends there (at a pitchfork of a
    planar orbit). Special points are held back until the next regular point, and dropped with
    the end (the test functions trip as the branch meets the plane)."""

    def __init__(self, mirror, n: int, state_scale: np.ndarray, switch_size: float):
        self.mirror = mirror
        self.n = n
        self.state_scale = state_scale
        self.switch_size = switch_size
        self.far = False
        self.previous: np.ndarray | None = None
        self.pending: list = []
        #: Whether the branch came back to the plane.
        self.returned = False

    def odd(self, u: np.ndarray) -> np.ndarray:
        """The scaled out-of-plane part of the state in the unknowns ``u``."""
        x = np.asarray(u[: self.n], dtype=float)
        return self.mirror.odd.T @ x / (np.abs(self.mirror.odd.T) @ self.state_scale)

    def resume(self, u: np.ndarray, far: bool) -> None:
        """The state after the regular point of unknowns ``u`` (a resumed branch), ``far``
        as it was then."""
        self.far, self.previous = far, self.odd(u)

    def observe(self, cp, op, deliver: Callable[[object], bool]) -> bool:
        """Pass the continuation point ``cp`` (as orbit point ``op``) on to ``deliver``, or hold
        it back, or end the branch; True ends it."""
        odd = self.odd(cp.u)
        size = float(np.abs(odd).max())
        self.far = self.far or size > 2.0 * self.switch_size
        flipped = self.previous is not None and float(odd @ self.previous) < 0.0
        if self.far and (flipped or size < 0.5 * self.switch_size):
            self.returned = True
            return True
        if cp.special is not None:
            self.pending.append(op)
            return False
        self.previous = odd
        stop_now = False
        for o in self.pending + [op]:
            stop_now = deliver(o) or stop_now
        self.pending = []
        return stop_now
