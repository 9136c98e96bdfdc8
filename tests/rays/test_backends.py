"""Every ray-casting backend gives the same first hits on the same rays (a box and a sphere,
analytic distances): rays (EmbreeScene, EmbreeRays, PacketScene, TrimeshRays) and the depth
engines of vision.engines (one-ray Embree, 16-ray packets, the rasteriser)."""

import numpy as np
import pytest
import trimesh

from affordgrasp.rays import RayCaster, RayHits, embree_available, packets
from affordgrasp.rays.embree import EmbreeScene
from affordgrasp.rays.mesh import EmbreeRays, TrimeshRays
from affordgrasp.vision.engines import EmbreeEngine, PacketEngine, RasterEngine

pytestmark = pytest.mark.skipif(not embree_available(), reason="embreex not installed")

CENTRE = np.array([0.3, -0.1, 0.05])
EXTENTS = np.array([0.2, 0.1, 0.06])
RADIUS = 0.05


def box_mesh() -> trimesh.Trimesh:
    return trimesh.creation.box(
        EXTENTS, transform=trimesh.transformations.translation_matrix(CENTRE)
    )


def sphere_mesh() -> trimesh.Trimesh:
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=RADIUS)
    mesh.apply_translation(CENTRE)
    return mesh


def backends(mesh: trimesh.Trimesh) -> dict:
    """Every backend of the interface on one mesh."""
    tri = np.asarray(mesh.triangles)
    out = {
        "EmbreeScene": EmbreeScene(mesh.vertices, mesh.faces, origin=CENTRE),
        "EmbreeRays": EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale),
        "TrimeshRays": TrimeshRays(mesh),
        "embreex": EmbreeEngine(tri, CENTRE),
        "raster": RasterEngine(
            mesh.vertices,
            mesh.faces,
            CENTRE,
            cull=True,
            near=1e-3,
            fallback=lambda: EmbreeEngine(tri, CENTRE),
        ),
    }
    if packets.available():
        out["PacketScene"] = packets.PacketScene(tri, origin=CENTRE)
        out["packets"] = PacketEngine(tri, CENTRE)
    return out


def box_rays(rng: np.random.Generator, n: int):
    """Rays that hit a face at least 2 mm from its edges, and rays that pass 2 mm clear."""
    half = EXTENTS / 2
    axis = rng.integers(0, 3, n)
    sign = rng.choice([-1.0, 1.0], n)
    normal = np.zeros((n, 3))
    normal[np.arange(n), axis] = sign
    target = rng.uniform(-half + 2e-3, half - 2e-3, (n, 3))
    target[np.arange(n), axis] = sign * half[axis]
    # from 1 m away, at most 60 degrees off the face's normal
    w = normal + rng.normal(size=(n, 3)) * 0.5
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    w = np.where((np.sum(w * normal, axis=1) > 0.5)[:, None], w, normal)
    origins = CENTRE + target + w
    hit_dirs = -w * rng.uniform(0.5, 2.0, (n, 1))  # not unit: t in units of |d|
    hit_t = 1.0 / np.linalg.norm(hit_dirs, axis=1)
    # misses: the closest approach to the centre beyond the box's bounding sphere
    miss_origins = CENTRE + rng.normal(size=(n, 3))
    miss_origins = CENTRE + (miss_origins - CENTRE) / np.linalg.norm(
        miss_origins - CENTRE, axis=1, keepdims=True
    )
    towards = CENTRE - miss_origins
    side = np.cross(towards, rng.normal(size=(n, 3)))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    aim = CENTRE + side * (np.linalg.norm(half) + 2e-3 + rng.uniform(0, 0.05, (n, 1)))
    miss_dirs = aim - miss_origins
    return (
        np.concatenate([origins, miss_origins]),
        np.concatenate([hit_dirs, miss_dirs]),
        np.concatenate([hit_t, np.full(n, np.inf)]),
        np.concatenate([normal, np.zeros((n, 3))]),
    )


def check_hits(hits: RayHits, mesh, origins, dirs, t, normal, *, dist_tol, normal_tol):
    hit = np.isfinite(t)
    np.testing.assert_array_equal(hits.hit, hit)
    np.testing.assert_allclose(hits.distance[hit], t[hit], atol=dist_tol, rtol=0)
    assert np.all(np.isinf(hits.distance[~hit]))
    assert np.all(hits.triangle[~hit] == -1)
    np.testing.assert_allclose(hits.normal[hit], normal[hit], atol=normal_tol)
    # the point hit lies in the triangle reported, at the barycentric coordinates reported
    tri = np.asarray(mesh.triangles)[hits.triangle[hit]]
    u, v = hits.barycentric[hit].T
    point = (1 - u - v)[:, None] * tri[:, 0] + u[:, None] * tri[:, 1] + v[:, None] * tri[:, 2]
    expected = origins[hit] + hits.distance[hit, None] * dirs[hit]
    np.testing.assert_allclose(point, expected, atol=2e-6)
    assert np.all(hits.barycentric[hit] >= -1e-5) and np.all(u + v <= 1 + 1e-5)


def test_every_backend_hits_a_box_at_the_analytic_distance():
    mesh = box_mesh()
    origins, dirs, t, normal = box_rays(np.random.default_rng(0), 150)
    found = {}
    for name, backend in backends(mesh).items():
        assert isinstance(backend, RayCaster), name
        hits = backend.cast(origins, dirs)
        check_hits(hits, mesh, origins, dirs, t, normal, dist_tol=1e-6, normal_tol=1e-9)
        found[name] = hits
    # and the same triangles (a box face's two triangles meet on its diagonal: rays
    # within float32 rounding of it may name either)
    ref = found["EmbreeScene"]
    for name, hits in found.items():
        same = np.mean(hits.triangle == ref.triangle)
        assert same > 0.97, (name, same)


def sphere_rays(rng: np.random.Generator, n: int):
    """Rays from 0.5 m at the sphere within 0.7 r of its centre (hits), or 1.3 r (misses)."""
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    origins = CENTRE + 0.5 * w
    side = np.cross(w, rng.normal(size=(n, 3)))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    offset = np.where(np.arange(n) % 4 == 0, 1.3, rng.uniform(0, 0.7, n)) * RADIUS
    dirs = CENTRE + side * offset[:, None] - origins
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    along = 0.5 * np.sqrt(1 - (offset / 0.5) ** 2)
    t = np.where(offset < RADIUS, along - np.sqrt(np.maximum(RADIUS**2 - offset**2, 0)), np.inf)
    point = origins + t[:, None] * dirs
    normal = np.where(np.isfinite(t)[:, None], (point - CENTRE) / RADIUS, 0.0)
    return origins, dirs, t, normal


def test_every_backend_hits_a_sphere_at_the_analytic_distance():
    mesh = sphere_mesh()
    origins, dirs, t, normal = sphere_rays(np.random.default_rng(1), 200)
    # The icosphere's flat faces lie inside the sphere by at most its sagitta; at <= 45
    # degrees of incidence a ray meets them at most sqrt(2) times that further.
    sag = RADIUS - np.min(np.linalg.norm(mesh.triangles_center - CENTRE, axis=1))
    found = {}
    for name, backend in backends(mesh).items():
        hits = backend.cast(origins, dirs)
        check_hits(hits, mesh, origins, dirs, t, normal, dist_tol=1.5 * sag + 1e-6, normal_tol=0.05)
        found[name] = hits
    ref = found["EmbreeScene"]
    for name, hits in found.items():
        np.testing.assert_allclose(hits.distance, ref.distance, rtol=1e-6, err_msg=name)
        assert np.mean(hits.triangle == ref.triangle) > 0.97, name


def test_the_viewers_caster_casts_through_the_interface():
    from affordgrasp.viz.raycast import SceneCaster, caster_of
    from affordgrasp.viz.scene import GraspScene

    mesh = box_mesh()
    caster = caster_of(GraspScene(object_mesh=mesh, hand=None))
    assert isinstance(caster, SceneCaster) and isinstance(caster, RayCaster)
    origins, dirs, t, normal = box_rays(np.random.default_rng(3), 50)
    hits = caster.cast(origins, dirs)
    check_hits(hits, mesh, origins, dirs, t, normal, dist_tol=1e-6, normal_tol=1e-9)
