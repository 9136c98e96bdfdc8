"""The z-buffer rasteriser (the default depth engine) against the Embree ray casters."""

import numpy as np
import pytest
import trimesh

from affordgrasp.grasp.pregrasp import sample_inputs
from affordgrasp.objects import load_object
from affordgrasp.vision import DepthCamera, DepthRenderer, depth_to_mm


def _agree(fast, ref, *, max_hit_diff):
    """Same hit pixels (but for edge grazes), depths equal up to float32 rounding."""
    assert fast.dtype == np.float32 and fast.shape == ref.shape
    hit, hit_ref = fast > 0, ref > 0
    assert (hit != hit_ref).sum() <= max_hit_diff
    both = hit & hit_ref
    rel = np.abs(fast[both] - ref[both]) / ref[both]
    # Embree intersects in float32, the rasteriser in float64: ~1e-7 relative, more only
    # where a ray grazes its triangle (ill-conditioned in float32)
    assert np.quantile(rel, 0.999) < 1e-6
    assert (rel > 1e-5).mean() < 1e-3
    np.testing.assert_array_equal(depth_to_mm(fast)[~both], depth_to_mm(ref)[~both])


@pytest.mark.parametrize("name", ["mug", "knife:1", "wine_glass", "hammer:2"])
def test_raster_matches_the_one_ray_reference_on_built_in_objects(name):
    p0, _ = sample_inputs(5, 0, 24)
    mesh = load_object(name).mesh
    fast = DepthRenderer(mesh, engine="raster").render(p0)
    ref = DepthRenderer(mesh, engine="embreex").render(p0)
    assert (ref > 0).any(axis=(1, 2)).mean() > 0.5
    _agree(fast, ref, max_hit_diff=2)


def test_raster_is_the_default_and_matches_packets_on_a_small_camera():
    from affordgrasp.rays import packets

    if not packets.available():
        pytest.skip("Embree 4 library of embreex not loadable")
    p0, _ = sample_inputs(6, 0, 24)
    mesh = load_object("bottle").mesh
    camera = DepthCamera(size=30, fov_deg=45.0)
    renderer = DepthRenderer(mesh, camera)
    assert renderer.engine == "raster"
    ref = DepthRenderer(mesh, camera, engine="packets").render(p0)
    _agree(renderer.render(p0), ref, max_hit_diff=1)


def test_back_faces_count_on_a_mesh_that_is_not_closed_and_outward():
    # Turned inside out (negative volume), the mug cannot skip back faces; an open plate
    # (the box without its far face) neither: both must still give the reference pixels.
    p0, _ = sample_inputs(7, 0, 12)
    mug = load_object("mug").mesh.copy()
    mug.invert()
    box = trimesh.creation.box(extents=(0.3, 0.2, 0.05))
    open_box = trimesh.Trimesh(box.vertices, box.faces[box.triangles_center[:, 2] < 0.02])
    for mesh in (mug, open_box):
        ref = DepthRenderer(mesh, engine="embreex").render(p0)
        assert (ref > 0).mean() > 0.02
        _agree(DepthRenderer(mesh, engine="raster").render(p0), ref, max_hit_diff=1)


def test_camera_too_close_is_left_to_the_ray_caster():
    # A camera inside the box (its centre, looking along +z): the rasteriser cannot project
    # vertices behind it and hands the image to the ray caster, which sees the far face.
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.04))
    renderer = DepthRenderer(box, DepthCamera(size=16))
    inside, outside = np.eye(4), np.eye(4)
    outside[2, 3] = -0.1
    depth = renderer.render_poses(np.stack([inside, outside]))
    np.testing.assert_allclose(depth[0], 0.02, atol=1e-6)  # the far face, 2 cm ahead
    np.testing.assert_allclose(depth[1][depth[1] > 0], 0.08, atol=1e-6)
    assert (depth[1] > 0).all()
