"""The cable drawing of ``cablesim static``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..cable import nodes_with_supports
from .base import legend_columns, pyplot, save_atomic, title_line
from .snapshots import label_nodes
from .spatial import end_view, plan_view
from .style import COLOURS, figure_width, lowest_modes_text, styled

#: Above this many nodes the loads are drawn as one quiver rather than an arrow per node.
ARROW_NODES = 40
#: Colour of the sustained loads.
SERIES_LOADS = "#8c564b"


@styled
def plot_cable(result, path: str | Path, title: str) -> Path:
    """Draw the cable: natural and deformed shapes, supports, loads and tensions.

    Parameters
    ----------
    result : cablesim.analyses.static.StaticResult
    path : str or Path
        PNG file to write.
    title : str
        First title line (the case name).
    """
    plt = pyplot()
    cable = result.cable
    spatial = cable.dim == 3
    if spatial:  # elevation above the plan and end views
        fig = plt.figure(figsize=(figure_width(), 7.6), layout="constrained")
        grid = fig.add_gridspec(2, 2, height_ratios=(2.0, 1.1), width_ratios=(2.2, 1.0))
        ax, ax_plan, ax_end = fig.add_subplot(grid[0, :]), fig.add_subplot(grid[1, 0]), fig.add_subplot(grid[1, 1])
    else:
        fig, ax = plt.subplots(figsize=(figure_width(), 4.8), layout="constrained")
    loads = SERIES_LOADS
    y = result.y0
    pts = nodes_with_supports(cable, y)[:, :2]  # a spatial cable: its elevation (x, v)
    if result.inextensible is not None:
        nat = nodes_with_supports(cable, result.inextensible.x)[:, :2]
        ax.plot(nat[:, 0], nat[:, 1], "--", color=COLOURS["reference"], lw=1.2,
                label="natural state $x(F_0)$ (inextensible)")
        dmax = np.abs(y - result.inextensible.x).max()
        deformed_label = f"deformed $y$ ({result.analysis} analysis; max $|y - x|$ = {dmax:.3g} m)"
    else:
        deformed_label = f"deformed $y$ ({result.analysis} analysis)"
    ax.plot(pts[:, 0], pts[:, 1], "-", color=COLOURS["response"], lw=2, label=deformed_label)
    masses = cable.masses
    sizes = (30 + 120 * masses / masses.max()) * min(1.0, ARROW_NODES / cable.n_nodes)
    ax.scatter(pts[1:-1, 0], pts[1:-1, 1], s=sizes, color=COLOURS["response"], zorder=3,
               label="lumped masses (area ~ mass)")
    ax.plot([0, cable.L], [0, cable.H], "^", color="k", ms=11, zorder=4, label="supports A, B")
    ax.annotate("A", (0, 0), textcoords="offset points", xytext=(-12, -14))
    ax.annotate("B", (cable.L, cable.H), textcoords="offset points", xytext=(6, -14))
    label_nodes(ax, pts)  # node numbers: all of a short cable, a readable subset of a long one

    # Load arrows, the largest one 15% of the span long.
    P = result.P.reshape(-1, cable.dim)[:, :2]
    pmax = np.abs(P).max()
    span = max(cable.L, np.ptp(pts[:, 1]), 1e-9)
    if pmax > 0:
        scale = 0.15 * span / np.hypot(P[:, 0], P[:, 1]).max()
        # the axes hold every arrow's tip (an annotation whose point is outside is not drawn)
        ax.update_datalim(pts[1:-1] + P * scale)
        if cable.n_nodes > ARROW_NODES:  # one quiver: thousands of annotations take many seconds
            ax.quiver(pts[1:-1, 0], pts[1:-1, 1], P[:, 0] * scale, P[:, 1] * scale, angles="xy",
                      scale_units="xy", scale=1.0, color=loads, width=0.002)
        for k, (node, load) in enumerate(zip(pts[1:-1], P) if cable.n_nodes <= ARROW_NODES else ()):
            if np.hypot(*load) == 0:
                continue
            ax.annotate(
                "",
                xy=node + load * scale,
                xytext=node,
                arrowprops=dict(arrowstyle="-|>", color=loads, lw=1.5),
            )
            if cable.n_nodes <= 10:
                ax.annotate(
                    f"$F_0$ = ({load[0] / 1e3:.4g}, {load[1] / 1e3:.4g}) kN",
                    node + load * scale,
                    textcoords="offset points",
                    xytext=(4, 4),
                    color=loads,
                    fontsize=8,
                )
        ax.plot([], [], color=loads, label="sustained loads $F_0$")
    if cable.n_segments <= 12:
        label_tensions(ax, pts, result.T0)
    ax.invert_yaxis()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("horizontal coordinate (m)")
    ax.set_ylabel("vertical coordinate (m), pointing down")
    if spatial:
        ax.set_title("elevation", fontsize="small")
        plan_view(ax_plan, nodes_with_supports(cable, y), result.P.reshape(-1, 3), span, COLOURS["response"])
        end_view(ax_end, nodes_with_supports(cable, y), COLOURS["response"])
    fig.legend(loc="outside lower center", ncol=legend_columns(2), frameon=False)
    title_line(fig, f"{title}: static equilibrium under $F_0$",
               f"n = {cable.n_nodes} nodes, L = {cable.L:g} m, H = {cable.H:g} m, EA = {cable.EA:.3g} N; "
               f"lowest frequencies {lowest_modes_text(cable, y, result.modes)}")
    return save_atomic(fig, path)


def label_tensions(ax, pts: np.ndarray, T: np.ndarray) -> None:
    """Each segment's tension beside its middle, on its upper side (the sustained loads, and
    their labels, mostly point down): the normal ``(dy, dx)`` points up on screen, the vertical
    axis pointing down."""
    mid = 0.5 * (pts[1:] + pts[:-1])
    for k in range(T.size):
        dx, dy = pts[k + 1] - pts[k]
        nx, ny = np.array([dy, dx]) / max(np.hypot(dx, dy), 1e-300)
        ax.annotate(f"$T_{{{k + 1}}}$ = {T[k] / 1e3:.4g} kN", mid[k], textcoords="offset points",
                    xytext=(8 * nx, 8 * ny), ha="left" if nx > 0.3 else "right" if nx < -0.3 else "center",
                    va="bottom", fontsize=8, color="0.25")
