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
Orbits with slack intervals are shot through them (dense shooting with the saltation matrices of
the events, :mod:`~cablesim.orbits.slackflow`), under the same acceptance rule; the point's snap
loads are then its orbit's, as an integrated steady point's are. The matrix-free shooting of heavy
cables (below) stops at a slack segment; once one has, the point's orbits are shot through slack
under the same rules: densely up to :data:`DENSE_DOF` degrees of freedom (on a 20-node heavy span,
80 states, a Newton solve with its multipliers costs 1.4 s of CPU so, against 15.8 s by
differences), above it by :class:`~cablesim.orbits.slackdifference.SlackDifferenceShooting` (the
same flow through slack, its monodromy's action by extrapolated central differences: four orbit
integrations per direction, so an attempt costs some hundreds of orbit integrations).

Cost: an orbit found once is remembered (stable or not), so later checks against it need no
integration at all; Newton stops at the first step that does not halve the residual (the
trajectory is then too far from the orbit for the acceptance test anyway), and fruitless
attempts back off geometrically.

**Heavy cables: matrix-free shooting.** Above the crossover the continuation measured
(:func:`~cablesim.orbits.mfproblem.uses_matrix_free`: more than
:data:`~cablesim.orbits.mfproblem.MATRIX_FREE_DOF` states) the monodromy is never formed
(:class:`~cablesim.orbits.matrixfree.MatrixFreeShooting`, the scheme chosen by cost: Radau IIA
for stiff heavy cables, else rk8 at :data:`STEP_RATE`):

- Newton's steps are solved by GMRES on the action of ``M - I``, preconditioned by the deflation
  of the leading invariant subspace at the first iterate (:func:`newton_mf`; same full steps,
  abandonment rule and tolerance as the dense :func:`newton`);
- the leading multipliers (modulus above :data:`LEADING_BOUND`) come from subspace iteration on
  ``M v`` (:func:`~cablesim.orbits.matrixfree.orbit_leading`), with the largest discarded
  modulus; ``rho`` is the largest of them, and "every multiplier inside the unit circle" means
  every leading one with its Ritz residual inside, and the bound on the discarded ones below 1
  (a search stopped at its cap on products establishes no bound: not accepted);
- the linearisation test takes ``M e_j`` as one directional derivative along the orbit per test
  vector (the oldest first, so that a failing test costs one), remembered for the next checks.

Cables at or below the crossover (the paper's examples among them) are shot densely, exactly as
before; those between it and :data:`DENSE_DOF` degrees of freedom, shot densely before, are now
shot matrix-free; a cable asked to be shot densely (``matrix_free=False``) above
:data:`DENSE_DOF` is integrated alone, as every cable above it was.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import DOPRI5, Integrator
from ..dynamics.steady import DECIDE_EVERY, PointResult, SteadyCriterion, periodic_response, steady_response
from .floquet import DEFAULT_BOUND, Deflation
from .kernels import OK, SLACK
from .krylov import gmres
from .matrixfree import MatrixFreeShooting, MFEvaluation, orbit_leading
from .mfproblem import uses_matrix_free
from .shooting import Evaluation, Shooting
from .slackdifference import SlackDifferenceShooting
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
#: Most degrees of freedom of the dense shooting: above, a cable whose orbits are not shot
#: matrix-free is integrated alone (a dense monodromy per attempt would cost more than it saves).
DENSE_DOF = 40
#: Matrix-free path: multipliers of modulus above this bound are computed, the rest are stated
#: to be below it (:class:`~cablesim.orbits.floquet.Leading`); the deflation by their subspace
#: preconditions Newton's GMRES.
LEADING_BOUND = DEFAULT_BOUND
#: Residual of the kept Ritz pairs at the orbit (scaled coordinates), and at the first Newton
#: iterate, where they only precondition.
LEADING_TOL = 1e-9
PRECONDITION_TOL = 1e-6
#: GMRES relative tolerance of a matrix-free Newton step (the steps then converge linearly at
#: this rate, well inside :data:`NEWTON_SHRINK`) and its most iterations.
KRYLOV_TOL = 1e-6
MAX_KRYLOV = 200


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
    shooting : MatrixFreeShooting or None
        The matrix-free shooting of the orbit (its monodromy is then used through its action
        only, ``evaluation`` an :class:`~cablesim.orbits.matrixfree.MFEvaluation` with the
        leading multipliers); None for the dense shooting.
    """

    period: int
    u: np.ndarray
    evaluation: Evaluation
    scale: np.ndarray
    phase: int
    noise: float = 0.0
    shooting: MatrixFreeShooting | None = None
    actions: dict = field(default_factory=dict, repr=False)

    @property
    def rho(self) -> float:
        """Largest multiplier modulus (matrix-free: of the leading ones, or the largest
        discarded modulus when none is above the bound)."""
        if self.shooting is None:
            return float(np.abs(self.evaluation.multipliers[0]))
        lead = self.evaluation.leading
        return max(float(np.abs(lead.multipliers).max(initial=0.0)), float(lead.discarded))

    @property
    def stable(self) -> bool:
        """Every multiplier inside the unit circle. Matrix-free: every leading one, with its
        Ritz residual, and the bound on the discarded ones below 1 (it is below
        :data:`LEADING_BOUND` only when the search converged, i.e. stopped before its cap on
        products)."""
        if self.shooting is None:
            return bool(np.all(np.abs(self.evaluation.multipliers) < 1.0))
        lead = self.evaluation.leading
        converged = lead.complete or lead.products < max(200, 20 * self.u.size)
        inside = bool(np.all(np.abs(lead.multipliers) + lead.residuals < 1.0))
        return bool(converged and inside and lead.discarded < lead.bound < 1.0)

    def scaled_action(self, e: np.ndarray) -> np.ndarray | None:
        """``M e`` in the scaled coordinates ``x / scale``, by one directional derivative along
        the orbit (matrix-free orbits; remembered, as the same strobes are tested again at the
        next checks); None if the variational equations cannot be integrated."""
        key = e.tobytes()
        if key not in self.actions:
            try:
                Me = self.shooting.monodromy_apply(self.evaluation, (e * self.scale)[:, None])[:, 0] / self.scale
            except FloatingPointError:
                Me = None
            if len(self.actions) >= 4 * LINEAR_PERIODS:
                self.actions.pop(next(iter(self.actions)))
            self.actions[key] = Me
        return self.actions[key]


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
    if orbit.shooting is not None:
        return _linear_matrix_free(states[j - LINEAR_PERIODS * p : j + 1 : p], orbit)
    M = orbit.evaluation.monodromy
    Ms = (M / orbit.scale[:, None]) * orbit.scale[None, :]  # M in scaled coordinates
    margin = NONLINEAR * abs(1.0 - orbit.rho)  # |.|: an unstable orbit is tested alike, never accepted
    e = (states[j - LINEAR_PERIODS * p : j + 1 : p] - orbit.u) / orbit.scale
    for i in range(LINEAR_PERIODS):
        unexplained = float(np.abs(e[i + 1] - Ms @ e[i]).max())
        if unexplained > margin * float(np.abs(e[i]).max()) + orbit.noise:
            return False
    return True


def _linear_matrix_free(passages: np.ndarray, orbit: Orbit) -> bool:
    """:func:`in_linear_neighbourhood` on the last :data:`LINEAR_PERIODS` + 1 passages near a
    matrix-free orbit: ``M e_j`` by one directional derivative per test vector, the oldest first
    (the likeliest to fail: the others are then not needed)."""
    margin = NONLINEAR * abs(1.0 - orbit.rho)
    e = (passages - orbit.u) / orbit.scale
    for i in range(LINEAR_PERIODS):
        Me = orbit.scaled_action(e[i])
        if Me is None:
            return False
        if float(np.abs(e[i + 1] - Me).max()) > margin * float(np.abs(e[i]).max()) + orbit.noise:
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


def newton_mf(eom: EquationsOfMotion, shooting: MatrixFreeShooting, x: np.ndarray,
              start: np.ndarray | None = None) -> MFEvaluation | None:
    """:func:`newton` by the matrix-free shooting: each step by GMRES on the action of
    ``J_u = M - I``, preconditioned by the deflation of the leading invariant subspace at the
    first iterate (from ``start``, a basis of a nearby orbit's, if given); the same full steps,
    abandonment rule and tolerance. The converged evaluation carries its leading multipliers
    (:data:`LEADING_BOUND`, :data:`LEADING_TOL`), or None."""
    omega = eom.omega
    jac = shooting.scheme == "radau"  # the directions of a Radau orbit replay its tape
    ev = shooting.evaluate(x, omega, jac=jac)
    if ev.status != OK:
        return None
    scale = _orbit_scale(eom, ev.xmax, ev.xmin)
    bound = NEWTON_TOL * scale + np.broadcast_to(np.asarray(shooting.system.noise, dtype=float), x.shape)
    res = float(np.abs(ev.r / scale).max())
    try:
        lead = orbit_leading(shooting, ev, scale, bound=LEADING_BOUND, tol=PRECONDITION_TOL, start=start)
        pre = Deflation(lead.basis, lead.schur)
        for _ in range(MAX_NEWTON):
            def apply(v, ev=ev):
                return shooting.jacobian_apply(ev, (v * scale)[:, None])[:, 0] / scale

            du = gmres(apply, -ev.r / scale, tol=KRYLOV_TOL, max_iter=MAX_KRYLOV, precondition=pre).x * scale
            if not np.all(np.isfinite(du)):
                return None
            if np.all(np.abs(du) <= bound) and np.all(np.abs(ev.r) <= bound):
                ev.leading = None  # computed to precondition only: again, to full accuracy
                orbit_leading(shooting, ev, scale, bound=LEADING_BOUND, tol=LEADING_TOL, start=lead.basis)
                return ev
            trial = shooting.evaluate(ev.u + du, omega, jac=jac)
            if trial.status != OK:
                return None
            tres = float(np.abs(trial.r / scale).max())
            if tres > NEWTON_SHRINK * res and not np.all(np.abs(trial.r) <= bound):
                return None
            ev, res = trial, tres
    except (FloatingPointError, np.linalg.LinAlgError):  # the variational equations or the deflation failed
        return None
    return None


class _Shooter:
    """The ``decide`` hook of :func:`~cablesim.dynamics.steady.steady_response` (module
    docstring): finds the orbits the trajectory may be approaching, and accepts a stable one once
    its linearisation describes the trajectory."""

    def __init__(self, eom, integrator, transient, channels, criterion, every: int, system=None,
                 matrix_free: bool = False, scheme: str = "auto"):
        self.eom, self.integrator, self.channels, self.criterion = eom, integrator, channels, criterion
        self.transient = transient
        self.system = cable_system(eom, gamma=1.0) if system is None else system
        self.matrix_free, self.scheme = matrix_free, scheme
        self.mf: dict[int, MatrixFreeShooting | SlackDifferenceShooting] = {}
        #: Matrix-free orbits are shot through slack (:mod:`~cablesim.orbits.slackdifference`)
        #: once a matrix-free flow from the trajectory has met a slack segment.
        self.through_slack = False
        self.basis = None  # the latest matrix-free orbit's leading subspace (warm start)
        self.orbits: list[Orbit] = []  # stable and unstable orbits found so far
        self.next_try = 0  # forcing periods; Newton attempts back off after fruitless ones
        self.wait = every
        # the longest wait: about one slowest decay time (the trajectory has changed by then),
        # or a quarter of the periods done (fruitless attempts then cost a bounded fraction of
        # the integration, and a late acceptance comes at most 25 % late)
        self.max_wait = CHECKS_PER_DECAY * every

    def shooting(self, p: int) -> Shooting | MatrixFreeShooting | SlackDifferenceShooting:
        """Single shooting over ``p`` forcing periods, dense or matrix-free; once a matrix-free
        flow from the trajectory has met a slack segment, through slack: densely up to
        :data:`DENSE_DOF` degrees of freedom, else by differences
        (:class:`~cablesim.orbits.slackdifference.SlackDifferenceShooting`). An explicit scheme
        with the step of :data:`STEP_RATE`."""
        if not self.matrix_free or (self.through_slack and self.eom.n_dof <= DENSE_DOF):
            return Shooting(self.system, p, 1, "omega", step_rate=STEP_RATE, through_slack=True)
        if self.through_slack and not isinstance(self.mf.get(p), SlackDifferenceShooting):
            self.mf[p] = SlackDifferenceShooting(self.system, p, 1, "omega", step_rate=STEP_RATE)
        if p not in self.mf:
            sh = MatrixFreeShooting(self.system, p, 1, "omega", scheme=self.scheme)
            if sh.scheme != "radau":
                sh = MatrixFreeShooting(self.system, p, 1, "omega", scheme=sh.scheme, step_rate=STEP_RATE)
            self.mf[p] = sh
        return self.mf[p]

    def newton(self, p: int, x: np.ndarray) -> Evaluation | None:
        """The orbit of period ``p`` near ``x`` (:func:`newton` or :func:`newton_mf`). A
        matrix-free Newton stopped by a slack segment is taken again through slack, and so are
        the later ones (the system must be able to follow slack: ``system.slack``)."""
        sh = self.shooting(p)
        if isinstance(sh, Shooting):
            return newton(self.eom, sh, x)
        ev = newton_mf(self.eom, sh, x, start=self.basis)
        if (ev is None and not self.through_slack and self.system.slack is not None
                and sh.last_status == SLACK):
            self.through_slack = True
            return self.newton(p, x)
        if ev is not None:
            self.basis = ev.leading.basis
        return ev

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
        ev = self.newton(p, x)
        if ev is None:
            return False
        scale = _orbit_scale(self.eom, ev.xmax, ev.xmin)
        if any(o.period <= p and _distance(ev.u, o.u, o.scale) < 1e-4 for o in self.orbits):
            return False  # one already known (Newton at lag p found a divisor's orbit again)
        q = self.minimal_period(ev.u, p, scale)
        if q != p:  # the same orbit, its monodromy over its own period
            ev = self.newton(q, ev.u)
            if ev is None:
                return False
        self.orbits.append(Orbit(q, ev.u.copy(), ev, scale, k % q,
                                 strobe_noise(self.eom, self.transient, ev.u, q, scale),
                                 None if ev.monodromy is not None else self.shooting(q)))
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
    matrix_free: bool | None = None,
    scheme: str = "auto",
) -> PointResult:
    """The steady response at one forcing frequency, by integration and shooting (module
    docstring); the same contract as :func:`cablesim.dynamics.steady.steady_response`.

    Parameters
    ----------
    eom, integrator, channels, criterion, s0
        As for :func:`~cablesim.dynamics.steady.steady_response`.
    matrix_free : bool, optional
        Shoot matrix-free (True) or with the dense monodromy (False); by default as the
        continuation does, above :data:`~cablesim.orbits.mfproblem.MATRIX_FREE_DOF` states
        (:func:`~cablesim.orbits.mfproblem.uses_matrix_free`).
    scheme : str
        The matrix-free shooting's scheme (:class:`~cablesim.orbits.matrixfree.MatrixFreeShooting`:
        ``"auto"``, ``"rk8"``, ``"rk4"``, ``"radau"``).

    Integration alone for the approximate analysis (its shooting state does not give ``y''`` at
    forcing phase 0 without an inner solve) and for cables of more than :data:`DENSE_DOF`
    degrees of freedom shot densely (a dense monodromy per attempt would cost more than it
    saves).
    """
    if not eom.exact:
        return steady_response(eom, integrator, channels, criterion, s0=s0)
    system = cable_system(eom, gamma=1.0)
    mf = uses_matrix_free(system, matrix_free)
    if not mf and eom.n_dof > DENSE_DOF:
        return steady_response(eom, integrator, channels, criterion, s0=s0)
    # the transient only has to bring the response near its orbit; the orbit, once accepted, is
    # measured with the sweep's own integrator. An adaptive scheme's absolute tolerance stays:
    # loosened alike it would save a third of the transient's cost, but the integration-alone
    # rules, which decide whatever shooting does not, then miss small periodic responses (1 rad/s
    # on the paper example: never steady within the cap at atol 1e-8 chord, steady at 886 s at the
    # default 1e-10 chord; see TRANSIENT_RTOL)
    transient = integrator.for_transient(TRANSIENT_RTOL)
    every = check_interval(eom)
    shooter = _Shooter(eom, integrator, transient, channels, criterion, every, system=system, matrix_free=mf,
                       scheme=scheme)
    return steady_response(eom, transient, channels, criterion, s0=s0, decide=shooter, decide_every=every)
