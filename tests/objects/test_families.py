"""Tests for the procedural object families (conventions: Objects)."""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import re
import subprocess
import sys

import manifold3d
import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.objects.families import (
    ALIASES,
    CATEGORIES,
    FAMILIES,
    FamilyInfo,
    make_family,
)
from affordgrasp.objects.families.geometry import (
    hollow_lathe,
    section,
    silhouette,
    sweep,
    to_trimesh,
)
from affordgrasp.objects.families.parameters import ParameterDraw
from affordgrasp.objects.resolve import list_families

REQUIRED = (
    "hammer",
    "knife",
    "meat_cleaver",
    "axe",
    "screwdriver",
    "spatula",
    "sword",
    "dagger",
    "bottle",
    "wine_glass",
    "tumbler",
    "mug",
    "ice_cream_cone",
)
SEEDS = (0, 1, 2, 3)
CASES = [(name, seed) for name in REQUIRED for seed in SEEDS]

# Longest extent (m) of every instance: the real-size ranges the descriptions promise.
LONGEST_M = {
    "hammer": (0.25, 0.35),
    "knife": (0.20, 0.33),
    "meat_cleaver": (0.27, 0.35),
    "axe": (0.36, 0.70),
    "screwdriver": (0.15, 0.30),
    "spatula": (0.25, 0.35),
    "sword": (0.70, 1.00),
    "dagger": (0.22, 0.35),
    "bottle": (0.20, 0.32),
    "wine_glass": (0.15, 0.22),
    "tumbler": (0.08, 0.15),
    "mug": (0.105, 0.13),  # body plus handle
    "ice_cream_cone": (0.10, 0.15),
}
CONTAINERS = ("bottle", "wine_glass", "tumbler", "mug", "ice_cream_cone")
ELONGATED = ("hammer", "knife", "meat_cleaver", "axe", "screwdriver", "spatula", "sword", "dagger")
# Which way the cutting edge faces, and the least total length of sharp edge (m).
BLADES = {
    "knife": ("-y", 0.06),
    "meat_cleaver": ("-y", 0.12),
    "axe": ("-y", 0.06),
    "dagger": ("+-y", 0.08),
    "sword": ("+-y", 0.40),
    "spatula": ("+x", 0.03),
}
SHARP_DEG = 30.0


@functools.cache
def built(name: str, seed: int) -> trimesh.Trimesh:
    """Each instance is built once per test session; tests must not modify it."""
    return make_family(name, seed)


def digest(mesh: trimesh.Trimesh) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(mesh.vertices).tobytes())
    h.update(np.ascontiguousarray(mesh.faces).tobytes())
    return h.hexdigest()


def sharp_edges(mesh: trimesh.Trimesh):
    """Convex mesh edges whose interior dihedral angle (the solid's opening) is < 30 deg.

    Returns (interior_deg (k,), midpoints (k, 3), outward bisectors (k, 3), lengths (k,)).
    """
    interior = np.degrees(np.pi - mesh.face_adjacency_angles)
    keep = mesh.face_adjacency_convex & (interior < SHARP_DEG)
    ends = mesh.vertices[mesh.face_adjacency_edges[keep]]
    normals = mesh.face_normals[mesh.face_adjacency[keep]]
    bisector = normals.sum(axis=1)
    bisector /= np.linalg.norm(bisector, axis=1, keepdims=True)
    return (
        interior[keep],
        ends.mean(axis=1),
        bisector,
        np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1),
    )


def first_hits(mesh: trimesh.Trimesh, origin, direction) -> np.ndarray:
    """Distances along a ray to every surface crossing, sorted."""
    locations, _, _ = mesh.ray.intersects_location(
        np.array([origin], dtype=float), np.array([direction], dtype=float)
    )
    if len(locations) == 0:
        return np.zeros(0)
    return np.sort(np.linalg.norm(locations - np.asarray(origin, dtype=float), axis=1))


def working_end_start(name: str, mesh: trimesh.Trimesh) -> float:
    """x where a bladed tool's blade (or axe head) begins, from its drawn parameters."""
    params = mesh.metadata["params"]
    x_min, x_max = mesh.bounds[:, 0]
    if name in ("knife", "meat_cleaver"):
        return x_min + params["handle_length_m"]
    if name in ("dagger", "sword"):
        return x_min + 1.6 * params["pommel_radius_m"] + params["grip_length_m"]
    if name == "axe":
        return x_max - params["edge_length_m"] - 0.005
    raise KeyError(name)


def container_axis(name: str, mesh: trimesh.Trimesh) -> np.ndarray:
    """(x, y) of the container's axis; the mug's handle shifts its box centre along +x."""
    if name == "mug":
        return np.array([mesh.bounds[0, 0] + mesh.extents[1] / 2.0, 0.0])
    return np.zeros(2)


# ---------------------------------------------------------------------------- registry


def test_registry_lists_every_required_family_with_a_category():
    names = list_families()
    assert set(REQUIRED) <= set(names)
    assert sorted(FAMILIES) == names
    for name, info in FAMILIES.items():
        assert isinstance(info, FamilyInfo)
        assert info.name == name
        assert info.category in CATEGORIES
        assert re.search(r"\d m\b|\d mm\b", info.description), info.description
    assert FAMILIES["knife"].category == "knife"
    assert FAMILIES["meat_cleaver"].category == "knife"
    assert FAMILIES["hammer"].category == "hammer"
    assert all(FAMILIES[c].category == "container" for c in CONTAINERS)
    with pytest.raises(dataclasses.FrozenInstanceError):
        FAMILIES["knife"].category = "spoon"  # type: ignore[misc]


def test_cleaver_alias_and_name_normalisation():
    assert ALIASES["cleaver"] == "meat_cleaver"
    a = make_family("cleaver", 1)
    b = built("meat_cleaver", 1)
    c = make_family("Meat-Cleaver", 1)
    assert digest(a) == digest(b) == digest(c)
    assert a.metadata["family"] == "meat_cleaver"


@pytest.mark.parametrize("bad", ["spoon", "", "knife:3", 3, None])
def test_unknown_family_is_an_input_error_listing_the_families(bad):
    with pytest.raises(InputError) as info:
        make_family(bad)  # type: ignore[arg-type]
    message = str(info.value)
    assert "available families" in message
    for name in REQUIRED:
        assert name in message


@pytest.mark.parametrize("bad", [-1, 1.5, "3", True, None, np.float64(2.0)])
def test_bad_seed_is_an_input_error(bad):
    with pytest.raises(InputError, match="seed"):
        make_family("knife", bad)  # type: ignore[arg-type]


def test_numpy_integer_seed_is_accepted():
    assert digest(make_family("tumbler", np.int64(2))) == digest(built("tumbler", 2))


# ---------------------------------------------------------------- every family, every seed


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_instance_is_a_single_closed_outward_volume(name, seed):
    mesh = built(name, seed)
    assert mesh.vertices.dtype == np.float64
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.is_volume
    assert mesh.volume > 0.0  # consistent winding + positive volume = outward normals
    assert mesh.body_count == 1
    assert mesh.nondegenerate_faces().all()
    assert mesh.area_faces.min() > 1e-14
    assert 1_000 <= len(mesh.faces) <= 30_000
    # Same check from the solid modeller's side: one genuine 2-manifold.
    solid = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(mesh.vertices),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint64),
        )
    )
    assert solid.status() == manifold3d.Error.NoError
    assert len(solid.decompose()) == 1


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_instance_has_real_size_and_the_documented_frame(name, seed):
    mesh = built(name, seed)
    low, high = LONGEST_M[name]
    assert low <= mesh.extents.max() <= high, mesh.extents
    # Origin at the centre of the axis-aligned bounding box.
    np.testing.assert_allclose(mesh.bounds.mean(axis=0), 0.0, atol=1e-12)
    if name in ELONGATED:
        assert np.argmax(mesh.extents) == 0  # tools lie along x
    if name in CONTAINERS and name != "mug":
        # Upright: the axis of revolution is z, so the x and y extents agree.
        assert mesh.extents[0] == pytest.approx(mesh.extents[1], rel=1e-3)
        assert not np.isclose(mesh.extents[2], mesh.extents[0], rtol=1e-3)


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_metadata_records_the_draw(name, seed):
    mesh = built(name, seed)
    assert mesh.metadata["family"] == name
    assert mesh.metadata["category"] == FAMILIES[name].category
    assert mesh.metadata["seed"] == seed
    assert mesh.metadata["params"]


@pytest.mark.parametrize("name", REQUIRED)
def test_same_seed_same_bytes_and_different_seeds_differ(name):
    fresh = [make_family(name, seed) for seed in SEEDS]
    for seed, mesh in zip(SEEDS, fresh, strict=True):
        assert digest(mesh) == digest(built(name, seed))
    assert len({digest(mesh) for mesh in fresh}) == len(SEEDS)


def test_same_seed_same_bytes_in_another_process():
    cases = [("knife", 1), ("mug", 2), ("axe", 3)]
    code = (
        "import hashlib\n"
        "from affordgrasp.objects.families import make_family\n"
        f"for name, seed in {cases!r}:\n"
        "    m = make_family(name, seed)\n"
        "    h = hashlib.sha256(m.vertices.tobytes())\n"
        "    h.update(m.faces.tobytes())\n"
        "    print(h.hexdigest())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == [digest(built(name, seed)) for name, seed in cases]


# -------------------------------------------------------------------------- blades


@pytest.mark.parametrize(("name", "seed"), [c for c in CASES if c[0] in BLADES])
def test_blades_have_a_real_cutting_edge_and_nothing_else_is_sharp(name, seed):
    mesh = built(name, seed)
    facing, min_length = BLADES[name]
    interior, mid, bisector, length = sharp_edges(mesh)
    assert len(interior) > 0
    # The mesh's edge angle is the drawn one (the tip of a point may be a little blunter).
    drawn = mesh.metadata["params"]["edge_angle_deg"]
    assert 14.0 <= drawn <= 26.0
    assert np.median(interior) == pytest.approx(drawn, abs=0.5)
    assert interior.min() > 0.9 * drawn - 2.0
    if facing == "+x":
        # The spatula's chisel edge: its front, facing +x.
        assert np.all(bisector[:, 0] > 0.2)
        assert np.all(mid[:, 0] > mesh.bounds[1, 0] - 0.005)
        assert length.sum() >= min_length
        return
    # Knives, cleavers, axes, daggers, swords: the edge lies in the blade's mid-plane.
    np.testing.assert_allclose(mid[:, 2], 0.0, atol=1e-5)
    # ... it faces sideways in that plane, never up or down like a flat face would ...
    assert np.all(np.abs(bisector[:, 2]) < 0.1)
    # ... and it runs along the blade, not along the handle or the hilt.
    assert np.all(mid[:, 0] > working_end_start(name, mesh) - 0.001)
    if facing == "-y":
        assert np.all(bisector[:, 1] < 0.0)
        assert length.sum() >= min_length
    else:
        at_point = mid[:, 0] > mesh.bounds[1, 0] - 0.01  # the two edges meet at the point
        assert np.all((np.abs(bisector[:, 1]) > 0.2) | at_point)
        assert length[bisector[:, 1] < -0.2].sum() >= min_length
        assert length[bisector[:, 1] > 0.2].sum() >= min_length


@pytest.mark.parametrize(("name", "seed"), [c for c in CASES if c[0] not in BLADES])
def test_non_blades_have_no_sharp_edges(name, seed):
    interior, *_ = sharp_edges(built(name, seed))
    assert len(interior) == 0


@pytest.mark.parametrize("seed", SEEDS)
def test_knife_blade_is_thin_up_to_the_spine(seed):
    mesh = built("knife", seed)
    handle = mesh.metadata["params"]["handle_length_m"]
    blade = mesh.vertices[mesh.vertices[:, 0] > mesh.bounds[0, 0] + handle + 0.002]
    assert len(blade) > 50
    thickness = blade[:, 2].max() - blade[:, 2].min()
    spine = mesh.metadata["params"]["spine_thickness_m"]
    assert 0.0015 <= spine <= 0.0025
    # The thickest point of the blade is its spine at the heel (distal taper after it).
    assert 0.9 * spine <= thickness <= spine + 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_hammer_striking_face_points_to_minus_y_on_the_head(seed):
    mesh = built("hammer", seed)
    centres = mesh.triangles_center
    face = (mesh.face_normals[:, 1] < -0.999) & (centres[:, 1] < mesh.bounds[0, 1] + 1e-9)
    radius = mesh.metadata["params"]["face_radius_m"]
    # A flat disc (inside the chamfer) at the -y extreme of the head, which is at +x.
    assert mesh.area_faces[face].sum() > 0.9 * np.pi * (0.9 * radius) ** 2
    assert np.all(centres[face, 0] > mesh.bounds[1, 0] - 0.04)


@pytest.mark.parametrize("seed", SEEDS)
def test_screwdriver_tip_is_at_plus_x(seed):
    mesh = built("screwdriver", seed)
    v = mesh.vertices
    tip = v[v[:, 0] > mesh.bounds[1, 0] - 0.003]
    butt = v[v[:, 0] < mesh.bounds[0, 0] + 0.03]
    assert np.abs(tip[:, 1:]).max() < 0.006
    assert np.abs(butt[:, 1:]).max() > 0.011


# ---------------------------------------------------------------------- containers

CAVITY_CHECK_HEIGHT = {
    "bottle": 0.3,
    "wine_glass": 0.78,
    "tumbler": 0.5,
    "mug": 0.5,
    "ice_cream_cone": 0.6,
}


@pytest.mark.parametrize(("name", "seed"), [c for c in CASES if c[0] in CONTAINERS])
def test_containers_are_hollow_open_at_the_top_with_real_walls(name, seed):
    mesh = built(name, seed)
    assert mesh.volume < 0.35 * mesh.convex_hull.volume
    axis = container_axis(name, mesh)
    z_low, z_high = mesh.bounds[:, 2]
    height = z_high - z_low
    # Down the axis from above: the first surface is the cavity's floor, deep inside.
    hits = first_hits(mesh, [axis[0], axis[1], z_high + 0.05], [0.0, 0.0, -1.0])
    assert len(hits) >= 2
    depth = hits[0] - 0.05
    assert depth > 0.4 * height
    # Sideways from the axis (away from the mug's handle): inner wall, then outer wall.
    z = z_low + CAVITY_CHECK_HEIGHT[name] * height
    hits = first_hits(mesh, [axis[0], axis[1], z], [-1.0, 0.0, 0.0])
    assert len(hits) == 2
    wall = hits[1] - hits[0]
    assert 0.0014 <= wall <= 0.0046, wall


@pytest.mark.parametrize("seed", SEEDS)
def test_mug_handle_has_a_hole_a_finger_fits_through(seed):
    mesh = built("mug", seed)
    params = mesh.metadata["params"]
    assert mesh.euler_number == 0  # genus 1: the handle is a loop
    axis_x = container_axis("mug", mesh)[0]
    body_r = mesh.extents[1] / 2.0
    inner_x = mesh.bounds[1, 0] - 2.0 * params["handle_half_thickness_m"]
    z_low = mesh.bounds[0, 2]
    z_mid = z_low + 0.5 * (
        params["handle_bottom_gap_m"] + params["height_m"] - params["handle_top_gap_m"]
    )
    gap = inner_x - (axis_x + body_r)
    assert gap > 0.016
    # Rays along y pass freely through a hole at least 16 mm wide and 30 mm tall.
    x_mid = 0.5 * (axis_x + body_r + inner_x)
    probes = [(x, z_mid) for x in np.linspace(axis_x + body_r + 0.002, inner_x - 0.002, 5)]
    probes += [(x_mid, z_mid + dz) for dz in np.linspace(-0.015, 0.015, 5)]
    for x, z in probes:
        assert len(first_hits(mesh, [x, -1.0, z], [0.0, 1.0, 0.0])) == 0
    through_handle = [mesh.bounds[1, 0] - params["handle_half_thickness_m"], -1.0, z_mid]
    assert len(first_hits(mesh, through_handle, [0.0, 1.0, 0.0])) == 2


# ---------------------------------------------------------------------- primitives


def test_sweep_matches_closed_form_volumes():
    a, b, length = 0.02, 0.01, 0.1
    square = np.array([[-a / 2, -b / 2], [a / 2, -b / 2], [a / 2, b / 2], [-a / 2, b / 2]])

    def rings(last: np.ndarray) -> np.ndarray:
        out = np.zeros((2, 4, 3))
        out[:, :, 0] = [[0.0], [length]]
        out[0, :, 1:] = square
        out[1, :, 1:] = last
        return out

    box = to_trimesh(sweep(rings(square)))
    pyramid = to_trimesh(sweep(rings(np.zeros((4, 2)))))
    ridge = square.copy()
    ridge[:, 1] = 0.0
    wedge = to_trimesh(sweep(rings(ridge)))
    for mesh, expected in (
        (box, a * b * length),
        (pyramid, a * b * length / 3),
        (wedge, a * b * length / 2),
    ):
        assert mesh.is_volume
        assert mesh.volume == pytest.approx(expected, rel=1e-12)
    # The ridge is a true edge: its interior angle is the wedge's opening angle.
    interior, *_ = sharp_edges(wedge)
    assert np.degrees(2 * np.arctan(b / 2 / length)) == pytest.approx(interior.min(), rel=1e-9)


def test_hollow_lathe_matches_a_polygonal_cup():
    radius, height, wall, base, n = 0.04, 0.1, 0.003, 0.008, 64
    outer = section(silhouette(np.array([radius, radius]), np.array([0.0, height])))
    cavity_from = section(silhouette(np.array([radius, radius]), np.array([0.0, height + 0.05])))
    cup = to_trimesh(hollow_lathe(outer, cavity_from, wall, floor_z=base, segments=n))
    polygon = 0.5 * n * np.sin(2 * np.pi / n)  # area of the n-gon inscribed in a unit circle
    expected = polygon * (radius**2 * height - (radius - wall) ** 2 * (height - base))
    assert cup.is_volume
    # Clipper2 offsets work on a 1e-8 m grid, hence the tolerance.
    assert cup.volume == pytest.approx(expected, rel=2e-6)


def test_parameter_draw_seed_zero_is_typical_and_others_stay_in_range():
    typical = ParameterDraw(0)
    assert typical.uniform("a", 1.0, 2.0, 1.25) == 1.25
    assert typical.choice("b", ("x", "y"), "y") == "y"
    assert typical.integer("c", 0, 4, 3) == 3
    assert typical.values == {"a": 1.25, "b": "y", "c": 3}
    for seed in range(1, 20):
        draw = ParameterDraw(seed)
        assert 1.0 <= draw.uniform("a", 1.0, 2.0, 1.25) <= 2.0
        assert draw.choice("b", ("x", "y"), "y") in ("x", "y")
        assert 0 <= draw.integer("c", 0, 4, 3) <= 4
    again = ParameterDraw(7)
    assert again.uniform("a", 1.0, 2.0, 1.25) == ParameterDraw(7).uniform("a", 1.0, 2.0, 1.25)
