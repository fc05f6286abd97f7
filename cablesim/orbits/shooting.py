"""Shooting for periodic orbits of periodically forced systems, and their Floquet multipliers.

A periodic orbit of period ``T = p 2 pi / omega`` (``p`` forcing periods) is a fixed point of
the flow map over ``T``. With ``m`` shooting segments of ``T / m`` each, the unknowns are the
states ``s_0 .. s_{m-1}`` at the forcing phases ``2 pi p k / m`` and the residual is::

    r_k = Phi_k(s_k) - s_{k+1}        (k = 0 .. m-1, s_m = s_0)

``Phi_k`` is the flow over segment ``k``, computed by a fixed-step explicit Runge-Kutta scheme
(:mod:`cablesim.orbits.tableaux`) together with its variational equations, so the Jacobian
blocks ``G_k = dPhi_k/ds_k`` and the parameter derivatives ``dPhi_k/dlambda`` are exact
derivatives of the discrete map (:mod:`cablesim.orbits.kernels`). The monodromy matrix is
``G_{m-1} ... G_0``; its eigenvalues are the Floquet multipliers. Liouville's formula
``det(monodromy) = exp(int tr(df/dx) dt)`` is reported as a check of the integration
(:attr:`Evaluation.liouville`).

The step: ``steps_per_period`` per forcing period at least, and never more than
``step_rate / fastest_rate`` seconds (the scheme's accuracy on the system's fastest mode; the
stability limits are ``h |lambda| < 2.8`` for rk4, ``< 5.9`` for rk8). The step count is an
integer, so as ``omega`` varies the discrete map changes by jumps of the size of the
integration error (about 1e-10 with the defaults), which Newton's method and the continuation
do not notice.

Defaults (:data:`DEFAULT_STEPS`), measured on the paper's cable at 2.45 rad/s against a
4000-steps-per-period solution (orbit error / slow multipliers / Liouville mismatch):
rk8, 48 steps per period and ``h * rate <= 1.25`` (107 steps): 1.5e-10 / 3e-12 / 1.6e-5;
rk4, 256 and 0.15 (888 steps): 1.1e-9 / 4e-10 / 5e-5, for about three times the work. The Liouville mismatch is set by the
fastest (axial) mode, whose multiplier is far inside the unit circle.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from . import kernels as ok
from . import slackflow as sf
from .rotation import phase_direction, phased_step
from .stability import sort_multipliers
from .systems import OdeSystem
from .tableaux import TABLEAUX

#: Default fixed-step settings per scheme: (steps per forcing period, h * fastest_rate).
DEFAULT_STEPS = {"rk8": (48, 1.25), "rk4": (256, 0.15)}

_EMPTY_REC = np.zeros((0, 0))
_NO_EVENTS = np.zeros((0, 3))


class FlowStatus(IntEnum):
    """Outcome of one flow integration (the codes of :mod:`cablesim.orbits.kernels`)."""

    OK = ok.OK
    NONFINITE = ok.NONFINITE
    SLACK = ok.SLACK
    INNER_SOLVE = ok.INNER_SOLVE
    INTERRUPTED = ok.INTERRUPTED
    CHATTER = sf.CHATTER


class SolveStatus(IntEnum):
    """Outcome of :func:`solve_orbit`."""

    CONVERGED = 0
    MAX_ITERATIONS = 1
    INTEGRATION_FAILED = 2
    LINE_SEARCH_FAILED = 3
    SINGULAR = 4


@dataclass
class Evaluation:
    """The shooting residual and its derivatives at one ``(u, lambda)``.

    Attributes
    ----------
    u : ndarray (m n,)
        Stacked segment start states.
    lam : float
        Parameter value.
    omega : float
        Forcing frequency used, rad/s.
    period : int
        Orbit period in forcing periods.
    T : float
        Orbit period, s.
    r : ndarray (m n,)
        Residual ``Phi_k(s_k) - s_{k+1}``.
    J_u : ndarray (m n, m n)
        ``dr/du`` (None if not computed).
    J_lam : ndarray (m n,)
        ``dr/dlambda`` (None if not computed).
    ends : ndarray (m, n)
        ``Phi_k(s_k)``.
    G : ndarray (m, n, n)
        Segment Jacobians.
    monodromy : ndarray (n, n)
    multipliers : ndarray (n,) complex
        Sorted by decreasing modulus.
    logdet : float
        ``log |det(monodromy)|`` accumulated over well-conditioned chunks.
    divergence : float
        ``int_0^T tr(df/dx) dt`` along the discrete orbit.
    xmax, xmin : ndarray (n,)
        Extremes of every state component over the orbit.
    status : FlowStatus
        ``OK`` or why the flow could not be computed (a slack segment, a failed inner solve,
        a non-finite state).
    steps : list or None
        With ``record``: the orbit at the integrator's steps, as :meth:`Shooting.steps` gives
        it (the same flow, so the same numbers), for measures taken on the orbit without
        integrating it again; None otherwise (or once they have been used and released).
    blocks_mu, blocks_phi : tuple or None
        On a planar orbit of a mirror-symmetric system: the in-plane and the out-of-plane
        multipliers and blocks of the monodromy, once computed
        (:func:`cablesim.orbits.problems.block_multipliers`, :func:`~cablesim.orbits.problems.monodromy_blocks`).
    neutral : Neutral, False or None
        The multiplier forced to +1 by a rotation symmetry and the deflated multipliers the
        tests see (:mod:`cablesim.orbits.rotation`), once computed; False: none (no symmetry, or
        an orbit the rotation leaves in place).
    events : ndarray (k, 3)
        The segments' mode changes over the orbit, ``(t, segment, new mode)`` rows in time
        order, ``t`` in s from the orbit's start, mode 0 slack (an onset) and 1 taut (a
        re-tightening); empty for an orbit that stays taut (:mod:`cablesim.orbits.slackflow`).
    """

    u: np.ndarray
    lam: float
    omega: float
    period: int
    T: float
    r: np.ndarray
    J_u: np.ndarray | None
    J_lam: np.ndarray | None
    ends: np.ndarray
    G: np.ndarray | None
    monodromy: np.ndarray | None
    multipliers: np.ndarray | None
    logdet: float
    divergence: float
    xmax: np.ndarray
    xmin: np.ndarray
    status: FlowStatus = FlowStatus.OK
    steps: list | None = None
    blocks_mu: tuple | None = None
    blocks_phi: tuple | None = None
    neutral: object = None
    events: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def liouville(self) -> float:
        """``|log det(monodromy) - int tr(df/dx) dt|``: zero for exact integration (relative
        error of the determinant)."""
        return abs(self.logdet - self.divergence)

    @property
    def spectral_radius(self) -> float:
        return float(np.abs(self.multipliers[0])) if self.multipliers is not None else np.nan


class Shooting:
    """Flow maps over the ``m`` segments of a ``p``-periodic orbit of an :class:`OdeSystem`.

    Parameters
    ----------
    system : OdeSystem
    period : int
        ``p``: orbit period in forcing periods.
    segments : int
        ``m``: shooting segments (1: single shooting).
    parameter : str
        ``"omega"`` or a name in ``system.parameters``.
    scheme : str
        ``"rk8"`` (default) or ``"rk4"``.
    steps_per_period : int, optional
        Fixed steps per forcing period (minimum; the default depends on the scheme, see
        :data:`DEFAULT_STEPS`).
    step_rate : float, optional
        Upper bound of ``h * fastest_rate``.
    through_slack : bool
        Follow the flows through slack segments (:mod:`cablesim.orbits.slackflow`) where the
        system can (its ``slack`` functions: the exact analysis of a cable with its supports at
        rest and ``slack: continue``); otherwise (the default, and the continuation's: its
        branches end at the first orbit with a slack segment) a flow that meets one stops with
        ``SLACK``.
    """

    def __init__(
        self,
        system: OdeSystem,
        period: int = 1,
        segments: int = 1,
        parameter: str = "omega",
        scheme: str = "rk8",
        steps_per_period: int | None = None,
        step_rate: float | None = None,
        through_slack: bool = False,
    ):
        if period < 1 or segments < 1:
            raise ValueError("period and segments must be positive")
        if parameter != "omega" and parameter not in system.parameters:
            raise ValueError(f"unknown parameter {parameter!r}: 'omega' or one of {sorted(system.parameters)}")
        if scheme not in TABLEAUX:
            raise ValueError(f"unknown scheme {scheme!r}: one of {sorted(TABLEAUX)}")
        self.system = system
        self.period = int(period)
        self.segments = int(segments)
        self.parameter = parameter
        self.scheme = scheme
        self.tableau = TABLEAUX[scheme]
        spp, rate = DEFAULT_STEPS[scheme]
        self.steps_per_period = int(steps_per_period if steps_per_period is not None else spp)
        self.step_rate = float(step_rate if step_rate is not None else rate)
        self.n = system.dim
        self._A = np.ascontiguousarray(self.tableau.A)
        self._b = np.ascontiguousarray(self.tableau.b)
        self._c = np.ascontiguousarray(self.tableau.c)
        self._flow = ok.EntryPoint(ok.flow_segment)
        self._flow_modes = ok.EntryPoint(sf.flow_segment_modes)
        self.through_slack = bool(through_slack) and system.slack is not None
        #: Through slack: integrate with the segment modes from the start rather than retake a
        #: flow that met a slack segment (the same steps bit for bit while no event occurs; for
        #: flows known to go slack, such as the differences of an orbit through slack).
        self.modes_from_start = False
        self._whole = (np.arange(system.dim, dtype=np.int64), np.array([0, system.dim], dtype=np.int64))
        self._ipar = -1 if parameter == "omega" else int(system.parameters[parameter])
        self._pmode = ok.PARAM_OMEGA if parameter == "omega" else ok.PARAM_PRM
        #: Counters: flow-segment integrations and Runge-Kutta steps taken.
        self.calls = 0
        self.steps_taken = 0

    # ------------------------------------------------------------------------------------------
    def omega_of(self, lam: float) -> float:
        """Forcing frequency at parameter value ``lam``."""
        return float(lam) if self.parameter == "omega" else self.system.omega

    def default_lam(self) -> float:
        """The system's own value of the parameter."""
        if self.parameter == "omega":
            return self.system.omega
        return float(self.system.prm[self._ipar])

    def segment_steps(self, omega: float) -> int:
        """Fixed steps per segment at forcing frequency ``omega``."""
        tf = 2.0 * np.pi / omega
        per_period = max(self.steps_per_period, int(np.ceil(tf * self.system.fastest_rate / self.step_rate)))
        return max(1, int(np.ceil(per_period * self.period / self.segments)))

    def _prm(self, lam: float) -> np.ndarray:
        if self.parameter == "omega":
            return self.system.prm
        prm = self.system.prm.copy()
        prm[self._ipar] = lam
        return prm

    def segment(self, k: int, x0: np.ndarray, lam: float, jac: bool = True, record: bool = False,
                blocks: tuple | None = None):
        """Integrate segment ``k`` from ``x0``; ``blocks`` (``(rows, bounds)``, see
        :func:`~cablesim.orbits.kernels.flow_segment`) carries the variational equations on
        those diagonal blocks only, for a Jacobian known not to couple them.

        Returns
        -------
        dict with ``status``, ``x`` (end state), ``G``, ``dp`` (with ``jac``), ``info``,
        ``xmax``, ``xmin``, ``events`` (the segments' mode changes, ``(t, segment, new mode)``
        from the segment's start) and, with ``record``, ``t`` (times from the segment start)
        and ``rec`` (state and rate at every step).

        With ``through_slack``, a flow that meets a slack segment is taken again through slack
        (:mod:`cablesim.orbits.slackflow`); a flow that stays taut is the plain kernel's, so
        orbits without slack are unchanged bit for bit.
        """
        omega = self.omega_of(lam)
        if not omega > 0.0:
            return {"status": ok.NONFINITE}
        n = self.n
        T = self.period * 2.0 * np.pi / omega
        dur = T / self.segments
        theta0 = 2.0 * np.pi * self.period * k / self.segments
        ns = self.segment_steps(omega)
        xend = np.empty(n)
        G = np.empty((n, n))
        dp = np.zeros(n)
        xmax = np.empty(n)
        xmin = np.empty(n)
        info = np.zeros(4)
        rec = np.empty((ns + 1, 2 * n)) if record else _EMPTY_REC
        work = ok.copy_work(self.system.work)
        rows, bounds = blocks if blocks is not None else self._whole
        args = (self.system.model, self._prm(lam), work, flushed(x0), float(theta0), float(omega), float(dur), int(ns),
                self._A, self._b, self._c, self._ipar, self._pmode, bool(jac), rows, bounds, xend, G, dp, xmax, xmin,
                rec, info)
        if self.through_slack and self.modes_from_start:
            with_modes = True
        else:
            code = self._flow(self.system.field, *args)
            # a flow that met a slack segment is taken again, tracking the segments' modes
            with_modes = code == ok.SLACK and self.through_slack
        events = _NO_EVENTS
        if with_modes:
            gaps, modes = self.system.slack
            nseg = modes(work)[0].size
            ev, nev = np.zeros((sf.EVENTS_PER_SEGMENT * nseg, 3)), np.zeros(1, dtype=np.int64)
            work = ok.copy_work(self.system.work)
            code = self._flow_modes(self.system.field, gaps, modes, *args[:2], work, *args[3:], ev, nev)
            events = ev[: nev[0]]
        self.calls += 1
        self.steps_taken += ns
        out = {"status": int(code), "x": xend, "xmax": xmax, "xmin": xmin, "info": info, "steps": ns,
               "events": events}
        if jac:
            out["G"] = G
            out["dp"] = dp
        if record:
            out["t"] = np.arange(ns + 1) * (dur / ns)
            out["rec"] = rec
        return out

    def evaluate(self, u: np.ndarray, lam: float, jac: bool = True, blocks: tuple | None = None,
                 record: bool = False) -> Evaluation:
        """Residual (and derivatives) at ``(u, lam)``; ``status`` says whether it succeeded.
        ``blocks``: the variational equations on these diagonal blocks only (:meth:`segment`);
        ``record``: keep the orbit at every step (:attr:`Evaluation.steps`; the state's
        arithmetic does not depend on the variational equations, so these are the steps of
        :meth:`steps` bit for bit)."""
        n, m = self.n, self.segments
        u = np.asarray(u, dtype=float)
        S = np.array([flushed(s) for s in u.reshape(m, n)])  # the map and its residual of the same states
        omega = self.omega_of(lam)
        T = self.period * 2.0 * np.pi / omega if omega > 0 else np.nan
        ends = np.empty((m, n))
        G = np.empty((m, n, n)) if jac else None
        dp = np.empty((m, n)) if jac else None
        xmax = np.full(n, -np.inf)
        xmin = np.full(n, np.inf)
        logdet = 0.0
        sign = 1.0
        div = 0.0
        status = ok.OK
        steps = [] if record else None
        events = []
        for k in range(m):
            seg = self.segment(k, S[k], lam, jac=jac, blocks=blocks, record=record)
            if seg["status"] != ok.OK:
                status = seg["status"]
                break
            ends[k] = seg["x"]
            if record:
                steps.append((seg["t"], seg["rec"]))
            if seg["events"].size:
                events.append(seg["events"] + np.array([k * T / m, 0.0, 0.0]))
            np.maximum(xmax, seg["xmax"], out=xmax)
            np.minimum(xmin, seg["xmin"], out=xmin)
            if jac:
                G[k] = seg["G"]
                dp[k] = seg["dp"]
                div += seg["info"][0]
                logdet += seg["info"][1]
                sign *= seg["info"][2]
        if status != ok.OK:
            return Evaluation(u, lam, omega, self.period, T, np.full(n * m, np.nan), None, None, ends, None, None,
                              None, np.nan, np.nan, xmax, xmin, FlowStatus(status))
        r = (ends - np.roll(S, -1, axis=0)).ravel()
        J_u = J_lam = mono = mu = None
        if jac:
            J_u = np.zeros((m * n, m * n))
            for k in range(m):
                J_u[k * n : (k + 1) * n, k * n : (k + 1) * n] = G[k]
                kk = (k + 1) % m
                J_u[k * n : (k + 1) * n, kk * n : (kk + 1) * n] -= np.eye(n)
            J_lam = dp.ravel().copy()
            mono = G[0].copy()
            for k in range(1, m):
                mono = G[k] @ mono
            mu = np.linalg.eigvals(mono)
            mu = sort_multipliers(mu)
        return Evaluation(u.copy(), float(lam), omega, self.period, T, r, J_u, J_lam, ends, G, mono, mu, logdet,
                          div, xmax, xmin, status, steps,
                          events=np.concatenate(events) if events else _NO_EVENTS)

    # ------------------------------------------------------------------------------------------
    def spread(self, s0: np.ndarray, lam: float) -> np.ndarray | None:
        """Multiple-shooting unknowns from one start state: integrate through the segments."""
        S = [np.asarray(s0, dtype=float)]
        for k in range(self.segments - 1):
            seg = self.segment(k, S[-1], lam, jac=False)
            if seg["status"] != ok.OK:
                return None
            S.append(seg["x"])
        return np.concatenate(S)

    def trajectory(self, u: np.ndarray, lam: float, samples_per_period: int = 256, steps=None):
        """The orbit sampled uniformly: ``(t, x)`` over one orbit period, from the cubic Hermite
        interpolant between steps (``t`` in s from forcing phase 0, ``x`` of shape (N, n));
        ``steps``: the orbit's :meth:`steps`, if already integrated."""
        n, m = self.n, self.segments
        T = self.period * 2.0 * np.pi / self.omega_of(lam)
        N = samples_per_period * self.period
        t_all = np.arange(N + 1) * (T / N)
        x_all = np.empty((N + 1, n))
        dur = T / m
        for k, (ts, rec) in enumerate(self.steps(u, lam) if steps is None else steps):
            lo = k * dur
            sel = (t_all >= lo - 1e-12 * T) & (t_all <= lo + dur + 1e-12 * T)
            tt = np.clip(t_all[sel] - lo, 0.0, dur)
            x_all[sel] = hermite_sample(ts, rec[:, :n], rec[:, n:], tt)
        return t_all, x_all

    def steps(self, u: np.ndarray, lam: float) -> list:
        """The orbit at the integrator's steps: per segment ``(t, rec)``, ``t`` from the segment's
        start (s), ``rec`` the state and its rate at every step (steps + 1, 2 n)."""
        n, m = self.n, self.segments
        S = np.asarray(u, dtype=float).reshape(m, n)
        out = []
        for k in range(m):
            seg = self.segment(k, S[k], lam, jac=False, record=True)
            if seg["status"] != ok.OK:
                raise FloatingPointError(f"integration failed (status {seg['status']})")
            out.append((seg["t"], seg["rec"]))
        return out


#: Components of a flow's start state below this fraction of its largest are taken as zero.
FLUSH_BELOW = 1e-100


def flushed(x0: np.ndarray) -> np.ndarray:
    """A contiguous copy of a start state with its components below :data:`FLUSH_BELOW` of the
    largest set to zero. On a branch of planar orbits of a spatial cable the out-of-plane
    components that round-off put there shrink with every Newton correction, into subnormal
    numbers whose arithmetic is slow: in the paper's example every flow of its planar period-2
    branch took twenty times as long. Anything that small is far below the round-off of the
    other components, so their arithmetic is unchanged bit for bit."""
    x = np.array(x0, dtype=float)
    x[np.abs(x) < FLUSH_BELOW * np.abs(x).max(initial=0.0)] = 0.0
    return x


def hermite_sample(ts: np.ndarray, x: np.ndarray, dx: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation of samples ``x`` with rates ``dx`` at times ``ts``."""
    h = ts[1] - ts[0]
    j = np.clip(np.floor(t / h).astype(int), 0, ts.size - 2)
    th = ((t - ts[j]) / h)[:, None]
    th2 = th * th
    th3 = th2 * th
    return ((2 * th3 - 3 * th2 + 1) * x[j] + (th3 - 2 * th2 + th) * h * dx[j]
            + (-2 * th3 + 3 * th2) * x[j + 1] + (th3 - th2) * h * dx[j + 1])


@dataclass
class OrbitSolution:
    """Result of :func:`solve_orbit`.

    Attributes
    ----------
    u : ndarray
        Converged (or last) unknowns.
    evaluation : Evaluation
        At ``u`` (with derivatives and multipliers), or None if the flow failed.
    status : SolveStatus
    iterations : int
        Newton iterations (Jacobian evaluations).
    residual : float
        ``max |r_i| / scale_i`` at ``u``.
    history : list of float
        Scaled residual per iteration.
    flow_status : FlowStatus
        Why the flow failed at the start, if it did.
    """

    u: np.ndarray
    evaluation: Evaluation | None
    status: SolveStatus
    iterations: int
    residual: float
    history: list = field(default_factory=list)
    flow_status: FlowStatus = FlowStatus.OK

    @property
    def converged(self) -> bool:
        return self.status == SolveStatus.CONVERGED


def solve_orbit(
    shooting: Shooting,
    u0: np.ndarray,
    lam: float | None = None,
    scale: np.ndarray | None = None,
    tol: float = 1e-10,
    max_iter: int = 30,
) -> OrbitSolution:
    """Damped Newton's method on the periodicity condition at a fixed parameter value.

    The full Newton step is tried first; if the flow fails or the scaled residual does not
    decrease (``|r(u + a du)| < (1 - a/4) |r(u)|``), the step is halved (down to 1/1024).
    Converged when, in every component, the Newton correction and the residual are below
    ``tol`` times the component's scale or the system's round-off level
    (:attr:`OdeSystem.noise`), whichever is larger; the solution returned is the last
    *evaluated* point (its data are consistent with it).

    Parameters
    ----------
    shooting : Shooting
    u0 : ndarray
        Initial guess (``m n`` values; a single state is spread over the segments).
    lam : float, optional
        Parameter value (default: the system's own).
    scale : ndarray, optional
        Scale of each state component (default: ``max(|u0|)`` for all, floored).
    tol : float
    max_iter : int
    """
    n, m = shooting.n, shooting.segments
    lam = shooting.default_lam() if lam is None else float(lam)
    u = np.asarray(u0, dtype=float).copy()
    if u.size == n and m > 1:
        spread = shooting.spread(u, lam)
        if spread is None:
            return OrbitSolution(u, None, SolveStatus.INTEGRATION_FAILED, 0, np.inf)
        u = spread
    if scale is None:
        scale = np.full(n, max(float(np.abs(u).max()), 1e-12))
    sc = np.tile(np.asarray(scale, dtype=float), m)
    # converged when every component is within tol (relative to its scale) or the round-off
    # level of the flow map, whichever is larger
    bound = tol * sc + np.tile(np.broadcast_to(np.asarray(shooting.system.noise, dtype=float), (n,)), m)
    ev = shooting.evaluate(u, lam)
    if ev.status != ok.OK:
        return OrbitSolution(u, None, SolveStatus.INTEGRATION_FAILED, 0, np.inf, flow_status=ev.status)
    res = float(np.abs(ev.r / sc).max())
    hist = [res]
    rotation = getattr(shooting.system, "rotation", None)
    for it in range(1, max_iter + 1):
        try:  # the phase condition on an orbit a rotation symmetry moves (a family of orbits)
            du = phased_step(ev.J_u, ev.r, phase_direction(rotation, u, sc, n, m))
        except np.linalg.LinAlgError:
            return OrbitSolution(u, ev, SolveStatus.SINGULAR, it, res, hist)
        if np.all(np.abs(du) <= bound) and np.all(np.abs(ev.r) <= bound):
            return OrbitSolution(u, ev, SolveStatus.CONVERGED, it, res, hist)
        step = line_search(shooting, u, du, lam, res, sc, bound)
        if step is None:
            return OrbitSolution(u, ev, SolveStatus.LINE_SEARCH_FAILED, it, res, hist)
        u, ev, res = step
        hist.append(res)
    return OrbitSolution(u, ev, SolveStatus.MAX_ITERATIONS, max_iter, res, hist)


def line_search(shooting, u: np.ndarray, du: np.ndarray, lam: float, res: float, sc: np.ndarray,
                bound: np.ndarray) -> tuple[np.ndarray, Evaluation, float] | None:
    """The damped Newton step of the orbit solvers: ``u + a du`` for the first ``a = 1, 1/2,
    ...`` whose flow succeeds and whose scaled residual falls below ``(1 - a/4) res`` (or within
    ``bound``); ``(u, evaluation, residual)`` there, None if ``a`` falls below 1/1024."""
    a = 1.0
    while True:
        trial = shooting.evaluate(u + a * du, lam)
        if trial.status == ok.OK:
            tres = float(np.abs(trial.r / sc).max())
            if tres < (1.0 - 0.25 * a) * res or np.all(np.abs(trial.r) <= bound):
                return u + a * du, trial, tres
        a *= 0.5
        if a < 1.0 / 1024:
            return None
