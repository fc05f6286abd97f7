"""Steady states by shooting from the transient: a sweep point decided without waiting for it.

A sweep point integrated from rest (or from the previous point of a chain) spends most of its
time waiting for lightly damped transients to die out (damping ratio 0.01: a factor e every
``1 / (xi w1)``, about 40 s for the paper example). Here the response is integrated in short
chunks (:func:`check_interval`); after each, the periodic orbit the trajectory is approaching
is sought by shooting (Newton on ``(z, y')`` from the trajectory's state at forcing phase 0,
for periods ``p = 1 .. max_period``) and **accepted only when**

1. Newton converges and every Floquet multiplier is inside the unit circle (an unstable orbit,
   however long the response lingers near it, is never accepted: the paper's late jumps are still
   found), and
2. the trajectory has entered the orbit's neighbourhood, in the sense that the orbit's
   linearisation describes it: writing ``e_j`` for the stroboscopic samples' deviation from the
   orbit (scaled by the orbit's extent) and ``M`` for its monodromy matrix, the last
   :data:`LINEAR_PERIODS` steps of ``p`` forcing periods each obey

   ``|e_{j+p} - M e_j| <= NONLINEAR (1 - rho) |e_j| + noise``

   (max norms; ``rho`` the largest multiplier modulus; ``noise`` what the integration of the
   strobes leaves unexplained even on the orbit, :data:`NOISE_FACTOR` times the difference
   between the sweep integrator's flow map and the shooting scheme's at the orbit, measured once
   per orbit by integrating it over one period). The left side is what the
   linearisation leaves unexplained, quadratic in ``|e|``; bounding it by a fraction of the
   contraction margin ``1 - rho`` per orbit period means the deviation keeps shrinking every
   orbit period, at no less than half the rate the linearisation predicts, so the trajectory
   converges to this orbit rather than passing by on its way to another attractor. The test adapts itself: far from resonance the response
   is linear from the start and is accepted at the first attempt; next to a fold or a period
   doubling (``rho`` near 1) it waits until the deviation is small. A deviation that grows for a
   while (two slow modes beating) passes when ``M`` predicts the growth.

The integration itself is that of :func:`cablesim.dynamics.steady.steady_response` (same
periodicity and Floquet rules, same cap); the shooting is a hook it calls every few forcing
periods, so a point that would be found steady, not steady or failed without acceleration is
found so with it, only sooner when an orbit is accepted; the exception is a point integration
alone leaves at the cap because its transient decays too slowly for the periodicity test (a
multiplier near -1 next to a period doubling), which shooting may decide. The amplitudes of an accepted orbit are
measured exactly as for an integrated one (:func:`~cablesim.dynamics.steady.periodic_response`).

Cost: an orbit found once is remembered (stable or not), so later checks against it need no
integration at all; Newton stops at the first step that does not halve the residual (the
trajectory is then too far from the orbit for the acceptance test anyway), and fruitless
attempts back off geometrically.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import DOPRI5, Integrator
from ..dynamics.steady import DECIDE_EVERY, PointResult, SteadyCriterion, periodic_response, steady_response
from .kernels import OK
from .shooting import Evaluation, Shooting
from .systems import cable_system

#: Shooting is tried at a period p once the last strobes repeat at lag p to this fraction (a
#: cost rule only: Newton from farther away rarely converges, and acceptance does not depend
#: on it).
REPEATS = 0.5
#: Newton iterations per shooting attempt (an orbit within reach converges in a few).
MAX_NEWTON = 8
#: A Newton step must reduce the scaled residual by this factor, else the attempt is abandoned:
#: inside the region where the orbit's linearisation holds (what acceptance needs) Newton
#: converges quadratically, so a step that does not halve the residual means the trajectory is
#: not there yet, and damping the step would only buy an orbit that cannot be accepted.
NEWTON_SHRINK = 0.5
#: Relative tolerance of an adaptive integrator while the transient is integrated (atol
#: unchanged): the strobes only have to show the approach to the orbit, and their error enters
#: the acceptance test through its measured noise term. On the paper example a simulated second
#: costs 0.16-0.18 ms against 0.26-0.29 at the default 1e-8 (``bench_accelerate.py
#: --integration``); loosening atol alike would bring it to 0.11-0.12 ms, but see
#: :func:`accelerated_steady_response` for why it is not.
TRANSIENT_RTOL = 1e-6
#: Newton's tolerance (relative to the orbit's extent): the orbit only seeds the measurement,
#: which integrates it with the sweep's own integrator.
NEWTON_TOL = 1e-7
#: Fixed rk8 step of the shooting, ``h * fastest_rate`` (the continuation's default 1.25 aims
#: at orbit errors of 1e-10): measured against 4x finer steps, 2.5 leaves orbit errors of 1e-9
#: to 2e-9 of the orbit's extent and multiplier errors below 1e-9 (paper example at 0.5 and
#: 2 rad/s, low-sag cable of Fig. 7a at 1.5 and 3 rad/s), two orders below
#: :data:`NEWTON_TOL`, at half the steps where the fastest mode sets them.
STEP_RATE = 2.5
#: Consecutive orbit periods the linearisation must describe the trajectory over (three, so
#: that one period that happens to fit, e.g. while two slow modes cancel, is not enough).
LINEAR_PERIODS = 3
#: Largest unexplained part of an orbit period's step, as a fraction of the contraction margin
#: ``(1 - rho) |e|``. One half: where ``M`` shrinks a deviation by ``rho``, the step then
#: shrinks it by at least ``rho + (1 - rho) / 2 = (1 + rho) / 2``, i.e. at no less than half the
#: predicted rate, every period.
NONLINEAR = 0.5
#: The linearisation's prediction is only as good as the strobes: their integration leaves a
#: residual of about the integrator's local error per period even on the orbit. That is
#: measured once per orbit as ``delta``, the difference between the integrator's and the
#: shooting scheme's flow maps over one period from the orbit; along a trajectory the residual
#: was measured at 2-3 ``delta`` (5.05 rad/s, DOPRI5 at rtol 1e-6: delta 6e-6 of the orbit's
#: extent, residuals 1-2e-5), hence this factor.
NOISE_FACTOR = 4.0
#: Checks per slowest free decay time ``1 / sigma``: the deviation shrinks by at most
#: ``exp(-1/8)`` (12 %) between two checks, so acceptance comes at most that late.
CHECKS_PER_DECAY = 8
#: Scaled distance within which a state is "at" a known orbit, stable or not: no new Newton
#: attempt from it (it would find the same orbit again). A cost rule only, like
#: :data:`REPEATS`: acceptance does not depend on it.
NEAR = 0.2


@dataclass
class Orbit:
    """A periodic orbit found by shooting from the trajectory.

    Attributes
    ----------
    period : int
        Least period, forcing periods.
    u : ndarray
        ``(z, y')`` at forcing phase 0.
    evaluation : Evaluation
        At ``u``, with the monodromy matrix and the multipliers.
    scale : ndarray
        Per-component scale (the orbit's extent).
    phase : int
        Strobe index modulo ``period`` of the trajectory's passages near ``u``.
    noise : float
        Scaled prediction residual the strobes' integration leaves even on the orbit
        (:data:`NOISE_FACTOR`).
    """

    period: int
    u: np.ndarray
    evaluation: Evaluation
    scale: np.ndarray
    phase: int
    noise: float = 0.0

    @property
    def rho(self) -> float:
        """Largest multiplier modulus."""
        return float(np.abs(self.evaluation.multipliers[0]))

    @property
    def stable(self) -> bool:
        return bool(np.all(np.abs(self.evaluation.multipliers) < 1.0))


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


def slowest_decay_rate(eom: EquationsOfMotion) -> float:
    """``sigma``: the smallest ``-Re(lambda)`` of the damped linear system ``M z'' + C z' +
    K0 z = 0`` (1/s), the rate at which its slowest free transient dies out."""
    nd = eom.n_dof
    A = np.zeros((2 * nd, 2 * nd))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -eom.K0 / eom.mass[:, None]
    A[nd:, nd:] = -eom.C / eom.mass[:, None]
    return float(np.min(-np.linalg.eigvals(A).real))


def check_interval(eom: EquationsOfMotion) -> int:
    """Forcing periods between two acceptance checks: :data:`CHECKS_PER_DECAY` per slowest
    decay time, at least one period and at most :data:`~cablesim.dynamics.steady.DECIDE_EVERY`."""
    T = 2.0 * np.pi / eom.omega
    sigma = slowest_decay_rate(eom)
    if not sigma > 0.0:
        return DECIDE_EVERY
    return int(np.clip(round(1.0 / (CHECKS_PER_DECAY * sigma * T)), 1, DECIDE_EVERY))


def strobe_noise(eom: EquationsOfMotion, integrator: Integrator, u: np.ndarray, p: int, scale: np.ndarray) -> float:
    """:data:`NOISE_FACTOR` times the scaled difference between ``integrator``'s flow map over
    ``p`` forcing periods from ``u`` (``(z, y')`` at forcing phase 0) and ``u`` itself, for an
    orbit ``u`` of the shooting scheme (inf if the integration fails)."""
    Tp = p * 2.0 * np.pi / eom.omega
    state = integrator.start(eom, _third_order(eom, u))
    out = np.empty((1, 3 * eom.n_dof))
    n, code = integrator.advance(eom.model(), state, Tp, np.array([Tp]), out)
    if code != OK or n != 1:
        return np.inf
    return NOISE_FACTOR * _distance(out[0, : u.size], u, scale)


def in_linear_neighbourhood(states: np.ndarray, k: int, orbit: Orbit) -> bool:
    """Whether the trajectory's states at forcing phase 0 (``states[j]``, ``(z, y')``, j up to
    ``k``) follow the orbit's linearisation over the last :data:`LINEAR_PERIODS` orbit periods
    (module docstring, criterion 2)."""
    p = orbit.period
    j = k - ((k - orbit.phase) % p)  # last passage near orbit.u
    if j - LINEAR_PERIODS * p < 0:
        return False
    M = orbit.evaluation.monodromy
    Ms = (M / orbit.scale[:, None]) * orbit.scale[None, :]  # M in scaled coordinates
    margin = NONLINEAR * abs(1.0 - orbit.rho)  # |.|: an unstable orbit is tested alike, never accepted
    e = (states[j - LINEAR_PERIODS * p : j + 1 : p] - orbit.u) / orbit.scale
    for i in range(LINEAR_PERIODS):
        unexplained = float(np.abs(e[i + 1] - Ms @ e[i]).max())
        if unexplained > margin * float(np.abs(e[i]).max()) + orbit.noise:
            return False
    return True


def newton(eom: EquationsOfMotion, shooting: Shooting, x: np.ndarray) -> Evaluation | None:
    """The periodic orbit near ``x`` by Newton's method with full steps, abandoned at the first
    step that does not shrink the residual by :data:`NEWTON_SHRINK` (see there); the converged
    evaluation (with monodromy and multipliers) or None. Tolerance :data:`NEWTON_TOL` of the
    extent of the trajectory's first period, or the flow map's round-off level."""
    omega = eom.omega
    ev = shooting.evaluate(x, omega)
    if ev.status != OK:
        return None
    scale = _orbit_scale(eom, ev.xmax, ev.xmin)
    bound = NEWTON_TOL * scale + np.broadcast_to(np.asarray(shooting.system.noise, dtype=float), x.shape)
    res = float(np.abs(ev.r / scale).max())
    for _ in range(MAX_NEWTON):
        try:
            du = np.linalg.solve(ev.J_u, -ev.r)
        except np.linalg.LinAlgError:
            return None
        if np.all(np.abs(du) <= bound) and np.all(np.abs(ev.r) <= bound):
            return ev
        trial = shooting.evaluate(ev.u + du, omega)
        if trial.status != OK:
            return None
        tres = float(np.abs(trial.r / scale).max())
        if tres > NEWTON_SHRINK * res and not np.all(np.abs(trial.r) <= bound):
            return None
        ev, res = trial, tres
    return None


class _Shooter:
    """The ``decide`` hook of :func:`~cablesim.dynamics.steady.steady_response` (module
    docstring): finds the orbits the trajectory may be approaching, and accepts a stable one once
    its linearisation describes the trajectory."""

    def __init__(self, eom, integrator, transient, channels, criterion, every: int):
        self.eom, self.integrator, self.channels, self.criterion = eom, integrator, channels, criterion
        self.transient = transient
        self.system = cable_system(eom, gamma=1.0)
        self.orbits: list[Orbit] = []  # stable and unstable orbits found so far
        self.next_try = 0  # forcing periods; Newton attempts back off after fruitless ones
        self.wait = every
        # the longest wait: about one slowest decay time (the trajectory has changed by then),
        # or a quarter of the periods done (fruitless attempts then cost a bounded fraction of
        # the integration, and a late acceptance comes at most 25 % late)
        self.max_wait = CHECKS_PER_DECAY * every

    def shooting(self, p: int) -> Shooting:
        """Single shooting over ``p`` forcing periods with the step of :data:`STEP_RATE`."""
        return Shooting(self.system, p, 1, "omega", step_rate=STEP_RATE)

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
                ev = self.shooting(d).evaluate(u, self.eom.omega, jac=False)
                if ev.status == 0 and float(np.max(np.abs(ev.r) / scale)) < 1e-6:
                    return d
        return p

    def shoot(self, k: int, x: np.ndarray, p: int) -> bool:
        """Seek a ``p``-periodic orbit from ``x`` (strobe ``k``); remember it if new. Whether a
        new orbit was found."""
        ev = newton(self.eom, self.shooting(p), x)
        if ev is None:
            return False
        scale = _orbit_scale(self.eom, ev.xmax, ev.xmin)
        if any(o.period <= p and _distance(ev.u, o.u, o.scale) < 1e-4 for o in self.orbits):
            return False  # one already known (Newton at lag p found a divisor's orbit again)
        q = self.minimal_period(ev.u, p, scale)
        if q != p:  # the same orbit, its monodromy over its own period
            ev = newton(self.eom, self.shooting(q), ev.u)
            if ev is None:
                return False
        self.orbits.append(Orbit(q, ev.u.copy(), ev, scale, k % q,
                                 strobe_noise(self.eom, self.transient, ev.u, q, scale)))
        return True


    def near_known(self, x: np.ndarray) -> bool:
        return any(_distance(x, o.u, o.scale) < NEAR for o in self.orbits)

    def accepted(self, k: int, states: np.ndarray) -> Orbit | None:
        for o in self.orbits:
            if o.stable and in_linear_neighbourhood(states, k, o):
                return o
        return None

    def __call__(self, k: int, s: np.ndarray, strobes: np.ndarray) -> PointResult | None:
        nd = self.eom.n_dof
        states = strobes * np.concatenate([np.ones(nd), np.full(nd, self.eom.omega)])  # (z, y')
        x = states[k]
        found = self.accepted(k, states)
        if found is None and k >= self.next_try and not self.near_known(x):
            new = False
            for p in self.likely_periods(strobes):
                new = self.shoot(k, x, p) or new
            found = self.accepted(k, states) if new else None
            if not new:  # fruitless: wait longer before the next attempt
                self.next_try = k + self.wait
                self.wait = min(2 * self.wait, max(self.max_wait, k // 4))
        if found is None:
            return None
        T = 2.0 * np.pi / self.eom.omega
        return periodic_response(self.eom, self.integrator, _third_order(self.eom, found.u), k * T, self.channels,
                                 found.period, self.criterion, floquet=found.rho, decided="shooting",
                                 multipliers=found.evaluation.multipliers)


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
    # the transient only has to bring the response near its orbit; the orbit, once accepted, is
    # measured with the sweep's own integrator. An adaptive scheme's absolute tolerance stays:
    # loosened alike it would save a third of the transient's cost, but the integration-alone
    # rules, which decide whatever shooting does not, then miss small periodic responses (1 rad/s
    # on the paper example: never steady within the cap at atol 1e-8 chord, steady at 886 s at the
    # default 1e-10 chord; see TRANSIENT_RTOL)
    transient = integrator.for_transient(TRANSIENT_RTOL)
    every = check_interval(eom)
    return steady_response(eom, transient, channels, criterion, s0=s0,
                           decide=_Shooter(eom, integrator, transient, channels, criterion, every), decide_every=every)
