"""ε and the GWS volume (epsilon.py, conventions: Metrics) against an independent qhull."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from metrics_support import cube_face_contacts, random_contacts, ref_wrenches
from scipy.spatial import ConvexHull, QhullError

from affordgrasp.errors import InputError
from affordgrasp.metrics import epsilon, gws_volume
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.epsilon import epsilon_from_wrenches_qhull


def reference_epsilon(cs, center, r_max):
    """ε and volume straight from the definition: qhull on all cone-edge wrenches."""
    W = ref_wrenches(cs.points, cs.normals, cs.mu, np.asarray(center), 1 / r_max)
    if W.shape[1] == 0 or np.linalg.matrix_rank(W, tol=1e-10 * np.abs(W).max()) < 6:
        return 0.0, 0.0
    try:
        hull = ConvexHull(W.T, qhull_options="Qt Qx")
    except QhullError:
        return 0.0, 0.0
    e = np.min(-hull.equations[:, -1])
    return (e, hull.volume) if e > 0 else (0.0, 0.0)


def test_two_antipodal_point_contacts_are_never_force_closure():
    for mu in (0.2, 1.0, 3.0):
        through_com = ContactSet.from_arrays(
            [[0.05, 0, 0], [-0.05, 0, 0]], [[1, 0, 0], [-1, 0, 0]], mu
        )
        res = epsilon(through_com, np.zeros(3), 0.1)
        assert res.epsilon == 0.0 and res.volume == 0.0
        assert res.reason in ("not force closure", "degenerate")
        off_axis = ContactSet.from_arrays(
            [[0.05, 0.02, 0], [-0.05, 0.02, 0]], [[1, 0, 0], [-1, 0, 0]], mu
        )
        res = epsilon(off_axis, np.zeros(3), 0.1)
        assert res.epsilon == 0.0 and res.reason in ("not force closure", "degenerate")


def test_no_contact():
    res = epsilon(ContactSet.empty(), np.zeros(3), 0.1)
    assert (res.epsilon, res.volume, res.reason) == (0.0, 0.0, "no contact")


def test_cube_face_centres_are_force_closure_and_match_qhull():
    cs = cube_face_contacts(0.05, 0.5)
    r_max = 0.05 * np.sqrt(3)
    res = epsilon(cs, np.zeros(3), r_max)
    e_ref, v_ref = reference_epsilon(cs, np.zeros(3), r_max)
    assert res.reason == "" and res.epsilon > 0
    assert res.epsilon == pytest.approx(e_ref, rel=1e-9)
    assert res.volume == pytest.approx(v_ref, rel=1e-9)


def test_tetrahedron_face_contacts():
    verts = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]]) * 0.03
    faces = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]
    centres = np.array([verts[f].mean(axis=0) for f in faces])
    normals = centres / np.linalg.norm(centres, axis=1)[:, None]
    cs = ContactSet.from_arrays(centres, normals, 0.6)
    res = epsilon(cs, np.zeros(3), 0.03 * np.sqrt(3))
    e_ref, v_ref = reference_epsilon(cs, np.zeros(3), 0.03 * np.sqrt(3))
    assert res.epsilon > 0 and res.epsilon == pytest.approx(e_ref, rel=1e-9)
    assert res.volume == pytest.approx(v_ref, rel=1e-9)


def test_random_contact_sets_match_qhull():
    rng = np.random.default_rng(21)
    closure = 0
    for _ in range(220):
        k = int(rng.integers(1, 7))
        cs = random_contacts(rng, k, spread=float(rng.uniform(0.1, 0.8)))
        center = rng.normal(size=3) * 0.005
        r_max = float(rng.uniform(0.05, 0.1))
        res = epsilon(cs, center, r_max)
        e_ref, v_ref = reference_epsilon(cs, center, r_max)
        assert res.epsilon == pytest.approx(e_ref, rel=1e-9, abs=1e-11)
        assert res.volume == pytest.approx(v_ref, rel=1e-9, abs=1e-15)
        assert (res.reason == "") == (res.epsilon > 0)
        closure += res.epsilon > 0
    assert 40 <= closure <= 200  # both outcomes well represented


def test_compiled_and_qhull_paths_agree():
    rng = np.random.default_rng(5)
    from affordgrasp.metrics.cones import contact_wrenches
    from affordgrasp.metrics.epsilon import REASONS, epsilon_kernel

    for _ in range(40):
        cs = random_contacts(rng, int(rng.integers(3, 7)))
        W = contact_wrenches(cs.points, cs.normals, cs.mu, np.zeros(3), torque_scale=1 / 0.07)
        a = epsilon_kernel(W)
        b = epsilon_from_wrenches_qhull(W)
        assert REASONS[a[0]] == REASONS[b[0]] or (a[1] == 0 and b[1] == 0)
        assert a[1] == pytest.approx(b[1], rel=1e-9, abs=1e-11)


def test_graspit_reference_point_and_radius_are_arguments():
    rng = np.random.default_rng(8)
    cs = random_contacts(rng, 5, spread=0.1)
    centroid = np.array([0.003, -0.002, 0.001])  # e.g. GraspIt!'s surface centroid
    for r_max in (0.04, 0.08):
        res = epsilon(cs, centroid, r_max)
        assert res.epsilon == pytest.approx(reference_epsilon(cs, centroid, r_max)[0], rel=1e-9)


def test_scale_invariance_and_soft_contacts_never_lower_epsilon():
    rng = np.random.default_rng(9)
    for _ in range(20):
        cs = random_contacts(rng, 4, spread=0.1)
        base = epsilon(cs, np.zeros(3), 0.06)
        for s in (0.01, 30.0):
            scaled = ContactSet.from_arrays(cs.points * s, cs.normals, cs.mu)
            res = epsilon(scaled, np.zeros(3), 0.06 * s)
            assert res.epsilon == pytest.approx(base.epsilon, rel=1e-9, abs=1e-12)
            assert res.volume == pytest.approx(base.volume, rel=1e-9, abs=1e-15)
        soft = epsilon(cs, np.zeros(3), 0.06, soft=True)
        assert soft.epsilon >= base.epsilon - 1e-12


def test_degenerate_inputs_never_crash():
    one = ContactSet.from_arrays([[0, 0, 0.05]], [[0, 0, 1]], 0.5)
    assert epsilon(one, np.zeros(3), 0.1).reason == "degenerate"
    frictionless = cube_face_contacts(0.05, 0.0)  # 8 identical edges per contact
    res = epsilon(frictionless, np.zeros(3), 0.1)
    assert res.epsilon == 0.0 and res.reason in ("degenerate", "not force closure")
    same = ContactSet.from_arrays([[0, 0, 0.05]] * 6, [[0, 0, 1]] * 6, 0.5)
    assert epsilon(same, np.zeros(3), 0.1).epsilon == 0.0
    collinear = ContactSet.from_arrays(
        [[0, 0, z] for z in (0.01, 0.02, 0.03)], [[1, 0, 0]] * 3, 1.0
    )
    assert epsilon(collinear, np.zeros(3), 0.1).epsilon == 0.0


def test_gws_volume_for_non_closure_hulls():
    rng = np.random.default_rng(12)
    cs = random_contacts(rng, 3, spread=0.05)
    W = ref_wrenches(cs.points, cs.normals, cs.mu, np.zeros(3), 1 / 0.05)
    assert gws_volume(cs, np.zeros(3), 0.05) == pytest.approx(ConvexHull(W.T).volume, rel=1e-9)
    assert gws_volume(ContactSet.empty(), np.zeros(3), 0.05) == 0.0


def test_bad_arguments():
    cs = cube_face_contacts()
    with pytest.raises(InputError):
        epsilon(cs, np.zeros(3), -1.0)
    with pytest.raises(InputError):
        epsilon(cs, [0, 0], 0.1)
    with pytest.raises(InputError):
        epsilon(np.zeros((3, 3)), np.zeros(3), 0.1)


def _box_face_contacts(rng, half, noise):
    """Contacts on 2-4 faces of a box, 1-3 per face: coplanar, with equal normals."""
    points, normals = [], []
    for face in rng.choice(6, size=int(rng.integers(2, 5)), replace=False):
        axis, sign = face // 2, (1.0 if face % 2 == 0 else -1.0)
        for _ in range(int(rng.integers(1, 4))):
            p = rng.uniform(-half, half)
            p[axis] = sign * half[axis]
            n = np.zeros(3)
            n[axis] = sign
            points.append(p)
            normals.append(n)
    normals = np.array(normals) + noise * rng.normal(size=(len(normals), 3))
    return np.array(points), normals / np.linalg.norm(normals, axis=1)[:, None]


def test_coplanar_contacts_with_equal_normals_match_qhull():
    # Such sets made the compiled hull build zero-volume facets whose offsets were taken
    # for ε (wrong by up to 0.2) or called force-closure grasps "not force closure".
    from affordgrasp.metrics.epsilon import closure_margin

    rng = np.random.default_rng(0)
    half = np.array([0.05, 0.03, 0.02])
    r_max = float(np.linalg.norm(half))
    closure = 0
    for trial in range(120):
        points, normals = _box_face_contacts(rng, half, 1e-10 if trial % 2 else 0.0)
        cs = ContactSet.from_arrays(points, normals, 0.4)
        res = epsilon(cs, np.zeros(3), r_max)
        e_ref, v_ref = reference_epsilon(cs, np.zeros(3), r_max)
        assert res.epsilon == pytest.approx(e_ref, rel=1e-9, abs=1e-11)
        assert res.volume == pytest.approx(v_ref, rel=1e-7, abs=1e-15)
        W = ref_wrenches(points, normals, 0.4, np.zeros(3), 1 / r_max)
        status, margin = closure_margin(np.ascontiguousarray(W))
        if status == 0 and margin > 1e-9:
            # the LP proved the origin strictly inside: ε > 0, never "degenerate"
            assert res.epsilon > 0 and res.reason == ""
        closure += res.epsilon > 0
    assert closure >= 20


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1))
def test_normal_noise_on_coplanar_contacts_moves_epsilon_continuously(seed):
    # 1e-10 of noise on the normals must move ε by about that much, not flip force closure.
    rng = np.random.default_rng(seed)
    half = np.array([0.05, 0.03, 0.02])
    points, normals = _box_face_contacts(rng, half, 0.0)
    noisy = normals + 1e-10 * rng.normal(size=normals.shape)
    noisy /= np.linalg.norm(noisy, axis=1)[:, None]
    r_max = float(np.linalg.norm(half))
    exact = epsilon(ContactSet.from_arrays(points, normals, 0.4), np.zeros(3), r_max)
    moved = epsilon(ContactSet.from_arrays(points, noisy, 0.4), np.zeros(3), r_max)
    assert moved.epsilon == pytest.approx(exact.epsilon, abs=1e-7)
    assert exact.epsilon == pytest.approx(
        reference_epsilon(ContactSet.from_arrays(points, normals, 0.4), np.zeros(3), r_max)[0],
        rel=1e-9,
        abs=1e-11,
    )


def test_epsilon_without_volume_is_the_same_epsilon():
    rng = np.random.default_rng(21)
    closure = 0
    for _ in range(60):
        cs = random_contacts(rng, int(rng.integers(2, 9)), spread=0.4)
        full = epsilon(cs, np.zeros(3), 0.06)
        fast = epsilon(cs, np.zeros(3), 0.06, volume=False)
        assert fast.reason == full.reason
        assert fast.epsilon == pytest.approx(full.epsilon, rel=1e-9, abs=1e-12)
        if full.epsilon > 0:
            closure += 1
            assert np.isnan(fast.volume)
        else:
            assert fast.volume == 0.0
    assert closure >= 10
