"""Momentum discharge efficiency δ (discharge.py, conventions: Metrics)."""

import numpy as np
import pytest

from affordgrasp.metrics import discharge


def test_normal_along_the_swing_velocity_with_perpendicular_lever_is_one():
    w = np.array([0.0, 0.0, 0.0])
    a = np.array([0.0, 0.0, 1.0])
    U = np.array([0.3, 0.0, 0.0])  # lever ⊥ a
    velocity = np.cross(a, U - w)  # +y
    assert discharge(U, velocity, w, a) == pytest.approx(1.0, abs=1e-15)


def test_force_line_through_the_axis_or_pushing_forward_is_zero():
    w, a = np.zeros(3), np.array([0.0, 0.0, 1.0])
    U = np.array([0.3, 0.0, 0.0])
    assert discharge(U, [1.0, 0, 0], w, a) == 0.0  # force line through the wrist point
    assert discharge(U, [0, 0, 1.0], w, a) == 0.0  # force parallel to the axis: moment ⊥ a
    assert discharge(U, [0, -1.0, 0], w, a) == 0.0  # would accelerate the swing
    assert discharge(w, [0, 1.0, 0], w, a) == 0.0  # use point on the wrist point


def test_partial_alignment_is_the_cosine():
    w, a = np.zeros(3), np.array([0.0, 0.0, 1.0])
    U = np.array([0.3, 0.0, 0.4])  # lever tilted out of the swing plane
    n = np.array([0.0, 1.0, 0.0])
    M = np.cross(U - w, -n)
    assert discharge(U, n, w, a) == pytest.approx(-M @ a / np.linalg.norm(M), rel=1e-14)
    assert discharge(U, n, w, a) == pytest.approx(0.6, rel=1e-14)


def test_vectorised_and_invariant():
    rng = np.random.default_rng(0)
    U, n, w, a = (rng.normal(size=(50, 3)) for _ in range(4))
    d = discharge(U, n, w, a)
    assert d.shape == (50,) and np.all((d >= 0) & (d <= 1))
    singles = [discharge(U[i], n[i], w[i], a[i]) for i in range(50)]
    np.testing.assert_allclose(d, singles, rtol=1e-14)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    Q *= np.sign(np.linalg.det(Q))
    t = rng.normal(size=3)
    moved = discharge(3 * U @ Q.T + t, n @ Q.T, 3 * w @ Q.T + t, a @ Q.T)
    np.testing.assert_allclose(moved, d, atol=1e-12)
