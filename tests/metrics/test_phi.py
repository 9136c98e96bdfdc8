"""The metric vector Φ (phi.py): columns, consistency with the metric functions, invariances."""

import numpy as np
import pytest
import trimesh
from metrics_support import rotation_about_x, transform_mass

from affordgrasp.metrics import (
    METRIC_COLUMNS,
    compute_phi,
    compute_phi_batch,
    discharge,
    epsilon,
    hold_effort,
    impact_effort,
    rotational_inertia,
    use_edge,
    use_edge_angle,
    use_force,
    use_wedge_angle,
    use_wedge_shape,
)
from affordgrasp.metrics import phi as phi_module
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.objects.mass import mass_properties

EXPECTED_COLUMNS = [
    "epsilon", "gws_volume", "epsilon_reason", "inertia", "hold_effort_px", "hold_effort_nx",
    "hold_effort_py", "hold_effort_ny", "hold_effort_pz", "hold_effort_nz", "impact_effort",
    "discharge", "use_force", "use_edge", "use_edge_angle", "use_wedge_angle",
    "use_wedge_angle_fine", "use_edge_span", "use_edge_thickness", "use_clearance",
    "use_lever_ratio", "contact_reach",
    "use_depth", "use_relief", "use_swing_cosine",
    "contact_thickness", "contact_width", "epsilon_hand",
]  # fmt: skip


@pytest.fixture(scope="module")
def scene():
    """A box object and 12 grasps: no contact, one contact, and 3-12 surface contacts."""
    mesh = trimesh.creation.box(extents=(0.12, 0.06, 0.04))
    mesh = mesh.subdivide().subdivide()
    mesh.apply_translation([0.01, -0.02, 0.005])
    mass = mass_properties(mesh)
    rng = np.random.default_rng(0)
    contacts, U, nU, T, w, a = [], [], [], [], [], []
    for i in range(12):
        k = [0, 1, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12][i]
        pts, faces = trimesh.sample.sample_surface(mesh, k, seed=i) if k else (np.zeros((0, 3)), [])
        normals = mesh.face_normals[faces] if k else np.zeros((0, 3))
        contacts.append(ContactSet.from_arrays(pts, normals, rng.uniform(0.5, 1.0, k)))
        p, f = trimesh.sample.sample_surface(mesh, 1, seed=100 + i)
        U.append(p[0])
        T.append(f[0])
        nU.append(mesh.face_normals[f[0]])
        w.append(mass.center_of_mass + rng.normal(size=3) * 0.1)
        a.append(rng.normal(size=3))
    return mesh, mass, contacts, *map(np.asarray, (U, nU, T, w, a))


def _phi(scene, **kw):
    mesh, mass, contacts, U, nU, T, w, a = scene
    return compute_phi_batch(mass, mesh, contacts, U, nU, T, w, a, **kw)


def test_columns_are_exactly_the_spec_names(scene):
    cols = _phi(scene)
    assert list(cols) == EXPECTED_COLUMNS == list(METRIC_COLUMNS)
    for name, col in cols.items():
        assert col.shape == (12,)
        if name == "epsilon_reason":
            assert all(isinstance(r, str) for r in col)
        else:
            assert col.dtype == np.float64 and not np.any(np.isnan(col))


def test_batch_equals_the_metric_functions(scene):
    mesh, mass, contacts, U, nU, T, w, a = scene
    cols = _phi(scene)
    c, r = mass.center_of_mass, mass.r_max
    for i, cs in enumerate(contacts):
        e = epsilon(cs, c, r)
        assert cols["epsilon"][i] == e.epsilon and cols["gws_volume"][i] == e.volume
        assert cols["epsilon_reason"][i] == e.reason
        np.testing.assert_array_equal(
            [cols[f"hold_effort_{s}"][i] for s in ("px", "nx", "py", "ny", "pz", "nz")],
            hold_effort(cs, c),
        )
        assert cols["impact_effort"][i] == impact_effort(cs, c, U[i], nU[i], a[i])
        assert cols["use_force"][i] == use_force(cs, c, U[i], nU[i])
        assert cols["discharge"][i] == pytest.approx(discharge(U[i], nU[i], w[i], a[i]))
        assert cols["inertia"][i] == pytest.approx(rotational_inertia(mass, w[i], a[i]))
        assert cols["use_edge"][i] == pytest.approx(use_edge(mesh, T[i], U[i]))
        assert cols["use_edge_angle"][i] == use_edge_angle(mesh, U[i])
        assert cols["use_wedge_angle"][i] == pytest.approx(use_wedge_angle(mesh, U[i], nU[i]))
        shape = use_wedge_shape(mesh, U[i], nU[i])
        assert cols["use_wedge_angle_fine"][i] == pytest.approx(shape.inner_angle[0])
        assert cols["use_edge_span"][i] == pytest.approx(shape.span[0])
        assert cols["use_edge_thickness"][i] == pytest.approx(shape.edge_thickness[0], nan_ok=True)
        near = np.linalg.norm(cs.points - U[i], axis=1).min() if len(cs) else np.inf
        assert cols["use_clearance"][i] == pytest.approx(near)
        assert cols["epsilon_hand"][i] == cols["epsilon"][i]  # r_max 0.07 m: within 0.25 m
    empty = [i for i, cs in enumerate(contacts) if len(cs) == 0]
    assert empty and all(cols["epsilon_reason"][i] == "no contact" for i in empty)
    assert all(np.isinf(cols["hold_effort_px"][i]) and cols["use_force"][i] == 0 for i in empty)


def test_single_grasp_and_fallback_path(scene, monkeypatch):
    mesh, mass, contacts, U, nU, T, w, a = scene
    cols = _phi(scene)
    one = compute_phi(mass, mesh, contacts[5], U[5], nU[5], int(T[5]), w[5], a[5])
    assert list(one) == EXPECTED_COLUMNS
    assert isinstance(one["epsilon_reason"], str) and isinstance(one["epsilon"], float)
    for k, v in one.items():
        assert v == cols[k][5]
    # force every grasp through the reference solvers (HiGHS, qhull): same numbers
    real = phi_module.contact_metrics_batch

    def give_up(*args):
        out = real(*args)
        return (*out[:-1], np.ones_like(out[-1]))

    monkeypatch.setattr(phi_module, "contact_metrics_batch", give_up)
    slow = _phi(scene)
    for k in EXPECTED_COLUMNS:
        if k == "epsilon_reason":
            assert list(slow[k]) == list(cols[k])
        else:
            np.testing.assert_allclose(slow[k], cols[k], rtol=1e-9, atol=1e-12)


def _moved_scene(scene, R, t, s=1.0):
    mesh, mass, contacts, U, nU, T, w, a = scene
    M = np.eye(4)
    M[:3, :3] = s * R
    M[:3, 3] = t
    mesh2 = mesh.copy()
    mesh2.apply_transform(M)
    mass2 = transform_mass(mass, R, t, s)
    contacts2 = [
        ContactSet.from_arrays(s * cs.points @ R.T + t, cs.normals @ R.T, cs.mu) for cs in contacts
    ]
    return mesh2, mass2, contacts2, s * U @ R.T + t, nU @ R.T, T, s * w @ R.T + t, a @ R.T


SCALARS = ["epsilon", "gws_volume", "inertia", "impact_effort", "discharge", "use_force",
           "use_edge", "use_edge_angle"]  # fmt: skip


def test_translation_changes_nothing(scene):
    base = _phi(scene)
    moved = _phi(_moved_scene(scene, np.eye(3), np.array([0.3, -1.2, 2.0])))
    for k in SCALARS + [f"hold_effort_{s}" for s in ("px", "nx", "py", "ny", "pz", "nz")]:
        np.testing.assert_allclose(moved[k], base[k], rtol=1e-8, atol=1e-12, err_msg=k)


def test_rotations_that_keep_the_x_axis_line(scene):
    # GraspIt!'s tangent t1 = n × x: a rotation about x maps every cone onto the rotated
    # cone exactly, and so does a half turn about z (x -> -x maps edge j to edge j + 4).
    # Normals along ±x use t1 = n × z instead, which a rotation about x by φ turns by φ
    # about n: the octagon maps onto itself when φ is a multiple of π/4, so those angles
    # are exact for every contact (the box has contacts with normals ±x). Other rotations
    # turn the 8-edge polygons about their normals, which changes the linearised cones
    # (by up to 1 - cos(π/8) ≈ 8 %), so they are not exact invariances.
    base = _phi(scene)
    for angle in (np.pi / 4, -3 * np.pi / 4):
        moved = _phi(_moved_scene(scene, rotation_about_x(angle), np.array([0.1, 0.2, -0.3])))
        for k in SCALARS:
            np.testing.assert_allclose(moved[k], base[k], rtol=1e-7, atol=1e-11, err_msg=k)
    # quarter turn about x: gravity +y of the moved scene is gravity -z of the original
    moved = _phi(_moved_scene(scene, rotation_about_x(np.pi / 2), np.zeros(3)))
    perm = {"px": "px", "nx": "nx", "py": "nz", "ny": "pz", "pz": "py", "nz": "ny"}
    for new, old in perm.items():
        np.testing.assert_allclose(moved[f"hold_effort_{new}"], base[f"hold_effort_{old}"],
                                   rtol=1e-9, atol=1e-12)  # fmt: skip
    half_z = np.diag([-1.0, -1.0, 1.0])
    moved = _phi(_moved_scene(scene, half_z, np.zeros(3)))
    perm = {"px": "nx", "nx": "px", "py": "ny", "ny": "py", "pz": "pz", "nz": "nz"}
    for new, old in perm.items():
        np.testing.assert_allclose(moved[f"hold_effort_{new}"], base[f"hold_effort_{old}"],
                                   rtol=1e-9, atol=1e-12)  # fmt: skip
    for k in SCALARS:
        np.testing.assert_allclose(moved[k], base[k], rtol=1e-7, atol=1e-11, err_msg=k)


def test_uniform_scale(scene):
    s = 3.0
    base = _phi(scene)
    big = _phi(_moved_scene(scene, np.eye(3), np.zeros(3), s), edge_radius=0.003 * s)
    same = ["epsilon", "gws_volume", "discharge", "use_force", "use_edge_angle"] + [
        f"hold_effort_{x}" for x in ("px", "nx", "py", "ny", "pz", "nz")
    ]
    for k in same:
        np.testing.assert_allclose(big[k], base[k], rtol=1e-8, atol=1e-12, err_msg=k)
    np.testing.assert_allclose(big["inertia"], base["inertia"] * s**5, rtol=1e-9)
    np.testing.assert_allclose(big["impact_effort"], base["impact_effort"] / s, rtol=1e-8)
    np.testing.assert_allclose(big["use_edge"], base["use_edge"] / s**2, rtol=1e-6, atol=1e-9)


def test_soft_contacts_and_input_checks(scene):
    hard = _phi(scene)
    soft = _phi(scene, soft=True)
    assert np.all(soft["epsilon"] >= hard["epsilon"] - 1e-12)
    assert np.all(soft["hold_effort_pz"] <= hard["hold_effort_pz"] + 1e-9)
    mesh, mass, contacts, U, nU, T, w, a = scene
    from affordgrasp.errors import InputError

    with pytest.raises(InputError):
        compute_phi_batch(mass, mesh, contacts, U[:3], nU, T, w, a)
    empty = compute_phi_batch(mass, mesh, [], np.zeros((0, 3)), np.zeros((0, 3)), [],
                              np.zeros((0, 3)), np.zeros((0, 3)))  # fmt: skip
    assert list(empty) == EXPECTED_COLUMNS and all(len(v) == 0 for v in empty.values())


def test_without_volume_every_other_column_is_the_same(scene):
    full = _phi(scene)
    fast = _phi(scene, volume=False)
    closure = full["epsilon"] > 0
    assert closure.any()
    assert np.all(np.isnan(fast["gws_volume"][closure]))
    assert np.all(fast["gws_volume"][~closure] == 0.0)
    for name in full:
        if name in ("epsilon", "epsilon_hand"):
            np.testing.assert_allclose(fast[name], full[name], rtol=1e-9, atol=1e-12)
        elif name != "gws_volume":
            np.testing.assert_array_equal(fast[name], full[name])


def test_read_only_and_writable_objects_run_one_compiled_kernel(scene):
    # A cached object's arrays are read-only, a worker's unpickled copy's are writable;
    # numba types (and compiles) a kernel once per read-only flag, so a worker would
    # compile the metric kernels that the package ships for the in-process run.
    import dataclasses

    mesh, mass, *rest = scene
    center = np.array(mass.center_of_mass)
    frozen = center.copy()
    frozen.flags.writeable = False
    runs, signatures = [], []
    for c in (frozen, center):
        runs.append(compute_phi_batch(dataclasses.replace(mass, center_of_mass=c), mesh, *rest))
        signatures.append(set(phi_module.contact_metrics_batch.signatures))
    assert signatures[0] == signatures[1]
    for name in runs[0]:
        np.testing.assert_array_equal(runs[0][name], runs[1][name])
