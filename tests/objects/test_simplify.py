"""Large meshes simplified to a measured tolerance (objects/simplify.py, prepare_mesh)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
import trimesh

from affordgrasp.objects.loading import prepare_mesh
from affordgrasp.objects.simplify import (
    LARGE_MESH_FACES,
    simplify_to_tolerance,
    surface_distance_bound,
)

RADIUS = 0.05


@pytest.fixture(scope="module")
def sphere():
    """An 82k-triangle sphere of radius 5 cm (generated, not stored)."""
    return trimesh.creation.icosphere(subdivisions=6, radius=RADIUS)


def test_distance_bound_is_exact_where_refined_and_never_below():
    rng = np.random.default_rng(0)
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=RADIUS)
    points = rng.normal(size=(300, 3)) * RADIUS
    _, truth, _ = trimesh.proximity.closest_point(mesh, points)
    bound = surface_distance_bound(points, mesh.vertices, mesh.faces, neighbours=1)
    assert np.all(bound >= truth - 1e-12)
    assert np.any(bound > truth + 1e-6)  # one neighbour is not enough: a real bound
    exact = surface_distance_bound(points, mesh.vertices, mesh.faces, neighbours=1, exact_above=0)
    np.testing.assert_allclose(exact, truth, atol=1e-12)


def test_sphere_simplified_within_tolerance_checked_against_trimesh(sphere):
    tol = 1e-4
    v, f, report = simplify_to_tolerance(
        sphere.vertices, sphere.faces, tol, max_faces=20_000, min_faces=2000
    )
    assert report.faces_before == len(sphere.faces)
    assert report.faces_after == len(f) < len(sphere.faces) / 4
    assert report.within_tolerance and report.distance <= tol
    # The reported distance is the maximum over the sampled vertices: check a few with trimesh.
    simplified = trimesh.Trimesh(v, f, process=False)
    rng = np.random.default_rng(1)
    pts = sphere.vertices[rng.choice(len(sphere.vertices), 100, replace=False)]
    _, truth, _ = trimesh.proximity.closest_point(simplified, pts)
    assert truth.max() <= report.distance + 1e-12
    # Analytic: the simplified vertices stay within the tolerance of the true sphere.
    assert np.abs(np.linalg.norm(v, axis=1) - RADIUS).max() <= tol


def test_unreachable_tolerance_is_reported_not_hidden():
    small = trimesh.creation.icosphere(subdivisions=4, radius=RADIUS)
    v, f, report = simplify_to_tolerance(small.vertices, small.faces, 1e-9, max_faces=100)
    assert not report.within_tolerance
    assert report.distance > 1e-9 and len(f) == report.faces_after


def test_prepare_mesh_simplifies_a_large_mesh_and_says_so(sphere, caplog):
    with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.loading"):
        out = prepare_mesh(sphere, source="scan.ply", simplify_above=20_000)
    message = " ".join(r.getMessage() for r in caplog.records)
    assert "scan.ply has 81920 triangles: simplified to" in message, message
    assert "within the 0.1 mm tolerance" in message and "measured at" in message
    assert len(out.faces) <= 81_920 // 2
    # Metrics of the two agree within what the tolerance allows: the volume differs by at
    # most the area times the distance.
    assert abs(out.volume - sphere.volume) <= sphere.area * 1e-4
    assert out.is_watertight


def test_prepare_mesh_leaves_meshes_below_the_threshold(caplog):
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    with caplog.at_level(logging.WARNING):
        out = prepare_mesh(box, source="box")
    assert len(out.faces) == 12 and "simplified" not in caplog.text
    assert LARGE_MESH_FACES >= 100_000  # scans of 0.1-2 M triangles: the large ones only


def test_torus_prepared_to_its_stated_distance(caplog):
    """A 60k-triangle torus: simplified, its volume within the stated distance."""
    torus = trimesh.creation.torus(0.05, 0.015, major_sections=200, minor_sections=150)
    with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.loading"):
        out = prepare_mesh(torus, source="torus.ply", simplify_above=50_000)
    assert len(out.faces) < len(torus.faces)
    text = caplog.text
    assert "torus.ply has 60000 triangles: simplified to" in text
    stated = float(text.split("lies at most ")[1].split(" mm")[0]) * 1e-3
    assert abs(out.volume - torus.volume) <= torus.area * stated
    true_volume = 2 * math.pi**2 * 0.05 * 0.015**2
    assert out.volume == pytest.approx(true_volume, rel=2e-3)


def test_distance_to_sub_millimetre_triangles_is_exact():
    """trimesh's closest_point mistakes 0.5 mm triangles in metres for degenerate ones."""
    from affordgrasp.objects.simplify import _distance_to_triangles

    rng = np.random.default_rng(2)
    corner = rng.normal(size=(200, 3)) * 0.05
    tri = corner[:, None, :] + rng.uniform(0, 5e-4, size=(200, 3, 3)) * [1, 1, 0]
    above = tri.mean(axis=1) + [0, 0, 1e-6]  # 1 µm over the triangle's centroid
    np.testing.assert_allclose(_distance_to_triangles(tri, above), 1e-6, rtol=1e-6)


def test_a_simplification_that_opens_a_closed_mesh_is_not_kept(sphere, caplog, monkeypatch):
    # Quadric decimation can open a closed surface (seen on a mug's scan of 772,000
    # triangles); whatever the decimation returns, an open result of a closed original
    # gives way to the original.
    from affordgrasp.objects import loading

    simplified = loading._simplified

    def opened(vertices, faces, tolerance, factor, source):
        v, f = simplified(vertices, faces, tolerance, factor, source)
        return v, f[1:]  # one triangle missing: three open edges

    monkeypatch.setattr(loading, "_simplified", opened)
    with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.loading"):
        out = prepare_mesh(sphere, source="scan.ply", simplify_above=20_000)
    assert len(out.faces) == len(sphere.faces) and out.is_watertight
    assert "its simplified mesh is not closed (3 open or non-manifold edges)" in caplog.text
    assert out.volume == pytest.approx(sphere.volume, rel=1e-12)
    # an open original keeps the simplified mesh, repaired as any open mesh is
    caplog.clear()
    holed = sphere.copy()
    holed.update_faces(np.arange(1, len(sphere.faces)))
    with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.loading"):
        out = prepare_mesh(holed, source="scan.ply", simplify_above=20_000)
    assert len(out.faces) < len(sphere.faces) // 2 and out.is_watertight
    assert "is not closed" not in caplog.text and "capped" in caplog.text


def test_a_simplified_mesh_is_not_merged_by_position(sphere, caplog, monkeypatch):
    # Decimation can leave two vertices at one position where it pinched a surface (a closed
    # mug scan of 772,000 triangles, halved); the decimated mesh is indexed already, and
    # merging them by position would make edges of four faces. Here the "decimated" mesh is
    # two closed boxes touching along an edge, each with its own vertices.
    from affordgrasp.objects import loading

    a = trimesh.creation.box([0.05, 0.05, 0.05])
    a.apply_translation([0.025, 0.025, 0.025])
    b = a.copy()
    b.apply_translation([0.05, 0.05, 0.0])
    two = trimesh.util.concatenate([a, b])
    merged = two.copy()
    merged.merge_vertices()
    assert two.is_watertight and not merged.is_watertight  # what a merge would do

    def decimated(vertices, faces, tolerance, factor, source):
        return np.asarray(two.vertices), np.asarray(two.faces)

    monkeypatch.setattr(loading, "_simplified", decimated)
    with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.loading"):
        out = prepare_mesh(sphere, source="scan.ply", simplify_above=20_000)
    assert len(out.faces) == 24 and out.is_watertight  # kept, not the original sphere
    assert out.volume == pytest.approx(2 * 0.05**3, rel=1e-9)
    assert "is not closed" not in caplog.text
