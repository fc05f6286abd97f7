"""Steady states by shooting from the transient: a sweep point decided without waiting for it.

A sweep point integrated from rest (or from the previous point of a chain) spends most of its
time waiting for lightly damped transients to die out (damping ratio 0.01: a factor e every
``1 / (xi w1)``, about 40 s for the paper example). Here the response is integrated in short
chunks; after each, the periodic orbit the trajectory is approaching is sought by shooting
(Newton on ``(z, y')`` from the trajectory's state, for periods ``p = 1 .. max_period``) and
**accepted only when**

1. Newton converges and every Floquet multiplier is inside the unit circle (an unstable orbit,
   however long the response lingers near it, is never accepted: the paper's late jumps are still
   found), and
2. the trajectory has entered its neighbourhood: the distance from the trajectory's state to
   the orbit's (same forcing phase, scaled by the orbit's extent) is below :data:`NEAR`, and
   over the next ``q`` forcing periods (the least multiple of ``p`` not below
   :data:`CONTRACTION_PERIODS`) it shrinks at least as fast as the leading multiplier ``rho``
   predicts, ``d_q <= 2 rho^(q / p) d_0`` (a trajectory passing by on its way to another
   attractor does not keep contracting at that rate), or both distances are at the
   integration's accuracy (:data:`AT_ORBIT`).

The integration itself is that of :func:`cablesim.dynamics.steady.steady_response` (same
periodicity and Floquet rules, same cap); the shooting is a hook it calls every few forcing
periods, so a point that would be found steady, not steady or failed without acceleration is
found so with it, only sooner when an orbit is accepted. The amplitudes of an accepted orbit are
measured exactly as for an integrated one (:func:`~cablesim.dynamics.steady.periodic_response`).
"""

from __future__ import annotations

import numpy as np

from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import DOPRI5, Integrator
from ..dynamics.steady import DECIDE_EVERY, PointResult, SteadyCriterion, periodic_response, steady_response
from .shooting import Shooting, solve_orbit
from .systems import cable_system

#: The trajectory is near an orbit when its scaled distance is below this.
NEAR = 0.2
#: Shooting is tried at a period p once the last strobes repeat at lag p to this fraction.
REPEATS = 0.5
#: Newton iterations per shooting attempt (an orbit within reach converges in a few).
MAX_NEWTON = 8
#: Relative tolerance of an adaptive integrator while the transient is integrated.
TRANSIENT_RTOL = 1e-6
#: Newton's tolerance (relative to the orbit's extent): the orbit only seeds the measurement,
#: which integrates it with the sweep's own integrator.
NEWTON_TOL = 1e-7
#: Forcing periods over which the contraction towards a proposed orbit is checked.
CONTRACTION_PERIODS = 5
#: Scaled distances below this are at the integration's accuracy: the trajectory is on the orbit.
AT_ORBIT = 1e-6
#: Allowed excess of the observed contraction over the one the leading multiplier predicts.
CONTRACTION_SLACK = 2.0


def _third_order(eom: EquationsOfMotion, x: np.ndarray) -> np.ndarray:
    """``(z, y', y'')`` at forcing phase 0 from ``(z, y')`` (``y''`` from eq. 15)."""
    nd = eom.n_dof
    return eom.initial_state(z0=x[:nd], v0=x[nd:])


def _distance(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> float:
    return float(np.max(np.abs(a - b) / scale))


def _orbit_scale(eom: EquationsOfMotion, xmax: np.ndarray, xmin: np.ndarray) -> np.ndarray:
    """Per-component scale: the orbit's extent, displacements and velocities apart, floored."""
    nd = eom.n_dof
    ext = np.maximum(np.abs(xmax), np.abs(xmin))
    zs = max(float(ext[:nd].max()), 1e-9 * eom.cable.chord_length)
    vs = max(float(ext[nd:].max()), zs * float(eom.frequencies[0]))
    return np.concatenate([np.full(nd, zs), np.full(nd, vs)])


class _Shooter:
    """The ``decide`` hook of :func:`~cablesim.dynamics.steady.steady_response` (module
    docstring): proposes the stable orbit nearest the trajectory, then accepts it once the
    trajectory has contracted towards it at the predicted rate."""

    def __init__(self, eom, integrator, channels, criterion):
        self.eom, self.integrator, self.channels, self.criterion = eom, integrator, channels, criterion
        self.system = cable_system(eom, gamma=1.0)
        self.unstable: list = []  # (u, scale) of orbits found unstable: no new attempt near them
        self.orbits: dict = {}  # p -> (q, solution, scale): stable orbits already found
        self.next_try = 0  # forcing periods; attempts back off after fruitless ones
        self.wait = DECIDE_EVERY

    def likely_periods(self, strobes: np.ndarray) -> list[int]:
        """Periods at which the trajectory nearly repeats already (lag differences of the last
        strobes below :data:`REPEATS` of their size), shortest first, at most two: shooting is
        tried only there, so that a response far from any orbit costs no Newton solves."""
        k = strobes.shape[0] - 1
        out = []
        for p in range(1, self.criterion.max_period + 1):
            if k < 2 * p or len(out) == 2:
                break
            size = max(float(np.abs(strobes[k - 2 * p :]).max()), 1e-300)
            rel = float(np.abs(strobes[k - p + 1 :] - strobes[k - 2 * p + 1 : k - p + 1]).max()) / size
            if rel < REPEATS and not any(p % q == 0 for q in out):
                out.append(p)
        return out

    def minimal_period(self, u: np.ndarray, p: int, scale: np.ndarray) -> int:
        """The least period of an orbit found as ``p``-periodic (a divisor of p)."""
        for d in range(1, p):
            if p % d == 0:
                ev = Shooting(self.system, d, 1, "omega").evaluate(u, self.eom.omega, jac=False)
                if ev.status == 0 and float(np.max(np.abs(ev.r) / scale)) < 1e-6:
                    return d
        return p

    def stable_orbit(self, x: np.ndarray, p: int):
        """``(q, solution, scale)``: the stable orbit of period ``q`` (``p`` or a divisor) that
        Newton reaches from ``x``, remembered for later attempts; None if there is none."""
        if p in self.orbits:
            return self.orbits[p]
        sol = solve_orbit(Shooting(self.system, p, 1, "omega"), x, self.eom.omega, tol=NEWTON_TOL, max_iter=MAX_NEWTON)
        if not sol.converged or sol.evaluation is None:
            return None
        ev = sol.evaluation
        scale = _orbit_scale(self.eom, ev.xmax, ev.xmin)
        if not np.all(np.abs(ev.multipliers) < 1.0):
            self.unstable.append((sol.u, scale))  # never a steady state
            return None
        q = self.minimal_period(sol.u, p, scale)
        if q != p:  # the same orbit, its multipliers over its own period
            sol = solve_orbit(Shooting(self.system, q, 1, "omega"), sol.u, self.eom.omega, tol=NEWTON_TOL,
                              max_iter=MAX_NEWTON)
            if not sol.converged or sol.evaluation is None:
                return None
        self.orbits[p] = (q, sol, scale)
        return self.orbits[p]

    def nearest_stable_orbit(self, x: np.ndarray, periods: list[int]):
        """``(p, solution, scale)`` of a stable orbit within :data:`NEAR` of ``x``, or None."""
        for p in periods:
            found = self.stable_orbit(x, p)
            if found is not None and _distance(x, found[1].u, found[2]) < NEAR:
                return found
        return None

    def near_unstable(self, x: np.ndarray) -> bool:
        return any(_distance(x, u, scale) < NEAR for u, scale in self.unstable)

    def contracted(self, k: int, s: np.ndarray, p: int, sol, scale, d0: float) -> bool:
        """Whether, integrated ``q`` more forcing periods (a multiple of ``p``), the trajectory's
        distance to the orbit shrinks at least as the leading multiplier predicts (or both
        distances are at the integration's accuracy: the trajectory is on the orbit)."""
        q = p * max(1, int(np.ceil(CONTRACTION_PERIODS / p)))
        T = 2.0 * np.pi / self.eom.omega
        state = self.integrator.start(self.eom, s.copy(), k * T)
        out = np.empty((1, s.size))
        n, code = self.integrator.advance(self.eom.params(), state, (k + q) * T, np.array([(k + q) * T]), out)
        if code != 0 or n != 1:
            return False
        dq = _distance(out[0, : 2 * self.eom.n_dof], sol.u, scale)
        rho = float(np.abs(sol.evaluation.multipliers[0]))
        return dq <= CONTRACTION_SLACK * rho ** (q / p) * d0 or max(d0, dq) <= AT_ORBIT

    def __call__(self, k: int, s: np.ndarray, strobes: np.ndarray) -> PointResult | None:
        x = s[: 2 * self.eom.n_dof]
        if k < self.next_try or self.near_unstable(x):
            return None
        periods = self.likely_periods(strobes)
        found = self.nearest_stable_orbit(x, periods) if periods else None
        if found is not None:
            p, sol, scale = found
            if self.contracted(k, s, p, sol, scale, _distance(x, sol.u, scale)):
                T = 2.0 * np.pi / self.eom.omega
                rho = float(np.abs(sol.evaluation.multipliers[0]))
                return periodic_response(self.eom, self.integrator, _third_order(self.eom, sol.u), k * T,
                                         self.channels, p, self.criterion, floquet=rho, decided="shooting",
                                         multipliers=sol.evaluation.multipliers)
        # nothing accepted yet: wait longer before the next attempt
        self.next_try = k + self.wait
        self.wait = min(2 * self.wait, 8 * DECIDE_EVERY)
        return None


def accelerated_steady_response(
    eom: EquationsOfMotion,
    integrator: Integrator,
    channels: np.ndarray,
    criterion: SteadyCriterion,
    s0: np.ndarray | None = None,
) -> PointResult:
    """The steady response at one forcing frequency, by integration and shooting (module
    docstring); the same contract as :func:`cablesim.dynamics.steady.steady_response`.

    Integration alone for the approximate analysis (its shooting state does not give ``y''`` at
    forcing phase 0 without an inner solve) and for cables of more than 40 degrees of freedom
    (a dense monodromy per attempt would cost more than it saves).
    """
    if not eom.exact or eom.n_dof > 40:
        return steady_response(eom, integrator, channels, criterion, s0=s0)
    transient = integrator
    if isinstance(integrator, DOPRI5) and integrator.rtol < TRANSIENT_RTOL:
        # the transient only has to bring the response near its orbit; the orbit, once accepted,
        # is measured with the sweep's own integrator
        transient = DOPRI5(rtol=TRANSIENT_RTOL, atol=integrator.atol, dt_max=integrator.dt_max)
    return steady_response(eom, transient, channels, criterion, s0=s0,
                           decide=_Shooter(eom, integrator, channels, criterion))
