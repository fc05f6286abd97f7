"""Static equilibrium of a weightless cable fixed at both ends.

Three models (THEORY.md section 2):

- **inextensible** -- configuration ``x(P)`` and tensions ``T(P)`` of the inextensible cable;
- **approximate elastic** -- the paper's approximate analysis: natural state ``x(P)``, elastic
  displacements ``u`` first order in ``1/EA`` (eq. 7), flexibilities ``D`` and ``f`` (eq. 8);
- **exact elastic** -- equilibrium of the deformed configuration ``y`` with
  ``T_r = EA (l_r - S_r) / S_r``.

All three are solved the same way. With both ends fixed every segment force vector follows from
the force ``F`` carried by segment 1, ``F_{k+1} = F_k - P_k``, and closure of the polygon is the
stationarity condition of the convex complementary energy (two unknowns, whatever ``n`` is)::

    Phi(F) = sum_k [ S_k |F_k| + S_k |F_k|^2 / (2 EA) ] - F . (L, H)

Every derivative (``B = dT/dP``, ``D = dx/dP``, ``f = du/dP``, ``dy/dP``) follows from implicit
differentiation of ``grad Phi = 0``; none uses finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .cable import Cable
from .errors import ConvergenceError, SlackSegmentError

#: Closure tolerance of the Newton solve, relative to the larger of chord and total length.
CLOSURE_RTOL = 1e-12
_MAX_NEWTON = 200


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
    minimiser (segment k slack) exactly when the gradient lies inside that disk.
    """
    diff = Q[:, None, :] - Q[None, :, :]  # F_m at the kink of k: Q_k - Q_m, shape (k, m, 2)
    T = np.hypot(diff[..., 0], diff[..., 1])
    zero = T <= zero_tol
    Tsafe = np.where(zero, 1.0, T)
    coef = np.where(zero, 0.0, S[None, :] * (1.0 / Tsafe + eps))
    g_rest = np.einsum("km,kmi->ki", coef, diff) - c
    radius = (S[None, :] * zero).sum(axis=1)
    inside = np.hypot(g_rest[:, 0], g_rest[:, 1]) <= radius * (1.0 + 1e-12)
    if np.any(inside):
        return int(np.flatnonzero(inside)[0])
    return None


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
        Test first whether some segment would be slack (exact, ``O(n^2)``); turn off only for
        warm-started solves inside a time loop.

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
    if eps_dim == 0.0 and cable.total_length <= cable.chord_length:
        raise ConvergenceError(
            f"The natural segment lengths sum to {cable.total_length:.6g} m, not more than the "
            f"chord {cable.chord_length:.6g} m between the supports, so an inextensible cable "
            "cannot span them. Lengthen cable.S, or use the exact analysis for a pretensioned cable.",
        )

    # Work in units of the chord length and a load scale, so tolerances are scale-free.
    ell = cable.chord_length
    p = _force_scale(cable, Q)
    S = cable.S / ell
    c = cable.chord / ell
    Qh = Q / p
    eps = eps_dim * p
    tol = CLOSURE_RTOL * max(1.0, S.sum())

    if check_slack:
        k = _check_slack(S, Qh, c, eps, zero_tol=1e-13 * max(1.0, np.abs(Qh).max()))
        if k is not None:
            raise SlackSegmentError(
                f"Segment {k + 1} (natural length {cable.S[k]:.6g} m) would be slack: under these "
                "loads the cable reaches equilibrium only with zero tension in it. Check the signs "
                "and sizes of the loads on its end nodes, or shorten the cable (cable.S).",
                segment=k + 1,
            )

    def state(F):
        Fk = F - Qh
        T = np.hypot(Fk[:, 0], Fk[:, 1])
        T = np.maximum(T, 1e-300)
        e = Fk / T[:, None]
        lk = S * (1.0 + eps * T)
        g = lk @ e - c
        phi = float(S @ T + 0.5 * eps * (S @ (T * T)) - F @ c)
        return T, e, lk, g, phi

    if F_start is None:
        # Minimise Phi along the chord direction through the mean segment force: a 1-D convex
        # problem whose solution is a good, kink-free start for the 2-D Newton iteration.
        base = Qh.mean(axis=0)
        u = c / np.hypot(*c)

        def slope(s):
            return state(base + s * u)[3] @ u

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
        F = base + brentq(slope, lo, hi, xtol=1e-14, rtol=1e-12) * u
    else:
        F = np.asarray(F_start, dtype=float) / p

    zero_tol = 1e-13 * max(1.0, np.abs(Qh).max())

    def escape_kink(F):
        # Near F = Q_k (segment k carrying almost nothing) Newton's quadratic model is useless.
        # At the kink itself the steepest-descent direction is exactly -g_rest (the gradient of
        # the other terms), a descent direction because the segment is not slack
        # (|g_rest| > S_k): minimise Phi along that ray, a 1-D convex problem.
        k = int(np.argmin(state(F)[0]))
        diff = Qh[k] - Qh
        Tm = np.hypot(diff[:, 0], diff[:, 1])
        zero = Tm <= zero_tol
        coef = np.where(zero, 0.0, S * (1.0 / np.where(zero, 1.0, Tm) + eps))
        g_rest = coef @ diff - c
        u = -g_rest / np.hypot(*g_rest)

        def slope(a):
            return state(Qh[k] + a * u)[3] @ u

        hi = 1e-6
        while slope(hi) < 0.0:
            hi *= 4.0
            if hi > 1e30:
                raise ConvergenceError("could not bracket the tension of the cable")
        return Qh[k] + brentq(slope, 0.0, hi, xtol=1e-15, rtol=1e-13) * u

    T, e, lk, g, phi = state(F)
    gnorm = float(np.hypot(*g))
    it = 0
    escapes = 0
    while gnorm > tol:
        if it >= _MAX_NEWTON:
            raise ConvergenceError(
                f"The static solver did not converge in {_MAX_NEWTON} Newton iterations "
                f"(closure error {gnorm * ell:.3g} m). The loads may nearly slacken a segment "
                f"(smallest tension {T.min() * p:.3g} N); check the loads and segment lengths."
            )
        it += 1
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
        d = -np.linalg.solve(Hm, g)
        slope0 = float(g @ d)
        step = 1.0
        while True:
            Fn = F + step * d
            Tn, en, lkn, gn, phin = state(Fn)
            gnn = float(np.hypot(*gn))
            if phin <= phi + 1e-4 * step * slope0 or gnn < 0.5 * gnorm:
                break
            step *= 0.5
            if step < 1e-10:
                break
        near_kink = Tn.min() < 1e-9 * max(1.0, np.hypot(*Fn))
        if (step < 1e-10 or near_kink) and escapes < 50:
            escapes += 1
            Fn = escape_kink(Fn if near_kink else F)
            Tn, en, lkn, gn, phin = state(Fn)
            gnn = float(np.hypot(*gn))
        elif step < 1e-10:
            raise ConvergenceError(
                "The static solver's line search stalled (closure error "
                f"{gnorm * ell:.3g} m); the loads may nearly slacken a segment "
                f"(smallest tension {T.min() * p:.3g} N)."
            )
        F, T, e, lk, g, phi, gnorm = Fn, Tn, en, lkn, gn, phin, gnn

    Fk = (F - Qh) * p
    return SegmentForces(
        F=Fk,
        T=T * p,
        e=e,
        length=lk * ell,
        closure_error=gnorm * ell,
        iterations=it,
    )


# ----------------------------------------------------------------------------------------------
# Implicit derivatives
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Tangents:
    a: np.ndarray  # (n+1, 2n): rows t_k . dF_k/dP (transverse force derivatives)
    b: np.ndarray  # (n+1, 2n): rows e_k . dF_k/dP = dT_k/dP  (the matrix B)
    H: np.ndarray  # (2, 2): Hessian of Phi
    dydP: np.ndarray  # (2n, 2n): derivative of the node positions
    gt: np.ndarray  # (n+1,): transverse segment compliance l_k / T_k
    ge: np.ndarray  # (n+1,): axial segment compliance S_k / EA


def _tangents(cable: Cable, seg: SegmentForces, compliance: float) -> _Tangents:
    n = cable.n_nodes
    e, t, T = seg.e, seg.normal, seg.T
    gt = seg.length / T
    ge = cable.S * compliance
    # 2x2 compliance of each segment, G_k = d(l_k e_k)/dF_k.
    G = gt[:, None, None] * t[:, :, None] * t[:, None, :] + ge[:, None, None] * e[:, :, None] * e[:, None, :]
    H = G.sum(axis=0)
    # dF/dP_j = H^-1 sum_{k>j} G_k  (segments after node j feel P_j with a minus sign).
    suffix = np.cumsum(G[::-1], axis=0)[::-1]  # suffix[k] = sum_{m>=k} G_m
    W = np.linalg.solve(H, np.concatenate(list(suffix[1 : n + 1]), axis=1))  # (2, 2n)
    # dF_k/dP = W - E_k, E_k = identity blocks on nodes j < k.
    below = np.tri(n + 1, n, k=-1, dtype=bool)  # [k, j] = j < k
    a = t @ W - (below[:, :, None] * t[:, None, :]).reshape(n + 1, 2 * n)
    b = e @ W - (below[:, :, None] * e[:, None, :]).reshape(n + 1, 2 * n)
    # Node r sits at sum_{k<=r} l_k e_k, so dy_r/dP = sum_{k<=r} G_k dF_k/dP.
    contrib = gt[:, None, None] * t[:, :, None] * a[:, None, :] + ge[:, None, None] * e[:, :, None] * b[:, None, :]
    dydP = np.cumsum(contrib, axis=0)[:n].reshape(2 * n, 2 * n)
    return _Tangents(a=a, b=b, H=H, dydP=dydP, gt=gt, ge=ge)


def _positions(seg: SegmentForces, n: int) -> np.ndarray:
    return np.cumsum(seg.length[:, None] * seg.e, axis=0)[:n].reshape(-1)


def _sym(A: np.ndarray) -> np.ndarray:
    return 0.5 * (A + A.T)


# ----------------------------------------------------------------------------------------------
# The three models
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InextensibleEquilibrium:
    """Equilibrium of the inextensible cable under loads ``P``.

    Attributes
    ----------
    P : ndarray, shape (2n,)
        Nodal loads, N.
    x : ndarray, shape (2n,)
        Node coordinates ``x(P)``, m (homogeneous of order 0 in P).
    T : ndarray, shape (n + 1,)
        Segment tensions ``T(P)``, N (homogeneous of order 1).
    B : ndarray, shape (n + 1, 2n)
        Tangent transformation ``B = dT/dP`` (eq. 7).
    D : ndarray, shape (2n, 2n)
        Tangent configurational flexibility ``D = dx/dP``, m/N; symmetric, ``D P = 0``.
    omega_c : float
        Configurational complementary energy ``Omega_c = T . S``, J.
    segments : SegmentForces
        The underlying closure solution.
    """

    P: np.ndarray
    x: np.ndarray
    T: np.ndarray
    B: np.ndarray
    D: np.ndarray
    omega_c: float
    segments: SegmentForces

    @property
    def F_end(self) -> np.ndarray:
        """Force vector carried by the last segment, N (pulls on support B)."""
        return self.segments.F[-1]


@dataclass(frozen=True)
class ApproximateEquilibrium:
    """The paper's approximate elastic analysis (first order in ``1/EA``).

    Attributes
    ----------
    P, x, T, B, D
        As in :class:`InextensibleEquilibrium`.
    u : ndarray, shape (2n,)
        Elastic displacements ``u_i = (1/EA) sum_r T_r S_r B_ri`` (eq. 7), m.
    y : ndarray, shape (2n,)
        Deformed coordinates ``y = x + u``, m.
    f : ndarray, shape (2n, 2n)
        Tangent elastic flexibility ``f = du/dP`` (eq. 8), m/N.
    N : ndarray, shape (2n, 2n)
        Elasto-configurational flexibility ``N = D + f``, m/N.
    K : ndarray, shape (2n, 2n)
        Tangent stiffness ``K = N^-1``, N/m.
    omega_c, omega_e : float
        Configurational and elastic complementary energies, J.
    """

    P: np.ndarray
    x: np.ndarray
    T: np.ndarray
    B: np.ndarray
    D: np.ndarray
    u: np.ndarray
    y: np.ndarray
    f: np.ndarray
    N: np.ndarray
    K: np.ndarray
    omega_c: float
    omega_e: float
    inextensible: InextensibleEquilibrium


@dataclass(frozen=True)
class ExactEquilibrium:
    """Exact elastic equilibrium of the deformed cable.

    Attributes
    ----------
    P : ndarray, shape (2n,)
        Nodal loads, N.
    y : ndarray, shape (2n,)
        Deformed node coordinates, m.
    T : ndarray, shape (n + 1,)
        Segment tensions ``EA (l_r - S_r) / S_r``, N.
    length : ndarray, shape (n + 1,)
        Stretched segment lengths ``l_r``, m.
    K : ndarray, shape (2n, 2n)
        Tangent stiffness of the deformed configuration, N/m.
    dydP : ndarray, shape (2n, 2n)
        Tangent flexibility ``dy/dP`` from implicit differentiation, m/N (equals ``K^-1``).
    segments : SegmentForces
    """

    P: np.ndarray
    y: np.ndarray
    T: np.ndarray
    length: np.ndarray
    K: np.ndarray
    dydP: np.ndarray
    segments: SegmentForces


def inextensible_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> InextensibleEquilibrium:
    """Configuration and tensions of the inextensible cable under loads ``P``.

    Parameters
    ----------
    cable : Cable
        Its ``EA`` is ignored.
    P : ndarray, shape (2n,)
        Nodal loads, N.
    F_start : ndarray, shape (2,), optional
        Warm start: force in segment 1 of a nearby solution.
    check_slack : bool
        See :func:`solve_segment_forces`.

    Returns
    -------
    InextensibleEquilibrium
    """
    P = np.asarray(P, dtype=float)
    seg = solve_segment_forces(cable, P, elastic=False, F_start=F_start, check_slack=check_slack)
    tg = _tangents(cable, seg, 0.0)
    x = _positions(seg, cable.n_nodes)
    return InextensibleEquilibrium(
        P=P, x=x, T=seg.T, B=tg.b, D=_sym(tg.dydP), omega_c=float(seg.T @ cable.S), segments=seg
    )


def elastic_flexibility(cable: Cable, inext: InextensibleEquilibrium) -> np.ndarray:
    """Tangent elastic flexibility ``f = du/dP`` of the approximate analysis (eq. 8).

    ``f_ij = (1/EA) sum_r S_r [B_ri B_rj + T_r d^2 T_r / dP_i dP_j]``, with the second
    derivatives of the tensions from twice differentiating the closure condition.

    Parameters
    ----------
    cable : Cable
    inext : InextensibleEquilibrium

    Returns
    -------
    ndarray, shape (2n, 2n)
    """
    seg = inext.segments
    tg = _tangents(cable, seg, 0.0)
    S, T, e, t = cable.S, seg.T, seg.e, seg.normal
    a, b = tg.a, tg.b
    # Contracting d^2F/dP^2 with w = sum_k S_k T_k e_k needs only v = H^-1 w.
    v = np.linalg.solve(tg.H, (S * T) @ e)
    c1 = S * (t @ v) / T**2
    c2 = S * (e @ v) / T**2
    f = b.T @ (S[:, None] * b) + a.T @ ((S + c2)[:, None] * a)
    cross = a.T @ (c1[:, None] * b)
    f += cross + cross.T
    return _sym(f) * cable.compliance


def approximate_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> ApproximateEquilibrium:
    """The paper's approximate elastic analysis under loads ``P``.

    Parameters
    ----------
    cable : Cable
    P : ndarray, shape (2n,)
        Nodal loads, N.
    F_start, check_slack
        See :func:`inextensible_equilibrium`.

    Returns
    -------
    ApproximateEquilibrium
    """
    inext = inextensible_equilibrium(cable, P, F_start=F_start, check_slack=check_slack)
    S, T = cable.S, inext.T
    u = inext.B.T @ (S * T) * cable.compliance
    f = elastic_flexibility(cable, inext)
    N = inext.D + f
    K = _sym(np.linalg.inv(N))
    return ApproximateEquilibrium(
        P=inext.P,
        x=inext.x,
        T=T,
        B=inext.B,
        D=inext.D,
        u=u,
        y=inext.x + u,
        f=f,
        N=N,
        K=K,
        omega_c=inext.omega_c,
        omega_e=float(0.5 * (T * T) @ S * cable.compliance),
        inextensible=inext,
    )


def exact_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> ExactEquilibrium:
    """Exact elastic equilibrium of the deformed cable under loads ``P``.

    Parameters
    ----------
    cable : Cable
        Must have finite ``EA``.
    P : ndarray, shape (2n,)
        Nodal loads, N.
    F_start, check_slack
        See :func:`solve_segment_forces`.

    Returns
    -------
    ExactEquilibrium
    """
    if cable.compliance == 0.0:
        raise ValueError("the exact elastic analysis needs a finite EA")
    P = np.asarray(P, dtype=float)
    seg = solve_segment_forces(cable, P, elastic=True, F_start=F_start, check_slack=check_slack)
    tg = _tangents(cable, seg, cable.compliance)
    y = _positions(seg, cable.n_nodes)
    return ExactEquilibrium(
        P=P,
        y=y,
        T=seg.T,
        length=seg.length,
        K=tangent_stiffness(cable, y),
        dydP=_sym(tg.dydP),
        segments=seg,
    )


# ----------------------------------------------------------------------------------------------
# The deformed configuration as the unknown (exact analysis, dynamics)
# ----------------------------------------------------------------------------------------------
def segment_geometry(cable: Cable, y: np.ndarray):
    """Lengths, unit vectors and tensions of the segments of configuration ``y``.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (2n,)
        Node coordinates, m.

    Returns
    -------
    length : ndarray, shape (n + 1,)
        Segment lengths ``l_r``, m.
    e : ndarray, shape (n + 1, 2)
        Unit vectors along the segments.
    T : ndarray, shape (n + 1,)
        Tensions ``EA (l_r - S_r) / S_r``, N; negative values mean the segment is shorter than
        its natural length (slack: the tension-only cable carries nothing there).
    """
    pts = np.empty((cable.n_nodes + 2, 2))
    pts[0] = 0.0
    pts[1:-1] = np.reshape(y, (-1, 2))
    pts[-1] = cable.chord
    d = np.diff(pts, axis=0)
    length = np.hypot(d[:, 0], d[:, 1])
    e = d / length[:, None]
    T = cable.EA * (length - cable.S) / cable.S
    return length, e, T


def resisting_force(cable: Cable, y: np.ndarray) -> np.ndarray:
    """Internal resisting nodal forces ``P(y)`` of the exact analysis, N.

    ``P_r = T_r e_r - T_{r+1} e_{r+1}`` (eq. 2) with ``T = EA (l - S) / S``.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (2n,)

    Returns
    -------
    ndarray, shape (2n,)
    """
    _, e, T = segment_geometry(cable, y)
    F = T[:, None] * e
    return (F[:-1] - F[1:]).reshape(-1)


def tangent_stiffness(cable: Cable, y: np.ndarray) -> np.ndarray:
    """Tangent stiffness ``K = dP/dy`` of the exact analysis at configuration ``y``, N/m.

    ``K = sum_r [ (EA/S_r) e e^T + (T_r / l_r)(I - e e^T) ]`` assembled over the segments.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (2n,)

    Returns
    -------
    ndarray, shape (2n, 2n)
    """
    n = cable.n_nodes
    length, e, T = segment_geometry(cable, y)
    I2 = np.eye(2)
    ks = (cable.EA / cable.S)[:, None, None] * e[:, :, None] * e[:, None, :] + (T / length)[
        :, None, None
    ] * (I2 - e[:, :, None] * e[:, None, :])
    K = np.zeros((2 * n, 2 * n))
    for r in range(n + 1):
        i, j = r - 1, r  # segment r joins node r-1 to node r (0 and n+1 are supports)
        if i >= 0:
            K[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] += ks[r]
        if j < n:
            K[2 * j : 2 * j + 2, 2 * j : 2 * j + 2] += ks[r]
        if i >= 0 and j < n:
            K[2 * i : 2 * i + 2, 2 * j : 2 * j + 2] -= ks[r]
            K[2 * j : 2 * j + 2, 2 * i : 2 * i + 2] -= ks[r]
    return K
