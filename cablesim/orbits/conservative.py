"""The unforced, undamped cable with an artificial damping parameter, for backbone curves.

``M z'' + P(y0 + z) - F0 = 0`` (no harmonic load, no structural damping) conserves the
mechanical energy ``1/2 v^T M v + U(z)``, ``U`` the strain energy less the work of ``F0``. The
fields here are the cable's own (:mod:`cablesim.orbits.cablefield`, exact or approximate
analysis) evaluated with ``FL = 0`` and ``C = 0``, plus the unfolding term of
:mod:`cablesim.orbits.backbone`::

    v' = M^-1 (F0 - P(y0 + z)) - delta v

whose energy rate ``-delta v^T M v`` is negative on every motion when ``delta > 0``, with the
derivative ``d v' / d delta = -v`` for the shooting kernel (``prm = (gamma, support, delta)``,
the first two those of :mod:`cablesim.orbits.cablefield`: gamma multiplies the zero harmonic
load, and the supports are held at rest).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from . import cablefield
from .kernels import OK
from .systems import OdeSystem, cable_system

#: Index of the artificial damping ``delta`` in ``prm`` (after the cable field's own).
DELTA = 2


@njit
def _unfold(x, prm, dx, J, dp, ipar):
    """Add ``-delta v`` to the rates of a mechanical state ``x = (z, v)``, its Jacobian and, for
    ``ipar == DELTA``, its derivative."""
    nd = x.size // 2
    d = prm[DELTA]
    for i in range(nd):
        dx[nd + i] -= d * x[nd + i]
        J[nd + i, nd + i] -= d
    if ipar == DELTA:
        for i in range(nd):
            dp[i] = 0.0
            dp[nd + i] = -x[nd + i]


@njit(borrowed=True)  # called at every stage: no reference counting (cablesim.jit)
def unfolded_exact_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    """Exact analysis, unforced and undamped (``model.FL = 0``, ``model.C = 0``), unfolded."""
    code = cablefield.exact_field(theta, omega, x, model, prm, work, dx, J, dp, -1)
    if code != OK:
        return code
    _unfold(x, prm, dx, J, dp, ipar)
    return OK


@njit
def unfolded_approximate_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    """Approximate analysis, unforced and undamped, unfolded."""
    code = cablefield.approximate_field(theta, omega, x, model, prm, work, dx, J, dp, -1)
    if code != OK:
        return code
    _unfold(x, prm, dx, J, dp, ipar)
    return OK


def conservative_cable_system(eom) -> OdeSystem:
    """The cable's free undamped motions about its equilibrium under ``F0``, with the unfolding
    parameter ``"delta"`` (module docstring).

    Parameters
    ----------
    eom : EquationsOfMotion
        Exact or approximate analysis; its harmonic load and damping are dropped.

    Returns
    -------
    OdeSystem
        State ``(z, v)``; ``omega`` is the lowest modal frequency (the backbone sets its own);
        ``fastest_rate`` the highest undamped modal frequency.
    """
    forced = cable_system(eom)
    model = forced.model._replace(C=np.zeros_like(forced.model.C), FL=np.zeros_like(forced.model.FL), moving=False)
    field = unfolded_exact_field if eom.analysis == "exact" else unfolded_approximate_field
    nd = eom.n_dof
    A = np.zeros((2 * nd, 2 * nd))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -eom.K0 / eom.mass[:, None]
    rate = float(np.abs(np.linalg.eigvals(A)).max())
    return OdeSystem(field=field, dim=2 * nd, prm=np.array([0.0, 0.0, 0.0]), work=forced.work, model=model,
                     omega=float(eom.frequencies[0]), parameters={"delta": DELTA}, fastest_rate=rate,
                     displacements=forced.displacements, divergence=None, noise=forced.noise, names=forced.names)
