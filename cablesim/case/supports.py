"""Moving supports (section ``supports:``): harmonic motion of A and B at the forcing frequency."""

from __future__ import annotations

import math

from pydantic import Field, field_validator

from .numbers import in_range, real
from .sections import Load, StrictModel

#: Largest support amplitude a case may give, m.
AMPLITUDE_RANGE = (-1e3, 1e3, "m")


class SupportMotion(StrictModel):
    """One support's motion: ``A(t) = A + amplitude sin(omega t + phase)``, with ``omega`` the
    forcing frequency of the run (scaled by ``gamma`` like the harmonic loads)."""

    amplitude: tuple[Load, ...] = Field(description="displacement amplitude (x, v) or (x, v, w), m")
    phase: real(-100.0, 100.0, "rad") = Field(default=0.0, description="phase, rad")

    @field_validator("amplitude")
    @classmethod
    def _components(cls, v):
        if len(v) not in (2, 3):
            raise ValueError(f"has {len(v)} values; give 2 (x, v) or, out of the plane, 3 (x, v, w) in m")
        for i, x in enumerate(v):
            if not math.isfinite(x):
                raise ValueError(f"every value must be finite; item {i + 1} is {x}")
        in_range(v, *AMPLITUDE_RANGE, what="amplitude")
        return v

    def components(self, dim: int) -> tuple[float, ...]:
        """The amplitude with ``dim`` components (a planar one padded with w = 0)."""
        return tuple(float(x) for x in self.amplitude[:dim]) + (0.0,) * (dim - len(self.amplitude[:dim]))

    @property
    def out_of_plane(self) -> bool:
        """Whether the support moves out of the vertical plane of the span."""
        return len(self.amplitude) == 3 and self.amplitude[2] != 0.0


class SupportsSpec(StrictModel):
    """Harmonic motion of support A and/or B (the exact analysis only)."""

    A: SupportMotion | None = Field(default=None, description="motion of support A")
    B: SupportMotion | None = Field(default=None, description="motion of support B")

    @property
    def out_of_plane(self) -> bool:
        return any(s is not None and s.out_of_plane for s in (self.A, self.B))

    @property
    def moving(self) -> bool:
        return any(s is not None and any(x != 0.0 for x in s.amplitude) for s in (self.A, self.B))
