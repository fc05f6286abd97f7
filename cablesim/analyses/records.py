"""Which part of a time history a spectrum reads, and when a record is too short for one.

A forced response is read over its last half (its steady part); a run that stopped early over
all of it (its steady part never came). A free vibration decays: it is read from the start
until its motion has fallen to :data:`MOTION_FLOOR` of its largest excursion (after that the
record holds round-off, whose spectrum means nothing). A part that spans fewer than
:data:`MIN_PERIODS` periods of the motion of interest (the forcing, or the strongest frequency
of a free vibration) has no spectrum worth drawing: its bins are wider than the peaks they
would locate.

Used by the text summaries and the spectrum figures alike, so that both read the same part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Fewest periods of the motion of interest a spectrum's part of the record must span.
MIN_PERIODS = 3.0
#: A free vibration is read until its motion has decayed to this fraction of its largest.
MOTION_FLOOR = 1e-4


@dataclass(frozen=True)
class SpectrumPart:
    """Samples ``start:stop`` of a record, and how they were chosen (``"last half"``, ...);
    ``short`` says why there is no spectrum (None if there is one)."""

    start: int
    stop: int
    how: str
    short: str | None = None


def spectrum_part(t, z, omega: float | None, completed: bool = True, frequency: float | None = None) -> SpectrumPart:
    """The part of the record ``(t, z)`` a spectrum of it reads.

    Parameters
    ----------
    t, z : array_like, shape (m,)
        Times (s) and one channel's displacement (m).
    omega : float or None
        The forcing frequency, rad/s (None for a free vibration).
    completed : bool
        Whether the run reached its end.
    frequency : float, optional
        A free vibration's strongest frequency, rad/s, if known (its periods are counted).
    """
    t = np.asarray(t, dtype=float)
    z = np.asarray(z, dtype=float)
    m = t.size
    if omega is None:
        a = np.abs(z - z[-1]) if m else z
        big = np.flatnonzero(np.isfinite(a) & (a >= MOTION_FLOOR * np.nanmax(a))) if m and np.nanmax(a) > 0 else []
        stop = min(m, int(big[-1]) + 2) if len(big) else m
        start, how = 0, f"until the motion decayed to {MOTION_FLOOR:.2%} of its largest" if stop < m else "whole run"
    elif completed:
        start, stop, how = m - int(round(0.5 * m)), m, "last half"
    else:
        start, stop, how = 0, m, "whole run, stopped early"
    span = float(t[stop - 1] - t[start]) if stop - start > 1 else 0.0
    w = omega if omega is not None else frequency
    short = None
    if stop - start < 8:
        short = f"the part of the record read ({how}) holds {stop - start} samples; a spectrum needs 8"
    elif w is not None and np.isfinite(w) and w > 0 and span * w / (2.0 * np.pi) < MIN_PERIODS:
        periods = span * w / (2.0 * np.pi)
        need = MIN_PERIODS * 2.0 * np.pi / w / (0.5 if omega is not None and completed else 1.0)
        longer = f" (a record of at least {need:.3g} s)" if omega is not None else " (the motion decays too fast)"
        short = (f"the part of the record read ({how}: {span:.3g} s) spans {periods:.2g} periods of {w:.4g} rad/s; "
                 f"a spectrum needs at least {MIN_PERIODS:g}{longer}")
    return SpectrumPart(start, stop, how, short)
