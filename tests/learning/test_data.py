"""Splits by object instance and by family; balanced sampling; target scales."""

import numpy as np
import pytest

from affordgrasp.dataset.splits import split_by_family, split_by_object
from affordgrasp.errors import InputError
from affordgrasp.learning.data import balanced_indices
from affordgrasp.learning.targets import (
    make_target,
    target_column,
    target_rows,
    target_values,
    threshold_target,
)

OBJECTS = [f"{f}:{i}" for f in ("knife", "mug", "axe") for i in range(5)] + ["cone:0"]
FAMILIES = [o.split(":")[0] for o in OBJECTS]


def test_split_by_object_is_disjoint_seeded_and_categories_overlap():
    split = split_by_object(OBJECTS, FAMILIES, seed=0)
    parts = [set(split.train), set(split.val), set(split.test)]
    assert sum(map(len, parts)) == len(OBJECTS)
    assert not (parts[0] & parts[1] or parts[0] & parts[2] or parts[1] & parts[2])
    for fam in ("knife", "mug", "axe"):  # every family with >= 3 instances is in all parts
        for part in parts:
            assert any(o.startswith(fam + ":") for o in part)
    assert "cone:0" in split.train  # a family with one instance only trains
    assert split == split_by_object(OBJECTS, FAMILIES, seed=0)
    assert split != split_by_object(OBJECTS, FAMILIES, seed=1)


def test_split_by_family_holds_out_whole_families():
    split = split_by_family(OBJECTS, FAMILIES, ["mug"], seed=0)
    assert set(split.test) == {f"mug:{i}" for i in range(5)}
    assert not any(o.startswith("mug") for o in split.train + split.val)
    with pytest.raises(InputError, match="not in the dataset"):
        split_by_family(OBJECTS, FAMILIES, ["spoon"])


def test_balanced_indices():
    labels = np.array([1, 0, 0, 0, 0, 1, 0, 0])
    idx = balanced_indices(labels, seed=0)
    assert labels[idx].sum() == 2 and len(idx) == 4
    np.testing.assert_array_equal(idx, balanced_indices(labels, seed=0))


def test_targets():
    t = make_target("hold_effort_sum")
    assert t.kind == "regression" and t.rows == "viable" and t.lower_is_better
    np.testing.assert_allclose(t.denormalise(t.normalise(np.array([10.0, 125.0]))), [10, 125])
    g = make_target("epsilon", np.array([0.0, 0.01, 0.02, np.inf]))
    assert g.rows == "finite" and not g.lower_is_better and g.low == 0.0
    lg = make_target("impact_effort", np.linspace(0, 100, 101), log=True)
    np.testing.assert_allclose(lg.denormalise(lg.normalise(np.array([5.0, 50.0]))), [5, 50])
    assert make_target("viable").kind == "classification"


def test_thresholded_classification_target():
    t = make_target("robust_viable>=0.50")
    assert (t.name, t.kind, t.rows) == ("robust_viable>=0.5", "classification", "all")
    assert threshold_target(t.name) == ("robust_viable", 0.5)
    assert target_column(t.name) == "robust_viable"
    assert target_column("viable") is None and target_column("task:pick") is None
    assert target_column("robust_hold") == "robust_hold"
    columns = {"robust_viable": np.array([0.0, 0.48, 0.5, 0.52, 1.0, np.nan])}
    # the level itself counts as reached; an unknown (NaN) rate does not
    assert target_values(t.name, columns).tolist() == [0, 0, 1, 1, 1, 0]
    assert target_rows(t, columns).all()
    for bad in ("robust_viable>=", ">=0.5", "robust_viable>=high", "robust_viable>=inf"):
        with pytest.raises(InputError, match="COLUMN>=LEVEL"):
            make_target(bad)
