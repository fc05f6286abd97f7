"""The case: one cable, its loads, the analysis and the run settings, validated and frozen."""

from __future__ import annotations

import re
from typing import Literal

import numpy as np
import yaml
from pydantic import Field, PrivateAttr, field_validator, model_validator

from ..cable import Cable
from ..channels import channel_index
from ..errors import CablesimError
from ..names import ANALYSES, SLACK_POLICIES
from .sections import (
    CableSpec,
    ContinuationSpec,
    DampingSpec,
    FigureSpec,
    FreeVibrationSpec,
    HistorySpec,
    IntegratorSpec,
    LoadsSpec,
    OutputsSpec,
    StrictModel,
    SweepSpec,
)


class Case(StrictModel):
    """One analysis case, as read from a YAML case file."""

    name: str | None = Field(default=None, description="case name; default: the file stem")
    cable: CableSpec
    loads: LoadsSpec
    analysis: Literal[ANALYSES] = "exact"
    slack: Literal[SLACK_POLICIES] = Field(
        default="continue",
        description="exact analysis: 'continue' through slack segments (tension-only, events located) "
        "or 'stop' where a segment first goes slack; the approximate analysis always stops",
    )
    damping: DampingSpec = DampingSpec(ratio=0.01)
    integrator: IntegratorSpec = IntegratorSpec()
    history: HistorySpec = HistorySpec()
    free_vibration: FreeVibrationSpec = FreeVibrationSpec()
    sweep: SweepSpec | None = None
    continuation: ContinuationSpec | None = None
    outputs: OutputsSpec = OutputsSpec()
    figure: FigureSpec | None = None
    _text: str = PrivateAttr(default="")

    def set_text(self, text: str) -> None:
        """Record the YAML text this case was read from (the readers of case files do)."""
        self._text = text

    @property
    def text(self) -> str:
        """The YAML text this case was read from (with any ``--set`` overrides recorded), stored
        with every result so that it can be rerun."""
        return self._text

    @field_validator("name")
    @classmethod
    def _safe_name(cls, v):
        if v is not None and not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", v):
            raise ValueError("use letters, digits, '.', '_' and '-' only (it names the output folder)")
        if v is not None and len(v) > 100:
            raise ValueError(f"is {len(v)} characters long; keep it to 100 (it names the output folder)")
        return v

    @model_validator(mode="after")
    def _sizes(self):
        n = self.cable.n_nodes
        for key in ("F0", "FL"):
            v = getattr(self.loads, key)
            if v is not None and len(v) != 2 * n:
                raise ValueError(
                    f"loads.{key} has {len(v)} values; this cable has n = {n} interior nodes, so it "
                    f"needs 2n = {2 * n} (horizontal, vertical for each node in turn)"
                )
        if self.damping.modes[1] > 2 * n or self.damping.modes[0] > 2 * n:
            raise ValueError(f"damping.modes must be between 1 and 2n = {2 * n}")
        fv = self.free_vibration
        for key in ("z0", "v0"):
            v = getattr(fv, key)
            if v is not None and len(v) != 2 * n:
                raise ValueError(f"free_vibration.{key} has {len(v)} values; it needs 2n = {2 * n}")
        length = sum(self.cable.S)
        if fv.z0 is not None and max(abs(x) for x in fv.z0) > length:
            raise ValueError(f"free_vibration.z0 moves a node by more than the cable's whole length ({length:g} m); "
                             "give displacements from the equilibrium smaller than that, in m")
        if fv.mode is not None and fv.mode > 2 * n:
            raise ValueError(f"free_vibration.mode must be between 1 and 2n = {2 * n}")
        for section in ("history", "free_vibration", "sweep", "outputs"):
            spec = getattr(self, section)
            for name in (getattr(spec, "channels", None) or ()) if spec is not None else ():
                try:
                    channel_index(name, 2 * n)
                except CablesimError as exc:
                    raise ValueError(f"{section}.channels: {exc}".rstrip(".")) from None
        return self

    def effective_yaml(self) -> str:
        """The case as it will run, every default filled in, as YAML (``cablesim check``)."""
        data = self.model_dump(mode="json", exclude_none=True)
        if isinstance(self.sweep, SweepSpec) and isinstance(self.sweep.omega, tuple):
            data["sweep"]["omega"] = list(self.sweep.omega)
        return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)

    # -- derived objects ---------------------------------------------------------------------
    def to_cable(self) -> Cable:
        """The :class:`~cablesim.cable.Cable` this case describes."""
        c = self.cable
        return Cable(c.L, c.H, np.array(c.S), c.axial_rigidity, np.array(c.masses))

    @property
    def F0(self) -> np.ndarray:
        """Sustained loads, N."""
        return np.array(self.loads.F0, dtype=float)

    @property
    def FL(self) -> np.ndarray:
        """Peak harmonic loads, N (zeros if not given)."""
        if self.loads.FL is None:
            return np.zeros(2 * self.cable.n_nodes)
        return np.array(self.loads.FL, dtype=float)


# ----------------------------------------------------------------------------------------------
# YAML
# ----------------------------------------------------------------------------------------------
