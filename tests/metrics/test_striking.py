"""The striking-surface columns (striking.py): depth behind U and relief around it."""

import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.metrics.striking import RELIEF_RADIUS_M, use_depth, use_relief


@pytest.fixture(scope="module")
def head():
    """A hammer-like head: a 100 x 28 x 24 mm box along x (its faces at x = ±50 mm)."""
    return trimesh.creation.box(extents=(0.1, 0.028, 0.024))


def test_depth_is_the_chord_behind_each_face(head):
    P = np.array([[0.05, 0.003, 0.002], [-0.05, 0, 0], [0.01, 0.014, 0], [0.02, 0, -0.012]])
    N = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 0, -1]])
    np.testing.assert_allclose(use_depth(head, P, N), [0.1, 0.1, 0.028, 0.024], atol=1e-9)
    assert use_depth(head, P[0], N[0]) == pytest.approx(0.1)  # one point: a float


def test_relief_is_zero_on_a_face_and_the_sag_on_a_sphere(head):
    face = use_relief(head, [[0.05, 0, 0], [0, 0, 0.012]], [[1.0, 0, 0], [0, 0, 1]])
    np.testing.assert_allclose(face, 0.0, atol=1e-9)
    for radius in (0.011, 0.015):  # a ball peen's radius
        ball = trimesh.creation.icosphere(subdivisions=6, radius=radius)
        sag = 8 / 9 * (radius - np.sqrt(radius**2 - RELIEF_RADIUS_M**2))
        got = use_relief(ball, [0, 0, radius], [0, 0, 1])
        assert got == pytest.approx(sag, rel=0.05)  # the facets' chord error
        assert got > 0.7e-3
    # a noisy normal tilts U's tangent plane, not the fitted one
    tilted = np.array([np.sin(0.1), 0, np.cos(0.1)])
    assert use_relief(head, [0, 0, 0.012], tilted) == pytest.approx(0.0, abs=1e-9)
    # U 2 mm from the face's rim: the ring falls off the face, 10 mm down the side faces
    assert use_relief(head, [0.05, 0.012, 0], [1.0, 0, 0]) >= 0.002
    # a thin plate's edge (a claw's tine, 3 mm): the ring misses the part entirely
    plate = trimesh.creation.box(extents=(0.05, 0.003, 0.05))
    assert np.isinf(use_relief(plate, [0.025, 0, 0], [1.0, 0, 0]))


def test_rigid_motions_and_bad_input(head):
    rng = np.random.default_rng(0)
    R = trimesh.transformations.random_rotation_matrix(rng.random(3))
    R[:3, 3] = [0.3, -0.2, 0.1]
    moved = head.copy().apply_transform(R)
    P = np.array([[0.05, 0.003, 0.002], [0.01, 0.014, 0]])
    N = np.array([[1.0, 0, 0], [0, 1, 0]])
    P2 = P @ R[:3, :3].T + R[:3, 3]
    N2 = N @ R[:3, :3].T
    np.testing.assert_allclose(use_depth(moved, P2, N2), use_depth(head, P, N), atol=1e-9)
    np.testing.assert_allclose(use_relief(moved, P2, N2), use_relief(head, P, N), atol=1e-9)
    with pytest.raises(InputError, match="one per use point"):
        use_depth(head, P, N[:1])
    with pytest.raises(InputError, match="radius"):
        use_relief(head, P, N, radius=-1.0)
    with pytest.raises(InputError, match="rays"):
        use_relief(head, P, N, rays=2)
    assert use_depth(head, np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


def test_lever_ratio_compares_distances_to_the_wrist_axis():
    from affordgrasp.metrics.striking import use_lever_ratio

    U = np.array([[0.3, 0, 0.5], [0.05, 0, 0]])
    W = np.zeros((2, 3))
    A = np.tile([0, 0, 1.0], (2, 1))
    np.testing.assert_allclose(use_lever_ratio(U, [0.2, 0, 0], W, A), [1.5, 0.25])
    # signed: the mass on the other side of the axis from U, or on it, is -inf; NaN stays NaN
    other = np.array([[-0.1, 0, 0], [0.1, 0, 0], [np.nan, 0, 0]])
    got = use_lever_ratio(other, [0.2, 0, 0], np.zeros((3, 3)), np.tile([0, 0, 1.0], (3, 1)))
    assert got[0] == -np.inf and got[1] == pytest.approx(0.5) and np.isnan(got[2])
    # only the lever's projection counts: the mass off to the side of U's lever
    side = use_lever_ratio([[0.2, 0, 0]], [0.1, 0.3, 0], np.zeros((1, 3)), [[0, 0, 1.0]])
    np.testing.assert_allclose(side, [2.0])
