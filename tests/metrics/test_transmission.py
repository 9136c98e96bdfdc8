"""Force transmitted to use U_τ (transmission.py, conventions: Metrics)."""

import numpy as np
import pytest
from metrics_support import random_contacts, ref_wrenches
from scipy.optimize import linprog

from affordgrasp.metrics import use_force
from affordgrasp.metrics.contacts import ContactSet


def reference_use_force(cs, center, U, nU):
    """max F with inequality rows for the normal-force bounds (no slack variables)."""
    W = ref_wrenches(cs.points, cs.normals, cs.mu, center)
    k, n = len(cs.points), W.shape[1]
    if k == 0:
        return 0.0
    n_in = -nU / np.linalg.norm(nU)
    w_use = np.concatenate([n_in, np.cross(U - center, n_in)])
    A_eq = np.hstack([W, w_use[:, None]])
    A_ub = np.zeros((k, n + 1))
    for i in range(k):
        A_ub[i, 8 * i : 8 * i + 8] = 1.0
    c = np.zeros(n + 1)
    c[-1] = -1.0
    res = linprog(
        c, A_ub=A_ub, b_ub=np.ones(k), A_eq=A_eq, b_eq=np.zeros(6), bounds=(0, None), method="highs"
    )
    assert res.status == 0
    return -res.fun


def test_one_contact_straight_behind_the_use_point_transmits_one_newton():
    cs = ContactSet.from_arrays([[-0.05, 0, 0]], [[-1, 0, 0]], 0.5)
    F = use_force(cs, np.zeros(3), [0.05, 0, 0], [1, 0, 0])
    assert F == pytest.approx(1.0, abs=1e-12)
    two = ContactSet.from_arrays([[-0.05, 0.01, 0], [-0.05, -0.01, 0]], [[-1, 0, 0]] * 2, 0.5)
    assert use_force(two, np.zeros(3), [0.05, 0, 0], [1, 0, 0]) == pytest.approx(2.0, abs=1e-12)
    assert use_force(cs, np.zeros(3), [0.05, 0, 0], [1, 0, 0], backend="highs") == pytest.approx(
        1.0
    )


def test_zero_when_nothing_can_be_transmitted():
    assert use_force(ContactSet.empty(), np.zeros(3), [0.05, 0, 0], [1, 0, 0]) == 0.0
    # the only contact is on the same side as the use point: it cannot push towards it
    same_side = ContactSet.from_arrays([[0.05, 0, 0.01]], [[1, 0, 0]], 0.3)
    assert use_force(same_side, np.zeros(3), [0.05, 0, 0], [1, 0, 0]) == pytest.approx(
        0.0, abs=1e-12
    )


def test_matches_an_independent_formulation_on_random_contact_sets():
    rng = np.random.default_rng(41)
    positive = 0
    for _ in range(110):
        cs = random_contacts(rng, int(rng.integers(1, 7)), spread=float(rng.uniform(0.1, 0.9)))
        center = rng.normal(size=3) * 0.01
        U = rng.normal(size=3)
        U = 0.08 * U / np.linalg.norm(U)
        nU = U / np.linalg.norm(U) + 0.3 * rng.normal(size=3)
        ours = use_force(cs, center, U, nU)
        assert ours == pytest.approx(reference_use_force(cs, center, U, nU), rel=1e-9, abs=1e-9)
        positive += ours > 1e-9
    assert 20 < positive < 110


def test_scale_invariant():
    rng = np.random.default_rng(42)
    cs = random_contacts(rng, 5, spread=0.3)
    U, nU = np.array([0.06, 0.01, 0]), np.array([1.0, 0.2, 0])
    base = use_force(cs, np.zeros(3), U, nU)
    scaled = ContactSet.from_arrays(cs.points * 5, cs.normals, cs.mu)
    assert use_force(scaled, np.zeros(3), U * 5, nU) == pytest.approx(base, rel=1e-9, abs=1e-12)
