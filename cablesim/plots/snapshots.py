"""Snapshots of the deformed cable during a time history, and node labels for many nodes.

``cablesim plot RUN.h5 --snapshots K`` draws the cable at K instants spread evenly over the
stored record: the shapes ``y0 + z(t)`` at true scale (equilibrium dashed, instants coloured
from early to late), and below them the vertical displacement of every node against its
horizontal position at the same instants, inside the envelope of the whole record, which shows
what the true-scale drawing cannot when the motion is small beside the span.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..cable import Cable, nodes_with_supports
from ..errors import CablesimError
from .base import pyplot, save_atomic, title_line
from .spatial import end_view, plan_view
from .style import COLOURS, figure_width, styled

#: Largest number of node labels on a cable drawing (more would overlap).
MAX_NODE_LABELS = 12
#: Most snapshots one figure draws.
MAX_SNAPSHOTS = 24


def labelled_nodes(n: int, max_labels: int = MAX_NODE_LABELS) -> list[int]:
    """The nodes (1-based) to label on a drawing of ``n`` nodes: all of them up to
    ``max_labels``, else the first and the last and evenly spaced round numbers between."""
    if n <= max_labels:
        return list(range(1, n + 1))
    raw = (n - 1) / (max_labels - 1)
    step = next(s * 10**e for e in range(int(np.log10(raw)) + 2) for s in (1, 2, 5) if s * 10**e >= raw)
    inner = list(range(step, n, step))
    if inner and n - inner[-1] <= step / 2:  # keep the labels clear of nodes 1 and n
        inner.pop()
    return [1, *[k for k in inner if k - 1 > step / 2], n]


def label_nodes(ax, pts: np.ndarray, max_labels: int = MAX_NODE_LABELS) -> list[int]:
    """Write node numbers beside a subset of the nodes (``pts``: supports included, as from
    :func:`cablesim.cable.nodes_with_supports`); returns the labelled nodes."""
    nodes = labelled_nodes(pts.shape[0] - 2, max_labels)
    for k in nodes:
        ax.annotate(str(k), pts[k], textcoords="offset points", xytext=(3, 5), fontsize=8, color="0.3")
    return nodes


def snapshot_indices(m: int, count: int) -> np.ndarray:
    """Indices of ``count`` saved instants spread evenly over ``m`` (first and last included)."""
    return np.unique(np.round(np.linspace(0, m - 1, min(count, m))).astype(int))


#: A response is periodic at its end when its last period repeats the one before to this
#: fraction of its range ...
PERIODIC_TOL = 1e-3
#: ... for a period of at most this many forcing periods.
MAX_PERIODS = 6


def steady_period(t: np.ndarray, z: np.ndarray, omega: float | None) -> float | None:
    """The period of a forced response that is periodic at the end of its record, s: the
    smallest ``p`` forcing periods over which its last stretch repeats the one before (None if
    it does not, for a free vibration, or if the record is too short)."""
    if omega is None or not omega > 0 or t.size < 8:
        return None
    T = 2.0 * np.pi / omega
    scale = np.ptp(z, axis=0).max()
    if not scale > 0:
        return None
    for p in range(1, MAX_PERIODS + 1):
        lo = t[-1] - 2 * p * T
        if lo < t[0]:
            return None
        late = (t >= t[-1] - p * T)
        earlier = np.column_stack([np.interp(t[late] - p * T, t, z[:, j]) for j in range(z.shape[1])])
        if np.max(np.abs(z[late] - earlier)) <= PERIODIC_TOL * scale:
            return p * T
    return None


def periodic_snapshot_indices(t: np.ndarray, period: float, count: int) -> np.ndarray:
    """Indices of ``count`` instants evenly spaced over the last ``period`` of the record (its
    steady period: every phase of the motion, once)."""
    targets = t[-1] - period + period * np.arange(count) / count
    return np.unique(np.clip(np.searchsorted(t, targets), 0, t.size - 1))


@styled
def plot_snapshots(hist, cable: Cable, path: str | Path, title: str, count: int = 6) -> Path:
    """Draw the cable at ``count`` instants of a time history as a PNG (see
    :func:`snapshot_figure`)."""
    return save_atomic(snapshot_figure(hist, cable, title, count), path)


def snapshot_figure(hist, cable: Cable, title: str, count: int = 6):
    """The figure of :func:`plot_snapshots`: axes 0 the shapes, axes 1 the vertical displacements
    and, for a spatial cable, axes 2 and 3 the plan (x, w) and end (w, v) views of the same instants.

    Parameters
    ----------
    hist : cablesim.dynamics.result.HistoryResult
        It must have kept every DOF (``outputs.channels`` unset).
    cable : Cable
        The cable of the run (supports and number of nodes).
    title : str
        First title line.
    count : int
        Number of instants, 1 to :data:`MAX_SNAPSHOTS`: evenly spaced over the last period of a
        response that is periodic at its end (:func:`steady_period`), else spread evenly over
        the record (:func:`snapshot_indices`).

    Raises
    ------
    CablesimError
        If the history kept only some DOF, or ``count`` is out of range.
    """
    n_dof = cable.n_dof
    if not 1 <= count <= MAX_SNAPSHOTS:
        raise CablesimError(f"--snapshots is {count}; draw 1 to {MAX_SNAPSHOTS} instants.", field="snapshots")
    every = list(range(1, n_dof + 1))
    if list(hist.dof_numbers) != every and sorted(set(hist.dof_numbers)) == every:
        hist = hist.keep(every)  # every DOF kept, in another order (outputs.channels)
    if list(hist.dof_numbers) != every:
        raise CablesimError(
            f"Snapshots of the cable need every DOF, but this history kept only {len(hist.dof_numbers)} of "
            f"{n_dof} (outputs.channels); rerun it without outputs.channels.", field="snapshots")
    plt = pyplot()
    spatial = cable.dim == 3
    if spatial:  # the plan and end views of the same instants below (axes 2 and 3)
        fig = plt.figure(figsize=(figure_width(), 9.4), layout="constrained")
        grid = fig.add_gridspec(3, 2, height_ratios=(3, 2, 2.2), width_ratios=(2.2, 1.0))
        shape_ax, disp_ax = fig.add_subplot(grid[0, :]), fig.add_subplot(grid[1, :])
        plan_ax, end_ax = fig.add_subplot(grid[2, 0]), fig.add_subplot(grid[2, 1])
    else:
        fig, (shape_ax, disp_ax) = plt.subplots(2, 1, figsize=(figure_width(), 6.6), layout="constrained",
                                                gridspec_kw=dict(height_ratios=(3, 2)))
    base = nodes_with_supports(cable, hist.y0)[:, :2]  # a spatial cable: its elevation (x, v)
    shape_ax.plot(base[:, 0], base[:, 1], "--", color=COLOURS["reference"], lw=1.2, label="static equilibrium $y_0$")
    label_nodes(shape_ax, base)
    period = steady_period(np.asarray(hist.t, dtype=float), np.asarray(hist.z, dtype=float), hist.omega)
    picks = snapshot_indices(hist.t.size, count) if period is None else \
        periodic_snapshot_indices(np.asarray(hist.t, dtype=float), period, count)
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, picks.size))
    vertical = np.zeros((hist.t.size, cable.n_nodes + 2))  # zero at the supports
    vertical[:, 1:-1] = hist.z[:, 1::cable.dim]
    if spatial:
        base3 = nodes_with_supports(cable, hist.y0)
        plan_view(plan_ax, base3, None, cable.L, COLOURS["reference"])
        end_view(end_ax, base3, COLOURS["reference"])
    for colour, i in zip(colours, picks):
        pts3 = nodes_with_supports(cable, hist.y0 + hist.z[i])
        pts = pts3[:, :2]
        shape_ax.plot(pts[:, 0], pts[:, 1], "-", color=colour, lw=1.4, label=f"t = {hist.t[i]:.4g} s")
        disp_ax.plot(base[:, 0], vertical[i], "-", color=colour, lw=1.4)
        if spatial:
            plan_ax.plot(pts3[:, 0], pts3[:, 2], "-", color=colour, lw=1.2)
            end_ax.plot(pts3[:, 2], pts3[:, 1], "-", color=colour, lw=1.2)
    disp_ax.fill_between(base[:, 0], vertical.min(axis=0), vertical.max(axis=0), color="0.85",
                         label=f"envelope over {hist.t[0]:.4g}-{hist.t[-1]:.4g} s")
    shape_ax.plot([0, cable.L], [0, cable.H], "^", color="k", ms=8, zorder=4)
    for ax in (shape_ax, disp_ax):
        ax.invert_yaxis()
        ax.grid(True, alpha=0.3)
    shape_ax.set_aspect("equal", adjustable="datalim")
    shape_ax.set_ylabel("vertical coordinate (m), down +")
    shape_ax.legend(loc="lower left", ncol=2, framealpha=0.9)
    disp_ax.set_xlabel("horizontal coordinate at equilibrium (m)")
    disp_ax.set_ylabel("vertical displacement (m), down +")
    disp_ax.legend(loc="lower left")
    when = (f"over one steady period of the response ({period:.4g} s, "
            f"{period * hist.omega / (2 * np.pi):.0f} of the forcing)" if period is not None else "spread over the record")
    title_line(fig, f"{title}: the cable at {picks.size} instants (true scale)",
               f"{cable.n_nodes} nodes; span L = {cable.L:g} m, H = {cable.H:g} m; instants {when}")
    return fig
