"""The compiled multiple-hit loop (metrics/ray_crossings.py) against EmbreeRays' own loop."""

import numpy as np
import pytest

from affordgrasp.metrics import use_geometry
from affordgrasp.metrics.ray_crossings import all_crossings
from affordgrasp.objects import load_object
from affordgrasp.objects.rays import embree_available

pytestmark = pytest.mark.skipif(not embree_available(), reason="embreex not installed")


def _rays(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Rays from a sphere around the origin towards points near it: most cross a mug's or a
    knife's surface several times, a few start inside, some graze or miss."""
    rng = np.random.default_rng(seed)
    outward = rng.normal(size=(n, 3))
    origins = 0.2 * outward / np.linalg.norm(outward, axis=1, keepdims=True)
    origins[: n // 10] *= 0.05
    directions = rng.uniform(-0.03, 0.03, (n, 3)) - origins
    return origins, directions


@pytest.mark.parametrize("family", ["mug", "knife"])
def test_every_crossing_is_the_loops_bit_for_bit(family):
    mesh = load_object(family).mesh_data
    origins, directions = _rays(600, 7)
    got = all_crossings(mesh.ray, origins, directions)
    ref = mesh.ray.intersects_id(origins, directions, multiple_hits=True, return_locations=True)
    assert len(got[1]) > 2 * 600 // 3  # several hits per ray on most rays
    for a, b in zip(got, ref, strict=True):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_no_ray_no_hit():
    mesh = load_object("mug").mesh_data
    tri, ray, loc = all_crossings(mesh.ray, np.zeros((0, 3)), np.zeros((0, 3)))
    assert tri.shape == ray.shape == (0,) and loc.shape == (0, 3)
    # pointing away from the mug from far outside: no crossing at all
    tri, ray, loc = all_crossings(mesh.ray, np.array([[1.0, 0, 0]]), np.array([[1.0, 0, 0]]))
    assert len(tri) == 0


def test_sorted_by_ray_is_the_two_key_sort():
    rng = np.random.default_rng(3)
    ray = rng.integers(0, 50, 2000)
    t = rng.uniform(0, 1, 2000)
    # in order within each ray (the usual case) and shuffled (the fallback), with ties
    for distances in (np.sort(t)[np.argsort(np.argsort(ray, kind="stable"))], t, np.round(t, 1)):
        got = use_geometry._sorted_by_ray(ray, distances)
        order = np.lexsort((distances, ray))
        assert np.array_equal(got[0], ray[order]) and np.array_equal(got[1], distances[order])
