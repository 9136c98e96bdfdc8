"""Seeing results: grasp renders, grids, dataset plots and an offline 3D viewer.

Everything runs headless: images are ray cast (the package's ray-casting interface,
:mod:`affordgrasp.rays`, Embree through ``embreex``), drawn with
matplotlib's Agg canvas and written as PNG; the viewer is one self-contained HTML file.

* :func:`grasp_scene` turns a sample row (conventions: Sample columns) into a :class:`GraspScene`;
  :func:`save_grasp_png` / :func:`grasp_image` draw it (camera: :func:`auto_camera`, or your
  own :class:`Camera`).
* Modules: :mod:`.scene` (what is drawn), :mod:`.camera` (pinhole cameras, the default view),
  :mod:`.raycast` (the image: one ray caster per scene), :mod:`.overlays` (contacts, use
  point, wrist axis drawn over it).
* :class:`DatasetSource` and :class:`TableSource` hold the rows to rank
  (:func:`affordgrasp.search.best.top_grasps`); :func:`draw_best` writes the grid, the
  per-grasp PNGs and the HTML page (``affordgrasp show``).
* :func:`summarize` and :func:`save_plots` plot a dataset (``affordgrasp plots``).
"""

from __future__ import annotations

from .camera import Camera, framed_camera
from .grid import grid_image, save_grid
from .html import ViewerEntry, write_viewer
from .overlays import OverlayStyle, draw_grasp, grasp_image, save_grasp_png
from .plots import save_plots, summarize
from .raycast import Render, SceneCaster, auto_camera, render_image
from .scene import GraspScene, grasp_scene
from .showcase import draw_best
from .sources import DatasetSource, TableSource

__all__ = [
    "Camera",
    "DatasetSource",
    "GraspScene",
    "OverlayStyle",
    "SceneCaster",
    "Render",
    "TableSource",
    "ViewerEntry",
    "auto_camera",
    "draw_best",
    "draw_grasp",
    "framed_camera",
    "grasp_image",
    "grasp_scene",
    "grid_image",
    "render_image",
    "save_grasp_png",
    "save_grid",
    "save_plots",
    "summarize",
    "write_viewer",
]
