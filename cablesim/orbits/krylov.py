"""GMRES for the matrix-free shooting's Newton systems.

Right-preconditioned GMRES (Saad and Schultz 1986) without restarts: the systems are small enough
(a few hundred to a few thousand unknowns) and the iteration short enough (tens of steps, each a
monodromy action costing far more than the orthogonalisation) that the whole Krylov basis is
kept; modified Gram-Schmidt with one reorthogonalisation pass, Givens rotations for the least
squares problem.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class KrylovResult:
    """Outcome of :func:`gmres`: the solution, the iterations (operator applications), the
    relative residual reached and whether it met the tolerance."""

    x: np.ndarray
    iterations: int
    residual: float
    converged: bool


def gmres(apply, b: np.ndarray, tol: float = 1e-6, max_iter: int = 100, precondition=None,
          atol: float = 0.0) -> KrylovResult:
    """Solve ``A x = b`` to ``|b - A x| <= max(tol |b|, atol)``.

    Parameters
    ----------
    apply : callable
        ``apply(v) -> A v``.
    b : ndarray
    tol : float
        Relative residual.
    max_iter : int
        Most applications of ``A``.
    precondition : callable, optional
        ``x -> P^-1 x`` (right preconditioning: GMRES on ``A P^-1``, so that the residual it
        minimises is the true one).
    atol : float
        Absolute residual below which the iteration stops whatever ``|b|`` (a Newton step whose
        size only has to be told from its tolerance needs no more).

    Returns
    -------
    KrylovResult
        ``residual`` is relative to ``|b|``; ``converged`` whether the tolerance was met.
    """
    b = np.asarray(b, dtype=float)
    N = b.size
    beta = float(np.linalg.norm(b))
    if beta == 0.0 or not np.isfinite(beta):
        return KrylovResult(np.zeros(N), 0, 0.0 if beta == 0.0 else np.inf, beta == 0.0)
    P = precondition if precondition is not None else (lambda v: v)
    m = max(1, min(max_iter, N))
    Vk = np.zeros((m + 1, N))
    H = np.zeros((m + 1, m))
    cs, sn = np.zeros(m), np.zeros(m)
    g = np.zeros(m + 1)
    g[0] = beta
    Vk[0] = b / beta
    res = 1.0
    goal = max(tol, atol / beta)
    k = 0
    for k in range(1, m + 1):
        w = np.asarray(apply(P(Vk[k - 1])), dtype=float)
        if not np.all(np.isfinite(w)):
            return KrylovResult(np.zeros(N), k, np.inf, False)
        for _ in range(2):
            for i in range(k):
                c = Vk[i] @ w
                H[i, k - 1] += c
                w = w - c * Vk[i]
        H[k, k - 1] = np.linalg.norm(w)
        for i in range(k - 1):
            t = cs[i] * H[i, k - 1] + sn[i] * H[i + 1, k - 1]
            H[i + 1, k - 1] = -sn[i] * H[i, k - 1] + cs[i] * H[i + 1, k - 1]
            H[i, k - 1] = t
        d = np.hypot(H[k - 1, k - 1], H[k, k - 1])
        if d == 0.0:
            k -= 1
            break
        cs[k - 1], sn[k - 1] = H[k - 1, k - 1] / d, H[k, k - 1] / d
        H[k - 1, k - 1] = d
        H[k, k - 1] = 0.0
        g[k] = -sn[k - 1] * g[k - 1]
        g[k - 1] = cs[k - 1] * g[k - 1]
        res = abs(g[k]) / beta
        if res <= goal:
            break
        hn = float(np.linalg.norm(w))
        if hn == 0.0:
            break
        Vk[k] = w / hn
    if k == 0:
        return KrylovResult(np.zeros(N), 0, 1.0, False)
    y = np.linalg.solve(np.triu(H[:k, :k]), g[:k])
    x = P(Vk[:k].T @ y)
    return KrylovResult(np.asarray(x, dtype=float), k, float(res), bool(res <= goal))
