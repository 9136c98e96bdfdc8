"""Point clouds: back-projection inverts the projection; fixed size; seeded; padding."""

import numpy as np
import trimesh

from affordgrasp.vision import DepthCamera, DepthRenderer, depth_to_points, point_clouds

TOP = np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 0.5]])


def _depth():
    return DepthRenderer(trimesh.creation.icosphere(subdivisions=3, radius=0.05)).render(TOP)[0]


def test_points_project_back_to_their_pixels():
    depth = _depth()
    camera = DepthCamera()
    pts = depth_to_points(depth, camera)
    assert len(pts) == int((depth > 0).sum())
    k = camera.intrinsics()
    uvw = pts.astype(np.float64) @ k.T
    cols, rows = uvw[:, 0] / uvw[:, 2], uvw[:, 1] / uvw[:, 2]
    r_idx, c_idx = np.nonzero(depth > 0)
    np.testing.assert_allclose(rows, r_idx, atol=1e-3)
    np.testing.assert_allclose(cols, c_idx, atol=1e-3)
    np.testing.assert_allclose(pts[:, 2], depth[depth > 0], rtol=1e-6)


def test_fixed_size_subsample_and_padding():
    depth = _depth()
    n_hit = int((depth > 0).sum())
    sub, counts = point_clouds(depth, 256, seed=3)
    assert sub.shape == (1, 256, 3) and counts[0] == n_hit
    again, _ = point_clouds(depth, 256, seed=3)
    np.testing.assert_array_equal(sub, again)
    other, _ = point_clouds(depth, 256, seed=4)
    assert not np.array_equal(sub, other)
    # every subsampled point is a real point of the cloud
    full = depth_to_points(depth)
    assert np.isin(sub[0].view([("", sub.dtype)] * 3), full.view([("", full.dtype)] * 3)).all()
    padded, _ = point_clouds(depth, n_hit + 10)
    assert np.all(padded[0, n_hit:] == 0) and np.all(padded[0, :n_hit, 2] > 0)
    empty, counts = point_clouds(np.zeros((128, 128), np.float32), 16)
    assert counts[0] == 0 and np.all(empty == 0)


def test_canonicalisations():
    depth = _depth()
    pts, _ = point_clouds(depth, 4000, crop_radius=0.02, centre_depth=True)
    real = pts[0][np.any(pts[0] != 0, axis=1)]
    assert np.all(np.hypot(real[:, 0], real[:, 1]) <= 0.02 + 1e-7)
    assert abs(float(real[:, 2].min())) < 1e-7
