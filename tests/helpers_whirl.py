"""An independent reference for the out-of-plane stability of periodic cable motion.

Nothing here calls cablesim's mechanics, dynamics, orbits or statics; only
:func:`cable_from_case` reads a case's numbers through ``cablesim.api.load_case``. The model is
the exact analysis of docs/theory.md (sections 1, 2.3, 5 and 7), written again from the physics:

- lumped node masses ``M_r`` (the same in every direction) joined by straight segments of
  natural length ``S_r``; tension ``T_r = EA (l_r - S_r) / S_r`` if ``l_r > S_r``, else 0;
- supports ``A(t) = A + gamma uA sin(omega t + phA)`` and ``B(t) = B + gamma uB sin(omega t + phB)``;
  A is at the origin, B at ``(L, H)`` (planar) or ``(L, H, W)`` (spatial), the vertical axis v
  pointing down and w out of the plane;
- loads ``F0 + gamma FL sin(omega t)`` per node;
- Rayleigh damping on the rate of deformation (section 7):

      M y'' + a0 M y' + a1 (K0 y' + K0s s') + P(y, s) = F(t),

  ``K0`` the tangent stiffness at the static equilibrium under ``F0`` and ``K0s`` its
  derivative in the support positions ``s``, so that a rigid motion is not damped by the ``a1``
  part.

One code serves both the planar form (2 components per node, ``(x, v)``) and the spatial form
(3, ``(x, v, w)``): the dimension is the length of ``B``.

Contents: the model (:class:`LumpedCable`, :func:`force`, :func:`stiffness`,
:func:`support_stiffness`, :func:`static_equilibrium`, :func:`natural_frequencies`,
:func:`rayleigh`); its periodic orbits (:class:`Motion`, :func:`flow`,
:func:`fd_monodromy`, :func:`periodic_orbit`); the out-of-plane (Hill) problem of a planar
orbit (:func:`string_stiffness`, :func:`out_of_plane_multipliers`). The located bifurcations,
their case files and the damped Mathieu closed form are in ``helpers_whirl_cases.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg
from numba import njit
from scipy.integrate import solve_ivp

RTOL = 1e-11  # of every reference integration (DOP853)


# ----------------------------------------------------------------------------------------------
# The model
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LumpedCable:
    """A lumped cable between two supports, from raw numbers (SI units).

    Parameters
    ----------
    S : (n+1,) natural segment lengths, m.
    EA : axial rigidity, N.
    masses : (n,) lumped node masses, kg.
    B : support B's static position, m, relative to A (length 2: planar, 3: spatial).
    F0, FL : (dim n,) sustained and peak harmonic nodal loads, N (node by node, x, v[, w]).
    uA, uB : (dim,) support amplitudes, m; phA, phB their phases, rad.
    a0, a1 : Rayleigh coefficients, 1/s and s.
    """

    S: np.ndarray
    EA: float
    masses: np.ndarray
    B: np.ndarray
    F0: np.ndarray
    FL: np.ndarray = None
    uA: np.ndarray = None
    uB: np.ndarray = None
    phA: float = 0.0
    phB: float = 0.0
    a0: float = 0.0
    a1: float = 0.0

    def __post_init__(self):
        dim = len(self.B)
        zeros = {"FL": np.zeros(dim * (len(self.S) - 1)), "uA": np.zeros(dim), "uB": np.zeros(dim)}
        for key in ("S", "masses", "B", "F0", "FL", "uA", "uB"):
            value = getattr(self, key)
            object.__setattr__(self, key, zeros[key] if value is None else np.array(value, dtype=float))
        assert self.F0.size == self.FL.size == dim * self.n and self.masses.size == self.n

    @property
    def dim(self) -> int:
        return self.B.size

    @property
    def n(self) -> int:
        return self.S.size - 1

    @property
    def mass_diagonal(self) -> np.ndarray:
        """diag(M): each node's mass repeated for its components."""
        return np.repeat(self.masses, self.dim)

    def planar(self) -> LumpedCable:
        """The planar (x, v) form of a spatial cable whose loads and supports lie in x-v."""
        if self.dim == 2:
            return self
        assert self.B[2] == 0 and not np.any(self.F0[2::3]) and not np.any(self.FL[2::3])
        assert self.uA[2] == 0 and self.uB[2] == 0
        keep = np.arange(3 * self.n) % 3 != 2
        return replace(self, B=self.B[:2], F0=self.F0[keep], FL=self.FL[keep], uA=self.uA[:2], uB=self.uB[:2])

    def spatial(self) -> LumpedCable:
        """The spatial form of a planar cable (w = 0 everywhere)."""
        if self.dim == 3:
            return self
        return replace(self, B=np.append(self.B, 0.0), F0=to_spatial(self.F0), FL=to_spatial(self.FL),
                       uA=np.append(self.uA, 0.0), uB=np.append(self.uB, 0.0))


def to_spatial(y: np.ndarray) -> np.ndarray:
    """Node vectors (x, v) per node, padded with w = 0 (also works on stacked states)."""
    y = np.asarray(y, dtype=float)
    out = np.zeros((y.size // 2, 3))
    out[:, :2] = y.reshape(-1, 2)
    return out.ravel()


def planar_indices(n: int) -> np.ndarray:
    """Indices of the (x, v) components of a spatial node vector (n nodes)."""
    return np.flatnonzero(np.arange(3 * n) % 3 != 2)


def _segments(c: LumpedCable, y, sA, sB):
    """Segment vectors d (n+1, dim), stretched lengths l and tensions T."""
    pts = np.vstack((sA, np.reshape(y, (-1, c.dim)), c.B + sB))
    d = np.diff(pts, axis=0)
    l = np.sqrt(np.einsum("ij,ij->i", d, d))
    T = c.EA * np.maximum(l - c.S, 0.0) / c.S
    return d, l, T


def _zero(c):
    return np.zeros(c.dim)


def force(c: LumpedCable, y, sA=None, sB=None) -> np.ndarray:
    """Resisting force ``P_r = T_r e_r - T_(r+1) e_(r+1)`` (N); ``sA``, ``sB`` displace the supports."""
    sA = _zero(c) if sA is None else sA
    sB = _zero(c) if sB is None else sB
    d, l, T = _segments(c, y, sA, sB)
    f = (T / l)[:, None] * d
    return (f[:-1] - f[1:]).ravel()


def tangent_blocks(c: LumpedCable, y, sA=None, sB=None) -> np.ndarray:
    """``k_r = (EA/S_r) e e^T + (T_r/l_r)(I - e e^T)`` per segment (zero if slack): (n+1, dim, dim)."""
    sA = _zero(c) if sA is None else sA
    sB = _zero(c) if sB is None else sB
    d, l, T = _segments(c, y, sA, sB)
    e = d / l[:, None]
    ee = e[:, :, None] * e[:, None, :]
    taut = (l > c.S).astype(float)
    eye = np.eye(c.dim)[None]
    return (c.EA / c.S * taut)[:, None, None] * ee + (T / l)[:, None, None] * (eye - ee)


def assemble(blocks: np.ndarray) -> np.ndarray:
    """The block-tridiagonal matrix of a chain: node i gets k_i + k_(i+1), nodes i, i+1 share -k_(i+1)."""
    n, dim = blocks.shape[0] - 1, blocks.shape[1]
    K = np.zeros((n, n, dim, dim))
    ar = np.arange(n)
    K[ar, ar] = blocks[:-1] + blocks[1:]
    K[ar[:-1], ar[:-1] + 1] = -blocks[1:-1]
    K[ar[:-1] + 1, ar[:-1]] = -blocks[1:-1]
    return K.transpose(0, 2, 1, 3).reshape(n * dim, n * dim)


def stiffness(c: LumpedCable, y, sA=None, sB=None) -> np.ndarray:
    """Tangent stiffness ``K = dP/dy`` (N/m), dense."""
    return assemble(tangent_blocks(c, y, sA, sB))


def support_stiffness(c: LumpedCable, y) -> np.ndarray:
    """``K0s = dP/ds`` (N/m) at the fixed supports: (dim n, 2 dim), columns for A then B.
    P_1 holds +F_1 and F_1 grows with node 1 - A, so dP_1/dA = -k_1; likewise dP_n/dB = -k_(n+1)."""
    k = tangent_blocks(c, y)
    Ks = np.zeros((c.dim * c.n, 2 * c.dim))
    Ks[: c.dim, : c.dim] = -k[0]
    Ks[-c.dim :, c.dim :] = -k[-1]
    return Ks


def _start(c: LumpedCable) -> np.ndarray:
    """A start for Newton: the chord if the cable is taut, else a parabola of the cable's length
    sagging across the chord along the loads."""
    chord = np.linalg.norm(c.B)
    xi = np.cumsum(c.S)[:-1] / c.S.sum()
    pts = xi[:, None] * c.B[None]
    excess = 1.002 * c.S.sum() - chord
    if excess > 0:
        u = c.B / chord
        load = c.F0.reshape(-1, c.dim).sum(0)
        side = load - (load @ u) * u
        if np.linalg.norm(side) < 1e-12 * (np.abs(load).max() + 1.0):
            side = np.eye(c.dim)[1] - u[1] * u
        side /= np.linalg.norm(side)
        sag = math.sqrt(3.0 * chord * excess / 8.0)
        pts = pts + 4.0 * sag * (xi * (1 - xi))[:, None] * side[None]
    return pts.ravel()


def static_equilibrium(c: LumpedCable, y_start=None, tol=1e-11, max_iter=200) -> np.ndarray:
    """y with ``P(y) = F0`` (supports at rest): Newton with backtracking on the residual's norm,
    the tangent from :func:`stiffness`. Converged when the residual is below ``tol`` times the
    larger of |F0| and the tensions, or when the Newton step is at the rounding of the
    coordinates (1e-14 of the span: the residual is then at its floor, about EA/S times that)."""
    y = _start(c) if y_start is None else np.array(y_start, dtype=float)
    span = max(np.linalg.norm(c.B), c.S.sum())
    for _ in range(max_iter):
        r = force(c, y) - c.F0
        scale = max(np.abs(c.F0).max(), _segments(c, y, _zero(c), _zero(c))[2].max(), 1e-300)
        if np.abs(r).max() <= tol * scale:
            return y
        K = stiffness(c, y) + 1e-12 * scale / max(c.S.min(), 1e-300) * np.eye(y.size)
        dy = np.linalg.solve(K, r)
        if np.abs(dy).max() < 1e-14 * span and np.abs(r).max() < 1e-6 * scale:
            return y
        t, r0 = 1.0, np.linalg.norm(r)
        while t > 1e-8:
            trial = y - t * dy
            if np.linalg.norm(force(c, trial) - c.F0) < r0:
                break
            t *= 0.5
        y = trial
    raise RuntimeError(f"static Newton did not converge: residual {np.abs(r).max():.3e} N")


def natural_frequencies(c: LumpedCable, y0) -> tuple[np.ndarray, np.ndarray]:
    """Undamped circular frequencies (rad/s) at y0, split into (not out of the plane, out of the
    plane) when the cable is spatial with its equilibrium in the x-v plane (scipy.linalg.eigh on
    each block: they decouple there, and a taut string's in-plane and out-of-plane frequencies
    may coincide); otherwise (all, empty)."""
    K = stiffness(c, y0)
    m = c.mass_diagonal
    if c.dim == 3 and c.B[2] == 0 and np.abs(np.reshape(y0, (-1, 3))[:, 2]).max() == 0:
        ip, w = planar_indices(c.n), np.arange(2, 3 * c.n, 3)
        return (np.sqrt(scipy.linalg.eigh(K[np.ix_(ip, ip)], np.diag(m[ip]), eigvals_only=True)),
                np.sqrt(scipy.linalg.eigh(K[np.ix_(w, w)], np.diag(m[w]), eigvals_only=True)))
    return np.sqrt(scipy.linalg.eigh(K, np.diag(m), eigvals_only=True)), np.zeros(0)


def rayleigh(omega_i: float, omega_j: float, ratio: float) -> tuple[float, float]:
    """``a0 = 2 xi wi wj / (wi + wj)`` (1/s), ``a1 = 2 xi / (wi + wj)`` (s): ratio xi at wi and wj."""
    return 2 * ratio * omega_i * omega_j / (omega_i + omega_j), 2 * ratio / (omega_i + omega_j)


def with_damping(c: LumpedCable, ratio: float, modes=(1, 2)) -> LumpedCable:
    """The cable with a0, a1 giving ``ratio`` in ``modes`` (1-based, counted among the modes not
    out of the plane) at its static equilibrium."""
    w, _ = natural_frequencies(c, static_equilibrium(c))
    a0, a1 = rayleigh(w[modes[0] - 1], w[modes[1] - 1], ratio)
    return replace(c, a0=a0, a1=a1)


def cable_from_case(case) -> LumpedCable:
    """The numbers of a ``cablesim.case.Case`` (its shorthand expanded by the case: masses and
    loads per length lumped from half of each adjacent segment's natural length, gravity along +v)
    as a :class:`LumpedCable`, with a0 and a1 from ``damping`` (the ratio's modes counted among
    those not out of the plane)."""
    cab, dim = case.cable, case.dim
    B = [cab.L, cab.H, cab.W][:dim]
    uA, uB, phA, phB = case.support_motion()
    c = LumpedCable(S=np.array(cab.S), EA=cab.axial_rigidity, masses=np.array(cab.masses), B=B,
                    F0=case.F0, FL=case.FL, uA=uA, uB=uB, phA=phA, phB=phB)
    d = case.damping
    if d.ratio is None:
        return replace(c, a0=d.a0, a1=d.a1)
    return with_damping(c, d.ratio, d.modes)


# ----------------------------------------------------------------------------------------------
# Motion: the equations of motion at a forcing frequency, their flow and periodic orbits
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _segments_kernel(y, S, EA, B, sA, sB, dim):
    n = S.size - 1
    d = np.empty((n + 1, dim))
    l = np.empty(n + 1)
    T = np.empty(n + 1)
    for r in range(n + 1):
        ss = 0.0
        for k in range(dim):
            a = sA[k] if r == 0 else y[dim * (r - 1) + k]
            b = B[k] + sB[k] if r == n else y[dim * r + k]
            d[r, k] = b - a
            ss += d[r, k] * d[r, k]
        l[r] = math.sqrt(ss)
        T[r] = EA * max(l[r] - S[r], 0.0) / S[r]
    return d, l, T


@njit(cache=True)
def _k_times(d, l, T, S, EA, X, dim):
    """K X for the chain (support displacements zero), X of shape (dim n, k)."""
    n = S.size - 1
    out = np.zeros_like(X)
    u = np.empty(dim)
    for r in range(n + 1):
        ka = EA / S[r] if l[r] > S[r] else 0.0
        kt = T[r] / l[r]
        for c in range(X.shape[1]):
            eu = 0.0
            for k in range(dim):
                xi = X[dim * (r - 1) + k, c] if r > 0 else 0.0
                xj = X[dim * r + k, c] if r < n else 0.0
                u[k] = xj - xi
                eu += d[r, k] / l[r] * u[k]
            for k in range(dim):
                e = d[r, k] / l[r]
                f = ka * eu * e + kt * (u[k] - eu * e)
                if r > 0:
                    out[dim * (r - 1) + k, c] -= f
                if r < n:
                    out[dim * r + k, c] += f
    return out


@njit(cache=True)
def _acceleration(t, Y, V, S, EA, B, m, F0, FL, uA, uB, phA, phB, omega, gamma, C, kA, kB, a1, dim):
    """y'' for each column of Y, V (docs/theory.md section 7's second-order form)."""
    N = Y.shape[0]
    sA = gamma * uA * math.sin(omega * t + phA)
    sB = gamma * uB * math.sin(omega * t + phB)
    dA = gamma * omega * uA * math.cos(omega * t + phA)
    dB = gamma * omega * uB * math.cos(omega * t + phB)
    sn = math.sin(omega * t)
    rate = np.zeros(N)  # a1 K0s s': -k_1 sA' at node 1, -k_(n+1) sB' at node n
    for k in range(dim):
        for j in range(dim):
            rate[k] -= a1 * kA[k, j] * dA[j]
            rate[N - dim + k] -= a1 * kB[k, j] * dB[j]
    CV = C @ V
    out = np.empty_like(Y)
    for c in range(Y.shape[1]):
        d, l, T = _segments_kernel(Y[:, c], S, EA, B, sA, sB, dim)
        for i in range(N):
            r, k = i // dim, i % dim
            P = T[r] / l[r] * d[r, k] - T[r + 1] / l[r + 1] * d[r + 1, k]
            out[i, c] = (F0[i] + gamma * FL[i] * sn - CV[i, c] - rate[i] - P) / m[i]
    return out


@njit(cache=True)
def _string_times(l, T, X):
    """K_w X with K_w the tridiagonal of T_r / l_r."""
    n = X.shape[0]
    out = np.zeros_like(X)
    for r in range(n + 1):
        kt = T[r] / l[r]
        for c in range(X.shape[1]):
            u = (X[r, c] if r < n else 0.0) - (X[r - 1, c] if r > 0 else 0.0)
            if r > 0:
                out[r - 1, c] -= kt * u
            if r < n:
                out[r, c] += kt * u
    return out


@dataclass
class Motion:
    """The first-order form ``x = (y, y')`` of the equations of motion of ``cable`` forced at
    ``omega`` (rad/s), loads and support amplitudes scaled by ``gamma``. ``y`` is absolute (node
    positions, m); ``y0``, ``K0``, ``K0s`` are the static state and its tangents. The right-hand
    sides run compiled (numba); :meth:`acceleration_numpy` is the same force in plain numpy."""

    cable: LumpedCable
    omega: float
    gamma: float = 1.0
    y0: np.ndarray = field(default=None)

    def __post_init__(self):
        c = self.cable
        if self.y0 is None:
            self.y0 = static_equilibrium(c)
        self.K0 = stiffness(c, self.y0)
        self.K0s = support_stiffness(c, self.y0)
        self.m = c.mass_diagonal
        self.C = c.a0 * np.diag(self.m) + c.a1 * self.K0
        self.N = self.y0.size
        k0 = tangent_blocks(c, self.y0)
        self._args = (c.S, float(c.EA), c.B, self.m, c.F0, c.FL, c.uA, c.uB, float(c.phA), float(c.phB),
                      float(self.omega), float(self.gamma), np.ascontiguousarray(self.C),
                      np.ascontiguousarray(k0[0]), np.ascontiguousarray(k0[-1]), float(c.a1), c.dim)

    @property
    def period(self) -> float:
        return 2 * math.pi / self.omega

    def supports(self, t):
        """Support displacements sA, sB and their rates at t."""
        c, w, g = self.cable, self.omega, self.gamma
        aA, aB = w * t + c.phA, w * t + c.phB
        return (g * c.uA * math.sin(aA), g * c.uB * math.sin(aB),
                g * w * c.uA * math.cos(aA), g * w * c.uB * math.cos(aB))

    def acceleration(self, t, Y, V):
        """y'' for the columns of Y, V (N x k)."""
        return _acceleration(t, Y, V, *self._args)

    def acceleration_numpy(self, t, y, v):
        """y'' = M^-1 (F0 + gamma FL sin(omega t) - a0 M v - a1 (K0 v + K0s s') - P(y, s))."""
        c = self.cable
        sA, sB, dA, dB = self.supports(t)
        F = c.F0 + self.gamma * c.FL * math.sin(self.omega * t)
        damp = self.C @ v + c.a1 * (self.K0s @ np.concatenate((dA, dB)))
        return (F - damp - force(c, y, sA, sB)) / self.m

    def rhs(self, t, x):
        N = self.N
        return np.concatenate((x[N:], self.acceleration(t, x[:N, None], x[N:, None])[:, 0]))

    def rhs_variational(self, t, x):
        """The state and the 2N x 2N variational matrix Phi: Phi_y' = Phi_v,
        M Phi_v' = -(a0 M + a1 K0) Phi_v - K(y, s(t)) Phi_y."""
        N = self.N
        y, v = x[:N], x[N : 2 * N]
        Phi = x[2 * N :].reshape(2 * N, 2 * N)
        sA, sB, _, _ = self.supports(t)
        c = self.cable
        d, l, T = _segments_kernel(y, c.S, c.EA, c.B, sA, sB, c.dim)
        KPhi = _k_times(d, l, T, c.S, c.EA, np.ascontiguousarray(Phi[:N]), c.dim)
        dPhi = np.vstack((Phi[N:], -(self.C @ Phi[N:] + KPhi) / self.m[:, None]))
        acc = self.acceleration(t, y[:, None], v[:, None])[:, 0]
        return np.concatenate((v, acc, dPhi.ravel()))

    def atol(self):
        """Absolute tolerances: 1e-13 of the span on positions, of span x omega on velocities."""
        span = max(np.linalg.norm(self.cable.B), self.cable.S.sum())
        return np.concatenate((np.full(self.N, 1e-13 * span), np.full(self.N, 1e-13 * span * self.omega)))

    def static_state(self) -> np.ndarray:
        return np.concatenate((self.y0, np.zeros(self.N)))


def flow(motion: Motion, x0, periods: float = 1.0, variational=False, rtol=RTOL, t0=0.0):
    """x(t0 + periods T) from x(t0) = x0 by DOP853; with ``variational`` also the monodromy
    (2N x 2N, from the variational equations). Returns ``(x, Phi or None)``."""
    N, T = motion.N, periods * motion.period
    atol = motion.atol()
    if variational:
        z0 = np.concatenate((x0, np.eye(2 * N).ravel()))
        atol = np.concatenate((atol, _variational_atol(atol)))
        sol = solve_ivp(motion.rhs_variational, (t0, t0 + T), z0, method="DOP853", rtol=rtol, atol=atol)
        z = sol.y[:, -1]
        return z[: 2 * N], z[2 * N :].reshape(2 * N, 2 * N)
    sol = solve_ivp(motion.rhs, (t0, t0 + T), x0, method="DOP853", rtol=rtol, atol=atol)
    assert sol.success, sol.message
    return sol.y[:, -1], None


def _variational_atol(atol):
    """1e-12 of (row scale / column scale) for each entry of a monodromy, row-major."""
    return (1e-12 * atol[:, None] / atol[None, :]).ravel()


def _batch_rhs(motion: Motion, k: int):
    N = motion.N

    def rhs(t, z):
        X = z.reshape(2 * N, k)
        return np.vstack((X[N:], motion.acceleration(t, np.ascontiguousarray(X[:N]), np.ascontiguousarray(X[N:])))).ravel()

    return rhs


def fd_monodromy(motion: Motion, x0, rel_step=1e-5, rtol=RTOL) -> np.ndarray:
    """The monodromy by central differences of the flow map over one period. The 4N perturbed
    states are integrated as one system, so that they share one step sequence and the
    differences see a smooth map (not the noise of separate adaptive step choices). Steps:
    ``rel_step`` times the span (positions) and the span x omega (velocities)."""
    N = motion.N
    h = motion.atol() / 1e-13 * rel_step
    X0 = np.repeat(np.asarray(x0, dtype=float)[:, None], 4 * N, axis=1)
    ar = np.arange(2 * N)
    X0[ar, 2 * ar] += h
    X0[ar, 2 * ar + 1] -= h
    atol = np.repeat(motion.atol(), 4 * N)
    sol = solve_ivp(_batch_rhs(motion, 4 * N), (0.0, motion.period), X0.ravel(), method="DOP853",
                    rtol=rtol, atol=atol)
    X = sol.y[:, -1].reshape(2 * N, 4 * N)
    return (X[:, 0::2] - X[:, 1::2]) / (2 * h[None, :])


@dataclass
class Orbit:
    """A periodic orbit: its state ``x0`` at t = 0, the Jacobian Newton last used (a monodromy
    near the orbit's) and, if asked for, the monodromy ``Phi`` at ``x0`` (variational equations)."""

    x0: np.ndarray
    jacobian: np.ndarray
    monodromy: np.ndarray | None = None


def periodic_orbit(motion: Motion, x_guess=None, jacobian=None, monodromy=True, tol=1e-10, max_iter=40) -> Orbit:
    """A periodic orbit (period 2 pi / omega) by Newton shooting on ``r = x(T) - x(0) = 0``.

    The Jacobian ``Phi - I`` comes from the variational equations, at the guess or given (a
    neighbour's monodromy); it is kept while the residual falls at least tenfold per iteration
    (chord iterations: one plain integration each) and recomputed otherwise. ``tol`` is relative
    to the span (positions) and span x omega (velocities)."""
    x = motion.static_state() if x_guess is None else np.array(x_guess, dtype=float)
    scale = motion.atol() / 1e-13
    J = jacobian
    last = math.inf
    for _ in range(max_iter):
        xT, _ = flow(motion, x)
        err = np.abs((xT - x) / scale).max()
        if err < tol:
            return Orbit(x, J, flow(motion, x, variational=True)[1] if monodromy else None)
        if J is None or err > 0.1 * last:
            xT, J = flow(motion, x, variational=True)
        last = err
        x = x - np.linalg.solve(J - np.eye(x.size), xT - x)
    raise RuntimeError(f"shooting did not converge: residual {err:.3e} of the scales")


def floquet_multipliers(Phi) -> np.ndarray:
    """Eigenvalues of a monodromy, largest modulus first."""
    mu = np.linalg.eigvals(Phi)
    return mu[np.argsort(-np.abs(mu))]


def out_of_plane_block(Phi: np.ndarray, n: int) -> np.ndarray:
    """The (w, w') rows and columns of a spatial monodromy (n nodes)."""
    idx = np.arange(2, 3 * n, 3)
    idx = np.concatenate((idx, 3 * n + idx))
    return Phi[np.ix_(idx, idx)]


# ----------------------------------------------------------------------------------------------
# Out-of-plane motion about a planar orbit (Hill's equation)
# ----------------------------------------------------------------------------------------------
def string_stiffness(c: LumpedCable, y, sA=None, sB=None) -> np.ndarray:
    """Out-of-plane tangent stiffness of a planar state (n x n, N/m): the tridiagonal of the
    segments' ``T_r / l_r``.

    For a state in the x-v plane every unit vector ``e_r`` has ``e_w = 0``, so the w-w entry of
    each block ``k_r = (EA/S_r) e e^T + (T_r/l_r)(I - e e^T)`` is ``T_r / l_r`` and its w-x and
    w-v entries ``(EA/S_r - T_r/l_r) e_w e_x`` vanish: the out-of-plane motion decouples, a string
    with the instantaneous segment tensions (no EA), ``diag = T_r/l_r + T_(r+1)/l_(r+1)``,
    ``off-diagonal = -T_(r+1)/l_(r+1)``.
    """
    cp = c.planar()
    sA = np.zeros(2) if sA is None else sA
    sB = np.zeros(2) if sB is None else sB
    _, l, T = _segments(cp, y, sA, sB)
    return assemble((T / l)[:, None, None])


def out_of_plane_monodromy(planar: Motion, x0, rtol=RTOL) -> np.ndarray:
    """Monodromy (2n x 2n) of ``M dw'' + (a0 M + a1 K0_ww) dw' + K_w(t) dw = 0`` along the planar
    orbit from ``x0`` (a planar state of ``planar``, the planar form), ``K_w(t)`` from
    :func:`string_stiffness`, integrated together with the planar state."""
    c, N = planar.cable, planar.N
    n = c.n
    m = c.masses
    Cw = c.a0 * np.diag(m) + c.a1 * string_stiffness(c, planar.y0)

    def rhs(t, z):
        y, v = z[:N], z[N : 2 * N]
        W = z[2 * N :].reshape(2 * n, 2 * n)
        sA, sB, _, _ = planar.supports(t)
        _, l, T = _segments_kernel(y, c.S, c.EA, c.B, sA, sB, 2)
        KW = _string_times(l, T, np.ascontiguousarray(W[:n]))
        dW = np.vstack((W[n:], -(Cw @ W[n:] + KW) / m[:, None]))
        return np.concatenate((v, planar.acceleration(t, y[:, None], v[:, None])[:, 0], dW.ravel()))

    z0 = np.concatenate((x0, np.eye(2 * n).ravel()))
    scale = planar.atol()
    wscale = np.concatenate((scale[:n], scale[N : N + n]))
    atol = np.concatenate((scale, _variational_atol(wscale)))
    sol = solve_ivp(rhs, (0.0, planar.period), z0, method="DOP853", rtol=rtol, atol=atol)
    return sol.y[2 * N :, -1].reshape(2 * n, 2 * n)


def out_of_plane_multipliers(planar: Motion, x0) -> np.ndarray:
    """Floquet multipliers of the out-of-plane motion about a planar orbit, largest modulus first."""
    return floquet_multipliers(out_of_plane_monodromy(planar, x0))
