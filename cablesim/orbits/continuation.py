"""Pseudo-arclength continuation of solution branches of ``r(u, lambda) = 0``.

The algorithm knows neither the physics nor the output: a *problem* object supplies the residual
and its derivatives, and a *callback* receives every converged point.

Problem protocol
----------------
``evaluate(u, lam)``
    Returns an object with attributes ``r`` (residual, shape (N,)), ``J_u`` ((N, N)) and
    ``J_lam`` ((N,)), or None (or an object whose ``r`` is not finite) when the residual
    cannot be evaluated there (the step is then shortened).
``u_scale`` (ndarray (N,)), ``lam_scale`` (float)
    Typical sizes of the unknowns and of the parameter. Every norm, the arclength and the
    tangent are taken in the scaled variables ``u / u_scale``, ``lam / lam_scale`` (residuals
    in ``r / r_scale``, ``r_scale`` defaulting to ``u_scale``), so that the step mixes state
    and parameter sensibly.
Optional: ``test_names`` (tuple of str) and ``test_functions(ev) -> ndarray``
    Real test functions evaluated at every point (``ev`` is what ``evaluate`` returned); a sign
    change between consecutive points marks a special point, located by the secant method
    (Illinois variant) on the arclength between them, re-solving the branch at every trial.
    The algorithm itself watches the parameter component of the tangent (``"fold"``: a turning
    point). Tests named in the optional ``fold_tests`` duplicate the turning point (for example
    ``det(J_u)``): they are ignored in an interval where the tangent's parameter component also
    changes sign.
Optional: ``bordered(ev, u_scale, lam_scale, r_scale)``
    For problems that form no Jacobian (``ev.J_u`` None): an object whose ``solve(normal, rhs,
    atol)`` returns the solution ``dv`` of the scaled bordered system ``[J_u J_lam; normal] dv =
    rhs`` (or None; an iterative solver may stop at a residual ``atol``) and whose
    ``tangent(ref)`` returns the unit null vector of ``[J_u J_lam]`` with a positive projection
    on ``ref`` (or None), for instance by a Krylov method on the Jacobian's action on vectors.
Optional: ``step_ratio(ev_a, ev_b, ev_before) -> float``
    A problem-specific measure of the change between consecutive points (for instance of the
    quantities the test functions depend on); a step with a ratio above 1 is rejected and
    halved, one below 1/4 lets the step grow. ``ev_before``: the evaluation of the branch's
    point before ``ev_a`` (None at its first step), for a rule that models the change along
    the branch beyond two points.
Optional: ``confirm(name, ev) -> str or None``
    Final label of a located special point (None discards it, for instance a neutral saddle
    that a Neimark-Sacker test cannot tell from a genuine crossing).

Algorithm
---------
Predictor: tangent step ``v + ds t`` in scaled variables ``v = (u, lam)``. Corrector: Newton
on ``r = 0`` bordered by the hyperplane through the prediction orthogonal to ``t`` (Keller).
A point is accepted when the scaled Newton correction and residual fall below the tolerances;
the data of the last *evaluated* iterate are kept, so everything reported belongs to one
evaluation. Step control: after an accepted step the next one aims at a tangent turn of
``max_angle / 2`` and at half the problem's ``step_ratio`` limit, growing by at most ``grow``
and shrinking by ``shrink`` (also after a correction that took more than ``target_newton``
iterations); a step is halved and retried after a failure, a correction that wanders farther
than the step, a turn of the tangent by more than ``max_angle`` or a ``step_ratio`` above 1. The
step stays within ``[ds_min, ds_max]``. Continuation stops
at the parameter bounds (the last point is solved exactly at the bound), after ``max_points``,
when the step falls below ``ds_min``, or when the callback returns True.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any, Callable

import numpy as np


class Status(IntEnum):
    """Why a branch ended."""

    BOUND_REACHED = 0
    MAX_POINTS = 1
    STEP_TOO_SMALL = 2
    STOPPED_BY_CALLBACK = 3
    START_FAILED = 4


@dataclass(frozen=True)
class Settings:
    """Continuation settings (steps in scaled arclength).

    Attributes
    ----------
    ds, ds_min, ds_max : float
        Initial, smallest and largest step.
    max_points : int
        Most points on the branch (special points included).
    newton_tol : float
        Scaled Newton correction (max norm) for convergence.
    residual_tol : float
        Scaled residual (max norm) for convergence.
    max_newton : int
        Corrector iterations before the step is rejected.
    target_newton : int
        Iterations of a "comfortable" correction (step kept).
    grow, shrink : float
        Step factors after easy / hard corrections.
    max_angle : float
        Largest angle between consecutive tangents, rad.
    lam_min, lam_max : float
        Parameter bounds.
    locate : bool
        Locate special points (else they are only detected between points).
    locate_tol : float
        Arclength bracket width at which a special point counts as located.
    max_locate : int
        Secant iterations per special point.
    """

    ds: float = 0.01
    ds_min: float = 1e-7
    ds_max: float = 0.05
    max_points: int = 1000
    newton_tol: float = 1e-9
    residual_tol: float = 1e-9
    max_newton: int = 8
    target_newton: int = 3
    grow: float = 1.5
    shrink: float = 0.6
    max_angle: float = 0.35
    lam_min: float = -np.inf
    lam_max: float = np.inf
    locate: bool = True
    locate_tol: float = 1e-9
    max_locate: int = 40


@dataclass
class Point:
    """A converged point of a branch.

    Attributes
    ----------
    u : ndarray
        Unknowns.
    lam : float
        Parameter.
    tangent : ndarray (N + 1,)
        Unit tangent in scaled variables, ``(du, dlam)``, oriented along the continuation.
    evaluation : object
        What ``problem.evaluate`` returned at this point.
    tests : ndarray
        Values of the test functions (fold test first: the tangent's parameter component).
    iterations : int
        Corrector iterations.
    residual : float
        Scaled residual max norm.
    special : str or None
        Label of a located special point (``"fold"``, a problem test name or what
        ``confirm`` returned), None for a regular point.
    located : bool
        For a special point: whether the location converged to ``locate_tol``.
    arclength : float
        Scaled arclength from the start (along the chords between points).
    """

    u: np.ndarray
    lam: float
    tangent: np.ndarray
    evaluation: Any
    tests: np.ndarray
    iterations: int
    residual: float
    special: str | None = None
    located: bool = True
    arclength: float = 0.0


@dataclass
class Branch:
    """Result of :func:`continuation`: the points in order and why it stopped."""

    points: list = field(default_factory=list)
    status: Status = Status.MAX_POINTS
    steps_rejected: int = 0
    evaluations: int = 0

    @property
    def special_points(self) -> list:
        return [p for p in self.points if p.special is not None]


class _Scaled:
    """The problem in scaled variables ``v = (u / u_scale, lam / lam_scale)``."""

    def __init__(self, problem):
        self.p = problem
        self.us = np.asarray(problem.u_scale, dtype=float)
        self.ls = float(problem.lam_scale)
        self.rs = np.asarray(getattr(problem, "r_scale", self.us), dtype=float)
        self.N = self.us.size
        self.names = tuple(getattr(problem, "test_names", ()))
        self.fold_like = set(getattr(problem, "fold_tests", ()))
        self.count = 0

    def unscale(self, v):
        return v[:-1] * self.us, float(v[-1] * self.ls)

    def scale(self, u, lam):
        return np.concatenate([np.asarray(u, dtype=float) / self.us, [lam / self.ls]])

    def evaluate(self, v):
        u, lam = self.unscale(v)
        self.count += 1
        try:
            ev = self.p.evaluate(u, lam)
        except (FloatingPointError, np.linalg.LinAlgError, ValueError):
            return None
        if ev is None or not np.all(np.isfinite(ev.r)):
            return None
        return ev

    def linear(self, ev):
        """The scaled bordered systems at ``ev``: the dense ``[J_u J_lam]``, or the problem's own
        (``bordered``) when it forms no Jacobian."""
        if getattr(ev, "J_u", None) is None and hasattr(self.p, "bordered"):
            return self.p.bordered(ev, self.us, self.ls, self.rs)
        Ju = ev.J_u * (self.us[None, :] / self.rs[:, None])
        Jl = ev.J_lam * (self.ls / self.rs)
        return _DenseBordered(np.hstack([Ju, Jl[:, None]]))

    def tests(self, ev):
        if not self.names:
            return np.zeros(0)
        return np.asarray(self.p.test_functions(ev), dtype=float)


class _DenseBordered:
    """The bordered systems of a formed ``[J_u J_lam]`` (scaled), solved by LU."""

    def __init__(self, Jfull: np.ndarray):
        self.J = Jfull

    def solve(self, normal: np.ndarray, rhs: np.ndarray, atol: float = 0.0) -> np.ndarray | None:
        try:
            return np.linalg.solve(np.vstack([self.J, normal[None, :]]), rhs)
        except np.linalg.LinAlgError:
            return None

    def tangent(self, ref: np.ndarray) -> np.ndarray | None:
        return _tangent(self.J, ref)


def _tangent(Jfull: np.ndarray, ref: np.ndarray) -> np.ndarray | None:
    """Unit null vector of ``[J_u J_lam]`` with positive projection on ``ref``."""
    A = np.vstack([Jfull, ref[None, :]])
    rhs = np.zeros(A.shape[0])
    rhs[-1] = 1.0
    try:
        t = np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError:
        return None
    nt = np.linalg.norm(t)
    if not np.isfinite(nt) or nt == 0.0:
        return None
    t /= nt
    return t if t @ ref >= 0 else -t


#: A corrector that gives up (:func:`_correct`) when a Newton step is more than this fraction of
#: the last one (from the third on), or a patient one (``patient=True``) more than
#: :data:`PATIENT_CONTRACTION`, which also takes :data:`PATIENT_ITERATIONS` times the iterations:
#: near a double root (two solutions about to merge) Newton's steps shrink only linearly.
CONTRACTION = 0.5
#: An iterative solution of the bordered system stops at a residual of this fraction of the
#: Newton tolerance (``atol`` of ``solve``): near convergence the step need only be told from the
#: tolerance, and a relative residual alone would solve a step of 1e-12 to 1e-18.
LINEAR_FLOOR = 1e-3
PATIENT_CONTRACTION = 0.9
PATIENT_ITERATIONS = 6


def _correct(sp: _Scaled, v_pred, normal, offset, st: Settings, radius: float, patient: bool = False):
    """Newton on ``r = 0`` and ``normal . v = offset``; returns ``(v, ev, iterations, residual,
    bordered systems at ev)`` in scaled variables, or None."""
    v = v_pred.copy()
    prev = np.inf
    contraction = PATIENT_CONTRACTION if patient else CONTRACTION
    for it in range(1, st.max_newton * (PATIENT_ITERATIONS if patient else 1) + 1):
        ev = sp.evaluate(v)
        if ev is None:
            return None
        R = ev.r / sp.rs
        Jf = sp.linear(ev)
        dv = Jf.solve(normal, -np.concatenate([R, [normal @ v - offset]]), atol=LINEAR_FLOOR * st.newton_tol)
        if dv is None:
            return None
        step = float(np.abs(dv).max())
        res = float(np.abs(R).max())
        if not np.isfinite(step):
            return None
        if step <= st.newton_tol and res <= st.residual_tol:
            return v, ev, it, res, Jf
        if it >= 3 and step > contraction * prev:  # not contracting
            return None
        prev = step
        v = v + dv
        if np.linalg.norm(v - v_pred) > radius:
            return None
    return None


def _point(sp, v, ev, its, res, Jf, ref, special=None, arclength=0.0):
    t = Jf.tangent(ref)
    if t is None:
        return None
    u, lam = sp.unscale(v)
    tests = np.concatenate([[t[-1]], sp.tests(ev)])
    return Point(u=u, lam=lam, tangent=t, evaluation=ev, tests=tests, iterations=its, residual=res,
                 special=special, arclength=arclength)


def _v(sp, p: Point):
    return sp.scale(p.u, p.lam)


def _solve_at(sp, a: Point, sigma: float, st: Settings, special=None, near: tuple | None = None,
              patient: bool = False):
    """The branch point at projected arclength ``sigma`` beyond ``a`` (along ``a.tangent``),
    predicted from ``near = (v, s)``, a point of the branch in scaled variables at projected
    arclength ``s`` (default ``a`` itself); ``patient``: the corrector of :func:`_correct`."""
    va = _v(sp, a)
    v_near, s_near = (va, 0.0) if near is None else near
    pred = v_near + (sigma - s_near) * a.tangent
    out = _correct(sp, pred, a.tangent, a.tangent @ va + sigma, st, radius=max(2.0 * abs(sigma), 1e-12) + 1.0,
                   patient=patient)
    if out is None:
        return None
    v, ev, its, res, Jf = out
    return _point(sp, v, ev, its, res, Jf, a.tangent, special, a.arclength + abs(sigma))


def _solve_at_lam(sp, a: Point, b: Point, lam_b: float, st: Settings):
    """The branch point at parameter ``lam_b`` between a and b (natural-parameter corrector)."""
    va, vb = _v(sp, a), _v(sp, b)
    x = lam_b / sp.ls
    f = (x - va[-1]) / (vb[-1] - va[-1])
    pred = va + f * (vb - va)
    e = np.zeros(va.size)
    e[-1] = 1.0
    out = _correct(sp, pred, e, x, st, radius=np.linalg.norm(vb - va) + 1.0)
    if out is None:
        return None
    v, ev, its, res, Jf = out
    return _point(sp, v, ev, its, res, Jf, a.tangent, None, a.arclength + np.linalg.norm(v - va))


def _locate(sp, a: Point, b: Point, k: int, name: str, st: Settings):
    """Zero of test ``k`` between a and b by the Illinois secant method on the arclength."""
    va, vb = _v(sp, a), _v(sp, b)
    s_lo, s_hi = 0.0, float(a.tangent @ (vb - va))
    f_lo, f_hi = a.tests[k], b.tests[k]
    v_lo, v_hi = va, vb
    best = None
    side = 0
    for _ in range(st.max_locate):
        if abs(s_hi - s_lo) <= st.locate_tol:
            break
        s = (s_lo * f_hi - s_hi * f_lo) / (f_hi - f_lo)
        width = s_hi - s_lo  # s_lo < s_hi throughout (a at 0, b beyond)
        if not np.isfinite(s):
            s = 0.5 * (s_lo + s_hi)
        # keep the trial off the bracket ends, where secant steps stall
        s = min(max(s, s_lo + 1e-3 * width), s_hi - 1e-3 * width)
        p = _solve_at(sp, a, s, st, special=name)
        if p is None:
            # again, patiently, from the nearer bracket end: at a zero where two solutions merge
            # (a 1:1 resonance, which ends a Neimark-Sacker curve) Newton's steps only halve
            near = (v_lo, s_lo) if s - s_lo <= s_hi - s else (v_hi, s_hi)
            p = _solve_at(sp, a, s, st, special=name, near=near, patient=True)
        if p is None:
            return best, False
        fs = p.tests[k]
        # the trial nearest the zero: the last one may be the far end of the final bracket
        if best is None or abs(fs) <= abs(best.tests[k]):
            best = p
        if fs == 0.0:
            return p, True
        if np.sign(fs) == np.sign(f_lo):
            s_lo, f_lo, v_lo = s, fs, _v(sp, p)
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            s_hi, f_hi, v_hi = s, fs, _v(sp, p)
            if side == 1:
                f_lo *= 0.5
            side = 1
    return best, best is not None and abs(s_hi - s_lo) <= st.locate_tol * 10


def continuation(
    problem,
    u0: np.ndarray,
    lam0: float,
    settings: Settings = Settings(),
    callback: Callable[[Point], bool | None] | None = None,
    direction: float = 1.0,
    tangent: np.ndarray | None = None,
    checkpoint: Callable[[Point, float, int], None] | None = None,
    resume: Resume | None = None,
) -> Branch:
    """Continue the branch through ``(u0, lam0)`` (see the module docstring).

    Parameters
    ----------
    problem : object
        See the module docstring.
    u0, lam0 : ndarray, float
        Starting point (corrected at fixed ``lam0`` first).
    settings : Settings
    callback : callable, optional
        ``callback(point)`` for every converged point in order (special points included);
        returning True stops the continuation.
    direction : float
        +1 to start towards increasing ``lam``, -1 towards decreasing (ignored if ``tangent``).
    tangent : ndarray, optional
        Initial direction ``(du, dlam)`` in *unscaled* variables (for branch switching); the
        start is then corrected on the hyperplane through ``(u0, lam0)`` normal to it.
    checkpoint : callable, optional
        ``checkpoint(point, ds, count)`` after the first point and after every accepted step:
        the march goes on from ``point`` with the step ``ds``, ``count`` points on the branch
        so far (what :class:`Resume` needs to go on after the run is killed).
    resume : Resume, optional
        Go on from a checkpoint instead of starting at ``(u0, lam0)`` (ignored, like
        ``direction`` and ``tangent``): the steps taken are those the uninterrupted run took.

    Returns
    -------
    Branch
        Its ``points`` are those computed by this call (after ``resume``: from the checkpoint).
    """
    st = settings
    sp = _Scaled(problem)
    branch = Branch()
    p = _first_point(sp, u0, lam0, st, direction, tangent) if resume is None else resume.point(sp)
    if p is None:
        branch.status = Status.START_FAILED
    elif resume is not None:
        branch.points.append(p)
        branch.status = _march(sp, branch, st, callback, checkpoint, resume.ds, resume.count - 1)
    else:
        branch.points.append(p)
        if callback is not None and callback(p):
            branch.status = Status.STOPPED_BY_CALLBACK
        else:
            if checkpoint is not None:
                checkpoint(p, st.ds, 1)
            branch.status = _march(sp, branch, st, callback, checkpoint)
    branch.evaluations = sp.count
    return branch


@dataclass(frozen=True)
class Resume:
    """Where an interrupted :func:`continuation` goes on: the last point's unknowns ``u``,
    parameter ``lam``, scaled unit ``tangent``, test function values ``tests`` and
    ``arclength`` (as :class:`Point` holds them), the next step ``ds`` and the ``count`` of
    points on the branch. The point's evaluation is computed again (the problem's evaluation
    is deterministic, so the march takes the steps the uninterrupted one took)."""

    u: np.ndarray
    lam: float
    tangent: np.ndarray
    tests: np.ndarray
    arclength: float
    ds: float
    count: int

    def point(self, sp: _Scaled) -> Point | None:
        """The checkpoint's point with its evaluation (None if it cannot be evaluated)."""
        sp.count += 1
        ev = sp.p.evaluate(np.array(self.u, dtype=float), float(self.lam))
        if ev is None:
            return None
        return Point(u=np.array(self.u, dtype=float), lam=float(self.lam), tangent=np.array(self.tangent, dtype=float),
                     evaluation=ev, tests=np.array(self.tests, dtype=float), iterations=0, residual=0.0,
                     arclength=float(self.arclength))


def _first_point(sp: _Scaled, u0, lam0, st: Settings, direction: float, tangent) -> Point | None:
    """The starting point, corrected at fixed ``lam0`` or, given a tangent, on the hyperplane
    through ``(u0, lam0)`` normal to it; None if the correction fails."""
    v0 = sp.scale(u0, lam0)
    if tangent is None:
        ref = np.zeros(v0.size)
        ref[-1] = np.sign(direction) or 1.0
        out = _correct(sp, v0, ref, v0[-1] * ref[-1], st, radius=np.inf)
    else:
        ref = np.concatenate([np.asarray(tangent[:-1], float) / sp.us, [tangent[-1] / sp.ls]])
        ref /= np.linalg.norm(ref)
        out = _correct(sp, v0, ref, ref @ v0, st, radius=np.inf)
    if out is None:
        return None
    v, ev, its, res, Jf = out
    return _point(sp, v, ev, its, res, Jf, ref)


def _march(sp: _Scaled, branch: Branch, st: Settings, callback, checkpoint=None, ds: float | None = None,
           before: int = 0) -> Status:
    """Predictor-corrector steps from the branch's last point until a stop (module docstring);
    returns why it stopped. ``ds``: the first step (default ``st.ds``); ``before``: points of
    the branch computed before its first (a resumed march)."""
    ds = st.ds if ds is None else ds
    cos_min = np.cos(st.max_angle)
    while True:
        if len(branch.points) + before >= st.max_points:
            return Status.MAX_POINTS
        a = branch.points[-1]
        va = _v(sp, a)
        pred = va + ds * a.tangent
        out = _correct(sp, pred, a.tangent, a.tangent @ pred, st, radius=ds)
        b = None
        if out is not None:
            v, ev, its, res, Jf = out
            b = _point(sp, v, ev, its, res, Jf, a.tangent, arclength=a.arclength + float(np.linalg.norm(v - va)))
        ratio = 0.0
        if b is not None and hasattr(sp.p, "step_ratio"):
            previous = branch.points[-2].evaluation if len(branch.points) > 1 else None
            ratio = float(sp.p.step_ratio(a.evaluation, b.evaluation, previous))
        if b is None or ((b.tangent @ a.tangent < cos_min or ratio > 1.0) and ds > st.ds_min):
            branch.steps_rejected += 1
            ds *= 0.5
            if ds < st.ds_min:
                return Status.STEP_TOO_SMALL
            continue
        bound = _bound_crossed(a, b, st)
        if bound is not None:  # finish exactly on the bound
            e = _solve_at_lam(sp, a, b, bound, st)
            if e is None:
                ds *= 0.5
                branch.steps_rejected += 1
                if ds < st.ds_min:
                    return Status.STEP_TOO_SMALL
                continue
            b = e
        if _accept(sp, branch, a, b, st, callback):
            return Status.STOPPED_BY_CALLBACK
        if bound is not None:
            return Status.BOUND_REACHED
        ds = _next_step(ds, a, b, ratio, st)
        if checkpoint is not None:
            checkpoint(b, ds, len(branch.points) + before)


def _bound_crossed(a: Point, b: Point, st: Settings) -> float | None:
    """The parameter bound crossed by the step from a to b, if any."""
    if b.lam > st.lam_max and a.lam <= st.lam_max:
        return st.lam_max
    if b.lam < st.lam_min and a.lam >= st.lam_min:
        return st.lam_min
    return None


def _next_step(ds: float, a: Point, b: Point, ratio: float, st: Settings) -> float:
    """Step after an accepted step from a to b: aim at half the largest tangent turn and half the
    problem's ratio limit."""
    angle = float(np.arccos(np.clip(a.tangent @ b.tangent, -1.0, 1.0)))
    factor = min(st.grow, 0.5 * st.max_angle / max(angle, 1e-12), 0.5 / max(ratio, 1e-12))
    if b.iterations > st.target_newton:
        factor = min(factor, st.shrink)
    return float(np.clip(ds * max(factor, st.shrink), st.ds_min, st.ds_max))


def _accept(sp, branch, a: Point, b: Point, st: Settings, callback) -> bool:
    """Locate special points between a and b, append them and b; True if the callback stops."""
    specials = []
    names = ("fold",) + sp.names
    fold_flip = np.sign(a.tests[0]) * np.sign(b.tests[0]) < 0
    for k, name in enumerate(names):
        fa, fb = a.tests[k], b.tests[k]
        if not (np.isfinite(fa) and np.isfinite(fb)) or np.sign(fa) * np.sign(fb) >= 0:
            continue
        if k > 0 and fold_flip and name in sp.fold_like:
            continue
        if st.locate:
            p, ok = _locate(sp, a, b, k, name, st)
        else:
            p, ok = None, False
        if p is None:  # not located: report the interval end that is nearer in test value
            p = _copy_as_special(a if abs(fa) < abs(fb) else b, name)
            ok = False
        p.located = ok
        label = name
        if name != "fold" and hasattr(sp.p, "confirm"):
            label = sp.p.confirm(name, p.evaluation)
        if label is None:
            continue
        p.special = label
        specials.append(p)
    specials.sort(key=lambda p: p.arclength)
    for p in specials + [b]:
        branch.points.append(p)
        if callback is not None and callback(p):
            return True
    return False


def _copy_as_special(p: Point, name: str) -> Point:
    return Point(u=p.u.copy(), lam=p.lam, tangent=p.tangent.copy(), evaluation=p.evaluation, tests=p.tests.copy(),
                 iterations=p.iterations, residual=p.residual, special=name, located=False, arclength=p.arclength)
