"""The compiled multiple-hit loop (rays/crossings.py) against trimesh's own loop."""

import numpy as np
import pytest

from affordgrasp.metrics import wedge
from affordgrasp.objects import load_object
from affordgrasp.rays import embree_available
from affordgrasp.rays.crossings import crossings
from affordgrasp.rays.mesh import mesh_caster

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
    obj = load_object(family)
    origins, directions = _rays(600, 7)
    got = crossings(mesh_caster(obj.mesh_data), origins, directions)
    # trimesh's own loop (Embree through embreex), which the compiled one follows step by step
    ref = obj.mesh.ray.intersects_id(origins, directions, multiple_hits=True, return_locations=True)
    assert len(got[1]) > 2 * 600 // 3  # several hits per ray on most rays
    for a, b in zip(got, ref, strict=True):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_no_ray_no_hit():
    rays = mesh_caster(load_object("mug").mesh_data)
    tri, ray, loc = crossings(rays, np.zeros((0, 3)), np.zeros((0, 3)))
    assert tri.shape == ray.shape == (0,) and loc.shape == (0, 3)
    # pointing away from the mug from far outside: no crossing at all
    tri, ray, loc = crossings(rays, np.array([[1.0, 0, 0]]), np.array([[1.0, 0, 0]]))
    assert len(tri) == 0


def _wedge_rays(mesh, n_faces: int, k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The wedge shape's rays at face centres: from 20 µm under the surface, k directions."""
    rng = np.random.default_rng(seed)
    faces = rng.choice(len(mesh.faces), n_faces, replace=False)
    centre = mesh.vertices[mesh.faces[faces]].mean(axis=1) - 2e-5 * mesh.face_normals[faces]
    sphere = wedge._fibonacci_sphere(k)
    return np.repeat(centre, k, axis=0), np.tile(sphere, (n_faces, 1))


@pytest.mark.parametrize("family", ["mug", "knife"])
def test_near_crossings_are_every_crossing_within_reach(family):
    mesh = load_object(family).mesh_data
    origins, directions = _wedge_rays(mesh, 60, 64, 1)
    reach = 3e-3
    ref_tri, ref_ray, ref_loc = crossings(mesh_caster(mesh), origins, directions)
    tri, ray, loc = crossings(mesh_caster(mesh), origins, directions, reach)
    assert len(ray) < len(ref_ray)  # the rays went on past the ball before

    def per_ray(t_ray, t_tri, t_loc, keep):
        order = np.argsort(t_ray[keep], kind="stable")  # each ray's hits in the loop's order
        return t_ray[keep][order], t_tri[keep][order], t_loc[keep][order]

    def along(t_ray, t_loc):
        return np.einsum("ij,ij->i", t_loc - origins[t_ray], directions[t_ray])

    # every crossing within reach, the same faces and points to the bit
    got = per_ray(ray, tri, loc, along(ray, loc) < reach)
    want = per_ray(ref_ray, ref_tri, ref_loc, along(ref_ray, ref_loc) < reach)
    for a, b in zip(got, want, strict=True):
        assert a.tobytes() == b.tobytes()
    # and each ray's first crossing, wherever it is
    first = np.unique(ray, return_index=True)
    ref_first = np.unique(ref_ray, return_index=True)
    assert np.array_equal(first[0], ref_first[0])
    assert np.array_equal(tri[first[1]], ref_tri[ref_first[1]])
    assert loc[first[1]].tobytes() == ref_loc[ref_first[1]].tobytes()
