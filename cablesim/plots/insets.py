"""Insets for features too small to read on a figure's own scale.

A free vibration whose later extremes are a few percent of the first peak, a response that is
small until it jumps, a subharmonic band beside a large resonance: each gets an inset with its
own scale, placed where the main curve leaves room.
"""

from __future__ import annotations

import numpy as np

from .base import envelope_plot
from .style import COLOURS

#: A stretch is small when its largest |value| is below this fraction of the record's.
SMALL = 0.12
#: ... and worth an inset when it covers at least this fraction of the shown time.
MIN_SPAN = 0.15


def quiet_stretch(t, y, small: float = SMALL, min_span: float = MIN_SPAN):
    """The start or end of a record where ``|y|`` stays below ``small`` times its largest value.

    Parameters
    ----------
    t, y : ndarray, shape (m,)
        The shown part of a record.
    small, min_span : float
        See :data:`SMALL` and :data:`MIN_SPAN`.

    Returns
    -------
    tuple or None
        ``(t0, t1, "late")`` for a small ending (a decaying response: the stretch after its
        last large value), ``(t0, t1, "early")`` for a small beginning (a response that grows
        or jumps later), or None when neither stretch covers ``min_span`` of the time.
    """
    t = np.asarray(t, dtype=float)
    a = np.abs(np.asarray(y, dtype=float))
    finite = np.isfinite(a)
    if t.size < 8 or not finite.any():
        return None
    top = a[finite].max()
    if not top > 0:
        return None
    large = np.flatnonzero(finite & (a >= small * top))
    span = t[-1] - t[0]
    # a small ending starts where the response first crosses zero after its last large value
    after = large[-1] + np.flatnonzero(np.diff(np.sign(np.asarray(y, dtype=float)[large[-1]:])) != 0)
    late0 = t[after[0] + 1] if after.size else t[large[-1]]
    early1 = t[large[0]]
    if t[-1] - late0 >= min_span * span:
        return float(late0), float(t[-1]), "late"
    if early1 - t[0] >= min_span * span:
        return float(t[0]), float(early1), "early"
    return None


def add_time_inset(ax, t, y, label: str = "enlarged"):
    """An inset showing the small stretch of ``y(t)`` (:func:`quiet_stretch`) on its own scale:
    top right for a small ending, top left for a small beginning. Returns the inset or None."""
    found = quiet_stretch(t, y)
    if found is None:
        return None
    t0, t1, where = found
    bounds = [0.5, 0.5, 0.48, 0.42] if where == "late" else [0.16, 0.5, 0.42, 0.42]
    inset = ax.inset_axes(bounds)
    sel = (t >= t0) & (t <= t1)
    envelope_plot(inset, t[sel], y[sel], "-", color=COLOURS["response"], lw=0.8)
    inset.axhline(0.0, color=COLOURS["reference"], lw=0.6, ls="--")
    inset.set_xlim(t0, t1)
    inset.tick_params(labelsize=8, pad=1)
    inset.text(0.98, 0.94, label, transform=inset.transAxes, ha="right", va="top", fontsize=8, color="0.3")
    inset.patch.set_alpha(0.92)
    ax.indicate_inset([t0, np.nanmin(y[sel]), t1 - t0, np.nanmax(y[sel]) - np.nanmin(y[sel])], inset,
                      edgecolor="0.4", lw=0.7)
    return inset
