"""Matplotlib figures without a display: the Agg canvas, exact pixel sizes, stable PNG bytes."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..runtime.writing import atomic_write

DPI = 100


def new_figure(width_px: int, height_px: int, *, axes: bool = True):
    """A figure of exactly ``width_px`` x ``height_px`` pixels (and one full-size axes).

    Parameters
    ----------
    width_px, height_px : int
    axes : bool
        Add one axes covering the figure.

    Returns
    -------
    matplotlib.figure.Figure or (Figure, Axes)
        The figure, with its axes when ``axes``.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI)
    fig.patch.set_facecolor("white")
    if not axes:
        return fig
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    return fig, ax


def save_figure(fig, path: str | os.PathLike) -> Path:
    """Write a figure as PNG with no time stamp in it (the same inputs give the same bytes).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : path

    Returns
    -------
    pathlib.Path
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(
        path, lambda fh: fig.savefig(fh, format="png", dpi=DPI, metadata={"Software": None})
    )


def figure_pixels(fig) -> np.ndarray:
    """The figure drawn on the Agg canvas.

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    (h, w, 3) uint8 ndarray
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def save_image(rgb: np.ndarray, path: str | os.PathLike, *, colors: int | None = None) -> Path:
    """Write an image as PNG, optionally reduced to a palette (smaller files, deterministic).

    Parameters
    ----------
    rgb : (h, w, 3) uint8 ndarray
    path : path
    colors : int, optional
        Palette size.

    Returns
    -------
    pathlib.Path
    """
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    image = Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8), "RGB")
    if colors:
        image = image.quantize(
            colors=int(colors), method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
        )
    return atomic_write(path, lambda fh: image.save(fh, format="PNG", optimize=True))


def png_bytes(rgb: np.ndarray, *, max_px: int | None = None) -> bytes:
    """PNG bytes of an image, downscaled to fit ``max_px`` if given.

    Parameters
    ----------
    rgb : (h, w, 3) uint8 ndarray
    max_px : int, optional
        Largest side, pixels.

    Returns
    -------
    bytes
    """
    import io

    from PIL import Image

    image = Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8), "RGB")
    if max_px and max(image.size) > max_px:
        image.thumbnail((max_px, max_px), Image.Resampling.LANCZOS)
    buffer = io.BytesIO()
    image.save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()
