"""The closure problem of a cable fixed at both ends, solved on its complementary energy.

With both ends fixed every segment force vector follows from the force ``F`` carried by
segment 1, ``F_{k+1} = F_k - P_k``, and closure of the polygon is the stationarity condition of
the convex complementary energy (two unknowns, whatever ``n`` is)::

    Phi(F) = sum_k [ S_k |F_k| + S_k |F_k|^2 / (2 EA) ] - F . (L, H)

(without the second term for the inextensible cable). A damped Newton method converges from
any start; a segment whose force passes through zero is slack and is reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cable import Cable
from .errors import ConvergenceError, SlackSegmentError
from .roots import brentq

#: Closure tolerance of the Newton solve, relative to the larger of chord and total length.
CLOSURE_RTOL = 1e-12
_MAX_NEWTON = 200
#: Kinks tested at once by the slack check (rows of its O(n^2) temporaries).
SLACK_BLOCK = 128
#: A solution whose smallest tension is below this fraction of the largest is checked for a
#: slack segment (a minimiser at a kink of Phi) before it is returned.
SLACK_SUSPECT = 1e-6


# ----------------------------------------------------------------------------------------------
# The closure problem
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SegmentForces:
    """Solution of the closure problem: the force carried by each segment.

    Attributes
    ----------
    F : ndarray, shape (n + 1, 2)
        Force vector of each segment, N, pointing from its start node to its end node
        (``F_r = T_r e_r``).
    T : ndarray, shape (n + 1,)
        Segment tensions ``T_r = |F_r|``, N.
    e : ndarray, shape (n + 1, 2)
        Unit vectors along the segments, ``e_r``.
    length : ndarray, shape (n + 1,)
        Segment lengths in the solved configuration, ``l_r = S_r (1 + T_r / EA)``, m.
    closure_error : float
        ``|sum_r l_r e_r - (L, H)|`` at the solution, m: the solver's residual.
    iterations : int
        Newton iterations used.
    """

    F: np.ndarray
    T: np.ndarray
    e: np.ndarray
    length: np.ndarray
    closure_error: float
    iterations: int

    @property
    def normal(self) -> np.ndarray:
        """Unit normals ``t_r = e_r`` rotated by +90 degrees, shape (n + 1, 2)."""
        return np.column_stack([-self.e[:, 1], self.e[:, 0]])

    @property
    def F1(self) -> np.ndarray:
        """Force vector carried by segment 1 (the reaction pulling on support A, negated)."""
        return self.F[0]


def cumulative_loads(P: np.ndarray) -> np.ndarray:
    """``Q_k = sum_{j<k} P_j``, so that segment ``k`` carries ``F_1 - Q_k``.

    Parameters
    ----------
    P : ndarray, shape (2n,)
        Nodal loads in DOF order, N.

    Returns
    -------
    ndarray, shape (n + 1, 2)
    """
    Pn = np.asarray(P, dtype=float).reshape(-1, 2)
    Q = np.zeros((Pn.shape[0] + 1, 2))
    np.cumsum(Pn, axis=0, out=Q[1:])
    return Q


def _force_scale(cable: Cable, Q: np.ndarray) -> float:
    scale = float(np.max(np.abs(Q))) if Q.size else 0.0
    if scale > 0.0:
        return scale
    # No loads: only a pretensioned (shorter than chord) elastic cable carries tension.
    if cable.compliance > 0.0:
        strain = max(cable.chord_length / cable.total_length - 1.0, 1e-12)
        return cable.EA * strain
    return 1.0


def _check_slack(S: np.ndarray, Q: np.ndarray, c: np.ndarray, eps: float, zero_tol: float):
    """Find a segment that would be slack: the optimum of Phi at a kink ``F = Q_k``.

    At ``F = Q_k`` the subdifferential of Phi is the gradient of the smooth terms plus a disk
    of radius ``sum S_m`` over the segments m whose force vanishes there. The kink is the
    minimiser (segment k slack) exactly when the gradient lies inside that disk. O(n^2) work,
    done in blocks of kinks so that the temporaries stay small (n = 2000: 2 MB, not 200 MB).
    """
    for start in range(0, Q.shape[0], SLACK_BLOCK):
        Qk = Q[start : start + SLACK_BLOCK]
        diff = Qk[:, None, :] - Q[None, :, :]  # F_m at the kink of k: Q_k - Q_m, shape (k, m, 2)
        T = np.hypot(diff[..., 0], diff[..., 1])
        zero = T <= zero_tol
        Tsafe = np.where(zero, 1.0, T)
        coef = np.where(zero, 0.0, S[None, :] * (1.0 / Tsafe + eps))
        g_rest = np.einsum("km,kmi->ki", coef, diff) - c
        radius = (S[None, :] * zero).sum(axis=1)
        inside = np.hypot(g_rest[:, 0], g_rest[:, 1]) <= radius * (1.0 + 1e-12)
        if np.any(inside):
            return start + int(np.flatnonzero(inside)[0])
    return None


def _raise_if_slack(cable: Cable, phi: "_ComplementaryEnergy") -> None:
    k = _check_slack(phi.S, phi.Qh, phi.c, phi.eps, zero_tol=phi.zero_tol)
    if k is not None:
        raise SlackSegmentError(
            f"Segment {k + 1} (natural length {cable.S[k]:.6g} m) would be slack: under these "
            "loads the cable reaches equilibrium only with zero tension in it. Check the signs "
            "and sizes of the loads on its end nodes, or shorten the cable (cable.S).",
            segment=k + 1,
        )


class _ComplementaryEnergy:
    """``Phi`` in units of the chord length and a load scale (so tolerances are scale-free)."""

    def __init__(self, cable: Cable, Q: np.ndarray, eps_dim: float):
        self.ell = cable.chord_length
        self.p = _force_scale(cable, Q)
        self.S = cable.S / self.ell
        self.c = cable.chord / self.ell
        self.Qh = Q / self.p
        self.eps = eps_dim * self.p
        self.tol = CLOSURE_RTOL * max(1.0, self.S.sum())
        self.zero_tol = 1e-13 * max(1.0, np.abs(self.Qh).max())

    def state(self, F):
        """Tensions, unit vectors, lengths, gradient (closure error) and ``Phi`` at ``F``."""
        S, eps = self.S, self.eps
        Fk = F - self.Qh
        T = np.hypot(Fk[:, 0], Fk[:, 1])
        T = np.maximum(T, 1e-300)
        e = Fk / T[:, None]
        lk = S * (1.0 + eps * T)
        g = lk @ e - self.c
        phi = float(S @ T + 0.5 * eps * (S @ (T * T)) - F @ self.c)
        return T, e, lk, g, phi

    def start(self):
        """Minimise Phi along the chord direction through the mean segment force: a 1-D convex
        problem whose solution is a good, kink-free start for the 2-D Newton iteration."""
        base = self.Qh.mean(axis=0)
        u = self.c / np.hypot(*self.c)

        def slope(s):
            return self.state(base + s * u)[3] @ u

        hi = 1.0
        while slope(hi) <= 0.0:
            hi *= 4.0
            if hi > 1e30:
                raise ConvergenceError("could not bracket the tension of the cable")
        lo = -1.0
        while slope(lo) >= 0.0:
            lo *= 4.0
            if lo < -1e30:
                raise ConvergenceError("could not bracket the tension of the cable")
        return base + brentq(slope, lo, hi, xtol=1e-14, rtol=1e-12) * u

    def escape_kink(self, F):
        """Near ``F = Q_k`` (segment k carrying almost nothing) Newton's quadratic model is
        useless. At the kink itself the steepest-descent direction is exactly ``-g_rest`` (the
        gradient of the other terms), a descent direction because the segment is not slack
        (``|g_rest| > S_k``): minimise Phi along that ray, a 1-D convex problem."""
        S, eps, Qh = self.S, self.eps, self.Qh
        k = int(np.argmin(self.state(F)[0]))
        diff = Qh[k] - Qh
        Tm = np.hypot(diff[:, 0], diff[:, 1])
        zero = Tm <= self.zero_tol
        coef = np.where(zero, 0.0, S * (1.0 / np.where(zero, 1.0, Tm) + eps))
        g_rest = coef @ diff - self.c
        u = -g_rest / np.hypot(*g_rest)

        def slope(a):
            return self.state(Qh[k] + a * u)[3] @ u

        hi = 1e-6
        while slope(hi) < 0.0:
            hi *= 4.0
            if hi > 1e30:
                raise ConvergenceError("could not bracket the tension of the cable")
        return Qh[k] + brentq(slope, 0.0, hi, xtol=1e-15, rtol=1e-13) * u

    def newton_direction(self, T, e, g):
        """``-H^-1 g`` with the Hessian of Phi (regularised when all segments are parallel)."""
        S, eps = self.S, self.eps
        tn = np.column_stack([-e[:, 1], e[:, 0]])
        wt = S * (1.0 / T + eps)
        we = S * eps
        Hm = (wt[:, None, None] * tn[:, :, None] * tn[:, None, :]).sum(0) + (
            we[:, None, None] * e[:, :, None] * e[:, None, :]
        ).sum(0)
        tr = np.trace(Hm)
        if np.linalg.det(Hm) <= 1e-12 * tr * tr:
            # All segments (nearly) parallel: the inextensible Hessian is singular there.
            Hm = Hm + 1e-6 * tr * np.eye(2)
        return -np.linalg.solve(Hm, g)

    def line_search(self, F, d, g, phi, gnorm):
        """Backtracking along ``d`` (Armijo, or halving the closure error)."""
        slope0 = float(g @ d)
        step = 1.0
        while True:
            Fn = F + step * d
            Tn, en, lkn, gn, phin = self.state(Fn)
            gnn = float(np.hypot(*gn))
            if phin <= phi + 1e-4 * step * slope0 or gnn < 0.5 * gnorm:
                break
            step *= 0.5
            if step < 1e-10:
                break
        return step, Fn, (Tn, en, lkn, gn, phin), gnn

    def minimise(self, F):
        """Damped Newton from ``F`` to ``grad Phi = 0``; ``(F, state, |g|, iterations)``."""
        ell, p = self.ell, self.p
        T, e, lk, g, phi = self.state(F)
        gnorm = float(np.hypot(*g))
        it = 0
        escapes = 0
        while gnorm > self.tol:
            if it >= _MAX_NEWTON:
                raise ConvergenceError(
                    f"The static solver did not converge in {_MAX_NEWTON} Newton iterations "
                    f"(closure error {gnorm * ell:.3g} m). The loads may nearly slacken a segment "
                    f"(smallest tension {T.min() * p:.3g} N); check the loads and segment lengths."
                )
            it += 1
            d = self.newton_direction(T, e, g)
            step, Fn, st, gnn = self.line_search(F, d, g, phi, gnorm)
            near_kink = st[0].min() < 1e-9 * max(1.0, np.hypot(*Fn))
            if (step < 1e-10 or near_kink) and escapes < 50:
                escapes += 1
                Fn = self.escape_kink(Fn if near_kink else F)
                st = self.state(Fn)
                gnn = float(np.hypot(*st[3]))
            elif step < 1e-10:
                raise ConvergenceError(
                    "The static solver's line search stalled (closure error "
                    f"{gnorm * ell:.3g} m); the loads may nearly slacken a segment "
                    f"(smallest tension {T.min() * p:.3g} N)."
                )
            F, (T, e, lk, g, phi), gnorm = Fn, st, gnn
        return F, (T, e, lk, g, phi), gnorm, it


def solve_segment_forces(
    cable: Cable,
    P: np.ndarray,
    elastic: bool = True,
    F_start: np.ndarray | None = None,
    check_slack: bool = True,
) -> SegmentForces:
    """Solve the closure problem by damped Newton on the complementary energy.

    Parameters
    ----------
    cable : Cable
    P : ndarray, shape (2n,)
        Nodal loads, N, in DOF order.
    elastic : bool
        Include the elastic term ``S |F|^2 / (2 EA)`` (exact elastic equilibrium); ``False``
        solves the inextensible cable.
    F_start : ndarray, shape (2,), optional
        Starting guess for the force in segment 1 (a warm start from a nearby solution).
    check_slack : bool
        Report a segment that would be slack (an exact test, ``O(n^2)``, run only when Newton
        fails or ends next to a kink); turn off only for warm-started solves inside a time loop.

    Returns
    -------
    SegmentForces

    Raises
    ------
    SlackSegmentError
        If a segment would carry no tension under these loads.
    ConvergenceError
        If Newton's method fails.
    """
    eps_dim = cable.compliance if elastic else 0.0
    Q = cumulative_loads(P)
    if Q.shape[0] != cable.n_segments:
        raise ValueError(f"expected {cable.n_dof} load components, got {2 * (Q.shape[0] - 1)}")
    if eps_dim == 0.0 and not cable.spans_slack:
        raise ConvergenceError(
            f"The natural segment lengths sum to {cable.total_length:.15g} m, not more than the "
            f"chord {cable.chord_length:.15g} m between the supports, so an inextensible cable "
            "cannot span them. Lengthen cable.S, or use the exact analysis for a pretensioned cable.",
        )
    phi = _ComplementaryEnergy(cable, Q, eps_dim)
    # Phi is convex, and strictly so where it is smooth (segments not all parallel), so a
    # stationary point with every segment in tension is its only minimiser and no segment is
    # slack: the O(n^2) slack check runs only when Newton fails or ends next to a kink.
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # a slack case may run off to infinity
            F = phi.start() if F_start is None else np.asarray(F_start, dtype=float) / phi.p
            F, (T, e, lk, g, _), gnorm, it = phi.minimise(F)
        if not np.isfinite(gnorm):
            raise ConvergenceError("The static solver's Newton iteration diverged; a segment may be slack.")
    except (ConvergenceError, ValueError):
        if check_slack:
            _raise_if_slack(cable, phi)
        raise
    if check_slack and T.min() <= SLACK_SUSPECT * T.max():
        _raise_if_slack(cable, phi)
    return SegmentForces(
        F=(F - phi.Qh) * phi.p,
        T=T * phi.p,
        e=e,
        length=lk * phi.ell,
        closure_error=gnorm * phi.ell,
        iterations=it,
    )
