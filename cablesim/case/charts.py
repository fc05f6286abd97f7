"""The ``backbone:`` section of a case file (``cablesim backbone``)."""

from __future__ import annotations

from pydantic import Field

from .numbers import MODE, integer, real
from .sections import StrictModel


class BackboneSpec(StrictModel):
    """Backbone curves of the unforced, undamped cable (section ``backbone:``, ``cablesim backbone``)."""

    mode: MODE = Field(default=1, description="linear mode the backbone starts from")
    amplitude: real(0.0, 1e5, "m", lo_open=True) | None = Field(
        default=None, description="largest |z| of the channels followed, m (default: 2 % of the chord)")
    channels: tuple[str, ...] | None = Field(default=None, description="DOF reported and followed, e.g. [z2, z4]")
    max_points: integer(2, 100_000) = Field(default=2000, description="most points")
    max_ratio: real(0.0, 100.0, lo_open=True) = Field(
        default=5.0, description="largest frequency ratio of the internal resonances watched")
