"""What every plot shares: matplotlib (imported lazily, Agg backend), the figure grid at the
journal width, atomic saving with provenance in the PNG, the preview stamp and true envelopes.

Only :mod:`cablesim.plots` imports matplotlib, and only through :func:`pyplot`, so that
commands that draw nothing never pay for it. The look (sizes, fonts, colours, wording) is
defined in :mod:`cablesim.plots.style`.
"""

from __future__ import annotations

import contextlib
import math
import sys
import textwrap
from pathlib import Path

import numpy as np

from ..io.paths import discard, part_path, remove_stale_parts, write_error
from ..io.provenance import git_commit, invocation
from ..version import __version__
from .style import COLOURS, DPI, FIGURE_FORMATS, FIGURE_WIDTH, figure_width, minmax_decimate, output_settings

#: Samples kept per drawn line of a time history: two (the minimum and the maximum) per bucket.
ENVELOPE_BUCKETS = 2000
#: Largest number of samples drawn per part of a phase plot or Lissajous figure.
CURVE_POINTS = 20000
#: Characters of a title line at the figure width.
TITLE_CHARS = 85
#: Text drawn in a corner of every figure saved inside :func:`stamp_figures` (None: none).
_STAMP = {"text": None}
#: The figures :func:`kept_figures` collects (None outside it).
_KEPT: dict = {"figures": None}


def pyplot():
    """``matplotlib.pyplot`` with the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


@contextlib.contextmanager
def stamp_figures(text: str | None):
    """Draw ``text`` (e.g. ``"preview: coarse grid"``) in the top right corner of every figure
    saved inside this context, and record it in the PNG metadata (key ``Stamp``)."""
    before = _STAMP["text"]
    _STAMP["text"] = text or None
    try:
        yield
    finally:
        _STAMP["text"] = before


def add_stamp(fig, text: str):
    """The stamp: ``text`` in the figure's top right corner, in the warning colour, on a line
    added above the title (so that it covers nothing)."""
    title = fig._suptitle
    if title is None:
        fig.suptitle(" ")
    else:
        title.set_text("\n" + title.get_text())
    # drawn as written: a `$` in the text is not the start of mathematical notation
    return fig.text(0.995, 0.995, text, ha="right", va="top", fontsize=8.5, fontweight="bold",
                    color=COLOURS["failure"], zorder=100, parse_math=False, usetex=False,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec=COLOURS["failure"], lw=0.8))


def png_metadata(stamp: str | None = None) -> dict:
    """PNG text chunks of a figure: cablesim version, git commit, the command that drew it."""
    line = invocation()["command_line"] or "python " + " ".join(sys.argv)  # not the command line: a script
    meta = {"Software": f"cablesim {__version__}", "cablesim version": __version__,
            "git commit": git_commit() or "unknown (not a git checkout)", "Command": line}
    if stamp:
        meta["Stamp"] = stamp
    return meta


def figure_metadata(fmt: str, stamp: str | None = None) -> dict:
    """The provenance a saved figure carries, in the keys its format has: PNG text chunks
    (:func:`png_metadata`); PDF ``Creator``, ``Subject`` (the command) and ``Keywords`` (the
    git commit, the stamp); SVG ``Creator``, ``Description`` and ``Keywords``."""
    meta = png_metadata(stamp)
    if fmt == "png":
        return meta
    words = [f"git commit {meta['git commit']}", *([f"stamp: {stamp}"] if stamp else [])]
    if fmt == "pdf":
        return {"Creator": meta["Software"], "Subject": meta["Command"], "Keywords": "; ".join(words)}
    return {"Creator": meta["Software"], "Description": meta["Command"], "Keywords": words}


def figure_path(path: str | Path) -> tuple[Path, str]:
    """Where a figure meant for ``path`` goes and its format: the suffix the ``format`` of
    :func:`~cablesim.plots.style.figure_output` names, else ``path``'s own (png, pdf, svg),
    else PNG."""
    path = Path(path)
    fmt = output_settings()["format"]
    if fmt:
        return path.with_suffix("." + fmt), fmt
    own = path.suffix.lower().lstrip(".")
    return path, own if own in FIGURE_FORMATS else "png"


@contextlib.contextmanager
def kept_figures():
    """Within this context every figure saved (:func:`save_atomic`) is also kept: yields the
    list they are appended to, for the API to return the figures themselves."""
    previous = _KEPT["figures"]
    _KEPT["figures"] = kept = []
    try:
        yield kept
    finally:
        _KEPT["figures"] = previous


def save_atomic(fig, path: str | Path, dpi: int | None = None) -> Path:
    """Save a figure through a temporary file so a failure never leaves a broken file; it
    carries :func:`figure_metadata` and, inside :func:`stamp_figures`, the stamp. The format and
    resolution follow :func:`~cablesim.plots.style.figure_output` (PNG at :data:`DPI` by
    default); the path returned has the format's suffix."""
    path, fmt = figure_path(path)
    dpi = dpi or output_settings()["dpi"] or DPI
    remove_stale_parts(path)
    tmp = part_path(path)
    stamp = _STAMP["text"]
    if stamp:
        add_stamp(fig, stamp)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # a figure laid out by matplotlib keeps its width; one placed by hand is cropped to its content
        crop = None if fig.get_layout_engine() is not None else "tight"
        fig.savefig(tmp, dpi=dpi, format=fmt, metadata=figure_metadata(fmt, stamp), bbox_inches=crop)
        tmp.replace(path)
    except OSError as exc:
        raise write_error(path, exc) from None
    finally:
        discard(tmp)
        pyplot().close(fig)  # (a closed figure can still be shown, in a notebook, and saved)
        if _KEPT["figures"] is not None:
            _KEPT["figures"].append(fig)
    return path


def figure_grid(nrows, ncols, row_height, *, sharex=False, sharey=False, extra_height=0.6, width=None,
                height_ratios=None):
    """Figure ``width`` wide (default: the journal width, or the one of
    :func:`~cablesim.plots.style.figure_output`) with an ``nrows`` x ``ncols`` grid of axes,
    laid out by matplotlib's constrained layout (titles, labels and outside legends fit).

    Two-panel rows stack rather than shrink: callers pass ``ncols`` = 1 and twice the rows.
    """
    plt = pyplot()
    fig, axes = plt.subplots(nrows, ncols, sharex=sharex, sharey=sharey, squeeze=False,
                             figsize=(width or figure_width(), extra_height + nrows * row_height), layout="constrained",
                             height_ratios=height_ratios)
    fig.get_layout_engine().set(w_pad=0.04, h_pad=0.04, wspace=0.03, hspace=0.03)
    return fig, axes


def title_line(fig, text: str, note: str | None = None) -> None:
    """The figure's title line; an optional line of conditions under it (both wrapped to the
    figure's width: a long scene title would otherwise run past its edges)."""
    chars = int(TITLE_CHARS * fig.get_window_extent().width / (fig.get_figure(root=True).dpi * FIGURE_WIDTH))
    lines = wrap_text(text, chars) or [text]
    if note:  # without the conditions the title states already
        parts = [p for p in note.split("; ") if p.lower() not in text.lower()]
        lines += wrap_text("; ".join(parts), chars) if parts else []
    fig.suptitle("\n".join(lines), fontsize=9.5)


def wrap_text(text: str, width: int) -> list[str]:
    """``text`` in lines of at most ``width`` characters, never broken inside ``$...$`` (a
    mathtext expression cut in two would not parse) nor inside a word."""
    pieces = text.split("$")
    guarded = "$".join(p.replace(" ", "\0") if k % 2 else p for k, p in enumerate(pieces))
    return [line.replace("\0", " ") for line in textwrap.wrap(guarded, width=width, break_long_words=False)]


def legend_columns(ncol: int) -> int:
    """Columns of a legend laid out for the journal width, in a figure of the width being drawn
    (fewer in a narrower one, so that it stays within the figure)."""
    return max(1, min(ncol, math.floor(ncol * figure_width() / FIGURE_WIDTH + 1e-9)))


def legend_below(fig, handles, ncol: int = 2) -> None:
    """One legend for the whole figure, below the axes (within the figure width: ``ncol``
    columns at the journal width, fewer in a narrower figure)."""
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncol=legend_columns(ncol), frameon=False)


def bottom_notes(fig, lines, warn: bool = False) -> None:
    """Notes under a figure (or subfigure), wrapped to its width: above the legend entries when
    the figure has a legend below (the layout would put both in one place), else as its x label;
    in the warning colour when ``warn`` (a run that stopped early, an incomplete sweep)."""
    if not lines:
        return
    chars = int(TITLE_CHARS * 1.1 * fig.get_window_extent().width / (fig.get_figure(root=True).dpi * FIGURE_WIDTH))
    text = "\n".join(w for line in lines for w in textwrap.wrap(line, width=max(30, chars)))
    colour = COLOURS["failure"] if warn else "0.3"
    below = [lg for lg in fig.legends if getattr(lg, "_outside_loc", None)]
    if below:
        below[0].set_title(text, prop={"size": 8.5, "weight": "bold" if warn else "normal"})
        below[0].get_title().set_color(colour)
    else:
        fig.supxlabel(text, fontsize=8.5, color=colour, fontweight="bold" if warn else "normal")


def steady_start(t: np.ndarray, steady_fraction: float = 0.5) -> int:
    """Index where the steady part (last ``steady_fraction``) starts."""
    return t.size - int(round(steady_fraction * t.size))


def envelope_plot(ax, x, y, *args, **kwargs):
    """``ax.plot`` of a long time history as its true envelope (:func:`minmax_decimate`)."""
    xd, yd = minmax_decimate(x, y, ENVELOPE_BUCKETS)
    return ax.plot(xd, yd, *args, **kwargs)


def two_tone(ax, x, y, i0, label_early, label_late):
    """Draw the early part of a parametric curve (phase plot, Lissajous figure) light and the
    latter part dark, and mark its end. Every sample up to :data:`CURVE_POINTS` per part is
    drawn (an envelope means nothing for a curve that is not a function of time)."""
    s_early = max(1, -(-(i0 + 1) // CURVE_POINTS))
    s_late = max(1, -(-(x.size - i0) // CURVE_POINTS))
    ax.plot(x[: i0 + 1 : s_early], y[: i0 + 1 : s_early], "-", color=COLOURS["early"], lw=0.6, label=label_early)
    ax.plot(x[i0::s_late], y[i0::s_late], "-", color=COLOURS["late"], lw=0.7, label=label_late)
    if x.size:
        ax.plot(x[-1], y[-1], "o", color=COLOURS["annotation"], mfc="white", ms=4, zorder=3, label="end of run")
