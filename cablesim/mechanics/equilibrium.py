"""The static closure problem for the statics: scaled, solved, checked for slack, explained.

:func:`solve_segment_forces` solves the closure problem of :mod:`cablesim.mechanics.closure`
for a :class:`~cablesim.cable.Cable` under nodal loads, in scaled units (lengths per chord,
forces per load scale) so that its tolerances are scale-free, and reports failures as one
paragraph naming the cause: a segment that would be slack (an exact test at the kinks of the
complementary energy, :func:`slack_segment`) or a Newton method that did not converge.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..cable import Cable
from ..errors import ConvergenceError, SlackSegmentError
from . import closure as cl

#: Closure tolerance of the Newton solve, relative to the larger of chord and total length.
CLOSURE_RTOL = 1e-12
MAX_NEWTON = 200
#: Kinks tested at once by the slack check (rows of its O(n^2) temporaries).
SLACK_BLOCK = 128
#: A solution whose smallest tension is below this fraction of the largest is checked for a
#: slack segment (a minimiser at a kink of Phi) before it is returned.
SLACK_SUSPECT = 1e-6


@dataclass(frozen=True)
class SegmentForces:
    """Solution of the closure problem: the force carried by each segment.

    Attributes
    ----------
    F : ndarray, shape (n + 1, dim)
        Force vector of each segment, N, pointing from its start node to its end node
        (``F_r = T_r e_r``).
    T : ndarray, shape (n + 1,)
        Segment tensions ``T_r = |F_r|``, N.
    e : ndarray, shape (n + 1, dim)
        Unit vectors along the segments, ``e_r``.
    length : ndarray, shape (n + 1,)
        Segment lengths in the solved configuration, ``l_r = S_r (1 + T_r / EA)``, m.
    closure_error : float
        ``|sum_r l_r e_r - c|`` at the solution (``c`` the chord), m: the solver's residual.
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
    def F1(self) -> np.ndarray:
        """Force vector carried by segment 1 (the reaction pulling on support A, negated)."""
        return self.F[0]


def cumulative_loads(P: np.ndarray, dim: int = 2) -> np.ndarray:
    """``Q_k = sum_{j<k} P_j``, so that segment ``k`` carries ``F_1 - Q_k``.

    Parameters
    ----------
    P : ndarray, shape (dim n,)
        Nodal loads in DOF order, N.
    dim : int
        Components per node.

    Returns
    -------
    ndarray, shape (n + 1, dim)
    """
    Pn = np.asarray(P, dtype=float).reshape(-1, dim)
    Q = np.zeros((Pn.shape[0] + 1, dim))
    np.cumsum(Pn, axis=0, out=Q[1:])
    return Q


def force_scale(cable: Cable, Q: np.ndarray) -> float:
    """The load scale of the scaled problem, N: the largest cumulative load, or for an unloaded
    pretensioned cable its tension scale."""
    scale = float(np.max(np.abs(Q))) if Q.size else 0.0
    if scale > 0.0:
        return scale
    # No loads: only a pretensioned (shorter than chord) elastic cable carries tension.
    if cable.compliance > 0.0:
        strain = max(cable.chord_length / cable.total_length - 1.0, 1e-12)
        return cable.EA * strain
    return 1.0


@dataclass(frozen=True)
class ScaledClosure:
    """The closure problem in units of the chord length ``ell`` and a load scale ``p``."""

    ell: float
    p: float
    S: np.ndarray
    c: tuple
    Q: np.ndarray
    eps: float
    tol: float

    @classmethod
    def of(cls, cable: Cable, Q: np.ndarray, compliance: float) -> "ScaledClosure":
        ell = cable.chord_length
        p = force_scale(cable, Q)
        S = np.ascontiguousarray(cable.S / ell)
        return cls(ell=ell, p=p, S=S, c=tuple(float(x) for x in cable.chord / ell), Q=np.ascontiguousarray(Q / p),
                   eps=compliance * p, tol=CLOSURE_RTOL * max(1.0, float(S.sum())))

    def rebased(self, r: int) -> "ScaledClosure":
        """The same problem with segment ``r``'s force as the unknown: ``Q_k - Q_r`` for ``Q_k``."""
        return replace(self, Q=np.ascontiguousarray(self.Q - self.Q[r]))

    def forces(self, F: np.ndarray):
        """``(F_k, T_k, e_k, l_k, closure error)`` at the scaled segment-1 force ``F``."""
        n1, dim = self.Q.shape
        Fk, e, T, lk = np.empty((n1, dim)), np.empty((n1, dim)), np.empty(n1), np.empty(n1)
        err = cl.segment_forces(self.S, self.Q, self.eps, self.c, F, Fk, T, e, lk)
        return Fk, T, e, lk, err


def slack_segment(S: np.ndarray, Q: np.ndarray, c: np.ndarray, eps: float, zero_tol: float) -> int | None:
    """A segment (0-based) that would be slack: the minimum of Phi at a kink ``F = Q_k``, or None.

    At ``F = Q_k`` the subdifferential of Phi is the gradient of the smooth terms plus a ball of
    radius ``sum S_m`` over the segments m whose force vanishes there. The kink is the minimiser
    (segment k slack) exactly when the gradient lies inside that ball. O(n^2) work, done in
    blocks of kinks so that the temporaries stay small (n = 2000: 2 MB, not 200 MB).
    """
    for start in range(0, Q.shape[0], SLACK_BLOCK):
        Qk = Q[start : start + SLACK_BLOCK]
        diff = Qk[:, None, :] - Q[None, :, :]  # F_m at the kink of k: Q_k - Q_m, shape (k, m, dim)
        T = np.sqrt(np.einsum("kmi,kmi->km", diff, diff))
        zero = T <= zero_tol
        Tsafe = np.where(zero, 1.0, T)
        coef = np.where(zero, 0.0, S[None, :] * (1.0 / Tsafe + eps))
        g_rest = np.einsum("km,kmi->ki", coef, diff) - np.asarray(c)
        radius = (S[None, :] * zero).sum(axis=1)
        inside = np.sqrt(np.einsum("ki,ki->k", g_rest, g_rest)) <= radius * (1.0 + 1e-12)
        if np.any(inside):
            return start + int(np.flatnonzero(inside)[0])
    return None


def _raise_if_slack(cable: Cable, sc: ScaledClosure) -> None:
    zero_tol = 1e-13 * max(1.0, float(np.abs(sc.Q).max()) if sc.Q.size else 1.0)
    k = slack_segment(sc.S, sc.Q, np.array(sc.c), sc.eps, zero_tol)
    if k is not None:
        raise SlackSegmentError(
            f"Segment {k + 1} (natural length {cable.S[k]:.6g} m) would be slack: under these "
            "loads the cable reaches equilibrium only with zero tension in it. Check the signs "
            "and sizes of the loads on its end nodes, or shorten the cable (cable.S).",
            segment=k + 1,
        )


def _failure(code: int, sc: ScaledClosure, F: np.ndarray) -> ConvergenceError:
    with np.errstate(all="ignore"):
        _, T, _, _, err = sc.forces(F)
    where = f"closure error {err * sc.ell:.3g} m"
    tmin = f"smallest tension {np.nanmin(T) * sc.p:.3g} N" if np.isfinite(T).any() else "tensions not finite"
    if code == cl.FAIL_ITERATIONS:
        return ConvergenceError(
            f"The static solver did not converge in {MAX_NEWTON} Newton iterations ({where}). The loads may "
            f"nearly slacken a segment ({tmin}); check the loads and segment lengths.")
    if code == cl.FAIL_STALLED:
        return ConvergenceError(
            f"The static solver's line search stalled ({where}); the loads may nearly slacken a segment ({tmin}).")
    return ConvergenceError(f"The static solver's Newton iteration failed ({where}); a segment may be slack ({tmin}).")


def solve_segment_forces(cable: Cable, P: np.ndarray, elastic: bool = True, F_start: np.ndarray | None = None,
                         check_slack: bool = True) -> SegmentForces:
    """Solve the closure problem by damped Newton on the complementary energy.

    Parameters
    ----------
    cable : Cable
    P : ndarray, shape (dim n,)
        Nodal loads, N, in DOF order.
    elastic : bool
        Include the elastic term ``S |F|^2 / (2 EA)`` (exact elastic equilibrium); ``False``
        solves the inextensible cable.
    F_start : ndarray, shape (dim,), optional
        Starting guess for the force in segment 1 (a warm start from a nearby solution).
    check_slack : bool
        Report a segment that would be slack (an exact test, ``O(n^2)``, run only when Newton
        fails or ends next to a kink); turn off only for warm-started solves inside a loop.

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
    compliance = cable.compliance if elastic else 0.0
    Q = cumulative_loads(P, cable.dim)
    if Q.shape[0] != cable.n_segments:
        raise ValueError(f"expected {cable.n_dof} load components, got {cable.dim * (Q.shape[0] - 1)}")
    if compliance == 0.0 and not cable.spans_slack:
        raise ConvergenceError(
            f"The natural segment lengths sum to {cable.total_length:.15g} m, not more than the "
            f"chord {cable.chord_length:.15g} m between the supports, so an inextensible cable "
            "cannot span them. Lengthen cable.S, or use the exact analysis for a pretensioned cable.",
        )
    sc = ScaledClosure.of(cable, Q, compliance)
    # Phi is convex, and strictly so where it is smooth (segments not all parallel), so a
    # stationary point with every segment in tension is its only minimiser and no segment is
    # slack: the O(n^2) slack check runs only when Newton fails or ends next to a kink.
    F = np.zeros(cable.dim)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # a slack case may run off to infinity
        if F_start is None:
            started = cl.start_along_chord(sc.S, sc.Q, sc.eps, sc.c, F)
        else:
            F[:] = np.asarray(F_start, dtype=float) / sc.p
            started = True
        code = cl.minimise(sc.S, sc.Q, sc.eps, sc.c, F, sc.tol, MAX_NEWTON) if started else cl.FAIL_ITERATIONS
        Fk, T, e, lk, err = sc.forces(F)
        if started and code in (cl.FAIL_ITERATIONS, cl.FAIL_STALLED) and np.isfinite(err):
            # A segment force far below the loads is the difference F - Q_k of two much larger
            # vectors: its direction carries their rounding amplified by |Q_k| / T_k, and the
            # closure error stalls above its tolerance. Solve again with that segment's force as
            # the unknown (Q_k - Q_r for Q_k), which takes no difference for it.
            r = int(np.argmin(T))
            F, sc = Fk[r].copy(), sc.rebased(r)
            code = cl.minimise(sc.S, sc.Q, sc.eps, sc.c, F, sc.tol, MAX_NEWTON)
            Fk, T, e, lk, err = sc.forces(F)
    if not started or code < 0 or not np.isfinite(err):
        if check_slack:
            _raise_if_slack(cable, sc)
        if not started:
            raise ConvergenceError("could not bracket the tension of the cable")
        raise _failure(code if code < 0 else cl.FAIL_SLACK, sc, F)
    if check_slack and T.min() <= SLACK_SUSPECT * T.max():
        _raise_if_slack(cable, sc)
    return SegmentForces(F=Fk * sc.p, T=T * sc.p, e=e, length=lk * sc.ell, closure_error=err * sc.ell, iterations=code)
