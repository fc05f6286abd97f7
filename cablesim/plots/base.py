"""What every plot shares: matplotlib (imported lazily, Agg backend), atomic saving, figure grids.

Only :mod:`cablesim.plots` imports matplotlib, and only through :func:`pyplot`, so that
commands that draw nothing never pay for it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.paths import part_path, remove_stale_parts, write_error

#: Largest number of points drawn per line in the time-domain plots.
MAX_LINE_POINTS = 20000


def pyplot():
    """``matplotlib.pyplot`` with the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_atomic(fig, path: str | Path, dpi: int = 130) -> Path:
    """Save a figure through a temporary file so a failure never leaves a broken PNG."""
    path = Path(path)
    remove_stale_parts(path)
    tmp = part_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="png")
        tmp.replace(path)
    except OSError as exc:
        raise write_error(path, exc) from None
    finally:
        tmp.unlink(missing_ok=True)
        pyplot().close(fig)
    return path


def stride(m: int, max_points: int = MAX_LINE_POINTS) -> int:
    """Step between drawn samples so that a line has at most ``max_points`` points."""
    return max(1, -(-m // max_points))

def figure_grid(nrows, ncols, ax_w, ax_h, *, sharex=False, top=0.75, hspace=0.25, wspace=0.9, left=1.0):
    """Figure with fixed margins in inches (no layout engine: log axes make those slow).

    ``top`` leaves room for the two-line figure title (plus any axes titles); the saved file
    is cropped to its content by ``save_atomic`` (``bbox_inches="tight"``).
    """
    plt = pyplot()
    right, bottom = 0.3, 0.65
    width = left + ncols * ax_w + (ncols - 1) * wspace + right
    height = top + nrows * ax_h + (nrows - 1) * hspace + bottom
    fig, axes = plt.subplots(nrows, ncols, sharex=sharex, squeeze=False, figsize=(width, height))
    fig.subplots_adjust(
        left=left / width,
        right=1 - right / width,
        bottom=bottom / height,
        top=1 - top / height,
        hspace=hspace / ax_h,
        wspace=wspace / ax_w,
    )
    return fig, axes


def steady_start(t: np.ndarray, steady_fraction: float = 0.5) -> int:
    """Index where the steady part (last ``steady_fraction``) starts."""
    return t.size - int(round(steady_fraction * t.size))


def two_tone(ax, x, y, i0, label_early, label_late, color="C0"):
    """Draw the early part of a curve light and the latter part dark."""
    s = stride(x.size)
    ax.plot(x[: i0 + 1 : s], y[: i0 + 1 : s], "-", color=color, alpha=0.3, lw=0.7, label=label_early)
    ax.plot(x[i0::s], y[i0::s], "-", color="k", lw=0.9, label=label_late)
    if x.size:
        ax.plot(x[-1], y[-1], "o", color="C3", ms=4, zorder=3, label="end of run")
