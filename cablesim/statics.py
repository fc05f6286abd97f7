"""Static equilibrium of a weightless cable fixed at both ends.

Three models (``docs/theory.md``, section 2):

- **inextensible** -- configuration ``x(P)`` and tensions ``T(P)`` of the inextensible cable;
- **approximate elastic** -- the paper's approximate analysis: natural state ``x(P)``, elastic
  displacements ``u`` first order in ``1/EA`` (eq. 7), flexibilities ``D`` and ``f`` (eq. 8);
- **exact elastic** -- equilibrium of the deformed configuration ``y`` with
  ``T_r = EA (l_r - S_r) / S_r``.

All three are solved the same way, by :func:`cablesim.closure.solve_segment_forces` (Newton's
method on the convex complementary energy, two unknowns whatever ``n`` is). Every derivative (``B = dT/dP``, ``D = dx/dP``, ``f = du/dP``, ``dy/dP``) follows from implicit
differentiation of ``grad Phi = 0``; none uses finite differences.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from .cable import Cable
from .closure import SegmentForces, solve_segment_forces

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
        ``B`` and ``D`` are dense: they are computed on first use.
    omega_c : float
        Configurational complementary energy ``Omega_c = T . S``, J.
    segments : SegmentForces
        The underlying closure solution.
    """

    P: np.ndarray
    x: np.ndarray
    T: np.ndarray
    omega_c: float
    segments: SegmentForces
    cable: Cable

    @functools.cached_property
    def _tangents(self) -> _Tangents:
        return _tangents(self.cable, self.segments, 0.0)

    @property
    def B(self) -> np.ndarray:
        """Tangent transformation ``B = dT/dP``."""
        return self._tangents.b

    @functools.cached_property
    def D(self) -> np.ndarray:
        """Tangent configurational flexibility ``D = dx/dP``, m/N."""
        return _sym(self._tangents.dydP)

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
        Tangent stiffness of the deformed configuration, N/m; dense, so computed on first use
        (a heavy cable works with :attr:`K_band`).
    K_band : ndarray, shape (4, 2n)
        The same in symmetric lower band form (:func:`tangent_stiffness_band`), O(n).
    dydP : ndarray, shape (2n, 2n)
        Tangent flexibility ``dy/dP`` from implicit differentiation, m/N (equals ``K^-1``);
        computed on first use (a dense O(n^2) product that large cables seldom need).
    segments : SegmentForces
    """

    P: np.ndarray
    y: np.ndarray
    T: np.ndarray
    length: np.ndarray
    segments: SegmentForces
    cable: Cable

    @functools.cached_property
    def K(self) -> np.ndarray:
        """Dense tangent stiffness, N/m."""
        return tangent_stiffness(self.cable, self.y)

    @functools.cached_property
    def K_band(self) -> np.ndarray:
        """Tangent stiffness in lower band form, N/m."""
        return tangent_stiffness_band(self.cable, self.y)

    @functools.cached_property
    def dydP(self) -> np.ndarray:
        """Tangent flexibility ``dy/dP``, m/N."""
        return _sym(_tangents(self.cable, self.segments, self.cable.compliance).dydP)


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
    x = _positions(seg, cable.n_nodes)
    return InextensibleEquilibrium(P=P, x=x, T=seg.T, omega_c=float(seg.T @ cable.S), segments=seg, cable=cable)


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
    y = _positions(seg, cable.n_nodes)
    return ExactEquilibrium(P=P, y=y, T=seg.T, length=seg.length, segments=seg, cable=cable)


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


def tangent_stiffness_band(cable: Cable, y: np.ndarray) -> np.ndarray:
    """The tangent stiffness of :func:`tangent_stiffness` in symmetric lower band form, N/m.

    ``K`` is block-tridiagonal with 2x2 blocks, so its bandwidth is 3: ``band[d, j] = K[j + d, j]``
    for ``d = 0..3`` (the layout of ``scipy.linalg.eig_banded(lower=True)``); O(n) storage.

    Returns
    -------
    ndarray, shape (4, 2n)
    """
    n = cable.n_nodes
    length, e, T = segment_geometry(cable, y)
    ks = (cable.EA / cable.S)[:, None, None] * e[:, :, None] * e[:, None, :] + (T / length)[
        :, None, None
    ] * (np.eye(2) - e[:, :, None] * e[:, None, :])
    diag = ks[:-1] + ks[1:]  # node j is the end of segment j and the start of segment j+1
    off = -ks[1:-1]  # coupling of node j+1 (rows) to node j (columns)
    band = np.zeros((4, 2 * n))
    band[0, 0::2], band[0, 1::2] = diag[:, 0, 0], diag[:, 1, 1]
    band[1, 0::2] = diag[:, 1, 0]
    band[1, 1:-1:2] = off[:, 0, 1]  # K[2j+2, 2j+1]
    band[2, 0:-2:2], band[2, 1:-2:2] = off[:, 0, 0], off[:, 1, 1]  # K[2j+2, 2j], K[2j+3, 2j+1]
    band[3, 0:-3:2] = off[:, 1, 0]  # K[2j+3, 2j]
    return band


def band_to_dense(band: np.ndarray) -> np.ndarray:
    """The full symmetric matrix of a lower band form (``band[d, j] = A[j + d, j]``)."""
    m = band.shape[1]
    A = np.zeros((m, m))
    for d in range(band.shape[0]):
        idx = np.arange(m - d)
        A[idx + d, idx] = band[d, : m - d]
        A[idx, idx + d] = band[d, : m - d]
    return A
