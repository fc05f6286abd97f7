"""The ``continuation:`` section of a case file: the parameter, its range and the orbits' settings."""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Discriminator, Field, Tag, model_validator

from ..names import CONTINUATION_PARAMETERS
from .numbers import OMEGA, integer, real
from .sections import StrictModel


#: A load factor gamma (scales FL and the support amplitudes).
GAMMA = real(0.0, 1e6, lo_open=True)
#: A support motion multiplier s (scales the amplitudes of ``supports:`` alone; 0: the supports at rest).
SUPPORT = real(0.0, 1e6)


class ParameterRange(StrictModel):
    """A range of a continuation parameter: from ``start`` (where the first branch starts) to ``stop``."""

    start: GAMMA = Field(description="first value")
    stop: GAMMA = Field(description="last value")

    @model_validator(mode="after")
    def _distinct(self):
        if self.stop == self.start:
            raise ValueError("start and stop must differ")
        return self


class OmegaRange(ParameterRange):
    """A range of the forcing frequency, rad/s (``continuation.omega``)."""

    start: OMEGA = Field(description="first frequency, rad/s")
    stop: OMEGA = Field(description="last frequency, rad/s")


class SupportRange(ParameterRange):
    """A range of the support motion multiplier s (``continuation.support``): dimensionless, the
    amplitudes of ``supports:`` times s (s = 1: as written; s = 0: the cable at rest under its
    static loads, when FL is zero). With ``loci: true``, the range over which bifurcation curves
    are continued in (omega, s), with ``at`` and ``levels`` as for gamma."""

    start: SUPPORT = Field(description="first multiplier (may be 0)")
    stop: SUPPORT = Field(description="last multiplier")
    at: SUPPORT | None = Field(default=None, description="loci: s of the response curve (default: stop)")
    levels: tuple[SUPPORT, ...] = Field(default=(), description=(
        "loci: values of s at which each curve's crossings are located (special: level), e.g. [0.2, 0.3]"))


class LociRange(ParameterRange):
    """The range of gamma over which bifurcation curves are continued (``continuation.gamma``
    with ``loci: true``), and the gamma of the frequency response whose bifurcations start them."""

    at: GAMMA | None = Field(default=None, description="gamma of the response curve (default: stop)")
    levels: tuple[GAMMA, ...] = Field(default=(), description=(
        "values of gamma at which each curve's crossings are located (special: level), e.g. [0.5, 2]"))


#: The parameters a bifurcation curve can be continued in beside omega (``loci: true``).
LOCI_PARAMETERS = ("gamma", "support")


#: Marks a tag of a union in the location of a validation error; the messages leave it out.
UNION_TAG = "~"


def _range_or_value(v) -> str:
    return f"{UNION_TAG}range" if isinstance(v, (dict, ParameterRange)) else f"{UNION_TAG}value"


def range_or_value(range_type, value_type):
    """A mapping ``{start, stop}`` validated as ``range_type``, anything else as the number
    ``value_type`` (so that a message is about the one the user wrote, not both)."""
    return Annotated[Union[Annotated[range_type, Tag(f"{UNION_TAG}range")], Annotated[value_type, Tag(f"{UNION_TAG}value")]],
                     Discriminator(_range_or_value)]


class ContinuationSpec(StrictModel):
    """Periodic responses by shooting and pseudo-arclength continuation (``continuation:``), in the
    forcing frequency omega, the load factor gamma (FL and the supports' motion) or the support
    motion multiplier s (``support``: the amplitudes of ``supports:`` alone); the parameter is a
    range ``{start, stop}``, the others single values."""

    parameter: Literal[CONTINUATION_PARAMETERS] = Field(default="omega", description="omega | gamma | support")
    omega: range_or_value(OmegaRange, OMEGA) = Field(description="range (parameter omega) or value, rad/s")
    gamma: range_or_value(LociRange, GAMMA) = Field(default=1.0, description=(
        "range (parameter gamma, or loci) or value; scales FL and the supports' motion"))
    support: range_or_value(SupportRange, SUPPORT) = Field(default=1.0, description=(
        "range (parameter support, or loci) or value; multiplies the amplitudes of supports: alone"))
    period: integer(1, 16) = Field(default=1, description="period of the first branch, forcing periods")
    switch_branches: bool = Field(default=True, description="follow every period doubling onto its 2p branch")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF reported, e.g. [z2, z4]")
    start_from: Literal["linear", "history"] = Field(
        default="linear", description="first orbit from the linear response, or integrated from rest")
    segments: integer(1, 64) = Field(default=1, description="shooting segments per orbit (multiple shooting)")
    max_period: integer(1, 64) = Field(default=8, description="no branch switching beyond this period")
    max_points: integer(2, 100_000) = Field(default=2000, description="most points per branch")
    through_slack: bool = Field(default=False, description=(
        "follow the orbits through slack segments (exact analysis, supports at rest, slack: continue): "
        "branches go on where a segment goes slack, each orbit records its slack episodes and snap loads, "
        "and grazing points are located"))
    loci: bool = Field(default=False, description=(
        "continue every fold, period doubling and Neimark-Sacker point found in omega and gamma "
        "(gamma: {start, stop, at}) or, with moving supports, in omega and the support multiplier s "
        "(support: {start, stop, at}): the stability chart"))

    @model_validator(mode="after")
    def _ranges(self):
        names = CONTINUATION_PARAMETERS
        ranged = {k: isinstance(getattr(self, k), ParameterRange) for k in names}
        if self.loci:
            return self._loci_ranges(ranged)
        if not ranged[self.parameter]:
            raise ValueError(
                f"continuation.parameter is {self.parameter}, so continuation.{self.parameter} must be a "
                f"range {{start: .., stop: ..}}"
            )
        for other in (k for k in names if k != self.parameter and ranged[k]):
            raise ValueError(self._single_value_text(other))
        for k in LOCI_PARAMETERS:
            rng = getattr(self, k)
            if isinstance(rng, ParameterRange) and (rng.at is not None or rng.levels):
                raise ValueError(f"continuation.{k}.at and continuation.{k}.levels are used only with loci: true")
        for other in (k for k in ("omega", "gamma") if k != self.parameter):
            if not getattr(self, other) > 0:
                raise ValueError(f"continuation.{other} must be positive")
        return self

    def _single_value_text(self, other: str) -> str:
        """The refusal of a range given for ``other``, which is not the parameter."""
        if other == "support":
            return (f"continuation.support is a range, but the parameter is {self.parameter}: continue in the "
                    "support motion multiplier with parameter: support (omega and gamma then single values), "
                    "give continuation.support a single value (the multiplier of the amplitudes of "
                    "supports:, default 1), or add loci: true to continue the bifurcations over that range of s")
        hint = (" (or add loci: true to continue the bifurcations over that gamma range)"
                if other == "gamma" and self.parameter == "omega" else "")
        return f"continuation.{other} must be a single value when the parameter is {self.parameter}" + hint

    def _loci_ranges(self, ranged: dict):
        """The checks of ``loci: true``: the response in omega, the curves over a range of gamma
        or of the support multiplier s (one of the two; the other a single value)."""
        if ranged["gamma"] and ranged["support"]:
            raise ValueError(
                "continuation.loci: both continuation.gamma and continuation.support are ranges; the curves are "
                "continued in omega and one second parameter. Give the range of the one to continue them in "
                "(gamma: the scale of FL and the supports' motion; support: the supports' motion alone) and a "
                "single value for the other")
        if self.parameter != "omega" or not (ranged["omega"] and (ranged["gamma"] or ranged["support"])):
            raise ValueError(
                "continuation.loci needs the response in omega (parameter: omega, the default) with "
                "continuation.omega a range {start: .., stop: ..} and the range of the curves in "
                "continuation.gamma {start: .., stop: .., at: ..} or, with moving supports, in "
                "continuation.support (at: the value of the response, default stop)")
        name = self.loci_parameter
        g = getattr(self, name)
        lo, hi = min(g.start, g.stop), max(g.start, g.stop)
        if g.at is not None and not lo <= g.at <= hi:
            raise ValueError(f"continuation.{name}.at ({g.at:g}) must lie between {name}.start ({g.start:g}) and "
                             f"{name}.stop ({g.stop:g}), the range the curves are continued over")
        bad = [x for x in g.levels if not lo <= x <= hi]
        if bad:
            raise ValueError(f"continuation.{name}.levels: {', '.join(f'{x:g}' for x in bad)} outside the range "
                             f"{name}.start ({g.start:g}) to {name}.stop ({g.stop:g}); give levels inside it")
        return self

    @property
    def loci_parameter(self) -> str | None:
        """With ``loci: true``, the second parameter of the curves (``gamma`` or ``support``, the
        one given as a range); else None."""
        if not self.loci:
            return None
        return "support" if isinstance(self.support, ParameterRange) else "gamma"

    @property
    def loci_range(self) -> ParameterRange | None:
        """With ``loci: true``, the range of the curves' second parameter (:attr:`loci_parameter`)."""
        return getattr(self, self.loci_parameter) if self.loci else None

    @property
    def loci_response(self) -> float | None:
        """With ``loci: true``, the value of the second parameter at which the response in omega
        is traced (``at``, default ``stop``)."""
        g = self.loci_range
        return None if g is None else float(g.at if g.at is not None else g.stop)

    @property
    def range(self) -> ParameterRange:
        """The range of the continuation parameter."""
        return getattr(self, self.parameter)

    @property
    def fixed(self) -> float:
        """The value of the other parameter: gamma when the parameter is omega (with loci the
        gamma of the response curve), omega in rad/s when it is gamma or support."""
        if self.loci_parameter == "gamma":
            return self.loci_response
        return float(getattr(self, "gamma" if self.parameter == "omega" else "omega"))

    @property
    def fixed_gamma(self) -> float:
        """The multiplier gamma of FL (and of the supports' motion) when it is not the parameter
        (with loci in gamma, the gamma of the response curve)."""
        return self.fixed if self.parameter == "omega" else 1.0 if self.parameter == "gamma" else float(self.gamma)

    @property
    def fixed_support(self) -> float:
        """The support motion multiplier s when it is not the parameter (default 1; with loci in
        s, the s of the response curve)."""
        if self.loci_parameter == "support":
            return self.loci_response
        return 1.0 if self.parameter == "support" else float(self.support)
