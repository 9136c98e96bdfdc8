"""Decision rule and decision measures, checked by hand on small cases."""

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.learning.decisions import (
    decision_measures,
    decision_order,
    decision_threshold,
    oracle_hit_rate,
    oracle_order,
    percentile_among,
    random_measures,
    robust_first,
    true_percentiles,
)


def test_threshold_then_least_predicted_effort():
    prob = np.array([0.9, 0.4, 0.6, 0.7, 0.45])
    effort = np.array([50.0, 1.0, 20.0, 20.0, 2.0])
    order = decision_order(prob, effort, threshold=0.5)
    # passed (0, 2, 3) by effort, the tie 2/3 broken by probability; then 4, 1 by probability
    assert order.tolist() == [3, 2, 0, 4, 1]
    assert decision_order(prob, -effort, threshold=0.5, lower_is_better=False).tolist() == [
        3,
        2,
        0,
        4,
        1,
    ]
    # nothing passes: the most probable first
    assert decision_order(prob, effort, threshold=0.95)[0] == 0


def test_one_model_orders_by_its_own_score():
    assert decision_order(np.array([0.1, 0.8, 0.3])).tolist() == [1, 2, 0]
    assert decision_order(None, np.array([3.0, 1.0, np.nan])).tolist() == [1, 0, 2]
    assert decision_order(None, np.array([3.0, 1.0, 2.0]), lower_is_better=False)[0] == 0
    with pytest.raises(InputError):
        decision_order(None, None)
    with pytest.raises(InputError, match="2 probabilities but 3"):
        decision_order(np.ones(2), np.ones(3))


def test_true_percentiles_share_ties_and_treat_nan_as_failure():
    s = np.array([-np.inf, np.nan, 1.0, 3.0])
    # the two failures tie at the bottom: 50 * (0 + 2) / 4 = 25
    assert true_percentiles(s).tolist() == [25.0, 25.0, 62.5, 87.5]
    assert true_percentiles(np.full(5, 2.0)).tolist() == [50.0] * 5
    rng = np.random.default_rng(0)
    for _ in range(5):  # the mean of mid-rank percentiles is 50 whatever the ties
        x = rng.integers(0, 4, 17).astype(float)
        assert true_percentiles(x).mean() == pytest.approx(50.0)


def test_measures_random_and_oracle():
    score = np.array([-np.inf, -10.0, -5.0, -1.0, -np.inf, -7.0])
    viable = np.array([False, True, True, False, False, True])
    m = decision_measures(np.array([2, 3, 0, 1, 4, 5]), score, viable, k=2)
    assert m["chosen"] == 2 and m["top1_viable"] == 1.0 and m["top1_feasible"] == 1.0
    assert m["top1_percentile"] == pytest.approx(50 * (4 + 5) / 6)
    assert m["topk_precision"] == 0.5
    # the oracle's choice is good first (here viable: the best viable, not the best score)
    oracle = decision_measures(oracle_order(score, viable), score, viable)
    assert oracle["chosen"] == 2 and oracle["top1_viable"] == 1.0
    feasible = np.isfinite(score)
    oracle = decision_measures(oracle_order(score, feasible), score, viable)
    assert oracle["chosen"] == 3 and oracle["top1_percentile"] == pytest.approx(100 * 11 / 12)
    r = random_measures(score, viable)
    assert r["top1_viable"] == pytest.approx(0.5) and r["top1_feasible"] == pytest.approx(4 / 6)
    assert r["top1_percentile"] == pytest.approx(50.0)


def test_robust_viable_rate_of_the_choice():
    score = np.array([-np.inf, -10.0, -5.0])
    viable = np.array([False, True, True])
    rv = np.array([0.2, 0.4, 0.9])
    m = decision_measures(np.array([1, 2, 0]), score, viable, robust_viable=rv)
    assert m["top1_robust_viable"] == 0.4
    assert "top1_robust_viable" not in decision_measures(np.array([1, 2, 0]), score, viable)
    assert random_measures(score, viable, robust_viable=rv)["top1_robust_viable"] == pytest.approx(
        0.5
    )


def test_oracle_hit_rate_is_exact():
    from itertools import combinations

    good = np.array([True, False, False, True, False, False, False])
    for k in range(len(good) + 1):  # enumerate every candidate set
        sets = list(combinations(range(len(good)), k))
        expected = np.mean([good[list(c)].any() for c in sets])
        assert oracle_hit_rate(len(good), int(good.sum()), k) == pytest.approx(expected)
    assert oracle_hit_rate(4, 1, 2) == pytest.approx(1 - 3 / 6)
    assert oracle_hit_rate(10, 0, 5) == 0.0 and oracle_hit_rate(10, 1, 10) == 1.0
    assert np.isnan(oracle_hit_rate(10, 3, 11))  # more candidates than rows
    with pytest.raises(InputError, match="good <= rows"):
        oracle_hit_rate(3, 4, 2)


def test_decision_threshold_stored_or_default():
    assert decision_threshold({}) == 0.5
    assert decision_threshold({"decision_threshold": {"value": 0.83}}) == 0.83
    with pytest.raises(InputError, match="not a probability"):
        decision_threshold({"decision_threshold": {"value": "high"}})


def test_within_object_against_pooled():
    from affordgrasp.learning.decision_eval import object_mean_baseline, within_object

    # perfect order inside each object, objects swapped: pooled is wrong on cross pairs
    objects = np.array(["a"] * 4 + ["b"] * 4, dtype=object)
    truth = np.r_[0.0, 1, 2, 3, 10, 11, 12, 13]
    pred = np.r_[10.0, 11, 12, 13, 0, 1, 2, 3]
    w = within_object(objects, truth, pred, kind="regression")
    assert w["comparison_accuracy"] == 1.0 and w["objects"] == 2
    from affordgrasp.learning.evaluation import comparison_accuracy

    pooled = comparison_accuracy(truth, pred)
    assert pooled == pytest.approx(12 / 28)  # 2 x 6 within pairs right, 16 cross pairs wrong
    # the object mean: cross pairs right, within pairs tied (one half each)
    base = object_mean_baseline(objects, truth)
    assert base["comparison_accuracy"] == pytest.approx((16 + 0.5 * 12) / 28)
    c = within_object(objects, np.r_[1.0, 0, 0, 0, 0, 0, 0, 0], pred, kind="classification")
    assert c["objects"] == 1 and c["average_precision"] == pytest.approx(1 / 4)


def test_margin_order_takes_viable_then_feasible_then_the_widest_epsilon():
    from affordgrasp.learning.decisions import margin_order

    viable = [False, True, False, True, False]
    score = [-1.0, -5.0, -np.inf, -2.0, -3.0]
    eps = [0.9, 0.1, 0.8, 0.3, np.nan]
    assert margin_order(viable, score, eps).tolist() == [3, 1, 0, 4, 2]
    # ties keep the candidates' order
    assert margin_order([True] * 3, [0.0] * 3, [0.2] * 3).tolist() == [0, 1, 2]
    with pytest.raises(InputError):
        margin_order([True], [0.0, 1.0], [0.1])


def test_robust_first_moves_the_most_often_viable_of_the_first_forward():
    order = [4, 2, 0, 1, 3]
    viable = [True, False, False, False, True]  # by candidate: 0 and 4 viable, 2 not
    # the first three (4, 2, 0) re-simulated: 2 is the most robust but not viable itself,
    # so the better of the viable ones (0) comes first; the rest keep their places
    assert robust_first(order, viable, [0.5, 0.9, 0.75], 3).tolist() == [0, 4, 2, 1, 3]
    # ties keep the order; NaN counts as 0
    assert robust_first(order, viable, [0.5, 0.9, 0.5], 3).tolist() == order
    assert robust_first(order, viable, [np.nan, 0.0, 0.25], 3).tolist() == [0, 4, 2, 1, 3]
    # none of the first viable: the most robust of them
    assert robust_first(order, [False] * 5, [0.1, 0.3, 0.2], 3).tolist() == [2, 4, 0, 1, 3]
    # one checked: the order as it is
    assert robust_first(order, viable, [0.0], 1).tolist() == order
    # more checked than candidates: all of them
    assert robust_first([1, 0], [True, True], [0.2, 0.4], 5).tolist() == [0, 1]
    with pytest.raises(InputError):
        robust_first(order, viable, [0.5, 0.9], 3)
    with pytest.raises(InputError):
        robust_first(order, viable, [], 0)


def test_percentile_among_places_scores_among_a_reference():
    ref = np.array([1.0, 2.0, 2.0, 4.0, -np.inf])
    # 3 of 5 below 3 (-inf, 1, 2, 2: 4 below, none equal) -> 50 (4 + 4) / 5 = 80
    got = percentile_among([3.0, 2.0, 10.0, -np.inf, np.nan], ref)
    np.testing.assert_allclose(got, [80.0, 50.0 * (2 + 4) / 5, 100.0, 10.0, 10.0])
    # a reference's own scores get their true_percentiles
    np.testing.assert_array_equal(percentile_among(ref, ref), true_percentiles(ref))
    with pytest.raises(InputError, match="reference"):
        percentile_among([1.0], [])


def test_task_feasibility_and_the_oracles_good_choices():
    from affordgrasp.learning.decisions import PROBABLE, oracle_good, task_feasible
    from affordgrasp.tasks import get_task

    p = np.array([0.2, 0.7, np.nan, PROBABLE, 0.9])
    viable = np.array([True, False, True, True, False])
    beat, rules, pick = get_task("beat"), get_task("beat-rules"), get_task("pick")
    # a task probability: p_T >= 0.5; a task of tests: a finite value
    assert task_feasible(beat, p).tolist() == [False, True, False, True, True]
    assert task_feasible(rules, np.array([-np.inf, 1.0, np.nan])).tolist() == [False, True, False]
    # the oracle must choose a task-feasible row for a task with a use point, viable for pick
    assert oracle_good(beat, p, viable).tolist() == task_feasible(beat, p).tolist()
    assert oracle_good(pick, p, viable).tolist() == viable.tolist()
    assert oracle_order(p, oracle_good(pick, p, viable))[0] == 3  # the most probable viable
    # the feasible mask replaces the finite test in the measures
    f = task_feasible(beat, p)
    m = decision_measures(np.array([0, 1, 2, 3, 4]), p, viable, feasible=f)
    assert m["top1_feasible"] == 0.0
    assert random_measures(p, viable, feasible=f)["top1_feasible"] == pytest.approx(3 / 5)
