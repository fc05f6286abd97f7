"""The look of every figure cablesim draws, defined once: size, fonts, colours and wording.

A journal column pair is 7 in wide; at that width the text is at least 8 pt. Every plotting
entry point draws inside :func:`journal_style` (the :func:`styled` decorator), takes its colours
from :data:`COLOURS` (one meaning per colour across all plots) and its words for the response
classes from :data:`WORDS`. Symbols are mathtext (:func:`symbols` converts the plain-text
spelling of user-given titles and captions). Numbers are printed to their resolution
(:func:`to_resolution`), long time histories are drawn as true envelopes
(:func:`minmax_decimate`), and modes are named by their shape (:func:`mode_symmetry`).
"""

from __future__ import annotations

import contextlib
import functools
import math
import re

import numpy as np

#: Width of every figure (in): two journal columns.
FIGURE_WIDTH = 7.0
#: Smallest text size (pt) at that width.
MIN_FONT = 8.0
#: Resolution of the saved PNGs (dots per inch).
DPI = 200

#: matplotlib settings of every figure.
RC = {
    "font.size": 8.5,
    "axes.titlesize": 9.0,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "legend.title_fontsize": 8.0,
    "figure.titlesize": 10.0,
    "figure.labelsize": 9.0,
    "mathtext.fontset": "dejavusans",
    "axes.formatter.use_mathtext": True,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.6,
    "lines.linewidth": 1.0,
    "legend.framealpha": 0.9,
    "savefig.dpi": DPI,
    "pdf.fonttype": 42,  # TrueType fonts embedded whole in PDF (journals refuse Type 3)
    "ps.fonttype": 42,
}

#: The formats figures are saved in (``--format``, or the output's suffix).
FIGURE_FORMATS = ("png", "pdf", "svg")
#: Range of ``--width`` (in): narrower, 8 pt text no longer fits the panels; wider is a poster.
WIDTH_RANGE = (3.0, 14.0)
#: Range of ``--dpi``.
DPI_RANGE = (50, 1200)
#: The settings of :func:`figure_output` in force (None: the defaults).
_OUTPUT = {"format": None, "width": None, "dpi": None}


@contextlib.contextmanager
def figure_output(format: str | None = None, width: float | None = None, dpi: int | None = None):
    """Context in which every figure is drawn ``width`` inches wide (default
    :data:`FIGURE_WIDTH`; the text keeps its sizes) and saved as ``format`` (``png``, ``pdf``,
    ``svg``; default: the output's suffix, else PNG) at ``dpi`` (default :data:`DPI`)."""
    before = dict(_OUTPUT)
    _OUTPUT.update(format=format, width=width, dpi=dpi)
    try:
        yield
    finally:
        _OUTPUT.update(before)


def figure_width() -> float:
    """The width of the figures being drawn, in (:func:`figure_output`)."""
    return float(_OUTPUT["width"] or FIGURE_WIDTH)


def output_settings() -> dict:
    """``{"format", "width", "dpi"}`` of :func:`figure_output` in force (None where not set)."""
    return dict(_OUTPUT)

#: One colour per meaning, in every plot.
COLOURS = {
    "response": "#1f5fa8",       # the computed response (z, z(t), a spectrum, period-1 branches)
    "early": "#9bbbe0",          # the transient part of a response drawn before its steady part
    "late": "#111111",           # the steady part (last half) of a phase plot or Lissajous figure
    "configurational": "#7b3fa0",  # z_c
    "elastic": "#2a9d4b",        # z_e
    "forcing": "#e08a00",        # the forcing frequency
    "reference": "#777777",      # static equilibrium, static tensions, modal frequencies
    "failure": "#d62728",        # warnings and failures: not steady, went slack, run stopped
    "failed_point": "#555555",   # a sweep point that stopped early (partial value)
    "annotation": "#222222",     # spectral peaks, subharmonic markers, bifurcations
}
#: Colours of several series of one kind (files, gamma values, segments, response periods):
#: none of them red (warnings) or orange (the forcing).
SERIES = ("#1f5fa8", "#2a9d4b", "#7b3fa0", "#8c564b", "#17becf", "#bcbd22", "#e377c2", "#7f7f7f", "#393b79")

#: Legend words of the response classes of a sweep point.
WORDS = {
    "independent": "from rest at each frequency",
    "up": "increasing frequency (from the previous state)",
    "down": "decreasing frequency (from the previous state)",
    "not steady": "not steady within the time limit",
    "failed": "stopped early: a segment went slack\n(partial value, not a peak)",
    "went slack": "a segment goes slack (on the steady orbit; in the run if not steady)",
    "subharmonic": "subharmonic response (period p > 1),\nlabelled 1/p",
}

# Plain-text symbols of user-given titles and captions, and their mathtext.
_SYMBOLS = [
    (re.compile(r"\bomega\b|\bw(?= ?=)"), r"$\\omega$"),
    (re.compile(r"\bxi\b"), r"$\\xi$"),
    (re.compile(r"\bgamma\b"), r"$\\gamma$"),
    (re.compile(r"\bz_?([ce])\b"), r"$z_\1$"),
    (re.compile(r"\b([zT])_?(\d+)\b"), r"$\1_{\2}$"),
    (re.compile(r"\bF_?([0L])\b"), r"$F_{\1}$"),
]


def journal_style():
    """Context in which a figure is drawn and saved with the settings :data:`RC`."""
    import matplotlib  # matplotlib loads only when drawing

    return matplotlib.rc_context(RC)


def styled(func):
    """Decorator: run a plotting entry point inside :func:`journal_style`."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with journal_style():
            return func(*args, **kwargs)

    return wrapper


def symbols(text: str) -> str:
    """Text with its plain-text symbols as mathtext: ``w =`` and ``omega`` as omega, ``xi``,
    ``gamma``, ``z2``, ``T1``, ``F0`` and ``FL`` with subscripts, ``z_c``/``z_e``. Text already holding mathtext
    (a ``$``) is returned unchanged."""
    if "$" in text:
        return text
    for pattern, repl in _SYMBOLS:
        text = pattern.sub(repl, text)
    return text


def channel_tex(name: str) -> str:
    """A channel or tension name as mathtext, e.g. ``"z2"`` -> ``"$z_{2}$"``."""
    m = re.fullmatch(r"([zT])_?(\d+|[ce])", name)
    return f"${m.group(1)}_{{{m.group(2)}}}$" if m else name


def decimals_for(resolution: float) -> int:
    """Decimal places that write a value to ``resolution``: those of its first significant digit."""
    if not (np.isfinite(resolution) and resolution > 0):
        return 4
    return max(0, -math.floor(math.log10(resolution) + 1e-9))


def to_resolution(value: float, resolution: float, unit: str = "") -> str:
    """``value`` printed with as many digits as ``resolution`` allows (e.g. a grid step, a
    spectral bin width, an output step): ``to_resolution(12.7751, 0.025) == "12.78"``,
    ``to_resolution(1.6234, 0.043, "rad/s") == "1.62 rad/s"``. A resolution of 1 or more rounds
    to its first significant digit (``to_resolution(1234.0, 20.0) == "1230"``)."""
    if not np.isfinite(value):
        text = f"{value}"
    elif np.isfinite(resolution) and resolution >= 1.0:
        step = 10.0 ** math.floor(math.log10(resolution) + 1e-9)
        text = f"{round(value / step) * step:.0f}"
    else:
        text = f"{value:.{decimals_for(resolution)}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return f"{text} {unit}" if unit else text


def grid_step(values) -> float:
    """Smallest spacing of a sorted grid (e.g. a sweep's frequencies); NaN for fewer than 2."""
    v = np.unique(np.asarray(values, dtype=float)[np.isfinite(values)])
    return float(np.diff(v).min()) if v.size > 1 else float("nan")


def _bucket_extremes(v: np.ndarray, size: int) -> np.ndarray:
    """Indices of the smallest and largest value of each run of ``size`` samples (NaN ignored)."""
    m = v.size
    pad = (-m) % size
    body = np.concatenate([v, np.full(pad, np.nan)]).reshape(-1, size)
    nan = np.isnan(body)
    start = np.arange(body.shape[0]) * size
    lo = start + np.argmin(np.where(nan, np.inf, body), axis=1)
    hi = start + np.argmax(np.where(nan, -np.inf, body), axis=1)
    return np.minimum(np.concatenate([lo, hi]), m - 1)


def minmax_decimate(x, y, buckets: int = 2000):
    """A long line reduced to the smallest and largest value of each of ``buckets`` runs of
    consecutive samples, in their order, so that the drawn envelope is the true one.

    Parameters
    ----------
    x, y : array_like, shape (m,)
        The line (e.g. time and a displacement).
    buckets : int
        Number of runs (about one per pixel column of the axes).

    Returns
    -------
    x_out, y_out : ndarray
        The samples kept, in their order: the minimum and the maximum of each run (the input
        itself when it has no more than ``2 * buckets`` samples). NaN samples are never picked
        unless a whole run is NaN.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if y.size <= 2 * buckets:
        return x, y
    size = -(-y.size // buckets)
    keep = np.unique(_bucket_extremes(y, size))  # sorted: the samples stay in time order
    return x[keep], y[keep]


def mode_symmetry(span: float, rise: float, nodes: np.ndarray, shape: np.ndarray, masses=None,
                  rtol: float = 1e-3) -> str:
    """Whether a mode of a cable is symmetric or antisymmetric about mid-span.

    A cable has such modes only if it is itself symmetric: level supports (``rise`` = 0), nodes
    mirrored about mid-span and (if given) mirrored masses. Then the mode is symmetric when the
    vertical components at mirrored nodes are equal, antisymmetric when they are opposite.

    Parameters
    ----------
    span, rise : float
        Horizontal and vertical distances between the supports (m).
    nodes : ndarray, shape (n, 2)
        Static positions of the nodes (horizontal, vertical), m.
    shape : ndarray, shape (2 n,)
        Mode shape, components ordered (horizontal, vertical) per node.
    masses : ndarray, shape (n,), optional
    rtol : float
        Tolerance relative to the largest component (and to the span for the geometry).

    Returns
    -------
    str
        ``"symmetric"``, ``"antisymmetric"``, or ``""`` when the cable or the mode is neither
        (inclined or unsymmetric cable: name the mode by its number only).
    """
    nodes = np.asarray(nodes, dtype=float).reshape(-1, 2)
    shape = np.asarray(shape, dtype=float).reshape(-1, 2)
    tol = rtol * max(span, 1e-12)
    mirrored = np.allclose(nodes[::-1, 0], span - nodes[:, 0], atol=tol) and np.allclose(
        nodes[::-1, 1], nodes[:, 1], atol=tol)
    if abs(rise) > tol or not mirrored:
        return ""
    if masses is not None and not np.allclose(masses, np.asarray(masses)[::-1], rtol=rtol):
        return ""
    scale = np.abs(shape).max()
    if scale == 0:
        return ""
    vert = shape[:, 1] / scale
    if np.allclose(vert, vert[::-1], atol=rtol * 10):
        return "symmetric"
    if np.allclose(vert, -vert[::-1], atol=rtol * 10):
        return "antisymmetric"
    return ""


def mode_name(k: int, symmetry: str = "") -> str:
    """``"mode 2 (antisymmetric)"``, or ``"mode 2"`` when the shape is neither."""
    return f"mode {k} ({symmetry})" if symmetry else f"mode {k}"



def lowest_modes_text(cable, y0, modes, count: int = 2) -> str:
    """``"1.84 rad/s (mode 1, symmetric), 2.86 rad/s (mode 2, antisymmetric)"``: the lowest
    modal frequencies, each named by its shape (:func:`mode_symmetry`) when the shapes are known."""
    shapes = getattr(modes, "shapes", None)
    dim = getattr(cable, "dim", 2)
    nodes = np.asarray(y0, dtype=float).reshape(-1, dim)[:, :2]
    kinds = getattr(modes, "kinds", ())
    parts = []
    for k, w in enumerate(np.asarray(modes.omega, dtype=float)[:count]):
        sym = ""
        if shapes is not None and k < np.shape(shapes)[1] and (not kinds or kinds[k] == "in-plane"):
            sym = mode_symmetry(cable.L, cable.H, nodes, np.asarray(shapes)[:, k].reshape(-1, dim)[:, :2], cable.masses)
        if kinds:
            sym = f"{kinds[k]}, {sym}" if sym else kinds[k]
        text = f"{w:.4g} rad/s ({mode_name(k + 1, sym).replace(' (', ', ').rstrip(')')})"
        parts.append(text.replace(" ", "\u00a0"))  # no line break inside one mode's text
    return ", ".join(parts)


def force_unit(values) -> tuple[float, str]:
    """``(divisor, unit)`` that writes forces of the size of ``values`` (N) in kN, or in MN
    from 10 MN up (no exponents in tick or legend labels)."""
    top = float(np.nanmax(np.abs(values))) if np.size(values) else 0.0
    return (1e6, "MN") if top >= 1e7 else (1e3, "kN")
