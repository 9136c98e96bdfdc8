"""The task probabilities p_beat, p_cut, p_pick: the shipped models and the tasks built on them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from affordgrasp.errors import TaskError
from affordgrasp.tasks import get_task
from affordgrasp.tasks.metric_columns import MetricColumns
from affordgrasp.tasks.probability import (
    MODEL_COLUMNS,
    TaskModel,
    probability_columns,
    task_model,
    transform_column,
)


def _stump_model() -> TaskModel:
    # two trees on two features: x0 <= 1 -> -1 else +1 (NaN left); x1 <= 0 -> 0 else 2
    arrays = {
        "feature": np.array([0, -1, -1, 1, -1, -1]),
        "threshold": np.array([1.0, 0, 0, 0.0, 0, 0]),
        "left": np.array([1, 0, 0, 4, 0, 0]),
        "right": np.array([2, 0, 0, 5, 0, 0]),
        "nan_left": np.array([True, False, False, False, False, False]),
        "value": np.array([0.0, -1.0, 1.0, 0.0, 0.0, 2.0]),
        "roots": np.array([0, 3]),
    }
    return TaskModel(
        "beat", False, ("a", "b"), ("raw", "raw"), "trees", arrays, 0.5,
        np.array([-1.0, 3.0]), np.array([0.0, 1.0]),
    )  # fmt: skip


def test_trees_are_walked_as_written_and_calibrated_by_the_knots():
    m = _stump_model()
    x = np.array([[0.0, -1.0], [2.0, -1.0], [2.0, 1.0], [np.nan, 1.0], [1.0, np.nan]])
    # bias 0.5 + tree 1 + tree 2; NaN in x1 goes right (nan_left False)
    np.testing.assert_array_equal(m.raw_score(x), [-0.5, 1.5, 3.5, 1.5, 2.5 - 1.0 + 0.0 + 0.0])
    p = m.predict({"a": x[:, 0], "b": x[:, 1]})
    np.testing.assert_allclose(p, np.clip((m.raw_score(x) + 1.0) / 4.0, 0.0, 1.0))


def test_a_model_survives_its_file_and_a_bad_file_is_named():
    m = _stump_model()
    again = TaskModel.from_dict(json.loads(json.dumps(m.to_dict())))
    x = np.random.default_rng(0).normal(size=(50, 2))
    np.testing.assert_array_equal(again.raw_score(x), m.raw_score(x))
    with pytest.raises(TaskError, match="not a task probability model"):
        TaskModel.from_dict({"format": "something else"})


def test_missing_columns_are_named():
    with pytest.raises(TaskError, match="p_beat needs the metric columns b"):
        _stump_model().predict({"a": np.zeros(3)})


def test_effort_transform_reads_infinite_effort_as_zero():
    x = transform_column(np.array([0.0, 1.0, np.inf, np.nan, -2.0]), "inv1p")
    np.testing.assert_array_equal(x[[0, 1, 2, 4]], [1.0, 0.5, 0.0, 1.0])
    assert np.isnan(x[3])


def _rows(n: int = 300, seed: int = 0) -> dict:
    """Plausible metric rows (every model column)."""
    rng = np.random.default_rng(seed)
    cols = {c: rng.uniform(0.0, 1.0, n) for c in MODEL_COLUMNS}
    for c in MODEL_COLUMNS:
        if c.startswith("hold_effort") or c == "impact_effort":
            cols[c] = rng.exponential(20.0, n)
    cols["epsilon"] = cols["epsilon_hand"] = rng.uniform(0.0, 0.1, n)
    cols["use_wedge_angle"] = rng.uniform(0.3, 3.1, n)
    cols["hold_dirs"] = rng.integers(0, 7, n).astype(float)
    cols["inertia"] = rng.uniform(1e-4, 1e-2, n)  # read by the tie-break of beat only
    return cols


@pytest.mark.parametrize("task", ["beat", "cut", "pick"])
def test_shipped_models_rise_with_the_grip(task):
    # fitted with monotone constraints: a larger ε_hand or a smaller hold effort never lowers p
    model = task_model(task)
    rows = _rows()
    p = model.predict(rows)
    assert np.all((p >= 0) & (p <= 1))
    stronger = dict(rows, epsilon_hand=rows["epsilon_hand"] + 0.05)
    assert np.all(model.predict(stronger) >= p - 1e-12)
    lighter = dict(rows, hold_effort_px=rows["hold_effort_px"] * 0.5)
    assert np.all(model.predict(lighter) >= p - 1e-12)
    assert model.card["label"] == f"{task}_ok" and "held_out" in model.card


def test_probability_columns_and_the_tasks_that_rank_by_them():
    rows = _rows()
    rows["use_depth"][:5] = np.nan  # no use point
    m = MetricColumns(rows)
    p = probability_columns(m)
    assert set(p) == {"p_beat", "p_cut", "p_pick"}
    assert np.all(p["p_beat"][:5] == 0) and np.all(p["p_cut"][:5] == 0)
    for task, paper in (("beat", "beat-paper"), ("cut", "cut-ug"), ("pick", "pick-paper")):
        t = get_task(task)
        assert t.probability and not get_task(paper).probability
        v = t.evaluate(m)
        assert np.all(np.isfinite(v)) and np.all((v >= 0) & (v <= 1))
        # the value orders as p_T; ties (equal p) order by the paper's value
        col = p[f"p_{task}"]
        assert np.max(np.abs(v - col)) <= 1e-6
        order = np.argsort(-v, kind="stable")
        assert np.all(np.diff(col[order]) <= 1e-12)


def test_evaluate_shows_the_probability_and_says_when_none_is_likely(capsys):
    from affordgrasp.cli import main

    assert main(["evaluate", "hammer", "--samples", "30", "--task", "beat", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    best = doc["best"]["beat"]
    assert best is not None and 0.0 <= best["value"] <= 1.0
    assert best["probable"] == (best["value"] >= 0.5)
    assert main(["evaluate", "hammer", "--samples", "30", "--task", "beat"]) == 0
    text = capsys.readouterr().out
    assert (best["value"] >= 0.5) or "no grasp reaches p_beat ≥ 0.5" in text


def test_the_screen_keeps_each_grasps_most_promising_use_points():
    from affordgrasp.search.pairs import _top_per_grasp

    values = np.array([0.1, 0.9, 0.5, np.nan, 0.3, 0.2, 0.8, 0.7])  # two grasps × four uses
    keep = _top_per_grasp(values, 4, 2)
    assert keep.tolist() == [False, True, True, False, False, False, True, True]
    assert _top_per_grasp(values, 4, 8).all()  # fewer uses than k: all kept


def test_a_probability_search_is_never_empty_and_scores_its_rows_as_the_task_does():
    from affordgrasp.search.pairs import PairSearchSettings, best_pairs

    settings = PairSearchSettings("cut", grasps=120, uses=60, top=3, per_grasp=True, seed=1)
    found = best_pairs("knife", settings)
    assert found.table.num_rows == 3
    value = found.table.column("value").to_numpy()
    assert np.all((value >= 0) & (value <= 1)) and np.all(np.diff(value) <= 1e-12)
    again = get_task("cut").evaluate(found.table)
    np.testing.assert_allclose(again, value, rtol=0, atol=1e-12)
    np.testing.assert_allclose(found.table.column("p_cut").to_numpy(), value, atol=1e-6)
