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
from .charts import BackboneSpec
from .continuation_spec import ContinuationSpec
from .integrator_spec import IntegratorSpec
from .placement import Placement, place
from .sections import (
    CableSpec,
    DampingSpec,
    FigureSpec,
    FreeVibrationSpec,
    HistorySpec,
    LoadsSpec,
    ModalSpec,
    OutputsSpec,
    StrictModel,
    SweepSpec,
)
from .supports import SupportsSpec


class Case(StrictModel):
    """One analysis case, as read from a YAML case file."""

    name: str | None = Field(default=None, description="case name; default: the file stem")
    spatial: bool = Field(default=False, description="three components per node (x, v, w); implied by cable.W, "
                          "three-component loads or a support moving out of the plane")
    cable: CableSpec
    loads: LoadsSpec
    supports: SupportsSpec | None = Field(default=None, description="harmonic motion of the supports")
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
    _dim: int = PrivateAttr(default=2)
    _placements: tuple = PrivateAttr(default=())

    def __eq__(self, other) -> bool:
        """Equal cases run alike: the same sections and text, whether a point load was written by
        node or by position (:attr:`placements` says how it was written, not what runs)."""
        if not isinstance(other, Case):
            return NotImplemented
        return self.__dict__ == other.__dict__ and (self._text, self._dim) == (other._text, other._dim)

    def set_placements(self, placements) -> None:
        """Record where the items of ``loads.point`` were placed, as read from a stored case text
        whose lists are explicit (the readers of case files do)."""
        self._placements = tuple(placements)

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

    @property
    def placements(self) -> tuple[Placement, ...]:
        """Where each item of ``loads.point`` went: its node and, for one given by position
        (``x`` or ``s``), the snap distance to that node (empty without ``loads.point``)."""
        return self._placements

    @property
    def dim(self) -> int:
        """Components per node: 2 (planar) or 3 (spatial)."""
        return self._dim

    def _components(self) -> int:
        """3 if the case is spatial (it says so, support B is out of the plane, a load has three
        components, or a support moves out of the plane), else 2."""
        c, ld, n = self.cable, self.loads, self.cable.n_nodes
        if self.spatial or c.W != 0.0 or (self.supports is not None and self.supports.out_of_plane):
            return 3
        if any(v is not None and len(v) == 3 * n for v in (ld.F0, ld.FL)):
            return 3
        if any(len(p.F or ()) == 3 or len(p.FL or ()) == 3 for p in ld.point or ()):
            return 3
        if ld.per_length is not None and len(ld.per_length) == 3:
            return 3
        return 2

    @model_validator(mode="after")
    def _sizes(self):
        self._dim = self._components()
        self._expand()
        n, dim = self.cable.n_nodes, self._dim
        nd = dim * n
        for key in ("F0", "FL"):
            v = getattr(self.loads, key)
            if v is not None and len(v) not in (2 * n, nd):
                raise ValueError(
                    f"loads.{key} has {len(v)} values; this cable has n = {n} interior nodes, so it "
                    f"needs 2n = {2 * n} (horizontal, vertical for each node in turn)"
                    + (f" or 3n = {3 * n} (x, v, w for each node, a spatial case)" if n > 0 else "")
                )
        if self.damping.modes[1] > nd or self.damping.modes[0] > nd:
            raise ValueError(f"damping.modes must be between 1 and {dim}n = {nd}")
        if self.modal.modes is not None and self.modal.modes > nd:
            raise ValueError(f"modal.modes is {self.modal.modes}; this cable has {dim}n = {nd} modes")
        fv = self.free_vibration
        for key in ("z0", "v0"):
            v = getattr(fv, key)
            if v is not None and len(v) not in (2 * n, nd):
                raise ValueError(f"free_vibration.{key} has {len(v)} values; it needs {dim}n = {nd}")
        length = sum(self.cable.S)
        if fv.z0 is not None and max(abs(x) for x in fv.z0) > length:
            raise ValueError(f"free_vibration.z0 moves a node by more than the cable's whole length ({length:g} m); "
                             "give displacements from the equilibrium smaller than that, in m")
        if fv.mode is not None and fv.mode > nd:
            raise ValueError(f"free_vibration.mode must be between 1 and {dim}n = {nd}")
        for section in ("history", "sweep"):
            spec = getattr(self, section)
            if spec is not None and (spec.disturbance or 0.0) > 0 and dim != 3:
                raise ValueError(f"{section}.disturbance is an out-of-plane displacement, for spatial cases only; set "
                                 "spatial: true, or remove it")
        if self.supports is not None and self.supports.moving and self.analysis != "exact":
            raise ValueError("supports: moving supports need the exact analysis; set analysis: exact")
        moving = self.supports is not None and self.supports.moving
        if self.continuation is not None and not moving and self.continuation.loci_parameter == "support":
            raise ValueError(
                "continuation.loci with continuation.support a range continues the bifurcation curves in the "
                "support motion multiplier s, but no support of this case moves; add one, e.g. `supports: {A: "
                "{amplitude: [0.004, -0.003]}}` (m), or give the curves a range of gamma (continuation.gamma "
                "{start: .., stop: ..}) and continuation.support a single value")
        if self.continuation is not None and not moving and (self.continuation.parameter == "support"
                                                             or self.continuation.support != 1.0):
            raise ValueError(
                "continuation.support multiplies the amplitudes of moving supports, but no support of this case "
                "moves; add one, e.g. `supports: {A: {amplitude: [0.004, -0.003]}}` (m), or continue in omega "
                "or gamma (continuation.parameter)")
        if self.backbone.mode > nd:
            raise ValueError(f"backbone.mode is {self.backbone.mode}; this cable has {dim}n = {nd} modes")
        for section in ("history", "free_vibration", "sweep", "outputs", "continuation", "backbone", "figure"):
            spec = getattr(self, section)
            for name in (getattr(spec, "channels", None) or ()) if spec is not None else ():
                try:
                    channel_index(name, nd, dim)
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
        n, dim = c.n_nodes, self._dim
        masses = np.array(c.masses, dtype=float)
        F0 = np.zeros(dim * n) if ld.F0 is None else np.array(ld.F0, dtype=float)
        FL = None if ld.FL is None else np.array(ld.FL, dtype=float)
        for key, v in (("F0", F0), ("FL", FL)):
            if v is not None and len(v) not in (2 * n, dim * n):
                raise ValueError(f"loads.{key} has {len(v)} values; this cable has n = {n} interior nodes, so it "
                                 f"needs 2n = {2 * n} (horizontal, vertical for each node in turn)"
                                 + (f" or 3n = {3 * n} (x, v, w, a spatial case)" if dim == 3 else ""))
        F0 = node_components(F0, n, dim)
        FL = None if FL is None else node_components(FL, n, dim)
        self._placements = tuple(place(k + 1, p, c.S, c.L) for k, p in enumerate(ld.point or ()))
        for p, where in zip(ld.point or (), self._placements):
            i = where.node - 1
            masses[i] += p.mass or 0.0
            F0[dim * i:dim * i + len(p.F or ())] += p.F or ()
            if p.FL is not None:
                FL = np.zeros(dim * n) if FL is None else FL
                FL[dim * i:dim * i + len(p.FL)] += p.FL
        F0[1::dim] += (ld.gravity or 0.0) * masses
        if ld.per_length is not None:  # lumped like the masses: half of each adjacent segment
            S = np.asarray(c.S, dtype=float)
            share = 0.5 * (S[:-1] + S[1:])
            for d, q in enumerate(ld.per_length):
                F0[d::dim] += q * share
        rigidity = {"EA": c.EA} if c.EA is not None else {"E": c.E, "A": c.A}
        try:
            cable = CableSpec(L=c.L, H=c.H, W=c.W, S=c.S, masses=tuple(masses.tolist()), **rigidity)
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
        return Cable(c.L, c.H, np.array(c.S), c.axial_rigidity, np.array(c.masses), W=c.W, dim=self._dim)

    @property
    def F0(self) -> np.ndarray:
        """Sustained loads, N, ``dim`` components per node (a planar list padded with w = 0)."""
        return node_components(self.loads.F0, self.cable.n_nodes, self._dim)

    @property
    def FL(self) -> np.ndarray:
        """Peak harmonic loads, N (zeros if not given), ``dim`` components per node."""
        if self.loads.FL is None:
            return np.zeros(self._dim * self.cable.n_nodes)
        return node_components(self.loads.FL, self.cable.n_nodes, self._dim)

    @property
    def forced(self) -> bool:
        """Whether the cable is forced: harmonic loads FL or a moving support."""
        return bool(np.any(self.FL)) or (self.supports is not None and self.supports.moving)

    def support_motion(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """``(uA, uB, phA, phB)``: the supports' amplitudes (m, ``dim`` components) and phases (rad)."""
        sp, dim = self.supports, self._dim
        motion = [(np.zeros(dim), 0.0) if m is None else (np.array(m.components(dim)), float(m.phase))
                  for m in ((sp.A, sp.B) if sp is not None else (None, None))]
        return motion[0][0], motion[1][0], motion[0][1], motion[1][1]


def node_components(values, n: int, dim: int) -> np.ndarray:
    """A list of nodal values (loads, displacements) with ``dim`` components per node: a list of
    ``2 n`` (x, v per node) is padded with ``w = 0`` for a spatial cable."""
    v = np.array(values, dtype=float)
    if dim == 2 or v.size == dim * n:
        return v
    out = np.zeros((n, dim))
    out[:, :2] = v.reshape(n, 2)
    return out.ravel()


# ----------------------------------------------------------------------------------------------
# YAML
# ----------------------------------------------------------------------------------------------
