"""The wedge in a ball at U from rays: angle, span, thickness (wedge.py, conventions: Metrics)."""

import numpy as np
import pytest
import trimesh
from metrics_support import wedge_prism

from affordgrasp.metrics import wedge
from affordgrasp.objects import load_object
from affordgrasp.rays import embree_available
from affordgrasp.rays.mesh import EmbreeRays, mesh_caster


def _prism(opening_deg: float):
    """A 60 mm wedge prism along x, apex on the x axis, opening towards +y (closed)."""
    return wedge_prism(np.radians(opening_deg), length=0.06)


def test_wedge_angle_known_geometries():
    import trimesh

    from affordgrasp.metrics.wedge import use_wedge_angle

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
    from affordgrasp.metrics.wedge import use_wedge_angle
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

    from affordgrasp.metrics.wedge import use_edge_span, use_wedge_angle, use_wedge_shape

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
    from affordgrasp.metrics.wedge import use_wedge_shape
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

    from affordgrasp.metrics.wedge import use_wedge_shape

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

    from affordgrasp.metrics.wedge import use_edge_thickness, use_wedge_shape

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

    from affordgrasp.metrics.wedge import use_edge_thickness
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


def test_order_by_ray_is_the_two_key_sort():
    rng = np.random.default_rng(3)
    ray = rng.integers(0, 50, 2000)
    t = rng.uniform(0, 1, 2000)
    # in order within each ray (the usual case) and shuffled (the fallback), with ties
    for distances in (np.sort(t)[np.argsort(np.argsort(ray, kind="stable"))], t, np.round(t, 1)):
        got = wedge._order_by_ray(ray, distances)
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
    ray, t, inside = wedge._near_crossing_distances(rays, origins, directions, 3e-3)
    assert inside.tolist() == [True, True]
    w, w_in = wedge._ball_weights(ray, t, 3e-3, 2e-3, inside)
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
    ray, t, inside = wedge._near_crossing_distances(rays, origins, directions, 3e-3)
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
    sphere = wedge._fibonacci_sphere(k)
    return np.repeat(centre, k, axis=0), np.tile(sphere, (n_faces, 1))


@pytest.mark.parametrize("family", ["mug", "knife~scan"])
def test_ball_weights_are_numpys_bit_for_bit(family):
    mesh = load_object(family).mesh_data
    origins, directions = _wedge_rays(mesh, 200, 256, 2)
    rays = mesh_caster(mesh)
    ray, t, inside = wedge._near_crossing_distances(rays, origins, directions, 3e-3)
    w, w_in = wedge._ball_weights(ray, t, 3e-3, 2e-3, inside)
    assert np.array_equal(w, _ray_inside(ray, t, 3e-3, inside))
    assert np.array_equal(w_in, _ray_inside(ray, t, 2e-3, inside))
    assert 0.3 < w.mean() < 0.7 and np.all((w > -1e-12) & (w < 1 + 1e-12))


def test_edge_frame_is_the_bisector_and_the_edge_line():
    from affordgrasp.metrics.wedge import use_edge_frame

    # a 20° wedge along x opening towards +y: the bisector out of it is -y, the edge x,
    # also from a point on a flank 0.3 mm from the apex with the flank's normal
    prism = _prism(20.0)
    half = np.radians(10.0)
    flank = [0.005, 0.0003, 0.0003 * np.tan(half)]
    normal = [0.0, -np.sin(half), np.cos(half)]
    outward, along = use_edge_frame(prism, [[0.0, 0.0, 0.0], flank], [[0.0, -1.0, 0.0], normal])
    assert np.degrees(np.arccos(-outward[:, 1])).max() < 6.0
    assert np.degrees(np.arccos(np.abs(along[:, 0]))).max() < 2.0
    np.testing.assert_allclose(np.einsum("ij,ij->i", outward, along), 0.0, atol=1e-12)
    # a flat face: its normal, and a direction in it
    box = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    outward, along = use_edge_frame(box, [0.0, 0.0, 0.02], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(outward[0], [0.0, 0.0, 1.0], atol=1e-3)
    assert abs(along[0, 2]) < 1e-3 and np.linalg.norm(along[0]) == pytest.approx(1.0)
