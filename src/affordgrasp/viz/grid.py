"""A grid of grasp images with row and column labels and a legend of the overlays."""

from __future__ import annotations

import os
from collections.abc import Sequence
from functools import partial
from pathlib import Path

import numpy as np

from .overlays import COM_COLOR, CONTACT_COLOR, USE_COLOR, WRIST_COLOR

LABEL_PX = 28  # width of the row-label column and height of the column-label row
TITLE_PX = 30
LEGEND_PX = 34
_LEGEND_ENTRIES = 5


def grid_image(
    cells: Sequence[Sequence[np.ndarray | str | None]],
    *,
    row_labels: Sequence[str] = (),
    col_labels: Sequence[str] = (),
    title: str = "",
) -> np.ndarray:
    """Assemble square cell images into one labelled image, the legend of the overlays below.

    Parameters
    ----------
    cells : sequence of sequences
        Rows of cells; a cell is an (s, s, 3) uint8 image (all the same size), a string (a
        message drawn in an empty cell) or None (left blank).
    row_labels : sequence of str
        One per row, written vertically on the left.
    col_labels : sequence of str
        One per column, written on top.
    title : str
        Written above the grid.

    Returns
    -------
    (h, w, 3) uint8 ndarray
    """
    from .figure import figure_pixels, new_figure

    n_rows = len(cells)
    n_cols = max((len(r) for r in cells), default=0)
    if n_rows == 0 or n_cols == 0:
        raise ValueError("a grid needs at least one cell")
    size = next((c.shape[0] for r in cells for c in r if isinstance(c, np.ndarray)), 256)
    left = LABEL_PX if row_labels else 0
    top = (TITLE_PX if title else 0) + (LABEL_PX if col_labels else 0)
    width = left + n_cols * size
    legend_cols = max(1, min(_LEGEND_ENTRIES, width // 150))
    legend_rows = -(-_LEGEND_ENTRIES // legend_cols)
    bottom = LEGEND_PX + 16 * (legend_rows - 1)
    height = top + n_rows * size + bottom
    fig = new_figure(width, height, axes=False)

    def frac(x0, y0, w, h):  # pixel box (from the top-left) to figure fractions
        return (x0 / width, 1.0 - (y0 + h) / height, w / width, h / height)

    if title:
        fig.text(0.5, 1.0 - 0.5 * TITLE_PX / height, title, ha="center", va="center", fontsize=12)
    y_cols = TITLE_PX if title else 0
    for j, label in enumerate(col_labels[:n_cols]):
        x = (left + (j + 0.5) * size) / width
        fig.text(
            x,
            1.0 - (y_cols + 0.5 * LABEL_PX) / height,
            label,
            ha="center",
            va="center",
            fontsize=10,
            fontweight="bold",
        )
    for i, label in enumerate(row_labels[:n_rows]):
        y = 1.0 - (top + (i + 0.5) * size) / height
        fig.text(
            0.5 * LABEL_PX / width,
            y,
            label,
            ha="center",
            va="center",
            rotation=90,
            fontsize=10,
            fontweight="bold",
        )
    for i, row in enumerate(cells):
        for j, cell in enumerate(row):
            ax = fig.add_axes(frac(left + j * size, top + i * size, size, size))
            ax.set_axis_off()
            if isinstance(cell, np.ndarray):
                ax.imshow(cell, interpolation="nearest")
                ax.set_xlim(-0.5, cell.shape[1] - 0.5)
                ax.set_ylim(cell.shape[0] - 0.5, -0.5)
            elif isinstance(cell, str):
                ax.text(
                    0.5,
                    0.5,
                    cell,
                    ha="center",
                    va="center",
                    fontsize=9,
                    color="#555555",
                    wrap=True,
                    transform=ax.transAxes,
                )
            # Thin separators keep neighbouring cells apart at thumbnail size.
            ax.add_patch(_frame(ax))
    _legend(fig, frac(0, height - bottom, width, bottom), legend_cols)
    return figure_pixels(fig)


def _frame(ax):
    from matplotlib.patches import Rectangle

    return Rectangle((0, 0), 1, 1, transform=ax.transAxes, fill=False, ec="#d0d0d0", lw=0.8)


def _legend(fig, box, ncol: int) -> None:
    from matplotlib.lines import Line2D

    ax = fig.add_axes(box)
    ax.set_axis_off()
    line = partial(Line2D, [], [], marker="o", ms=6)
    handles = [
        line(ls="-", color=CONTACT_COLOR, mec="black", lw=1.6, label="contact + normal"),
        line(ls="none", mfc="none", mec=CONTACT_COLOR, mew=1.5, label="hidden contact"),
        line(ls="-", color=USE_COLOR, mec="black", ms=7, lw=1.6, label="use point + normal"),
        line(ls=(0, (4, 2)), color=WRIST_COLOR, marker="s", ms=5, lw=1.6, label="wrist axis"),
        line(ls="none", marker="P", mfc="white", mec=COM_COLOR, ms=7, label="centre of mass"),
    ]
    ax.legend(
        handles=handles,
        loc="center",
        ncol=ncol,
        frameon=False,
        fontsize=8,
        handlelength=2.0,
        columnspacing=1.2,
    )


def save_grid(
    cells: Sequence[Sequence[np.ndarray | str | None]],
    path: str | os.PathLike,
    *,
    row_labels: Sequence[str] = (),
    col_labels: Sequence[str] = (),
    title: str = "",
    colors: int | None = None,
) -> Path:
    """:func:`grid_image` written as PNG.

    Parameters
    ----------
    cells, row_labels, col_labels, title
        As for :func:`grid_image`.
    path : path
        The PNG file.
    colors : int, optional
        Reduce to a palette of this many colours for small files.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    from .figure import save_image

    image = grid_image(cells, row_labels=row_labels, col_labels=col_labels, title=title)
    return save_image(image, path, colors=colors)
