"""Friction cone edges and wrench matrices (cones.py, conventions: Metrics)."""

import numpy as np
import pytest
from metrics_support import ref_wrenches

from affordgrasp.metrics.cones import (
    SOFT_PATCH_RADIUS_M,
    contact_wrenches,
    edges_per_contact,
    friction_cone_edges,
    tangent_frames,
)


def test_edges_follow_graspit_convention():
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(20, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    mu = rng.uniform(0.1, 1.5, 20)
    edges = friction_cone_edges(normals, mu)
    assert edges.shape == (20, 8, 3)
    n_in = -normals
    # unit normal component: Σ edge weights = normal force
    np.testing.assert_allclose(np.einsum("kej,kj->ke", edges, n_in), 1.0, atol=1e-14)
    t1, t2 = tangent_frames(n_in)
    expected_t1 = np.cross(n_in, [1.0, 0, 0])
    expected_t1 /= np.linalg.norm(expected_t1, axis=1)[:, None]
    np.testing.assert_allclose(t1, expected_t1, atol=1e-15)
    np.testing.assert_allclose(t2, np.cross(n_in, t1), atol=1e-15)
    # edge 0 along +t1, edge 2 along +t2 (θ_j = 2πj/8)
    np.testing.assert_allclose(edges[:, 0], n_in + mu[:, None] * t1, atol=1e-15)
    np.testing.assert_allclose(edges[:, 2], n_in + mu[:, None] * t2, atol=1e-15)


def test_normal_along_x_switches_to_z_axis():
    edges = friction_cone_edges(np.array([[-1.0, 0, 0]]), 0.5)  # inward n = +x
    t1, _ = tangent_frames(np.array([[1.0, 0, 0]]))
    np.testing.assert_allclose(t1[0], [0, -1.0, 0], atol=1e-15)  # normalise(x × z)
    assert np.all(np.isfinite(edges))


def test_wrench_matrix_matches_independent_construction():
    rng = np.random.default_rng(1)
    points = rng.normal(size=(5, 3)) * 0.05
    normals = rng.normal(size=(5, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    mu = rng.uniform(0.2, 1.0, 5)
    center = rng.normal(size=3) * 0.01
    W = contact_wrenches(points, normals, mu, center, torque_scale=1 / 0.07)
    np.testing.assert_allclose(W, ref_wrenches(points, normals, mu, center, 1 / 0.07), atol=1e-14)


def test_soft_finger_edges_add_torsion_about_the_normal():
    points = np.array([[0.0, 0.0, 0.05]])
    normals = np.array([[0.0, 0.0, 1.0]])
    W = contact_wrenches(points, normals, 0.4, np.zeros(3), soft=True)
    assert W.shape == (6, edges_per_contact(True)) == (6, 10)
    gamma = 2 / 3 * 0.4 * SOFT_PATCH_RADIUS_M
    np.testing.assert_allclose(W[:, 8], [0, 0, -1, 0, 0, -gamma], atol=1e-15)
    np.testing.assert_allclose(W[:, 9], [0, 0, -1, 0, 0, gamma], atol=1e-15)
    np.testing.assert_allclose(W[:, :8], contact_wrenches(points, normals, 0.4, np.zeros(3)))


def test_empty_contact_set():
    assert contact_wrenches(np.zeros((0, 3)), np.zeros((0, 3)), 0.5, np.zeros(3)).shape == (6, 0)


@pytest.mark.parametrize("mu", [0.0, 2.0])
def test_extreme_friction(mu):
    e = friction_cone_edges(np.array([[0.0, 0.0, -1.0]]), mu)
    np.testing.assert_allclose(np.linalg.norm(e[0, :, :2], axis=1), mu, atol=1e-15)
