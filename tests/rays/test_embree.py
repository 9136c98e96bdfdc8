"""Embree scenes: many alive in one process (a long generate run keeps one per object), and
EmbreeRays answers trimesh's ray queries with trimesh's bits."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from affordgrasp.objects import load_object, prepared
from affordgrasp.rays import embree_available
from affordgrasp.rays.embree import EmbreeScene, embree_device
from affordgrasp.rays.mesh import EmbreeRays

pytestmark = pytest.mark.skipif(not embree_available(), reason="embreex is not installed")

# Builds 1500 scenes of 20 triangles each, keeps them alive and casts a ray into each. With a
# device per scene (embreex's default) the process segfaults after about a thousand: run in
# a child process, so that a crash fails this test rather than the suite.
SCRIPT = textwrap.dedent(
    """
    import numpy as np
    from affordgrasp.rays.embree import EmbreeScene

    rng = np.random.default_rng(0)
    scenes = []
    for i in range(1500):
        tri = rng.random((20, 3, 3))
        tri[0] = [[-1.0, -1.0, 0.5], [1.0, -1.0, 0.5], [0.0, 1.0, 0.5]]
        scene = EmbreeScene(tri)
        scenes.append(scene)
        hits = scene.cast(np.array([[0.0, 0.0, -1.0]]), np.array([[0.0, 0.0, 1.0]]))
        assert hits.hit[0] and abs(hits.distance[0] - 1.5) < 1e-5, (i, hits)
    print("ok", len(scenes))
    """
)


def test_a_thousand_scenes_alive_in_one_process():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=240
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert done.stdout.strip() == "ok 1500"


def test_scenes_share_one_device_and_stay_independent():
    a = EmbreeScene(np.array([[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]]))
    b = EmbreeScene(np.array([[[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]]]))
    assert embree_device() is embree_device()
    origin, direction = np.array([[0.2, 0.2, 0.0]]), np.array([[0.0, 0.0, 1.0]])
    assert a.cast(origin, direction).distance[0] == pytest.approx(1.0, abs=1e-6)
    assert b.cast(origin, direction).distance[0] == pytest.approx(2.0, abs=1e-6)
    del a  # releasing one scene leaves the other (and the device) working
    assert b.cast(origin, direction).distance[0] == pytest.approx(2.0, abs=1e-6)
    assert not b.cast(np.array([[5.0, 5.0, 0.0]]), direction).hit[0]


def test_rays_are_trimeshs_rays_bit_for_bit():
    obj = load_object("mug")
    mesh = obj.mesh
    data = prepared.MeshData.from_trimesh(mesh, obj.mesh_hash)
    rays = EmbreeRays(data.vertices, data.faces, data.face_normals, data.scale)
    rng = np.random.default_rng(5)
    # from a sphere around the mug towards points near its centre: most rays cross its
    # walls several times; a few start inside it
    outward = rng.normal(size=(400, 3))
    origins = 0.2 * outward / np.linalg.norm(outward, axis=1, keepdims=True)
    origins[:40] *= 0.1
    directions = rng.uniform(-0.03, 0.03, (400, 3)) - origins
    for a, b in zip(
        rays.intersects_location(origins, directions, multiple_hits=True),
        mesh.ray.intersects_location(origins, directions, multiple_hits=True),
        strict=True,
    ):
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
    assert len(rays.intersects_location(origins, directions)[0]) > 400  # several hits per ray
    first = rays.intersects_first(origins, directions)
    assert first.tobytes() == mesh.ray.intersects_first(origins, directions).tobytes()
    assert np.array_equal(rays.intersects_any(origins, directions), first != -1)
    loc = rays.intersects_location(origins, directions, multiple_hits=False)
    ref = mesh.ray.intersects_location(origins, directions, multiple_hits=False)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(loc, ref, strict=True))
