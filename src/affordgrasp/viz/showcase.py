"""The best grasps of tasks, drawn: a PNG grid, one PNG per grasp, an interactive HTML page.

This is the library side of ``affordgrasp show``: :func:`draw_best` takes rankings (see
:func:`affordgrasp.search.best.top_grasps`) and the objects they refer to, renders every
grasp once, and writes the files.

Grid layout: with one grasp per task (``top == 1``) the rows are the objects and the columns
the tasks; otherwise each row is one (object, task) pair and the columns are the ranks.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..columns import hold_effort_sum
from ..hands.model import Hand
from ..search.best import RankedGrasp, TaskRanking
from .figure import png_bytes, save_image
from .grid import save_grid
from .html import ViewerEntry, fmt_value, write_viewer
from .overlays import OverlayStyle, grasp_image
from .scene import grasp_scene

# Facts listed beside each grasp in the viewer: (label, column).
METRIC_FACTS = (
    ("ε", "epsilon"),
    ("GWS volume", "gws_volume"),
    ("I (kg m²)", "inertia"),
    ("ΣE_h (N)", None),
    ("E_i", "impact_effort"),
    ("δ", "discharge"),
    ("U_τ (N)", "use_force"),
    ("U_g (m⁻²)", "use_edge"),
    ("edge angle (°)", "use_edge_angle"),
)


@dataclass
class ShowResult:
    """What :func:`draw_best` wrote.

    Attributes
    ----------
    grid : pathlib.Path or None
        The grid PNG.
    html : pathlib.Path or None
        The viewer page.
    grasps : list of pathlib.Path
        One PNG per grasp (with ``each``).
    best : list of dict
        :func:`best_record` of every grasp drawn.
    """

    grid: Path | None = None
    html: Path | None = None
    grasps: list[Path] = field(default_factory=list)
    best: list[dict] = field(default_factory=list)


def safe_name(text: str) -> str:
    """A file-name-safe version of an object or task name (``knife:3`` → ``knife-3``).

    Parameters
    ----------
    text : str

    Returns
    -------
    str
    """
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-") or "object"


def grasp_facts(g: RankedGrasp, mode: str) -> list[tuple[str, str]]:
    """The (name, value) pairs listed beside a grasp: object, task, rank, score, key, metrics.

    Parameters
    ----------
    g : RankedGrasp
    mode : str
        Threshold mode (shown with the task).

    Returns
    -------
    list of (str, str)
    """
    row = g.row
    facts = [
        ("object", g.object),
        ("task", f"{g.task} ({mode})"),
        ("rank", str(g.rank)),
        ("score F", fmt_value(g.score)),
        ("seed · sample", f"{g.seed} · {g.sample}"),
        ("status", str(row.get("status", ""))),
        ("contacts", str(len(row.get("contact_points") or []))),
    ]
    for label, column in METRIC_FACTS:
        if column is None:
            value = hold_effort_sum(row)
        elif column == "use_edge_angle" and row.get(column) is not None:
            value = math.degrees(float(row[column]))
        else:
            value = row.get(column)
        if value is not None:
            facts.append((label, fmt_value(value)))
    reason = row.get("epsilon_reason")
    if reason:
        facts.append(("why ε = 0", str(reason)))
    links = row.get("contact_link") or []
    if links:
        facts.append(("links touching", ", ".join(sorted(set(map(str, links))))))
    return facts


def best_record(g: RankedGrasp, mode: str) -> dict:
    """One best grasp for JSON output.

    Parameters
    ----------
    g : RankedGrasp
    mode : str
        Threshold mode.

    Returns
    -------
    dict
    """
    row = g.row
    rec = {
        "object": g.object,
        "task": g.task,
        "mode": mode,
        "rank": g.rank,
        "score": g.score,
        "seed": g.seed,
        "sample": g.sample,
        "status": row.get("status"),
        "n_contacts": len(row.get("contact_points") or []),
        "hold_effort_sum": hold_effort_sum(row),
    }
    for _, column in METRIC_FACTS:
        if column is not None and column in row:
            rec[column] = row[column]
    return rec


def draw_best(
    rankings: Sequence[TaskRanking],
    objects: dict,
    out_dir: str | os.PathLike,
    *,
    mode: str = "default",
    top: int = 4,
    cell_px: int = 320,
    grasp_px: int = 512,
    each: bool = False,
    html: bool = True,
    cones: bool = False,
    name: str = "best_grasps",
    title: str = "",
    progress: Callable[[int], None] | None = None,
    hands: Mapping[str, Hand] | None = None,
) -> ShowResult:
    """Render the ranked grasps and write the grid PNG, the viewer page and single PNGs.

    Writes ``<name>.png``, ``<name>.html`` and, with ``each``,
    ``grasps/<object>_<task>_<rank>.png`` under ``out_dir``.

    Parameters
    ----------
    rankings : sequence of TaskRanking
        One per (object, task), in the order to show.
    objects : dict of str to GraspObject
        Object name -> the mesh the rows were simulated on.
    out_dir : path
    mode : str
        Threshold mode (captions).
    top : int
        Grasps per ranking.
    cell_px : int
        Side of a grid cell, pixels.
    grasp_px : int
        Side of a single-grasp PNG, pixels.
    each : bool
        Also write one PNG per grasp.
    html : bool
        Also write the viewer page.
    cones : bool
        Draw the friction cones.
    name : str
        Base name of the files.
    title : str
        Heading (default: from the tasks and mode).
    progress : callable, optional
        Called with 1 after each grasp drawn.
    hands : mapping of str to Hand, optional
        The hand that made each object's rows (e.g. a dataset's custom hand); an object
        not in it is drawn with the hand its rows' ``hand`` column names.

    Returns
    -------
    ShowResult
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    style = OverlayStyle(cones=cones)
    result = ShowResult()
    images: dict[tuple[str, str, int], np.ndarray] = {}
    entries: list[ViewerEntry] = []
    for ranking in rankings:
        obj = objects[ranking.object]
        for g in ranking.best:
            caption = f"#{g.rank}  F={fmt_value(g.score)}"
            scene = grasp_scene(
                obj,
                g.row,
                hand=(hands or {}).get(ranking.object),
                title=f"{g.object} · {g.task} #{g.rank}",
            )
            image, camera = grasp_image(scene, size_px=cell_px, style=style, caption=caption)
            images[(ranking.object, ranking.task, g.rank)] = image
            if each:
                path = (
                    out_dir / "grasps" / f"{safe_name(g.object)}_{safe_name(g.task)}_{g.rank}.png"
                )
                big, _ = grasp_image(
                    scene,
                    size_px=grasp_px,
                    style=style,
                    camera=camera,
                    caption=f"{g.object} · {g.task} #{g.rank}  F={fmt_value(g.score)}",
                )
                save_image(big, path)
                result.grasps.append(path)
            if html:
                entries.append(
                    ViewerEntry(
                        scene,
                        camera,
                        title=f"#{g.rank}  F={fmt_value(g.score)}  (sample {g.sample})",
                        group=f"{g.object} · {g.task}",
                        facts=grasp_facts(g, mode),
                        thumbnail=png_bytes(image, max_px=144),
                    )
                )
            result.best.append(best_record(g, mode))
            if progress is not None:
                progress(1)

    object_names = list(dict.fromkeys(r.object for r in rankings))
    task_names = list(dict.fromkeys(r.task for r in rankings))
    by_key = {(r.object, r.task): r for r in rankings}

    def cell(obj_name, task_name, rank):
        image = images.get((obj_name, task_name, rank))
        if image is not None:
            return image
        r = by_key.get((obj_name, task_name))
        if r is None:
            return None
        if rank == 1:
            return (
                f"no grasp with F > −∞\n{r.accepted} of {r.scored} samples accepted\n"
                f"({task_name}, {mode})"
            )
        return None

    if top == 1 and len(task_names) > 1:
        cells = [[cell(o, t, 1) for t in task_names] for o in object_names]
        rows, cols = object_names, task_names
    else:
        keys = [(r.object, r.task) for r in rankings]
        cells = [[cell(o, t, k) for k in range(1, top + 1)] for o, t in keys]
        rows = [o if len(task_names) == 1 else f"{o} · {t}" for o, t in keys]
        cols = [f"#{k}" for k in range(1, top + 1)]
        if len(task_names) == 1:
            title = title or f"best grasps for {task_names[0]} ({mode})"
    title = title or f"best grasps ({mode})"
    result.grid = save_grid(
        cells, out_dir / f"{name}.png", row_labels=rows, col_labels=cols, title=title, colors=256
    )
    if html and entries:
        result.html = write_viewer(
            out_dir / f"{name}.html",
            entries,
            title=title,
            subtitle=f"{len(entries)} grasps · tasks {', '.join(task_names)} · mode {mode}",
        )
    return result
