"""The leading Floquet multipliers of a planar orbit of a mirror-symmetric system, block by block,
from the monodromy's action on vectors, and the matrix-free continuation problem of planar
branches.

On an orbit in the mirror plane the monodromy ``M`` maps the even (in-plane) states onto even
states and the odd (out-of-plane) ones onto odd ones (:mod:`cablesim.orbits.symmetry`): a
direction with no out-of-plane part stays in the plane, one with no in-plane part stays across
it. In the scaled coordinates ``x / d`` of the matrix-free shooting (``d`` the state scale, ``D =
diag(d)``) the two invariant subspaces are spanned by the orthonormal ``U_e``, ``U_o`` of
``D^-1 Q_e`` and ``D^-1 Q_o``, and the blocks

    ``M_e = U_e^T D^-1 M D U_e``,   ``M_o = U_o^T D^-1 M D U_o``

are similar to the dense path's ``Phi_e``, ``Phi_o``: the same multipliers. Each block's leading
multipliers are computed apart (:func:`~cablesim.orbits.floquet.leading_multipliers` on the
action ``y -> M_e y``, of dimension ``4 n_nodes``, and ``y -> M_o y``, ``2 n_nodes``), each with
its own adaptive count and its own largest discarded modulus below the bound, so that an
out-of-plane multiplier near +1 is never mixed with the in-plane ones: on the whole action the
subspace iteration returns both sets together, with no label, and an out-of-plane crossing of
+1 would read as a fold of the planar branch.

The two blocks' invariant subspaces together are one of ``D^-1 M D`` (:func:`joined`: the
eigenvectors that start a period-doubled branch, the accuracy check of the kept pairs). The
continuation's bordered systems of a planar branch are solved in the plane
(:class:`PlanarMatrixFreeProblem`): its corrections and tangents have no out-of-plane part, as
the dense path's (to round-off), and its Krylov iteration is preconditioned by the in-plane
block alone. Across the plane the Jacobian is singular at a pitchfork, and a Krylov iteration
over the whole state, preconditioned by a subspace whose out-of-plane multiplier is 1 there,
turned round-off into out-of-plane corrections (the correction failed at the located point).

A planar orbit of a cable symmetric about its chord that the rotation moves has its generator
``g`` across the plane (odd): the out-of-plane block is computed on the deflated action
(:func:`~cablesim.orbits.matrixfree.scaled_monodromy`), without the multiplier +1 the symmetry
forces, as the dense path deflates its out-of-plane block (:mod:`cablesim.orbits.rotation`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import stability
from ..modal import IN_PLANE
from .floquet import DEFAULT_BOUND, DEFAULT_TOL, Deflation, Leading, leading_from, leading_multipliers, truncated_tests
from .matrixfree import Bordered, MatrixFreeShooting, MFEvaluation, scaled_monodromy
from .mfproblem import MatrixFreeOrbitProblem, reported_multipliers
from .stability import sort_multipliers
from .symmetry import Mirror

__all__ = ["PlanarMatrixFreeProblem", "SplitLeading", "block_bases", "joined", "labelled_leading", "split_leading"]


@dataclass
class SplitLeading:
    """The leading multipliers of the in-plane and out-of-plane blocks of a planar orbit.

    Attributes
    ----------
    in_plane, out_of_plane : Leading
        Each block's (:class:`~cablesim.orbits.floquet.Leading`, in the block coordinates
        ``y`` of ``U y``): its kept multipliers above the bound, their residuals, and its own
        largest discarded modulus.
    bases : tuple of ndarray
        ``(U_e, U_o)``: orthonormal bases of the two blocks in scaled coordinates (module
        docstring).
    """

    in_plane: Leading
    out_of_plane: Leading
    bases: tuple

    def block(self, plane: str) -> Leading:
        """The :class:`~cablesim.orbits.floquet.Leading` of block ``plane``."""
        return self.in_plane if plane == IN_PLANE else self.out_of_plane

    def vector(self, plane: str, target: complex) -> np.ndarray:
        """The real part of block ``plane``'s eigenvector whose multiplier is nearest ``target``,
        in the scaled coordinates of the whole state."""
        lead = self.block(plane)
        j = int(np.argmin(np.abs(lead.multipliers - target)))
        return np.real(self.bases[0 if plane == IN_PLANE else 1] @ lead.vectors[:, j])

    @property
    def discarded(self) -> float:
        """The largest modulus left out of either block."""
        return max(self.in_plane.discarded, self.out_of_plane.discarded)


def block_bases(mirror: Mirror, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(U_e, U_o)``: orthonormal bases of the even and odd states in the coordinates ``x /
    scale`` (module docstring). With one scale for the three components of every node's
    displacement (and of its velocity), as the cable's, they are ``Q_e`` and ``Q_o`` themselves
    up to the signs of their columns."""
    d = np.asarray(scale, dtype=float)[:, None]
    return tuple(np.linalg.qr(Q / d)[0] for Q in (mirror.even, mirror.odd))


def joined(split: SplitLeading) -> Leading:
    """Both blocks as one :class:`~cablesim.orbits.floquet.Leading` of the whole scaled action:
    the multipliers of both (by decreasing modulus), their eigenvectors in the whole state, and
    the union of the two invariant subspaces, ``D^-1 M D V = V S``, made orthonormal (``V =
    [U_e B_e, U_o B_o] = W R``, ``S = R diag(T_e, T_o) R^-1``)."""
    Ue, Uo = split.bases
    a, b = split.in_plane, split.out_of_plane
    mu = np.concatenate([a.multipliers, b.multipliers])
    order = np.lexsort((-mu.imag, -np.abs(mu)))
    vectors = np.hstack([Ue @ a.vectors, Uo @ b.vectors])[:, order]
    V = np.hstack([Ue @ a.basis, Uo @ b.basis])
    W, R = np.linalg.qr(V)
    T = np.zeros((V.shape[1], V.shape[1]))
    k = a.basis.shape[1]
    T[:k, :k], T[k:, k:] = a.schur, b.schur
    S = np.linalg.solve(R.T, (R @ T).T).T  # R T R^-1
    return Leading(mu[order], np.concatenate([a.residuals, b.residuals])[order], vectors, W, S, split.discarded,
                   a.bound, a.products + b.products, a.complete and b.complete)


def split_leading(shooting: MatrixFreeShooting, ev: MFEvaluation, mirror: Mirror, scale: np.ndarray,
                  bound: float = DEFAULT_BOUND, tol: float = DEFAULT_TOL, start: SplitLeading | None = None,
                  bases: tuple | None = None, neutral: np.ndarray | None = None) -> SplitLeading:
    """The leading multipliers of both blocks of the planar orbit ``ev`` (kept in ``ev.split``;
    ``ev.leading`` their :func:`joined` form, ``ev.multipliers`` all of them sorted), in the
    coordinates ``x / scale``.

    Parameters
    ----------
    shooting : MatrixFreeShooting
    ev : MFEvaluation
        A planar orbit (its out-of-plane part zero) of a system with mirror ``mirror``.
    mirror : Mirror
    scale : ndarray (n,)
        Typical size of each state component.
    bound, tol : float
        Kept moduli and residuals (:func:`~cablesim.orbits.floquet.leading_multipliers`), for each
        block.
    start : SplitLeading, optional
        A nearby orbit's, whose block bases start the iterations.
    bases : tuple, optional
        :func:`block_bases` of ``mirror`` and ``scale``, if already formed.
    neutral : ndarray, optional
        The odd eigenvector ``g`` (unscaled) of a multiplier +1 forced by a symmetry: the
        out-of-plane block's multipliers are then those of the deflated action, without it.
    """
    if ev.split is None:
        bases = block_bases(mirror, scale) if bases is None else bases
        actions = (scaled_monodromy(shooting, ev, scale), scaled_monodromy(shooting, ev, scale, neutral))
        blocks = []
        for j, U in enumerate(bases):
            def apply(Y, U=U, act=actions[j]):
                return U.T @ act(U @ Y)

            begin = None if start is None else (start.in_plane, start.out_of_plane)[j].basis
            blocks.append(leading_multipliers(apply, U.shape[1], bound=bound, tol=tol, start=begin))
        ev.split = SplitLeading(blocks[0], blocks[1], bases)
        ev.leading = joined(ev.split)
        ev.multipliers = sort_multipliers(ev.leading.multipliers)
    return ev.split


def labelled_leading(mirror: Mirror, split: SplitLeading, neutral=None) -> tuple[np.ndarray, tuple]:
    """The kept multipliers of both blocks sorted together
    (:func:`~cablesim.orbits.stability.sort_multipliers`), and the block of each (the form of
    :func:`~cablesim.orbits.problems.labelled_multipliers`); with the out-of-plane ones the
    ``neutral`` multiplier excluded from them, if any (:class:`~cablesim.orbits.rotation.Neutral`,
    :func:`~cablesim.orbits.mfproblem.reported_multipliers`)."""
    out = reported_multipliers(split.out_of_plane, neutral) if neutral else leading_from(split.out_of_plane)
    return mirror.labelled(leading_from(split.in_plane), out)


class PlanarMatrixFreeProblem(MatrixFreeOrbitProblem):
    """:class:`~cablesim.orbits.mfproblem.MatrixFreeOrbitProblem` on a branch of planar orbits of a
    mirror-symmetric system: the bifurcation tests run on each block's leading multipliers
    (:func:`split_leading`), those of :data:`~cablesim.orbits.stability.TEST_NAMES` on the
    in-plane block and those of :data:`~cablesim.orbits.stability.OUT_OF_PLANE_TESTS` on the
    out-of-plane one, as :class:`~cablesim.orbits.problems.PlanarOrbitProblem` does on the dense
    monodromy's blocks; the step control on the multipliers of both."""

    test_names = stability.TEST_NAMES + stability.OUT_OF_PLANE_TESTS

    def __init__(self, shooting: MatrixFreeShooting, state_scale: np.ndarray, lam_scale: float, mirror: Mirror,
                 bound: float = DEFAULT_BOUND):
        super().__init__(shooting, state_scale, lam_scale, bound)
        self.mirror = mirror
        self.bases = block_bases(mirror, self.state_scale)
        #: The split multipliers last computed (warm start of both blocks).
        self.latest_split: SplitLeading | None = None

    def split(self, ev: MFEvaluation) -> SplitLeading:
        """The split leading multipliers of ``ev`` (computed once, from the latest blocks)."""
        if ev.split is None:
            g = self.generator(ev)
            self.latest_split = split_leading(self.shooting, ev, self.mirror, self.state_scale, bound=self.bound,
                                              start=self.latest_split, bases=self.bases, neutral=g)
            self.latest = ev.leading
            self.record_neutral(ev, g, ev.split.out_of_plane, others=ev.split.in_plane.multipliers)
        return ev.split

    def leading(self, ev: MFEvaluation) -> Leading:
        self.split(ev)
        return ev.leading

    def in_plane(self, x: np.ndarray) -> np.ndarray:
        """The orthogonal projection of scaled shooting unknowns onto the in-plane states."""
        Ue = self.bases[0]
        X = np.reshape(x, (self.shooting.segments, -1))
        return ((X @ Ue) @ Ue.T).ravel()

    def bordered(self, ev: MFEvaluation, us, ls, rs) -> Bordered:
        """The bordered systems of the planar branch, solved in the plane (:class:`Bordered`'s
        ``project``: its corrections and tangents have no out-of-plane part), preconditioned by
        the in-plane block's invariant subspace."""
        split = ev.split if ev.split is not None else self.latest_split
        pre = None
        if split is not None and self.shooting.segments == 1:
            pre = Deflation(self.bases[0] @ split.in_plane.basis, split.in_plane.schur)
        return Bordered(self.shooting, ev, us, ls, rs, precondition=pre, project=self.in_plane,
                        phase=self.phase_vector)

    def test_functions(self, ev: MFEvaluation) -> np.ndarray:
        s = self.split(ev)
        return np.concatenate([truncated_tests(s.in_plane.multipliers), truncated_tests(s.out_of_plane.multipliers)])

    def confirm(self, name: str, ev: MFEvaluation) -> str | None:
        s = self.split(ev)
        if name.startswith("out-of-plane "):
            base = stability.confirm(name[len("out-of-plane "):], leading_from(s.out_of_plane))
            return None if base is None else name
        return stability.confirm(name, leading_from(s.in_plane))

