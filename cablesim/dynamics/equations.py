"""The equations of motion: the vector field every integrator calls.

The paper's third-order equation (17), ``M y''' + C y'' + K y' = F'``, with
``F(t) = F0 + FL sin(w t)`` and ``K`` the tangent stiffness of the analysis in use:

- exact analysis: ``K = K(y)`` of the deformed configuration;
- approximate analysis: ``K = N(P)^-1`` with ``P = F - C y' - M y''`` (eq. 15) and ``x(P)`` the
  inextensible equilibrium (warm-started from the previous evaluation).

The state integrated is ``s = (z, y', y'')`` with ``z = y - y(0)`` measured from the static
equilibrium (so tolerances act on the displacement, not on absolute coordinates).

Numba functions take the model as a tuple ``prm`` built by :meth:`EquationsOfMotion.params`:
``(model, S, EA, L, H, m, C, F0, FL, w, y0, x0, u0, Cr, tol, slack)`` with ``slack`` 1 when the exact
analysis continues through slack segments (:data:`CONTINUE`) and 0 when it stops there. The
damping is ``C - U G U^T`` (:func:`cablesim.dynamics.banded.damping_product`): ``C`` banded
(or dense, for checks) and ``Cr = [U; G]`` a low-rank part, empty in the exact analysis and of
rank 2 in the approximate one, so that every product costs O(n).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from ..jit import njit

from ..cable import Cable
from ..modal import modal_analysis
from ..statics import band_to_dense, resisting_force
from . import banded as bd
from . import flexibility as fx
from . import kernels as kn

EXACT = 0
APPROXIMATE = 1
#: ``prm[15]``: whether the exact analysis stops where a segment goes slack or continues.
STOP = 0
CONTINUE = 1


@njit
def load(prm, t):
    """``F(t) = F0 + FL sin(w t)`` (allocates; for code outside the hot loop)."""
    return prm[7] + prm[8] * np.sin(prm[9] * t)


def workspace(n: int):
    """Scratch arrays for :func:`rate` (no allocation inside the time loop): y, P, Kv, v, the
    segment modes ``taut`` (1: taut, 0: slack; all taut to start, see :func:`segment_modes`) and
    a damping product ``C x``."""
    nd = 2 * n
    return (np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.ones(n + 1), np.empty(nd))


def approximate_workspace(n: int):
    """Scratch arrays of the approximate analysis' inner solves: Q (n+1, 2), x, u, T and the
    stiffness factors of :func:`cablesim.dynamics.flexibility.factor_workspace` (O(n) memory)."""
    nd = 2 * n
    return (np.empty((n + 1, 2)), np.empty(nd), np.empty(nd), np.empty(n + 1), *fx.factor_workspace(n))


@njit
def approximate_stiffness(prm, P, warm, awk):
    """Solve the inextensible closure at loads P (warm start ``warm``) and factor ``K = N^-1``.

    Fills ``awk`` (:func:`approximate_workspace`): Q, T and the factors of
    :func:`cablesim.dynamics.flexibility.segment_factors` (all O(n)); returns ``kn.OK`` or
    ``kn.INNER_SOLVE``. The states x and u follow from :func:`natural_state` (outputs only).
    """
    S, EA, L, H, tol = prm[1], prm[2], prm[3], prm[4], prm[14]
    Q, T = awk[0], awk[3]
    for i in range(P.size):
        if not abs(P[i]) < 1e100:  # a blown-up state (or NaN): the closure's products would underflow
            return kn.INNER_SOLVE
    kn.cumulative_loads(P, Q)
    if kn.closure_solve(S, Q, 0.0, L, H, warm, tol, 60) < 0:
        return kn.INNER_SOLVE
    if not fx.segment_factors(S, EA, Q, warm, T, awk[4], awk[5]):
        return kn.INNER_SOLVE
    return kn.OK


@njit
def natural_state(prm, awk):
    """``x(P)`` and ``u(P)`` into ``awk[1]``, ``awk[2]`` after :func:`approximate_stiffness`."""
    fx.natural_and_elastic(prm[1], prm[2], awk[4], awk[5], awk[3], awk[1], awk[2])


@njit
def resisting_from_eq15(prm, t, v, a, P):
    """``P = F(t) - C y' - M y''`` (eq. 15) into P."""
    m, C, F0, FL, w = prm[5], prm[6], prm[7], prm[8], prm[9]
    sw = np.sin(w * t)
    bd.damping_product(C, prm[13], v, 0, P)
    for i in range(m.size):
        P[i] = F0[i] + FL[i] * sw - m[i] * a[i] - P[i]


@njit
def rate(prm, t, s, warm, ds, wk, awk):
    """Right-hand side of the third-order system: ``ds = (velocity, acceleration, jerk)``.

    ``awk`` is None for the exact analysis (numba then compiles a version without the
    approximate branch) and :func:`approximate_workspace` for the approximate one. Returns a
    status code (:data:`cablesim.dynamics.kernels.OK` on success). In the exact analysis the
    segments count as the modes ``wk[4]`` say (taut or slack); with ``slack: stop`` a segment not
    longer than its natural length returns :data:`cablesim.dynamics.kernels.SLACK`.
    """
    S, EA, L, H, m, C = prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    FL, w, y0 = prm[8], prm[9], prm[10]
    y, P, Kv, v = wk[0], wk[1], wk[2], wk[3]
    nd = m.size
    for i in range(nd):
        ds[i] = s[nd + i]
        ds[nd + i] = s[2 * nd + i]
        v[i] = s[nd + i]  # contiguous copy: slicing here costs more than the physics
    if awk is None:
        for i in range(nd):
            y[i] = y0[i] + s[i]
        if kn.exact_force_and_Kv(y, v, S, EA, L, H, P, Kv, wk[4]) >= 0 and prm[15] == STOP:
            return kn.SLACK
    else:
        st = _approximate_Kv(prm, t, s, warm, wk, awk)
        if st != kn.OK:
            return st
    wc = w * np.cos(w * t)
    Ca = wk[5]
    bd.damping_product(C, prm[13], s, 2 * nd, Ca)
    for i in range(nd):
        acc = (FL[i] * wc - Kv[i] - Ca[i]) / m[i]
        if not np.isfinite(acc):
            return kn.NONFINITE
        ds[2 * nd + i] = acc
    return kn.OK


@njit
def consistent_acceleration(prm, t, s, wk):
    """Exact analysis: set ``y''`` in ``s`` from eq. 15 with the segment modes ``wk[4]``,
    ``y'' = M^-1 (F(t) - C y' - P(y))`` (eq. 19 at a restart)."""
    S, EA, L, H, m, C = prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    F0, FL, w, y0 = prm[7], prm[8], prm[9], prm[10]
    y, P, Kv, v = wk[0], wk[1], wk[2], wk[3]
    nd = m.size
    for i in range(nd):
        y[i] = y0[i] + s[i]
        v[i] = s[nd + i]
    kn.exact_force_and_Kv(y, v, S, EA, L, H, P, Kv, wk[4])
    sw = np.sin(w * t)
    bd.damping_product(C, prm[13], v, 0, wk[5])
    for i in range(nd):
        s[2 * nd + i] = (F0[i] + FL[i] * sw - P[i] - wk[5][i]) / m[i]


@njit
def _approximate_Kv(prm, t, s, warm, wk, awk):
    """``K(P) y'`` of the approximate analysis into ``wk[2]``, with P from eq. 15."""
    nd = prm[5].size
    resisting_from_eq15(prm, t, s[nd : 2 * nd], s[2 * nd :], wk[1])
    st = approximate_stiffness(prm, wk[1], warm, awk)
    if st != kn.OK:
        return st
    fx.stiffness_product(awk[4], awk[5], wk[3], wk[2], awk[6])
    return kn.OK


@njit
def equilibrium_factors(prm, warm, awk):
    """The factors of the approximate analysis' ``K0 = K(F0)`` (copies of ``awk[4]``, ``awk[5]``
    after :func:`approximate_stiffness` at F0), for :func:`observe`'s drift: computed once per
    record. NaN for the exact analysis or if the closure at F0 fails (the drift is then NaN)."""
    fac0, gi0 = np.full_like(awk[4], np.nan), np.full_like(awk[5], np.nan)
    if prm[0] == APPROXIMATE and approximate_stiffness(prm, prm[7], warm.copy(), awk) == kn.OK:
        fac0[:, :] = awk[4]
        gi0[:] = awk[5]
    return fac0, gi0


@njit
def observe(prm, t, s, warm, zc, ze, T, segment_state, awk, split, k0):
    """Derived outputs at one instant: ``z_c``, ``z_e``, tensions and the drift of eq. 15.

    ``segment_state`` receives the index of a slack segment (exact) or -1; tensions follow the
    tension-only law ``EA max(l - S, 0) / S``. Returns the drift
    residual ``|M y'' + C y' + P - F| / |F0|`` (exact analysis) or, for the approximate analysis
    where eq. 15 defines P, the mismatch between the integrated ``y`` and ``x(P) + u(P)``
    expressed as a force through ``K0`` (its factors ``k0`` from :func:`equilibrium_factors`),
    also relative to ``|F0|``. NaN if the inner solve fails.
    Without ``split`` the exact analysis skips the inner solve (``zc``, ``ze`` set to zero).
    """
    model, S, EA, L, H, m, C = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    nd = m.size
    z = s[:nd]
    v = s[nd : 2 * nd]
    a = s[2 * nd :]
    F = load(prm, t)
    f0norm = np.sqrt(np.sum(prm[7] ** 2))
    x, u = awk[1], awk[2]
    if model == EXACT:
        y = prm[10] + z
        P = np.empty(nd)
        Kv = np.empty(nd)
        taut = np.empty(S.size)
        kn.tension_only_mask(y, S, L, H, taut)
        segment_state[0] = kn.exact_force_and_Kv(y, v, S, EA, L, H, P, Kv, taut)
        kn.exact_tensions(y, S, EA, L, H, T)
        for k in range(S.size):
            T[k] *= taut[k]
        if not split:
            zc[:] = 0.0
            ze[:] = 0.0
        elif approximate_stiffness(prm, P, warm, awk) != kn.OK:
            zc[:] = np.nan
            ze[:] = np.nan
        else:
            natural_state(prm, awk)
            zc[:] = x - prm[11]
            ze[:] = z - zc
        Cv = np.empty(nd)
        bd.damping_product(C, prm[13], v, 0, Cv)
        r = m * a + P - F + Cv
        return np.sqrt(np.sum(r * r)) / f0norm
    P = np.empty(nd)
    resisting_from_eq15(prm, t, v, a, P)
    segment_state[0] = -1
    if approximate_stiffness(prm, P, warm, awk) != kn.OK:
        zc[:] = np.nan
        ze[:] = np.nan
        T[:] = np.nan
        return np.nan
    T[:] = awk[3]
    natural_state(prm, awk)
    zc[:] = x - prm[11]
    ze[:] = u - prm[12]
    mismatch = z - zc - ze
    d = np.empty(nd)
    fx.stiffness_product(k0[0], k0[1], mismatch, d, awk[6])
    return np.sqrt(np.sum(d * d)) / f0norm


@dataclass(frozen=True)
class EquationsOfMotion:
    """The cable's equations of motion about a static equilibrium (the vector field).

    Attributes
    ----------
    cable : Cable
    analysis : str
        ``"exact"`` or ``"approximate"``.
    mass : ndarray, shape (2n,)
        Diagonal of ``M``, kg.
    F0, FL : ndarray, shape (2n,)
        Sustained and peak harmonic loads, N.
    omega : float
        Forcing frequency, rad/s (``FL`` may be zero).
    y0 : ndarray
        Static equilibrium under F0 of the chosen analysis, m.
    x0, u0 : ndarray
        Natural state ``x(F0)`` and elastic displacement ``y0 - x0`` there, m.
    T0 : ndarray
        Tensions at the equilibrium, N.
    F1 : ndarray, shape (2,)
        Force in segment 1 of the inextensible equilibrium (warm start of inner solves), N.
    a0, a1 : float
        The Rayleigh coefficients of the damping ``C = a0 M + a1 K0`` (1/s, s).
    modal_omega : ndarray, optional
        Linear modal frequencies about the equilibrium, rad/s, ascending (computed from ``K0``
        and ``mass`` when not given).
    slack : str
        ``"continue"`` (default): in the exact analysis segments are tension-only and the
        integrators locate every slack onset and re-tightening; ``"stop"``: a run stops where a
        segment first goes slack. The approximate analysis always stops.
    K0_band : ndarray, shape (4, 2n), optional
        Tangent stiffness at the equilibrium in symmetric lower band form
        (``K0_band[d, j] = K0[j + d, j]``), N/m: the exact analysis, whose ``K0`` is
        block-tridiagonal. ``C`` is then kept banded too and the compiled kernels multiply by it
        in O(n); dense ``K0`` and ``C`` are built only when asked for (orbits, small checks).
    K0_dense : ndarray, shape (2n, 2n), optional
        The full tangent stiffness, N/m: the approximate analysis, whose ``K = N(P)^-1`` is
        full. Exactly one of ``K0_band`` and ``K0_dense`` is given.
    """

    cable: Cable
    analysis: str
    mass: np.ndarray
    F0: np.ndarray
    FL: np.ndarray
    omega: float
    y0: np.ndarray
    x0: np.ndarray
    u0: np.ndarray
    T0: np.ndarray
    F1: np.ndarray
    a0: float = 0.0
    a1: float = 0.0
    modal_omega: np.ndarray | None = None
    slack: str = "continue"
    K0_band: np.ndarray | None = None
    K0_dense: np.ndarray | None = None

    def __post_init__(self):
        if (self.K0_band is None) == (self.K0_dense is None):
            raise ValueError("EquationsOfMotion takes exactly one of K0_band and K0_dense")

    @cached_property
    def K0(self) -> np.ndarray:
        """Tangent stiffness at the equilibrium, N/m, full ``(2n, 2n)`` (built from the band on
        first use for the exact analysis: O(n^2) memory, so not in the time loop)."""
        return self.K0_dense if self.K0_band is None else band_to_dense(self.K0_band)

    @cached_property
    def C(self) -> np.ndarray:
        """Rayleigh damping ``C = a0 M + a1 K0``, N s/m, full ``(2n, 2n)`` (see :attr:`K0`)."""
        return self.a0 * np.diag(self.mass) + self.a1 * self.K0

    @cached_property
    def C_band(self) -> np.ndarray | None:
        """``C`` in banded storage (:func:`cablesim.dynamics.banded.band_storage`), O(n): the whole
        of it in the exact analysis, its banded part ``C + U G U^T`` in the approximate one (see
        :attr:`damping_low_rank`); None when only a dense ``K0`` is given for the exact analysis.
        The compiled kernels multiply by it in O(n)."""
        if self.K0_band is not None:
            lower = self.a1 * self.K0_band
            lower[0] += self.a0 * self.mass
            return bd.band_storage(lower)
        if self.exact:
            return None
        Cb = self.a1 * self._approximate_K0[0]
        Cb[bd.BAND_HALF] += self.a0 * self.mass
        return Cb

    @cached_property
    def damping_low_rank(self) -> np.ndarray:
        """``Cr = [U; G]`` (2n + r, r) with ``C = C_band - U G U^T``: r = 0, except in the
        approximate analysis, whose ``K0 = B0 - U0 Gamma0^-1 U0^T`` (block-tridiagonal minus
        rank 2, see :mod:`cablesim.dynamics.flexibility`) gives ``U = U0``, ``G = a1 Gamma0^-1``
        (not always definite: for soft cables the segment flexibilities of the approximate
        analysis need not be)."""
        if self.exact:
            return np.zeros((self.n_dof, 0))
        U0, Gi0 = self._approximate_K0[1:]
        return np.ascontiguousarray(np.vstack([U0, self.a1 * Gi0]))

    @cached_property
    def _approximate_K0(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(B0, U0, Gamma0^-1)`` of the approximate analysis' ``K0 = K(F0)`` from the segment
        factors at the inextensible equilibrium under F0 (band storage (7, 2n), (2n, 2), (2, 2))."""
        c = self.cable
        n = c.n_nodes
        Q, F, T = np.empty((n + 1, 2)), np.array(self.F1, dtype=float), np.empty(n + 1)
        kn.cumulative_loads(self.F0, Q)
        S = np.ascontiguousarray(c.S, dtype=float)
        kn.closure_solve(S, Q, 0.0, float(c.L), float(c.H), F, 1e-13 * max(c.total_length, c.chord_length), 60)
        fac, gi, _ = fx.factor_workspace(n)
        if not fx.segment_factors(S, float(c.EA), Q, F, T, fac, gi):
            raise ValueError("the approximate analysis' stiffness at the equilibrium is singular")
        B0, U0 = np.empty((bd.BAND_ROWS, self.n_dof)), np.empty((self.n_dof, 2))
        fx.stiffness_band(fac, gi, B0, U0)
        return B0, U0, np.array([[gi[0], gi[1]], [gi[1], gi[2]]])

    def damping_force(self, v: np.ndarray) -> np.ndarray:
        """``C y'``, N: O(n) when ``C`` is banded (minus a rank-2 part in the approximate analysis)."""
        if self.C_band is None:
            return self.C @ v
        nd, Cr = self.n_dof, self.damping_low_rank
        U, G = Cr[:nd], Cr[nd:]
        return bd.band_product(self.C_band, v) - U @ (G @ (U.T @ v))

    def internal_force(self, t: float, s: np.ndarray) -> np.ndarray:
        """``P = F(t) - C y' - M y''`` (eq. 15) at the state ``s = (z, y', y'')``, N."""
        nd = self.n_dof
        F = self.F0 + self.FL * np.sin(self.omega * t)
        return F - self.damping_force(s[nd : 2 * nd]) - self.mass * s[2 * nd :]

    @cached_property
    def frequencies(self) -> np.ndarray:
        """Linear modal frequencies about the equilibrium, rad/s, ascending."""
        if self.modal_omega is not None:
            return np.asarray(self.modal_omega, dtype=float)
        return modal_analysis(self.K0, self.mass).omega

    @property
    def exact(self) -> bool:
        """Whether the exact analysis is in use (else the approximate one)."""
        return self.analysis == "exact"

    @property
    def continues_slack(self) -> bool:
        """Whether a run continues through slack segments (exact analysis, ``slack: continue``)."""
        return self.exact and self.slack == "continue"

    @property
    def n_dof(self) -> int:
        """Number of degrees of freedom."""
        return self.mass.size

    def workspaces(self):
        """``(wk, awk)`` scratch arrays for the compiled kernels; ``awk`` is None for the exact
        analysis."""
        n = self.cable.n_nodes
        return workspace(n), (None if self.exact else approximate_workspace(n))

    def params(self) -> tuple:
        """The numba parameter tuple (see the module docstring)."""
        c = self.cable
        tol = 1e-13 * max(c.total_length, c.chord_length)
        return (
            EXACT if self.exact else APPROXIMATE,
            np.ascontiguousarray(c.S),
            float(c.EA),
            float(c.L),
            float(c.H),
            np.ascontiguousarray(self.mass),
            np.ascontiguousarray(self.C if self.C_band is None else self.C_band),
            np.ascontiguousarray(self.F0),
            np.ascontiguousarray(self.FL),
            float(self.omega),
            np.ascontiguousarray(self.y0),
            np.ascontiguousarray(self.x0),
            np.ascontiguousarray(self.u0),
            self.damping_low_rank,
            float(tol),
            CONTINUE if self.continues_slack else STOP,
        )

    def initial_state(self, z0: np.ndarray | None = None, v0: np.ndarray | None = None) -> np.ndarray:
        """``s(0) = (z(0), y'(0), y''(0))`` with ``y''(0)`` from eq. 19.

        Parameters
        ----------
        z0 : ndarray, optional
            Initial displacement from the equilibrium, m (default zero). Only the exact analysis
            can start displaced: the approximate analysis defines the configuration through P.
        v0 : ndarray, optional
            Initial velocities, m/s (default zero).
        """
        nd = self.n_dof
        z0 = np.zeros(nd) if z0 is None else np.asarray(z0, dtype=float)
        v0 = np.zeros(nd) if v0 is None else np.asarray(v0, dtype=float)
        F = self.F0  # F(0) = F0 + FL sin 0
        if self.exact:
            P = resisting_force(self.cable, self.y0 + z0)
        else:
            if np.any(z0 != 0):
                raise ValueError("the approximate analysis starts from its equilibrium (z0 = 0)")
            P = self.F0
        a0 = (F - P - self.damping_force(v0)) / self.mass
        return np.concatenate([z0, v0, a0])
