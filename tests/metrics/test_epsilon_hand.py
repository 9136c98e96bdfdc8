"""ε at a hand's torque length (epsilon_hand.py): ε itself within r_ref, bounded beyond it."""

import numpy as np
import pytest
from metrics_support import cube_face_contacts, random_contacts

from affordgrasp.metrics import epsilon
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.epsilon_hand import (
    EPSILON_HAND_LENGTH_M,
    epsilon_hand,
    epsilon_torque_length,
)


def _stacked(sets):
    points = np.concatenate([c.points for c in sets])
    normals = np.concatenate([c.normals for c in sets])
    mu = np.concatenate([c.mu for c in sets])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in sets])])
    return points, normals, mu, offsets


def _grasps(rng, n=30):
    sets = [random_contacts(rng, int(rng.integers(2, 7)), radius=0.04) for _ in range(n)]
    sets.append(cube_face_contacts(0.03, 0.5))
    return sets


@pytest.mark.parametrize("r_max", [0.05, 0.2, EPSILON_HAND_LENGTH_M])
def test_objects_within_the_reference_length_keep_epsilon_bit_for_bit(r_max):
    rng = np.random.default_rng(0)
    sets = _grasps(rng)
    eps = np.array([epsilon(c, np.zeros(3), r_max, volume=False).epsilon for c in sets])
    out = epsilon_hand(*_stacked(sets), np.zeros(3), r_max, eps)
    assert np.array_equal(out, eps)
    assert epsilon_torque_length(r_max) == r_max


def test_long_objects_get_epsilon_at_the_reference_length_and_its_bounds():
    rng = np.random.default_rng(1)
    sets = _grasps(rng, 60)
    r_max = 0.7  # a sword
    eps = np.array([epsilon(c, np.zeros(3), r_max, volume=False).epsilon for c in sets])
    assert (eps > 0).sum() >= 5  # the test sees force-closure grasps
    out = epsilon_hand(*_stacked(sets), np.zeros(3), r_max, eps)
    ref = np.array(
        [epsilon(c, np.zeros(3), EPSILON_HAND_LENGTH_M, volume=False).epsilon for c in sets]
    )
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-15)
    # the torque coordinates stretched by r_max / L: closure kept, ε <= ε_hand <= ε r_max / L
    assert np.array_equal(out > 0, eps > 0)
    assert np.all(out >= eps)
    assert np.all(out <= eps * r_max / EPSILON_HAND_LENGTH_M * (1 + 1e-9))
    # the cube's grasp is limited by torque at this scale: the gate moves
    assert out[-1] > eps[-1] * 1.01


def test_the_same_torque_in_newton_metres_passes_on_any_length():
    # one grasp, seen on objects of growing r_max: ε falls as 1/r_max once torque-limited,
    # ε_hand stays at its value for r_max = r_ref
    cs = cube_face_contacts(0.03, 0.5)
    values = []
    for r_max in (0.25, 0.4, 0.8, 1.6):
        eps = epsilon(cs, np.zeros(3), r_max, volume=False).epsilon
        values.append(epsilon_hand(cs.points, cs.normals, cs.mu, [0, 6], np.zeros(3), r_max, [eps]))
    np.testing.assert_allclose(np.concatenate(values), values[0][0], rtol=1e-9)


def test_no_contact_and_bad_input():
    empty = ContactSet.empty()
    out = epsilon_hand(empty.points, empty.normals, empty.mu, [0, 0], np.zeros(3), 0.7, [0.0])
    assert out.tolist() == [0.0]
    with pytest.raises(ValueError, match="offsets"):
        epsilon_hand(empty.points, empty.normals, empty.mu, [0], np.zeros(3), 0.7, [0.0])
