"""Surface samples (objects/surface.py): spacing, and memory bounded by construction."""

import logging
import tracemalloc

import numpy as np
import pytest
import trimesh

from affordgrasp.objects import GraspObject, mass_properties, mesh_hash
from affordgrasp.objects.surface import DEFAULT_SPACING, sample_count_bound, sample_surface


def test_count_bound_holds_and_default_spacing_is_kept_on_tools():
    mesh = trimesh.creation.box((0.05, 0.03, 0.2))
    s = sample_surface(mesh)
    assert s.spacing == DEFAULT_SPACING
    tri = np.asarray(mesh.triangles)
    edges = np.asarray(mesh.edges_unique)
    edge_len = np.linalg.norm(mesh.vertices[edges[:, 1]] - mesh.vertices[edges[:, 0]], axis=1)
    assert len(s.points) <= sample_count_bound(tri, edge_len, len(mesh.vertices), s.spacing)
    # no two neighbours on a face farther apart than the spacing (checked on the big face)
    on_face = s.points[np.isclose(s.points[:, 0], 0.025)]
    grid = np.unique(np.round(on_face[:, 2] / 1e-4))
    assert np.max(np.diff(np.sort(grid))) * 1e-4 <= DEFAULT_SPACING + 1e-9


@pytest.mark.parametrize("size_m", [100.0, 1000.0, 1e6])
def test_huge_meshes_are_sampled_in_bounded_memory(size_m, caplog):
    # A 100 mm cube read as metres needed 228 GiB, a 1 km cube 22 TiB: now the sample count
    # is capped before any array is built, and a warning says the spacing grew.
    mesh = trimesh.creation.box((size_m,) * 3)
    tracemalloc.start()
    try:
        with caplog.at_level(logging.WARNING, logger="affordgrasp.objects.surface"):
            s = sample_surface(mesh, max_points=50_000)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(s.points) <= 50_000
    assert s.spacing > DEFAULT_SPACING
    assert peak < 200e6
    assert "spacing raised" in caplog.text


def test_a_kilometre_cube_runs_through_the_whole_pipeline():
    from affordgrasp.pipeline import evaluate_samples

    mesh = trimesh.creation.box((1000.0,) * 3)
    obj = GraspObject("cube", "mesh", mesh, mass_properties(mesh), mesh_hash(mesh), "test")
    table = evaluate_samples(obj, 4, seed=0).table
    assert table.num_rows == 4


@pytest.mark.parametrize("max_points", [3000, 1000], ids=["cap above the vertices", "below"])
def test_spacing_stays_finite_when_the_mesh_alone_fills_the_cap(max_points, caplog):
    """More triangles than the cap allows samples: the spacing stops at the longest side.

    It used to be raised by 1.25x up to 400 times (8e38 mm) or set to inf.
    """
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=0.05)  # 2562 vertices
    longest = float(mesh.edges_unique_length.max())
    with caplog.at_level(logging.WARNING):
        sample = sample_surface(mesh, max_points=max_points)
    assert np.isfinite(sample.spacing)
    assert DEFAULT_SPACING < sample.spacing <= longest * (1 + 1e-12)
    assert "inf mm" not in caplog.text and "e+" not in caplog.text
    # Every vertex is kept, and at the longest side nothing is added inside the triangles.
    assert len(sample.points) >= len(mesh.vertices)
    if max_points < len(mesh.vertices):
        assert sample.spacing == pytest.approx(longest)
        assert len(sample.points) == len(mesh.vertices)
