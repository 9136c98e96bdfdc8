"""Triangle meshes of the rounded hand links (affordgrasp.hands.meshes)."""

import numpy as np
import pytest

from affordgrasp.hands import Shape, get_hand
from affordgrasp.hands.meshes import posed_hand_mesh, shape_mesh


def rounded_box_sdf(points, half, radius):
    q = np.abs(points) - np.asarray(half)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return outside + inside - radius


def rounded_cylinder_sdf(points, core_radius, half_height, radius):
    r = np.linalg.norm(points[:, :2], axis=1) - core_radius
    z = np.abs(points[:, 2]) - half_height
    q = np.stack([r, z], axis=1)
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - radius


def test_rounded_box_vertices_lie_on_the_exact_surface():
    shape = Shape("box", (0.004, 0.0025, 0.038), 0.008)
    mesh = shape_mesh(shape)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    sdf = rounded_box_sdf(mesh.vertices, shape.half_extents, shape.radius)
    assert np.abs(sdf).max() < 1e-9
    np.testing.assert_allclose(
        mesh.extents, 2 * (np.array(shape.half_extents) + shape.radius), atol=1e-9
    )
    # Volume of a sphere-swept box: box + faces * r + edges * quarter cylinders + sphere.
    a, b, c = 2 * np.array(shape.half_extents)
    r = shape.radius
    exact = (
        a * b * c
        + 2 * r * (a * b + b * c + a * c)
        + np.pi * r**2 * (a + b + c)
        + 4 / 3 * np.pi * r**3
    )
    assert mesh.volume == pytest.approx(exact, rel=0.03)


def test_rounded_cylinder_vertices_lie_on_the_exact_surface():
    shape = Shape("cylinder", (0.0395, 0.0395, 0.030), 0.005)
    mesh = shape_mesh(shape)
    assert mesh.is_watertight
    sdf = rounded_cylinder_sdf(mesh.vertices, 0.0395, 0.030, 0.005)
    # The rim is a 48-gon: vertices may be inside by its chord error, never outside.
    assert sdf.max() < 1e-12
    assert sdf.min() > -0.0395 * (1 - np.cos(np.pi / 48)) - 0.005 * 0.03
    np.testing.assert_allclose(mesh.extents, [0.089, 0.089, 0.070], atol=1e-9)


def test_posed_hand_mesh_follows_the_hand_pose():
    hand = get_hand("barrett")
    dofs = hand.open_dofs(0.5)
    local = posed_hand_mesh(hand, dofs)
    assert len(local.face_link) == len(local.mesh.faces)
    assert set(np.unique(local.face_link)) == {
        i for i, link in enumerate(hand.links) if link.shapes
    }
    assert local.link_names == tuple(hand.link_names)
    # The palm face is the plane z = 0 and the palm lies behind it.
    palm_vertices = np.unique(local.mesh.faces[local.face_link == 0])
    assert local.mesh.vertices[palm_vertices, 2].max() == pytest.approx(0.0, abs=1e-9)
    pose = np.eye(4)
    pose[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    pose[:3, 3] = [0.1, -0.2, 0.3]
    moved = posed_hand_mesh(hand, dofs, pose.reshape(-1))
    expected = local.mesh.vertices @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_allclose(moved.mesh.vertices, expected, atol=1e-12)


def test_closing_the_fingers_moves_only_finger_links():
    hand = get_hand("barrett")
    open_ = posed_hand_mesh(hand, hand.open_dofs(0.0))
    closed_dofs = hand.open_dofs(0.0)
    closed_dofs[hand.dof_index("f3_prox")] = 1.0
    closed = posed_hand_mesh(hand, closed_dofs)
    moved = np.any(np.abs(open_.mesh.vertices - closed.mesh.vertices) > 1e-9, axis=1)
    moved_links = {
        hand.link_names[i]
        for i in np.unique(open_.face_link[np.any(moved[open_.mesh.faces], axis=1)])
    }
    assert moved_links == {"f3_prox", "f3_dist"}
