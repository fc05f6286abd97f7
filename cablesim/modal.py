"""Modal analysis and Rayleigh damping.

Linear modal frequencies are ``sqrt(eig(M^-1 K0))`` with ``K0`` the tangent stiffness of the
chosen analysis at the static equilibrium; mode shapes are mass-normalised
(``Phi^T M Phi = I``). Rayleigh damping ``C = a0 M + a1 K0`` (eq. 18) gives two chosen modes
the same damping ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import CablesimError


@dataclass(frozen=True)
class Modes:
    """Linear modes about an equilibrium.

    Attributes
    ----------
    omega : ndarray, shape (m,)
        Circular frequencies, rad/s, ascending.
    shapes : ndarray, shape (2n, m)
        Mass-normalised mode shapes as columns, in DOF order.
    omega_max : float or None
        The highest frequency of the system, rad/s, when ``omega`` holds only the lowest modes
        (None when ``omega`` is complete): the explicit steps and the stiff-cable rule need it.
    kinds : tuple of str
        For a spatial cable, each mode's kind: ``"in-plane"``, ``"out-of-plane"`` (of the plane
        of a planar equilibrium) or ``"coupled"``; empty for a planar cable.
    """

    omega: np.ndarray
    shapes: np.ndarray
    omega_max: float | None = None
    kinds: tuple = ()

    @property
    def highest(self) -> float:
        """The highest frequency of the system, rad/s (computed or not among ``omega``)."""
        return float(self.omega[-1] if self.omega_max is None else self.omega_max)

    @property
    def complete(self) -> bool:
        """Whether ``omega`` holds every mode."""
        return self.omega_max is None

    def omega_with_highest(self) -> np.ndarray:
        """``omega``, followed by the highest frequency when it is not among them, rad/s."""
        return self.omega if self.complete else np.append(self.omega, self.omega_max)

    @property
    def frequency_hz(self) -> np.ndarray:
        """Frequencies in Hz."""
        return self.omega / (2.0 * np.pi)

    @property
    def period(self) -> np.ndarray:
        """Periods, s."""
        return 2.0 * np.pi / self.omega


def modal_analysis(K: np.ndarray, mass_diagonal: np.ndarray, n_modes: int | None = None) -> Modes:
    """Frequencies and mass-normalised mode shapes of ``M q'' + K q = 0``.

    Parameters
    ----------
    K : ndarray, shape (2n, 2n)
        Symmetric tangent stiffness, N/m.
    mass_diagonal : ndarray, shape (2n,)
        Diagonal of the lumped mass matrix, kg.
    n_modes : int, optional
        Only the lowest ``n_modes`` modes (and the highest frequency, ``Modes.omega_max``);
        default all.

    Returns
    -------
    Modes

    Raises
    ------
    CablesimError
        If ``K`` is not positive definite (the equilibrium is unstable or a segment is slack).
    """
    N = mass_diagonal.size
    m = N if n_modes is None else max(1, min(int(n_modes), N))
    # M is diagonal: M^-1/2 K M^-1/2 is symmetric with the same eigenvalues, and its eigenvectors
    # scaled by M^-1/2 are mass-normalised (numpy's eigh: no scipy import on the static path).
    r = 1.0 / np.sqrt(mass_diagonal)
    A = 0.5 * (K + K.T) * r[:, None] * r[None, :]
    lam_all, V = np.linalg.eigh(A)
    lam, phi = lam_all[:m], r[:, None] * V[:, :m]
    if lam[0] <= 0.0:
        raise _not_positive(lam[0])
    top = None if m == N else float(np.sqrt(lam_all[-1]))
    # Fix the sign of each shape: its largest component is positive, for reproducible output.
    return Modes(omega=np.sqrt(lam), shapes=_fix_signs(phi), omega_max=top)


def _fix_signs(phi: np.ndarray) -> np.ndarray:
    idx = np.argmax(np.abs(phi), axis=0)
    return phi * np.sign(phi[idx, np.arange(phi.shape[1])])


def _not_positive(lam0: float) -> CablesimError:
    return CablesimError(
        "The tangent stiffness is not positive definite (lowest eigenvalue "
        f"{lam0:.3g} N/m per kg): the static equilibrium has no stable vibration modes. "
        "Check that every segment is in tension under the sustained loads F0."
    )


#: Up to this many DOF the banded eigensolver returns every mode shape (O(n^3), quick there).
ALL_SHAPES_DOF = 600


def modal_analysis_banded(K_band: np.ndarray, mass_diagonal: np.ndarray, n_modes: int | None = None,
                          n_shapes: int | None = None) -> Modes:
    """:func:`modal_analysis` for a banded stiffness: dense up to ALL_SHAPES_DOF, beyond it
    ``scipy.linalg.eig_banded``, O(n^2) or less.

    Parameters
    ----------
    K_band : ndarray, shape (b + 1, 2n)
        Symmetric stiffness in lower band form, ``K_band[d, j] = K[j + d, j]``, N/m.
    mass_diagonal : ndarray, shape (2n,)
        kg.
    n_modes : int, optional
        Only the lowest ``n_modes`` frequencies (default: all), and the highest one
        (``Modes.omega_max``), each by bisection on the band, O(n) per eigenvalue.
    n_shapes : int, optional
        Mode shapes of the lowest ``n_shapes`` modes only (default: every computed mode when
        2n <= ALL_SHAPES_DOF, else 0). Beyond ALL_SHAPES_DOF the shapes come from inverse
        iteration on the banded matrix, O(n) each.

    Returns
    -------
    Modes
        ``omega`` of the computed modes; ``shapes`` with ``n_shapes`` columns.
    """
    r = 1.0 / np.sqrt(mass_diagonal)
    N = r.size
    A = np.array(K_band[:N], dtype=float)  # a band wider than the matrix holds only zeros beyond it
    for d in range(A.shape[0]):
        A[d, : N - d] *= r[d:] * r[: N - d]
    m = N if n_modes is None else max(1, min(int(n_modes), N))
    if n_shapes is None:
        n_shapes = m if N <= ALL_SHAPES_DOF else 0
    n_shapes = min(n_shapes, m)
    top = None
    if N <= ALL_SHAPES_DOF:  # small enough for a dense solve: numpy's, so no scipy on the static path
        dense = np.zeros((N, N))
        for d in range(A.shape[0]):
            idx = np.arange(N - d)
            dense[idx + d, idx] = dense[idx, idx + d] = A[d, : N - d]
        lam_all, x = np.linalg.eigh(dense)
        lam, x = lam_all[:m], x[:, :n_shapes]
        if m < N:
            top = float(np.sqrt(lam_all[-1]))
    else:
        from scipy.linalg import eig_banded  # heavy cables only: scipy.linalg is slow to import

        select = {} if m == N else {"select": "i", "select_range": (0, m - 1)}
        lam = eig_banded(A, lower=True, eigvals_only=True, **select)
        x = _inverse_iteration(A, lam[:n_shapes])
        if m < N:
            top = float(np.sqrt(eig_banded(A, lower=True, eigvals_only=True, select="i",
                                           select_range=(N - 1, N - 1))[0]))
    if lam[0] <= 0.0:
        raise _not_positive(lam[0])
    phi = _fix_signs(r[:, None] * x) if n_shapes else np.zeros((N, 0))
    return Modes(omega=np.sqrt(lam), shapes=phi, omega_max=top)


def _inverse_iteration(A: np.ndarray, lam: np.ndarray, sweeps: int = 3) -> np.ndarray:
    """Unit eigenvectors of the banded symmetric ``A`` (lower form) for its eigenvalues ``lam``.

    Each vector: a few solves of ``(A - lam I) x = b`` (banded LU, O(n b^2)); vectors of nearly
    equal eigenvalues are orthogonalised against each other. A final Rayleigh-Ritz step on the
    span of all of them (O(n k^2)) makes them orthonormal to round-off and separates nearly
    degenerate pairs, whose computed eigenvalues are too coarse a shift for a few sweeps (the
    eigenvalues of a finely divided cable's lowest modes carry errors of ~1e-16 of the highest).
    """
    from scipy.linalg import solve_banded

    b, N = A.shape[0] - 1, A.shape[1]
    full = np.zeros((2 * b + 1, N))
    for d in range(b + 1):
        full[b + d, : N - d] = A[d, : N - d]
        full[b - d, d:] = A[d, : N - d]
    X = np.zeros((N, lam.size))
    rng = np.random.default_rng(1)
    scale = max(abs(lam[-1]), 1e-300) if lam.size else 1.0
    for i, mu in enumerate(lam):
        shifted = full.copy()
        shifted[b] -= mu * (1.0 + 1e-13) if mu != 0.0 else 1e-13 * scale
        x = rng.standard_normal(N)
        close = [k for k in range(i) if abs(lam[k] - mu) <= 1e-8 * scale]
        for _ in range(sweeps):
            x = solve_banded((b, b), shifted, x, check_finite=False)
            for k in close:
                x -= (X[:, k] @ x) * X[:, k]
            x /= np.linalg.norm(x)
        X[:, i] = x
    if lam.size == 0:
        return X
    Q, _ = np.linalg.qr(X)
    AQ = full[b][:, None] * Q
    for d in range(1, b + 1):  # the symmetric band's off-diagonals, both sides
        AQ[d:] += A[d, : N - d, None] * Q[: N - d]
        AQ[: N - d] += A[d, : N - d, None] * Q[d:]
    H = Q.T @ AQ
    _, V = np.linalg.eigh(0.5 * (H + H.T))
    return Q @ V


def inextensible_frequencies(D: np.ndarray, mass_diagonal: np.ndarray, n_nodes: int | None = None) -> np.ndarray:
    """Modal frequencies of the inextensible cable, rad/s.

    From the inextensible equation of motion ``(D M) x''' + x' = D F'`` (eq. 20): each nonzero
    eigenvalue ``mu`` of ``D M`` gives ``omega = mu^(-1/2)``. ``D`` has rank ``n - 1``, so the
    inextensible cable has ``n - 1`` finite frequencies (one for the paper's 2-node cable); the
    others are infinite.

    Parameters
    ----------
    D : ndarray, shape (2n, 2n)
        Configurational flexibility, m/N.
    mass_diagonal : ndarray, shape (2n,)
        kg.

    Returns
    -------
    ndarray
        Ascending frequencies, rad/s.
    """
    r = np.sqrt(mass_diagonal)
    mu = np.linalg.eigvalsh(r[:, None] * D * r[None, :])
    # D has rank dim n - (n + 1) (the mechanism modes: n - 1 in the plane, 2 n - 1 in space), so
    # keep exactly that many of the largest eigenvalues: a relative threshold would promote
    # round-off to a frequency when n = 1.
    n_finite = mass_diagonal.size - (n_nodes + 1) if n_nodes else mass_diagonal.size // 2 - 1
    mu = np.sort(mu)[::-1][:n_finite]
    mu = mu[mu > 0]
    return np.sort(1.0 / np.sqrt(mu))


def sole_inextensible_frequency(
    x: np.ndarray, P: np.ndarray, T2: float, S: np.ndarray, masses: np.ndarray, L: float, H: float
) -> float:
    """The paper's closed-form sole frequency of the 2-node inextensible cable, rad/s.

    ``omega^2 = R / (s (m^2 M1 S1^2 + s^2 M2 S3^2))`` (after eq. 21), with ``R``, ``m``, ``s``
    and ``A1..A4`` of eq. 21 and ``r = s T2 / S2`` (docs/theory.md, section 4).

    Parameters
    ----------
    x : ndarray, shape (4,)
        Inextensible node coordinates, m.
    P : ndarray, shape (4,)
        Nodal loads, N.
    T2 : float
        Tension in the middle segment, N.
    S : ndarray, shape (3,)
        Natural segment lengths, m.
    masses : ndarray, shape (2,)
        kg.
    L, H : float
        Support offsets, m.

    Returns
    -------
    float
    """
    R, s, m = eq21_R(x, P, T2, S, L, H)
    return float(np.sqrt(R / (s * (m**2 * masses[0] * S[0] ** 2 + s**2 * masses[1] * S[2] ** 2))))


def eq21_R(x, P, T2, S, L, H):
    """``R``, ``s`` and ``m`` of the paper's closed-form 2-node flexibility (eq. 21)."""
    x1, x2, x3, x4 = x
    s = x1 * x4 - x2 * x3
    m = s + H * x3 + L * x2 - H * x1 - L * x4
    r = s * T2 / S[1]
    A1 = r * (L * x4 - H * x3) * (x2 - x4) + P[1] * m * s
    A2 = r * (L * x4 - H * x3) * (x3 - x1) - P[0] * m * s
    A3 = r * (L * x2 - H * x1) * (x4 - x2) + P[3] * s**2
    A4 = r * (L * x2 - H * x1) * (x1 - x3) - P[2] * s**2
    R = m * (A1 * x2 - A2 * x1) + (A3 * (x4 - H) + A4 * (L - x3)) * s
    return R, s, m


def eq21_flexibility(x, P, T2, S, L, H) -> np.ndarray:
    """The paper's closed-form configurational flexibility ``D`` of the 2-node cable (eq. 21).

    ``D = (s / R) v v^T`` with ``v = [m x2, -m x1, s (x4 - H), s (L - x3)]``.
    """
    R, s, m = eq21_R(x, P, T2, S, L, H)
    x1, x2, x3, x4 = x
    v = np.array([m * x2, -m * x1, s * (x4 - H), s * (L - x3)])
    return (s / R) * np.outer(v, v)


def rayleigh_coefficients(omega_i: float, omega_j: float, ratio: float) -> tuple[float, float]:
    """Rayleigh coefficients giving damping ratio ``ratio`` at two frequencies (eq. 18).

    ``a0 = 2 xi wi wj / (wi + wj)``, ``a1 = 2 xi / (wi + wj)``.

    Parameters
    ----------
    omega_i, omega_j : float
        The two modal frequencies, rad/s.
    ratio : float
        Damping ratio ``xi``.

    Returns
    -------
    a0 : float
        Mass-proportional coefficient, 1/s.
    a1 : float
        Stiffness-proportional coefficient, s.
    """
    a0 = 2.0 * ratio * omega_i * omega_j / (omega_i + omega_j)
    a1 = 2.0 * ratio / (omega_i + omega_j)
    return a0, a1


def modal_damping_ratios(omega: np.ndarray, a0: float, a1: float) -> np.ndarray:
    """Damping ratio of each mode under Rayleigh damping: ``a0 / (2 w) + a1 w / 2``."""
    omega = np.asarray(omega, dtype=float)
    return a0 / (2.0 * omega) + a1 * omega / 2.0


def fastest_rate(omega: np.ndarray, a0: float, a1: float) -> float:
    """Largest ``|lambda|`` of the damped linear system ``M q'' + C q' + K0 q = 0``, 1/s.

    With Rayleigh damping each mode obeys ``lambda^2 + 2 xi w lambda + w^2 = 0``. A lightly
    damped mode has ``|lambda| = w``; an overdamped one (``xi > 1``: stiffness-proportional
    damping does this to the high modes of a finely divided cable) has a fast real root
    ``w (xi + sqrt(xi^2 - 1))``, roughly ``a1 w^2``, which can exceed ``omega_max`` several times.
    An explicit scheme's step must resolve this rate (rk4: ``dt < 2.8 / rate``).

    Parameters
    ----------
    omega : ndarray
        Modal frequencies, rad/s.
    a0, a1 : float
        Rayleigh coefficients.

    Returns
    -------
    float
    """
    w = np.asarray(omega, dtype=float)
    xi = modal_damping_ratios(w, a0, a1)
    lam = np.where(xi > 1.0, w * (xi + np.sqrt(np.maximum(xi * xi - 1.0, 0.0))), w)
    return float(lam.max())


# ----------------------------------------------------------------------------------------------
# Spatial cables: in-plane and out-of-plane modes of a planar equilibrium
# ----------------------------------------------------------------------------------------------
#: Relative size below which a cable's points count as lying in one plane.
PLANE_TOL = 1e-9
#: Mode kinds.
IN_PLANE, OUT_OF_PLANE, COUPLED = "in-plane", "out-of-plane", "coupled"


def equilibrium_plane(points: np.ndarray, chord: np.ndarray) -> np.ndarray | None:
    """Unit normal of the plane that holds every node and both supports (rows of ``points``,
    (n + 2, 3)), or None if they are not in one plane. A straight cable lies in many planes: the
    vertical one through its chord is taken. The normal points along +w where it can."""
    c = points - points.mean(axis=0)
    _, sv, Vt = np.linalg.svd(c, full_matrices=False)
    scale = sv[0] if sv.size and sv[0] > 0 else 1.0
    if sv.size < 2 or sv[1] <= PLANE_TOL * scale:
        normal = np.cross(chord, [0.0, 1.0, 0.0])
        if np.linalg.norm(normal) <= PLANE_TOL * np.linalg.norm(chord):
            normal = np.array([0.0, 0.0, 1.0])
    elif sv.size < 3 or sv[2] <= PLANE_TOL * scale:
        normal = Vt[2]
    else:
        return None
    normal = normal / np.linalg.norm(normal)
    return -normal if normal[2] < 0 or (normal[2] == 0 and normal[0] < 0) else normal


def plane_basis(normal: np.ndarray, chord: np.ndarray) -> np.ndarray:
    """Columns ``(e1, e2, normal)``: ``e1`` along the chord's part in the plane, ``e2`` the
    third axis of a right-handed frame (3 x 3, orthonormal)."""
    e1 = chord - (chord @ normal) * normal
    e1 = e1 / np.linalg.norm(e1) if np.linalg.norm(e1) > 0 else np.cross(normal, [0.0, 1.0, 0.0])
    e2 = np.cross(normal, e1)
    return np.column_stack([e1, e2, normal])


def _node_blocks(K_band: np.ndarray, n: int):
    """Diagonal blocks ``K_ii`` and sub-diagonal blocks ``K_(i+1) i`` (3 x 3) of a matrix of 3 x 3
    blocks in lower band form (``K_band[d, j] = K[j + d, j]``)."""
    def entry(r, c):
        return K_band[r - c, c] if r >= c else K_band[c - r, r]
    diag = np.array([[[entry(3 * i + a, 3 * i + b) for b in range(3)] for a in range(3)] for i in range(n)])
    sub = np.array([[[entry(3 * i + 3 + a, 3 * i + b) for b in range(3)] for a in range(3)] for i in range(n - 1)])
    return diag, sub.reshape(-1, 3, 3)


def _band_of_blocks(diag: np.ndarray, sub: np.ndarray) -> np.ndarray:
    """Lower band form of the symmetric block-tridiagonal matrix with these m x m blocks."""
    n, m = diag.shape[0], diag.shape[1]
    N = n * m
    band = np.zeros((2 * m, N))
    for i in range(n):
        for a in range(m):
            for b in range(a + 1):
                band[a - b, m * i + b] = diag[i, a, b]
    for i in range(n - 1):
        for a in range(m):
            for b in range(m):
                r, c = m * (i + 1) + a, m * i + b
                band[r - c, c] = sub[i, a, b]
    return band


def planar_modes(K: np.ndarray, masses: np.ndarray, R: np.ndarray, n_modes: int | None = None,
                 n_shapes: int | None = None, banded: bool = True) -> Modes:
    """Modes of a spatial cable whose equilibrium lies in a plane, solved as the two problems
    they are: in the plane (two components per node, the planar cable's) and across it (one
    component per node: the string with the segment tensions, ``T/l``, no ``EA``).

    Parameters
    ----------
    K : ndarray
        Tangent stiffness, N/m: in lower band form, shape (6, 3n), with ``banded``; else dense
        (3n, 3n).
    masses : ndarray, shape (n,)
        Nodal masses, kg.
    R : ndarray, shape (3, 3)
        :func:`plane_basis`: columns two in-plane axes and the normal.
    n_modes, n_shapes
        As :func:`modal_analysis_banded`, for the whole cable.

    Returns
    -------
    Modes
        Merged in ascending frequency, shapes in the cable's (x, v, w) components, ``kinds``
        ``"in-plane"`` or ``"out-of-plane"``.
    """
    n = masses.size
    N = 3 * n
    total = N if n_modes is None else max(1, min(int(n_modes), N))
    if n_shapes is None:
        n_shapes = total if N <= ALL_SHAPES_DOF else 0
    parts = []
    for k, cols, kind in ((2, R[:, :2], IN_PLANE), (1, R[:, 2:], OUT_OF_PLANE)):
        m = min(k * n, total)
        mass = np.repeat(masses, k)
        if banded:
            diag, sub = _node_blocks(K, n)
            rd = np.einsum("ai,nab,bj->nij", cols, diag, cols)
            rs = np.einsum("ai,nab,bj->nij", cols, sub, cols)
            md = modal_analysis_banded(_band_of_blocks(rd, rs), mass, n_modes=m, n_shapes=min(m, n_shapes))
        else:
            Rb = np.kron(np.eye(n), cols)  # (3n, k n): node by node into the part's components
            md = modal_analysis(Rb.T @ K @ Rb, mass, n_modes=m)
        q = md.shapes[:, : min(m, n_shapes)].reshape(n, k, -1)
        parts.append((md, np.einsum("ak,nkm->nam", cols, q).reshape(N, -1), kind))
    omega = np.concatenate([p[0].omega for p in parts])
    kinds = np.concatenate([[p[2]] * p[0].omega.size for p in parts])
    order = np.argsort(omega, kind="stable")[:total]
    # each part has the shapes of its lowest n_shapes modes, so the lowest n_shapes of all do
    column = np.concatenate([np.arange(p[0].omega.size) + (0 if j == 0 else parts[0][1].shape[1])
                             for j, p in enumerate(parts)])
    shape_cols = np.concatenate([p[1] for p in parts], axis=1)
    shapes = _fix_signs(shape_cols[:, column[order[:n_shapes]]]) if n_shapes else np.zeros((N, 0))
    top = None if total == N else float(max(p[0].highest for p in parts))
    return Modes(omega=omega[order], shapes=shapes, omega_max=top, kinds=tuple(str(k) for k in kinds[order]))


def with_kinds(modes: Modes, kind: str) -> Modes:
    """``modes`` with every mode of one kind (a planar cable: in-plane; a spatial cable whose
    equilibrium is not in a plane: coupled)."""
    return Modes(omega=modes.omega, shapes=modes.shapes, omega_max=modes.omega_max,
                 kinds=(kind,) * modes.omega.size)
