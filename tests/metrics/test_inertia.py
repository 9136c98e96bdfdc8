"""Rotational inertia about the wrist axis (inertia.py, conventions: Metrics)."""

import numpy as np
import pytest
import trimesh
from metrics_support import box_mass

from affordgrasp.metrics import rotational_inertia
from affordgrasp.objects.mass import mass_properties


def test_box_about_an_edge_and_through_its_centre():
    a, b, c = 0.2, 0.1, 0.05
    mass = box_mass((a, b, c))
    m = a * b * c
    # axis along z through the centre: m (a² + b²) / 12
    assert rotational_inertia(mass, [0, 0, 0], [0, 0, 1]) == pytest.approx(m * (a * a + b * b) / 12)
    # axis along z through an edge of the box: m (a² + b²) / 3 (parallel axes)
    edge = [a / 2, b / 2, 0.3]
    assert rotational_inertia(mass, edge, [0, 0, -2.0]) == pytest.approx(m * (a * a + b * b) / 3)


def test_thin_rod_about_its_end_is_m_l2_over_3():
    L, r = 0.5, 1e-4
    mass = box_mass((L, r, r))
    m = L * r * r
    assert rotational_inertia(mass, [-L / 2, 0, 0], [0, 1, 0]) == pytest.approx(
        m * L * L / 3, rel=1e-6
    )
    # along its own axis: almost nothing
    assert rotational_inertia(mass, [0, 0, 0], [1, 0, 0]) < 1e-6 * m * L * L


def test_oblique_axis_matches_a_direct_formula_and_mesh_mass_properties():
    mesh = trimesh.creation.box(extents=(0.1, 0.04, 0.02))
    mesh.apply_translation([0.01, 0.02, -0.03])
    mass = mass_properties(mesh)
    w = np.array([0.05, -0.1, 0.2])
    axis = np.array([1.0, 2.0, -0.5])
    u = axis / np.linalg.norm(axis)
    r = mass.center_of_mass - w
    d2 = r @ r - (r @ u) ** 2
    expected = u @ mass.inertia @ u + mass.mass * d2
    assert rotational_inertia(mass, w, axis) == pytest.approx(expected, rel=1e-12)
    ref = box_mass((0.1, 0.04, 0.02), center=(0.01, 0.02, -0.03))
    assert rotational_inertia(ref, w, axis) == pytest.approx(expected, rel=1e-9)


def test_vectorised_and_scales_as_s5():
    mass = box_mass((0.2, 0.1, 0.05))
    rng = np.random.default_rng(0)
    w, a = rng.normal(size=(20, 3)) * 0.1, rng.normal(size=(20, 3))
    values = rotational_inertia(mass, w, a)
    assert values.shape == (20,)
    np.testing.assert_allclose(values, [rotational_inertia(mass, w[i], a[i]) for i in range(20)])
    s = 3.0
    big = box_mass((0.2 * s, 0.1 * s, 0.05 * s))
    np.testing.assert_allclose(rotational_inertia(big, w * s, a), values * s**5, rtol=1e-12)
