"""A linear modal estimate of a fixed-step explicit scheme's error on a forced response from rest.

A fixed step of so many steps per period of interest says nothing of the faster modes that the
start excites: loads and support motion switched on at ``t = 0`` leave every mode a free
transient, and a lightly damped fast mode (the axial modes of a taut stay, hundreds of rad/s)
rings for many of its own periods. Before the step is chosen, the linearised cable about its
equilibrium (``M q'' + C q' + K0 q = Im(G exp(i w t))``, ``G`` the harmonic loads and the
supports' load, :meth:`~cablesim.dynamics.equations.EquationsOfMotion.support_load`) is solved mode
by mode: mode ``k`` (frequency ``w_k``, damping ratio ``xi_k``, mass-normalised shape ``phi_k``)
has the steady amplitude ``P_k = phi_k^T G / (w_k^2 - w^2 + 2 i xi_k w_k w)`` and a free transient
``a_k`` that cancels the steady part's displacement and velocity at ``t = 0``.

A scheme of order ``p`` errs in a root ``lambda`` of relative size ``c (|lambda| h)^p`` (rk4:
``c = 1/120``, the leading term of its phase error). The steady part of mode ``k`` errs by that of
the forcing, ``c (w h)^p``, times its sensitivity to the root, ``|d ln H / d ln w_k|``; the
transient by ``c (|lambda_k| h)^p`` times the radians it lives, ``|lambda_k| / |Re lambda_k|`` (``1 /
xi_k``) over ``e`` (the phase error grows as ``w_k t`` while it decays as ``exp(-xi_k w_k t)``).
Summed over the modes, with each shape's largest displacement and largest segment tension
change, over the linear peaks, they give the errors in ``z`` and in the tensions relative to their
peaks. A nonlinear response is not estimated: the estimate sets a step that the measured errors
of the shipped examples sit below by factors of 2 to 3 where the response is near linear, and
12 below where it is not (benchmarks/README.md), so it is asked for :data:`TARGET`, a tenth of
the accuracy aimed at.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import CablesimError
from ...modal import modal_analysis, modal_damping_ratios
from ...statics import segment_geometry

#: The relative error (of the peaks in z and in the tensions) the estimate is held to: a tenth of
#: the 1e-5 every default aims at, for the nonlinearity it does not see.
TARGET = 1e-6
#: Beyond this many degrees of freedom the dense modal analysis (O(n^3)) is not done and no
#: estimate is made: such cables are stiff, and an explicit step is held by stability well below
#: the one accuracy needs (their fast roots are overdamped).
MAX_DOF = 1500
#: The radians an undamped mode's error is counted over at most (that of xi = 0.001).
LIFE_MAX = 1000.0


@dataclass(frozen=True)
class ModalResponse:
    """The linear response mode by mode (see the module's text).

    Attributes
    ----------
    omega : float
        Forcing frequency, rad/s (positive: without forcing no estimate is made).
    roots : ndarray, complex
        Each mode's root ``lambda_k`` (the fast one of an overdamped mode), 1/s.
    steady, sensitivity : ndarray
        ``|P_k|`` and ``|d ln H_k / d ln w_k|``.
    transient, life : ndarray
        The free transient's amplitude ``a_k`` and the radians it lives.
    z_shape, T_shape : ndarray
        Each shape's largest displacement (m per unit modal amplitude) and largest segment tension
        change (N per unit modal amplitude).
    z_peak, T_peak : float
        The linear peaks: largest steady displacement (m) and largest tension (N).
    """

    omega: float
    roots: np.ndarray
    steady: np.ndarray
    sensitivity: np.ndarray
    transient: np.ndarray
    life: np.ndarray
    z_shape: np.ndarray
    T_shape: np.ndarray
    z_peak: float
    T_peak: float

    def relative_errors(self, h: float, order: int, constant: float) -> tuple[float, float]:
        """The estimated errors in z and in the tensions relative to their peaks of a scheme of
        ``order`` whose relative root error is ``constant (|lambda| h)^order``, at step ``h`` (s)."""
        if self.z_peak <= 0.0:
            return 0.0, 0.0
        e_steady = constant * (self.omega * h) ** order * self.steady * self.sensitivity
        e_free = constant * (np.abs(self.roots) * h) ** order * self.transient * self.life / np.e
        per_mode = e_steady + e_free
        return (float(per_mode @ self.z_shape) / self.z_peak,
                float(per_mode @ self.T_shape) / self.T_peak if self.T_peak > 0 else 0.0)


def _tension_shapes(eom, shapes: np.ndarray) -> np.ndarray:
    """``EA / S_j`` times each segment's elongation per unit modal amplitude, largest over the
    segments, for every mode (N)."""
    c = eom.cable
    unit = segment_geometry(c, eom.y0)[1]  # (n + 1, dim): along each segment at the equilibrium
    m = shapes.shape[1]
    disp = np.zeros((c.n_nodes + 2, c.dim, m))  # the supports held
    disp[1:-1] = shapes.reshape(c.n_nodes, c.dim, m)
    elong = np.einsum("jd,jdm->jm", unit, np.diff(disp, axis=0))
    return np.abs(c.EA / np.asarray(c.S, dtype=float)[:, None] * elong).max(axis=0)


def modal_response(eom) -> ModalResponse | None:
    """The linear modal response of ``eom`` from rest (:class:`ModalResponse`), or None where no
    estimate is made: no forcing, more than :data:`MAX_DOF` degrees of freedom, or an
    equilibrium that is not stable (the linearisation has no modes)."""
    w = float(eom.omega)
    if w <= 0.0 or eom.n_dof > MAX_DOF:
        return None
    try:
        modes = modal_analysis(eom.K0, np.asarray(eom.mass, dtype=float))
    except CablesimError:
        return None
    wk, phi = modes.omega, modes.shapes
    xi = modal_damping_ratios(wk, eom.a0, eom.a1)
    G = np.asarray(eom.FL, dtype=float) + eom.support_load(w)
    den = wk ** 2 - w ** 2 + 2j * xi * wk * w
    P = (phi.T @ G) / den
    under = xi < 1.0
    root = np.where(under, wk * (-xi + 1j * np.sqrt(np.maximum(1.0 - xi ** 2, 0.0))),
                    wk * (-xi - np.sqrt(np.maximum(xi ** 2 - 1.0, 0.0))))
    q0, v0 = -P.imag, -w * P.real  # the transient cancels Im(P exp(i w t)) and its rate at t = 0
    damped = np.maximum(np.abs(root.imag), 1e-12 * wk)
    a = np.where(under, np.hypot(q0, (v0 + xi * wk * q0) / damped), np.abs(q0) + np.abs(v0) / np.abs(root))
    life = np.minimum(np.abs(root) / np.maximum(np.abs(root.real), 1e-300), LIFE_MAX)
    sensitivity = np.abs(2.0 * wk ** 2 + 2j * xi * wk * w) / np.abs(den)
    z_lin = phi @ P
    T_shape = _tension_shapes(eom, phi)
    return ModalResponse(omega=w, roots=root, steady=np.abs(P), sensitivity=sensitivity, transient=a, life=life,
                         z_shape=np.abs(phi).max(axis=0), T_shape=T_shape, z_peak=float(np.abs(z_lin).max()),
                         T_peak=float(np.max(np.abs(eom.T0))))


def accurate_step(eom, h: float, order: int, constant: float, target: float = TARGET) -> float:
    """The step (s), at most ``h``, at which the estimated errors in z and in the tensions are
    within ``target``; ``h`` where no estimate is made (:func:`modal_response`)."""
    resp = modal_response(eom)
    if resp is None:
        return h
    worst = max(resp.relative_errors(h, order, constant))
    return h if worst <= target else h * (target / worst) ** (1.0 / order)
