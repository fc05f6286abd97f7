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
    mu_a = np.asarray(mu_a, dtype=complex)
    mu_b = np.asarray(mu_b, dtype=complex)
    ma = np.sort(np.abs(mu_a))
    mb = np.sort(np.abs(mu_b))
    crit = float(np.abs(ma - 1.0).min())
    ratio = float(np.abs(mb - ma).max()) / max(0.5 * crit, floor)
    dist = np.minimum(np.abs(mu_a + 1.0), np.abs(mu_a - 1.0))
    for k in np.flatnonzero(dist < near):
        moved = float(np.abs(mu_b - mu_a[k]).min())  # to its nearest partner at b
        ratio = max(ratio, moved / max(0.5 * float(dist[k]), floor))
    return ratio


#: Sub-steps of the linear interpolant of a monodromy block (:func:`interpolated_step_ratio`).
INTERPOLANT_SUBSTEPS = 8


def interpolated_step_ratio(P_a: np.ndarray, P_b: np.ndarray, substeps: int = INTERPOLANT_SUBSTEPS,
                            floor: float = 0.005, near: float = 0.3) -> float:
    """:func:`step_ratio` of a block of the monodromy between two points, judged on the matrix
    instead of its multipliers: the matrix is smooth along a branch, the multipliers are not
    (a conjugate pair meeting on the real axis, the start of a period-doubling or a +1 tongue,
    moves as a square root of the parameter there), so their linear motion between the points,
    which :func:`step_ratio` bounds, is a poor model exactly where it matters.

    The block is interpolated linearly, ``P(t) = (1 - t) P_a + t P_b``, and the step's ratio is
    the largest of

    - :func:`step_ratio` between the multipliers of ``P`` at consecutive sub-steps
      ``t = k / substeps`` (the moduli and the motion near ``+1`` and ``-1``, now of a path that
      goes through the collisions on the real axis as the true multipliers do);
    - 2 (reject) if a test function (:func:`test_functions`) of ``P`` changes sign inside the
      step but not between its ends: a multiplier that passes ``-1`` or ``+1`` and back, or a
      pair through the circle and back, within the step;
    - the linear model's error against the distance of ``P``'s multipliers from the unit circle
      (at most half of it, or of ``floor``, as :func:`step_ratio`): the defect
      ``|det P(1/2) / sqrt(det P_a det P_b) - 1|``, since ``log det`` of the true block is
      smooth and nearly linear along the branch (Liouville's formula) while the interpolant's
      determinant falls short by ``(dtheta / 2)^2`` for every pair turning by ``dtheta`` over the
      step, about twice the error that turn gives its multipliers at mid-step.
    """
    P_a, P_b = np.asarray(P_a, dtype=float), np.asarray(P_b, dtype=float)
    ts = np.linspace(0.0, 1.0, substeps + 1)
    mus = [sort_multipliers(mu) for mu in np.linalg.eigvals(np.array([(1.0 - t) * P_a + t * P_b for t in ts]))]
    ratio = max(step_ratio(mus[k], mus[k + 1], floor, near) for k in range(substeps))
    signs = np.sign(test_functions(np.array(mus)))
    hidden = (np.count_nonzero(signs[1:] != signs[:-1], axis=0) > 0) & (signs[0] == signs[-1])
    if np.any(hidden):
        ratio = max(ratio, 2.0)
    mean = np.sqrt(abs(np.linalg.det(P_a) * np.linalg.det(P_b)))
    if mean > 0.0:
        defect = abs(np.linalg.det(0.5 * (P_a + P_b)) / mean - 1.0)
        crit = float(np.abs(np.abs(np.concatenate(mus)) - 1.0).min())
        ratio = max(ratio, defect / max(0.5 * crit, floor))
    return float(ratio)


def is_stable(mu: np.ndarray) -> bool:
    """All multipliers strictly inside the unit circle."""
    return bool(np.abs(mu).max() < 1.0)
