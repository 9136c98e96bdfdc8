"""The judges of the paper's validation (§IV-C, Figs. 3-7): is a top grasp semantically right?

Each task is judged by the semantic parts of the built-in families (docs/validation.md §5):

* cut: the use point lies on the ``cutting_edge``;
* beat: the use point lies on the working end: the head of a hammer (``head``,
  ``striking_face``, ``claw``, ``peen``) or of an axe (the same, ``poll`` and its
  ``cutting_edge``), the blade of a meat cleaver (``blade``, ``cutting_edge``, ``spine``,
  ``tip``), by its face's part or by lying within 3 mm of the box of those parts' faces
  (the handle's end shows through the eye of a head); :func:`judge` without a box judges
  by the part alone;
* pick: the contacts surround the centre of mass: projected along the wrist axis onto
  the palm plane, the centre of mass lies inside the convex hull of the contact points
  (at least three contacts not on one line; hull from scipy, margin 0).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial import ConvexHull, QhullError

TASK_FAMILIES: dict[str, tuple[str, ...]] = {
    "cut": ("knife", "meat_cleaver", "axe", "sword", "dagger"),
    "beat": ("hammer", "axe", "meat_cleaver"),
    "pick": (
        "hammer",
        "knife",
        "meat_cleaver",
        "axe",
        "screwdriver",
        "spatula",
        "sword",
        "dagger",
        "bottle",
        "wine_glass",
        "tumbler",
        "mug",
        "ice_cream_cone",
    ),
}
"""The families each task is judged on (those with the parts its judge reads)."""

HEAD = {"head", "striking_face", "claw", "peen", "poll"}
WORKING_END: dict[str, set[str]] = {
    "hammer": HEAD,
    "axe": HEAD | {"cutting_edge"},
    "meat_cleaver": {"blade", "cutting_edge", "spine", "tip"},
}
"""The parts of each beat family that strike."""

# A hammer's or an axe's handle runs through the eye of the head and its end shows on the
# head (hammer:4: 15 mm² of handle faces beside the head's top, 462 mm² on it): a use point
# there strikes with the head, yet its face is labelled handle. So beat counts a use point
# inside the box of the working-end faces (grown by the 3 mm contact merge distance) too.
WORKING_END_GROW_M = 0.003


def surrounds_com(row: dict[str, Any], com: np.ndarray) -> bool:
    """Pick's judge: the centre of mass inside the hull of the contacts, seen along the wrist.

    Parameters
    ----------
    row : dict
        A dataset row with ``contact_points`` (3k floats, object frame, m) and
        ``wrist_axis`` (3 floats, unit).
    com : (3,) float
        The object's centre of mass, m.

    Returns
    -------
    bool
        True when the projection of ``com`` along the wrist axis lies inside (or on) the
        convex hull of the projected contacts; False with fewer than three contacts or
        collinear ones.
    """
    pts = np.asarray(row["contact_points"], dtype=float).reshape(-1, 3)
    if len(pts) < 3:
        return False
    a = np.asarray(row["wrist_axis"], dtype=float)
    e1 = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    q = np.stack([pts @ e1, pts @ e2], axis=1)
    c = np.array([com @ e1, com @ e2])
    try:
        hull = ConvexHull(q)
    except QhullError:  # collinear contacts
        return False
    # facet equations: n·x + b <= 0 inside
    return bool(np.all(hull.equations[:, :2] @ c + hull.equations[:, 2] <= 0.0))


def working_end_box(obj, family: str, grow: float = WORKING_END_GROW_M) -> np.ndarray:
    """The box around the faces of a beat family's working-end parts.

    Parameters
    ----------
    obj : GraspObject
        An instance of ``family`` (with part labels).
    family : str
        A key of :data:`WORKING_END`.
    grow : float
        Margin added on every side, m.

    Returns
    -------
    (2, 3) float
        Lower and upper corners, object frame, m.
    """
    faces = np.isin(obj.parts_of_faces(np.arange(len(obj.mesh.faces))), list(WORKING_END[family]))
    corners = obj.mesh.vertices[obj.mesh.faces[faces].ravel()]
    return np.stack([corners.min(axis=0) - grow, corners.max(axis=0) + grow])


def judge(
    task: str, family: str, rows: pa.Table, com: np.ndarray, box: np.ndarray | None = None
) -> list[bool]:
    """Is each top row right for ``task`` on ``family``?

    Parameters
    ----------
    task : str
        ``cut``, ``beat`` or ``pick``.
    family : str
        The object's family (beat reads its :data:`WORKING_END`).
    rows : pyarrow.Table
        Top rows with ``use_part`` and ``use_point`` (cut, beat) or ``contact_points`` and
        ``wrist_axis`` (pick).
    com : (3,) float
        Centre of mass, m (pick).
    box : (2, 3) float, optional
        Beat's working-end region (:func:`working_end_box`); strict part labels if None.

    Returns
    -------
    list of bool
        One verdict per row, in order.
    """
    out = []
    for row in rows.to_pylist():
        if task == "cut":
            out.append(row["use_part"] == "cutting_edge")
        elif task == "beat":
            inside = box is not None and bool(
                np.all(
                    (np.asarray(row["use_point"]) >= box[0])
                    & (np.asarray(row["use_point"]) <= box[1])
                )
            )
            out.append(row["use_part"] in WORKING_END[family] or inside)
        else:
            out.append(surrounds_com(row, com))
    return out


def scored(
    task: str, family: str, top: pa.Table, com: np.ndarray, box: np.ndarray | None
) -> dict[str, Any]:
    """Judge a top table with the working-end box and by the part labels alone.

    Parameters
    ----------
    task, family, top, com, box
        As for :func:`judge` (``top`` is its ``rows``).

    Returns
    -------
    dict
        ``hits``: [right rows, rows] with ``box``; ``labels``: the same by the labels
        alone; ``top1``: whether the first row is right (None when there is none).
    """
    ok = judge(task, family, top, com, box)
    strict = judge(task, family, top, com)
    return {
        "hits": [int(sum(ok)), len(ok)],
        "labels": [int(sum(strict)), len(strict)],
        "top1": bool(ok[0]) if ok else None,
    }
