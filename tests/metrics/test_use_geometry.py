"""U_g, the sharpest-edge angle and the wedge's rays (use_geometry.py, conventions: Metrics)."""

import numpy as np
import pytest
import trimesh
from metrics_support import fine_cylinder, folded_sheet, wedge_prism

from affordgrasp.errors import InputError
from affordgrasp.metrics import use_edge, use_edge_angle, use_geometry
from affordgrasp.objects import load_object
from affordgrasp.rays import embree_available
from affordgrasp.rays.mesh import EmbreeRays, mesh_caster


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
    from affordgrasp.objects import load_object

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
    from affordgrasp.metrics import use_geometry
    from affordgrasp.objects import load_object

    mesh = load_object("knife").mesh
    rng = np.random.default_rng(3)
    faces = rng.integers(0, len(mesh.faces), 300)
    points = mesh.triangles_center[faces] + rng.normal(scale=2e-3, size=(300, 3))
    normals = mesh.face_normals[faces] if with_normals else None
    monkeypatch.setattr(use_geometry, "_ALL_PAIRS_MAX", 10**12)
    every_edge = use_edge_angle(mesh, points, use_normal=normals)
    monkeypatch.setattr(use_geometry, "_ALL_PAIRS_MAX", 0)
    grid = use_edge_angle(mesh, points, use_normal=normals)
    assert every_edge.tobytes() == grid.tobytes()
    assert (every_edge < np.pi).sum() > 50  # many points near a convex edge


def test_use_edge_of_a_use_point_does_not_depend_on_the_batch():
    # The fits of a batch share one call; each query's value must be the same bits
    # whatever else is evaluated with it (the mug's handle and rim have vertices of
    # different valence, so the queries' fits have different row counts).
    from affordgrasp.objects import load_object

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


# --- wedge angle at a physical scale, use clearance ------------------------------------


def _prism(opening_deg: float):
    """A 60 mm wedge prism along x, apex on the x axis, opening towards +y (closed)."""
    return wedge_prism(np.radians(opening_deg), length=0.06)


def test_wedge_angle_known_geometries():
    import trimesh

    from affordgrasp.metrics.use_geometry import use_wedge_angle

    box = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    pts = [[0, 0, 0.02], [0.02, 0, 0.02], [0.02, 0.02, 0.02]]
    nrm = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1]], float)
    got = np.degrees(use_wedge_angle(box, pts, nrm / np.linalg.norm(nrm, axis=1)[:, None]))
    np.testing.assert_allclose(got, [180.0, 90.0, 45.0], atol=4.0)
    fine = box.subdivide().subdivide().subdivide()  # the triangles do not matter
    np.testing.assert_allclose(
        np.degrees(use_wedge_angle(fine, pts, nrm / np.linalg.norm(nrm, axis=1)[:, None])),
        got,
        atol=1.0,
    )
    for opening in (20.0, 40.0):
        prism = _prism(opening)
        at_apex = np.degrees(use_wedge_angle(prism, [0.0, 0.0, 0.0], [0.0, -1.0, 0.0]))
        assert abs(at_apex - opening) < 4.0


def test_wedge_angle_survives_a_scanner():
    from affordgrasp.metrics.use_geometry import use_wedge_angle
    from affordgrasp.objects.scan import ScanSettings, scan_like

    prism = _prism(20.0)
    scan, _ = scan_like(prism, seed=0, settings=ScanSettings(noise_m=0.2e-3))
    # use points on the rounded apex: the surface points nearest the apex line
    x = np.linspace(-0.02, 0.02, 9)
    probe = np.stack([x, np.full(9, -2e-3), np.zeros(9)], axis=1)
    loc, ray, tri = scan.ray.intersects_location(probe, np.tile([0, 1.0, 0], (9, 1)), False)
    wedge = np.degrees(use_wedge_angle(scan, loc, scan.face_normals[tri]))
    assert np.all(wedge < 45.0) and np.median(wedge) < 35.0
    # a flank 15 mm from the apex (the prism 5 mm thick there): no edge
    loc2, _, tri2 = scan.ray.intersects_location([[0.0, 0.015, 0.01]], [[0, 0, -1.0]], False)
    assert np.degrees(use_wedge_angle(scan, loc2[0], scan.face_normals[tri2[0]])) > 120.0


def test_edge_span_tells_an_edge_from_a_tip_and_a_corner():
    import trimesh

    from affordgrasp.metrics.use_geometry import use_edge_span, use_wedge_angle, use_wedge_shape

    # along a wedge of any opening the inside directions span the edge's line: λ2 = 1/3
    for opening in (20.0, 40.0):
        prism = _prism(opening)
        shape = use_wedge_shape(prism, [[0.0, 0.0, 0.0]], [[0.0, -1.0, 0.0]])
        assert shape.span[0] == pytest.approx(1 / 3, abs=0.02)
        assert shape.angle[0] == use_wedge_angle(prism, [0.0, 0.0, 0.0], [0.0, -1.0, 0.0])
    # a thin plate (2 mm): its 90° corner is a quarter disc (1/2 - 1/π = 0.18), its straight
    # edge a half disc (1/2), its flat a slab (close to 1/2 too: the flat is thinner than the
    # ball); a cone's tip about 0
    plate = trimesh.creation.box(extents=(0.04, 0.04, 0.002))
    pts = np.array([[0.02, 0.02, 0.0], [0.02, 0.0, 0.0]])
    nrm = np.array([[1.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    span = use_edge_span(plate, pts, nrm)
    assert span[0] == pytest.approx(0.5 - 1 / np.pi, abs=0.03) and span[1] > 0.4
    cone = trimesh.creation.cone(0.005, 0.03, sections=64)
    tip = use_edge_span(cone, [0.0, 0.0, 0.03], [0.0, 0.0, 1.0])
    assert isinstance(tip, float) and tip < 0.05
    # the triangles do not matter
    fine = plate.subdivide().subdivide().subdivide()
    np.testing.assert_allclose(use_edge_span(fine, pts, nrm), span, atol=0.01)


def test_edge_span_survives_a_scanner():
    from affordgrasp.metrics.use_geometry import use_wedge_shape
    from affordgrasp.objects.scan import ScanSettings, scan_like

    prism = _prism(20.0)
    scan, _ = scan_like(prism, seed=0, settings=ScanSettings(noise_m=0.2e-3))
    x = np.linspace(-0.02, 0.02, 9)
    probe = np.stack([x, np.full(9, -2e-3), np.zeros(9)], axis=1)
    loc, _, tri = scan.ray.intersects_location(probe, np.tile([0, 1.0, 0], (9, 1)), False)
    shape = use_wedge_shape(scan, loc, scan.face_normals[tri])
    # the rounded crest spreads the inside directions a little towards the half disc of a
    # plate's straight edge (1/2), never towards a corner's or a tip's
    assert np.all((shape.span > 0.3) & (shape.span < 0.45))
    # the prism's end (rounded by the scanner): the apex line stops there, the span drops
    # below every point along the edge (0.13 on the crisp prism)
    loc2, _, tri2 = scan.ray.intersects_location([[0.0299, -2e-3, 0]], [[0, 1.0, 0]], False)
    end = use_wedge_shape(scan, loc2, scan.face_normals[tri2])
    assert end.span[0] < 0.3 and end.span[0] < shape.span.min() - 0.05


def test_wedge_angle_fine_sees_a_thin_flat_but_not_an_edge():
    import trimesh

    from affordgrasp.metrics.use_geometry import use_wedge_shape

    # a wedge's apex reads its opening at any scale
    prism = _prism(20.0)
    apex = use_wedge_shape(prism, [[0.0, 0.0, 0.0]], [[0.0, -1.0, 0.0]])
    assert abs(np.degrees(apex.inner_angle[0]) - np.degrees(apex.angle[0])) < 1.0
    # a 1 mm plate's flat: the slab's part of the ball, 2π (3 T / (4 r) - T³ / (4 r³)), is
    # 86.7° at r = 3 mm, 123.8° at 2 mm, 153.3° at 1.5 mm
    plate = trimesh.creation.box(extents=(0.05, 0.05, 0.001))
    flat = use_wedge_shape(plate, [[0.0, 0.0, 0.0005]], [[0.0, 0.0, 1.0]])
    assert np.degrees(flat.angle[0]) == pytest.approx(86.7, abs=3.0)
    assert np.degrees(flat.inner_angle[0]) == pytest.approx(123.8, abs=3.0)
    half = use_wedge_shape(plate, [[0.0, 0.0, 0.0005]], [[0.0, 0.0, 1.0]], inner_radius=0.0015)
    assert np.degrees(half.inner_angle[0]) == pytest.approx(153.3, abs=4.0)
    assert half.angle[0] == flat.angle[0] and half.span[0] == flat.span[0]


def test_edge_thickness_tells_an_edge_from_a_plate_end():
    import trimesh

    from affordgrasp.metrics.use_geometry import use_edge_thickness, use_wedge_shape

    # on a wedge the chords 2 tan(α/2) d are linear in d: 0 at the apex, any opening
    for opening in (20.0, 40.0):
        apex = use_edge_thickness(_prism(opening), [0.0, 0.0, 0.0], [0.0, -1.0, 0.0])
        assert isinstance(apex, float) and abs(apex) < 2e-5
    # a 1.2 mm plate's end (a spine): its thickness; off the end's middle the inside
    # directions tilt the chords a little (5 % longer 0.2 mm off it)
    plate = trimesh.creation.box(extents=(0.04, 0.03, 0.0012))
    pts = np.array([[0.02, 0.0, 0.0], [0.02, 0.005, 0.0004]])
    nrm = np.tile([1.0, 0.0, 0.0], (2, 1))
    got = use_edge_thickness(plate, pts, nrm)
    assert got[0] == pytest.approx(0.0012, abs=2e-5) and got[1] == pytest.approx(0.0012, rel=0.06)
    # the end of a plate as thin as the balls reads as an edge to them, not to this
    shape = use_wedge_shape(plate, pts[:1], nrm[:1])
    assert np.degrees(shape.angle[0]) < 55.0 and np.degrees(shape.inner_angle[0]) < 90.0
    # rigid motion: the same thickness
    rot = trimesh.transformations.rotation_matrix(0.7, [1.0, 2.0, 3.0])
    rot[:3, 3] = [0.1, -0.2, 0.3]
    moved = plate.copy().apply_transform(rot)
    moved_got = use_edge_thickness(moved, trimesh.transform_points(pts, rot), nrm @ rot[:3, :3].T)
    np.testing.assert_allclose(moved_got, got, atol=1e-5)  # the rays turn with it, not exactly
    # no ray inside (a point off the part): NaN, not a number from a meaningless frame
    assert np.isnan(use_edge_thickness(plate, [0.5, 0.5, 0.5], [0.0, 0.0, 1.0]))
    # a point's value does not depend on its batch (300 points: more than one chunk)
    prism = _prism(20.0)
    pts, tri = trimesh.sample.sample_surface(prism, 300, seed=3)
    nrm = prism.face_normals[tri]
    batch = use_edge_thickness(prism, pts, nrm)
    for i in (0, 17, 299):
        np.testing.assert_array_equal(
            use_edge_thickness(prism, pts[i : i + 1], nrm[i : i + 1]), batch[i : i + 1]
        )


def test_edge_thickness_survives_a_scanner():
    import trimesh

    from affordgrasp.metrics.use_geometry import use_edge_thickness
    from affordgrasp.objects.scan import ScanSettings, scan_like

    settings = ScanSettings(noise_m=0.15e-3)
    x = np.linspace(-0.015, 0.015, 7)
    # the rounded, noisy crest of a 20° wedge: still thin
    scan, _ = scan_like(_prism(20.0), seed=0, settings=settings)
    probe = np.stack([x, np.full(7, -2e-3), np.zeros(7)], axis=1)
    loc, _, tri = scan.ray.intersects_location(probe, np.tile([0, 1.0, 0], (7, 1)), False)
    crest = use_edge_thickness(scan, loc, scan.face_normals[tri])
    assert np.median(crest) < 0.4e-3 and np.all(crest < 0.6e-3)
    # a 1.2 mm plate's end, rounded by the scanner to a half round: still the plate's
    plate = trimesh.creation.box(extents=(0.04, 0.03, 0.0012))
    scan, _ = scan_like(plate, seed=1, settings=settings)
    probe = np.stack([np.full(7, 0.03), x, np.zeros(7)], axis=1)
    loc, _, tri = scan.ray.intersects_location(probe, np.tile([-1.0, 0, 0], (7, 1)), False)
    end = use_edge_thickness(scan, loc, scan.face_normals[tri])
    assert np.median(end) > 0.9e-3 and np.all(end > 0.7e-3)


def test_use_clearance_is_the_nearest_contact():
    from affordgrasp.metrics.use_geometry import use_clearance

    contacts = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.0, 0.2, 0]])
    offsets = np.array([0, 2, 2, 3])  # grasp 1 has no contact
    U = np.array([[0.03, 0, 0], [0.0, 0, 0], [0.0, 0.25, 0]])
    np.testing.assert_allclose(use_clearance(contacts, offsets, U), [0.03, np.inf, 0.05])
    np.testing.assert_allclose(
        use_clearance(contacts, offsets, U[[0, 0]], group=[2, 0]), [np.hypot(0.03, 0.2), 0.03]
    )
    assert np.isnan(use_clearance(contacts, offsets, [[np.nan] * 3], group=[0]))[0]


def test_contact_thickness_is_the_chord_under_the_thinnest_contact():
    import trimesh

    from affordgrasp.metrics.use_geometry import contact_thickness

    plate = trimesh.creation.box(extents=(0.1, 0.05, 0.004))
    C = np.array([[0.0, 0.0, 0.002], [0.05, 0.0, 0.0], [0.0, 0.025, 0.0]])
    N = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0]])
    got = contact_thickness(plate, C, N, [0, 1, 1, 3])  # grasp 1 has no contact
    np.testing.assert_allclose(got, [0.004, np.inf, 0.05], rtol=1e-6)


def test_contact_width_measures_across_the_part():
    from affordgrasp.metrics.use_geometry import contact_thickness, contact_width

    # a cleaver's blade: 100 x 60 x 3 mm; a finger on its spine (normal +y) has a 60 mm chord
    # along the normal, but the part is 3 mm wide across
    plate = trimesh.creation.box(extents=(0.1, 0.06, 0.003))
    C = np.array([[0.0, 0.03, 0.0], [0.01, 0.0, 0.0015]])
    N = np.array([[0, 1.0, 0], [0, 0, 1.0]])
    np.testing.assert_allclose(contact_thickness(plate, C, N, [0, 1, 2]), [0.06, 0.003], rtol=1e-6)
    np.testing.assert_allclose(contact_width(plate, C, N, [0, 1, 2]), [0.003, 0.003], rtol=1e-6)
    # a round handle, 16 mm across: the same along the normal and across
    handle = trimesh.creation.cylinder(radius=0.008, height=0.1, sections=256)
    got = contact_width(
        handle, [[0.008, 0, 0.01], [0, -0.008, 0.0]], [[1.0, 0, 0], [0, -1.0, 0]], [0, 2]
    )
    assert got[0] == pytest.approx(0.016, rel=1e-3)
    # the grasp's narrowest contact decides; no contact: +inf
    both = contact_width(plate, C, N, [0, 2, 2])
    assert both[0] == pytest.approx(0.003) and both[1] == np.inf
    with pytest.raises(InputError, match="directions"):
        contact_width(plate, C, N, [0, 2], directions=0)


def test_contact_width_in_one_cast_is_each_direction_cast_alone():
    """The chords across the part, cast together, are the chords cast one direction (and
    one half) at a time, bit for bit, on a mug's contacts."""
    from affordgrasp.metrics.use_geometry import (
        _THICKNESS_START_M,
        _first_exit,
        _frames,
        contact_thickness_and_width,
    )
    from affordgrasp.objects import load_object

    mesh = load_object("mug").mesh_data
    rng = np.random.default_rng(4)
    faces = rng.choice(len(mesh.faces), 300, replace=False)
    C = mesh.vertices[mesh.faces[faces]].mean(axis=1)
    N = mesh.face_normals[faces]
    offsets = np.arange(0, 301, 3)
    thickness, width = contact_thickness_and_width(mesh, C, N, offsets, directions=6)
    origins = C - _THICKNESS_START_M * N
    along = _first_exit(mesh, origins, -N)
    want = np.where(np.isfinite(along), along + _THICKNESS_START_M, 0.0)
    assert np.array_equal(thickness, want.reshape(-1, 3).min(axis=1))
    inside = np.isfinite(along)
    centre = origins[inside] - 0.5 * along[inside, None] * N[inside]
    e1, e2 = _frames(N[inside])
    for angle in np.arange(6) * np.pi / 6:
        d = np.cos(angle) * e1 + np.sin(angle) * e2
        chord = _first_exit(mesh, centre, d) + _first_exit(mesh, centre, -d)
        want[inside] = np.minimum(want[inside], chord)
    assert np.array_equal(width, want.reshape(-1, 3).min(axis=1))
    assert np.all(width <= thickness) and np.any(width < thickness)


def test_lever_ratio_compares_distances_to_the_wrist_axis():
    from affordgrasp.metrics.use_geometry import use_lever_ratio

    U = np.array([[0.3, 0, 0.5], [0.05, 0, 0]])
    W = np.zeros((2, 3))
    A = np.tile([0, 0, 1.0], (2, 1))
    np.testing.assert_allclose(use_lever_ratio(U, [0.2, 0, 0], W, A), [1.5, 0.25])
    # signed: the mass on the other side of the axis from U, or on it, is -inf; NaN stays NaN
    other = np.array([[-0.1, 0, 0], [0.1, 0, 0], [np.nan, 0, 0]])
    got = use_lever_ratio(other, [0.2, 0, 0], np.zeros((3, 3)), np.tile([0, 0, 1.0], (3, 1)))
    assert got[0] == -np.inf and got[1] == pytest.approx(0.5) and np.isnan(got[2])
    # only the lever's projection counts: the mass off to the side of U's lever
    side = use_lever_ratio([[0.2, 0, 0]], [0.1, 0.3, 0], np.zeros((1, 3)), [[0, 0, 1.0]])
    np.testing.assert_allclose(side, [2.0])


def test_contact_reach_is_the_farthest_contact_towards_the_use_end():
    from affordgrasp.metrics.use_geometry import contact_reach, long_axis

    # a rod along x: the long axis is x (either sign)
    rod = trimesh.creation.box(extents=(0.3, 0.02, 0.02))
    axis = long_axis(rod.moment_inertia)
    assert abs(axis[0]) == pytest.approx(1.0)
    c = np.zeros(3)
    contacts = np.array([[-0.10, 0.01, 0], [-0.05, -0.01, 0], [0.02, 0.01, 0], [0.1, 0, 0.01]])
    offsets = [0, 2, 4, 4]  # grasp 0 behind the mass, grasp 1 past it, grasp 2 no contact
    U = np.array([[0.14, 0, 0], [0.14, 0, 0], [0.14, 0, 0]])
    expected = np.array([-0.05, 0.1, -np.inf]) / 0.14  # a fraction of U's own offset
    np.testing.assert_allclose(contact_reach(contacts, offsets, U, c, axis), expected)
    # the sign of the axis does not matter; U on the other end mirrors the reach
    np.testing.assert_allclose(contact_reach(contacts, offsets, U, c, -axis), expected)
    got = contact_reach(contacts, offsets, [[-0.14, 0, 0]] * 2, c, axis, group=[0, 1])
    np.testing.assert_allclose(got, [0.10 / 0.14, -0.02 / 0.14])
    assert np.isnan(contact_reach(contacts, offsets, [[np.nan] * 3], c, axis, group=[0]))[0]
    with pytest.raises(InputError, match="axis"):
        contact_reach(contacts, offsets, U, c, [0, 0, 0])
    with pytest.raises(InputError, match="offsets"):
        contact_reach(contacts, [0, 2, 3], U[:2], c, axis)


def test_order_by_ray_is_the_two_key_sort():
    rng = np.random.default_rng(3)
    ray = rng.integers(0, 50, 2000)
    t = rng.uniform(0, 1, 2000)
    # in order within each ray (the usual case) and shuffled (the fallback), with ties
    for distances in (np.sort(t)[np.argsort(np.argsort(ray, kind="stable"))], t, np.round(t, 1)):
        got = use_geometry._order_by_ray(ray, distances)
        order = np.lexsort((distances, ray))
        assert np.array_equal(ray[got], ray[order]) and np.array_equal(
            distances[got], distances[order]
        )


ENGINES = [
    pytest.param("embree", marks=pytest.mark.skipif(not embree_available(), reason="no embreex")),
    "trimesh",
]


def _engine_rays(mesh: trimesh.Trimesh, engine: str):
    """The mesh's rays cast by Embree (as a prepared mesh's), or by trimesh's own engine."""
    if engine == "embree":
        return EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale)
    return mesh_caster(mesh)


def _box_with_debris():
    """A closed 20 mm cube and, 50 mm above it, one stray triangle (a scan's debris)."""
    box = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    stray = np.array([[-0.05, -0.05, 0.06], [0.05, -0.05, 0.06], [0.0, 0.05, 0.06]])
    vertices = np.concatenate([box.vertices, stray])
    faces = np.concatenate([box.faces, [[8, 9, 10]]])
    return trimesh.Trimesh(vertices, faces, process=False)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_ray_starts_inside_when_its_first_crossing_leaves(engine):
    """Up from 1 mm under the cube's top: leaving the cube, then crossing the debris. The
    parity of the two crossings says the ray starts outside; its first crossing, leaving
    the solid, says inside, and the 3 mm ball is inside up to the top face."""
    mesh = _box_with_debris()
    origins = np.array([[0.0, 0.0, 0.009], [0.0, 0.0, 0.009]])
    directions = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    rays = _engine_rays(mesh, engine)
    ray, t, inside = use_geometry._near_crossing_distances(rays, origins, directions, 3e-3)
    assert inside.tolist() == [True, True]
    w, w_in = use_geometry._ball_weights(ray, t, 3e-3, 2e-3, inside)
    np.testing.assert_allclose(w, [(1.0 / 3.0) ** 3, 1.0], rtol=1e-9)
    np.testing.assert_allclose(w_in, [(1.0 / 2.0) ** 3, 1.0], rtol=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_fold_within_the_ball_falls_back_to_the_parity(engine):
    """A cube and a 2 mm plate overlapping its top, as one self-intersecting surface: from
    0.8 mm under the top, a ray enters the plate before it leaves the cube (enter, leave,
    leave within 3 mm): the crossings do not alternate, and the parity of all of them
    (three: odd) decides, not the first (entering)."""
    a = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    b = trimesh.creation.box(extents=(0.02, 0.02, 0.002)).apply_translation([0, 0, 0.0105])
    mesh = trimesh.Trimesh(
        np.concatenate([a.vertices, b.vertices]),
        np.concatenate([a.faces, b.faces + len(a.vertices)]),
        process=False,
    )
    origins = np.array([[0.001, 0.002, 0.0092]])
    directions = np.array([[0.0, 0.0, 1.0]])
    rays = _engine_rays(mesh, engine)
    ray, t, inside = use_geometry._near_crossing_distances(rays, origins, directions, 3e-3)
    assert len(t) == 3 and t[2] < 3e-3
    assert inside.tolist() == [True]


def _ray_inside(ray, t, radius, starts_inside):
    """The inside weights by numpy (bincount), the reference of the compiled pass."""
    n_rays = len(starts_inside)
    within = t < radius
    ray, t = ray[within], t[within]
    start = np.searchsorted(ray, np.arange(n_rays))
    rank = np.arange(len(ray)) - start[ray]
    cube = (t / radius) ** 3
    inside = np.bincount(ray, weights=np.where(rank % 2 == 0, cube, -cube), minlength=n_rays)
    count = np.bincount(ray, minlength=n_rays)
    inside = inside + (count % 2 == 0)
    return np.where(starts_inside, inside, 1.0 - inside)


def _wedge_rays(mesh, n_faces: int, k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The wedge shape's rays at face centres: from 20 µm under the surface, k directions."""
    rng = np.random.default_rng(seed)
    faces = rng.choice(len(mesh.faces), n_faces, replace=False)
    centre = mesh.vertices[mesh.faces[faces]].mean(axis=1) - 2e-5 * mesh.face_normals[faces]
    sphere = use_geometry._fibonacci_sphere(k)
    return np.repeat(centre, k, axis=0), np.tile(sphere, (n_faces, 1))


@pytest.mark.parametrize("family", ["mug", "knife~scan"])
def test_ball_weights_are_numpys_bit_for_bit(family):
    mesh = load_object(family).mesh_data
    origins, directions = _wedge_rays(mesh, 200, 256, 2)
    rays = mesh_caster(mesh)
    ray, t, inside = use_geometry._near_crossing_distances(rays, origins, directions, 3e-3)
    w, w_in = use_geometry._ball_weights(ray, t, 3e-3, 2e-3, inside)
    assert np.array_equal(w, _ray_inside(ray, t, 3e-3, inside))
    assert np.array_equal(w_in, _ray_inside(ray, t, 2e-3, inside))
    assert 0.3 < w.mean() < 0.7 and np.all((w > -1e-12) & (w < 1 + 1e-12))
