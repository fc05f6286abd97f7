"""Figures of spatial cables: the motion across the span (a node's path in the (w, v) plane and
the out-of-plane waveforms) and the plan view of an equilibrium."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..channels import components
from .base import CURVE_POINTS, envelope_plot, figure_grid, legend_below, save_atomic, steady_start, title_line
from .style import COLOURS, SERIES

#: Largest number of nodes whose paths are drawn across the span.
MAX_PATH_NODES = 3


def across_nodes(result) -> list[tuple[int, int, int]]:
    """``(node, column of v, column of w)`` (node 1-based) of the nodes of a spatial history whose
    vertical and out-of-plane displacements were both stored: at most :data:`MAX_PATH_NODES`,
    spread along the cable; empty for a planar history."""
    if components(result) != 3:
        return []
    dofs = [int(d) for d in result.dof_numbers]
    have = []
    for col_w, d in enumerate(dofs):
        if d % 3 == 0 and d - 1 in dofs:  # w of node d / 3, with its v
            have.append((d // 3, dofs.index(d - 1), col_w))
    if len(have) <= MAX_PATH_NODES:
        return have
    pick = np.unique(np.linspace(0, len(have) - 1, MAX_PATH_NODES).round().astype(int))
    return [have[k] for k in pick]


def plot_across(result, path: str | Path, title: str, describe: str) -> Path | None:
    """The motion across the span of a spatial history: the path of a few nodes in the plane
    of (w, v), last half of the record in full colour, and their out-of-plane waveforms
    ``w(t)``; None (nothing written) if no node kept both components.

    Parameters
    ----------
    result : cablesim.dynamics.result.HistoryResult
    path : str or Path
        PNG file to write.
    title : str
        First title line (the case name).
    describe : str
        Second title line (the run's conditions).
    """
    nodes = across_nodes(result)
    if not nodes:
        return None
    t = np.asarray(result.t, dtype=float)
    i0 = steady_start(t)
    fig, axes = figure_grid(1, 2, 4.6, extra_height=1.2)
    ax_path, ax_w = axes[0, 0], axes[0, 1]
    wmax = []
    for c, (node, jv, jw) in enumerate(nodes):
        v, w = result.z[:, jv], result.z[:, jw]
        color = SERIES[c % len(SERIES)]
        step = max(1, -(-w.size // CURVE_POINTS))
        ax_path.plot(w[: i0 + 1 : step], v[: i0 + 1 : step], "-", color=color, lw=0.5, alpha=0.3)
        ax_path.plot(w[i0::step], v[i0::step], "-", color=color, lw=0.8, label=f"node {node}")
        envelope_plot(ax_w, t, w, "-", color=color, lw=0.8, label=f"node {node}")
        wmax.append(float(np.nanmax(np.abs(w))) if w.size else 0.0)
    ax_path.invert_yaxis()  # v points down
    ax_path.set_title("paths in the ($w$, $v$) plane (last half dark)", fontsize="small")
    ax_path.set_xlabel("$w$ (m): across the span's plane")
    ax_path.set_ylabel("$v$ (m): down")
    ax_path.axhline(0.0, color=COLOURS["reference"], lw=0.6)
    ax_path.axvline(0.0, color=COLOURS["reference"], lw=0.6)
    ax_w.set_xlabel("time $t$ (s)")
    ax_w.set_ylabel("$w$ (m)")
    legend_below(fig, ax_w.get_legend_handles_labels()[0], ncol=len(nodes))
    largest = ", ".join(f"node {n}: {m:.3g} m" for (n, _, _), m in zip(nodes, wmax))
    title_line(fig, f"{title}: motion across the span (max $|w|$: {largest})", describe)
    return save_atomic(fig, Path(path))


def plan_view(ax, points: np.ndarray, loads: np.ndarray | None, span: float, color: str) -> None:
    """Draw the plan view (x along the span, w across it) of a spatial cable's nodes and
    supports (rows of ``points``, (n + 2, 3)), with the sustained loads' horizontal parts."""
    ax.plot(points[:, 0], points[:, 2], "-o", color=color, lw=1.6, ms=3)
    ax.plot(points[[0, -1], 0], points[[0, -1], 2], "^", color="k", ms=9)
    if loads is not None and np.abs(loads[:, [0, 2]]).max() > 0:
        h = loads[:, [0, 2]]
        scale = 0.1 * span / np.hypot(h[:, 0], h[:, 1]).max()
        ax.quiver(points[1:-1, 0], points[1:-1, 2], h[:, 0] * scale, h[:, 1] * scale, angles="xy",
                  scale_units="xy", scale=1.0, color="#8c564b", width=0.003)
        tips = np.column_stack([points[1:-1, 0] + h[:, 0] * scale, points[1:-1, 2] + h[:, 1] * scale])
        ax.update_datalim(tips)  # the axes hold every arrow's tip
        ax.autoscale_view()
    ax.set_xlabel("$x$ (m): along the span")
    ax.set_ylabel("$w$ (m): across")
    ax.set_title("plan view (looking down; $w$ to the left of A$\\to$B)", fontsize="small")


def end_view(ax, points: np.ndarray, color: str) -> None:
    """Draw the end view (w across, v down) of a spatial cable's nodes and supports (rows of
    ``points``, (n + 2, 3)), looking from support A along the span."""
    ax.plot(points[:, 2], points[:, 1], "-o", color=color, lw=1.2, ms=3)
    ax.plot(points[[0, -1], 2], points[[0, -1], 1], "^", color="k", ms=9)
    ax.invert_yaxis()  # v points down
    ax.invert_xaxis()  # looking from A towards B, w points to the left
    ax.set_xlabel("$w$ (m): to the left")
    ax.set_ylabel("$v$ (m): down")
    ax.set_title("end view (from A)", fontsize="small")
