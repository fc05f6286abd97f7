"""Starting points for the periodic-orbit solver.

- :func:`linear_response_state`: the closed-form steady response of the linearised cable,
  ``Z = (K0 - w^2 M + i w C)^-1 gamma FL``, ``z(t) = Im(Z e^{i w t})``, at forcing phase 0:
  ``z(0) = Im Z``, ``v(0) = w Re Z``.
- :func:`integrate_to_steady`: a state after ``periods`` forcing periods of free running from
  a given state (transients decay; a stable orbit attracts it).
- :func:`state_from_history`: the physical state ``(z, y')`` from the time integrators' third-order
  state ``(z, y', y'')`` (drops ``y''``, which eq. 15 determines).
"""

from __future__ import annotations

import numpy as np

from . import kernels as ok
from .shooting import Shooting


def linear_response(eom, omega: float, gamma: float = 1.0) -> np.ndarray:
    """Complex amplitude ``Z`` of the linear steady response to ``gamma FL sin(w t)``, m."""
    M = np.diag(eom.mass)
    D = eom.K0 - omega**2 * M + 1j * omega * eom.C
    return np.linalg.solve(D, gamma * np.asarray(eom.FL, dtype=float))


def linear_response_state(eom, omega: float, gamma: float = 1.0) -> np.ndarray:
    """``(z(0), v(0))`` of the linear steady response at forcing phase 0."""
    Z = linear_response(eom, omega, gamma)
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
