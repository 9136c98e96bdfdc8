"""The compiled multiple-hit loop (metrics/ray_crossings.py) against EmbreeRays' own loop."""

import numpy as np
import pytest

from affordgrasp.metrics import use_geometry
from affordgrasp.metrics.ray_crossings import all_crossings, near_crossings
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


def test_order_by_ray_is_the_two_key_sort():
    rng = np.random.default_rng(3)
    ray = rng.integers(0, 50, 2000)
    t = rng.uniform(0, 1, 2000)
    # in order within each ray (the usual case) and shuffled (the fallback), with ties
    for distances in (np.sort(t)[np.argsort(np.argsort(ray, kind="stable"))], t, np.round(t, 1)):
        got = use_geometry._order_by_ray(ray, distances)
        order = np.lexsort((distances, ray))
        assert np.array_equal(ray[got], ray[order]) and np.array_equal(
            distances[got], distances[order]
        )


def _wedge_rays(mesh, n_faces: int, k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The wedge shape's rays at face centres: from 20 µm under the surface, k directions."""
    rng = np.random.default_rng(seed)
    faces = rng.choice(len(mesh.faces), n_faces, replace=False)
    centre = mesh.vertices[mesh.faces[faces]].mean(axis=1) - 2e-5 * mesh.face_normals[faces]
    sphere = use_geometry._fibonacci_sphere(k)
    return np.repeat(centre, k, axis=0), np.tile(sphere, (n_faces, 1))


@pytest.mark.parametrize("family", ["mug", "knife"])
def test_near_crossings_are_every_crossing_within_reach(family):
    mesh = load_object(family).mesh_data
    origins, directions = _wedge_rays(mesh, 60, 64, 1)
    reach = 3e-3
    ref_tri, ref_ray, ref_loc = all_crossings(mesh.ray, origins, directions)
    tri, ray, loc = near_crossings(mesh.ray, origins, directions, reach)
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


def _box_with_debris():
    """A closed 20 mm cube and, 50 mm above it, one stray triangle (a scan's debris)."""
    import trimesh

    box = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    stray = np.array([[-0.05, -0.05, 0.06], [0.05, -0.05, 0.06], [0.0, 0.05, 0.06]])
    vertices = np.concatenate([box.vertices, stray])
    faces = np.concatenate([box.faces, [[8, 9, 10]]])
    return trimesh.Trimesh(vertices, faces, process=False)


@pytest.mark.parametrize("engine", ["embree", "trimesh"])
def test_a_ray_starts_inside_when_its_first_crossing_leaves(engine):
    """Up from 1 mm under the cube's top: leaving the cube, then crossing the debris. The
    parity of the two crossings says the ray starts outside; its first crossing, leaving
    the solid, says inside, and the 3 mm ball is inside up to the top face."""
    from affordgrasp.objects.rays import EmbreeRays

    mesh = _box_with_debris()
    if engine == "embree":
        mesh.ray = EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale)
    origins = np.array([[0.0, 0.0, 0.009], [0.0, 0.0, 0.009]])
    directions = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    ray, t, inside = use_geometry._near_crossing_distances(mesh, origins, directions, 3e-3)
    assert inside.tolist() == [True, True]
    w, w_in = use_geometry._ball_weights(ray, t, 3e-3, 2e-3, inside)
    np.testing.assert_allclose(w, [(1.0 / 3.0) ** 3, 1.0], rtol=1e-9)
    np.testing.assert_allclose(w_in, [(1.0 / 2.0) ** 3, 1.0], rtol=1e-9)


@pytest.mark.parametrize("engine", ["embree", "trimesh"])
def test_a_fold_within_the_ball_falls_back_to_the_parity(engine):
    """A cube and a 2 mm plate overlapping its top, as one self-intersecting surface: from
    0.8 mm under the top, a ray enters the plate before it leaves the cube (enter, leave,
    leave within 3 mm): the crossings do not alternate, and the parity of all of them
    (three: odd) decides, not the first (entering)."""
    import trimesh

    from affordgrasp.objects.rays import EmbreeRays

    a = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    b = trimesh.creation.box(extents=(0.02, 0.02, 0.002)).apply_translation([0, 0, 0.0105])
    mesh = trimesh.Trimesh(
        np.concatenate([a.vertices, b.vertices]),
        np.concatenate([a.faces, b.faces + len(a.vertices)]),
        process=False,
    )
    if engine == "embree":
        mesh.ray = EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale)
    origins = np.array([[0.001, 0.002, 0.0092]])
    directions = np.array([[0.0, 0.0, 1.0]])
    ray, t, inside = use_geometry._near_crossing_distances(mesh, origins, directions, 3e-3)
    assert len(t) == 3 and t[2] < 3e-3
    assert inside.tolist() == [True]


def _ray_inside(ray, t, radius, starts_inside):
    """The inside weights by numpy (bincount), the reference of the compiled pass."""
    n_rays = len(starts_inside)
    within = t < radius
    ray, t = ray[within], t[within]
    start = np.searchsorted(ray, np.arange(n_rays))
    rank = np.arange(len(ray)) - start[ray]
    cube = (t / radius) ** 3
    inside = np.bincount(ray, weights=np.where(rank % 2 == 0, cube, -cube), minlength=n_rays)
    count = np.bincount(ray, minlength=n_rays)
    inside = inside + (count % 2 == 0)
    return np.where(starts_inside, inside, 1.0 - inside)


@pytest.mark.parametrize("family", ["mug", "knife~scan"])
def test_ball_weights_are_numpys_bit_for_bit(family):
    mesh = load_object(family).mesh_data
    origins, directions = _wedge_rays(mesh, 200, 256, 2)
    ray, t, inside = use_geometry._near_crossing_distances(mesh, origins, directions, 3e-3)
    w, w_in = use_geometry._ball_weights(ray, t, 3e-3, 2e-3, inside)
    assert np.array_equal(w, _ray_inside(ray, t, 3e-3, inside))
    assert np.array_equal(w_in, _ray_inside(ray, t, 2e-3, inside))
    assert 0.3 < w.mean() < 0.7 and np.all((w > -1e-12) & (w < 1 + 1e-12))
