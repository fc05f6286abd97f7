"""Static equilibrium of a weightless cable fixed at both ends.

Three models (``docs/theory.md``, section 2):

- **inextensible** -- configuration ``x(P)`` and tensions ``T(P)`` of the inextensible cable;
- **approximate elastic** -- the paper's approximate analysis: natural state ``x(P)``, elastic
  displacements ``u`` first order in ``1/EA`` (eq. 7), flexibilities ``D`` and ``f`` (eq. 8);
- **exact elastic** -- equilibrium of the deformed configuration ``y`` with
  ``T_r = EA (l_r - S_r) / S_r``.

All three are solved the same way, by :func:`cablesim.mechanics.equilibrium.solve_segment_forces`
(Newton's method on the convex complementary energy, ``dim`` unknowns whatever ``n`` is). Every
derivative (``B = dT/dP``, ``D = dx/dP``, ``f = du/dP``, ``dy/dP``) follows from implicit
differentiation of the closure, through the segment factors of
:mod:`cablesim.mechanics.flexibility` (O(n) per column); none uses finite differences. Forces and
stiffness of a deformed configuration come from :mod:`cablesim.mechanics.assembly`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .cable import Cable
from .mechanics import assembly as asm
from .mechanics import flexibility as fx
from .mechanics import segments as sg
from .mechanics.banded import band_half, band_rows
from .mechanics.equilibrium import SegmentForces, cumulative_loads, solve_segment_forces


def _positions(seg: SegmentForces, n: int) -> np.ndarray:
    """Node coordinates ``y_r = sum_{k<=r} l_k e_k`` (support A at the origin), m."""
    return np.cumsum(seg.length[:, None] * seg.e, axis=0)[:n].reshape(-1)


def _sym(A: np.ndarray) -> np.ndarray:
    return 0.5 * (A + A.T)


@dataclass(frozen=True)
class Factors:
    """Segment factors of an equilibrium (:func:`cablesim.mechanics.flexibility.segment_factors`):
    the flexibility's products and dense matrices, column by column."""

    fac: np.ndarray
    gi: np.ndarray
    dim: int

    @property
    def like(self) -> tuple:
        return (0.0,) * self.dim

    def dense(self, part: int) -> np.ndarray:
        """``N`` (part 0), ``D`` (1) or ``f`` (2), m/N."""
        nd = self.dim * (self.fac.shape[0] - 1)
        out = np.empty((nd, nd))
        fx.dense_flexibility(self.fac, self.gi, out, np.empty((self.fac.shape[0], self.dim)), self.like, part)
        return out

    def tension_rates(self) -> np.ndarray:
        """``B = dT/dP``, (n + 1, dim n)."""
        n1 = self.fac.shape[0]
        B = np.empty((n1, self.dim * (n1 - 1)))
        fx.dense_tension_rates(self.fac, self.gi, B, np.empty((n1, self.dim)), self.like)
        return B


def _inextensible_factors(cable: Cable, P: np.ndarray, seg: SegmentForces, EA: float) -> tuple[Factors, bool]:
    """Factors at the inextensible closure under P (``EA = inf``: forward products only)."""
    n, dim = cable.n_nodes, cable.dim
    fac, gi, _ = fx.factor_workspace(n, dim)
    T = np.empty(n + 1)
    ok = fx.segment_factors(np.ascontiguousarray(cable.S, dtype=float), float(EA), cumulative_loads(P, dim),
                            np.array(seg.F[0], dtype=float), T, fac, gi, (0.0,) * dim)
    return Factors(fac, gi, dim), bool(ok)


# ----------------------------------------------------------------------------------------------
# The three models
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InextensibleEquilibrium:
    """Equilibrium of the inextensible cable under loads ``P``.

    Attributes
    ----------
    P : ndarray, shape (dim n,)
        Nodal loads, N.
    x : ndarray, shape (dim n,)
        Node coordinates ``x(P)``, m (homogeneous of order 0 in P).
    T : ndarray, shape (n + 1,)
        Segment tensions ``T(P)``, N (homogeneous of order 1).
    B : ndarray, shape (n + 1, dim n)
        Tangent transformation ``B = dT/dP`` (eq. 7).
    D : ndarray, shape (dim n, dim n)
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
    def _factors(self) -> Factors:
        return _inextensible_factors(self.cable, self.P, self.segments, np.inf)[0]

    @functools.cached_property
    def B(self) -> np.ndarray:
        """Tangent transformation ``B = dT/dP``."""
        return self._factors.tension_rates()

    @functools.cached_property
    def D(self) -> np.ndarray:
        """Tangent configurational flexibility ``D = dx/dP``, m/N."""
        return _sym(self._factors.dense(1))

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
    u : ndarray, shape (dim n,)
        Elastic displacements ``u_i = (1/EA) sum_r T_r S_r B_ri`` (eq. 7), m.
    y : ndarray, shape (dim n,)
        Deformed coordinates ``y = x + u``, m.
    f : ndarray, shape (dim n, dim n)
        Tangent elastic flexibility ``f = du/dP`` (eq. 8), m/N.
    N : ndarray, shape (dim n, dim n)
        Elasto-configurational flexibility ``N = D + f``, m/N.
    K : ndarray, shape (dim n, dim n)
        Tangent stiffness ``K = N^-1``, N/m (from the factored inverse: no matrix is inverted).
    omega_c, omega_e : float
        Configurational and elastic complementary energies, J.

    The dense matrices are computed on first use (O(n^2) each).
    """

    P: np.ndarray
    x: np.ndarray
    T: np.ndarray
    u: np.ndarray
    y: np.ndarray
    omega_c: float
    omega_e: float
    inextensible: InextensibleEquilibrium
    factors: Factors

    @property
    def B(self) -> np.ndarray:
        return self.inextensible.B

    @property
    def D(self) -> np.ndarray:
        return self.inextensible.D

    @functools.cached_property
    def f(self) -> np.ndarray:
        """Tangent elastic flexibility ``f = du/dP``, m/N."""
        return _sym(self.factors.dense(2))

    @functools.cached_property
    def N(self) -> np.ndarray:
        """Elasto-configurational flexibility ``N = D + f``, m/N."""
        return _sym(self.factors.dense(0))

    @functools.cached_property
    def K(self) -> np.ndarray:
        """Tangent stiffness ``K = N^-1``, N/m."""
        nd, dim = self.P.size, self.factors.dim
        K = np.empty((nd, nd))
        fx.dense_stiffness(self.factors.fac, self.factors.gi, K, 0, 0, np.empty((band_rows(dim), nd)), np.empty((nd, dim)),
                           self.factors.like)
        return _sym(K)


@dataclass(frozen=True)
class ExactEquilibrium:
    """Exact elastic equilibrium of the deformed cable.

    Attributes
    ----------
    P : ndarray, shape (dim n,)
        Nodal loads, N.
    y : ndarray, shape (dim n,)
        Deformed node coordinates, m.
    T : ndarray, shape (n + 1,)
        Segment tensions ``EA (l_r - S_r) / S_r``, N.
    length : ndarray, shape (n + 1,)
        Stretched segment lengths ``l_r``, m.
    K : ndarray, shape (dim n, dim n)
        Tangent stiffness of the deformed configuration, N/m; dense, so computed on first use
        (a heavy cable works with :attr:`K_band`).
    K_band : ndarray, shape (2 dim, dim n)
        The same in symmetric lower band form (:func:`tangent_stiffness_band`), O(n).
    dydP : ndarray, shape (dim n, dim n)
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
        c, seg = self.cable, self.segments
        fac, gi, _ = fx.factor_workspace(c.n_nodes, c.dim)
        fx.exact_factors(np.ascontiguousarray(c.S, dtype=float), float(c.EA), np.ascontiguousarray(seg.F), seg.T,
                         seg.length, fac, gi, c.support_A)
        return _sym(Factors(fac, gi, c.dim).dense(0))


def inextensible_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> InextensibleEquilibrium:
    """Configuration and tensions of the inextensible cable under loads ``P``.

    Parameters
    ----------
    cable : Cable
        Its ``EA`` is ignored.
    P : ndarray, shape (dim n,)
        Nodal loads, N.
    F_start : ndarray, shape (dim,), optional
        Warm start: force in segment 1 of a nearby solution.
    check_slack : bool
        See :func:`~cablesim.mechanics.equilibrium.solve_segment_forces`.

    Returns
    -------
    InextensibleEquilibrium
    """
    P = np.asarray(P, dtype=float)
    seg = solve_segment_forces(cable, P, elastic=False, F_start=F_start, check_slack=check_slack)
    x = _positions(seg, cable.n_nodes)
    return InextensibleEquilibrium(P=P, x=x, T=seg.T, omega_c=float(seg.T @ cable.S), segments=seg, cable=cable)


def elastic_flexibility(cable: Cable, inext: InextensibleEquilibrium) -> np.ndarray:
    """Tangent elastic flexibility ``f = du/dP`` of the approximate analysis (eq. 8), m/N.

    ``f_ij = (1/EA) sum_r S_r [B_ri B_rj + T_r d^2 T_r / dP_i dP_j]``, from the segment factors
    (:mod:`cablesim.mechanics.flexibility`).
    """
    factors, _ = _inextensible_factors(cable, inext.P, inext.segments, cable.EA)
    return _sym(factors.dense(2))


def approximate_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> ApproximateEquilibrium:
    """The paper's approximate elastic analysis under loads ``P``.

    Parameters
    ----------
    cable : Cable
    P : ndarray, shape (dim n,)
        Nodal loads, N.
    F_start, check_slack
        See :func:`inextensible_equilibrium`.

    Returns
    -------
    ApproximateEquilibrium
    """
    inext = inextensible_equilibrium(cable, P, F_start=F_start, check_slack=check_slack)
    factors, ok = _inextensible_factors(cable, inext.P, inext.segments, cable.EA)
    if not ok:
        raise ValueError("the approximate analysis' flexibility is singular at this equilibrium")
    n, dim = cable.n_nodes, cable.dim
    x, u = np.empty(dim * n), np.empty(dim * n)
    fx.natural_and_elastic(np.ascontiguousarray(cable.S, dtype=float), float(cable.EA), factors.fac, factors.gi,
                           np.ascontiguousarray(inext.T), x, u, factors.like)
    S, T = cable.S, inext.T
    return ApproximateEquilibrium(
        P=inext.P,
        x=inext.x,
        T=T,
        u=u,
        y=inext.x + u,
        omega_c=inext.omega_c,
        omega_e=float(0.5 * (T * T) @ S * cable.compliance),
        inextensible=inext,
        factors=factors,
    )


def exact_equilibrium(
    cable: Cable, P: np.ndarray, F_start: np.ndarray | None = None, check_slack: bool = True
) -> ExactEquilibrium:
    """Exact elastic equilibrium of the deformed cable under loads ``P``.

    Parameters
    ----------
    cable : Cable
        Must have finite ``EA``.
    P : ndarray, shape (dim n,)
        Nodal loads, N.
    F_start, check_slack
        See :func:`~cablesim.mechanics.equilibrium.solve_segment_forces`.

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
    y : ndarray, shape (dim n,)
        Node coordinates, m.

    Returns
    -------
    length : ndarray, shape (n + 1,)
        Segment lengths ``l_r``, m.
    e : ndarray, shape (n + 1, dim)
        Unit vectors along the segments.
    T : ndarray, shape (n + 1,)
        Tensions ``EA (l_r - S_r) / S_r``, N; negative values mean the segment is shorter than
        its natural length (slack: the tension-only cable carries nothing there).
    """
    n1 = cable.n_segments
    length, e, T = np.empty(n1), np.empty((n1, cable.dim)), np.empty(n1)
    sg.segment_states(np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(cable.S, dtype=float),
                      float(cable.EA), cable.support_A, cable.support_B, length, e, T)
    return length, e, T


def resisting_force(cable: Cable, y: np.ndarray) -> np.ndarray:
    """Internal resisting nodal forces ``P(y)`` of the exact analysis, N.

    ``P_r = T_r e_r - T_{r+1} e_{r+1}`` (eq. 2) with ``T = EA (l - S) / S``.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (dim n,)

    Returns
    -------
    ndarray, shape (dim n,)
    """
    nd = cable.n_dof
    P, Kv = np.empty(nd), np.empty(nd)
    zero = (0.0,) * cable.dim
    asm.force_and_rate(np.ascontiguousarray(y, dtype=float), np.zeros(nd), np.ascontiguousarray(cable.S, dtype=float),
                       float(cable.EA), cable.support_A, cable.support_B, zero, zero, np.ones(cable.n_segments), P, Kv)
    return P


def tangent_stiffness(cable: Cable, y: np.ndarray) -> np.ndarray:
    """Tangent stiffness ``K = dP/dy`` of the exact analysis at configuration ``y``, N/m.

    ``K = sum_r [ (EA/S_r) e e^T + (T_r / l_r)(I - e e^T) ]`` assembled over the segments.

    Parameters
    ----------
    cable : Cable
    y : ndarray, shape (dim n,)

    Returns
    -------
    ndarray, shape (dim n, dim n)
    """
    nd = cable.n_dof
    P, K = np.empty(nd), np.empty((nd, nd))
    asm.force_and_stiffness(np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(cable.S, dtype=float),
                            float(cable.EA), cable.support_A, cable.support_B, np.ones(cable.n_segments), P, K)
    return K


def tangent_stiffness_band(cable: Cable, y: np.ndarray) -> np.ndarray:
    """The tangent stiffness of :func:`tangent_stiffness` in symmetric lower band form, N/m.

    ``K`` is block-tridiagonal with ``dim x dim`` blocks, so its bandwidth is ``2 dim - 1``:
    ``band[d, j] = K[j + d, j]`` for ``d = 0 .. 2 dim - 1`` (the layout of
    ``scipy.linalg.eig_banded(lower=True)``); O(n) storage.

    Returns
    -------
    ndarray, shape (2 dim, dim n)
    """
    nd, dim = cable.n_dof, cable.dim
    P, Kb = np.empty(nd), np.empty((band_rows(dim), nd))
    asm.force_and_stiffness_band(np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(cable.S, dtype=float),
                                 float(cable.EA), cable.support_A, cable.support_B, np.ones(cable.n_segments), P, Kb)
    return np.ascontiguousarray(Kb[band_half(dim):])


def band_to_dense(band: np.ndarray) -> np.ndarray:
    """The full symmetric matrix of a lower band form (``band[d, j] = A[j + d, j]``)."""
    m = band.shape[1]
    A = np.zeros((m, m))
    for d in range(min(band.shape[0], m)):  # a band deeper than the matrix (one node) is cut
        idx = np.arange(m - d)
        A[idx + d, idx] = band[d, : m - d]
        A[idx, idx + d] = band[d, : m - d]
    return A
