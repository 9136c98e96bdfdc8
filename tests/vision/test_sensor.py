"""The depth sensor model: analytic planes, seeding, independence from the batch."""

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.vision.camera import DepthCamera
from affordgrasp.vision.sensor import SensorModel, apply_sensor, surface_cosines

CAMERA = DepthCamera(size=32, fov_deg=60.0)


def _plane(tilt_deg: float, distance: float = 0.5) -> np.ndarray:
    """Depth of the plane n·P = distance, n tilted by tilt_deg about the camera's y."""
    t = np.radians(tilt_deg)
    n = np.array([np.sin(t), 0.0, np.cos(t)])
    rays = CAMERA.ray_directions()
    depth = distance / (rays @ n)
    return np.where(depth > 0, depth, 0.0)[None]


def test_surface_cosines_of_planes():
    rays = CAMERA.ray_directions()
    for tilt in (0.0, 40.0, 55.0):  # every pixel sees the plane in front of the camera
        t = np.radians(tilt)
        n = np.array([np.sin(t), 0.0, np.cos(t)])
        expected = np.abs(rays @ n) / np.linalg.norm(rays, axis=-1)
        np.testing.assert_allclose(surface_cosines(_plane(tilt), CAMERA)[0], expected, atol=1e-9)
    empty = np.zeros((1, 32, 32))
    assert np.all(surface_cosines(empty, CAMERA) == 1.0)


def test_noise_grows_with_depth_and_grazing_returns_are_lost():
    model = SensorModel(grazing_deg=90.0, dropout=0.0)
    flat = np.full((4, 32, 32), 0.5)
    noisy = apply_sensor(flat, model, camera=CAMERA).astype(np.float64)
    sigma = model.sigma_m + model.sigma_quadratic * 0.25
    assert np.std(noisy - 0.5) == pytest.approx(sigma, rel=0.05)
    assert abs(np.mean(noisy - 0.5)) < 3 * sigma / 64
    far = apply_sensor(np.full((4, 32, 32), 1.0), model, camera=CAMERA)
    assert np.std(far - 1.0) > 2 * np.std(noisy - 0.5)
    # returns seen more than 75 degrees off the surface normal are lost, the others kept
    grazing = SensorModel(sigma_m=0.0, sigma_quadratic=0.0, grazing_deg=75.0, dropout=0.0)
    rays = CAMERA.ray_directions()
    t = np.radians(55.0)
    cos = np.abs(rays @ [np.sin(t), 0.0, np.cos(t)]) / np.linalg.norm(rays, axis=-1)
    kept = apply_sensor(_plane(55.0), grazing, camera=CAMERA)[0] > 0
    inner = np.s_[:-1, :-1]  # the last row and column use the neighbour before them
    assert np.array_equal(kept[inner], (cos >= np.cos(np.radians(75.0)))[inner])
    assert 0 < kept.mean() < 1
    # no return stays no return; dropout loses about its share
    holes = SensorModel(sigma_m=0.0, sigma_quadratic=0.0, grazing_deg=90.0, dropout=0.2)
    depth = np.full((8, 32, 32), 0.5)
    depth[:, :4] = 0.0
    out = apply_sensor(depth, holes, camera=CAMERA)
    assert (out[:, :4] == 0).all()
    assert np.mean(out[:, 4:] == 0) == pytest.approx(0.2, abs=0.02)


def test_seeded_and_independent_of_the_batch():
    model = SensorModel(seed=3)
    depth = np.concatenate([_plane(20.0), _plane(10.0, 0.4), _plane(0.0, 0.3)])
    a = apply_sensor(depth, model, keys=[5, 6, 7], camera=CAMERA)
    b = apply_sensor(depth, model, keys=[5, 6, 7], camera=CAMERA)
    assert a.tobytes() == b.tobytes()
    alone = apply_sensor(depth[1:2], model, keys=[6], camera=CAMERA)
    assert alone.tobytes() == a[1:2].tobytes()
    other = apply_sensor(depth, SensorModel(seed=4), keys=[5, 6, 7], camera=CAMERA)
    assert not np.array_equal(other, a)
    with pytest.raises(InputError, match="keys"):
        apply_sensor(depth, model, keys=[1, 2], camera=CAMERA)
    with pytest.raises(InputError, match="dropout"):
        SensorModel(dropout=1.0)


def test_render_depth_is_exact_unless_asked(box_mesh):
    from affordgrasp.vision.depth import render_depth

    p0 = np.array([[0.1, 0.2, 0.0, 0.0, 0.0, 0.5]])
    exact = render_depth(str(box_mesh), p0)
    assert np.array_equal(render_depth(str(box_mesh), p0), exact)
    sensed = render_depth(str(box_mesh), p0, sensor=SensorModel())
    hit = exact > 0
    assert hit.any() and not np.array_equal(sensed, exact)
    assert (sensed[~hit] == 0).all()
    assert np.median(np.abs(sensed - exact)[hit & (sensed > 0)]) < 0.01
