"""Convex decomposition keeps a mug's holes; mass and inertia come from the original mesh."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from affordgrasp.physics import PhysicsSettings
from affordgrasp.physics.decompose import _cache_path, convex_parts

# Coarser than the defaults, to keep the test fast; the holes must survive even so.
FAST = PhysicsSettings(
    coacd_resolution=300, coacd_mcts_iterations=20, coacd_mcts_nodes=8, coacd_mcts_depth=2
)


@pytest.fixture(scope="module")
def mug():
    from affordgrasp.objects import load_object

    return load_object("mug:0")


@pytest.fixture(scope="module")
def mug_parts(mug):
    return convex_parts(mug.mesh, mug.mesh_hash, FAST)


def _inside_any(parts, points):
    inside = np.zeros(len(points), dtype=bool)
    for v, f in parts:
        inside |= trimesh.Trimesh(v, f).contains(points)
    return inside


def _gaps_along_x(mesh, z, n=400):
    """Runs of points on the line y = 0, height z, that lie outside the mesh, between
    stretches inside it: the holes the line crosses, as arrays of points."""
    lo, hi = mesh.bounds
    xs = np.linspace(lo[0], hi[0], n)
    points = np.stack([xs, np.zeros(n), np.full(n, z)], axis=1)
    inside = mesh.contains(points)
    first, last = np.flatnonzero(inside)[[0, -1]]
    gaps, run = [], []
    for i in range(first, last + 1):
        if not inside[i]:
            run.append(points[i])
        elif run:
            gaps.append(np.array(run))
            run = []
    return gaps


def test_mug_keeps_its_cavity_and_handle_hole(mug, mug_parts):
    mesh = mug.mesh
    # Half way up the handle, the line y = 0 crosses the wall, the cavity, the wall, the
    # handle's hole and the handle: two gaps.
    zc = 0.5 * (mesh.bounds[0][2] + mesh.bounds[1][2])
    gaps = sorted(_gaps_along_x(mesh, zc), key=len, reverse=True)
    assert len(gaps) == 2, "the probe line should cross the cavity and the handle's hole"
    cavity, hole = gaps
    for name, gap in (("cavity", cavity), ("handle hole", hole)):
        core = gap[len(gap) // 4 : len(gap) - len(gap) // 4]  # the middle half of the gap
        covered = _inside_any(mug_parts, core)
        assert not covered.any(), f"the decomposition fills the mug's {name}"
    # The convex hull of the mug would fill both: the test can fail.
    assert _inside_any([(mesh.convex_hull.vertices, mesh.convex_hull.faces)], hole).all()


def test_decomposition_is_cached_and_seeded(mug, mug_parts, private_cache):
    path = _cache_path(mug.mesh_hash, FAST)
    assert path.is_file() and str(path).startswith(str(private_cache))
    again = convex_parts(mug.mesh, mug.mesh_hash, FAST)  # from the cache
    assert len(again) == len(mug_parts)
    for (v1, f1), (v2, f2) in zip(again, mug_parts, strict=True):
        np.testing.assert_array_equal(v1, v2)
        np.testing.assert_array_equal(f1, f2)


def test_decomposition_without_cache_is_deterministic():
    import trimesh.creation

    # An L-shaped block: non-convex, small, fast to decompose.
    a = trimesh.creation.box([0.06, 0.02, 0.02])
    b = trimesh.creation.box([0.02, 0.06, 0.02])
    b.apply_translation([-0.02, 0.02, 0.0])
    mesh = trimesh.boolean.union([a, b], engine="manifold")
    runs = [convex_parts(mesh, "l-block", FAST, use_cache=False) for _ in range(2)]
    assert len(runs[0]) >= 2  # really split
    for (v1, _), (v2, _) in zip(*runs, strict=True):
        np.testing.assert_array_equal(v1, v2)


def test_mass_and_inertia_come_from_the_original_mesh(mug, mug_parts):
    from affordgrasp.objects import mass_properties
    from affordgrasp.physics.scene import build_scene

    settings = PhysicsSettings(density=1200.0)
    scene = build_scene("parallel_jaw", mug, settings, parts=mug_parts)
    truth = mass_properties(mug.mesh, density=1200.0)
    m, body = scene.model, scene.object_body
    assert m.body_mass[body] == pytest.approx(truth.mass, rel=1e-9)
    np.testing.assert_allclose(m.body_ipos[body], truth.center_of_mass, atol=1e-12)
    principal = np.sort(np.linalg.eigvalsh(truth.inertia))
    np.testing.assert_allclose(np.sort(m.body_inertia[body]), principal, rtol=1e-6)
    # The parts' union is bigger than the mug (hulls overshoot its concave parts): a mass
    # taken from it would be wrong.
    parts_volume = sum(trimesh.Trimesh(v, f).volume for v, f in mug_parts)
    assert parts_volume > 1.02 * mug.mesh.volume
