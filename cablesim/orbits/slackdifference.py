"""Matrix-free shooting through slack: the flow of the dense shooting, its action by differences.

:class:`~cablesim.orbits.matrixfree.MatrixFreeShooting` carries directions along its orbits
(explicit schemes, or the tape of a Radau IIA orbit) but stops at a slack segment. Through slack
the orbit is integrated by :class:`~cablesim.orbits.shooting.Shooting` with ``through_slack``
(:mod:`cablesim.orbits.slackflow`: every slack onset and re-tightening located, no step across
one) without its variational equations, at ``O(n)`` per step, and the monodromy acts on a vector
by central differences of that flow map::

    G v ~ (Phi(x + d v) - Phi(x - d v)) / (2 d)

Why differences are sound here: the field is continuous where a segment changes mode, so the
saltation matrix of every transversal event is the identity and the event times' derivatives
drop out (docs/theory.md, "Periodic orbits through slack"); the flow map is as smooth as its
smooth pieces. The events are located to :data:`~cablesim.orbits.slackflow.EVENT_TOL` of a
step; the field being continuous there, a misplaced event moves the end state by the square of
that, far below the differences' round-off.

Why they are extrapolated: the flow map's curvature grows without bound towards a grazing orbit
(an episode's depth sets the scale of its nonlinearity). ``d`` is chosen per direction so that no
component moves by more than :data:`DIFFERENCE_STEP` of its half's extent over the orbit
(displacements and velocities apart); on the paper's cable at FL x 13.5 (segment 3 slack for 57
ms of its 2.565 s period) plain central differences at that step were 1.2e-5 off the variational
monodromy (quadratically in the step: 1.2e-3 at ten times it). The differences at ``d`` and
``d / 2`` are combined by Richardson's extrapolation (error ``O(d^4)``), ``d`` quartered while
they differ by more than :data:`DIFFERENCE_AGREEMENT`: 1.2e-8 off at most there
(tests/test_slack_difference.py).

Cost: four orbit integrations per direction (more where ``d`` is quartered), against one banded
solve per step for a Radau tape; on a 20-node heavy span (80 states, 681 rk8 steps a period) a
Newton solve with its leading multipliers took 15.8 s of CPU against 1.4 s for the dense shooting
through slack, which :mod:`cablesim.orbits.accelerate` therefore uses up to its
:data:`~cablesim.orbits.accelerate.DENSE_DOF` degrees of freedom; this serves the cables above.
The interface is that of :class:`~cablesim.orbits.matrixfree.MatrixFreeShooting` as
:func:`~cablesim.orbits.accelerate.newton_mf` and
:func:`~cablesim.orbits.matrixfree.orbit_leading` use it (``evaluate`` at a fixed parameter,
``segment_apply``, and the actions of :class:`~cablesim.orbits.matrixfree.SegmentActions`).
"""

from __future__ import annotations

import numpy as np

from .kernels import OK
from .matrixfree import MFEvaluation, SegmentActions
from .shooting import FlowStatus, Shooting
from .systems import OdeSystem

#: Largest move of any state component in a difference, as a fraction of the extent of its half
#: (displacements, velocities) over the orbit: truncation ``~ DIFFERENCE_STEP^2``, round-off
#: ``~ 1e-16 / DIFFERENCE_STEP``.
DIFFERENCE_STEP = 1e-5
#: Largest difference between the central differences at ``d`` and ``d / 2``, relative to the
#: column, before ``d`` is quartered (at most :data:`DIFFERENCE_REFINEMENTS` times): their
#: extrapolation's error is then about its square.
DIFFERENCE_AGREEMENT = 1e-4
DIFFERENCE_REFINEMENTS = 3


class SlackDifferenceShooting(SegmentActions):
    """Flow maps of the ``m`` segments of a ``p``-periodic orbit through slack and their action
    on vectors by central differences (module docstring).

    Parameters
    ----------
    system : OdeSystem
        A system that can follow slack segments (``system.slack``; the exact analysis).
    period, segments, parameter, scheme, steps_per_period, step_rate
        As for :class:`~cablesim.orbits.shooting.Shooting` (explicit schemes only).
    """

    def __init__(self, system: OdeSystem, period: int = 1, segments: int = 1, parameter: str = "omega",
                 scheme: str = "rk8", steps_per_period: int | None = None, step_rate: float | None = None):
        if system.slack is None:
            raise ValueError("this system cannot follow slack segments (exact analysis, supports at rest)")
        self.flow = Shooting(system, period, segments, parameter, scheme=scheme, steps_per_period=steps_per_period,
                             step_rate=step_rate, through_slack=True)
        self.flow.modes_from_start = True  # its orbits go slack: no plain flow tried first
        self.system = system
        self.period, self.segments, self.parameter = self.flow.period, self.flow.segments, parameter
        self.scheme = scheme
        self.n = system.dim
        #: Counters: directions applied (four flows each, or more).
        self.products = 0

    def omega_of(self, lam: float) -> float:
        return self.flow.omega_of(lam)

    def default_lam(self) -> float:
        return self.flow.default_lam()

    @property
    def calls(self) -> int:
        """Segment integrations so far."""
        return self.flow.calls

    def evaluate(self, u: np.ndarray, lam: float, jac: bool = False) -> MFEvaluation:
        """Residual at ``(u, lam)`` (its actions by :meth:`segment_apply`; no ``J_lam``: the
        steady states it serves are at a fixed parameter)."""
        if jac:
            raise ValueError("the shooting through slack by differences forms no parameter derivative")
        ev = self.flow.evaluate(u, lam, jac=False)
        starts = np.asarray(u, dtype=float).reshape(self.segments, self.n).copy()
        return MFEvaluation(ev.u, ev.lam, ev.omega, ev.period, ev.T, ev.r, None, None, ev.ends, None, None, None,
                            np.nan, np.nan, ev.xmax, ev.xmin, ev.status, events=ev.events, starts=starts)

    def _extent(self, ev: MFEvaluation) -> np.ndarray:
        """Per component: the extent of its half (displacements, velocities) over the orbit."""
        ext = np.maximum(np.abs(ev.xmax), np.abs(ev.xmin))
        h = self.n // 2
        tiny = np.finfo(float).tiny
        return np.concatenate([np.full(h, max(float(ext[:h].max()), tiny)),
                               np.full(self.n - h, max(float(ext[h:].max()), tiny))])

    def segment_apply(self, ev: MFEvaluation, k: int, X: np.ndarray) -> np.ndarray:
        """``G_k X`` for the columns of ``X`` (n, q): Richardson's extrapolation of central
        differences of segment ``k``'s flow map from its start at steps ``d`` and ``d / 2``
        (error ``O(d^4)``), ``d`` quartered while the two differ by more than
        :data:`DIFFERENCE_AGREEMENT` of the column (the flow map's curvature grows without bound
        towards a grazing orbit, where an episode's depth sets the scale of its nonlinearity)."""
        X = np.asarray(X, dtype=float)
        ext = self._extent(ev)
        out = np.zeros_like(X)
        for j in range(X.shape[1]):
            v = X[:, j]
            size = float(np.max(np.abs(v) / ext))
            if size == 0.0:
                continue
            d = DIFFERENCE_STEP / size
            for _ in range(DIFFERENCE_REFINEMENTS + 1):
                wide, narrow = self._central(ev, k, v, d), self._central(ev, k, v, d / 2.0)
                out[:, j] = (4.0 * narrow - wide) / 3.0
                if np.abs(narrow - wide).max() <= DIFFERENCE_AGREEMENT * np.abs(out[:, j]).max():
                    break
                d /= 4.0
            self.products += 1
        return out

    def _central(self, ev: MFEvaluation, k: int, v: np.ndarray, d: float) -> np.ndarray:
        ends = []
        for s in (d, -d):
            seg = self.flow.segment(k, ev.starts[k] + s * v, ev.lam, jac=False)
            if seg["status"] != OK:
                raise FloatingPointError(f"a differenced flow failed (status {FlowStatus(seg['status']).name})")
            ends.append(seg["x"])
        return (ends[0] - ends[1]) / (2.0 * d)
