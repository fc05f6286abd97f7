"""The equations of motion about a static equilibrium, and their compiled model.

:class:`EquationsOfMotion` holds what the integrators and the orbits need to know about a case:
the cable, the analysis, masses, loads, the static equilibrium and the Rayleigh damping
``C = a0 M + a1 K0``. :meth:`EquationsOfMotion.model` packs them into the named
:class:`~cablesim.mechanics.model.CableModel` that every compiled kernel reads
(:mod:`cablesim.dynamics.field` for the time integration). The damping is ``C - U G U^T``
(:func:`cablesim.mechanics.banded.damping_product`): ``C`` banded (or dense, for checks) and
``Cr = [U; G]`` a low-rank part, empty in the exact analysis and of rank ``DIM`` in the
approximate one, so that every product costs O(n).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..cable import Cable
from ..mechanics import banded as bd
from ..mechanics import closure as cl
from ..mechanics import flexibility as fx
from ..mechanics import segments as sg
from ..mechanics.model import APPROXIMATE, CONTINUE, EXACT, STOP, CableModel, approximate_workspace, workspace
from ..modal import modal_analysis
from ..statics import band_to_dense, resisting_force
from .field import consistent_acceleration


@dataclass(frozen=True)
class EquationsOfMotion:
    """The cable's equations of motion about a static equilibrium (the vector field).

    Attributes
    ----------
    cable : Cable
    analysis : str
        ``"exact"`` or ``"approximate"``.
    mass : ndarray, shape (dim n,)
        Diagonal of ``M``, kg.
    F0, FL : ndarray, shape (dim n,)
        Sustained and peak harmonic loads, N.
    omega : float
        Forcing frequency, rad/s (``FL`` may be zero).
    y0 : ndarray
        Static equilibrium under F0 of the chosen analysis, m.
    x0, u0 : ndarray
        Natural state ``x(F0)`` and elastic displacement ``y0 - x0`` there, m.
    T0 : ndarray
        Tensions at the equilibrium, N.
    F1 : ndarray, shape (dim,)
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
    K0_band : ndarray, shape (2 dim, dim n), optional
        Tangent stiffness at the equilibrium in symmetric lower band form
        (``K0_band[d, j] = K0[j + d, j]``), N/m: the exact analysis, whose ``K0`` is
        block-tridiagonal. ``C`` is then kept banded too and the compiled kernels multiply by it
        in O(n); dense ``K0`` and ``C`` are built only when asked for (orbits, small checks).
    K0_dense : ndarray, shape (dim n, dim n), optional
        The full tangent stiffness, N/m: the approximate analysis, whose ``K = N(P)^-1`` is
        full. Exactly one of ``K0_band`` and ``K0_dense`` is given.
    uA, uB : ndarray, shape (dim,), optional
        Amplitudes of the supports' harmonic motion at the forcing frequency, m
        (``A(t) = A + uA sin(omega t + phA)``); the exact analysis only.
    phA, phB : float
        Their phases, rad.
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
    uA: np.ndarray | None = None
    uB: np.ndarray | None = None
    phA: float = 0.0
    phB: float = 0.0

    def __post_init__(self):
        if (self.K0_band is None) == (self.K0_dense is None):
            raise ValueError("EquationsOfMotion takes exactly one of K0_band and K0_dense")
        dim = self.cable.dim
        for key in ("uA", "uB"):
            u = np.zeros(dim) if getattr(self, key) is None else np.asarray(getattr(self, key), dtype=float)
            if u.shape != (dim,):
                raise ValueError(f"{key} must have {dim} components")
            object.__setattr__(self, key, u)
        if self.moving_supports and not self.exact:
            raise ValueError("moving supports need the exact analysis")

    @property
    def moving_supports(self) -> bool:
        """Whether a support moves."""
        return bool(np.any(self.uA != 0.0) or np.any(self.uB != 0.0))

    @cached_property
    def support_stiffness_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """The tangent blocks ``k_first``, ``k_last`` (dim x dim, N/m) of the first and last
        segments at the equilibrium: ``K0s s = -k_first s_A`` at the first node and
        ``-k_last s_B`` at the last (``docs/theory.md``, section 7)."""
        c, dim = self.cable, self.cable.dim
        blocks = []
        for k in (0, c.n_segments - 1):
            out = np.empty((dim, dim))
            sg.segment_block(np.ascontiguousarray(self.y0, dtype=float), k, np.ascontiguousarray(c.S, dtype=float),
                             float(c.EA), c.support_A, c.support_B, out)
            blocks.append(out)
        return blocks[0], blocks[1]

    def support_damping_blocks(self) -> tuple[tuple, tuple]:
        """``a1`` times the tangent blocks of the first and last segments at the equilibrium
        (the support part of the stiffness-proportional damping, ``docs/theory.md`` section 7),
        flat tuples of dim x dim, N s/m."""
        return tuple(tuple(float(x) for x in (self.a1 * b).ravel()) for b in self.support_stiffness_blocks)

    def support_load(self, omega: float) -> np.ndarray:
        """Complex amplitude of the linearised load of the supports' motion, N: the harmonic load
        ``Im(G exp(i w t))`` on the nodes held still that moves them as the supports' motion does
        to first order, ``(k + i w a1 k) u exp(i ph)`` at the first node (``k_first``, ``uA``,
        ``phA``) and at the last (``k_last``, ``uB``, ``phB``); zero with the supports at rest."""
        G = np.zeros(self.n_dof, dtype=complex)
        if not self.moving_supports:
            return G
        dim = self.cable.dim
        k_first, k_last = self.support_stiffness_blocks
        for k, u, ph, at in ((k_first, self.uA, self.phA, 0), (k_last, self.uB, self.phB, self.n_dof - dim)):
            G[at : at + dim] += (1 + 1j * omega * self.a1) * (k @ np.asarray(u, dtype=float)) * np.exp(1j * ph)
        return G

    @cached_property
    def K0(self) -> np.ndarray:
        """Tangent stiffness at the equilibrium, N/m, full ``(dim n, dim n)`` (built from the band on
        first use for the exact analysis: O(n^2) memory, so not in the time loop)."""
        return self.K0_dense if self.K0_band is None else band_to_dense(self.K0_band)

    @cached_property
    def C(self) -> np.ndarray:
        """Rayleigh damping ``C = a0 M + a1 K0``, N s/m, full ``(dim n, dim n)`` (see :attr:`K0`)."""
        return self.a0 * np.diag(self.mass) + self.a1 * self.K0

    @cached_property
    def C_band(self) -> np.ndarray | None:
        """``C`` in banded storage (:func:`cablesim.mechanics.banded.band_storage`), O(n): the whole
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
        Cb[bd.band_half(self.cable.dim)] += self.a0 * self.mass
        return Cb

    @cached_property
    def damping_low_rank(self) -> np.ndarray:
        """``Cr = [U; G]`` (dim n + r, r) with ``C = C_band - U G U^T``: r = 0, except in the
        approximate analysis, whose ``K0 = B0 - U0 Gamma0^-1 U0^T`` (block-tridiagonal minus
        rank dim, see :mod:`cablesim.mechanics.flexibility`) gives ``U = U0``, ``G = a1 Gamma0^-1``
        (not always definite: for soft cables the segment flexibilities of the approximate
        analysis need not be)."""
        if self.exact:
            return np.zeros((self.n_dof, 0))
        U0, Gi0 = self._approximate_K0[1:]
        return np.ascontiguousarray(np.vstack([U0, self.a1 * Gi0]))

    @cached_property
    def _approximate_K0(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(B0, U0, Gamma0^-1)`` of the approximate analysis' ``K0 = K(F0)`` from the segment
        factors at the inextensible equilibrium under F0 (band storage, (dim n, dim), (dim, dim))."""
        c = self.cable
        n, dim = c.n_nodes, c.dim
        Q, F, T = np.empty((n + 1, dim)), np.array(self.F1, dtype=float), np.empty(n + 1)
        A, B = c.support_A, c.support_B
        cl.cumulative_loads(self.F0, Q, A)
        S = np.ascontiguousarray(c.S, dtype=float)
        cl.minimise(S, Q, 0.0, B, F, 1e-13 * max(c.total_length, c.chord_length), 60)
        fac, gi, _ = fx.factor_workspace(n, dim)
        if not fx.segment_factors(S, float(c.EA), Q, F, T, fac, gi, A):
            raise ValueError("the approximate analysis' stiffness at the equilibrium is singular")
        B0, U0 = np.empty((bd.band_rows(dim), self.n_dof)), np.empty((self.n_dof, dim))
        fx.stiffness_band(fac, gi, B0, U0, A)
        return B0, U0, gi[: dim * dim].reshape(dim, dim).copy()

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
        """``(wk, awk)`` scratch arrays for the compiled kernels
        (:class:`~cablesim.mechanics.model.Workspace`, and an
        :class:`~cablesim.mechanics.model.ApproximateWorkspace` or None for the exact analysis)."""
        n, dim = self.cable.n_nodes, self.cable.dim
        return workspace(n, dim), (None if self.exact else approximate_workspace(n, dim))

    def model(self, dense_damping: bool = False) -> CableModel:
        """The named constants every compiled kernel reads.

        Parameters
        ----------
        dense_damping : bool
            Give ``C`` as a dense matrix (the orbits' Jacobians) rather than banded.
        """
        c = self.cable
        tol = 1e-13 * max(c.total_length, c.chord_length)
        C = self.C if (dense_damping or self.C_band is None) else self.C_band
        Cr = np.zeros((self.n_dof, 0)) if dense_damping else self.damping_low_rank
        return CableModel(
            kind=EXACT if self.exact else APPROXIMATE,
            S=np.ascontiguousarray(c.S, dtype=float),
            EA=float(c.EA),
            A=c.support_A,
            B=c.support_B,
            mass=np.ascontiguousarray(self.mass, dtype=float),
            C=np.ascontiguousarray(C, dtype=float),
            Cr=np.ascontiguousarray(Cr, dtype=float),
            F0=np.ascontiguousarray(self.F0, dtype=float),
            FL=np.ascontiguousarray(self.FL, dtype=float),
            omega=float(self.omega),
            y0=np.ascontiguousarray(self.y0, dtype=float),
            x0=np.ascontiguousarray(self.x0, dtype=float),
            u0=np.ascontiguousarray(self.u0, dtype=float),
            tol=float(tol),
            slack=CONTINUE if self.continues_slack else STOP,
            moving=self.moving_supports,
            uA=tuple(float(x) for x in self.uA),
            uB=tuple(float(x) for x in self.uB),
            phA=float(self.phA),
            phB=float(self.phB),
            **dict(zip(("cA", "cB"), self.support_damping_blocks() if self.moving_supports
                       else ((0.0,) * c.dim ** 2,) * 2)),
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
        if self.moving_supports:  # eq. 19 with the supports where they are at t = 0
            s = np.concatenate([z0, v0, np.zeros(nd)])
            model = self.model()
            consistent_acceleration(model, 0.0, s, workspace(self.cable.n_nodes, self.cable.dim))
            return s
        if self.exact:
            P = resisting_force(self.cable, self.y0 + z0)
        else:
            if np.any(z0 != 0):
                raise ValueError("the approximate analysis starts from its equilibrium (z0 = 0)")
            P = self.F0
        a0 = (F - P - self.damping_force(v0)) / self.mass
        return np.concatenate([z0, v0, a0])
