import numpy as np
import pytest
import trimesh
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from affordgrasp.errors import InputError
from affordgrasp.grasp import kernels
from affordgrasp.grasp.pregrasp import (
    hand_rotations,
    sample_inputs,
    spherical_direction,
    start_poses,
    surface_use_directions,
    use_points,
    validate_pregrasps,
)

unit = st.floats(-1, 1, allow_nan=False)


def test_spherical_coding_matches_the_spec():
    np.testing.assert_allclose(spherical_direction([0.0], [1.0]), [[0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(spherical_direction([0.0], [0.0]), [[1, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(spherical_direction([0.5], [0.0]), [[0, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(spherical_direction([1.0], [-1.0]), [[0, 0, -1]], atol=1e-15)


def test_uniform_codes_give_uniform_directions():
    rng = np.random.default_rng(0)
    d = spherical_direction(rng.uniform(-1, 1, 200_000), rng.uniform(-1, 1, 200_000))
    # Uniform on the sphere: every coordinate has mean 0 and variance 1/3.
    np.testing.assert_allclose(d.mean(axis=0), 0, atol=5e-3)
    np.testing.assert_allclose((d**2).mean(axis=0), 1 / 3, atol=5e-3)


@settings(max_examples=60, deadline=None)
@given(unit, unit, unit)
def test_hand_frames_are_right_handed_and_approach_along_z(u1, u2, u3):
    p0 = np.array([[u1, u2, u3, 0, 0, 0.5]])
    r = hand_rotations(p0)[0]
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    np.testing.assert_allclose(r[:, 2], spherical_direction([u1], [u2])[0], atol=1e-12)


def test_roll_turns_the_hand_about_the_approach():
    a = hand_rotations(np.array([[0.3, 0.2, 0.0, 0, 0, 0]]))[0]
    b = hand_rotations(np.array([[0.3, 0.2, 0.5, 0, 0, 0]]))[0]
    assert a[:, 0] @ b[:, 0] == pytest.approx(0.0, abs=1e-12)  # 90° of roll
    np.testing.assert_allclose(np.cross(a[:, 0], b[:, 0]), a[:, 2], atol=1e-12)


def test_start_pose_is_outside_and_offsets_span_the_extent():
    mesh = trimesh.creation.box((0.1, 0.2, 0.3))
    hull = np.asarray(mesh.vertices)
    # Approach along +z: x/y offsets of ±1 reach the box's half extents along the hand axes.
    p0 = np.array([[0.0, 1.0, 0.0, 1.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]])
    poses, travel = start_poses(p0, hull, hand_reach=0.2)
    x, y, z = poses[0][:3, 0], poses[0][:3, 1], poses[0][:3, 2]
    origin = poses[0][:3, 3]
    assert origin @ x == pytest.approx(np.abs(hull @ x).max())
    assert origin @ y == pytest.approx(-np.abs(hull @ y).max())
    radius = np.linalg.norm(hull, axis=1).max()
    assert origin @ z == pytest.approx(-radius - 0.2)
    assert travel[0] > 2 * radius + 0.2
    np.testing.assert_allclose(poses[1][:3, 3], [0, 0, -radius - 0.2], atol=1e-12)


def test_start_poses_do_not_depend_on_the_batch_and_match_the_plain_projection():
    from affordgrasp.grasp.pregrasp import dot3

    rng = np.random.default_rng(5)
    hull = rng.normal(size=(300, 3)) * [0.05, 0.02, 0.1]
    p0 = np.concatenate([rng.uniform(0, 1, (300, 3)), rng.uniform(-1, 1, (300, 3))], axis=1)
    poses, _ = start_poses(p0, hull, hand_reach=0.2)  # more grasps than one block of them
    for i in (0, 127, 128, 299):
        np.testing.assert_array_equal(start_poses(p0[i : i + 1], hull, 0.2)[0][0], poses[i])
    # the extents are the projections of every hull vertex, bit for bit
    rot = hand_rotations(p0)
    px = dot3(hull[:, None, :], rot[None, :, :, 0])
    py = dot3(hull[:, None, :], rot[None, :, :, 1])
    lo, hi = px.min(axis=0), px.max(axis=0)
    ext = kernels.hull_extents(*np.ascontiguousarray(hull.T), rot)
    np.testing.assert_array_equal(ext, np.stack([lo, hi, py.min(axis=0), py.max(axis=0)], 1))
    x = dot3(poses[:, :3, 3], rot[:, :, 0])
    np.testing.assert_allclose(x, (lo + hi) / 2 + p0[:, 3] * (hi - lo) / 2, rtol=0, atol=1e-15)


def test_use_point_is_the_farthest_hit():
    # A hollow box (outer 10 cm, walls 1 cm): the ray from the centre crosses the inner wall
    # first; U is on the outer face.
    outer = trimesh.creation.box((0.1, 0.1, 0.1))
    inner = trimesh.creation.box((0.08, 0.08, 0.08))
    shell = outer.difference(inner)
    pts, nrm, tri = use_points(shell, np.zeros(3), np.array([[0.0, 0.0], [0.0, 1.0]]))
    np.testing.assert_allclose(pts[0], [0.05, 0, 0], atol=1e-12)
    np.testing.assert_allclose(nrm[0], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(pts[1], [0, 0, 0.05], atol=1e-12)
    assert (tri >= 0).all()


def test_use_ray_through_an_opening_takes_the_far_side():
    # the ray from the centre leaves through the opening: U is where the line meets the base,
    # the line's hit farthest along +d
    cup = trimesh.creation.box((0.1, 0.1, 0.1)).difference(
        trimesh.creation.box(
            (0.08, 0.08, 0.18), transform=trimesh.transformations.translation_matrix([0, 0, 0.05])
        )
    )  # 1 cm base, open top
    pts, nrm, tri = use_points(cup, np.array([0, 0, 0.0]), np.array([[0.1, 0.95], [0.3, 0.9]]))
    assert (tri >= 0).all()
    np.testing.assert_allclose(pts[:, 2], [-0.04, -0.04], atol=1e-9)  # the base's inner face
    np.testing.assert_allclose(nrm, [[0, 0, 1], [0, 0, 1]], atol=1e-9)


def test_surface_use_directions_reach_parts_by_area():
    # a plate (thin, large) beside a cube (the centre of mass in the cube): uniform d sees the
    # plate's edge-on sliver; area-uniform d lands on the plate in proportion to its area
    cube = trimesh.creation.box((0.04, 0.04, 0.04))
    plate = trimesh.creation.box(
        (0.1, 0.002, 0.04), transform=trimesh.transformations.translation_matrix([0.07, 0, 0])
    )
    both = trimesh.util.concatenate([cube, plate])
    center = np.zeros(3)
    d = surface_use_directions(both, center, 4000, seed=3)
    np.testing.assert_array_equal(d, surface_use_directions(both, center, 4000, seed=3))
    assert d.shape == (4000, 2) and np.all(np.abs(d) <= 1)
    pts, _, tri = use_points(both, center, d)
    on_plate = np.mean(pts[:, 0] > 0.021)
    share = plate.area / (plate.area + cube.area)
    assert on_plate > 0.8 * share
    _, d_uniform = sample_inputs(0, 0, 4000)
    pts_u, _, _ = use_points(both, center, d_uniform)
    assert np.mean(pts_u[:, 0] > 0.021) < 0.5 * on_plate


def test_samples_do_not_depend_on_how_a_run_is_split():
    p_all, d_all = sample_inputs(7, 0, 3000)
    parts = [sample_inputs(7, a, b) for a, b in ((0, 5), (5, 1500), (1500, 2999), (2999, 3000))]
    np.testing.assert_array_equal(np.concatenate([p for p, _ in parts]), p_all)
    np.testing.assert_array_equal(np.concatenate([d for _, d in parts]), d_all)
    assert not np.array_equal(sample_inputs(8, 0, 10)[0], p_all[:10])
    assert (np.abs(p_all[:, :5]) <= 1).all() and ((p_all[:, 5] >= 0) & (p_all[:, 5] <= 1)).all()


def test_bad_pregrasps_are_refused():
    with pytest.raises(InputError, match="shape"):
        validate_pregrasps(np.zeros((3, 5)))
    with pytest.raises(InputError, match="row 0, parameter 0 is 2.0"):
        validate_pregrasps(np.full((1, 6), 2.0))
    with pytest.raises(InputError, match="nan"):
        validate_pregrasps(np.full((1, 6), np.nan))


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-1, 1), min_size=3, max_size=3),
    st.lists(st.floats(-1, 1), min_size=3, max_size=3),
)
def test_directions_towards_points_invert_the_use_directions(center, point):
    from affordgrasp.grasp.pregrasp import directions_towards, spherical_direction

    c, p = np.array(center), np.array(point)
    assume(np.linalg.norm(p - c) > 1e-3)
    d = directions_towards(c, p[None])
    assert np.all(np.abs(d) <= 1)
    np.testing.assert_allclose(
        spherical_direction(d[:, 0], d[:, 1])[0], (p - c) / np.linalg.norm(p - c), atol=1e-9
    )
