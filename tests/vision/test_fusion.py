"""Depth images fused into a surface (vision/fusion.py), against known geometry."""

import numpy as np
import pytest
import trimesh

pytest.importorskip("skimage")

from affordgrasp.errors import InputError  # noqa: E402
from affordgrasp.grasp.pregrasp import sample_inputs  # noqa: E402
from affordgrasp.vision.depth import DepthRenderer  # noqa: E402
from affordgrasp.vision.fusion import (  # noqa: E402
    field_surface,
    free_space_field,
    fuse_views,
    fused_object,
    seen_points,
)


def views_of(mesh, n=64, seed=0, offset_range=0.25):
    """Depth images and camera poses of a mesh from plan-like pregrasps."""
    p0, _ = sample_inputs(seed, 0, n)
    p0[:, 3:5] *= offset_range
    renderer = DepthRenderer(mesh)
    return renderer.render(p0), renderer.poses(p0), renderer.camera


def surface_distances(a, b, count=4000):
    """Distances from points sampled on a to the surface b, and from b's to a, m."""
    pa = trimesh.sample.sample_surface(a, count, seed=1)[0]
    pb = trimesh.sample.sample_surface(b, count, seed=2)[0]
    return (
        np.abs(trimesh.proximity.closest_point(b, pa)[1]),
        np.abs(trimesh.proximity.closest_point(a, pb)[1]),
    )


def test_a_box_seen_from_plans_pregrasps_is_recovered_within_a_voxel():
    box = trimesh.creation.box([0.12, 0.04, 0.03])
    depth, poses, camera = views_of(box)
    mesh = fuse_views(depth, poses, camera)
    assert mesh.is_watertight and mesh.volume > 0
    fused_to_true, true_to_fused = surface_distances(mesh, box)
    assert np.median(fused_to_true) < 1.2e-3 and np.percentile(fused_to_true, 95) < 2.5e-3
    assert np.median(true_to_fused) < 1.2e-3 and np.percentile(true_to_fused, 95) < 2.5e-3
    assert mesh.volume == pytest.approx(box.volume, rel=0.2)
    np.testing.assert_allclose(mesh.bounds, box.bounds, atol=2.5e-3)


def test_a_sphere_is_recovered_at_its_radius():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.03)
    depth, poses, camera = views_of(sphere, seed=1)
    mesh = fuse_views(depth, poses, camera)
    radius = np.linalg.norm(mesh.vertices, axis=1)
    assert np.median(np.abs(radius - 0.03)) < 1e-3
    assert np.percentile(np.abs(radius - 0.03), 95) < 2e-3


def test_a_thin_plate_stays_one_piece_and_only_with_the_votes_and_the_dilation():
    # 2 mm thick: a view that sees past one voxel of it by rounding must not cut it
    plate = trimesh.creation.box([0.2, 0.05, 0.002])
    depth, poses, camera = views_of(plate, seed=2)
    mesh = fuse_views(depth, poses, camera)
    np.testing.assert_allclose(mesh.extents, plate.extents, atol=3e-3)
    assert len(mesh.split(only_watertight=False)) == 1
    # one vote and no dilation, where the filter is the only rule: the plate loses most of
    # its solid (what the votes and the filter fix)
    alone = {"subpixel": False, "keep_seen": False}
    solid = (free_space_field(depth, poses, camera, **alone).values < 0).sum()
    bare = free_space_field(depth, poses, camera, votes=1, dilate_px=0, **alone)
    assert (bare.values < 0).sum() < 0.5 * solid


def signed_distances(fused, true, count=4000):
    """Signed distances of points sampled on the fused surface to the true one, m (+ outside)."""
    points = trimesh.sample.sample_surface(fused, count, seed=3)[0]
    distance = np.abs(trimesh.proximity.closest_point(true, points)[1])
    return np.where(true.contains(points), -distance, distance)


def test_the_four_pixels_around_a_projection_keep_the_surface_in_place():
    # The 3 x 3 minimum filter alone puts a face seen at an angle a fraction of a pixel's
    # depth step nearer the camera: a 2 mm plate fused 3.7 mm thick. Reading the four
    # pixels around the projection where all returned takes most of it off.
    plate = trimesh.creation.box([0.2, 0.05, 0.002])
    depth, poses, camera = views_of(plate, seed=2)
    old = fuse_views(depth, poses, camera, subpixel=False, keep_seen=False).extents[2]
    new = fuse_views(depth, poses, camera).extents[2]
    assert old > 3.3e-3  # what the filter alone does
    assert new < old - 0.6e-3 and new < 3.0e-3
    box = trimesh.creation.box([0.12, 0.05, 0.03])
    depth, poses, camera = views_of(box, seed=6)
    placed = signed_distances(fuse_views(depth, poses, camera), box)
    assert abs(np.median(placed)) < 0.2e-3 and np.percentile(np.abs(placed), 95) < 0.5e-3


def test_a_blade_thinner_than_a_voxel_is_kept_whole_by_its_seen_voxels():
    # 1 mm thick on 2 mm voxels: without the filter's outward bias, no voxel centre need lie
    # inside it; the voxels its returns fall in keep it.
    blade = trimesh.creation.box([0.2, 0.05, 0.001])
    depth, poses, camera = views_of(blade, seed=7)
    kept = fuse_views(depth, poses, camera, voxel_m=2e-3)
    np.testing.assert_allclose(kept.extents[:2], blade.extents[:2], atol=4e-3)
    assert len(kept.split(only_watertight=False)) == 1
    field = free_space_field(depth, poses, camera, voxel_m=2e-3, keep_seen=False)
    assert field.seen is None
    with pytest.raises(InputError, match="no solid"):  # nothing left of the blade
        field_surface(field)


def test_moving_the_views_moves_the_surface():
    box = trimesh.creation.box([0.1, 0.05, 0.04])
    depth, poses, camera = views_of(box, n=24, seed=3)
    shift = np.array([0.5, -2.0, 0.25])
    moved = poses.copy()
    moved[:, :3, 3] += shift
    a = fuse_views(depth, poses, camera)
    b = fuse_views(depth, moved, camera)
    assert len(a.faces) == len(b.faces)
    np.testing.assert_allclose(b.bounds, a.bounds + shift, atol=1e-9)
    assert b.volume == pytest.approx(a.volume, rel=1e-9)


def test_the_field_keeps_solid_inside_and_frees_space_outside():
    box = trimesh.creation.box([0.08, 0.06, 0.04])
    depth, poses, camera = views_of(box, n=64, seed=4)
    field = free_space_field(depth, poses, camera, voxel_m=2e-3)
    centres = field.origin + field.voxel_m * np.stack(
        np.meshgrid(*[np.arange(n) for n in field.values.shape], indexing="ij"), axis=-1
    )
    inside = np.all(np.abs(centres) < box.extents / 2 - 3e-3, axis=-1)
    outside = np.any(np.abs(centres) > box.extents / 2 + 4e-3, axis=-1)
    assert (field.values[inside] < 0).all()
    assert (field.values[outside] > 0).mean() > 0.99
    # the grid covers what was seen, and every return lies on the box
    points = seen_points(depth, poses, camera)
    assert np.all(np.abs(points) <= box.extents / 2 + 1e-6)


def test_a_fused_object_is_graspable_and_kept_out_of_the_disk_cache():
    from affordgrasp.objects.prepared import TRANSIENT_SOURCE

    box = trimesh.creation.box([0.12, 0.04, 0.03])
    depth, poses, camera = views_of(box, n=32)
    obj = fused_object(depth, poses, camera, name="box seen")
    assert obj.name == "box seen" and obj.source == TRANSIENT_SOURCE
    assert obj.mass.volume == pytest.approx(box.volume, rel=0.2)


def test_bad_views_are_refused_with_what_to_do():
    box = trimesh.creation.box([0.12, 0.04, 0.03])
    depth, poses, camera = views_of(box, n=4)
    with pytest.raises(InputError, match="one camera pose"):
        free_space_field(depth, poses[:3], camera)
    with pytest.raises(InputError, match="shape"):
        free_space_field(depth[:, :10], poses, camera)
    with pytest.raises(InputError, match="nothing to fuse"):
        free_space_field(np.zeros_like(depth), poses, camera)
    with pytest.raises(InputError, match="finite"):
        free_space_field(np.where(depth > 0, np.nan, 0.0), poses, camera)
    with pytest.raises(InputError, match="votes"):
        free_space_field(depth, poses, camera, votes=0)
    with pytest.raises(InputError, match="voxel_m"):
        free_space_field(depth, poses, camera, voxel_m=-1.0)


def test_returns_lost_next_to_the_surface_are_unknown_not_empty_with_unknown_px():
    from scipy.ndimage import binary_erosion

    box = trimesh.creation.box([0.1, 0.05, 0.04])
    depth, poses, camera = views_of(box, n=48, seed=5)
    # a sensor loses the returns seen at grazing angles: here a 4-pixel band inside every
    # silhouette
    kept = binary_erosion(depth > 0, structure=np.ones((1, 9, 9)))
    lossy = np.where(kept, depth, 0.0)
    as_empty = fuse_views(lossy, poses, camera)
    as_unknown = fuse_views(lossy, poses, camera, unknown_px=5)
    assert as_empty.volume < 0.75 * box.volume  # the band carved into the box
    assert as_unknown.volume == pytest.approx(box.volume, rel=0.05)
    np.testing.assert_allclose(as_unknown.bounds, box.bounds, atol=2.5e-3)
    with pytest.raises(InputError, match="unknown_px"):
        free_space_field(depth, poses, camera, unknown_px=-1)


def test_a_fused_surface_is_never_simplified(monkeypatch):
    import affordgrasp.objects as objects
    from affordgrasp.objects.simplify import LARGE_MESH_FACES

    # a scan's 0.1 mm simplification cannot hold on 1 mm voxels, and once broke a closed
    # fused surface (213,000 triangles) whose repair then failed after 10 s
    made = objects.object_from_mesh
    options = []

    def recorded(mesh, name, **kwargs):
        options.append(kwargs)
        return made(mesh, name, **kwargs)

    monkeypatch.setattr(objects, "object_from_mesh", recorded)
    box = trimesh.creation.box([0.12, 0.04, 0.03])
    depth, poses, camera = views_of(box, n=16)
    fused_object(depth, poses, camera, name="box")
    assert options == [{"simplify_above": None}]
    # what that means: a mesh above the threshold keeps its triangles
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.04)  # 5120 triangles
    kept = made(sphere, "sphere", simplify_above=None)
    assert len(kept.faces) == 5120 and LARGE_MESH_FACES > 5120
    simplified = made(sphere, "sphere", simplify_above=1000)
    assert len(simplified.faces) < 5120


def test_a_surface_that_is_not_closed_is_fused_again_smoother_then_refused(monkeypatch):
    import affordgrasp.objects as objects
    from affordgrasp.errors import MeshError
    from affordgrasp.vision import fusion

    box = trimesh.creation.box([0.12, 0.04, 0.03])
    depth, poses, camera = views_of(box, n=16)
    made = objects.object_from_mesh
    tried = []

    def fails_first(mesh, name, **options):
        tried.append(len(mesh.faces))
        if len(tried) == 1:
            raise MeshError("not a closed volume")
        return made(mesh, name, **options)

    monkeypatch.setattr(objects, "object_from_mesh", fails_first)
    obj = fused_object(depth, poses, camera, name="box")
    assert len(tried) == 2 and obj.name == "box"

    def always_fails(mesh, name, **options):
        raise MeshError("not a closed volume")

    calls = []
    surface = fusion.field_surface

    def recorded(field, smooth_voxels):
        calls.append((field.seen is not None, smooth_voxels))
        return surface(field, smooth_voxels=smooth_voxels)

    monkeypatch.setattr(objects, "object_from_mesh", always_fails)
    monkeypatch.setattr(fusion, "field_surface", recorded)
    with pytest.raises(InputError, match="fused into no closed surface"):
        fused_object(depth, poses, camera, name="box")
    # without the seen voxels (which no smoothing parts), then smoother fields
    smooths = (fusion.SMOOTH_VOXELS, *fusion.RETRY_SMOOTH_VOXELS)
    assert calls == [(True, smooths[0])] + [(False, s) for s in smooths]
    calls.clear()
    with pytest.raises(InputError, match="fused into no closed surface"):
        fused_object(depth, poses, camera, name="box", keep_seen=False)
    assert calls == [(False, s) for s in smooths]
