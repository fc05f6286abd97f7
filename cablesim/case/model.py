"""The case: one cable, its loads, the analysis and the run settings, validated and frozen."""

from __future__ import annotations

import re
from typing import Literal

import numpy as np
import yaml
from pydantic import Field, PrivateAttr, ValidationError, field_validator, model_validator

from ..cable import Cable
from ..channels import channel_index
from ..errors import CablesimError
from ..names import ANALYSES, SLACK_POLICIES
from .sections import (
    BackboneSpec,
    CableSpec,
    ContinuationSpec,
    DampingSpec,
    FigureSpec,
    FreeVibrationSpec,
    HistorySpec,
    IntegratorSpec,
    LoadsSpec,
    ModalSpec,
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
    modal: ModalSpec = ModalSpec()
    integrator: IntegratorSpec = IntegratorSpec()
    history: HistorySpec = HistorySpec()
    free_vibration: FreeVibrationSpec = FreeVibrationSpec()
    sweep: SweepSpec | None = None
    continuation: ContinuationSpec | None = None
    backbone: BackboneSpec = BackboneSpec()
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
        self._expand()
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
        if self.modal.modes is not None and self.modal.modes > 2 * n:
            raise ValueError(f"modal.modes is {self.modal.modes}; this cable has 2n = {2 * n} modes")
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
        if self.backbone.mode > 2 * n:
            raise ValueError(f"backbone.mode is {self.backbone.mode}; this cable has 2n = {2 * n} modes")
        for section in ("history", "free_vibration", "sweep", "outputs", "continuation", "backbone", "figure"):
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

    def _expand(self) -> None:
        """Replace the shorthand (cable.length/nodes/mass_per_length, loads.gravity/point) by the
        explicit lists it stands for, so that the rest of cablesim sees S, masses, F0 and FL."""
        c, ld = self.cable, self.loads
        if not (c.shorthand or ld.shorthand):
            return
        n = c.n_nodes
        masses = np.array(c.masses, dtype=float)
        F0 = np.zeros(2 * n) if ld.F0 is None else np.array(ld.F0, dtype=float)
        FL = None if ld.FL is None else np.array(ld.FL, dtype=float)
        for key, v in (("F0", F0), ("FL", FL)):
            if v is not None and len(v) != 2 * n:
                raise ValueError(f"loads.{key} has {len(v)} values; this cable has n = {n} interior nodes, so it "
                                 f"needs 2n = {2 * n} (horizontal, vertical for each node in turn)")
        for k, p in enumerate(ld.point or ()):
            if p.node > n:
                raise ValueError(f"`loads.point[{k + 1}].node` is {p.node}, but this cable has n = {n} interior "
                                 f"nodes; count them from 1 at support A")
            i = p.node - 1
            masses[i] += p.mass or 0.0
            F0[2 * i:2 * i + 2] += p.F or (0.0, 0.0)
            if p.FL is not None:
                FL = np.zeros(2 * n) if FL is None else FL
                FL[2 * i:2 * i + 2] += p.FL
        F0[1::2] += (ld.gravity or 0.0) * masses
        rigidity = {"EA": c.EA} if c.EA is not None else {"E": c.E, "A": c.A}
        try:
            cable = CableSpec(L=c.L, H=c.H, S=c.S, masses=tuple(masses.tolist()), **rigidity)
            loads = LoadsSpec(F0=tuple(F0.tolist()), FL=None if FL is None else tuple(FL.tolist()))
        except ValidationError as err:  # e.g. point masses or weights beyond the ranges of the lists
            e = err.errors()[0]
            field = ".".join(["cable" if err.title == "CableSpec" else "loads", *(str(x) for x in e["loc"][:1])])
            msg = e["msg"].removeprefix("Value error, ")
            raise ValueError(f"with the shorthand expanded, `{field}` {msg}") from None
        object.__setattr__(self, "cable", cable)
        object.__setattr__(self, "loads", loads)

    def expanded(self) -> dict:
        """The ``cable`` and ``loads`` sections as explicit lists (the shorthand expanded)."""
        return {key: getattr(self, key).model_dump(mode="json", exclude_none=True) for key in ("cable", "loads")}

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
