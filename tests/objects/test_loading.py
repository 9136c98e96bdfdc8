"""Tests for mesh loading, repair, orientation and scaling."""

from __future__ import annotations

import logging
import re

import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError, MeshError
from affordgrasp.objects import load_mesh, prepare_mesh


def box(extents=(0.1, 0.2, 0.3), offset=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(offset)
    return mesh


def assert_solid(mesh: trimesh.Trimesh, volume: float) -> None:
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(volume, rel=1e-6)  # STL is float32
    assert mesh.vertices.dtype == np.float64 and mesh.faces.dtype == np.int64


@pytest.mark.parametrize(
    ("suffix", "kwargs"),
    [
        (".obj", {}),
        (".stl", {}),
        (".stl", {"file_type": "stl_ascii"}),
        (".ply", {}),
        (".ply", {"encoding": "ascii"}),
        (".glb", {}),
        (".off", {}),
    ],
)
def test_round_trip_through_each_format(tmp_path, suffix, kwargs):
    original = box()
    path = tmp_path / f"box{suffix}"
    original.export(path, **kwargs)
    mesh = load_mesh(path)
    assert_solid(mesh, 0.1 * 0.2 * 0.3)
    np.testing.assert_allclose(mesh.bounds, original.bounds, atol=1e-6)
    assert len(mesh.vertices) == 8  # STL's unshared corners were merged


def test_upper_case_extension(tmp_path):
    path = tmp_path / "BOX.STL"
    box().export(path, file_type="stl")
    assert_solid(load_mesh(path), 0.006)


def test_glb_scene_geometry_is_placed_by_its_transforms(tmp_path):
    scene = trimesh.Scene()
    part = box((0.1, 0.1, 0.1))
    scene.add_geometry(part, node_name="a", geom_name="cube")
    # The same geometry instanced a second time, moved by a node transform.
    scene.add_geometry(
        part,
        node_name="b",
        geom_name="cube",
        transform=trimesh.transformations.translation_matrix([1, 0, 0]),
    )
    path = tmp_path / "scene.glb"
    scene.export(path)
    mesh = load_mesh(path)
    assert_solid(mesh, 2e-3)
    np.testing.assert_allclose(mesh.bounds, [[-0.05, -0.05, -0.05], [1.05, 0.05, 0.05]], atol=1e-6)


def test_gltf_with_external_buffers(tmp_path):
    files = trimesh.Scene([box()]).export(file_type="gltf")
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    assert_solid(load_mesh(tmp_path / "model.gltf"), 0.006)


def test_unknown_extension_and_missing_file(tmp_path):
    path = tmp_path / "box.xyz"
    path.write_text("1 2 3\n")
    with pytest.raises(MeshError, match=r"unsupported mesh format '\.xyz'.*\.obj.*\.off"):
        load_mesh(path)
    with pytest.raises(MeshError, match="does not exist"):
        load_mesh(tmp_path / "missing.obj")
    with pytest.raises(MeshError, match="not a file"):
        load_mesh(tmp_path)


def test_corrupt_file_and_point_cloud_are_refused(tmp_path):
    path = tmp_path / "bad.glb"
    path.write_bytes(b"not a glb at all")
    with pytest.raises(MeshError, match="cannot read 'bad.glb' as GLB"):
        load_mesh(path)
    cloud = tmp_path / "cloud.ply"
    trimesh.PointCloud(np.random.default_rng(0).random((20, 3))).export(cloud)
    with pytest.raises(MeshError, match="has no faces"):
        load_mesh(cloud)


def test_off_file_with_quads_loads(tmp_path):
    path = tmp_path / "cube.off"
    path.write_text(
        "OFF 8 6 0 # counts on the header line\n"
        "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
        "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n"
    )
    assert_solid(load_mesh(path), 1.0)


def test_empty_nan_and_degenerate_meshes_are_refused():
    with pytest.raises(MeshError, match="empty"):
        prepare_mesh(trimesh.Trimesh())
    bad = box()
    vertices = bad.vertices.copy()
    vertices[3, 1] = np.nan
    with pytest.raises(MeshError, match="NaN or infinite.*vertex 3"):
        prepare_mesh(trimesh.Trimesh(vertices, bad.faces, process=False))
    vertices[3, 1] = np.inf
    with pytest.raises(MeshError, match="NaN or infinite"):
        prepare_mesh(trimesh.Trimesh(vertices, bad.faces, process=False))
    line = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 2], [0, 2, 1]], process=False)
    with pytest.raises(MeshError, match="degenerate"):
        prepare_mesh(line)


def test_prepare_does_not_modify_its_input_and_merges_vertices():
    original = box()
    soup = trimesh.Trimesh(
        original.triangles.reshape(-1, 3), np.arange(36).reshape(-1, 3), process=False
    )
    before = soup.vertices.copy()
    mesh = prepare_mesh(soup)
    np.testing.assert_array_equal(soup.vertices, before)
    assert len(mesh.vertices) == 8
    assert_solid(mesh, 0.006)


def test_inside_out_mesh_is_turned_outward():
    mesh = box()
    mesh.invert()
    assert mesh.volume < 0
    assert_solid(prepare_mesh(mesh), 0.006)


def test_cube_missing_a_face_is_repaired(caplog):
    mesh = box()
    mesh.update_faces(np.arange(10))
    mesh.remove_unreferenced_vertices()
    assert not mesh.is_watertight
    with caplog.at_level(logging.WARNING):
        repaired = prepare_mesh(mesh, source="open.obj")
    assert_solid(repaired, 0.006)
    assert "open.obj was repaired: capped 1 hole (4 boundary edges" in caplog.text


def test_big_non_convex_hole_is_capped_in_its_plane():
    # An L-shaped prism without its top: the cap must be the L, not a fan across the notch.
    outline = np.array([[2, 1], [1, 1], [1, 2], [0, 2], [0, 0], [2, 0]], dtype=float)
    bottom = np.column_stack([outline, np.zeros(6)])
    top = np.column_stack([outline, np.ones(6)])
    vertices = np.vstack([bottom, top])
    faces = [[1, 3, 2], [1, 4, 3], [1, 5, 4], [1, 0, 5]]  # bottom, facing down
    for i in range(6):
        j = (i + 1) % 6
        faces += [[i, j, j + 6], [i, j + 6, i + 6]]
    open_mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert not open_mesh.is_watertight
    assert open_mesh.area == pytest.approx(3.0 + 8.0)
    repaired = prepare_mesh(open_mesh)
    assert_solid(repaired, 3.0)
    assert repaired.area == pytest.approx(3.0 + 3.0 + 8.0)


def test_flat_patch_cannot_be_a_solid():
    disc = trimesh.creation.cylinder(radius=0.05, height=0.01, sections=24)
    disc.update_faces(disc.face_normals[:, 2] > 0.99)  # only the top cap
    disc.remove_unreferenced_vertices()
    with pytest.raises(MeshError, match="encloses no volume.*close it in a mesh editor"):
        prepare_mesh(disc, source="disc.stl")
    triangle = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    with pytest.raises(MeshError, match="no volume"):
        prepare_mesh(triangle)


def test_non_manifold_surface_that_cannot_be_closed():
    # Three fins sharing one edge: each edge is used by 1 or 3 faces, nothing encloses space.
    vertices = [[0, 0, 0], [0, 0, 1], [1, 0, 0], [-1, 1, 0], [-1, -1, 0]]
    fins = trimesh.Trimesh(vertices, [[0, 1, 2], [0, 1, 3], [0, 1, 4]], process=False)
    with pytest.raises(MeshError, match="(not a closed volume|no volume)"):
        prepare_mesh(fins)


def test_overlapping_parts_are_unioned_and_disjoint_parts_kept():
    overlapping = trimesh.util.concatenate([box((1, 1, 1)), box((1, 1, 1), (0.5, 0, 0))])
    assert_solid(prepare_mesh(overlapping), 1.5)
    disjoint = trimesh.util.concatenate([box((1, 1, 1)), box((1, 1, 1), (3, 0, 0))])
    kept = prepare_mesh(disjoint)
    assert_solid(kept, 2.0)
    np.testing.assert_array_equal(kept.faces, disjoint.faces)
    touching = trimesh.util.concatenate([box((1, 1, 1)), box((1, 1, 1), (1, 1, 0))])
    assert_solid(prepare_mesh(touching), 2.0)


def test_cavity_is_kept_and_inverted_part_is_flipped():
    inner = box((1, 1, 1))
    inner.invert()
    hollow = trimesh.util.concatenate([box((2, 2, 2)), inner])
    assert_solid(prepare_mesh(hollow), 7.0)
    flipped = box((1, 1, 1), (3, 0, 0))
    flipped.invert()
    assert_solid(prepare_mesh(trimesh.util.concatenate([box((1, 1, 1)), flipped])), 2.0)


def test_size_m_and_units():
    mesh = box((10.0, 20.0, 40.0), (5.0, 0.0, 0.0))
    sized = prepare_mesh(mesh, size_m=0.2)
    assert sized.extents.max() == pytest.approx(0.2)
    np.testing.assert_allclose(sized.extents, [0.05, 0.1, 0.2])
    # Uniform scaling about the origin of the mesh frame.
    np.testing.assert_allclose(sized.bounds.mean(axis=0), [0.025, 0.0, 0.0])
    in_mm = prepare_mesh(mesh, units="mm")
    np.testing.assert_allclose(in_mm.extents, [0.01, 0.02, 0.04])
    np.testing.assert_allclose(prepare_mesh(mesh, units="in").extents, [0.254, 0.508, 1.016])
    np.testing.assert_allclose(prepare_mesh(mesh, units="CM").extents, [0.1, 0.2, 0.4])


def test_scaling_options_are_validated(tmp_path):
    mesh = box()
    with pytest.raises(InputError, match="pass one"):
        prepare_mesh(mesh, size_m=0.1, units="mm")
    with pytest.raises(InputError, match="unknown length unit 'furlong'.*mm"):
        prepare_mesh(mesh, units="furlong")
    for bad in (0.0, -1.0, float("nan"), float("inf"), "big"):
        with pytest.raises(InputError, match="size_m must be a positive number"):
            prepare_mesh(mesh, size_m=bad)
    # Options are checked before the file is read.
    with pytest.raises(InputError, match="pass one"):
        load_mesh(tmp_path / "missing.obj", size_m=1.0, units="m")


def test_implausible_size_warns_but_keeps_the_mesh(caplog):
    with caplog.at_level(logging.WARNING):
        mesh = prepare_mesh(box((120.0, 30.0, 20.0)), source="mug.stl")
    assert mesh.extents.max() == pytest.approx(120.0)
    assert "did you mean --units mm" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        prepare_mesh(box((0.001, 0.001, 0.002)))
    assert "--size-m" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        prepare_mesh(box((120.0, 30.0, 20.0)), units="mm")
        prepare_mesh(box())
        prepare_mesh(box((120.0, 30.0, 20.0)), size_m=0.0001)
    assert caplog.text == ""
    with caplog.at_level(logging.WARNING):
        prepare_mesh(box((0.12, 0.03, 0.02)), units="mm")  # the file was in metres
    assert "0.00012 m long with units 'mm'" in caplog.text


def test_thin_solid_is_kept():
    # A 0.5 mm thick blade is a real solid, not a flat patch.
    blade = box((0.2, 0.03, 0.0005))
    assert_solid(prepare_mesh(blade), 0.2 * 0.03 * 0.0005)


@pytest.mark.parametrize(
    "size, options, expected",
    [
        ((100.0, 100.0, 100.0), {}, r"100 m long if its coordinates are metres.*--units mm"),
        ((1000.0, 1000.0, 1000.0), {}, r"1e\+03 m long.*--units mm"),
        ((4.9, 4.9, 4.9), {}, r"4.9 m long.*--units (cm|in)"),
        ((0.002, 0.002, 0.002), {}, r"0.002 m long.*units= the file's unit"),
        ((100.0, 10.0, 10.0), {"units": "m"}, r"100 m long with units='m'.*--units mm"),
        ((0.12, 0.03, 0.02), {"units": "mm"}, r"0.00012 m long with units='mm'.*--units m\b"),
        ((1.0, 1.0, 1.0), {"size_m": 8.0}, r"size_m 8 makes cube.stl 8 m long"),
    ],
)
def test_mesh_file_of_implausible_size_is_refused_with_the_fix(tmp_path, size, options, expected):
    path = tmp_path / "cube.stl"
    box(size).export(path)
    with pytest.raises(MeshError, match=expected):
        load_mesh(path, **options)


def test_mesh_file_of_plausible_size_loads(tmp_path):
    path = tmp_path / "cube.stl"
    box((100.0, 50.0, 20.0)).export(path)
    assert load_mesh(path, units="mm").extents.max() == pytest.approx(0.1)
    assert load_mesh(path, size_m=0.25).extents.max() == pytest.approx(0.25)
    box((0.1, 0.05, 0.02)).export(path)
    assert load_mesh(path).extents.max() == pytest.approx(0.1)


def _cube(size: float = 0.05) -> trimesh.Trimesh:
    return trimesh.creation.box((size, size, size))


def _fin_on(cube: trimesh.Trimesh) -> trimesh.Trimesh:
    """The cube with one triangle hanging off an edge (the edge then has three faces)."""
    a, b = cube.edges_unique[0]
    tip = cube.vertices[[a, b]].mean(axis=0) * 3.0
    return trimesh.Trimesh(
        np.vstack([cube.vertices, tip]),
        np.vstack([cube.faces, [[a, b, len(cube.vertices)]]]),
        process=False,
    )


@pytest.mark.parametrize(
    "make, said",
    [
        (_fin_on, r"dropped 1 non-manifold fin \(1 triangle of open surface"),
        (
            lambda c: trimesh.Trimesh(c.vertices, np.vstack([c.faces[:1, ::-1], c.faces[1:]])),
            "re-wound 1 face that was wound against the rest",
        ),
        (lambda c: trimesh.Trimesh(c.vertices, c.faces[:, ::-1]), "turned it outside out"),
        (lambda c: trimesh.Trimesh(c.vertices, np.vstack([c.faces, c.faces[:3]])), "3 duplicate"),
        (
            lambda c: trimesh.util.concatenate([c, c.copy().apply_translation((0.02, 0, 0))]),
            "merged 2 overlapping bodies into one solid",
        ),
    ],
    ids=["fin", "flipped face", "inside out", "duplicate faces", "overlap"],
)
def test_repair_warning_says_what_was_done(make, said, caplog):
    cube = _cube()
    with caplog.at_level(logging.WARNING):
        mesh = prepare_mesh(make(cube), source="part.obj")
    assert mesh.is_watertight
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1, lines
    assert lines[0].startswith("part.obj was repaired: ")
    assert re.search(said, lines[0]), lines[0]
    assert "hole" not in lines[0]  # nothing was capped: the old message said "closed 1 hole"


def test_clean_mesh_gets_no_repair_warning(caplog):
    with caplog.at_level(logging.WARNING):
        prepare_mesh(_cube(), source="part.obj")
    assert caplog.text == ""


def test_a_floating_speck_is_kept_and_named(caplog):
    # A scan's floating noise: kept (the mesh is what was given), but it widens the extent
    # that places the pregrasps, so the load says so with the sizes.
    body = box((0.1, 0.02, 0.02))
    speck = trimesh.creation.icosphere(subdivisions=1, radius=0.001)
    speck.apply_translation([0.1, 0.0, 0.0])  # 49 mm beyond the body's end
    with caplog.at_level(logging.WARNING):
        out = prepare_mesh(trimesh.util.concatenate([body, speck]), source="scan.obj")
    assert out.volume == pytest.approx(body.volume + speck.volume, rel=1e-9)
    message = (
        "scan.obj: 1 of its 2 disjoint bodies holds under 0.1 % of the largest one's volume "
        "(floating specks of a scan?); kept, they widen the object's extent from 100 mm to "
        "151 mm"
    )
    assert message in caplog.text, caplog.text
    # two real parts: no speck
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        prepare_mesh(
            trimesh.util.concatenate([body, box((0.02, 0.02, 0.02), (0.1, 0, 0))]), source="two"
        )
    assert "speck" not in caplog.text


def _cut_at_the_base(name: str, height_m: float) -> trimesh.Trimesh:
    """A built-in object with the faces of its lowest ``height_m`` removed: a scan whose
    base was never seen (the rim is the jagged edge of the triangles kept)."""
    from affordgrasp.objects import load_object

    obj = load_object(name)
    mesh = trimesh.Trimesh(obj.vertices, obj.faces, process=False)
    keep = mesh.triangles_center[:, 2] > mesh.bounds[0, 2] + height_m
    cut = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    cut.remove_unreferenced_vertices()
    assert not cut.is_watertight
    return cut


@pytest.mark.parametrize(
    ("name", "height_m"),
    [
        ("wine_glass:0", 0.002),  # a rim triangle with two rim edges: a fan from the centroid
        ("hammer:0", 0.004),
        ("spatula:0", 0.002),
    ],
)
def test_a_base_cut_open_is_capped(name, height_m, caplog):
    from affordgrasp.objects import load_object

    whole = load_object(name)
    with caplog.at_level(logging.WARNING):
        repaired = prepare_mesh(_cut_at_the_base(name, height_m), source="scan.ply")
    assert repaired.is_watertight and repaired.is_winding_consistent
    # the cap stands at the rim: less volume than the whole object, never more
    assert 0.8 * whole.mass.volume < repaired.volume < whole.mass.volume
    assert "scan.ply was repaired: " in caplog.text and "capped" in caplog.text


def test_a_hole_pinched_to_one_vertex_is_capped_as_two():
    # A unit cube open at the top, half its top covered by two triangles meeting at the
    # centre: the two holes left share that vertex, and the rim is traced through it twice.
    v = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    faces = [[0, 2, 1], [0, 3, 2]]
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, j, j + 4], [i, j + 4, i + 4]]
    faces += [[6, 7, 8], [4, 5, 8]]
    pinched = trimesh.Trimesh([*v, [0.5, 0.5, 1]], faces, process=False)
    assert not pinched.is_watertight
    assert_solid(prepare_mesh(pinched), 1.0)


def test_a_rim_through_one_vertex_twice_is_split_into_simple_loops():
    from affordgrasp.objects.loading import _simple_loops

    def split(loop):
        return [part.tolist() for part in _simple_loops(loop)]

    assert split([1, 2, 3, 4, 2, 5, 6]) == [[2, 3, 4], [1, 2, 5, 6]]
    assert split([1, 2, 3]) == [[1, 2, 3]]
    assert split([1, 2, 3, 2, 4, 5]) == [[1, 2, 4, 5]]  # a spur there and back: no cap


def test_consistent_winding_undoes_random_flips_with_the_fewest_turns():
    from affordgrasp.objects.loading import _consistent_winding

    sphere = trimesh.creation.icosphere(subdivisions=3)
    rng = np.random.default_rng(0)
    faces = sphere.faces.copy()
    flipped = rng.random(len(faces)) < 0.2
    faces[flipped] = faces[flipped][:, ::-1]
    assert np.array_equal(_consistent_winding(faces), sphere.faces)  # most faces kept
    assert _consistent_winding(sphere.faces) is None
    # two parts: each keeps its own majority (one all inside out: fixed later by volume)
    other = trimesh.creation.box()
    both = np.vstack([sphere.faces[:, ::-1], other.faces + len(sphere.vertices)])
    both[-2:] = both[-2:, ::-1]
    wound = _consistent_winding(both)
    assert np.array_equal(wound[: len(sphere.faces)], sphere.faces[:, ::-1])
    assert np.array_equal(wound[len(sphere.faces) :], other.faces + len(sphere.vertices))


def test_fixing_normals_agrees_with_trimesh():
    # an independent implementation of the same walk: trimesh's fix_normals
    from affordgrasp.objects.loading import _fix_normals

    rng = np.random.default_rng(1)
    parts = [trimesh.creation.icosphere(subdivisions=2), trimesh.creation.capsule()]
    parts[1].apply_translation([3, 0, 0])
    mesh = trimesh.util.concatenate(parts)
    faces = mesh.faces.copy()
    flipped = rng.random(len(faces)) < 0.3
    faces[flipped] = faces[flipped][:, ::-1]
    ours = trimesh.Trimesh(mesh.vertices, faces, process=False)
    theirs = trimesh.Trimesh(mesh.vertices, faces, process=False)
    _fix_normals(ours)
    trimesh.repair.fix_normals(theirs, multibody=True)
    assert ours.is_winding_consistent and ours.volume > 0
    assert np.array_equal(ours.faces, theirs.faces)


def _seam_sphere(radius=40.0, n_lat=16, n_lon=32, jitter=1e-5) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere whose seam meridian is written twice, the copy ``jitter`` away."""
    rng = np.random.default_rng(0)
    theta = np.pi * np.arange(1, n_lat) / n_lat
    phi = 2 * np.pi * (np.arange(n_lon + 1) % n_lon) / n_lon  # column n_lon: column 0 again
    t, p = np.meshgrid(theta, phi, indexing="ij")
    rings = radius * np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    rings[:, -1] += rng.uniform(-jitter, jitter, (n_lat - 1, 3))
    vertices = np.vstack([rings.reshape(-1, 3), [[0, 0, radius], [0, 0, -radius]]])
    index = np.arange((n_lat - 1) * (n_lon + 1)).reshape(n_lat - 1, n_lon + 1)
    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()
    c, d = index[1:, :-1].ravel(), index[1:, 1:].ravel()
    top, bottom = len(vertices) - 2, len(vertices) - 1
    faces = np.vstack(
        [
            np.stack([a, c, b], 1),
            np.stack([b, c, d], 1),
            np.stack([np.full(n_lon, top), index[0, :-1], index[0, 1:]], 1),
            np.stack([np.full(n_lon, bottom), index[-1, 1:], index[-1, :-1]], 1),
        ]
    )
    return vertices, faces


def test_a_seam_written_twice_is_welded_not_capped(tmp_path, caplog):
    vertices, faces = _seam_sphere()
    path = tmp_path / "ball.off"
    lines = ["OFF", f"{len(vertices)} {len(faces)} 0"]
    lines += [" ".join(repr(float(x)) for x in v) for v in vertices]
    lines += ["3 " + " ".join(map(str, f)) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    welded = trimesh.Trimesh(vertices, faces)
    welded.merge_vertices(digits_vertex=3)  # the seam's copy 1e-5 mm away: one vertex
    assert welded.is_watertight
    with caplog.at_level(logging.WARNING):
        mesh = load_mesh(path, units="mm")
    assert_solid(mesh, welded.volume * 1e-9)
    assert len(mesh.faces) == len(faces)  # no cap
    said = caplog.text
    assert "welded 15 vertices" in said and " mm away" in said and "capped" not in said, said


def test_repair_sizes_are_in_the_files_unit(tmp_path, caplog):
    # A cube 50 mm wide without one side: a hole 50 mm across, said in millimetres.
    cube = box((50.0, 50.0, 50.0))
    side = np.flatnonzero(np.isclose(cube.face_normals[:, 0], 1.0))
    path = tmp_path / "open.stl"
    trimesh.Trimesh(cube.vertices, np.delete(cube.faces, side, axis=0)).export(path)
    with caplog.at_level(logging.WARNING):
        load_mesh(path, units="mm")
    assert "the widest 50 mm across" in caplog.text, caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        load_mesh(path, size_m=0.1)
    assert "the widest 100 mm across" in caplog.text, caplog.text


def test_separate_bodies_are_named_and_specks_and_touching_parts_are_not(tmp_path, caplog):
    scene = trimesh.Scene()
    for i, size in enumerate([(0.06, 0.03, 0.03), (0.05, 0.03, 0.03), (0.055, 0.03, 0.02)]):
        scene.add_geometry(box(size, (0.1 * i, 0.0, 0.0)), geom_name=f"part{i}")
    path = tmp_path / "three.glb"
    scene.export(path)
    with caplog.at_level(logging.WARNING):
        mesh = load_mesh(path)
    assert mesh.volume == pytest.approx(0.06 * 0.03 * 0.03 + 0.05 * 0.03 * 0.03 + 0.055 * 6e-4)
    assert (
        "three.glb holds 3 separate bodies (60 mm, 55 mm, 50 mm long), the closest 45 mm "
        "apart: they are graded as ONE rigid object"
    ) in caplog.text, caplog.text
    caplog.clear()
    touching = trimesh.util.concatenate([box((1, 1, 1)), box((1, 1, 1), (1, 1, 0))])
    speck = trimesh.creation.icosphere(subdivisions=1, radius=0.001)
    speck.apply_translation([0.1, 0.0, 0.0])
    with caplog.at_level(logging.WARNING):
        prepare_mesh(touching, source="touching")
        prepare_mesh(trimesh.util.concatenate([box((0.1, 0.02, 0.02)), speck]), source="s")
    assert "separate" not in caplog.text and "speck" in caplog.text, caplog.text
