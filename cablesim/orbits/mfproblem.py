"""The periodicity condition of a :class:`~cablesim.orbits.matrixfree.MatrixFreeShooting` as a
continuation problem (:mod:`cablesim.orbits.continuation`), and the choice between the dense and
the matrix-free shooting.

The problem forms no Jacobian: its bordered systems are solved by GMRES on the shooting's
Jacobian action (:class:`~cablesim.orbits.matrixfree.Bordered`), preconditioned by the leading
invariant subspace of the monodromy at the latest point where the multipliers were computed
(a nearby orbit along the branch). At every converged point the leading multipliers are computed
(:func:`~cablesim.orbits.matrixfree.orbit_leading`, warm-started from the previous point's
subspace) and the bifurcation tests and the step control work on them
(:func:`~cablesim.orbits.floquet.truncated_tests`,
:func:`~cablesim.orbits.floquet.leading_step_ratio`: on a truncated spectrum, the monodromy on the
kept subspace along its geodesic).

On a system invariant under rotations about a cable's chord (:mod:`cablesim.orbits.rotation`)
the problem treats an orbit the rotation moves as the dense one does: its periodicity condition
carries the phase condition (in the residual and ``J_lam`` of every evaluation and in the
Jacobian's action of the bordered systems), and its tests, confirmation, step rule and stability
exclude the multiplier +1 the symmetry forces. The leading multipliers are computed on
Wielandt's deflation of the monodromy's action along the generator ``g``
(:func:`~cablesim.orbits.matrixfree.scaled_monodromy`), which moves that multiplier to
:data:`~cablesim.orbits.rotation.LEADING_SHIFT` (zero, below the bound) and keeps every other:
the kept set and the largest discarded modulus are then those of the other multipliers, as the
truncated tests need. Removing afterwards the kept multiplier nearest +1 would rely on telling it
from a genuine one near +1 (at a branch point or pitchfork of the branch itself, exactly where
it matters), and the iteration would still spend its products converging it; the deflation
needs no such choice and no extra product. The preconditioner is then built from the deflated
subspace, regular where the undeflated one holds the multiplier +1 (its ``(S - I)^-1``
singular to round-off: measured norm 1e13 on a stay's orbit, against 6 deflated). The neutral
multiplier itself is recorded from one product with ``g``
(:func:`~cablesim.orbits.rotation.action_neutral`: ``g^T M g / g^T g`` and
``|M g - g| / |g|``) and reported among the orbit's multipliers in place of the deflated one
(:func:`reported_multipliers`).
"""

from __future__ import annotations

import numpy as np

from . import kernels as ok
from . import stability
from .floquet import DEFAULT_BOUND, Deflation, Leading, leading_from, leading_step_ratio, truncated_tests
from .matrixfree import Bordered, MatrixFreeShooting, MFEvaluation, orbit_leading
from .rotation import LEADING_SHIFT, Neutral, RotationPhase, action_neutral
from .stability import sort_multipliers

__all__ = ["MATRIX_FREE_DOF", "MatrixFreeOrbitProblem", "reported_multipliers", "use_matrix_free",
           "uses_matrix_free"]

#: State dimension above which the continuation shoots matrix-free by default. Measured on the
#: heavy span (``benchmarks/bench_heavy_orbits.py --crossover``: one orbit by Newton's method
#: with its multipliers, rk8 both ways, medians of 3): the matrix-free shooting costs 2.3, 1.4,
#: 1.3 times the dense at 12, 20, 32 states and 0.75 times at 48.
MATRIX_FREE_DOF = 40


def use_matrix_free(dim: int, matrix_free: bool | None) -> bool:
    """Whether to shoot matrix-free: as asked, else from :data:`MATRIX_FREE_DOF`."""
    return bool(matrix_free) if matrix_free is not None else dim > MATRIX_FREE_DOF


def uses_matrix_free(system, matrix_free: bool | None) -> bool:
    """Whether the orbits of ``system`` are shot matrix-free: as asked, else above
    :data:`MATRIX_FREE_DOF` states for a system in mechanical form."""
    return use_matrix_free(system.dim, matrix_free) and bool(matrix_free or system.mechanical is not None)


def reported_multipliers(lead: Leading, neutral: Neutral) -> np.ndarray:
    """The multipliers of ``lead``, computed on the action deflated along the ``neutral``
    multiplier's eigenvector, with that multiplier among them (sorted): a complete spectrum holds
    the deflated one at :data:`~cablesim.orbits.rotation.LEADING_SHIFT`, which it replaces; a
    truncated one left it out."""
    mu = np.asarray(lead.multipliers)
    if lead.complete and mu.size:
        mu = np.delete(mu, int(np.argmin(np.abs(mu - LEADING_SHIFT))))
    return sort_multipliers(np.append(mu, neutral.multiplier))


class MatrixFreeOrbitProblem(RotationPhase):
    """:class:`~cablesim.orbits.branches.OrbitProblem` of a matrix-free shooting (module
    docstring; the phase condition of :class:`~cablesim.orbits.rotation.RotationPhase`).

    Parameters
    ----------
    shooting : MatrixFreeShooting
    state_scale : ndarray (n,)
        Typical size of each state component (also the coordinates of the multipliers'
        eigenvectors).
    lam_scale : float
    bound : float
        Multipliers of larger modulus are computed (:mod:`cablesim.orbits.floquet`).
    """

    test_names = stability.TEST_NAMES
    fold_tests = stability.FOLD_TESTS

    def __init__(self, shooting: MatrixFreeShooting, state_scale: np.ndarray, lam_scale: float,
                 bound: float = DEFAULT_BOUND):
        self.shooting = shooting
        self.last_failure = None
        self.state_scale = np.asarray(state_scale, dtype=float)
        self.u_scale = np.tile(self.state_scale, shooting.segments)
        self.lam_scale = float(lam_scale)
        self.bound = float(bound)
        #: The leading multipliers last computed (warm start and preconditioner).
        self.latest: Leading | None = None
        self.init_phase()

    def evaluate(self, u, lam):
        ev = self.shooting.evaluate(u, lam)
        if ev.status != ok.OK:
            self.last_failure = ev.status
            return None
        return self.phased(ev, u)

    @property
    def phase_vector(self) -> np.ndarray | None:
        """``q`` of the phase condition, if any (:class:`Bordered`'s ``phase``)."""
        return self.phase[1] if isinstance(self.phase, tuple) else None

    def leading(self, ev: MFEvaluation) -> Leading:
        """The leading multipliers of ``ev`` (computed once, from the latest subspace), without
        the neutral one of an orbit the rotation symmetry moves (module docstring), which is
        recorded in ``ev.neutral`` and added to ``ev.multipliers``."""
        if ev.leading is None:
            start = self.latest.basis if self.latest is not None else None
            g = self.generator(ev)
            self.latest = orbit_leading(self.shooting, ev, self.state_scale, bound=self.bound, start=start, neutral=g)
            self.record_neutral(ev, g, ev.leading)
        return ev.leading

    def record_neutral(self, ev: MFEvaluation, g: np.ndarray | None, lead: Leading,
                       others: np.ndarray | None = None) -> None:
        """``ev.neutral`` from the monodromy's action along the generator ``g`` (False without
        one), ``lead`` the leading multipliers the tests see (computed on the deflated action);
        ``ev.multipliers`` then are those of ``lead`` with the neutral one
        (:func:`reported_multipliers`) and the ``others`` (of another block)."""
        if g is None:
            ev.neutral = False if self.rotation is not None else None
            return
        ev.neutral = action_neutral(lambda X: self.shooting.monodromy_apply(ev, X), g, lead.multipliers)
        mu = reported_multipliers(lead, ev.neutral)
        ev.multipliers = mu if others is None else sort_multipliers(np.concatenate([others, mu]))

    def bordered(self, ev: MFEvaluation, us, ls, rs) -> Bordered:
        lead = ev.leading if ev.leading is not None else self.latest
        pre = None
        if lead is not None and self.shooting.segments == 1:
            pre = Deflation(lead.basis, lead.schur)
        return Bordered(self.shooting, ev, us, ls, rs, precondition=pre, phase=self.phase_vector)

    def test_functions(self, ev: MFEvaluation) -> np.ndarray:
        return truncated_tests(self.leading(ev).multipliers)

    def confirm(self, name: str, ev: MFEvaluation) -> str | None:
        return stability.confirm(name, leading_from(self.leading(ev)))

    def step_ratio(self, ev_a: MFEvaluation, ev_b: MFEvaluation, ev_before: MFEvaluation | None = None) -> float:
        """:func:`~cablesim.orbits.floquet.leading_step_ratio`: on a truncated spectrum the
        monodromy on the kept subspace along its geodesic, its error estimated from
        ``ev_before``; else the kept multipliers."""
        if ev_before is None:
            return leading_step_ratio(self.leading(ev_a), self.leading(ev_b))
        return leading_step_ratio(self.leading(ev_a), self.leading(ev_b), self.leading(ev_before),
                                  -self.distance(ev_before, ev_a), self.distance(ev_a, ev_b))

    def distance(self, ev_a: MFEvaluation, ev_b: MFEvaluation) -> float:
        """The scaled distance between two points of the branch
        (:func:`~cablesim.orbits.stability.scaled_distance`)."""
        return stability.scaled_distance(ev_a, ev_b, self.u_scale, self.lam_scale)
