"""A map of checks: one row per run, one coloured cell per check (``cablesim stress``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .base import pyplot, save_atomic

#: Cell colours by code: 0 passed, 1 stopped cleanly, 2 failed, 3 not applicable.
COLOURS = ("#2e9e44", "#f0a30a", "#d62728", "#d9d9d9")


def plot_check_map(grid, texts, row_labels, column_titles, breaks, title, legend, path) -> Path:
    """Draw a grid of check outcomes.

    Parameters
    ----------
    grid : ndarray of int, shape (rows, columns)
        Cell codes, indices into :data:`COLOURS`.
    texts : list of list of str
        Text written in each cell ("" for none).
    row_labels, column_titles : list of str
    breaks : list of int
        Rows above which a separating line is drawn.
    title : str
    legend : sequence of 4 str
        Meaning of each colour.
    path : Path
        PNG to write.
    """
    from matplotlib.colors import ListedColormap  # matplotlib loads only when drawing
    from matplotlib.patches import Patch

    plt = pyplot()
    n_rows, n_cols = grid.shape
    fig, ax = plt.subplots(figsize=(11.5, 1.2 + 0.24 * n_rows))
    ax.imshow(grid, cmap=ListedColormap(COLOURS), vmin=0, vmax=3, aspect="auto", interpolation="nearest")
    for i in range(n_rows):
        for j in range(n_cols):
            if texts[i][j]:
                ax.text(j, i, texts[i][j], ha="center", va="center", fontsize=6.5, color="black")
    ax.set_xticks(range(n_cols))
    ax.set_xticklabels(column_titles, fontsize=8)
    ax.xaxis.tick_top()
    ax.set_yticks(range(n_rows))
    ax.set_yticklabels(row_labels, fontsize=7, family="monospace")
    ax.set_xticks(np.arange(-0.5, n_cols), minor=True)
    ax.set_yticks(np.arange(-0.5, n_rows), minor=True)
    ax.grid(which="minor", color="white", linewidth=1.2)
    ax.tick_params(which="minor", length=0)
    for i in breaks:
        ax.axhline(i - 0.5, color="black", linewidth=1.5)
    ax.set_title(title, fontsize=9, pad=38)
    ax.legend(
        handles=[Patch(color=c, label=text) for c, text in zip(COLOURS, legend)],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.02 * 40 / max(n_rows, 1) - 0.005),
        ncol=4,
        fontsize=8,
        frameon=False,
    )
    return save_atomic(fig, path)
