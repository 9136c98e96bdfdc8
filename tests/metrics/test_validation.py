"""The batch check of contacts is the per-grasp check, done once on the stacked arrays."""

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.metrics.contacts import ContactSet
from affordgrasp.metrics.validation import contact_arrays, stacked_contact_arrays


def contact_sets(rng, n):
    out = []
    for g in range(n):
        k = int(rng.integers(0, 6))
        normals = rng.normal(size=(k, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        if g % 3 == 1 and k:
            normals[0] *= 1.0 + 1e-9  # one grasp's normal off unit: that grasp is rescaled
        out.append(
            ContactSet(
                rng.normal(size=(k, 3)), normals, rng.uniform(0, 1, k), np.array(["l"] * k, object)
            )
        )
    return out


@pytest.mark.parametrize("seed", range(4))
def test_stacked_is_each_grasp_checked_then_concatenated(seed):
    contacts = contact_sets(np.random.default_rng(seed), 25)
    points, normals, mu, offsets = stacked_contact_arrays(contacts)
    for g, c in enumerate(contacts):
        p, n, m = contact_arrays(c)
        rows = slice(offsets[g], offsets[g + 1])
        np.testing.assert_array_equal(points[rows], p)
        np.testing.assert_array_equal(normals[rows], n)  # bit for bit, rescaled or not
        np.testing.assert_array_equal(mu[rows], m)
    assert offsets[-1] == len(points) == len(normals) == len(mu)


def test_no_contacts_at_all():
    points, normals, mu, offsets = stacked_contact_arrays([ContactSet.empty()] * 3)
    assert points.shape == normals.shape == (0, 3) and mu.shape == (0,)
    assert offsets.tolist() == [0, 0, 0, 0]


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (dict(points=np.array([[np.nan, 0, 0]])), "finite"),
        (dict(mu=np.array([-0.1])), "friction"),
        (dict(normals=np.zeros((1, 3))), "non-zero"),
        (dict(mu=np.array([0.5, 0.5])), "inconsistent"),
    ],
)
def test_a_bad_grasp_among_good_ones_is_named(bad, message):
    good = ContactSet(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.array([0.5]), None)
    fields = dict(points=good.points, normals=good.normals, mu=good.mu, link=None) | bad
    with pytest.raises(InputError, match=message):
        stacked_contact_arrays([good, ContactSet(**fields), good])
    with pytest.raises(InputError, match="ContactSet"):
        stacked_contact_arrays([good, object()])
