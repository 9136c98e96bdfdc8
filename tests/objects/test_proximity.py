"""closest_faces (objects/proximity.py): trimesh's closest_point faces, without trimesh."""

import numpy as np
import pytest
import trimesh

from affordgrasp.objects import load_object, proximity
from affordgrasp.objects.prepared import MeshData


def query_points(mesh: MeshData, seed: int) -> np.ndarray:
    """Vertices, points on edges, inside faces, near edges and around the mesh."""
    rng = np.random.default_rng(seed)
    v, f = mesh.vertices, mesh.faces
    n = 150
    e = rng.integers(0, len(f), n)
    t = rng.random((n, 1))
    edges = v[f[e, 0]] * (1 - t) + v[f[e, 1]] * t
    inside = np.einsum("nk,nkd->nd", rng.dirichlet([1, 1, 1], n), v[f[rng.integers(0, len(f), n)]])
    low, high = v.min(axis=0) - 0.01, v.max(axis=0) + 0.01
    return np.concatenate(
        [
            v[rng.integers(0, len(v), n)],
            edges,
            inside,
            edges + 1e-4 * rng.normal(size=edges.shape),
            rng.uniform(low, high, (n, 3)),
        ]
    )


@pytest.mark.parametrize("spec", ["knife:3", "mug", "hammer"])
def test_closest_faces_are_trimeshs_face_for_face(spec):
    pytest.importorskip("rtree")
    obj = load_object(spec)
    points = query_points(obj.mesh_data, seed=len(spec))
    _, _, expected = trimesh.proximity.closest_point(obj.mesh, points)
    got = proximity.closest_faces(obj.mesh_data, points)
    assert got.dtype == np.int64
    assert np.array_equal(got, expected)
    # one point at a time too (other candidate lists, same answers)
    for k in range(0, len(points), 97):
        assert proximity.closest_faces(obj.mesh_data, points[k : k + 1])[0] == expected[k]
    assert len(proximity.closest_faces(obj.mesh_data, np.zeros((0, 3)))) == 0


def test_without_rtree_the_faces_are_at_trimeshs_distance(monkeypatch):
    obj = load_object("knife:3")
    mesh = MeshData.from_trimesh(obj.mesh, obj.mesh_hash)  # a fresh object: no cached tree
    monkeypatch.setattr(proximity, "_bounds_tree", lambda triangles: None)
    points = query_points(mesh, seed=1)
    _, distance, _ = trimesh.proximity.closest_point(obj.mesh, points)
    got = proximity.closest_faces(mesh, points)
    # a closest face (on an edge or a vertex, maybe another of the faces that meet there)
    on_got = trimesh.triangles.closest_point(obj.mesh.triangles[got], points)
    assert np.allclose(np.linalg.norm(on_got - points, axis=1), distance, rtol=0, atol=1e-12)
