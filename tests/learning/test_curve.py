"""The subsets, the fit and the settings check of learning curves (docs/learning.md, "Learning
curve")."""

import json
import math

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.learning import curve as lc


class _Rows:
    def __init__(self, objects, samples):
        self.object = np.array(objects, dtype=object)
        self.sample = np.array(samples)


FAMILIES = {"axe": ["axe:0", "axe:1", "axe:3"], "mug": ["mug:0", "mug:2"], "knife": ["knife:4"]}


def test_object_order_takes_every_family_in_turn_and_is_seeded():
    names = [o for objs in FAMILIES.values() for o in objs]
    fams = [f for f, objs in FAMILIES.items() for _ in objs]
    order = lc.object_order(names * 2, fams * 2, seed=0)  # one entry per row: repeats
    assert sorted(order) == sorted(names)
    # the first round has one object of each family, the second of each family left
    assert sorted(o.split(":")[0] for o in order[:3]) == ["axe", "knife", "mug"]
    assert sorted(o.split(":")[0] for o in order[3:5]) == ["axe", "mug"]
    assert order == lc.object_order(names, fams, seed=0)
    assert any(lc.object_order(names, fams, seed=s) != order for s in range(1, 6))


def test_subsets_are_nested():
    rows = _Rows(["a:0"] * 4 + ["b:0"] * 4 + ["c:0"] * 4, list(range(4)) * 3)
    order = ["b:0", "a:0", "c:0"]
    quarter = lc.keep_mask(rows, "samples:0.25", order, 4)
    half = lc.keep_mask(rows, "samples:0.5", order, 4)
    assert quarter.sum() == 3 and half.sum() == 6 and np.all(half[quarter])
    assert np.array_equal(rows.sample[half], [0, 1] * 3)
    third = lc.keep_mask(rows, "objects:0.34", order, 4)
    two = lc.keep_mask(rows, "objects:0.67", order, 4)
    assert set(rows.object[third]) == {"b:0"} and set(rows.object[two]) == {"a:0", "b:0"}
    assert lc.keep_mask(rows, "all", order, 4).all()
    with pytest.raises(InputError, match="unknown point 'rows:0.5'"):
        lc.keep_mask(rows, "rows:0.5", order, 4)
    with pytest.raises(InputError, match="must be in"):
        lc.keep_mask(rows, "objects:1.5", order, 4)


def test_fit_recovers_a_log_line_and_the_rows_for_the_goal():
    rows = [1000, 2000, 4000, 8000]
    points = [{"train_rows": n, "comparison_accuracy": 0.5 + 0.05 * math.log(n)} for n in rows]
    f = lc.fit_log_trend(points, 0.8)
    assert f["slope_per_ln_rows"] == pytest.approx(0.05)
    assert f["residual_sd"] == pytest.approx(0.0, abs=1e-12)
    assert f["rows_for_goal"] == pytest.approx(math.exp(0.3 / 0.05))
    flat = lc.fit_log_trend([{"train_rows": n, "comparison_accuracy": 0.6} for n in rows], 0.8)
    assert flat["rows_for_goal"] == math.inf
    assert lc.fit_log_trend(points[:2], 0.8) is None


def test_fit_of_a_plateau_says_never_instead_of_overflowing():
    # a tiny positive slope puts the goal at exp(>709) rows
    acc = [0.6785, 0.6786, 0.6783, 0.6787, 0.6786]
    rows = [1e4, 2e4, 4e4, 8e4, 1.2e5]
    f = lc.fit_log_trend(
        [{"train_rows": n, "comparison_accuracy": a} for n, a in zip(rows, acc, strict=True)], 0.8
    )
    assert f["slope_per_ln_rows"] > 0
    assert f["rows_for_goal"] == math.inf and f["rows_for_goal_slope_minus_se"] == math.inf


def test_a_finished_point_is_reused_only_with_the_same_settings(tmp_path):
    settings = lc.curve_settings(tmp_path / "data", 0, 0.02, None)
    path = tmp_path / "regressor-c3-s0-all.json"
    path.write_text(json.dumps({"comparison_accuracy": 0.6, "settings": settings}))
    lc.check_settings(path, settings)  # a resumed run: reused
    with pytest.raises(InputError, match="use another --out"):
        lc.check_settings(path, lc.curve_settings(tmp_path / "data", 0, 0.05, None))
    path.write_text(json.dumps({"comparison_accuracy": 0.6}))  # no settings: unknown
    with pytest.raises(InputError):
        lc.check_settings(path, settings)
