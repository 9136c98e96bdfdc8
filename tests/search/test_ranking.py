"""The one ranker: highest score first, −∞ and NaN never rank, ties by keys, order-free."""

from __future__ import annotations

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.search.ranking import TopRows, best_index, top_indices


def sorted_reference(values, *keys):
    """Indices of a full sort by (value descending, keys ascending, index), −∞/NaN dropped."""
    rows = [
        (-v, *(int(k[i]) for k in keys), i)
        for i, v in enumerate(values)
        if v > -np.inf  # False for NaN
    ]
    return [r[-1] for r in sorted(rows)]


def test_top_indices_equals_a_full_sort():
    rng = np.random.default_rng(0)
    values = rng.integers(0, 5, 300).astype(float)  # many ties
    values[rng.random(300) < 0.2] = -np.inf
    values[rng.random(300) < 0.1] = np.nan
    values[7] = np.inf  # +inf is a value: it ranks first
    key = rng.integers(0, 4, 300)
    for k in (1, 5, 300):
        assert top_indices(values, k, key).tolist() == sorted_reference(values, key)[:k]
    assert top_indices(values, 10).tolist() == sorted_reference(values)[:10]
    assert top_indices(values, 1)[0] == 7


def test_streamed_rows_do_not_depend_on_their_order():
    rng = np.random.default_rng(1)
    values = np.round(rng.normal(size=500), 1)
    values[::9] = -np.inf
    a, b = rng.integers(0, 3, 500), np.arange(500)
    whole = TopRows(12, 2)
    assert whole.add(values, a, b) == int(np.sum(values > -np.inf))
    streamed = TopRows(12, 2)
    perm = rng.permutation(500)
    for chunk in np.array_split(perm, 7):
        streamed.add(values[chunk], a[chunk], b[chunk])
    np.testing.assert_array_equal(streamed.values, whole.values)
    for s, w in zip(streamed.keys, whole.keys, strict=True):
        np.testing.assert_array_equal(s, w)
    assert whole.keys[1].tolist() == sorted_reference(values, a)[:12]


def test_nothing_ranks():
    assert best_index(np.array([-np.inf, np.nan])) is None
    assert len(top_indices(np.array([-np.inf, np.nan]), 3)) == 0
    assert len(top_indices(np.array([1.0, 2.0]), 0)) == 0
    assert best_index(np.array([np.nan, 2.0, 2.0, 1.0])) == 1  # the first of ties


@pytest.mark.parametrize("k", [-1, 1.5, True])
def test_bad_counts_are_refused(k):
    with pytest.raises(InputError, match="k"):
        top_indices(np.zeros(3), k)


def test_the_top_k_scan_breaks_ties_by_object_then_sample_then_seed():
    import pyarrow as pa

    from affordgrasp.search.best import scan_top
    from affordgrasp.tasks import make_task

    score = make_task("score", lambda m, t: m["score"], requires=("score",))
    rows = {
        "object": ["b", "a", "a", "b", "a", "a"],
        "sample": [0, 2, 1, 0, 1, 0],
        "seed": [0, 0, 9, 0, 3, 0],
        "score": [1.0, 1.0, 1.0, 2.0, 1.0, -np.inf],
    }
    table = pa.table(rows)
    batches = [table.slice(0, 3), table.slice(3)]  # the order rows arrive does not matter
    for tables in (batches, batches[::-1]):
        names, kept = scan_top(tables, [score], 4, objects=["a", "b"])
        found = kept[None, "score"]
        assert names == ["a", "b"] and (found.scanned, found.finite) == (6, 5)
        ranked = [(names[o], s, d) for o, s, d in zip(*found.best.keys, strict=True)]
        assert ranked == [("b", 0, 0), ("a", 1, 3), ("a", 1, 9), ("a", 2, 0)]
        _, per_object = scan_top(tables, [score], 2, per_object=True)
        _, samples, seeds = per_object["a", "score"].best.keys
        assert samples.tolist() == [1, 1] and seeds.tolist() == [3, 9]
