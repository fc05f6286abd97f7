"""The leading Floquet multipliers from the monodromy's action on vectors, and tests that fit them.

A damped cable's orbit has as many multipliers as state variables, but only a few can leave
the unit circle: the damping pushes the others far inside (a 50-node heavy span at 2.3 rad/s
has 200, of which about 40 exceed 0.5 in modulus and the axial ones are below 1e-30).
:func:`leading_multipliers` computes those of modulus above a *bound* (default
:data:`DEFAULT_BOUND`) from the action ``v -> M v`` alone, by block Krylov iteration with
Rayleigh-Ritz extraction (a block Davidson method without preconditioner): the basis is grown by
the residuals ``M y - mu y`` of the Ritz pairs not yet converged, so that a start near the
wanted invariant subspace (the previous orbit's, along a branch) converges in a few products per
multiplier. The number kept is adaptive: enough that one Ritz value *below* the bound is
converged too, and the largest such is reported as the largest discarded modulus
(:attr:`Leading.discarded`). Each kept pair carries its residual
``|M y - mu y| / |y|`` (in the scaled coordinates of the state): the accuracy check that
replaces Liouville's formula, which needs the whole spectrum.

Bifurcation test functions that fit a truncated spectrum (:func:`truncated_tests`): every
multiplier left out is inside the disc of radius ``bound < 1``, so

- period doubling ``prod(1 + mu)`` and fold ``prod(1 - mu)`` over the kept multipliers change
  sign exactly where the full products do (each left-out factor is positive);
- Neimark-Sacker ``prod(1 - mu_i mu_j)`` over the kept pairs that are not both real: a pair on
  the unit circle makes it vanish, a multiplier entering or leaving the kept set adds positive
  factors only. (Pairs of real multipliers with ``mu_i mu_j = 1``, neutral saddles, which the
  full product also flags, are not bifurcations and are left out.)

:class:`Deflation` turns the kept invariant subspace ``M V = V S`` into the preconditioner of
the shooting's Newton systems (:mod:`cablesim.orbits.matrixfree`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .stability import geodesic_model_ratio, sort_multipliers

#: Default bound: multipliers of larger modulus are computed. A multiplier must travel from
#: the bound to the unit circle to cause a bifurcation; the continuation's step control keeps
#: the kept moduli from moving more than half their distance to the circle per step, and one
#: below the bound is tracked as the discarded modulus, so none can cross unseen.
DEFAULT_BOUND = 0.5
#: Residual (scaled) of a kept Ritz pair for it to count as converged, by default.
DEFAULT_TOL = 1e-9
#: Residual of the largest discarded Ritz value (it only has to be known to be below the bound).
DISCARDED_TOL = 1e-3
#: Up to this state dimension the whole monodromy is formed from ``n`` products (cheaper than
#: iterating for so few).
DENSE_LIMIT = 24


@dataclass
class Leading:
    """The leading Floquet multipliers of an orbit.

    Attributes
    ----------
    multipliers : ndarray complex (k,)
        Those of modulus above ``bound``, by decreasing modulus (all ``n`` when ``complete``).
    residuals : ndarray (k,)
        ``|M y - mu y| / |y|`` of each, in scaled coordinates.
    vectors : ndarray complex (n, k)
        Their eigenvectors (unit, scaled coordinates).
    basis, schur : ndarray (n, q), (q, q)
        Orthonormal real basis of the kept invariant subspace and one Ritz value below it, and
        the monodromy on it, ``M basis = basis schur``: warm start and preconditioner.
    discarded : float
        Largest modulus left out (0 when ``complete``).
    bound : float
    products : int
        Actions of the monodromy spent.
    complete : bool
        The whole spectrum was computed.
    """

    multipliers: np.ndarray
    residuals: np.ndarray
    vectors: np.ndarray
    basis: np.ndarray
    schur: np.ndarray
    discarded: float
    bound: float
    products: int
    complete: bool

    @property
    def residual(self) -> float:
        """Largest residual of a kept pair."""
        return float(self.residuals.max()) if self.residuals.size else 0.0


def _orth(X: np.ndarray, B: np.ndarray | None = None, drop: float = 1e-10) -> np.ndarray:
    """Orthonormal basis of the columns of ``X`` orthogonal to the orthonormal ``B`` (two passes
    of classical Gram-Schmidt), dropping directions below ``drop`` of their size."""
    X = np.array(X, dtype=float, copy=True)
    if X.size == 0:
        return X.reshape(X.shape[0], 0)
    size = np.linalg.norm(X, axis=0)
    for _ in range(2):
        if B is not None and B.shape[1]:
            X -= B @ (B.T @ X)
    Q, R = np.linalg.qr(X)
    keep = np.abs(np.diag(R)) > drop * max(float(size.max()), 1e-300)
    Q = Q[:, keep]
    if B is not None and B.shape[1] and Q.shape[1]:
        Q -= B @ (B.T @ Q)
        Q, _ = np.linalg.qr(Q)
    return Q


def _dense(apply, n: int, bound: float) -> Leading:
    M = apply(np.eye(n))
    mu, Y = np.linalg.eig(M)
    order = np.lexsort((-mu.imag, -np.abs(mu)))
    mu, Y = mu[order], Y[:, order]
    res = np.linalg.norm(M @ Y - Y * mu, axis=0)
    T, Z = sla.schur(M, output="real")
    return Leading(mu, res, Y, Z, T, 0.0, bound, n, True)


def _ritz(B, MB):
    """Ritz values (by decreasing modulus), their vectors in the coordinates of ``B`` and in the
    state, and residual norms of ``span(B)``."""
    H = B.T @ MB
    theta, Y = np.linalg.eig(H)
    order = np.lexsort((-theta.imag, -np.abs(theta)))
    theta, Y = theta[order], Y[:, order]
    X = B @ Y
    R = MB @ Y - X * theta
    return H, theta, Y, X, R, np.linalg.norm(R, axis=0) / np.linalg.norm(X, axis=0)


def leading_multipliers(apply, n: int, bound: float = DEFAULT_BOUND, tol: float = DEFAULT_TOL,
                        start: np.ndarray | None = None, block: int = 8, max_basis: int = 160,
                        max_products: int | None = None, seed: int = 0) -> Leading:
    """Floquet multipliers above ``bound`` in modulus (module docstring).

    Parameters
    ----------
    apply : callable
        ``apply(X) -> M X`` for a block ``X`` (n, b) in scaled coordinates.
    n : int
        State dimension.
    bound : float
        Modulus above which multipliers are kept (below 1).
    tol : float
        Largest residual of a kept pair.
    start : ndarray (n, q), optional
        Start basis (for instance the previous orbit's :attr:`Leading.basis`), completed with
        random vectors up to ``block`` columns.
    block : int
        Least size of the first basis.
    max_basis : int
        Basis size at which the search restarts from the wanted Schur vectors.
    max_products : int, optional
        Most products (default ``20 n``, at least 200); on reaching it the result is returned as
        it is (residuals tell).
    seed : int
        Seed of the random start vectors (results are reproducible).
    """
    if not 0.0 < bound < 1.0:
        raise ValueError("bound must be between 0 and 1")
    if n <= DENSE_LIMIT:
        return _dense(apply, n, bound)
    rng = np.random.default_rng(seed)
    max_products = max(200, 20 * n) if max_products is None else int(max_products)
    B = _orth(start) if start is not None and np.size(start) else np.zeros((n, 0))
    if B.shape[1] < block:
        B = np.hstack([B, _orth(rng.standard_normal((n, block - B.shape[1])), B)])
    MB = apply(B)
    products = B.shape[1]
    while True:
        H, theta, Y, X, R, res = _ritz(B, MB)
        m = theta.size
        nk = int(np.sum(np.abs(theta) > bound))
        ok_kept = bool(np.all(res[:nk] <= tol))
        below = nk < m and res[nk] <= DISCARDED_TOL and abs(theta[nk]) + res[nk] < bound
        if (ok_kept and below) or products >= max_products or m >= n:
            break
        want = [j for j in range(min(nk + 1, m)) if res[j] > (tol if j < nk else DISCARDED_TOL)]
        if nk + 1 >= m:  # the space holds no Ritz value below the bound yet: widen it
            want = list(range(m))
        cols = []
        for j in want:
            if j > 0 and np.conj(theta[j]) == theta[j - 1] and theta[j].imag != 0.0:
                continue  # the conjugate of the previous pair spans the same real space
            cols.append(R[:, j].real)
            if theta[j].imag != 0.0:
                cols.append(R[:, j].imag)
        Xn = np.array(cols).T if cols else np.zeros((n, 0))
        if m + Xn.shape[1] > max_basis:
            B, MB = _restart(B, MB, H, theta, Y, nk)
        Xn = _orth(Xn, B)
        if Xn.shape[1] == 0:
            Xn = _orth(rng.standard_normal((n, block)), B)
        Xn = Xn[:, : max(0, min(Xn.shape[1], n - B.shape[1], max_products - products))]
        if Xn.shape[1] == 0:
            break
        MX = apply(Xn)
        products += Xn.shape[1]
        B, MB = np.hstack([B, Xn]), np.hstack([MB, MX])
    return _result(B, H, theta, Y, X, res, nk, bound, products, complete=B.shape[1] >= n)


#: The eigenvectors' span is taken as the kept subspace where ``|H Z - Z T| <= SPAN_TOL |H|``.
SPAN_TOL = 1e-12


def _eigen_columns(theta: np.ndarray, Y: np.ndarray, keep: np.ndarray) -> np.ndarray | None:
    """Real columns spanning the eigenvectors ``Y`` of ``theta[keep]``, one per eigenvalue (a
    real one's vector; a conjugate pair's real and imaginary parts, once); None where ``keep``
    splits a pair."""
    cols = []
    for j in np.flatnonzero(keep):
        if theta[j].imag == 0.0:
            cols.append(Y[:, j].real)
        elif theta[j].imag > 0.0:
            cols.extend((Y[:, j].real, Y[:, j].imag))
    return np.array(cols).T if len(cols) == int(keep.sum()) else None


def _leading_schur(H: np.ndarray, cut: float, eig: tuple | None = None):
    """``(Z, T)``: an orthonormal basis ``Z`` of the invariant subspace of ``H`` for its
    eigenvalues of modulus above ``cut``, and ``T = Z^T H Z``; ``eig``: ``(theta, Y)``, the
    eigen decomposition of ``H`` where it is at hand.

    The real span of those eigenvectors (a QR of a few columns) where they are independent to
    ``1e-6`` and their span is invariant to :data:`SPAN_TOL`; else (a nearly defective
    eigenvalue, a pair split by the cut) the ordered real Schur form; and where LAPACK's
    reordering moves an eigenvalue across the cut (moduli that close to it), the span of the
    eigenvectors however conditioned."""
    theta, Y = np.linalg.eig(H) if eig is None else eig
    keep = np.abs(theta) > cut
    if not np.any(keep):
        keep[int(np.argmax(np.abs(theta)))] = True
    X = _eigen_columns(theta, Y, keep)
    if X is not None:
        Z, R = np.linalg.qr(X)
        d = np.abs(np.diag(R))
        if d.min() >= 1e-6 * d.max():
            HZ = H @ Z
            T = Z.T @ HZ
            if np.linalg.norm(HZ - Z @ T) <= SPAN_TOL * np.linalg.norm(H):
                return Z, T
    try:
        T, Z, sdim = sla.schur(H, output="real", sort=lambda x, y: np.hypot(x, y) > cut)
        sdim = max(int(sdim), 1)
        return Z[:, :sdim], T[:sdim, :sdim]
    except np.linalg.LinAlgError:
        Z = _orth(np.hstack([Y[:, keep].real, Y[:, keep].imag]))
        return Z, Z.T @ H @ Z


def _restart(B, MB, H, theta, Y, nk):
    """Keep the basis of the wanted Ritz values and a few below them (``theta``, ``Y``: the
    Ritz pairs of ``H``, by decreasing modulus)."""
    m = H.shape[0]
    keep = min(m, nk + max(4, nk // 4))
    mods = np.abs(theta)
    cut = 0.5 * (mods[keep - 1] + mods[keep]) if keep < m else -1.0
    Z, _ = _leading_schur(H, cut, (theta, Y))
    return B @ Z, MB @ Z


def _result(B, H, theta, Y, X, res, nk, bound, products, complete) -> Leading:
    m = theta.size
    q = min(m, nk + 1)
    if complete:
        q = m
    cut = 0.5 * (abs(theta[q - 1]) + abs(theta[q])) if q < m else -1.0
    Z, schur = _leading_schur(H, cut, (theta, Y))
    basis = B @ Z
    k = m if complete else nk
    vec = X[:, :k] / np.linalg.norm(X[:, :k], axis=0)
    discarded = 0.0 if complete or nk >= m else float(abs(theta[nk]))
    return Leading(theta[:k].copy(), res[:k].copy(), vec, basis, schur, discarded, bound, products, complete)


# ----------------------------------------------------------------------------------------------
# Tests and step control on a truncated spectrum
# ----------------------------------------------------------------------------------------------
def truncated_tests(mu: np.ndarray) -> np.ndarray:
    """``[prod(1 + mu), prod'(1 - mu_i mu_j), prod(1 - mu)]`` over the kept multipliers
    (``prod'``: pairs not both real), in the order of :data:`cablesim.orbits.stability.TEST_NAMES`
    (module docstring)."""
    mu = np.asarray(mu, dtype=complex)
    pd = np.prod(1.0 + mu).real
    i, j = np.triu_indices(mu.size, k=1)
    real = np.abs(mu.imag) <= 1e-12 * np.maximum(np.abs(mu), 1e-300)
    mixed = ~(real[i] & real[j])
    ns = np.prod(1.0 - mu[i[mixed]] * mu[j[mixed]]).real
    bp = np.prod(1.0 - mu).real
    return np.array([pd, ns, bp])


def truncated_step_ratio(mu_a: np.ndarray, mu_b: np.ndarray, floor: float = 0.005, near: float = 0.3) -> float:
    """:func:`cablesim.orbits.stability.step_ratio` for kept sets that may differ in size: the
    sorted moduli are compared over the shorter set."""
    mu_a = np.asarray(mu_a, dtype=complex)
    mu_b = np.asarray(mu_b, dtype=complex)
    k = min(mu_a.size, mu_b.size)
    if k == 0:
        return 0.0
    ma = np.sort(np.abs(mu_a))[::-1][:k]
    mb = np.sort(np.abs(mu_b))[::-1][:k]
    crit = float(np.abs(ma - 1.0).min())
    ratio = float(np.abs(mb - ma).max()) / max(0.5 * crit, floor)
    dist = np.minimum(np.abs(mu_a + 1.0), np.abs(mu_a - 1.0))
    for j in np.flatnonzero(dist < near):
        moved = float(np.abs(mu_b - mu_a[j]).min())
        ratio = max(ratio, moved / max(0.5 * float(dist[j]), floor))
    return ratio


def kept_block(lead: Leading) -> tuple[np.ndarray, np.ndarray]:
    """``(V, S)``: an orthonormal basis of the invariant subspace of the kept multipliers (those
    above the bound; :attr:`Leading.basis` holds one Ritz value below it besides) and the
    monodromy on it, ``M V = V S``."""
    Z, S = _leading_schur(lead.schur, lead.bound)
    return lead.basis @ Z, S


def aligned_block(V: np.ndarray, S: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """The monodromy ``S`` on the subspace ``V`` in the coordinates of the orthonormal ``basis``
    of an invariant subspace of a nearby orbit: ``Q^T S Q`` with ``Q`` the rotation that takes
    ``V`` nearest to ``basis`` (orthogonal Procrustes: ``V^T basis = U s W^T``, ``Q = U W^T``).
    Similar to ``S``, so its eigenvalues are the kept multipliers."""
    U, _, Wt = np.linalg.svd(V.T @ basis)
    Q = U @ Wt
    return Q.T @ S @ Q


def leading_step_ratio(lead_a: Leading, lead_b: Leading, lead_before: Leading | None = None,
                       s_before: float = -1.0, s_b: float = 1.0) -> float:
    """The step rule of a matrix-free branch from ``lead_a`` to ``lead_b``: where a truncated
    spectrum is kept at the two points and at the point before the step with one count, the
    monodromy on the kept subspace along its geodesic
    (:func:`~cablesim.orbits.stability.geodesic_model_ratio` of the blocks aligned by
    :func:`aligned_block`, ``s_before < 0 < s_b`` the arclengths), else the kept multipliers
    compared (:func:`truncated_step_ratio`).

    A heavy cable keeps tens of lightly damped pairs (modulus about 0.94) that turn around the
    circle as the frequency changes and pass near -1 and +1 again and again; judged as
    multipliers that move, they hold the steps to a fraction of what their moduli need. On the
    geodesic a turning pair keeps its modulus. The multipliers' guard is also blind where a pair
    crosses the real axis within the step (the nearest multiplier at the other end is its own
    conjugate), so it accepts a step across a tongue whose ends look alike; the geodesic's error
    estimate (the curvature of its logarithm) refuses it. On a complete spectrum (a cable small
    enough for the whole monodromy) the multipliers judge, as on the dense path, so that both
    visit the same points; so they do where a count changes (a multiplier crosses the bound), at
    a branch's first step and where a logarithm is not usable.
    """
    leads = (lead_a, lead_b, lead_before)
    if lead_before is not None and not any(lead.complete for lead in leads):
        (Va, Sa), (Vb, Sb), (Vz, Sz) = (kept_block(lead) for lead in leads)
        if Va.shape == Vb.shape == Vz.shape and Va.shape[1] > 0:
            geodesic = geodesic_model_ratio(Sa, aligned_block(Vb, Sb, Va), aligned_block(Vz, Sz, Va), s_before, s_b)
            if geodesic is not None:
                return geodesic
    return truncated_step_ratio(lead_a.multipliers, lead_b.multipliers)


class Deflation:
    """Preconditioner of ``M - I`` from an invariant subspace ``M V = V S`` (scaled coordinates):
    ``P = V S V^T - I`` (the monodromy taken as zero outside the subspace, where its multipliers
    are small), ``P^-1 x = V ((S - I)^-1 + I) V^T x - x``. Exact on the subspace; on its
    complement the preconditioned operator is ``I - M``, whose spectrum lies within the discarded
    modulus of 1."""

    def __init__(self, basis: np.ndarray, schur: np.ndarray):
        self.V = np.asarray(basis, dtype=float)
        q = self.V.shape[1]
        self.W = np.linalg.solve(np.asarray(schur, dtype=float) - np.eye(q), np.eye(q)) + np.eye(q)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return self.V @ (self.W @ (self.V.T @ x)) - x


def leading_from(ev_leading: Leading | None) -> np.ndarray:
    """Multipliers of a :class:`Leading` sorted as :func:`~cablesim.orbits.stability.sort_multipliers`."""
    return sort_multipliers(ev_leading.multipliers) if ev_leading is not None else np.zeros(0, complex)
