"""The one pinhole model (vision/camera.PinholeCamera): pixel rays and projection invert each
other, for the depth camera (pixel centres at integers) and the viewer's camera (at + 0.5)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from affordgrasp.vision.camera import DepthCamera
from affordgrasp.viz.camera import Camera


def viewer_camera(width, height, fov):
    return Camera([0.3, -0.4, 0.2], [0.01, 0.02, 0.0], [0, 0, 1], fov, width, height)


@settings(max_examples=60, deadline=None)
@given(
    size=st.integers(2, 512),
    height=st.integers(2, 512),
    fov=st.floats(1.0, 170.0),
    u=st.floats(-0.2, 1.2),
    v=st.floats(-0.2, 1.2),
    depth=st.floats(1e-3, 1e3),
    viewer=st.booleans(),
)
def test_project_inverts_pixel_ray(size, height, fov, u, v, depth, viewer):
    cam = viewer_camera(size, height, fov) if viewer else DepthCamera(size=size, fov_deg=fov)
    uv = np.array([[u * cam.width, v * cam.height]])
    back, z = cam.project_camera(cam.pixel_rays(uv) * depth)
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-9 * max(cam.width, cam.height))
    assert z[0] == pytest.approx(depth, rel=1e-15)


def test_pixel_centres_and_principal_point():
    depth_cam = DepthCamera(size=8, fov_deg=50.0)
    viewer = viewer_camera(8, 8, 50.0)
    # one geometry: the same rays through the pixel centres, bit for bit
    np.testing.assert_array_equal(depth_cam.ray_directions(), viewer.ray_directions())
    assert depth_cam.focal_px == viewer.focal_px
    # pixel coordinates differ by the convention only: centres at integers vs at + 0.5
    uv, _ = depth_cam.project_camera(depth_cam.ray_directions().reshape(-1, 3))
    cols, rows = np.meshgrid(np.arange(8), np.arange(8))
    np.testing.assert_allclose(uv, np.column_stack([cols.ravel(), rows.ravel()]), atol=1e-12)
    uv, _ = viewer.project_camera(viewer.ray_directions().reshape(-1, 3))
    np.testing.assert_allclose(uv - 0.5, np.column_stack([cols.ravel(), rows.ravel()]), atol=1e-12)
    assert depth_cam.principal_point == (3.5, 3.5) == (depth_cam.principal_px,) * 2
    np.testing.assert_array_equal(depth_cam.intrinsics()[:2, 2], [3.5, 3.5])
    assert viewer.principal_point == (4.0, 4.0)


def test_points_behind_do_not_project():
    cam = DepthCamera(size=16)
    uv, z = cam.project_camera(np.array([[0.1, 0.0, -1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    assert np.all(np.isnan(uv[:2])) and np.all(np.isfinite(uv[2]))
    np.testing.assert_array_equal(z, [-1.0, 0.0, 1.0])


def test_world_rays_and_projection_agree_for_a_pose():
    rng = np.random.default_rng(4)
    cam = DepthCamera(size=24, fov_deg=40.0)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    rot = q * np.sign(np.linalg.det(q))  # a rotation, camera -> world
    position = rng.normal(size=3)
    rays = cam.world_rays(rot)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, atol=1e-12)
    k = 5 * 24 + 17
    uv, depth = cam.project_world(position + 0.7 * rays[k], rot, position)
    np.testing.assert_allclose(uv[0], [17, 5], atol=1e-9)
    assert depth[0] == pytest.approx(0.7 * (rays[k] @ rot[:, 2]))
