"""The scene of one grasp: the object, the posed hand and what the overlays mark.

Everything is in the object frame (metres), as the rows of a simulation store it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import trimesh

from ..errors import InputError
from ..hands import Hand, get_hand
from ..hands.meshes import HandMesh, posed_hand_mesh


@dataclass(frozen=True)
class GraspScene:
    """Everything drawn for one grasp, in the object frame (metres).

    Attributes
    ----------
    object_mesh : trimesh.Trimesh
        The object.
    hand : HandMesh or None
        The posed hand mesh, or None to draw the object alone.
    contact_points, contact_normals : (k, 3) float ndarray
        Normals: the object's outward normal.
    contact_mu : (k,) float ndarray
    contact_link : (k,) str ndarray
    use_point, use_normal : (3,) float ndarray
        NaN when the sample has no use point.
    wrist_point, wrist_axis : (3,) float ndarray
        The axis is the approach direction; NaN if unknown.
    center_of_mass : (3,) float ndarray
    title : str
        A short caption.
    hand_model : Hand or None
    link_poses : (n_links, 4, 4) float ndarray or None
        Link → object, for the interactive viewer (which draws the links, not the merged mesh).
    """

    object_mesh: trimesh.Trimesh
    hand: HandMesh | None
    contact_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_mu: np.ndarray = field(default_factory=lambda: np.zeros(0))
    contact_link: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))
    use_point: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    use_normal: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    wrist_point: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    wrist_axis: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    center_of_mass: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    title: str = ""
    hand_model: Hand | None = None
    link_poses: np.ndarray | None = None  # (n_links, 4, 4) link -> object

    @property
    def size(self) -> float:
        """Diagonal of the bounding box of the object and the hand, metres."""
        lo, hi = scene_bounds(self)
        return float(np.linalg.norm(hi - lo))


def _vec(row: Mapping, name: str, width: int) -> np.ndarray:
    value = row.get(name)
    if value is None:
        return np.full(width, np.nan)
    return np.asarray(value, dtype=np.float64).reshape(width)


def _points(row: Mapping, name: str) -> np.ndarray:
    value = row.get(name)
    if value is None or len(value) == 0:
        return np.zeros((0, 3))
    # Arrow gives lists of lists, pandas an object array of arrays: stack either way.
    return np.array([np.asarray(p, dtype=np.float64).reshape(3) for p in value])


def grasp_scene(
    obj, row: Mapping, *, hand: Hand | str | None = None, title: str = ""
) -> GraspScene:
    """The scene of one sample row.

    Parameters
    ----------
    obj : GraspObject
        Its mesh and centre of mass are drawn.
    row : mapping
        The sample columns (conventions: Sample columns), e.g.
        ``table.slice(i, 1).to_pylist()[0]``.
    hand : Hand or str, optional
        The hand that made the grasp; by default the row's ``hand`` column, else "barrett".
    title : str
        A short caption.

    Returns
    -------
    GraspScene
    """
    for name in ("hand_pose", "joints"):
        if row.get(name) is None:
            raise InputError(
                f"a grasp row needs the column {name!r} (see docs/conventions.md) to be drawn"
            )
    if hand is None:
        hand = row.get("hand")
        hand = hand if isinstance(hand, str) and hand else "barrett"
    hand = get_hand(hand) if isinstance(hand, str) else hand
    joints = np.asarray(row["joints"], dtype=np.float64)
    if joints.shape != (len(hand.dofs),):
        raise InputError(
            f"the row has {joints.size} joint values but hand {hand.name!r} has "
            f"{len(hand.dofs)} DOFs; pass the hand that made the dataset"
        )
    pose = np.asarray(row["hand_pose"], dtype=np.float64).reshape(4, 4)
    points = _points(row, "contact_points")
    normals = _points(row, "contact_normals")
    mu = row.get("contact_mu")
    mu = np.zeros(len(points)) if mu is None else np.asarray(mu, dtype=np.float64).reshape(-1)
    links = row.get("contact_link")
    links = np.asarray([""] * len(points) if links is None else list(links), dtype=object)
    return GraspScene(
        object_mesh=obj.mesh,
        hand=posed_hand_mesh(hand, joints, pose),
        hand_model=hand,
        link_poses=pose[None] @ hand.forward_kinematics(joints),
        contact_points=points,
        contact_normals=normals,
        contact_mu=mu,
        contact_link=links,
        use_point=_vec(row, "use_point", 3),
        use_normal=_vec(row, "use_normal", 3),
        wrist_point=_vec(row, "wrist_point", 3),
        wrist_axis=_vec(row, "wrist_axis", 3),
        center_of_mass=np.asarray(obj.mass.center_of_mass, dtype=np.float64),
        title=title,
    )


def scene_points(scene: GraspScene) -> np.ndarray:
    """Points whose projection bounds the scene's: the object's hull and the hand's vertices.

    Parameters
    ----------
    scene : GraspScene

    Returns
    -------
    (n, 3) float64 ndarray
        m.
    """
    pts = [np.asarray(scene.object_mesh.convex_hull.vertices)]
    if scene.hand is not None:
        pts.append(np.asarray(scene.hand.mesh.vertices))
    return np.concatenate(pts)


def scene_bounds(scene: GraspScene) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds of the object and the hand.

    Parameters
    ----------
    scene : GraspScene

    Returns
    -------
    lo, hi : (3,) float64 ndarray
        m.
    """
    lo = np.asarray(scene.object_mesh.bounds[0], dtype=np.float64)
    hi = np.asarray(scene.object_mesh.bounds[1], dtype=np.float64)
    if scene.hand is not None:
        lo = np.minimum(lo, scene.hand.mesh.bounds[0])
        hi = np.maximum(hi, scene.hand.mesh.bounds[1])
    return lo, hi
