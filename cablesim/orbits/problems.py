"""The periodicity condition of a shooting as a continuation problem
(:mod:`cablesim.orbits.continuation`): the dense one, and the one of a branch of planar orbits
of a mirror-symmetric system whose bifurcation tests run on the two blocks of the monodromy."""

from __future__ import annotations

import numpy as np

from . import kernels as ok
from . import stability
from .shooting import Evaluation, FlowStatus, Shooting
from .symmetry import Mirror


class OrbitProblem:
    """The periodicity condition of a :class:`Shooting` as a continuation problem."""

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

    def evaluate(self, u, lam):
        ev = self.shooting.evaluate(u, lam, blocks=self.blocks, record=self.record)
        if ev.status != ok.OK:
            self.last_failure = ev.status
            return None
        return ev

    def test_functions(self, ev: Evaluation) -> np.ndarray:
        return stability.test_functions(ev.multipliers)

    def confirm(self, name: str, ev: Evaluation) -> str | None:
        return stability.confirm(name, ev.multipliers)

    def step_ratio(self, ev_a: Evaluation, ev_b: Evaluation) -> float:
        return stability.step_ratio(ev_a.multipliers, ev_b.multipliers)


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

    def test_functions(self, ev: Evaluation) -> np.ndarray:
        return stability.split_test_functions(*block_multipliers(self.mirror, ev))

    def step_ratio(self, ev_a: Evaluation, ev_b: Evaluation) -> float:
        """Each block in its own terms: the in-plane multipliers as the planar cable's
        (:func:`~cablesim.orbits.stability.step_ratio`), the out-of-plane block on its matrix
        (:func:`~cablesim.orbits.stability.interpolated_step_ratio`). The out-of-plane
        multipliers of a lightly damped string turn fast with the parameter and pass near
        ``+1`` and ``-1`` again and again without approaching the circle; judged as multipliers
        they held the steps of the planar branch to a fraction of the planar cable's."""
        if not self.block_step_rule:
            return super().step_ratio(ev_a, ev_b)
        in_a, in_b = block_multipliers(self.mirror, ev_a)[0], block_multipliers(self.mirror, ev_b)[0]
        return max(stability.step_ratio(in_a, in_b),
                   stability.interpolated_step_ratio(monodromy_blocks(self.mirror, ev_a)[1],
                                                     monodromy_blocks(self.mirror, ev_b)[1]))

    def confirm(self, name: str, ev: Evaluation) -> str | None:
        mu_in, mu_out = block_multipliers(self.mirror, ev)
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
