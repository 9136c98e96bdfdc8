"""Hand effort on hold E_h and on impact E_i (effort.py, conventions: Metrics)."""

import numpy as np
import pytest
from metrics_support import random_contacts, ref_wrenches
from scipy.optimize import linprog

from affordgrasp.metrics import GRAVITY_DIRECTIONS, hold_effort, impact_effort
from affordgrasp.metrics.contacts import ContactSet


def dual_min_effort(W, b):
    """min 1·λ s.t. W λ = b, λ >= 0, through its dual max b·y s.t. Wᵀ y <= 1 (y free)."""
    res = linprog(-b, A_ub=W.T, b_ub=np.ones(W.shape[1]), bounds=(None, None), method="highs")
    if res.status == 3:  # dual unbounded: primal infeasible
        return np.inf
    assert res.status == 0
    return -res.fun


def test_gravity_along_two_antipodal_contacts_costs_exactly_one_newton():
    mu = 0.5
    cs = ContactSet.from_arrays([[0.05, 0, 0], [-0.05, 0, 0]], [[1, 0, 0], [-1, 0, 0]], mu)
    e = hold_effort(cs, np.zeros(3))
    assert e[0] == pytest.approx(1.0, abs=1e-12) and e[1] == pytest.approx(1.0, abs=1e-12)
    # sideways gravity is held by friction: 2 N_n mu = 1 (a cone edge lies along ±y)
    assert e[2] == pytest.approx(1 / mu, rel=1e-12) and e[3] == pytest.approx(1 / mu, rel=1e-12)
    np.testing.assert_allclose(hold_effort(cs, np.zeros(3), backend="highs"), e, rtol=1e-9)


def test_infeasible_is_inf_never_a_sentinel():
    one = ContactSet.from_arrays([[0, 0, 0.05]], [[0, 0, 1]], 0.5)
    e = hold_effort(one, np.zeros(3))
    # a single contact on top can push down (-z) only: gravity +z is held, the rest not
    assert e[4] == pytest.approx(1.0) and np.all(np.isinf(np.delete(e, 4)))
    assert np.all(np.isinf(hold_effort(ContactSet.empty(), np.zeros(3))))
    assert (
        impact_effort(ContactSet.empty(), np.zeros(3), [0, 0, 0.1], [0, 0, 1], [1, 0, 0]) == np.inf
    )
    assert impact_effort(one, np.zeros(3), [0.1, 0, 0], [1, 0, 0], [0, 1, 0]) == np.inf


def test_hold_effort_matches_the_dual_on_random_contact_sets():
    rng = np.random.default_rng(31)
    finite = infinite = 0
    for _ in range(110):
        cs = random_contacts(rng, int(rng.integers(1, 7)), spread=float(rng.uniform(0.1, 0.9)))
        center = rng.normal(size=3) * 0.01
        ours = hold_effort(cs, center)
        W = ref_wrenches(cs.points, cs.normals, cs.mu, center)
        for d, g in enumerate(GRAVITY_DIRECTIONS):
            ref = dual_min_effort(W, -np.concatenate([g, np.zeros(3)]))
            if np.isinf(ref):
                assert ours[d] == np.inf
                infinite += 1
            else:
                assert ours[d] == pytest.approx(ref, rel=1e-9, abs=1e-9)
                finite += 1
    assert finite > 100 and infinite > 100


def test_impact_effort_matches_the_dual_on_random_contact_sets():
    rng = np.random.default_rng(32)
    finite = infinite = 0
    for _ in range(110):
        cs = random_contacts(rng, int(rng.integers(1, 7)), spread=float(rng.uniform(0.1, 0.9)))
        center = rng.normal(size=3) * 0.01
        U = rng.normal(size=3)
        U = 0.1 * U / np.linalg.norm(U)
        nU = U / np.linalg.norm(U) + 0.3 * rng.normal(size=3)
        nU /= np.linalg.norm(nU)
        a = rng.normal(size=3)
        a /= np.linalg.norm(a)
        ours = impact_effort(cs, center, U, nU, a)
        W = ref_wrenches(cs.points, cs.normals, cs.mu, center)
        n_in = -nU
        w_use = np.concatenate([n_in, np.cross(U - center, n_in)])
        # dual of min 1·λ + 0·s, [W w_use] (λ, s) = -(0, a): max -(0,a)·y, Wᵀy <= 1, w_use·y <= 0
        A_ub = np.vstack([W.T, w_use])
        b_ub = np.concatenate([np.ones(W.shape[1]), [0.0]])
        rhs = np.concatenate([np.zeros(3), a])
        res = linprog(rhs, A_ub=A_ub, b_ub=b_ub, bounds=(None, None), method="highs")
        if res.status == 3:
            assert ours == np.inf
            infinite += 1
        else:
            assert res.status == 0
            assert ours == pytest.approx(-res.fun, rel=1e-9, abs=1e-9)
            assert impact_effort(cs, center, U, nU, a, backend="highs") == pytest.approx(
                ours, rel=1e-9
            )
            finite += 1
    assert finite > 30 and infinite > 10


def test_impact_effort_scales_as_inverse_length_and_hold_effort_is_invariant():
    rng = np.random.default_rng(33)
    cs = random_contacts(rng, 5, spread=0.2)
    U, nU, a = np.array([0.1, 0, 0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    base_i = impact_effort(cs, np.zeros(3), U, nU, a)
    base_h = hold_effort(cs, np.zeros(3))
    for s in (0.1, 7.0):
        scaled = ContactSet.from_arrays(cs.points * s, cs.normals, cs.mu)
        assert impact_effort(scaled, np.zeros(3), U * s, nU, a) == pytest.approx(
            base_i / s, rel=1e-9
        )
        np.testing.assert_allclose(hold_effort(scaled, np.zeros(3)), base_h, rtol=1e-9)
