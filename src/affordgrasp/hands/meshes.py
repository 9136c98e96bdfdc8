"""Triangle meshes of a hand's rounded link shapes, for drawing (not for collision).

A link shape is a sphere-swept convex core (see :mod:`affordgrasp.hands.model`): a box or a
capped cylinder grown by a ball of radius ``radius``. Such a solid is convex, so its surface is
the convex hull of balls placed on the core's corners (box) or around its two rims (cylinder);
the mesh is that hull over sampled balls. Every vertex lies on the exact surface of a box
shape; a cylinder's rim is sampled with 48 points, so its vertices may lie inside the exact
surface by the chord error (0.12 mm for the Barrett palm), never outside. The drawing thus
matches the geometry the grasp policy collides with.

Frames: :func:`shape_mesh` is in the shape's frame, :func:`link_meshes` in the link frames,
:func:`posed_hand_mesh` in the hand frame or, given ``hand_pose`` (hand → object), in the
object frame, as the rows of a simulation store it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import trimesh

from ..caching import IdentityCache
from .model import Hand, Shape

# Points on the unit sphere used to sweep the ball: an icosphere of 162 vertices keeps the
# chord error under 3 % of the rounding radius and hands stay under 10k triangles.
_BALL_SUBDIVISIONS = 2
_RIM_SEGMENTS = 48


@dataclass(frozen=True)
class HandMesh:
    """A posed hand as one triangle mesh.

    Attributes
    ----------
    mesh : trimesh.Trimesh
        Metres, in the frame asked for.
    face_link : (f,) int ndarray
        Index into ``link_names`` of the link each face belongs to.
    link_names : tuple of str
        The hand's link names.
    """

    mesh: trimesh.Trimesh
    face_link: np.ndarray
    link_names: tuple[str, ...]


@lru_cache(maxsize=1)
def _unit_ball() -> np.ndarray:
    return trimesh.creation.icosphere(subdivisions=_BALL_SUBDIVISIONS).vertices.copy()


@lru_cache(maxsize=256)
def _shape_mesh_cached(
    kind: str, half_extents: tuple[float, float, float], radius: float
) -> trimesh.Trimesh:
    ball = _unit_ball() * radius
    hx, hy, hz = (float(v) for v in half_extents)
    if kind == "box":
        corners = np.array(
            [[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
        )
    elif kind == "cylinder":
        angle = np.linspace(0.0, 2.0 * np.pi, _RIM_SEGMENTS, endpoint=False)
        ring = np.stack([hx * np.cos(angle), hx * np.sin(angle)], axis=1)
        corners = np.concatenate(
            [np.column_stack([ring, np.full(len(ring), z)]) for z in (-hz, hz)]
        )
    else:
        raise ValueError(f"unknown shape kind {kind!r}; expected 'box' or 'cylinder'")
    points = (corners[:, None, :] + ball[None, :, :]).reshape(-1, 3)
    hull = trimesh.convex.convex_hull(points)
    hull.fix_normals()
    return hull


def shape_mesh(shape: Shape) -> trimesh.Trimesh:
    """The surface of one rounded shape as a closed, outward-oriented mesh in its own frame.

    Parameters
    ----------
    shape : Shape
        A sphere-swept box or cylinder.

    Returns
    -------
    trimesh.Trimesh
        Metres, in the shape frame.
    """
    return _shape_mesh_cached(
        shape.kind, tuple(float(v) for v in shape.half_extents), float(shape.radius)
    ).copy()


def link_meshes(hand: Hand) -> list[trimesh.Trimesh | None]:
    """One mesh per link in its link frame (the union of its shapes).

    Parameters
    ----------
    hand : Hand
        The hand.

    Returns
    -------
    list of trimesh.Trimesh or None
        In link order, metres; None for a link without shapes. Cached per Hand object.
    """
    out: list[trimesh.Trimesh | None] = []
    for link in hand.links:
        parts = []
        for s in link.shapes:
            m = shape_mesh(s)
            m.apply_transform(np.asarray(s.pose, dtype=np.float64))
            parts.append(m)
        out.append(trimesh.util.concatenate(parts) if parts else None)
    return out


def posed_hand_mesh(
    hand: Hand, dof_values: np.ndarray, hand_pose: np.ndarray | None = None
) -> HandMesh:
    """The hand at ``dof_values`` as one mesh, with the link of every face.

    Parameters
    ----------
    hand : Hand
        The hand.
    dof_values : (n_dofs,) array_like of float
        DOF values (rad or m) in ``hand.dof_names`` order (a row's ``joints``).
    hand_pose : (4, 4) or (16,) array_like of float, optional
        Row-major hand → object transform (m); None for the hand frame.

    Returns
    -------
    HandMesh
    """
    link_poses = hand.forward_kinematics(np.asarray(dof_values, dtype=np.float64))
    if hand_pose is not None:
        pose = np.asarray(hand_pose, dtype=np.float64).reshape(4, 4)
        link_poses = pose[None] @ link_poses
    vertices, faces, face_link = [], [], []
    offset = 0
    for i, m in enumerate(_link_meshes_cached(hand)):
        if m is None:
            continue
        v = m.vertices @ link_poses[i, :3, :3].T + link_poses[i, :3, 3]
        vertices.append(v)
        faces.append(m.faces + offset)
        face_link.append(np.full(len(m.faces), i, dtype=np.int64))
        offset += len(v)
    mesh = trimesh.Trimesh(np.concatenate(vertices), np.concatenate(faces), process=False)
    return HandMesh(mesh, np.concatenate(face_link), tuple(hand.link_names))


_LINK_MESHES: IdentityCache[list] = IdentityCache()


def _link_meshes_cached(hand: Hand) -> list[trimesh.Trimesh | None]:
    # Hands are frozen dataclasses holding arrays (unhashable): cached by identity
    return _LINK_MESHES.get(hand, lambda: link_meshes(hand))
