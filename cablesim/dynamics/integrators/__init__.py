"""Time-integration schemes, by name.

=====================  =====  =====================================================
name                   order  kind
=====================  =====  =====================================================
``rk4``                4      explicit, fixed step, third-order state (paper)
``dopri5``             5      explicit, adaptive (rtol, atol), third-order state
``newmark``            2      implicit, average acceleration (paper): error-controlled
                              (rtol, atol), or a fixed step dt
``generalized-alpha``  2      implicit, high-mode dissipation rho_inf: error-controlled
                              (rtol, atol), or a fixed step dt
=====================  =====  =====================================================
"""

from .base import Integrator, IntegratorState
from .implicit import GeneralizedAlpha, Newmark
from .rk import DOPRI5, RK4

INTEGRATORS: dict[str, type[Integrator]] = {
    cls.name: cls for cls in (RK4, DOPRI5, Newmark, GeneralizedAlpha)
}
#: The table of settings, defaults and the default rule: :mod:`cablesim.dynamics.integrators.settings`.

__all__ = ["INTEGRATORS", "Integrator", "IntegratorState", "RK4", "DOPRI5", "Newmark", "GeneralizedAlpha"]
