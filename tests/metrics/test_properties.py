"""Property tests: monotonicity of the contact metrics in the contact set (hypothesis)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from metrics_support import random_contacts

from affordgrasp.metrics import epsilon, hold_effort, impact_effort, use_force
from affordgrasp.metrics.contacts import ContactSet

U = np.array([0.08, 0.0, 0.0])
NU = np.array([1.0, 0.0, 0.0])
AXIS = np.array([0.0, 0.0, 1.0])


def _with_one_more(cs: ContactSet, extra: ContactSet) -> ContactSet:
    return ContactSet.from_arrays(
        np.concatenate([cs.points, extra.points]),
        np.concatenate([cs.normals, extra.normals]),
        np.concatenate([cs.mu, extra.mu]),
    )


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(0, 5), spread=st.floats(0.05, 0.9))
def test_adding_a_contact_never_hurts(seed, k, spread):
    rng = np.random.default_rng(seed)
    cs = random_contacts(rng, k, spread=spread) if k else ContactSet.empty()
    more = _with_one_more(cs, random_contacts(rng, 1, spread=spread))
    c = np.zeros(3)
    # the wrench set only grows: ε never decreases
    assert epsilon(more, c, 0.07).epsilon >= epsilon(cs, c, 0.07).epsilon - 1e-12
    # an LP with one more non-negative variable group: minima never increase
    h0, h1 = hold_effort(cs, c), hold_effort(more, c)
    assert np.all((h1 <= h0 + 1e-9 * (1 + np.where(np.isfinite(h0), h0, 0))) | np.isinf(h0))
    i0, i1 = impact_effort(cs, c, U, NU, AXIS), impact_effort(more, c, U, NU, AXIS)
    assert i1 <= i0 + 1e-9 * (1 + i1) or np.isinf(i0)
    # ... and the maximum transmitted force never decreases
    assert use_force(more, c, U, NU) >= use_force(cs, c, U, NU) - 1e-9


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 6))
def test_efforts_are_bounded_below_by_the_load(seed, k):
    # every edge force has norm sqrt(1 + μ²), so balancing 1 N of gravity needs a normal
    # force sum of at least 1 / sqrt(1 + μ_max²)
    rng = np.random.default_rng(seed)
    cs = random_contacts(rng, k)
    h = hold_effort(cs, np.zeros(3))
    bound = 1.0 / np.sqrt(1.0 + cs.mu.max() ** 2)
    assert np.all(h >= bound - 1e-9)
