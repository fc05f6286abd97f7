"""Starting points for the periodic-orbit solver.

- :func:`linear_response_state`: the closed-form steady response of the linearised cable,
  ``Z = (K0 - w^2 M + i w C)^-1 gamma FL``, ``z(t) = Im(Z e^{i w t})``, at forcing phase 0:
  ``z(0) = Im Z``, ``v(0) = w Re Z``.
- :func:`integrate_to_steady`: a state after ``periods`` forcing periods of free running from
  a given state (transients decay; a stable orbit attracts it).
- :func:`state_from_history`: the physical state ``(z, y')`` from the time integrators' third-order
  state ``(z, y', y'')`` (drops ``y''``, which eq. 15 determines).
- :func:`cable_scales`: the scales of the state and of the parameter for a cable's continuation.
"""

from __future__ import annotations

import numpy as np

from . import kernels as ok
from .shooting import Shooting
from .symmetry import cable_mirror, component_frequencies


def linear_response(eom, omega: float, gamma: float = 1.0, support: float = 1.0) -> np.ndarray:
    """Complex amplitude ``Z`` of the linear steady response (``z = Im(Z exp(i w t))``, m) to
    ``gamma FL sin(w t)`` and the supports' motion times ``gamma support``
    (:meth:`~cablesim.dynamics.equations.EquationsOfMotion.support_load`)."""
    M = np.diag(eom.mass)
    D = eom.K0 - omega**2 * M + 1j * omega * eom.C
    load = gamma * np.asarray(eom.FL, dtype=float)
    if eom.moving_supports:
        load = load + gamma * support * eom.support_load(omega)
    return np.linalg.solve(D, load)


def linear_response_state(eom, omega: float, gamma: float = 1.0, support: float = 1.0) -> np.ndarray:
    """``(z(0), v(0))`` of the linear steady response at forcing phase 0."""
    Z = linear_response(eom, omega, gamma, support)
    return np.concatenate([Z.imag, omega * Z.real])


def state_from_history(s: np.ndarray, n_dof: int) -> np.ndarray:
    """``(z, y')`` from a third-order state ``(z, y', y'')`` (or pass ``(z, y')`` through)."""
    s = np.asarray(s, dtype=float)
    return s[: 2 * n_dof].copy()


def integrate_to_steady(shooting: Shooting, x0: np.ndarray, lam: float, periods: int = 50) -> np.ndarray | None:
    """The state after ``periods`` forcing periods from ``x0`` at forcing phase 0 (None if the
    integration fails). Uses the shooting scheme without variational equations."""
    x = np.asarray(x0, dtype=float).copy()
    laps = max(1, int(np.ceil(periods / shooting.period)))
    for _ in range(laps):
        for k in range(shooting.segments):
            seg = shooting.segment(k, x, lam, jac=False)
            if seg["status"] != ok.OK:
                return None
            x = seg["x"]
    return x


def cable_scales(eom, parameter: str, start: float, stop: float, gamma: float = 1.0, support: float = 1.0):
    """State and parameter scales of the cable problem, properties of the case (not of the range
    asked for, so that a branch is traced alike whatever part of it is requested).

    Displacements: the largest linear-response amplitude (to ``FL`` and to the supports' motion,
    :func:`linear_response`) at the largest load factor, over the
    range (a grid of 64 values) and at every linear resonance (the modal frequencies), floored at
    1e-6 of the chord: a nonlinear branch born far from resonance (a period doubling near
    ``2 w1``) grows to amplitudes of the primary resonance, which a range-local scale would not
    see. Velocities: that times the fundamental frequency of each component
    (:func:`~cablesim.orbits.symmetry.component_frequencies`: of its block on a cable with a
    mirror symmetry, so that a planar branch is traced in the planar cable's steps). Parameter:
    its largest magnitude.
    In ``s`` (support): at least the supports' largest amplitude at the largest ``s`` (and 1).
    """
    if parameter == "omega":
        g = gamma
        freqs = np.concatenate([np.linspace(min(start, stop), max(start, stop), 64), eom.frequencies])
    else:
        g = max(abs(start), abs(stop)) if parameter == "gamma" else gamma
        freqs = np.concatenate([[eom.omega], eom.frequencies])
    s = max(abs(start), abs(stop)) if parameter == "support" else support
    amp = max(float(np.abs(linear_response(eom, w, g, s)).max()) for w in freqs if w > 0)
    if parameter == "support":
        amp = max(amp, g * max(1.0, abs(start), abs(stop)) * float(np.abs(np.concatenate([eom.uA, eom.uB])).max()))
    amp = max(amp, 1e-6 * eom.cable.chord_length)
    nd = eom.n_dof
    scale = np.concatenate([np.full(nd, amp), amp * component_frequencies(eom, cable_mirror(eom))])
    lam_scale = max(abs(start), abs(stop))
    return scale, lam_scale
