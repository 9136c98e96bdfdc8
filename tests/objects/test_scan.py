"""Scan-like degradation (objects/scan.py): deterministic, closed, rounded, noisy, labelled."""

import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.objects import load_object
from affordgrasp.objects.scan import ScanSettings, scan_like, split_scan_spec

PLATE = trimesh.creation.box(extents=(0.04, 0.02, 0.004))
FAST = ScanSettings(triangle_m=1.5e-3, noise_m=0.1e-3)


def _labels(mesh):
    return (mesh.face_normals[:, 2] > 0.5).astype(np.int8)  # 1 on the top face


def test_same_seed_same_bytes_other_seed_other_mesh():
    a, la = scan_like(PLATE, _labels(PLATE), seed=1, settings=FAST)
    b, lb = scan_like(PLATE, _labels(PLATE), seed=1, settings=FAST)
    c, _ = scan_like(PLATE, _labels(PLATE), seed=2, settings=FAST)
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes() and la.tobytes() == lb.tobytes()
    assert a.vertices.shape != c.vertices.shape or not np.array_equal(a.vertices, c.vertices)


def test_closed_small_triangles_volume_kept_edges_rounded():
    mesh, _ = scan_like(PLATE, seed=0, settings=FAST)
    assert mesh.is_watertight and mesh.volume > 0
    assert abs(mesh.volume / PLATE.volume - 1) < 0.1  # rounded creases of a 4 mm plate
    assert np.percentile(mesh.edges_unique_length, 95) <= 1.6 * FAST.triangle_m
    # without noise, the box's 90-degree creases are rounded (away from its corners, where
    # three creases meet): no adjacent faces 80 degrees apart remain
    smooth = ScanSettings(triangle_m=1.5e-3, noise_m=0.0, holes=0)
    rounded, _ = scan_like(PLATE, seed=0, settings=smooth)
    mid = rounded.vertices[rounded.face_adjacency_edges].mean(axis=1)
    corners = PLATE.vertices
    far = np.linalg.norm(mid[:, None] - corners[None], axis=2).min(axis=1) > 4e-3
    assert np.degrees(rounded.face_adjacency_angles[far]).max() < 80


def test_noise_has_the_asked_spread():
    flat = ScanSettings(triangle_m=1.5e-3, round_radius_m=0.0, noise_m=0.0, holes=0)
    noisy = ScanSettings(triangle_m=1.5e-3, round_radius_m=0.0, noise_m=0.2e-3, holes=0)
    a, _ = scan_like(PLATE, seed=0, settings=flat)
    b, _ = scan_like(PLATE, seed=0, settings=noisy)
    shift = np.linalg.norm(b.vertices - a.vertices, axis=1)
    assert 0.1e-3 < np.sqrt(np.mean(shift**2)) < 0.3e-3


def test_labels_follow_the_faces():
    mesh, labels = scan_like(PLATE, _labels(PLATE), seed=3, settings=FAST)
    c = mesh.triangles_center
    inner = (np.abs(c[:, 0]) < 0.018) & (np.abs(c[:, 1]) < 0.008)
    assert np.all(labels[inner & (c[:, 2] > 1.5e-3)] == 1)
    assert np.all(labels[inner & (c[:, 2] < -1.5e-3)] == 0)
    assert np.all(labels[np.abs(c[:, 2]) < 1e-3] == 0)


def test_spec_grammar():
    assert split_scan_spec("knife:3") is None
    assert split_scan_spec("knife:3~scan") == ("knife:3", None)
    assert split_scan_spec("knife:3~scan:5") == ("knife:3", 5)
    with pytest.raises(InputError, match="scan-like"):
        split_scan_spec("knife~scan:x")
    with pytest.raises(InputError):
        ScanSettings(noise_m=-1.0)


def test_a_mesh_file_whose_name_holds_the_scan_suffix_is_a_file(tmp_path):
    import trimesh

    path = tmp_path / "mug~scan_v2.ply"
    trimesh.creation.box(extents=(0.05, 0.06, 0.07)).export(path)
    obj = load_object(str(path))
    assert obj.name == "mug~scan_v2.ply" and obj.mass.volume == pytest.approx(2.1e-4)


def test_family_variant_by_name_keeps_parts():
    crisp = load_object("knife:1")
    obj = load_object("knife:1~scan")
    assert obj.name == "knife:1~scan" and obj.category == crisp.category
    assert obj.mesh.is_watertight and len(obj.faces) > 5 * len(crisp.faces)
    assert obj.part_names == crisp.part_names
    assert set(np.unique(obj.face_parts)) == set(np.unique(crisp.face_parts))
    assert abs(obj.mass.volume / crisp.mass.volume - 1) < 0.02
    assert load_object("knife:1~scan") is obj


def test_a_family_variant_with_its_own_degradation_seed_loads():
    # knife:0 degraded with seed 2: a hole whose rim, projected on its plane, crosses itself
    obj = load_object("knife~scan:2")
    crisp = load_object("knife:0")
    assert obj.name == "knife:0~scan:2" and obj.mesh.is_watertight
    assert obj.mesh.is_winding_consistent
    assert abs(obj.mass.volume / crisp.mass.volume - 1) < 0.02


def test_a_mesh_file_named_like_a_variant_is_a_file_even_when_missing(tmp_path):
    with pytest.raises(InputError, match="no file exists at that path"):
        load_object(str(tmp_path / "knife~scan.stl"))
