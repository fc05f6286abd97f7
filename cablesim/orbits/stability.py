"""Floquet multipliers: stability, bifurcation test functions and their classification.

For a periodic orbit with monodromy matrix ``Phi`` and multipliers ``mu_i``:

- fold (turning point): a real multiplier through +1. Along a branch this is where the
  parameter component of the tangent changes sign (watched by the continuation algorithm);
  ``det(Phi - I) = prod(mu_i - 1)`` changes sign too. A sign change of ``det(Phi - I)``
  *without* a turning point is a branch point (symmetry breaking, or a period-``2p`` branch
  rejoining a period-``p`` orbit).
- period doubling: a real multiplier through -1: ``prod(1 + mu_i)`` changes sign.
- Neimark-Sacker: a complex pair through the unit circle: the product
  ``prod_{i<j} (mu_i mu_j - 1)`` changes sign. It also changes sign when two *real* multipliers
  pass through ``mu_i mu_j = 1`` (a neutral saddle, no bifurcation): :func:`confirm` tells the
  two apart at the located point.

All three test functions are real (complex multipliers come in conjugate pairs) and continuous
in the monodromy matrix, so they are robust to multipliers colliding and leaving the real axis.
"""

from __future__ import annotations

import functools

import numpy as np

TEST_NAMES = ("period-doubling", "neimark-sacker", "branch-point")
#: Tests that duplicate a turning point (ignored where the fold test changes sign too).
FOLD_TESTS = ("branch-point",)
#: Tests on the out-of-plane block of a planar orbit of a mirror-symmetric system
#: (:mod:`cablesim.orbits.symmetry`), in the order of :func:`test_functions`: -1, a complex
#: pair, +1 (the symmetry-breaking pitchfork; never a turning point of the planar branch).
OUT_OF_PLANE_TESTS = ("out-of-plane period-doubling", "out-of-plane neimark-sacker", "pitchfork")
#: ``(kind, plane)`` of every special point of a planar orbit whose monodromy is split.
SPLIT_KINDS = {
    "fold": ("fold", "in-plane"), "period-doubling": ("period-doubling", "in-plane"),
    "neimark-sacker": ("neimark-sacker", "in-plane"), "branch-point": ("branch-point", "in-plane"),
    "out-of-plane period-doubling": ("period-doubling", "out-of-plane"),
    "out-of-plane neimark-sacker": ("neimark-sacker", "out-of-plane"),
    "pitchfork": ("pitchfork", "out-of-plane"),
}


def sort_multipliers(mu: np.ndarray) -> np.ndarray:
    """By decreasing modulus, conjugate pairs with positive imaginary part first."""
    mu = np.asarray(mu, dtype=complex)
    return mu[np.lexsort((-mu.imag, -np.abs(mu)))]


def test_functions(mu: np.ndarray) -> np.ndarray:
    """``[prod(1 + mu), prod_{i<j}(mu_i mu_j - 1), prod(mu - 1)]`` (real parts); of every row
    of a 2-d ``mu``, one row per set of multipliers."""
    mu = np.asarray(mu, dtype=complex)
    pd = np.prod(1.0 + mu, axis=-1).real
    i, j = _pairs(mu.shape[-1])
    ns = np.prod(mu[..., i] * mu[..., j] - 1.0, axis=-1).real
    bp = np.prod(mu - 1.0, axis=-1).real
    return np.stack([pd, ns, bp], axis=-1)


@functools.lru_cache(maxsize=64)
def _pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The index pairs ``i < j`` of ``n`` multipliers (``numpy.triu_indices``, kept: every point
    of a branch asks for them)."""
    i, j = np.triu_indices(n, k=1)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


def split_test_functions(mu_in: np.ndarray, mu_out: np.ndarray) -> np.ndarray:
    """The tests of :data:`TEST_NAMES` on the in-plane multipliers, then those of
    :data:`OUT_OF_PLANE_TESTS` on the out-of-plane ones."""
    return np.concatenate([test_functions(mu_in), test_functions(mu_out)])


def frequency_ratio(mu: complex) -> float:
    """``arg(mu) / 2 pi`` of a multiplier on the unit circle (in ``[0, 1/2]``): the frequency of
    the new motion at a Neimark-Sacker point over the orbit's frequency."""
    return float(abs(np.angle(mu)) / (2.0 * np.pi))


def confirm(name: str, mu: np.ndarray, imag_tol: float = 1e-6) -> str | None:
    """Label of a special point located by test ``name`` at multipliers ``mu``.

    ``"neimark-sacker"`` only if the pair whose product is nearest to 1 is a complex-conjugate
    pair (else a neutral saddle: None).
    """
    mu = np.asarray(mu, dtype=complex)
    if name == "neimark-sacker":
        i, j = np.triu_indices(mu.size, k=1)
        k = int(np.argmin(np.abs(mu[i] * mu[j] - 1.0)))
        a, b = mu[i[k]], mu[j[k]]
        if abs(a.imag) > imag_tol and abs(a - np.conj(b)) <= 1e-6 * max(abs(a), 1.0) + 1e-9:
            return "neimark-sacker"
        return None
    return name


def critical_multiplier(kind: str, mu: np.ndarray) -> complex:
    """The multiplier that crosses the unit circle at a bifurcation of this kind."""
    mu = np.asarray(mu, dtype=complex)
    if kind in ("fold", "branch-point", "pitchfork"):
        return mu[int(np.argmin(np.abs(mu - 1.0)))]
    if kind == "period-doubling":
        return mu[int(np.argmin(np.abs(mu + 1.0)))]
    k = int(np.argmin(np.abs(np.abs(mu) - 1.0) + (np.abs(mu.imag) < 1e-9)))
    return mu[k]


def step_ratio(mu_a: np.ndarray, mu_b: np.ndarray, floor: float = 0.005, near: float = 0.3) -> float:
    """How far the multipliers moved between two points, relative to how close the first point
    is to a bifurcation; a step with a ratio above 1 is rejected.

    Two measures, the larger counts:

    - the sorted moduli: ``max |d|mu|| / max(crit / 2, floor)``, ``crit`` the smallest
      ``||mu| - 1||``. Moduli, not multipliers: lightly damped multipliers spin fast around the
      origin as the frequency changes without approaching the unit circle;
    - the multipliers themselves near ``+1`` or ``-1``: a multiplier within ``near`` of either
      point may move at most half its distance to it. A narrow period-doubling pair, where a
      complex pair close to -1 meets on the real axis, splits, and one multiplier passes -1 and
      back within a short parameter interval, would otherwise fit between two points whose
      moduli barely differ.
    """
    return _motion_ratio(np.array([np.asarray(mu_a, dtype=complex), np.asarray(mu_b, dtype=complex)]), floor, near)


def _motion_ratio(mus: np.ndarray, floor: float, near: float) -> float:
    """The largest :func:`step_ratio` between consecutive rows of ``mus``."""
    mods = np.sort(np.abs(mus), axis=1)
    crit = np.abs(mods[:-1] - 1.0).min(axis=1)
    ratio = float((np.abs(mods[1:] - mods[:-1]).max(axis=1) / np.maximum(0.5 * crit, floor)).max())
    mu_a, mu_b = mus[:-1], mus[1:]
    dist = np.minimum(np.abs(mu_a + 1.0), np.abs(mu_a - 1.0))
    watched = dist < near
    if watched.any():  # each watched multiplier's move to its nearest partner at the next row
        moved = np.abs(mu_b[:, None, :] - mu_a[:, :, None]).min(axis=2)
        ratio = max(ratio, float((moved / np.maximum(0.5 * dist, floor))[watched].max()))
    return ratio


#: Sub-steps of the interpolants of a monodromy block (:func:`interpolated_step_ratio`).
INTERPOLANT_SUBSTEPS = 8


def path_step_ratio(mus: np.ndarray, floor: float = 0.005, near: float = 0.3) -> float:
    """The largest :func:`step_ratio` between consecutive rows of ``mus`` (the multipliers,
    sorted, at the sub-steps of a path), and 2 (reject) if a test function
    (:func:`test_functions`) changes sign along the path but not between its ends: a multiplier
    that passes ``-1`` or ``+1`` and back, or a pair through the circle and back, within it."""
    mus = np.asarray(mus, dtype=complex)
    ratio = _motion_ratio(mus, floor, near)
    signs = np.sign(test_functions(mus))
    hidden = (np.count_nonzero(signs[1:] != signs[:-1], axis=0) > 0) & (signs[0] == signs[-1])
    return max(ratio, 2.0) if np.any(hidden) else ratio


def _path_multipliers(path: np.ndarray) -> np.ndarray:
    """The sorted multipliers of every matrix of a path ``(k, m, m)``."""
    return np.array([sort_multipliers(mu) for mu in np.linalg.eigvals(path)])


def interpolated_step_ratio(P_a: np.ndarray, P_b: np.ndarray, substeps: int = INTERPOLANT_SUBSTEPS,
                            floor: float = 0.005, near: float = 0.3) -> float:
    """:func:`step_ratio` of a block of the monodromy between two points, judged on the matrix
    instead of its multipliers: the matrix is smooth along a branch, the multipliers are not
    (a conjugate pair meeting on the real axis, the start of a period-doubling or a +1 tongue,
    moves as a square root of the parameter there), so their linear motion between the points,
    which :func:`step_ratio` bounds, is a poor model exactly where it matters.

    The block is interpolated linearly, ``P(t) = (1 - t) P_a + t P_b``, and the step's ratio is
    the largest of

    - :func:`path_step_ratio` of the multipliers of ``P`` at the sub-steps ``t = k / substeps``
      (the moduli and the motion near ``+1`` and ``-1``, now of a path that goes through the
      collisions on the real axis as the true multipliers do, and the sign changes of the tests
      inside the step but not between its ends);
    - the linear model's error against the distance of ``P``'s multipliers from the unit circle
      (at most half of it, or of ``floor``, as :func:`step_ratio`): the defect
      ``|det P(1/2) / sqrt(det P_a det P_b) - 1|``, since ``log det`` of the true block is
      smooth and nearly linear along the branch (Liouville's formula) while the interpolant's
      determinant falls short by ``(dtheta / 2)^2`` for every pair turning by ``dtheta`` over the
      step, about twice the error that turn gives its multipliers at mid-step.
    """
    P_a, P_b = np.asarray(P_a, dtype=float), np.asarray(P_b, dtype=float)
    ts = np.linspace(0.0, 1.0, substeps + 1)[:, None, None]
    mus = _path_multipliers((1.0 - ts) * P_a + ts * P_b)
    ratio = path_step_ratio(mus, floor, near)
    mean = np.sqrt(abs(np.linalg.det(P_a) * np.linalg.det(P_b)))
    if mean > 0.0:
        defect = abs(np.linalg.det(0.5 * (P_a + P_b)) / mean - 1.0)
        crit = float(np.abs(np.abs(mus) - 1.0).min())
        ratio = max(ratio, defect / max(0.5 * crit, floor))
    return float(ratio)


#: A straight-line ratio at or below which :func:`geodesic_step_ratio` does not follow the
#: geodesic: the smaller ratio it might give would change nothing, since a ratio below 1/4
#: already lets the continuation's step grow by its largest factor.
LENIENT = 0.25

#: Largest turn (radians) of an eigenvalue of ``P_a^-1 P_b`` over one step for which
#: :func:`geodesic_step_ratio` follows the block along its geodesic (the real principal logarithm
#: is then well defined); beyond it, or where the step's eigenvectors are too ill-conditioned
#: (condition above :data:`GEODESIC_MAX_CONDITION`), only the straight line judges the step.
GEODESIC_MAX_TURN = 0.5 * np.pi
GEODESIC_MAX_CONDITION = 1e6
#: Sub-steps of the geodesic in :func:`geodesic_step_ratio`: twice the straight line's, since a
#: step along it may turn a pair by up to :data:`GEODESIC_MAX_TURN` and the motion near ``+1``
#: and ``-1`` is judged between consecutive sub-steps (the sampling of the path, not its model,
#: which the error estimate judges).
GEODESIC_SUBSTEPS = 2 * INTERPOLANT_SUBSTEPS


class StepLog:
    """``Q = P_a^-1 P = V diag(w) V^-1`` with its real principal logarithm
    ``L = V diag(log w) V^-1`` and powers ``Q^t = V diag(w^t) V^-1``, from one eigensolution of
    ``Q - I`` (the eigenvectors of ``Q``; its eigenvalues ``w - 1`` carry the step's change to
    full precision)."""

    def __init__(self, P_a: np.ndarray, P: np.ndarray):
        d, self.V = np.linalg.eig(np.linalg.solve(P_a, P - P_a))
        with np.errstate(divide="ignore", invalid="ignore"):
            self.logw = np.log1p(d)
        self.Vinv = np.linalg.inv(self.V) if np.all(np.isfinite(self.V)) else self.V

    def usable(self) -> bool:
        """Every eigenvalue turned by at most :data:`GEODESIC_MAX_TURN`, the eigenvectors'
        condition (in the 1-norm) within :data:`GEODESIC_MAX_CONDITION`."""
        if not (np.all(np.isfinite(self.logw)) and np.all(np.isfinite(self.Vinv))):
            return False
        cond = np.abs(self.V).sum(axis=0).max() * np.abs(self.Vinv).sum(axis=0).max()
        return bool(np.abs(self.logw.imag).max() <= GEODESIC_MAX_TURN and cond <= GEODESIC_MAX_CONDITION)

    def power(self, t: np.ndarray) -> np.ndarray:
        """``Q^t`` for every ``t`` of a 1-d array, ``(len(t), m, m)``."""
        return np.real((self.V * np.exp(np.asarray(t)[:, None, None] * self.logw)) @ self.Vinv)

    def log(self) -> np.ndarray:
        """``L = log Q``."""
        return np.real((self.V * self.logw) @ self.Vinv)


def geodesic_step_ratio(P_a: np.ndarray, P_b: np.ndarray, P_before: np.ndarray | None = None,
                        s_before: float = -1.0, s_b: float = 1.0, substeps: int = INTERPOLANT_SUBSTEPS,
                        geodesic_substeps: int = GEODESIC_SUBSTEPS, floor: float = 0.005,
                        near: float = 0.3) -> float:
    """The step rule of :func:`interpolated_step_ratio` on the geodesic
    ``P(t) = P_a (P_a^-1 P_b)^t`` as well as on the straight line between the blocks, with the
    geodesic's error estimated from the point before the step; the smaller ratio counts.

    A block of the form ``P_a exp(A dT)`` (a lightly damped string whose period changes) lies on
    its geodesic: its pairs turn on their circles, where the straight line cuts across the
    chord and its determinant defect binds the step although the multipliers stay off the
    circle. The geodesic's own error is the curvature of ``Lambda(s) = log(P_a^-1 P(s))`` along
    the branch (``s`` the arclength, ``s_before < 0`` at ``P_before``, ``s_b > 0`` at ``P_b``):
    the parabola through the three points gives the mid-step error
    ``E = -(s_b^2 / 4) (L_b / s_b - L_before / s_before) / (s_b - s_before)``, and each
    multiplier's first-order shift by ``P(1/2) E`` must stay within half its own distance from
    the circle (or ``floor``), as the linear rule's defect (:func:`_model_error_ratio`). Each model, within its own
    error bound, certifies the step, hence the smaller ratio (where multipliers near zero leave
    the logarithms carrying rounding, the geodesic's estimate is large and the line's ratio
    counts). The line alone judges the step where its ratio is at most :data:`LENIENT`, without
    a point before the step, or where a logarithm is not usable (:meth:`StepLog.usable`: a turn
    of more than :data:`GEODESIC_MAX_TURN` over the step, or eigenvectors too ill-conditioned).
    The geodesic is sampled at ``geodesic_substeps``, the line at ``substeps``.
    """
    P_a, P_b = np.asarray(P_a, dtype=float), np.asarray(P_b, dtype=float)
    line = interpolated_step_ratio(P_a, P_b, substeps, floor, near)
    if line <= LENIENT or P_before is None:
        return line
    geodesic = geodesic_model_ratio(P_a, P_b, P_before, s_before, s_b, geodesic_substeps, floor, near)
    return line if geodesic is None else float(min(line, geodesic))


def geodesic_model_ratio(P_a: np.ndarray, P_b: np.ndarray, P_before: np.ndarray, s_before: float, s_b: float,
                         substeps: int = GEODESIC_SUBSTEPS, floor: float = 0.005,
                         near: float = 0.3) -> float | None:
    """The geodesic's own ratio in :func:`geodesic_step_ratio`: :func:`path_step_ratio` of the
    multipliers along ``P_a (P_a^-1 P_b)^t`` and its error estimate against their distance from
    the circle; None where a logarithm is not usable (:meth:`StepLog.usable`) or the arclengths
    do not bracket ``P_a`` (``s_before < 0 < s_b``)."""
    P_a, P_b = np.asarray(P_a, dtype=float), np.asarray(P_b, dtype=float)
    if not s_before < 0.0 < s_b:
        return None
    step, back = StepLog(P_a, P_b), StepLog(P_a, np.asarray(P_before, dtype=float))
    if not (step.usable() and back.usable()):
        return None
    geodesic = P_a @ step.power(np.linspace(0.0, 1.0, substeps + 1)[1:-1])
    mus = _path_multipliers(np.concatenate([P_a[None], geodesic, P_b[None]]))
    ratio = path_step_ratio(mus, floor, near)
    E = -(s_b * s_b / 4.0) * (step.log() / s_b - back.log() / s_before) / (s_b - s_before)
    middle = geodesic[substeps // 2 - 1]
    return float(max(ratio, _model_error_ratio(middle, middle @ E, mus, floor)))


def _model_error_ratio(P: np.ndarray, dP: np.ndarray, mus: np.ndarray, floor: float) -> float:
    """The model error ``dP`` of the block ``P`` at mid-step against the multipliers' distance
    from the circle: each multiplier's first-order shift ``|y_i^H dP x_i|`` (``x_i``, ``y_i`` its
    right and left eigenvectors, ``y_i^H x_i = 1``) over half its own distance (or ``floor``).
    The shift of a multiplier far inside the disc does not count against one near the circle,
    and near a collision on the real axis the eigenvectors' condition makes the shifts large, as
    the true ones are. Where the eigenvectors cannot be inverted, ``|dP|`` against the least
    distance along the path ``mus``."""
    try:
        mu, X = np.linalg.eig(P)
        shift = np.abs(np.einsum("ij,jk,ki->i", np.linalg.inv(X), dP, X))
    except np.linalg.LinAlgError:
        shift = None
    if shift is None or not np.all(np.isfinite(shift)):
        crit = float(np.abs(np.abs(mus) - 1.0).min())
        return float(np.linalg.norm(dP, 2)) / max(0.5 * crit, floor)
    return float((shift / np.maximum(0.5 * np.abs(np.abs(mu) - 1.0), floor)).max())


def scaled_distance(ev_a, ev_b, u_scale: np.ndarray, lam_scale: float) -> float:
    """The scaled distance between two points of a branch (evaluations with ``u`` and ``lam``:
    ``u / u_scale``, ``lambda / lam_scale``), the measure of arclength the geodesic rules'
    error estimates take."""
    du = (ev_b.u - ev_a.u) / u_scale
    return float(np.hypot(np.linalg.norm(du), (ev_b.lam - ev_a.lam) / lam_scale))


def is_stable(mu: np.ndarray) -> bool:
    """All multipliers strictly inside the unit circle."""
    return bool(np.abs(mu).max() < 1.0)
