"""U_g and the sharpest-edge angle (edges.py, conventions: Metrics)."""

import numpy as np
import pytest
import trimesh
from metrics_support import fine_cylinder, folded_sheet, wedge_prism

from affordgrasp.errors import InputError
from affordgrasp.metrics import edges, use_edge, use_edge_angle
from affordgrasp.objects import load_object


def _plane():
    mesh = trimesh.creation.box(extents=(0.2, 0.2, 0.02))
    for _ in range(4):
        mesh = mesh.subdivide()
    return mesh


def test_plane_is_zero():
    mesh = _plane()
    centres = mesh.triangles_center
    top = np.flatnonzero((mesh.face_normals[:, 2] > 0.99) & (np.abs(centres[:, :2]).max(1) < 0.05))
    ug = use_edge(mesh, top[:20], centres[top[:20]])
    np.testing.assert_allclose(ug, 0.0, atol=1e-12)


def test_finely_meshed_cylinder_is_one_over_r_squared():
    R = 0.02
    mesh = fine_cylinder(R, height=0.004, sections=128, subdivisions=3)
    centres = mesh.triangles_center
    middle = np.flatnonzero(
        (np.abs(mesh.face_normals[:, 2]) < 1e-6) & (np.abs(centres[:, 2]) < 5e-4)
    )
    rng = np.random.default_rng(0)
    T = rng.choice(middle, 25, replace=False)
    ug = use_edge(mesh, T, centres[T])
    np.testing.assert_allclose(ug * R * R, 1.0, rtol=0.03)


def test_sphere_is_nearly_zero():
    R = 0.03
    mesh = trimesh.creation.icosphere(subdivisions=5, radius=R)
    ug = use_edge(mesh, np.arange(0, len(mesh.faces), 997))
    assert np.all(ug * R * R < 1e-3)


def test_rigid_motion_and_scale():
    R = 0.02
    mesh = fine_cylinder(R, height=0.004, sections=64, subdivisions=2)
    rng = np.random.default_rng(1)
    T = rng.choice(len(mesh.faces), 30, replace=False)
    base = use_edge(mesh, T, mesh.triangles_center[T])
    M = trimesh.transformations.random_rotation_matrix(rng.random(3))
    M[:3, 3] = [0.1, -0.2, 0.3]
    moved = mesh.copy()
    moved.apply_transform(M)
    np.testing.assert_allclose(
        use_edge(moved, T, moved.triangles_center[T]), base, rtol=1e-6, atol=1e-9 * base.max()
    )
    s = 4.0
    scaled = mesh.copy()
    scaled.apply_scale(s)
    np.testing.assert_allclose(
        use_edge(scaled, T, scaled.triangles_center[T]),
        base / s**2,
        rtol=1e-6,
        atol=1e-9 * base.max(),
    )


def test_degenerate_fit_is_finite():
    tet = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    )
    ug = use_edge(tet, [0, 1, 2, 3])
    assert np.all(np.isfinite(ug)) and np.all(ug >= 0)


def test_paper_definition_depends_on_resolution_and_underrates_acute_edges():
    # documented limitations of U_g (see tasks.TAU_UG_DEFAULT): on the same isotropic
    # mesh a sharp 20° edge scores below a 60° one (the opposite flank folds back under
    # the fitting plane), and the same edge meshed 4x coarser scores 16x lower
    def median_on_edge(deg, spacing):
        mesh, edge_faces = folded_sheet(np.radians(deg), spacing=spacing)
        middle = edge_faces[np.abs(mesh.triangles_center[edge_faces, 0]) < 4 * spacing]
        return np.median(use_edge(mesh, middle))

    assert median_on_edge(20, 5e-4) < 0.5 * median_on_edge(60, 5e-4)
    assert median_on_edge(20, 2e-3) == pytest.approx(median_on_edge(20, 5e-4) / 16, rel=1e-6)


def test_edge_angle_of_wedges():
    for deg in (20.0, 45.0, 90.0):
        mesh = wedge_prism(np.radians(deg))
        near_edge = use_edge_angle(mesh, [[0.0, 0.001, 0.0]])
        assert np.degrees(near_edge[0]) == pytest.approx(deg, abs=1e-6)
        # on a flank face 10 mm from the sharp edge: the back corners are farther than 3 mm
        far = use_edge_angle(mesh, [0.0, 0.01, np.tan(np.radians(deg) / 2) * 0.01])
        assert far == pytest.approx(np.pi)


def test_edge_angle_radius_and_concave_edges():
    mesh = wedge_prism(np.radians(30.0))
    p = [0.0, 0.004, 0.0]  # 4 mm from the edge
    assert use_edge_angle(mesh, p) == pytest.approx(np.pi)
    assert np.degrees(use_edge_angle(mesh, p, radius=0.005)) == pytest.approx(30.0)
    # an L-shaped solid: its re-entrant (concave) edge is not a cutting edge
    a = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    b = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    b.apply_translation([0.04, 0, 0])
    c = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    c.apply_translation([0, 0.04, 0])
    ell = trimesh.boolean.union([a, b, c], engine="manifold")
    inner_corner = [0.02 + 0.001, 0.02 + 0.001, 0.0]  # next to the concave edge only
    assert use_edge_angle(ell, inner_corner) == pytest.approx(np.pi)
    outer_corner = [0.059, -0.019, 0.0]  # next to a convex 90° edge
    assert np.degrees(use_edge_angle(ell, outer_corner)) == pytest.approx(90.0)


def test_edge_angle_counts_only_edges_that_face_the_use_normal():
    deg = 30.0
    half = np.radians(deg) / 2
    mesh = wedge_prism(np.radians(deg))
    flank_normal = np.array([0.0, -np.sin(half), np.cos(half)])
    on_flank = [0.0, 0.001, 0.001 * np.tan(half)]  # 1 mm up the +z flank
    # a point on a flank, with the flank's normal, and the apex with the bisector: the edge
    for p, n in ((on_flank, flank_normal), ([0.0, 0.0, 0.0], [0.0, -1.0, 0.0])):
        assert np.degrees(use_edge_angle(mesh, p, use_normal=n)) == pytest.approx(deg)
    # a normal tilted along the edge by less than the tolerance (4°) still faces it
    tilted = np.cos(np.radians(4.0)) * flank_normal + [np.sin(np.radians(4.0)), 0.0, 0.0]
    assert np.degrees(use_edge_angle(mesh, on_flank, use_normal=tilted)) == pytest.approx(deg)
    # the end cap beside the edge: without a normal it counts, its normal runs along the
    # edge (90° off the edge's normal fan), so the edge does not face it: only the cap's
    # own 90° corners with the flanks do
    cap = [0.025, 0.001, 0.0]
    assert np.degrees(use_edge_angle(mesh, cap)) == pytest.approx(deg)
    assert np.degrees(use_edge_angle(mesh, cap, use_normal=[1.0, 0.0, 0.0])) == pytest.approx(90)
    # a flat beside the edge whose normal is half the edge angle (15°) off the fan
    assert use_edge_angle(mesh, on_flank, use_normal=[0.0, 0.0, 1.0]) == pytest.approx(np.pi)
    batch = use_edge_angle(mesh, [on_flank, cap], use_normal=[flank_normal, [1.0, 0.0, 0.0]])
    assert np.degrees(batch) == pytest.approx([deg, 90.0])
    with pytest.raises(InputError):
        use_edge_angle(mesh, [on_flank, cap], use_normal=[flank_normal])


def test_dagger_guard_beside_the_blade_root_is_not_a_cutting_edge():

    obj = load_object("dagger:0")
    mesh = obj.mesh
    names = np.asarray(obj.part_names, dtype=object)[obj.face_parts]
    points, faces = trimesh.sample.sample_surface(mesh, 20000, seed=0)
    normals = mesh.face_normals[faces]
    bare = use_edge_angle(mesh, points)
    facing = use_edge_angle(mesh, points, use_normal=normals)
    guard = names[faces] == "guard"
    near_guard = guard & (bare <= np.radians(45.0))
    assert near_guard.sum() >= 5  # guard points within 3 mm of the blade's edge exist ...
    # ... and no sharp edge faces them (only blunt facets of the guard itself)
    assert np.all(facing[near_guard] > np.radians(90.0))
    # on the cutting edge's flanks, near the edge line, the edge faces the use normal
    edge = (names[faces] == "cutting_edge") & (bare <= np.radians(45.0))
    assert edge.sum() >= 100
    assert np.mean(facing[edge] <= np.radians(45.0)) > 0.99
    # and what faces an edge is on the cutting edge (or the tip where two edges meet)
    cut = facing <= np.radians(45.0)
    assert set(names[faces[cut]]) <= {"cutting_edge", "tip"}


def test_batches_and_bad_input():
    mesh = _plane()
    ug = use_edge(mesh, np.arange(10))
    assert ug.shape == (10,)
    assert isinstance(use_edge(mesh, 3), float)
    with pytest.raises(InputError):
        use_edge(mesh, [len(mesh.faces)])
    with pytest.raises(InputError):
        use_edge_angle(mesh, [0, 0, 0], radius=-1.0)


@pytest.mark.parametrize("with_normals", [False, True])
def test_edge_angle_over_all_edges_equals_the_grid_search(monkeypatch, with_normals):
    # Short batches test every edge; long ones go through the grid of edge samples. The
    # exact distance decides in both, so the angles are the same bits.

    mesh = load_object("knife").mesh
    rng = np.random.default_rng(3)
    faces = rng.integers(0, len(mesh.faces), 300)
    points = mesh.triangles_center[faces] + rng.normal(scale=2e-3, size=(300, 3))
    normals = mesh.face_normals[faces] if with_normals else None
    monkeypatch.setattr(edges, "_ALL_PAIRS_MAX", 10**12)
    every_edge = use_edge_angle(mesh, points, use_normal=normals)
    monkeypatch.setattr(edges, "_ALL_PAIRS_MAX", 0)
    grid = use_edge_angle(mesh, points, use_normal=normals)
    assert every_edge.tobytes() == grid.tobytes()
    assert (every_edge < np.pi).sum() > 50  # many points near a convex edge


def test_use_edge_of_a_use_point_does_not_depend_on_the_batch():
    # The fits of a batch share one call; each query's value must be the same bits
    # whatever else is evaluated with it (the mug's handle and rim have vertices of
    # different valence, so the queries' fits have different row counts).

    mesh = load_object("mug").mesh
    rng = np.random.default_rng(0)
    faces = rng.integers(0, len(mesh.faces), 300)
    points = mesh.triangles_center[faces] + rng.normal(scale=1e-4, size=(300, 3))
    whole = use_edge(mesh, faces, points)
    pieces = np.concatenate(
        [use_edge(mesh, faces[i : i + 7], points[i : i + 7]) for i in range(0, 300, 7)]
    )
    alone = np.array([use_edge(mesh, int(f), p) for f, p in zip(faces, points, strict=True)])
    assert whole.tobytes() == pieces.tobytes()
    assert whole.tobytes() == alone.tobytes()
    reverse = use_edge(mesh, faces[::-1], points[::-1])[::-1]
    assert reverse.tobytes() == whole.tobytes()
