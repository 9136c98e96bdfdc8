"""The depth engines' own parts: the rasteriser's fallback and its view rotations (their
hits on the same rays as every other backend: tests/rays/test_backends.py)."""

import numpy as np
import pytest
import trimesh

from affordgrasp.rays import embree_available
from affordgrasp.vision.engines import EmbreeEngine, RasterEngine, view_rotations

pytestmark = pytest.mark.skipif(not embree_available(), reason="embreex not installed")

CENTRE = np.array([0.3, -0.1, 0.05])
EXTENTS = np.array([0.2, 0.1, 0.06])


def box_mesh() -> trimesh.Trimesh:
    return trimesh.creation.box(
        EXTENTS, transform=trimesh.transformations.translation_matrix(CENTRE)
    )


def test_raster_leaves_rays_from_inside_to_its_ray_engine():
    mesh = box_mesh()
    tri = np.asarray(mesh.triangles)
    engine = RasterEngine(
        mesh.vertices, mesh.faces, CENTRE, cull=True, near=1e-3, fallback=lambda: None
    )
    with pytest.raises(AttributeError):  # the (empty) fallback is asked for the inside ray
        engine.cast(CENTRE[None], np.array([[1.0, 0.0, 0.0]]))
    engine = RasterEngine(
        mesh.vertices,
        mesh.faces,
        CENTRE,
        cull=True,
        near=1e-3,
        fallback=lambda: EmbreeEngine(tri, CENTRE),
    )
    hits = engine.cast(CENTRE[None], np.array([[1.0, 0.0, 0.0]]))
    assert hits.distance[0] == pytest.approx(EXTENTS[0] / 2, abs=1e-6)
    np.testing.assert_allclose(hits.normal[0], [1.0, 0.0, 0.0], atol=1e-12)


def test_view_rotations_are_right_handed_with_the_axis_as_z():
    rng = np.random.default_rng(2)
    axes = rng.normal(size=(50, 3))
    axes[:3] = np.eye(3)
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    rot = view_rotations(axes)
    np.testing.assert_allclose(rot[:, :, 2], axes, atol=1e-15)
    np.testing.assert_allclose(
        rot.transpose(0, 2, 1) @ rot, np.broadcast_to(np.eye(3), rot.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-12)
