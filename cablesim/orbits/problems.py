"""The periodicity condition of a shooting as a continuation problem
(:mod:`cablesim.orbits.continuation`): the dense one, and the one of a branch of planar orbits
of a mirror-symmetric system whose bifurcation tests run on the two blocks of the monodromy.
On a system invariant under rotations about an axis (:mod:`cablesim.orbits.rotation`), the
tests, the step rule and the stability of an orbit the rotation moves exclude the multiplier +1
that the symmetry forces."""

from __future__ import annotations

import numpy as np

from . import kernels as ok
from . import stability
from .rotation import Neutral, Rotation, RotationPhase, neutral
from .shooting import Evaluation, FlowStatus, Shooting
from .symmetry import Mirror


class OrbitProblem(RotationPhase):
    """The periodicity condition of a :class:`Shooting` as a continuation problem (with the phase
    condition of :class:`~cablesim.orbits.rotation.RotationPhase` on a system with a rotation
    symmetry)."""

    test_names = stability.TEST_NAMES
    fold_tests = stability.FOLD_TESTS

    def __init__(self, shooting: Shooting, state_scale: np.ndarray, lam_scale: float):
        self.shooting = shooting
        #: Status of the last flow that failed (why a step was refused), if any.
        self.last_failure: FlowStatus | None = None
        self.u_scale = np.tile(np.asarray(state_scale, dtype=float), shooting.segments)
        self.lam_scale = float(lam_scale)
        #: Diagonal blocks the variational equations are carried on (None: the whole Jacobian;
        #: :meth:`~cablesim.orbits.shooting.Shooting.segment`).
        self.blocks = None
        #: Keep every evaluation's orbit at its steps (:attr:`Evaluation.steps`), for the measures
        #: of the converged orbits (strain, whirling) without integrating them once more.
        self.record = False
        self.init_phase()

    def evaluate(self, u, lam):
        ev = self.shooting.evaluate(u, lam, blocks=self.blocks, record=self.record)
        if ev.status != ok.OK:
            self.last_failure = ev.status
            return None
        return self.phased(ev, u)

    def neutral(self, ev: Evaluation) -> Neutral | None:
        """The multiplier the rotation symmetry forces to +1 on this orbit, with the deflated
        multipliers (:func:`evaluation_neutral`), or None."""
        return evaluation_neutral(self.rotation, self.u_scale[: self.shooting.n], ev)

    def tested(self, ev: Evaluation) -> np.ndarray:
        """The multipliers the tests and the step rule see: without the neutral one, if any."""
        nt = self.neutral(ev)
        return ev.multipliers if nt is None else nt.multipliers

    def test_functions(self, ev: Evaluation) -> np.ndarray:
        return stability.test_functions(self.tested(ev))

    def confirm(self, name: str, ev: Evaluation) -> str | None:
        return stability.confirm(name, self.tested(ev))

    def step_ratio(self, ev_a: Evaluation, ev_b: Evaluation, ev_before: Evaluation | None = None) -> float:
        return stability.step_ratio(self.tested(ev_a), self.tested(ev_b))


class PlanarOrbitProblem(OrbitProblem):
    """:class:`OrbitProblem` on a branch of planar orbits of a mirror-symmetric system: the
    bifurcation tests run on the in-plane and the out-of-plane blocks of the monodromy apart
    (:mod:`cablesim.orbits.symmetry`), so that an out-of-plane multiplier through +1 is a
    pitchfork, never a fold or branch point of the planar branch."""

    test_names = stability.TEST_NAMES + stability.OUT_OF_PLANE_TESTS
    #: Judge the out-of-plane block's steps on its matrix (:meth:`step_ratio`); False: on all the
    #: multipliers together, as the matrix-free path does (it forms no block).
    block_step_rule = True

    def __init__(self, shooting: Shooting, state_scale: np.ndarray, lam_scale: float, mirror: Mirror):
        super().__init__(shooting, state_scale, lam_scale)
        self.mirror = mirror
        #: The components of the two blocks when the plane's normal is a coordinate axis: the
        #: variational equations are then integrated on the blocks alone (about the planar
        #: cable's cost plus the out-of-plane block's instead of the whole spatial Jacobian's).
        self.blocks = mirror.coordinate_blocks()

    def neutral(self, ev: Evaluation) -> Neutral | None:
        """The out-of-plane multiplier the rotation symmetry forces to +1 (a planar orbit that
        leaves the chord: the generator is odd), with the deflated out-of-plane block, or None."""
        return evaluation_neutral(self.rotation, self.u_scale[: self.shooting.n], ev, self.mirror)

    def tested_blocks(self, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
        """The in-plane and out-of-plane multipliers the tests see."""
        mu_in, mu_out = block_multipliers(self.mirror, ev)
        nt = self.neutral(ev)
        return mu_in, (mu_out if nt is None else nt.multipliers)

    def test_functions(self, ev: Evaluation) -> np.ndarray:
        return stability.split_test_functions(*self.tested_blocks(ev))

    def step_ratio(self, ev_a: Evaluation, ev_b: Evaluation, ev_before: Evaluation | None = None) -> float:
        """Each block in its own terms: the in-plane multipliers as the planar cable's
        (:func:`~cablesim.orbits.stability.step_ratio`), the out-of-plane block on its matrix,
        along the geodesic from ``ev_a`` to ``ev_b`` with the model's error from ``ev_before``
        (:func:`~cablesim.orbits.stability.geodesic_step_ratio`). The out-of-plane multipliers
        of a lightly damped string turn fast with the parameter and pass near ``+1`` and ``-1``
        again and again without approaching the circle; judged as multipliers they held the
        steps of the planar branch to a fraction of the planar cable's."""
        if not self.block_step_rule:
            return super().step_ratio(ev_a, ev_b)
        in_a, in_b = block_multipliers(self.mirror, ev_a)[0], block_multipliers(self.mirror, ev_b)[0]
        out = (self.out_of_plane_block(ev_a), self.out_of_plane_block(ev_b))
        if ev_before is not None:  # the model's error from the point before the step
            out += (self.out_of_plane_block(ev_before), -self.distance(ev_before, ev_a), self.distance(ev_a, ev_b))
        return max(stability.step_ratio(in_a, in_b), stability.geodesic_step_ratio(*out))

    def distance(self, ev_a: Evaluation, ev_b: Evaluation) -> float:
        """The scaled distance between two points of the branch (``u / u_scale``, ``lambda /
        lam_scale``), the measure of arclength along it."""
        return stability.scaled_distance(ev_a, ev_b, self.u_scale, self.lam_scale)

    def out_of_plane_block(self, ev: Evaluation) -> np.ndarray:
        """The out-of-plane block of the monodromy, deflated by the neutral multiplier if any
        (the deflation is smooth along the branch, so the step rule may interpolate it)."""
        nt = self.neutral(ev)
        return monodromy_blocks(self.mirror, ev)[1] if nt is None else nt.matrix

    def confirm(self, name: str, ev: Evaluation) -> str | None:
        mu_in, mu_out = self.tested_blocks(ev)
        if name.startswith("out-of-plane "):
            base = stability.confirm(name[len("out-of-plane "):], mu_out)
            return None if base is None else name
        return stability.confirm(name, mu_in)


def block_multipliers(mirror: Mirror, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
    """The in-plane and out-of-plane multipliers of a planar orbit's evaluation
    (:func:`~cablesim.orbits.symmetry.split_multipliers` of its monodromy), computed once per
    evaluation: the tests, their confirmation and the orbit's labels all ask for them."""
    if ev.blocks_mu is None:
        Pe, Po = monodromy_blocks(mirror, ev)
        ev.blocks_mu = tuple(stability.sort_multipliers(np.linalg.eigvals(P)) for P in (Pe, Po))
    return ev.blocks_mu


def monodromy_blocks(mirror: Mirror, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
    """The in-plane and out-of-plane blocks of a planar orbit's monodromy
    (:meth:`~cablesim.orbits.symmetry.Mirror.blocks`), computed once per evaluation."""
    if ev.blocks_phi is None:
        ev.blocks_phi = mirror.blocks(ev.monodromy)[:2]
    return ev.blocks_phi


def labelled_multipliers(mirror: Mirror, ev: Evaluation) -> tuple[np.ndarray, tuple]:
    """The multipliers of a planar orbit's evaluation from the two blocks of its monodromy,
    sorted together (:func:`~cablesim.orbits.stability.sort_multipliers`), and the block of each."""
    return mirror.labelled(*block_multipliers(mirror, ev))


def evaluation_neutral(rotation: Rotation | None, scale: np.ndarray, ev: Evaluation,
                       mirror: Mirror | None = None) -> Neutral | None:
    """The neutral multiplier of an evaluation's orbit under ``rotation``
    (:func:`~cablesim.orbits.rotation.neutral`, of the out-of-plane block with a ``mirror``),
    computed once per evaluation; None without the symmetry, without a monodromy, or on an orbit
    the rotation leaves in place."""
    if rotation is None or ev.monodromy is None:
        return None
    if ev.neutral is None:
        g = rotation.moved(ev.u[: ev.monodromy.shape[0]], scale)
        if g is None:
            ev.neutral = False
        elif mirror is None:
            ev.neutral = neutral(ev.monodromy, g)
        else:
            ev.neutral = neutral(monodromy_blocks(mirror, ev)[1], mirror.odd.T @ g)
    return ev.neutral or None
