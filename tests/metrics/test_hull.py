"""The compiled 6D hull against qhull (hull.py)."""

import numpy as np
import pytest
from metrics_support import cube_face_contacts, random_contacts, ref_wrenches
from scipy.spatial import ConvexHull

from affordgrasp.metrics.hull import HULL_DEGENERATE, HULL_OK, convex_hull_6d, hull_volume


def _compare_with_qhull(P):
    status, verts, normals, offsets, interior = convex_hull_6d(P)
    assert status == HULL_OK
    ref = ConvexHull(P, qhull_options="Qt Qx")
    # every point beneath every facet, every facet through its vertices
    assert np.max(P @ normals.T - offsets) <= 1e-10
    on_plane = np.einsum("fj,fvj->fv", normals, P[verts])
    np.testing.assert_allclose(on_plane, np.repeat(offsets[:, None], 6, axis=1), atol=1e-10)
    # the same supporting hyperplanes: ε-style minimum offset and the volume
    assert offsets.min() == pytest.approx(np.min(-ref.equations[:, -1]), rel=1e-9, abs=1e-12)
    assert hull_volume(P, verts, interior) == pytest.approx(ref.volume, rel=1e-9)
    # same vertex set
    assert set(np.unique(verts)) == set(ref.vertices)


def test_random_wrench_sets_match_qhull():
    rng = np.random.default_rng(11)
    compared = 0
    for _ in range(120):
        k = int(rng.integers(2, 6))
        cs = random_contacts(rng, k, spread=0.5)
        c = rng.normal(size=3) * 0.01
        W = ref_wrenches(cs.points, cs.normals, cs.mu, c, 1 / 0.06)
        if np.linalg.matrix_rank(W) < 6:
            continue  # flat sets are tested below; qhull refuses them
        _compare_with_qhull(np.ascontiguousarray(W.T))
        compared += 1
    # most random sets of 2-5 contacts are full rank: the comparison really ran
    assert compared >= 60, compared


@pytest.mark.parametrize("mu", [0.3, 0.5, 1.0])
def test_symmetric_sets_with_many_coplanar_wrenches(mu):
    cs = cube_face_contacts(0.05, mu)
    P = np.ascontiguousarray(ref_wrenches(cs.points, cs.normals, cs.mu, np.zeros(3), 1 / 0.0866).T)
    _compare_with_qhull(P)
    # the hypercube: highly degenerate (many points on each facet)
    cube = np.array(np.meshgrid(*[[-1.0, 1.0]] * 6)).reshape(6, -1).T.copy()
    _compare_with_qhull(cube)


def test_generic_points_and_duplicates():
    rng = np.random.default_rng(3)
    P = rng.normal(size=(60, 6))
    _compare_with_qhull(P)
    _compare_with_qhull(np.concatenate([P, P[:10]]))


def test_flat_sets_are_degenerate_not_errors():
    rng = np.random.default_rng(4)
    flat = rng.normal(size=(30, 6))
    flat[:, 5] = 0.3  # an affine hyperplane
    assert convex_hull_6d(flat)[0] == HULL_DEGENERATE
    assert convex_hull_6d(rng.normal(size=(5, 6)))[0] == HULL_DEGENERATE
    assert convex_hull_6d(np.zeros((10, 6)))[0] == HULL_DEGENERATE
