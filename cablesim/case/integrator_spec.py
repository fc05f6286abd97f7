"""The ``integrator:`` section of a case file: the scheme and its settings."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from ..names import INTEGRATOR_KEYS, INTEGRATOR_SETTINGS, INTEGRATORS
from .numbers import RTOL, TIME_STEP, real
from .sections import StrictModel


class IntegratorSpec(StrictModel):
    """Time-integration scheme and its settings (section ``integrator:``).

    Without a name cablesim chooses: ``dopri5`` for ordinary cables, ``generalized-alpha`` for
    stiff ones (highest mode over 200 times the frequency of interest).
    """

    name: Literal[INTEGRATORS] | None = None
    dt: TIME_STEP | None = Field(default=None, description="fixed step, s (rk4; newmark and generalized-alpha "
                                 "instead of error control)")
    rtol: RTOL | None = Field(default=None, description="relative tolerance (dopri5; newmark and generalized-alpha: "
                              "error-controlled steps)")
    atol: real(1e-16, 1e3, "m") | None = Field(default=None, description="absolute displacement tolerance, m (dopri5, "
                                               "newmark, generalized-alpha)")
    rho_inf: real(0.0, 1.0) | None = Field(default=None, description="spectral radius (generalized-alpha)")

    def settings(self) -> dict:
        """The settings given (``{key: value}``, None left out)."""
        return {k: getattr(self, k) for k in INTEGRATOR_KEYS if getattr(self, k) is not None}

    @model_validator(mode="after")
    def _fits(self):
        if self.dt is not None and (self.rtol is not None or self.atol is not None) and self.name is not None \
                and "dt" in INTEGRATOR_SETTINGS[self.name] and "rtol" in INTEGRATOR_SETTINGS[self.name]:
            raise ValueError(f"integrator.dt (a fixed step) and integrator.rtol/atol (error-controlled steps) exclude "
                             f"each other for {self.name}: give one of them")
        if self.name is not None:
            keys = INTEGRATOR_SETTINGS[self.name]
            bad = [k for k in self.settings() if k not in keys]
            if bad:
                taken = " and ".join(f"integrator.{k}" for k in keys)
                verb = "does" if len(bad) == 1 else "do"
                raise ValueError(f"{' and '.join(f'integrator.{k}' for k in bad)} {verb} not apply to {self.name}, "
                                 f"which takes {taken}")
        return self
