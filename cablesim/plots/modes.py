"""The mode-shape drawing of ``cablesim static``: the lowest linear modes on the cable.

Each panel draws the static equilibrium and one mode shape added to it (and subtracted from it,
faint: the two extremes of the linear motion), at true scale (equal axes), scaled so that the
largest nodal displacement is :data:`SHAPE_FRACTION` of the span. The panel's title gives the
mode's frequency in rad/s and Hz, its damping ratio and its kind: symmetric or antisymmetric
when the cable and the shape are; for a spatial cable also in-plane or out-of-plane (of the
plane of the equilibrium, :mod:`cablesim.modal`). An out-of-plane mode is drawn in plan view
(``x``, ``w``), every other one in elevation (``x``, ``v``, down).

Lines carry a ``gid``: ``"static"`` for the equilibrium, ``"mode K"`` for the shape added and
``"mode K opposite"`` for it subtracted, so that a reader of the returned figure finds them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..cable import nodes_with_supports
from ..errors import CablesimError
from .base import pyplot, save_atomic, title_line
from .style import COLOURS, FIGURE_WIDTH, mode_symmetry, styled

#: Modes drawn by default.
DEFAULT_MODES_DRAWN = 4
#: Most modes one figure draws.
MAX_MODES_DRAWN = 20
#: Largest nodal displacement of a drawn shape, as a fraction of the span.
SHAPE_FRACTION = 0.08
#: Up to this many nodes each node is marked on the shapes.
MARKED_NODES = 40
#: Height of one row of panels, in.
ROW_HEIGHT = 2.1


def modes_drawable(result) -> int:
    """How many of the lowest modes of ``result`` have a stored shape (and can be drawn)."""
    shapes = getattr(result.modes, "shapes", None)
    return 0 if shapes is None else int(min(np.shape(shapes)[1], np.size(result.modes.omega)))


def mode_kind(result, k: int) -> str:
    """Words for mode ``k`` (0-based): ``"symmetric"``, ``"out-of-plane, antisymmetric"``, ``""``."""
    cable = result.cable
    kinds = tuple(getattr(result.modes, "kinds", ()) or ())
    kind = kinds[k] if k < len(kinds) else ""
    sym = ""
    if kind in ("", "in-plane"):
        nodes = np.asarray(result.y0, dtype=float).reshape(-1, cable.dim)[:, :2]
        shape = np.asarray(result.modes.shapes)[:, k].reshape(-1, cable.dim)[:, :2]
        sym = mode_symmetry(cable.L, cable.H, nodes, shape, cable.masses)
    return ", ".join(w for w in (kind, sym) if w)


def mode_title(result, k: int) -> str:
    """``"mode 1 (symmetric)\nω = 1.844 rad/s, f = 0.2935 Hz, ξ = 1 %"`` for mode ``k`` (0-based)."""
    w = float(result.modes.omega[k])
    ratios = np.asarray(getattr(result, "damping_ratios", ()), dtype=float)
    xi = f", $\\xi$ = {100 * ratios[k]:.3g} %" if k < ratios.size else ""
    kind = mode_kind(result, k)
    name = f"mode {k + 1}" + (f" ({kind})" if kind else "")
    return f"{name}\n$\\omega$ = {w:.4g} rad/s, $f$ = {w / (2 * math.pi):.4g} Hz{xi}"


def shape_scale(result, k: int) -> float:
    """The factor (m per unit of the mass-normalised shape) that makes the largest nodal
    displacement of mode ``k`` (0-based) :data:`SHAPE_FRACTION` of the span."""
    cable = result.cable
    phi = np.asarray(result.modes.shapes)[:, k].reshape(-1, cable.dim)
    largest = float(np.linalg.norm(phi, axis=1).max())
    return SHAPE_FRACTION * max(cable.L, 1e-9) / largest if largest > 0 else 0.0


def _panel(ax, result, k: int) -> None:
    """Draw mode ``k`` (0-based) on ``ax``."""
    cable = result.cable
    plan = mode_kind(result, k).startswith("out-of-plane")
    col = 2 if plan else 1
    y0 = np.asarray(result.y0, dtype=float)
    phi = np.asarray(result.modes.shapes)[:, k]
    a = shape_scale(result, k)
    rest = nodes_with_supports(cable, y0)
    ax.plot(rest[:, 0], rest[:, col], "--", color=COLOURS["reference"], lw=1.0, gid="static",
            label="static equilibrium")
    for sign, gid, style in ((-1.0, f"mode {k + 1} opposite", dict(lw=0.8, alpha=0.45)),
                             (1.0, f"mode {k + 1}", dict(lw=1.6))):
        pts = nodes_with_supports(cable, y0 + sign * a * phi)
        ax.plot(pts[:, 0], pts[:, col], "-o" if cable.n_nodes <= MARKED_NODES else "-", color=COLOURS["response"],
                ms=2.5, gid=gid,
                label="mode shape (scaled), its two extremes" if sign > 0 else None, **style)
    ax.plot(rest[[0, -1], 0], rest[[0, -1], col], "^", color="k", ms=7, zorder=4)
    if not plan:
        ax.invert_yaxis()  # v points down
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(mode_title(result, k), fontsize=8.5)
    ax.set_xlabel("$x$ (m)")
    ax.set_ylabel("$w$ (m): plan view" if plan else "$v$ (m): down")


@styled
def draw_modes(result, title: str, count: int = DEFAULT_MODES_DRAWN):
    """The figure of the lowest ``count`` modes of a static result (not saved).

    Parameters
    ----------
    result : cablesim.analyses.static.StaticResult or the drawing read from a static file
        Needs ``cable``, ``y0`` (m), ``modes`` (``omega`` in rad/s, ``shapes``, ``kinds``) and
        ``damping_ratios``.
    title : str
        First title line (the case name).
    count : int
        Modes to draw, 1 to :data:`MAX_MODES_DRAWN` (fewer if fewer shapes are stored).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not 1 <= int(count) <= MAX_MODES_DRAWN:
        raise CablesimError(f"--modes-drawn {count}: give how many of the lowest modes to draw, from 1 to "
                            f"{MAX_MODES_DRAWN} (or 0 for no mode figure).", field="modes-drawn")
    m = min(int(count), modes_drawable(result))
    if m == 0:
        raise CablesimError("This static result stores no mode shapes, so none can be drawn; rerun cablesim "
                            "static (it stores the shapes of the lowest modes).", field="modes-drawn")
    ncols = 1 if m == 1 else 2
    nrows = -(-m // ncols)
    plt = pyplot()
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, figsize=(FIGURE_WIDTH, 1.0 + nrows * ROW_HEIGHT),
                             layout="constrained")
    for k, ax in enumerate(axes.ravel()):
        if k < m:
            _panel(ax, result, k)
        else:
            ax.set_visible(False)
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=2, frameon=False)
    cable = result.cable
    shown = f"the lowest {m} modes" if m > 1 else "the lowest mode"
    title_line(fig, f"{title}: {shown} ({getattr(result, 'analysis', 'exact')} analysis)",
               f"n = {cable.n_nodes} nodes, L = {cable.L:g} m, H = {cable.H:g} m; shapes scaled so that the largest "
               f"nodal displacement is {100 * SHAPE_FRACTION:g} % of the span, drawn at true scale")
    return fig


@styled
def save_figure(fig, path: str | Path) -> Path:
    """Save a figure of this module as a PNG at ``path`` (atomically, with the provenance)."""
    return save_atomic(fig, path)


def plot_modes(result, path: str | Path, title: str, count: int = DEFAULT_MODES_DRAWN) -> Path:
    """Draw the lowest ``count`` modes (:func:`draw_modes`) and save them as a PNG at ``path``."""
    return save_figure(draw_modes(result, title, count), path)


def modes_png(static_png: str | Path) -> Path:
    """Where the mode figure goes beside the static drawing ``static_png`` (``NAME-modes.png``)."""
    p = Path(static_png)
    return p.with_name(p.stem + "-modes.png")
