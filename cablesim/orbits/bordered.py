"""Minimally augmented defining functions of fold, period-doubling and Neimark-Sacker orbits.

A periodic orbit of monodromy matrix ``M`` is at a bifurcation of kind

- ``fold``: ``M`` has a multiplier +1, ``A = M - I`` is singular;
- ``period-doubling``: a multiplier -1, ``A = M + I`` is singular;
- ``neimark-sacker``: a pair ``exp(+-i theta)``, ``A = M^2 - 2 kappa M + I`` with
  ``kappa = cos(theta)`` has a two-dimensional kernel (``kappa`` is an extra unknown).

Minimally augmented formulation (Govaerts, *Numerical methods for bifurcations of dynamical
equilibria*, SIAM 2000, ch. 4; the fold and flip of cycles of MatCont): with bordering matrices
``B``, ``C`` (``q x d``, ``d`` the rank defect), the bordered system::

    [ A    B ] [ V ]   [ 0 ]                  [ A^T  C ] [ W ]   [ 0 ]
    [ C^T  0 ] [ G ] = [ I ],    and its transpose [ B^T  0 ] [ H ] = [ I ]

is regular near the bifurcation, and ``G`` (``d x d``) vanishes exactly where ``A`` has the rank
defect ``d``. ``G`` is a smooth function of the orbit's unknowns and parameters, with the
derivative ``G_z = -W^T A_z V``: one or two scalar equations added to the periodicity
condition, whatever the size of the state. ``B`` and ``C`` are the left and right singular
vectors of the smallest singular values at the start and are replaced by the normalised ``W``
and ``V`` after every accepted point (they only need to stay close to the null vectors).

Everything is written in scaled coordinates (``Ms = S^-1 M S``, ``S`` the diagonal of the state
scales), so that displacements and velocities weigh alike; a *subspace* ``Q`` (``n x q``,
orthonormal columns spanning an invariant subspace of ``Ms``, by default the whole space)
restricts ``A`` to ``Q^T A Q``: the planar (or, on spatial cables, the out-of-plane) block of the
multipliers, without changing anything else.

Derivatives of ``G`` need the derivative of ``M`` along the unknowns and parameters. A term
``a^T Ms_z b`` is, by the symmetry of second derivatives of the flow map, the derivative of the
segment Jacobians along ``b`` (propagated through the segments) contracted with ``a``
(:func:`bilinear_gradient`): one extra flow evaluation per vector ``b`` gives the gradient with
respect to every unknown at once. :func:`defining_matrix` gives ``A`` of each kind and
:func:`derivative_terms` its ``(c, a, b)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Kinds of bifurcation curves and the rank defect of their test matrix.
RANK_DEFECT = {"fold": 1, "period-doubling": 1, "neimark-sacker": 2, "pitchfork": 1}
#: Extra unknowns of each kind (``kappa`` for Neimark-Sacker).
EXTRA_UNKNOWNS = {"fold": 0, "period-doubling": 0, "neimark-sacker": 1, "pitchfork": 0}


def defining_matrix(kind: str, Ms: np.ndarray, kappa: float = 0.0) -> np.ndarray:
    """``A`` of the kind (module docstring) on the whole scaled space."""
    eye = np.eye(Ms.shape[0])
    if kind in ("fold", "pitchfork"):  # a pitchfork: +1 in the odd block (LocusProblem's subspace)
        return Ms - eye
    if kind == "period-doubling":
        return Ms + eye
    if kind == "neimark-sacker":
        return Ms @ Ms - 2.0 * kappa * Ms + eye
    raise ValueError(f"unknown bifurcation kind {kind!r}: one of {sorted(RANK_DEFECT)}")


def derivative_terms(kind: str, Ms: np.ndarray, kappa: float, w: np.ndarray, v: np.ndarray) -> list:
    """``(c, a, b)`` such that ``w^T A_z v = sum c a^T Ms_z b`` for every unknown ``z`` (``Ms``
    is the only part of ``A`` that depends on the orbit and the parameters; ``kappa`` is
    treated separately, :func:`kappa_derivative`)."""
    if kind in ("fold", "period-doubling", "pitchfork"):
        return [(1.0, w, v)]
    return [(1.0, w, Ms @ v), (1.0, Ms.T @ w, v), (-2.0 * kappa, w, v)]


def kappa_derivative(kind: str, Ms: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``dG/dkappa = -W^T A_kappa V`` (``A_kappa = -2 Ms``; zero for the other kinds)."""
    if kind != "neimark-sacker":
        return np.zeros((W.shape[1], V.shape[1]))
    return 2.0 * W.T @ Ms @ V


def initial_borders(A: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray]:
    """``(B, C)``: the left and right singular vectors of the ``d`` smallest singular values."""
    U, _, Vt = np.linalg.svd(A)
    return U[:, -d:].copy(), Vt[-d:].T.copy()


def bordered_solve(A: np.ndarray, B: np.ndarray, C: np.ndarray):
    """``(V, W, G)`` of the bordered system and its transpose (module docstring).

    Raises
    ------
    numpy.linalg.LinAlgError
        If the bordered matrix is singular (the borders are far from the null vectors).
    """
    q, d = B.shape
    K = np.zeros((q + d, q + d))
    K[:q, :q] = A
    K[:q, q:] = B
    K[q:, :q] = C.T
    rhs = np.zeros((q + d, d))
    rhs[q:] = np.eye(d)
    sol = np.linalg.solve(K, rhs)
    solT = np.linalg.solve(K.T, rhs)
    return sol[:q], solT[:q], sol[q:]


def orthonormal(X: np.ndarray) -> np.ndarray:
    """Orthonormal columns spanning those of ``X`` (signs kept: ``Q^T X`` has a positive
    diagonal)."""
    Q, R = np.linalg.qr(X)
    return Q * np.where(np.diag(R) < 0.0, -1.0, 1.0)


def segment_directions(G: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``b_k = G_{k-1} ... G_0 b``: a state direction carried through the segments (m, n)."""
    out = [np.asarray(b, dtype=float)]
    for k in range(G.shape[0] - 1):
        out.append(G[k] @ out[-1])
    return np.array(out)


def segment_duals(G: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``a_k = (G_{m-1} ... G_{k+1})^T a``: a dual vector carried back through the segments."""
    m = G.shape[0]
    out = [np.asarray(a, dtype=float)]
    for k in range(m - 1, 0, -1):
        out.append(G[k].T @ out[-1])
    return np.array(out[::-1])


@dataclass
class DirectionalData:
    """Flow data at ``u + eps B`` (``B`` the segment directions of one vector ``b``).

    Attributes
    ----------
    directions : ndarray (m, n)
        ``b_k``.
    eps : float
    G : ndarray (m, n, n)
        Segment Jacobians at the displaced states.
    dparams : ndarray (m, n, P)
        Parameter derivatives of the segment maps at the displaced states (one column per
        parameter, in the order of the base data).
    """

    directions: np.ndarray
    eps: float
    G: np.ndarray
    dparams: np.ndarray


def bilinear_gradient(G: np.ndarray, dparams: np.ndarray, a: np.ndarray, data: DirectionalData):
    """Gradient of ``a^T M b`` (physical ``M = G_{m-1} ... G_0``) with respect to the shooting
    unknowns and the parameters, ``b`` being the vector ``data`` was computed along.

    By symmetry of second derivatives, ``d(a^T M b)/ds_k = D_k^T a_k`` with ``D_k`` the
    derivative of ``G_k`` along ``b_k``, and ``d(a^T M b)/dp = sum_k a_k^T d(dPhi_k/dp)/db_k``
    (one-sided differences of step ``eps``).

    Parameters
    ----------
    G : ndarray (m, n, n)
        Segment Jacobians at the base point.
    dparams : ndarray (m, n, P)
        Parameter derivatives of the segment maps at the base point.
    a : ndarray (n,)
        Physical dual vector.
    data : DirectionalData

    Returns
    -------
    grad_u : ndarray (m n,)
    grad_p : ndarray (P,)
    """
    A = segment_duals(G, a)
    dG = (data.G - G) / data.eps
    dP = (data.dparams - dparams) / data.eps
    grad_u = np.einsum("kij,ki->kj", dG, A).ravel()
    grad_p = np.einsum("kip,ki->p", dP, A)
    return grad_u, grad_p


def critical_indices(kind: str, mu: np.ndarray, kappa: float = 0.0) -> list[int]:
    """Indices of the critical multipliers: nearest +1 (fold), -1 (period doubling), or the
    pair nearest ``exp(+-i acos kappa)`` (Neimark-Sacker)."""
    mu = np.asarray(mu, dtype=complex)
    if kind in ("fold", "pitchfork"):
        return [int(np.argmin(np.abs(mu - 1.0)))]
    if kind == "period-doubling":
        return [int(np.argmin(np.abs(mu + 1.0)))]
    theta = np.arccos(np.clip(kappa, -1.0, 1.0))
    z = np.exp(1j * theta)
    i = int(np.argmin(np.abs(mu - z)))
    rest = [k for k in range(mu.size) if k != i]
    j = rest[int(np.argmin(np.abs(mu[rest] - np.conj(z))))]
    return [i, j]
