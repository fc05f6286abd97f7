"""The sections of a case file (``cable:``, ``loads:``, ``sweep:``, ...), each a frozen pydantic model."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, field_validator, model_validator
from pydantic_core import PydanticCustomError

from ..names import DIRECTIONS
from .numbers import (
    DAMPING_RATIO,
    DISTURBANCE,
    DURATION,
    MODE,
    OMEGA,
    OUTPUT_STEP,
    PEAK_VELOCITY,
    in_range,
    integer,
    plain_number,
    range_text,
    real,
)

#: Plain-words messages for pydantic's error types.
HINTS = {
    "extra_forbidden": "is not a known key; check its spelling and indentation "
    "(`cablesim example` prints a complete case file)",
    "missing": "is required; add it",
    "finite_number": "must be a finite number, not NaN or infinity",
    "float_parsing": "must be a number",
    "float_type": "must be a number",
    "int_parsing": "must be a whole number",
    "int_type": "must be a whole number",
    "int_from_float": "must be a whole number",
}

#: Most interior nodes a cable may have: the exact analysis is banded (O(n) per step), but a
#: run still holds a few dense 2n x 2n matrices (the tangent stiffness: 128 MB at 2000 nodes).
MAX_NODES = 2000
#: Ranges of the values of lists (the message names the item).
SEGMENT_RANGE = (1e-3, 1e6, "m")
MASS_RANGE = (1e-6, 1e10, "kg")
LOAD_RANGE = (-1e12, 1e12, "N")

Positive = real(0.0, None, lo_open=True)
Load = Annotated[float, BeforeValidator(plain_number)]


class StrictModel(BaseModel):
    """A section of a case file: unknown keys are errors, values frozen, no NaN or infinity."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


#: Stands for a list that is required unless its shorthand is given (see :func:`_require`).
_ABSENT = "\x00absent"


def _require(data, key: str, alternatives: tuple[str, ...]):
    """Mark ``key`` absent when neither it nor its shorthand is given, so that the field itself
    reports "is required" beside any other problem of the section."""
    if isinstance(data, dict) and key not in data and not any(k in data for k in alternatives):
        return {**data, key: _ABSENT}
    return data


def _absent_is_missing(v):
    if isinstance(v, str) and v == _ABSENT:
        raise PydanticCustomError("missing", "Field required")
    return v


def _finite(v: float, what: str) -> float:
    if not math.isfinite(v):
        raise ValueError(f"{what} must be a finite number")
    return v


class CableSpec(StrictModel):
    """Geometry, axial rigidity and masses (section ``cable:``).

    The segments are given as ``S`` (n+1 natural lengths) or as the shorthand ``length`` (total
    natural length) with ``nodes`` (n, equal segments); the masses as ``masses`` (n values) or
    as ``mass_per_length`` (kg per metre of natural length, each node carrying half of each
    adjacent segment). The case expands the shorthand into ``S`` and ``masses``.
    """

    L: real(0.0, 1e5, "m", lo_open=True) = Field(description="horizontal distance A->B, m")
    H: real(-1e5, 1e5, "m") = Field(description="vertical distance A->B, m, positive = B below A")
    W: real(-1e5, 1e5, "m") = Field(default=0.0, description="out-of-plane distance A->B, m (a spatial cable)")
    S: tuple[Load, ...] | None = Field(default=None, description="natural segment lengths, m (n+1)")
    length: real(0.0, 1e6, "m", lo_open=True) | None = Field(
        default=None, description="total natural length, m (with nodes)")
    nodes: integer(1, MAX_NODES) | None = Field(default=None, description="interior nodes n (with length)")
    EA: Positive | None = Field(default=None, description="axial rigidity, N")
    E: Positive | None = Field(default=None, description="Young's modulus, N/m^2")
    A: Positive | None = Field(default=None, description="cross-section area, m^2")
    masses: tuple[Load, ...] | None = Field(default=None, description="lumped nodal masses, kg (n)")
    mass_per_length: real(0.0, 1e6, "kg/m", lo_open=True) | None = Field(
        default=None, description="kg per m of natural length")

    @model_validator(mode="before")
    @classmethod
    def _required(cls, data):
        data = _require(data, "S", ("length", "nodes"))
        return _require(data, "masses", ("mass_per_length",))

    @field_validator("S", "masses", mode="before")
    @classmethod
    def _given(cls, v):
        return _absent_is_missing(v)

    @field_validator("S", "masses")
    @classmethod
    def _positive(cls, v, info):
        if v is None:
            return v
        least = 2 if info.field_name == "S" else 1
        if len(v) < least:
            raise ValueError(f"needs at least {least} value{'s' if least > 1 else ''}, one per "
                             f"{'segment' if least > 1 else 'interior node'}")
        for i, x in enumerate(v):
            if not math.isfinite(x) or x <= 0:
                raise ValueError(f"every value must be a positive finite number; item {i + 1} is {x}")
        if info.field_name == "S" and len(v) > MAX_NODES + 1:
            raise ValueError(
                f"has {len(v)} segments; cablesim handles at most {MAX_NODES} interior nodes "
                f"({MAX_NODES + 1} segments): merge segments"
            )
        in_range(v, *(SEGMENT_RANGE if info.field_name == "S" else MASS_RANGE))
        return v

    @model_validator(mode="after")
    def _rigidity_and_sizes(self):
        if self.EA is None and (self.E is None or self.A is None):
            raise ValueError("give the axial rigidity as EA (N), or as both E (N/m^2) and A (m^2)")
        if self.EA is not None and (self.E is not None or self.A is not None):
            raise ValueError("give either EA or E and A, not both")
        ea = self.axial_rigidity
        if not math.isfinite(ea) or ea <= 0 or ea < 1e-300:
            raise ValueError(
                f"the axial rigidity E*A = {ea:g} N is out of range; give EA (N) or E and A whose "
                "product is a positive finite number"
            )
        self._expand_segments()
        self._expand_masses()
        if len(self.masses) != len(self.S) - 1:
            raise ValueError(
                f"cable.masses has {len(self.masses)} values but cable.S has {len(self.S)} "
                f"segments: n+1 segments need n = {len(self.S) - 1} masses, one per interior node"
            )
        return self

    def _expand_segments(self) -> None:
        short = (self.length is not None, self.nodes is not None)
        if self.S is not None and any(short):
            raise ValueError("`cable.S` and `cable.length`/`cable.nodes` both give the segments; give one or the other")
        if self.S is None and not any(short):
            raise ValueError("`cable.S` is required; add it (n+1 natural segment lengths, m), or give the "
                             "total natural length as cable.length with the number of interior nodes as cable.nodes")
        if self.S is None and not all(short):
            missing = "cable.nodes" if short[0] else "cable.length"
            raise ValueError(f"`{missing}` is required with the shorthand cable.length and cable.nodes; add it")
        if self.S is None:
            seg = float(self.length) / (self.nodes + 1)
            lo, hi, unit = SEGMENT_RANGE
            if not lo <= seg <= hi:
                raise ValueError(f"`cable.length` / (cable.nodes + 1) gives segments of {seg:g} m; each must be "
                                 f"{range_text(lo, hi, unit)}: give fewer nodes or check cable.length")
            object.__setattr__(self, "S", (seg,) * (self.nodes + 1))

    def _expand_masses(self) -> None:
        if self.masses is not None and self.mass_per_length is not None:
            raise ValueError("`cable.masses` and `cable.mass_per_length` both give the masses; give one "
                             "(extra point masses go in loads.point)")
        if self.masses is None and self.mass_per_length is None:
            raise ValueError("`cable.masses` is required; add it (n lumped masses, kg), or give "
                             "cable.mass_per_length (kg/m of natural length)")
        if self.masses is None:
            S = np.asarray(self.S, dtype=float)
            m = 0.5 * self.mass_per_length * (S[:-1] + S[1:])
            lo, hi, unit = MASS_RANGE
            if not (lo <= m.min() and m.max() <= hi):
                raise ValueError(f"`cable.mass_per_length` gives nodal masses from {m.min():g} to {m.max():g} kg; "
                                 f"each must be {range_text(lo, hi, unit)}: check cable.mass_per_length")
            object.__setattr__(self, "masses", tuple(float(x) for x in m))

    @property
    def shorthand(self) -> bool:
        """True if the segments or the masses were given by the shorthand."""
        return self.length is not None or self.mass_per_length is not None

    @property
    def axial_rigidity(self) -> float:
        """EA, N."""
        return float(self.EA if self.EA is not None else self.E * self.A)

    @property
    def n_nodes(self) -> int:
        """Number of interior nodes."""
        return len(self.S) - 1


class PointLoad(StrictModel):
    """Loads and an extra mass at one interior node (an item of ``loads.point``).

    The node is given by number (``node``), or by position, placed on the nearest node: ``x``,
    the horizontal distance from support A along the span (m), or ``s``, the fraction of the
    cable's natural length from support A. The case states where each one was placed
    (:attr:`cablesim.case.Case.placements`).
    """

    node: integer(1, MAX_NODES) | None = Field(default=None, description="interior node, counted from 1 at support A")
    x: real(0.0, 1e6, "m") | None = Field(default=None, description="horizontal distance from support A, m: the nearest node")
    s: real(0.0, 1.0) | None = Field(default=None, description="fraction of the natural length from support A: the nearest node")
    F: tuple[Load, ...] | None = Field(default=None, description="sustained load (x, v) or (x, v, w), N")
    FL: tuple[Load, ...] | None = Field(default=None, description="peak harmonic load (x, v) or (x, v, w), N")
    mass: real(0.0, MASS_RANGE[1], "kg") | None = Field(default=None, description="extra lumped mass, kg")

    @field_validator("F", "FL")
    @classmethod
    def _range(cls, v):
        if v is not None:
            if len(v) not in (2, 3):
                raise ValueError(f"has {len(v)} values; give 2 (horizontal, vertical) or, for a spatial case, 3 "
                                 "(x, v, w) in N")
            in_range(v, *LOAD_RANGE, what="load")
        return v

    @model_validator(mode="after")
    def _one_position(self):
        given = [key for key in ("node", "x", "s") if getattr(self, key) is not None]
        if len(given) != 1:
            raise ValueError(("gives " + " and ".join(given) if given else "gives no position")
                             + "; give exactly one of node (interior node number, from 1 at support A), "
                             "x (m along the span from support A) or s (fraction of the natural length)")
        return self

    @property
    def position(self) -> str:
        """How the node was given: ``"node 20"``, ``"x = 150 m"`` or ``"s = 0.5"``."""
        if self.node is not None:
            return f"node {self.node}"
        return f"x = {self.x:g} m" if self.x is not None else f"s = {self.s:g}"


class LoadsSpec(StrictModel):
    """Sustained and harmonic nodal loads (section ``loads:``), N, 2n values each.

    ``F0`` may be left out or completed by the shorthand: ``gravity`` (m/s^2: every node's
    weight, vertical, down), ``per_length`` (a sustained load per metre of natural length, such
    as wind or current, lumped like the mass: half of each adjacent segment) and ``point`` (loads
    and extra masses at chosen nodes); the case expands them into ``F0`` and ``FL``.
    """

    F0: tuple[Load, ...] | None = Field(default=None, description="sustained nodal loads, N")
    FL: tuple[Load, ...] | None = Field(default=None, description="peak harmonic loads, N")
    gravity: real(0.0, 1e3, "m/s^2") | None = Field(default=None, description="acceleration of gravity, m/s^2")
    per_length: tuple[Load, ...] | None = Field(
        default=None, description="sustained load per m of natural length (x, v) or (x, v, w), N/m: wind, current")
    point: tuple[PointLoad, ...] | None = Field(default=None, description="loads and masses by node")

    @model_validator(mode="before")
    @classmethod
    def _required(cls, data):
        return _require(data, "F0", ("gravity", "point"))

    @field_validator("F0", mode="before")
    @classmethod
    def _given(cls, v):
        return _absent_is_missing(v)

    @field_validator("F0", "FL")
    @classmethod
    def _range(cls, v):
        if v is not None:
            in_range(v, *LOAD_RANGE, what="load")
        return v

    @field_validator("per_length")
    @classmethod
    def _per_length(cls, v):
        if v is not None:
            if len(v) not in (2, 3):
                raise ValueError(f"has {len(v)} values; give 2 (x, v) or, for a spatial case, 3 (x, v, w) in N/m")
            in_range(v, -1e9, 1e9, "N/m", what="load per length")
        return v

    @property
    def shorthand(self) -> bool:
        """True if gravity, loads per length or point loads were given."""
        return self.gravity is not None or self.point is not None or self.per_length is not None


class DampingSpec(StrictModel):
    """Rayleigh damping ``C = a0 M + a1 K0`` (section ``damping:``).

    Either a damping ratio for two modes (default: 1 and 2) or the coefficients themselves.
    """

    ratio: DAMPING_RATIO | None = Field(default=None, description="damping ratio xi")
    modes: tuple[MODE, MODE] = Field(default=(1, 2), description="the two modes given ratio xi")
    a0: real(0.0, 1e4, "1/s") | None = Field(default=None, description="mass-proportional coefficient, 1/s")
    a1: real(0.0, 1e4, "s") | None = Field(default=None, description="stiffness-proportional coefficient, s")

    @model_validator(mode="after")
    def _one_way(self):
        explicit = self.a0 is not None or self.a1 is not None
        if explicit and self.ratio is not None:
            raise ValueError("give damping either as ratio (with modes) or as a0 and a1, not both")
        if explicit and (self.a0 is None or self.a1 is None):
            raise ValueError("explicit Rayleigh damping needs both a0 and a1")
        if not explicit and self.ratio is None:
            raise ValueError("give damping.ratio (e.g. 0.01), or a0 and a1")
        if self.modes[0] < 1 or self.modes[1] < 1 or self.modes[0] == self.modes[1]:
            raise ValueError("damping.modes must be two different mode numbers counted from 1")
        return self


class HistorySpec(StrictModel):
    """Forced response at one frequency (section ``history:``)."""

    omega: OMEGA | None = Field(default=None, description="forcing frequency, rad/s")
    duration: DURATION = Field(default=600.0, description="simulated time, s")
    output_step: OUTPUT_STEP | None = Field(default=None, description="interval between saved instants, s")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF to plot, e.g. [z2, z4]")
    disturbance: DISTURBANCE = Field(default=0.0, description="largest initial out-of-plane displacement, m")


class FreeVibrationSpec(StrictModel):
    """Free vibration about the equilibrium (section ``free_vibration:``).

    Either ``mode`` with ``peak_velocity``, or explicit initial conditions ``z0``/``v0``.
    """

    mode: MODE | None = Field(default=None, description="linear mode giving the initial velocities")
    peak_velocity: PEAK_VELOCITY | None = Field(default=None, description="largest initial velocity, m/s")
    z0: tuple[real(-1e5, 1e5, "m"), ...] | None = Field(default=None, description="initial displacement from equilibrium, m")
    v0: tuple[real(-1e3, 1e3, "m/s"), ...] | None = Field(default=None, description="initial velocities, m/s")
    damping_ratio: DAMPING_RATIO | None = Field(default=None, description="overrides damping.ratio")
    duration: DURATION | None = Field(default=None, description="simulated time, s (default: until the motion "
                                      "has decayed to 0.01 %, from the damping)")
    output_step: OUTPUT_STEP | None = Field(default=None, description="interval between saved instants, s")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF to plot, e.g. [z2, z4]")

    @model_validator(mode="after")
    def _one_way(self):
        explicit = self.z0 is not None or self.v0 is not None
        if explicit and (self.mode is not None or self.peak_velocity is not None):
            raise ValueError("give either mode with peak_velocity, or z0/v0, not both")
        return self


#: Halvings of a sweep grid's step where neighbouring points disagree (``sweep.refine``): the
#: default for a grid, and the most allowed.
REFINE_LEVELS = 4
REFINE_MOST = 10


class OmegaGrid(StrictModel):
    """An evenly spaced frequency grid, rad/s: ``num`` points from ``start`` to ``stop``."""

    start: OMEGA = Field(description="first frequency, rad/s")
    stop: OMEGA = Field(description="last frequency, rad/s")
    num: integer(1, 1_000_000) = Field(description="number of points")

    @model_validator(mode="after")
    def _order(self):
        if self.num > 1 and self.stop <= self.start:
            raise ValueError("sweep.omega.stop must be greater than start")
        return self


class SweepSpec(StrictModel):
    """Frequency-domain response sweep (section ``sweep:``)."""

    omega: Any = Field(description="grid {start, stop, num} or a list, rad/s")
    duration: DURATION = Field(default=3000.0, description="cap on simulated seconds per point")
    window: DURATION = Field(default=200.0, description="seconds at the end used when not steady")
    direction: Literal[DIRECTIONS] = "independent"
    channels: tuple[str, ...] | None = Field(default=None, description="DOF reported, e.g. [z2, z4]")
    gamma: tuple[Load, ...] | None = Field(default=None, description="scales of FL, one curve each")
    tol: real(0.0, 0.1, lo_open=True, hi_open=True) = Field(default=1e-5, description="relative periodicity tolerance")
    max_period: integer(1, 50) = Field(default=6, description="largest response period sought")
    floquet: bool = Field(default=True, description="check the stability of periodic responses")
    accelerate: bool = Field(default=True, description="decide steady points by shooting from the transient")
    disturbance: DISTURBANCE | None = Field(default=None, description="out-of-plane start, m (default 1e-6 chord)")
    refine: bool | integer(0, REFINE_MOST) | None = Field(
        default=None, description="halvings of the grid step where neighbouring points disagree (true: "
        f"{REFINE_LEVELS}, false or 0: none; default: {REFINE_LEVELS} for a grid, none for a list)")

    @field_validator("omega", mode="before")
    @classmethod
    def _grid(cls, v):
        # One of two forms; parse it here so that an error speaks of the form the user wrote.
        if isinstance(v, dict):
            try:
                return OmegaGrid.model_validate(v)
            except ValidationError as err:
                e = err.errors()[0]
                where = ".".join(str(x) for x in e["loc"])
                msg = HINTS.get(e["type"], e["msg"].removeprefix("Value error, "))
                raise ValueError(f"{where + ': ' if where else ''}{msg}") from None
        if isinstance(v, (list, tuple)):
            if len(v) == 0:
                raise ValueError("the frequency list is empty; give at least one frequency")
            out = []
            for i, w in enumerate(v):
                try:
                    w = float(plain_number(w))
                except (TypeError, ValueError) as exc:
                    why = str(exc) if isinstance(exc, ValueError) and " " in str(exc) else "must be a number"
                    raise ValueError(f"item {i + 1} ({w!r}) {why}") from None
                if not math.isfinite(w) or w <= 0:
                    raise ValueError(f"frequencies must be positive (rad/s); item {i + 1} is {w}")
                out.append(w)
            in_range(out, 1e-4, 1e4, "rad/s", what="frequency")
            return tuple(out)
        raise ValueError("give a grid {start: .., stop: .., num: ..} or a list of frequencies in rad/s")

    @field_validator("gamma")
    @classmethod
    def _gamma(cls, v):
        if v is not None:
            if len(v) == 0:
                raise ValueError("gamma is empty; omit it or give at least one scale")
            for i, g in enumerate(v):
                if not math.isfinite(g) or g <= 0 or g > 1e6:
                    raise ValueError(f"gamma values scale FL and must be positive, at most 1e6; item {i + 1} is {g}")
        return v

    @model_validator(mode="after")
    def _window(self):
        if self.window > self.duration:
            raise ValueError(
                f"sweep.window ({self.window:g} s) is longer than sweep.duration ({self.duration:g} s); "
                "the window is the final part of each point's run, so shorten it"
            )
        return self

    @property
    def refine_levels(self) -> int:
        """How many times the grid step may be halved where neighbouring points disagree."""
        if self.refine is None:
            return REFINE_LEVELS if isinstance(self.omega, OmegaGrid) and self.omega.num > 1 else 0
        if isinstance(self.refine, bool):
            return REFINE_LEVELS if self.refine else 0
        return int(self.refine)

    def frequencies(self) -> np.ndarray:
        """The frequency grid, rad/s (ascending for up/down sweeps)."""
        if isinstance(self.omega, OmegaGrid):
            g = self.omega
            return np.linspace(g.start, g.stop, g.num)
        w = np.array(self.omega, dtype=float)
        return np.sort(w) if self.direction != "independent" else w


class OutputsSpec(StrictModel):
    """What time-history files keep (section ``outputs:``): a scene saves only what it draws."""

    channels: tuple[str, ...] | None = Field(default=None, description="DOF saved (default: all)")
    split: bool | None = Field(default=None, description="compute and save the configurational/elastic split "
                               "(default: up to 100 nodes; it costs a dense inner solve per saved instant)")


#: Modes computed by default for cables of more than ALL_MODES_DOF / 2 nodes.
DEFAULT_MODES = 100
#: Up to this many DOF (n = 300 nodes) every mode is computed by default.
ALL_MODES_DOF = 600


class ModalSpec(StrictModel):
    """Modal analysis (section ``modal:``)."""

    modes: int | None = Field(default=None, ge=1, description=(
        f"compute only the lowest this many modes (and the highest frequency); default: every mode up to "
        f"n = {ALL_MODES_DOF // 2} nodes, else the lowest {DEFAULT_MODES}"))


FIGURE_KINDS = ("fdr", "waveform", "waveform_phase", "waveform_fft", "split", "lissajous_tension")


class FigureSpec(StrictModel):
    """A composite figure drawn from stored results by ``cablesim plot`` (section ``figure:``).

    Kinds: ``fdr`` (frequency response from sweep files), ``waveform`` (z(t) of the channels),
    ``waveform_phase`` (z(t) beside the phase plot z vs z'), ``waveform_fft`` (z(t) beside its
    spectrum), ``split`` (z with its configurational and elastic parts), ``lissajous_tension``
    (z_i vs z_j beside tension waveforms). Several result files make one column each.
    """

    kind: Literal["fdr", "waveform", "waveform_phase", "waveform_fft", "split", "lissajous_tension"]
    title: str | None = Field(default=None, description="figure title")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF drawn, e.g. [z2]")
    pair: tuple[str, str] | None = Field(default=None, description="Lissajous pair, e.g. [z2, z4]")
    segments: tuple[int, ...] | None = Field(default=None, description="tension segments drawn (1-based)")
    time_window: tuple[float, float] | None = Field(default=None, description="time axis limits, s")
    labels: tuple[str, ...] | None = Field(default=None, description="one caption per result file")


