"""Tests for the OFF reader: the quirks of OFF files found in the wild."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from affordgrasp.errors import MeshError
from affordgrasp.objects.off import read_off, triangulate_polygon

CUBE_VERTICES = """\
-0.5 -0.5 -0.5
0.5 -0.5 -0.5
0.5 0.5 -0.5
-0.5 0.5 -0.5
-0.5 -0.5 0.5
0.5 -0.5 0.5
0.5 0.5 0.5
-0.5 0.5 0.5
"""
CUBE_FACES = """\
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
"""
CUBE = "OFF\n8 6 12\n" + CUBE_VERTICES + CUBE_FACES
EXPECTED_VERTICES = np.array([line.split() for line in CUBE_VERTICES.splitlines()], dtype=float)


def assert_unit_cube(vertices: np.ndarray, faces: np.ndarray) -> None:
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    assert faces.dtype == np.int64 and faces.shape == (12, 3)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(1.0)


def polygon_area_2d(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def test_cube_of_quads_is_triangulated_with_its_winding():
    vertices, faces = read_off(CUBE)
    assert_unit_cube(vertices, faces)
    # File order: the two triangles of the first quad come first.
    assert set(faces[:2].ravel()) == {0, 1, 2, 3}


def test_comment_after_counts_line_does_not_shift_vertices():
    text = "OFF\n8 6 0 # vertices faces edges\n# a full-line comment\n\n"
    text += CUBE_VERTICES.replace("\n", "  # trailing comment\n", 2) + CUBE_FACES
    assert_unit_cube(*read_off(text))


@pytest.mark.parametrize("header", ["off", "Off", "OFF 8 6 0", "OFF8 6 0", "off 8 6"])
def test_header_case_and_counts_on_the_header_line(header):
    counts = "" if header[3:].strip() else "8 6 0\n"
    assert_unit_cube(*read_off(f"{header}\n{counts}{CUBE_VERTICES}{CUBE_FACES}"))


def test_missing_header_is_accepted():
    assert_unit_cube(*read_off("8 6 0\n" + CUBE_VERTICES + CUBE_FACES))


def test_crlf_tabs_and_blank_lines():
    text = CUBE.replace(" ", "\t").replace("\n", "\r\n\r\n")
    assert_unit_cube(*read_off(text))


def test_coff_vertex_and_face_colours_are_ignored():
    vertices = "".join(line + " 255 0 0 255\n" for line in CUBE_VERTICES.splitlines())
    faces = "".join(line + " 0.1 0.2 0.3\n" for line in CUBE_FACES.splitlines())
    assert_unit_cube(*read_off("COFF\n8 6 0\n" + vertices + faces))


@pytest.mark.parametrize(
    ("header", "extra"), [("NOFF", " 0 0 1"), ("STOFF", " 0.5 0.5"), ("CNOFF", " 0 0 1 1 1 1")]
)
def test_extra_vertex_columns_are_ignored(header, extra):
    vertices = "".join(line + extra + "\n" for line in CUBE_VERTICES.splitlines())
    assert_unit_cube(*read_off(f"{header}\n8 6 0\n{vertices}{CUBE_FACES}"))


def test_noff_with_dimension_three_is_read():
    assert_unit_cube(*read_off("nOFF\n3\n8 6 0\n" + CUBE_VERTICES + CUBE_FACES))


def test_reads_from_a_path_and_from_bytes(tmp_path):
    path = tmp_path / "cube.off"
    path.write_text(CUBE)
    assert_unit_cube(*read_off(path))
    assert_unit_cube(*read_off(str(path)))
    assert_unit_cube(*read_off(CUBE.encode()))


def l_prism_off() -> tuple[str, np.ndarray]:
    """An L-shaped prism: two non-convex hexagon caps and six quads."""
    # Corner 0 cannot see corner 3 across the notch, so a fan from it would be wrong.
    outline = np.array([[2, 1], [1, 1], [1, 2], [0, 2], [0, 0], [2, 0]], dtype=float)
    bottom = np.column_stack([outline, np.zeros(6)])
    top = np.column_stack([outline, np.ones(6)])
    vertices = np.vstack([bottom, top])
    lines = [f"{len(vertices)} 8 0"] + [" ".join(map(str, v)) for v in vertices]
    lines.append("6 5 4 3 2 1 0")  # bottom, seen from below: counter-clockwise
    lines.append("6 6 7 8 9 10 11")
    for i in range(6):
        j = (i + 1) % 6
        lines.append(f"4 {i} {j} {j + 6} {i + 6}")
    return "OFF\n" + "\n".join(lines) + "\n", outline


def test_non_convex_faces_are_triangulated_exactly():
    text, outline = l_prism_off()
    vertices, faces = read_off(text)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    area = polygon_area_2d(outline)
    assert area == pytest.approx(3.0)
    fan = np.array([[0, j, j + 1] for j in range(1, 5)])
    fan_area = sum(abs(polygon_area_2d(outline[t])) for t in fan)
    assert fan_area > area + 0.1  # the fan would overlap itself
    caps = np.abs(mesh.face_normals[:, 2]) > 0.5
    assert caps.sum() == 8
    top = mesh.face_normals[:, 2] > 0.5
    assert top.sum() == 4
    assert mesh.area_faces[top].sum() == pytest.approx(area)
    assert mesh.area_faces[caps & ~top].sum() == pytest.approx(area)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(area)


def test_star_polygon_area():
    angles = np.linspace(0, 2 * np.pi, 11)[:-1]
    radii = np.where(np.arange(10) % 2 == 0, 1.0, 0.4)
    xy = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    text = "OFF\n10 1 0\n" + "".join(f"{x} {y} 0\n" for x, y in xy)
    text += "10 " + " ".join(map(str, range(10))) + "\n"
    vertices, faces = read_off(text)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert len(faces) == 8
    assert mesh.area == pytest.approx(polygon_area_2d(xy))
    assert np.all(mesh.face_normals[:, 2] > 0.999)


@st.composite
def star_shaped_polygons(draw):
    k = draw(st.integers(4, 14))
    gaps = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=k, max_size=k)))
    angles = np.cumsum(gaps) / gaps.sum() * 2 * np.pi
    radii = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=k, max_size=k)))
    rotation = trimesh.transformations.random_rotation_matrix(
        np.random.default_rng(draw(st.integers(0, 2**32 - 1))).random(3)
    )[:3, :3]
    xy = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    return xy, np.column_stack([xy, np.zeros(k)]) @ rotation.T, rotation[:, 2]


@settings(max_examples=60, deadline=None)
@given(star_shaped_polygons())
def test_triangulation_covers_the_polygon_with_its_winding(polygon):
    xy, points, normal = polygon
    tri = triangulate_polygon(points)
    assert tri.shape == (len(points) - 2, 3)
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    cross = np.cross(b - a, c - a)
    # Every triangle turns like the polygon, and together they cover its area exactly.
    assert np.all(cross @ normal > -1e-12)
    assert 0.5 * np.linalg.norm(cross, axis=1).sum() == pytest.approx(polygon_area_2d(xy))


def test_4d_and_nd_off_are_refused():
    with pytest.raises(MeshError, match="4-D OFF"):
        read_off("4OFF\n8 6 0\n" + CUBE_VERTICES + CUBE_FACES)
    with pytest.raises(MeshError, match="5-D OFF"):
        read_off("nOFF\n5\n8 6 0\n" + CUBE_VERTICES + CUBE_FACES)


def test_point_cloud_is_refused():
    with pytest.raises(MeshError, match="has no faces.*surface mesh"):
        read_off("OFF\n8 0 0\n" + CUBE_VERTICES)


def test_truncated_files_are_refused_with_the_counts_line():
    with pytest.raises(MeshError, match="ends after 5 of 6 faces.*line 2"):
        read_off("OFF\n8 6 0\n" + CUBE_VERTICES + "\n".join(CUBE_FACES.splitlines()[:5]))
    with pytest.raises(MeshError, match="ends after 8 of 9 vertices.*line 2"):
        read_off("OFF\n9 6 0\n" + CUBE_VERTICES)


def test_short_vertex_line_names_its_line():
    text = CUBE.replace("0.5 0.5 -0.5\n", "0.5 0.5\n", 1)
    with pytest.raises(MeshError, match="line 5: a vertex needs 3 coordinates"):
        read_off(text)


def test_out_of_range_index_names_its_line(tmp_path):
    path = tmp_path / "bad.off"
    path.write_text(CUBE.replace("4 4 5 6 7", "4 4 5 6 8"))
    with pytest.raises(MeshError, match=r"bad\.off line 12: vertex index 8 is out of range"):
        read_off(path)
    with pytest.raises(MeshError, match="vertex index -1"):
        read_off(CUBE.replace("4 4 5 6 7", "4 4 5 6 -1"))


def test_faces_with_fewer_than_three_vertices_are_refused():
    with pytest.raises(MeshError, match="line 11: a face has 2 vertices"):
        read_off(CUBE.replace("4 0 3 2 1", "2 0 3"))
    with pytest.raises(MeshError, match="lists 3 value"):
        read_off(CUBE.replace("4 0 3 2 1", "4 0 3 2"))


def test_other_malformed_input_is_refused(tmp_path):
    with pytest.raises(MeshError, match="expected an OFF header"):
        read_off("PLY\n8 6 0\n" + CUBE_VERTICES + CUBE_FACES)
    with pytest.raises(MeshError, match="binary OFF"):
        read_off("OFF BINARY\n8 6 0\n")
    with pytest.raises(MeshError, match="counts"):
        read_off("OFF\n8 x 0\n" + CUBE_VERTICES + CUBE_FACES)
    with pytest.raises(MeshError, match="must be numbers"):
        read_off(CUBE.replace("0.5 0.5 0.5", "0.5 zero 0.5"))
    with pytest.raises(MeshError, match="empty"):
        read_off("# nothing\n\n")
    with pytest.raises(MeshError, match="does not exist"):
        read_off(tmp_path / "missing.off")
