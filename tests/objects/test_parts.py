"""Semantic parts of the procedural families (objects/families/parts.py) and their columns."""

import numpy as np
import pytest
import trimesh

from affordgrasp.objects import list_families, load_object
from affordgrasp.objects.families import make_family
from affordgrasp.objects.families.parts import EDGE_BAND_M, PART_NAMES, SHARP_EDGE_RAD
from affordgrasp.pipeline import evaluate_samples

# the parts every instance of a family must have (at least one face each)
EXPECTED = {
    "hammer": {"handle", "head", "striking_face"},
    "knife": {"handle", "blade", "cutting_edge", "spine", "tip"},
    "meat_cleaver": {"handle", "blade", "cutting_edge", "spine"},
    "axe": {"handle", "head", "cutting_edge"},
    "screwdriver": {"handle", "shaft", "tip"},
    "spatula": {"handle", "shaft", "blade", "edge"},
    "sword": {"pommel", "handle", "guard", "blade", "cutting_edge", "tip"},
    "dagger": {"pommel", "handle", "guard", "blade", "cutting_edge", "tip"},
    "bottle": {"body", "neck", "rim", "base", "inside"},
    "wine_glass": {"bowl", "stem", "foot", "rim", "inside"},
    "tumbler": {"body", "rim", "base", "inside"},
    "mug": {"body", "handle", "rim", "base", "inside"},
    "ice_cream_cone": {"body", "rim", "inside"},
}


def test_every_family_is_listed():
    assert set(EXPECTED) == set(list_families())


@pytest.mark.parametrize("seed", [0, 5])
@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_every_face_has_a_part_and_the_family_has_its_parts(name, seed):
    mesh = make_family(name, seed)
    parts = mesh.metadata["face_parts"]
    assert parts.shape == (len(mesh.faces),)
    assert mesh.metadata["part_names"] == PART_NAMES
    assert parts.min() >= 0 and parts.max() < len(PART_NAMES)
    present = {PART_NAMES[i] for i in np.unique(parts)}
    assert EXPECTED[name] <= present, EXPECTED[name] - present
    again = make_family(name, seed).metadata["face_parts"]
    np.testing.assert_array_equal(parts, again)


def sharp_vertex_faces(mesh: trimesh.Trimesh) -> np.ndarray:
    """Faces touching a convex edge whose interior dihedral angle is below 45°."""
    interior = np.pi - mesh.face_adjacency_angles
    sharp = mesh.face_adjacency_convex & (interior < SHARP_EDGE_RAD)
    on = np.zeros(len(mesh.vertices), dtype=bool)
    on[mesh.face_adjacency_edges[sharp].ravel()] = True
    return on[mesh.faces].any(axis=1)


@pytest.mark.parametrize("name", ["knife", "meat_cleaver", "dagger", "sword", "axe"])
def test_cutting_edge_faces_are_the_faces_at_small_dihedral_angles(name):
    mesh = make_family(name, 2)
    parts = np.asarray(PART_NAMES, dtype=object)[mesh.metadata["face_parts"]]
    edge = parts == "cutting_edge"
    touching = sharp_vertex_faces(mesh)
    interior = np.pi - mesh.face_adjacency_angles
    sharp = mesh.face_adjacency_convex & (interior < SHARP_EDGE_RAD)
    seg = mesh.vertices[mesh.face_adjacency_edges[sharp]]  # (k, 2, 3)
    a, ab = seg[:, 0], seg[:, 1] - seg[:, 0]

    def distance(points):
        p = points[:, None]
        t = np.clip(np.einsum("pkj,kj->pk", p - a, ab) / np.einsum("kj,kj->k", ab, ab), 0, 1)
        return np.linalg.norm(p - (a + t[..., None] * ab), axis=2).min(axis=1)

    # every cutting-edge face touches the sharp edge line or lies, whole, within the band
    corners = distance(mesh.vertices[mesh.faces[edge].ravel()]).reshape(-1, 3)
    assert np.all(touching[edge] | (corners.max(axis=1) <= EDGE_BAND_M + 1e-3))
    # ... the faces that share a whole edge with the line are cutting-edge faces
    along = np.zeros(len(mesh.faces), dtype=bool)
    along[mesh.face_adjacency[sharp].ravel()] = True
    assert np.all(edge[along])
    # ... and the band is thin: every cutting-edge face's centre within 20 mm of the line
    assert distance(mesh.triangles_center[edge]).max() < 0.02
    # single-edged blades cut towards -y, their spine faces +y
    normals = mesh.face_normals
    if name in ("knife", "meat_cleaver", "axe"):
        assert np.mean(normals[edge, 1] < 0.05) > 0.95
    if name in ("knife", "meat_cleaver"):
        assert np.all(normals[parts == "spine", 1] > 0.7)


def test_hammer_striking_face_faces_minus_y_at_the_end_of_the_head():
    mesh = make_family("hammer", 1)
    parts = np.asarray(PART_NAMES, dtype=object)[mesh.metadata["face_parts"]]
    face = parts == "striking_face"
    assert np.all(mesh.face_normals[face, 1] < -0.5)
    head_y = mesh.triangles_center[(parts == "head") | face, 1]
    assert np.all(mesh.triangles_center[face, 1] <= head_y.min() + 0.002 + 1e-12)


def test_parts_columns_in_the_dataset(tmp_path):
    table = evaluate_samples("knife:1", 120, seed=0).table
    obj = load_object("knife:1")
    names = set(obj.part_names)
    use = table.column("use_part").to_pylist()
    tri = table.column("use_triangle").to_numpy()
    assert all(u in names for u in use)
    assert use == list(obj.parts_of_faces(tri))
    contact_parts = table.column("contact_parts").to_pylist()
    links = table.column("contact_link").to_pylist()
    assert [len(c) for c in contact_parts] == [len(c) for c in links]
    assert all(p in names for c in contact_parts for p in c)
    # a contact's part is the part of the face under it
    pts = np.array([p for row in table.column("contact_points").to_pylist() for p in row])
    flat = [p for row in contact_parts for p in row]
    _, _, under = trimesh.proximity.closest_point(obj.mesh, pts)
    agree = np.mean(np.asarray(flat, dtype=object) == obj.parts_of_faces(under))
    assert agree > 0.9  # contacts on a part boundary or a sharp edge may go to either side
    # a mesh file has no labels: empty strings
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(0.05, 0.04, 0.03)).export(path)
    box = evaluate_samples(str(path), 40, seed=0).table
    assert set(box.column("use_part").to_pylist()) == {""}
    assert {p for c in box.column("contact_parts").to_pylist() for p in c} <= {""}
    assert load_object(str(path)).face_parts is None
