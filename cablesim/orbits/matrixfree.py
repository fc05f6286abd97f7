"""Matrix-free shooting: the monodromy used only through its action on vectors.

:class:`~cablesim.orbits.shooting.Shooting` integrates the variational equations of all ``n``
state variables with every orbit, so a Newton step costs about ``n`` orbit integrations (and
``O(n^2)`` per stage of each) and the multipliers the eigenvalues of a dense ``n x n`` matrix.
:class:`MatrixFreeShooting` integrates the orbit alone, and then only the directions it is asked
for:

- the flow: the same fixed-step explicit Runge-Kutta schemes as the dense shooting
  (:mod:`cablesim.orbits.directional`: the same discrete orbit, the same extremes) or, for
  stiff systems, the implicit Radau IIA scheme (:mod:`cablesim.orbits.radau`), whose step is set
  by the resolved motion rather than the fastest mode; the Radau flow records a *tape* of its
  stages, so that every further direction costs one banded solve per step and no evaluation of
  the nonlinear field;
- the Jacobian's action ``J_u v`` on the shooting unknowns (``G_k v_k - v_(k+1)`` over the
  segments) and the parameter derivative ``J_lam`` (one extra direction with the orbit);
- Newton's method by GMRES (:mod:`cablesim.orbits.krylov`) for the orbit
  (:func:`solve_orbit_mf`) and the continuation's bordered systems (:class:`Bordered`),
  preconditioned by the leading invariant subspace of the monodromy
  (:class:`~cablesim.orbits.floquet.Deflation`), which the Floquet multipliers provide anyway:
  the preconditioned operator is the identity on it, and on the rest its spectrum lies within
  the largest discarded multiplier of 1, so the iteration count does not grow with ``n``;
- the leading Floquet multipliers (:func:`orbit_leading`, :mod:`cablesim.orbits.floquet`),
  computed in the coordinates of the state divided by its scale.

An evaluation (:class:`MFEvaluation`) has the fields of the dense
:class:`~cablesim.orbits.shooting.Evaluation` with ``J_u``, ``G`` and ``monodromy`` None; its
``multipliers`` are the leading ones once computed.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from . import directional as dk
from . import kernels as ok
from . import radau as rd
from .floquet import DEFAULT_BOUND, DEFAULT_TOL, Deflation, Leading, leading_multipliers
from .krylov import gmres
from .rotation import deflated_action, phase_direction, phased_action, without
from .shooting import DEFAULT_STEPS, Evaluation, FlowStatus, OrbitSolution, Shooting, SolveStatus, line_search
from .stability import sort_multipliers
from .systems import OdeSystem
from .tableaux import TABLEAUX

__all__ = ["Bordered", "MFEvaluation", "MatrixFreeShooting", "RADAU_STEPS", "orbit_leading", "solve_orbit_mf"]

#: Radau IIA step rule, ``(least steps per forcing period, h * rate)``: ``rate`` is the largest
#: ``|lambda|`` among the linearised modes that are not damped below ``exp(-RESOLVE_DECAY)`` over
#: one forcing period (the stiffer ones are damped by the scheme as by the cable, unresolved).
RADAU_STEPS = (64, 0.6)
#: Modes damped by more than this many e-folds per forcing period need not be resolved.
RESOLVE_DECAY = 7.0
#: Cost of one Radau step in vector-field evaluations (measured on heavy cables of 10 to 100
#: nodes: three stages, about three Newton iterations and the banded stage matrix), against the
#: stages of an explicit step: the automatic scheme is the cheaper.
RADAU_STEP_COST = 14.0
#: Evaluations whose Radau tapes are kept (the latest; an older one is integrated again if asked).
KEEP_TAPES = 3

_EMPTY_REC = np.zeros((0, 0))


class _Tape:
    """The stages of one Radau segment (:func:`cablesim.orbits.radau.radau_orbit`)."""

    def __init__(self, nsteps: int, n: int, geo_shape: tuple, kl: int):
        N = 3 * (n // 2)
        rows = 2 * kl + kl + 1
        self.AB = np.empty((nsteps, N, rows))
        self.piv = np.empty((nsteps, N), dtype=np.int64)
        self.geo = np.empty((nsteps, 3) + tuple(geo_shape))
        self.rate = np.empty((nsteps, 3, n))
        self.kl = kl


@dataclass
class MFEvaluation(Evaluation):
    """:class:`~cablesim.orbits.shooting.Evaluation` of the matrix-free shooting (module
    docstring); ``starts`` are the segment start states, ``leading`` the leading multipliers
    once computed (:func:`orbit_leading`), ``split`` those of each block of a planar orbit
    (:func:`cablesim.orbits.splitleading.split_leading`; then ``leading`` joins them)."""

    starts: np.ndarray | None = None
    tapes: list | None = None
    leading: Leading | None = None
    split: object = None
    newton_krylov: int = 0

    @property
    def liouville(self) -> float:
        return np.nan


class SegmentActions:
    """The monodromy's and the periodicity condition's actions of a matrix-free shooting from its
    segments' (``segment_apply(ev, k, X)``: ``G_k X``), over its ``segments`` of ``n`` states."""

    n: int
    segments: int

    def segment_apply(self, ev: MFEvaluation, k: int, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def monodromy_apply(self, ev: MFEvaluation, X: np.ndarray) -> np.ndarray:
        """``M X = G_(m-1) ... G_0 X``."""
        Y = np.asarray(X, dtype=float)
        for k in range(self.segments):
            Y = self.segment_apply(ev, k, Y)
        return Y

    def jacobian_apply(self, ev: MFEvaluation, X: np.ndarray) -> np.ndarray:
        """``J_u X``: block ``k`` is ``G_k X_k - X_(k+1)`` (``J_u = M - I`` for one segment)."""
        n, m = self.n, self.segments
        X = np.asarray(X, dtype=float).reshape(m, n, -1)
        out = np.empty_like(X)
        for k in range(m):
            out[k] = self.segment_apply(ev, k, X[k]) - X[(k + 1) % m]
        return out.reshape(m * n, -1)


class MatrixFreeShooting(SegmentActions):
    """Flow maps of the ``m`` segments of a ``p``-periodic orbit and their action on vectors
    (module docstring); the interface of :class:`~cablesim.orbits.shooting.Shooting`.

    Parameters
    ----------
    system : OdeSystem
    period, segments, parameter
        As for :class:`~cablesim.orbits.shooting.Shooting`.
    scheme : str
        ``"rk8"``, ``"rk4"`` (explicit, as the dense shooting), ``"radau"`` (implicit; needs
        :attr:`OdeSystem.mechanical`) or ``"auto"``: the cheaper per orbit
        (:data:`RADAU_STEP_COST`).
    steps_per_period, step_rate : optional
        The step rule of the scheme (:data:`~cablesim.orbits.shooting.DEFAULT_STEPS`,
        :data:`RADAU_STEPS`).
    """

    def __init__(self, system: OdeSystem, period: int = 1, segments: int = 1, parameter: str = "omega",
                 scheme: str = "auto", steps_per_period: int | None = None, step_rate: float | None = None):
        if period < 1 or segments < 1:
            raise ValueError("period and segments must be positive")
        if parameter != "omega" and parameter not in system.parameters:
            raise ValueError(f"unknown parameter {parameter!r}: 'omega' or one of {sorted(system.parameters)}")
        self.system = system
        self.mech = system.mechanical
        self.period = int(period)
        self.segments = int(segments)
        self.parameter = parameter
        self.n = system.dim
        self._ipar = -1 if parameter == "omega" else int(system.parameters[parameter])
        self._pmode = ok.PARAM_OMEGA if parameter == "omega" else ok.PARAM_PRM
        if scheme == "auto":
            scheme = self.cheaper_scheme(steps_per_period, step_rate)
        if scheme == "radau" and self.mech is None:
            raise ValueError("the radau scheme needs a system in mechanical form")
        if scheme != "radau" and scheme not in TABLEAUX:
            raise ValueError(f"unknown scheme {scheme!r}: one of {sorted(TABLEAUX) + ['radau', 'auto']}")
        self.scheme = scheme
        spp, rate = RADAU_STEPS if scheme == "radau" else DEFAULT_STEPS[scheme]
        self.steps_per_period = int(steps_per_period if steps_per_period is not None else spp)
        self.step_rate = float(step_rate if step_rate is not None else rate)
        if scheme != "radau":
            tab = TABLEAUX[scheme]
            self._A, self._b, self._c = (np.ascontiguousarray(a) for a in (tab.A, tab.b, tab.c))
        self._flow = ok.EntryPoint(dk.flow_mechanical if self.mech is not None else dk.flow_dense_directions)
        self._radau = ok.EntryPoint(rd.radau_orbit)
        self._replay = ok.EntryPoint(rd.radau_directions)
        noise = np.broadcast_to(np.asarray(system.noise, dtype=float), (self.n,))
        self._vnoise = np.ascontiguousarray(noise[self.n // 2:])
        self._taped: deque = deque()
        #: Counters: segment integrations, steps, directions carried, Newton steps, Krylov iterations.
        self.calls = 0
        self.steps_taken = 0
        self.products = 0
        self.newton_steps = 0
        self.krylov_iterations = 0
        self.stage_iterations = 0
        #: Status of the latest segment integration (why a flow stopped: ``SLACK``, ...).
        self.last_status = ok.OK

    # ------------------------------------------------------------------------------------------
    def omega_of(self, lam: float) -> float:
        return float(lam) if self.parameter == "omega" else self.system.omega

    def default_lam(self) -> float:
        return self.system.omega if self.parameter == "omega" else float(self.system.prm[self._ipar])

    def _prm(self, lam: float) -> np.ndarray:
        if self.parameter == "omega":
            return self.system.prm
        prm = self.system.prm.copy()
        prm[self._ipar] = lam
        return prm

    def resolved_rate(self, omega: float) -> float:
        """Largest ``|lambda|`` of the linearised modes the Radau step must resolve at forcing
        frequency ``omega`` (:data:`RESOLVE_DECAY`)."""
        lam = np.asarray(self.mech.eigenvalues, dtype=complex)
        tf = 2.0 * np.pi / omega
        keep = lam.real * tf >= -RESOLVE_DECAY
        return float(np.abs(lam[keep]).max()) if np.any(keep) else 0.0

    def segment_steps(self, omega: float) -> int:
        """Fixed steps per segment at forcing frequency ``omega``."""
        tf = 2.0 * np.pi / omega
        rate = self.resolved_rate(omega) if self.scheme == "radau" else self.system.fastest_rate
        per_period = max(self.steps_per_period, int(np.ceil(tf * rate / self.step_rate)))
        return max(1, int(np.ceil(per_period * self.period / self.segments)))

    def cheaper_scheme(self, steps_per_period=None, step_rate=None, omega: float | None = None) -> str:
        """``"radau"`` if it costs fewer field evaluations per orbit than rk8, else ``"rk8"``."""
        if self.mech is None:
            return "rk8"
        omega = self.system.omega if omega is None else omega
        tf = 2.0 * np.pi / omega
        spp, rate = DEFAULT_STEPS["rk8"]
        explicit = max(spp, np.ceil(tf * self.system.fastest_rate / rate)) * TABLEAUX["rk8"].stages
        rspp, rrate = RADAU_STEPS
        implicit = max(rspp, np.ceil(tf * self.resolved_rate(omega) / rrate)) * RADAU_STEP_COST
        return "radau" if implicit < explicit else "rk8"

    # ------------------------------------------------------------------------------------------
    def _integrate(self, k: int, x0, lam, param: bool, tape: bool, V=None, record: bool = False):
        """Segment ``k`` from ``x0``: ``(status, end, xmax, xmin, dp, tape, rec, nsteps)``; with
        ``V`` (q, n) for an explicit scheme, ``V`` becomes ``G V`` too."""
        omega = self.omega_of(lam)
        n = self.n
        if not omega > 0.0:
            return ok.NONFINITE, None, None, None, None, None, None, 0
        T = self.period * 2.0 * np.pi / omega
        dur = T / self.segments
        theta0 = 2.0 * np.pi * self.period * k / self.segments
        ns = self.segment_steps(omega)
        dp = np.zeros(n)
        rec = np.empty((ns + 1, 2 * n)) if record else _EMPTY_REC
        x0 = np.ascontiguousarray(x0, dtype=float)
        # the extremes start from the segment's start state: the Radau kernel only updates them
        # (the explicit ones set them first)
        xend, xmax, xmin = np.empty(n), x0.copy(), x0.copy()
        work = ok.copy_work(self.system.work)
        prm = self._prm(lam)
        pmode = self._pmode if param else ok.PARAM_NONE
        the_tape = None
        self.calls += 1
        self.steps_taken += ns
        if self.scheme == "radau":
            mech = self.mech
            kl = rd.q_bandwidth((mech.stiffness_rows - 1) // 2)
            the_tape = _Tape(ns, n, mech.geo_shape, kl) if (tape or param) else None
            tp = the_tape if the_tape is not None else _Tape(0, n, mech.geo_shape, kl)
            geo3 = np.empty((3,) + tuple(mech.geo_shape))
            Kb3 = np.empty((3, mech.stiffness_rows, n // 2))
            info = np.zeros(1 + rd.MAX_NEWTON); self.last_info = info
            code = self._radau(mech.balance, mech.stiffness_band, mech.model, prm, work, geo3, Kb3, x0, float(theta0),
                               float(omega), float(dur), int(ns), rd.RADAU.c, rd.RADAU.W1, rd.RADAU.W2, rd.RADAU.E,
                               self._vnoise, the_tape is not None, tp.AB, tp.piv, tp.geo, tp.rate, xend, xmax, xmin,
                               rec, info)
            self.stage_iterations += int(info[0])
            if code == ok.OK and param:
                code = self._replay_tape(the_tape, k, lam, np.zeros((0, n)), dp, pmode)
        else:
            Vq = np.zeros((0, n)) if V is None else V
            if self.mech is not None:
                mech = self.mech
                geo = np.empty(mech.geo_shape)
                code = self._flow(mech.balance, mech.stiffness_times, mech.load_derivative, mech.model, prm, work, geo,
                                  x0, float(theta0), float(omega), float(dur), int(ns), self._A, self._b, self._c,
                                  self._ipar, pmode, Vq, dp, xend, xmax, xmin, rec)
            else:
                code = self._flow(self.system.field, self.system.model, prm, work, x0, float(theta0), float(omega),
                                  float(dur), int(ns), self._A, self._b, self._c, self._ipar, pmode, Vq, dp, xend,
                                  xmax, xmin, rec)
            self.products += Vq.shape[0] + (1 if param else 0)
        self.last_status = int(code)
        return int(code), xend, xmax, xmin, dp, the_tape, rec, ns

    def _replay_tape(self, tape, k, lam, V, P, pmode):
        omega = self.omega_of(lam)
        T = self.period * 2.0 * np.pi / omega
        dur = T / self.segments
        theta0 = 2.0 * np.pi * self.period * k / self.segments
        ns = tape.AB.shape[0]
        mech = self.mech
        self.products += V.shape[0] + (1 if pmode != ok.PARAM_NONE else 0)
        return int(self._replay(mech.stiffness_times, mech.load_derivative, mech.model, self._prm(lam),
                                float(theta0), float(omega), float(dur), int(ns), rd.RADAU.c, rd.RADAU.W1, tape.AB,
                                tape.piv, tape.geo, tape.rate, tape.kl, self._ipar, pmode, V, P))

    def segment(self, k: int, x0: np.ndarray, lam: float, jac: bool = False, record: bool = False) -> dict:
        """Segment ``k`` from ``x0`` without directions (the dictionary of
        :meth:`Shooting.segment <cablesim.orbits.shooting.Shooting.segment>`, without ``G``)."""
        if jac:
            raise ValueError("the matrix-free shooting forms no segment Jacobian")
        code, xend, xmax, xmin, _, _, rec, ns = self._integrate(k, x0, lam, param=False, tape=False, record=record)
        out = {"status": code, "x": xend, "xmax": xmax, "xmin": xmin, "steps": ns}
        if record and code == ok.OK:
            omega = self.omega_of(lam)
            dur = self.period * 2.0 * np.pi / omega / self.segments
            out["t"] = np.arange(ns + 1) * (dur / ns)
            out["rec"] = rec
        return out

    def evaluate(self, u: np.ndarray, lam: float, jac: bool = True) -> MFEvaluation:
        """Residual at ``(u, lam)``; with ``jac`` also ``J_lam`` and what the actions need."""
        n, m = self.n, self.segments
        u = np.asarray(u, dtype=float)
        S = u.reshape(m, n)
        omega = self.omega_of(lam)
        T = self.period * 2.0 * np.pi / omega if omega > 0 else np.nan
        ends = np.empty((m, n))
        dp = np.empty((m, n))
        xmax, xmin = np.full(n, -np.inf), np.full(n, np.inf)
        tapes = [] if (jac and self.scheme == "radau") else None
        for k in range(m):
            code, xend, smax, smin, d, tape, _, _ = self._integrate(k, S[k], lam, param=jac, tape=jac)
            if code != ok.OK:
                return MFEvaluation(u, lam, omega, self.period, T, np.full(n * m, np.nan), None, None, ends, None, None,
                                    None, np.nan, np.nan, xmax, xmin, FlowStatus(code), starts=S.copy())
            ends[k], dp[k] = xend, d
            np.maximum(xmax, smax, out=xmax)
            np.minimum(xmin, smin, out=xmin)
            if tapes is not None:
                tapes.append(tape)
        r = (ends - np.roll(S, -1, axis=0)).ravel()
        ev = MFEvaluation(u.copy(), float(lam), omega, self.period, T, r, None, dp.ravel().copy() if jac else None,
                          ends, None, None, None, np.nan, np.nan, xmax, xmin, FlowStatus.OK, starts=S.copy(),
                          tapes=tapes)
        if tapes is not None:
            self._keep(ev)
        return ev

    def _keep(self, ev: MFEvaluation) -> None:
        """Keep the tapes of the latest :data:`KEEP_TAPES` evaluations only (memory)."""
        self._taped.append(ev)
        while len(self._taped) > KEEP_TAPES:
            self._taped.popleft().tapes = None

    #: The orbit at its integration steps and sampled uniformly (the whirling measures of a
    #: nonplanar orbit), as the dense shooting's: the same records of state and rate.
    steps = Shooting.steps
    trajectory = Shooting.trajectory

    # ------------------------------------------------------------------------------------------
    def segment_apply(self, ev: MFEvaluation, k: int, X: np.ndarray) -> np.ndarray:
        """``G_k X`` for the columns of ``X`` (n, q)."""
        V = np.array(np.asarray(X, dtype=float).T, order="C")  # a copy: the kernels overwrite it
        if self.scheme == "radau":
            if ev.tapes is None:
                again = self.evaluate(ev.u, ev.lam, jac=True)
                ev.tapes = again.tapes
            code = self._replay_tape(ev.tapes[k], k, ev.lam, V, np.zeros(self.n), ok.PARAM_NONE)
        else:
            code = self._integrate(k, ev.starts[k], ev.lam, param=False, tape=False, V=V)[0]
        if code != ok.OK:
            raise FloatingPointError(f"the variational equations could not be integrated (status {code})")
        return V.T.copy()



# ----------------------------------------------------------------------------------------------
def scaled_monodromy(shooting: MatrixFreeShooting, ev: MFEvaluation, scale: np.ndarray,
                     neutral: np.ndarray | None = None):
    """The action ``Y -> D^-1 M D Y`` of the monodromy of ``ev`` in the coordinates ``x / scale``
    (``D = diag(scale)``) on blocks; with ``neutral`` (an eigenvector ``g`` of ``M`` of multiplier
    +1, unscaled) that of Wielandt's deflation of ``M`` along it, similar to the dense path's
    (:func:`~cablesim.orbits.rotation.deflated_action` with ``g / d`` and ``d g / g^T g``)."""
    D = np.asarray(scale, dtype=float)

    def apply(X):
        return shooting.monodromy_apply(ev, X * D[:, None]) / D[:, None]

    if neutral is None:
        return apply
    g = np.asarray(neutral, dtype=float)
    return deflated_action(apply, g / D, g * D / float(g @ g))


def orbit_leading(shooting: MatrixFreeShooting, ev: MFEvaluation, scale: np.ndarray, bound: float = DEFAULT_BOUND,
                  tol: float = DEFAULT_TOL, start: np.ndarray | None = None,
                  neutral: np.ndarray | None = None) -> Leading:
    """The leading Floquet multipliers of the orbit ``ev`` (kept in ``ev.leading``, sorted into
    ``ev.multipliers``), in the coordinates ``x / scale``; ``start`` a basis to start from.
    With ``neutral`` (an eigenvector of multiplier +1 forced by a symmetry) those of the
    deflated monodromy (:func:`scaled_monodromy`): the neutral multiplier is left out."""
    if ev.leading is None:
        apply = scaled_monodromy(shooting, ev, scale, neutral)
        ev.leading = leading_multipliers(apply, shooting.n, bound=bound, tol=tol, start=start)
        ev.multipliers = sort_multipliers(ev.leading.multipliers)
    return ev.leading


def _preconditioner(shooting: MatrixFreeShooting, leading: Leading | None):
    """Deflation by the leading subspace (single shooting), else none."""
    if leading is None or shooting.segments != 1:
        return None
    return Deflation(leading.basis, leading.schur)


def solve_orbit_mf(shooting: MatrixFreeShooting, u0: np.ndarray, lam: float | None = None,
                   scale: np.ndarray | None = None, tol: float = 1e-10, max_iter: int = 30,
                   leading: Leading | None = None, krylov_tol: float = 1e-6, bound: float = DEFAULT_BOUND,
                   max_krylov: int = 200) -> OrbitSolution:
    """:func:`~cablesim.orbits.shooting.solve_orbit` with Newton's systems solved by GMRES
    (module docstring); the same convergence rule and line search. ``leading`` preconditions
    (the leading subspace of a nearby orbit); without it the leading multipliers are computed at
    the first iterate. The converged evaluation's ``newton_krylov`` counts the Krylov
    iterations spent."""
    n, m = shooting.n, shooting.segments
    lam = shooting.default_lam() if lam is None else float(lam)
    u = np.asarray(u0, dtype=float).copy()
    if u.size == n and m > 1:
        S = [u]
        for k in range(m - 1):
            seg = shooting.segment(k, S[-1], lam)
            if seg["status"] != ok.OK:
                return OrbitSolution(u, None, SolveStatus.INTEGRATION_FAILED, 0, np.inf)
            S.append(seg["x"])
        u = np.concatenate(S)
    if scale is None:
        scale = np.full(n, max(float(np.abs(u).max()), 1e-12))
    scale = np.asarray(scale, dtype=float)
    sc = np.tile(scale, m)
    bound_abs = tol * sc + np.tile(np.broadcast_to(np.asarray(shooting.system.noise, dtype=float), (n,)), m)
    ev = shooting.evaluate(u, lam)
    if ev.status != ok.OK:
        return OrbitSolution(u, None, SolveStatus.INTEGRATION_FAILED, 0, np.inf, flow_status=ev.status)
    if leading is None and m == 1:
        leading = orbit_leading(shooting, ev, scale, bound=bound, tol=1e-6)
    pre = _preconditioner(shooting, leading)
    res = float(np.abs(ev.r / sc).max())
    hist = [res]
    spent = 0
    rotation = getattr(shooting.system, "rotation", None)
    for it in range(1, max_iter + 1):
        # on an orbit a rotation symmetry moves, the phase condition along its scaled generator
        q = phase_direction(rotation, u, sc, n, m)
        qs = None if q is None else (q / sc) / np.linalg.norm(q / sc)
        rhs = -ev.r / sc if qs is None else -without(ev.r / sc, qs)

        def apply(v, ev=ev, qs=qs):
            Jv = shooting.jacobian_apply(ev, (v * sc)[:, None])[:, 0] / sc
            return Jv if qs is None else phased_action(Jv[:, None], v[:, None], qs)[:, 0]

        sol = gmres(apply, rhs, tol=krylov_tol, max_iter=max_krylov, precondition=pre)
        shooting.newton_steps += 1
        shooting.krylov_iterations += sol.iterations
        spent += sol.iterations
        if not np.all(np.isfinite(sol.x)):
            return OrbitSolution(u, ev, SolveStatus.SINGULAR, it, res, hist)
        du = sol.x * sc
        if np.all(np.abs(du) <= bound_abs) and np.all(np.abs(ev.r) <= bound_abs):
            ev.newton_krylov = spent
            return OrbitSolution(u, ev, SolveStatus.CONVERGED, it, res, hist)
        step = line_search(shooting, u, du, lam, res, sc, bound_abs)
        if step is None:
            return OrbitSolution(u, ev, SolveStatus.LINE_SEARCH_FAILED, it, res, hist)
        u, ev, res = step
        hist.append(res)
    return OrbitSolution(u, ev, SolveStatus.MAX_ITERATIONS, max_iter, res, hist)


class Bordered:
    """The continuation's scaled bordered system ``[J_u J_lam; normal]`` at an evaluation, solved
    by preconditioned GMRES (the protocol :mod:`cablesim.orbits.continuation` uses for problems
    that form no Jacobian).

    Parameters
    ----------
    shooting : MatrixFreeShooting
    ev : MFEvaluation
    us, ls, rs : ndarray, float, ndarray
        The continuation's scales of the unknowns, the parameter and the residual.
    precondition : callable or None
        ``x -> P^-1 x`` on the unknowns' block (scaled).
    tol, tangent_tol : float
        GMRES tolerances of the corrector and of the tangent.
    refresh : callable, optional
        Called before the tangent is solved; returns a better preconditioner (for instance from
        the multipliers at this point) or None.
    project : callable, optional
        An orthogonal projection of the unknowns' block (scaled) onto an invariant subspace of
        ``J_u`` that holds the branch, applied to every direction and to the solutions (the
        planar orbits of a symmetric system are corrected in the plane: at a pitchfork ``J_u``
        is singular across it, so that without the projection the Krylov iteration would amplify
        round-off into an out-of-plane correction).
    phase : ndarray, optional
        Unit vector ``q`` (unscaled) whose equation of the periodicity condition is replaced by
        a phase condition (:func:`~cablesim.orbits.rotation.phased_action`; the evaluation's
        residual and ``J_lam`` carry it already, :func:`~cablesim.orbits.rotation.with_phase`).
    """

    def __init__(self, shooting, ev, us, ls, rs, precondition=None, tol: float = 1e-6, tangent_tol: float = 1e-8,
                 max_iter: int = 200, refresh=None, project=None, phase=None):
        self.sh, self.ev = shooting, ev
        self.us, self.ls, self.rs = us, ls, rs
        self.pre = precondition
        self.tol, self.tangent_tol, self.max_iter = tol, tangent_tol, max_iter
        self.refresh = refresh
        self.project = project
        self.phase = phase

    def _projected(self, v: np.ndarray) -> np.ndarray:
        if self.project is None:
            return v
        return np.concatenate([self.project(v[:-1]), v[-1:]])

    def _matvec(self, normal):
        sh, ev, us, ls, rs = self.sh, self.ev, self.us, self.ls, self.rs

        def apply(v):
            v = self._projected(v)
            w = (v[:-1] * us)[:, None]
            Ju = sh.jacobian_apply(ev, w)
            if self.phase is not None:
                Ju = phased_action(Ju, w, self.phase)
            Ju = Ju[:, 0]
            top = (Ju + ev.J_lam * (v[-1] * ls)) / rs
            return np.concatenate([top, [normal @ v]])
        return apply

    def _precondition(self):
        if self.pre is None:
            return None
        pre = self.pre

        def apply(v):
            return np.concatenate([pre(v[:-1]), v[-1:]])
        return apply

    def solve(self, normal: np.ndarray, rhs: np.ndarray, tol: float | None = None,
              atol: float = 0.0) -> np.ndarray | None:
        """``dv`` with ``[J_u J_lam; normal] dv = rhs`` (scaled) to a relative residual ``tol``
        (default: the corrector's) or an absolute one ``atol``, whichever is larger; None if
        GMRES fails."""
        tol = self.tol if tol is None else tol
        try:
            sol = gmres(self._matvec(np.asarray(normal, dtype=float)), rhs, tol=tol, max_iter=self.max_iter,
                        precondition=self._precondition(), atol=atol)
        except FloatingPointError:  # the variational equations failed: the step is shortened
            return None
        self.sh.newton_steps += 1
        self.sh.krylov_iterations += sol.iterations
        self.ev.newton_krylov += sol.iterations
        goal = max(tol, atol / max(float(np.linalg.norm(rhs)), np.finfo(float).tiny), 1e-12)
        if not np.all(np.isfinite(sol.x)) or sol.residual > 1e3 * goal:
            return None
        return self._projected(sol.x)

    def tangent(self, ref: np.ndarray) -> np.ndarray | None:
        """Unit null vector of ``[J_u J_lam]`` with positive projection on ``ref``."""
        if self.refresh is not None:
            better = self.refresh(self.ev)
            if better is not None:
                self.pre = better
        rhs = np.zeros(ref.size)
        rhs[-1] = 1.0
        try:
            sol = gmres(self._matvec(np.asarray(ref, dtype=float)), rhs, tol=self.tangent_tol,
                        max_iter=self.max_iter, precondition=self._precondition())
        except FloatingPointError:
            return None
        self.sh.krylov_iterations += sol.iterations
        t = self._projected(sol.x)
        nt = np.linalg.norm(t)
        if not np.isfinite(nt) or nt == 0.0:
            return None
        t = t / nt
        return t if t @ ref >= 0 else -t
