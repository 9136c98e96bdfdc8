"""Comparison accuracy, GMS, PR/AP against hand-worked examples."""

import numpy as np
import pytest

from affordgrasp.learning.evaluation import (
    average_precision,
    comparison_accuracy,
    global_min_score,
    gms_distribution,
    mse,
    precision_recall,
)


def test_mse():
    assert mse([0, 1, 2], [0, 2, 0]) == pytest.approx(5 / 3)


def test_comparison_accuracy_by_hand():
    truth = [1.0, 2.0, 3.0, 4.0]
    assert comparison_accuracy(truth, [10, 20, 30, 40]) == 1.0
    assert comparison_accuracy(truth, [40, 30, 20, 10]) == 0.0
    # pairs (1,2) (1,3) (1,4) (2,3) (2,4) (3,4); prediction swaps 3 and 4 -> 5 of 6 right
    assert comparison_accuracy(truth, [1, 2, 4, 3]) == pytest.approx(5 / 6)
    # a tie in prediction counts 1/2; pairs equal in truth are skipped
    assert comparison_accuracy([1, 2, 2], [0, 0, 5]) == pytest.approx((0.5 + 1) / 2)
    # random pairs converge to the exact value
    rng = np.random.default_rng(0)
    t = rng.random(5000)
    p = t + rng.normal(0, 0.3, 5000)
    exact = comparison_accuracy(t[:1500], p[:1500])
    sampled = comparison_accuracy(t[:1500], p[:1500], pairs=200_000, seed=1)
    assert abs(exact - sampled) < 0.01


def test_global_min_score_by_hand():
    truth = np.array([5.0, 1.0, 3.0, 4.0, 2.0])
    # the model picks the sample with the smallest prediction: index 2 (truth 3);
    # samples truly greater than 3: 5 and 4 -> GMS = 2/5
    assert global_min_score(truth, [9, 8, 0, 7, 6]) == pytest.approx(2 / 5)
    # the perfect choice (truth 1) beats the 4 others
    assert global_min_score(truth, truth) == pytest.approx(4 / 5)
    # higher is better: the largest prediction is chosen, GMS counts smaller truths
    assert global_min_score(truth, [0, 0, 9, 0, 0], lower_is_better=False) == pytest.approx(2 / 5)


def test_gms_distribution_perfect_model_and_subset_size():
    truth = np.arange(100.0)
    g = gms_distribution(truth, truth, n_subsets=50, seed=0)
    # each 10-sample subset: its minimum beats the 9 others
    np.testing.assert_allclose(g, 0.9)
    g_bad = gms_distribution(truth, -truth, n_subsets=50, seed=0)
    np.testing.assert_allclose(g_bad, 0.0)
    np.testing.assert_array_equal(
        gms_distribution(truth, truth[::-1], seed=3, n_subsets=20),
        gms_distribution(truth, truth[::-1], seed=3, n_subsets=20),
    )


def test_precision_recall_and_average_precision_by_hand():
    labels = [1, 0, 1, 0]
    scores = [0.9, 0.8, 0.7, 0.1]
    precision, recall, thresholds = precision_recall(labels, scores)
    np.testing.assert_allclose(precision, [1, 1 / 2, 2 / 3, 1 / 2])
    np.testing.assert_allclose(recall, [0.5, 0.5, 1.0, 1.0])
    np.testing.assert_allclose(thresholds, [0.9, 0.8, 0.7, 0.1])
    # AP = 0.5 * 1 + 0.5 * 2/3
    assert average_precision(labels, scores) == pytest.approx(0.5 + 1 / 3)
    assert average_precision([1, 0, 0, 0], [0.5] * 4) == pytest.approx(0.25)
    assert average_precision([1, 1, 0], [3, 2, 1]) == 1.0


def test_expected_calibration_error_by_hand():
    from affordgrasp.learning.evaluation import expected_calibration_error, reliability_bins

    # bin [0.2, 0.3): p 0.25 twice, one positive -> gap 0.25; bin [0.9, 1]: p 1.0, positive
    y = np.array([1, 0, 1])
    p = np.array([0.25, 0.25, 1.0])
    r = reliability_bins(y, p, bins=10)
    assert r["count"][2] == 2 and r["count"][9] == 1 and r["count"].sum() == 3
    assert r["positive_rate"][2] == 0.5 and np.isnan(r["positive_rate"][0])
    assert expected_calibration_error(y, p, bins=10) == pytest.approx(2 / 3 * 0.25)
    # a perfectly calibrated score: the rate of each bin equals its probability
    rng = np.random.default_rng(0)
    q = rng.random(200_000)
    assert expected_calibration_error(rng.random(200_000) < q, q) < 0.01
    # weights count rows as that many rows
    assert expected_calibration_error(y, p, weights=[1, 1, 2]) == pytest.approx(2 / 4 * 0.25)


def test_best_f1_threshold_by_hand():
    from affordgrasp.learning.evaluation import best_f1_threshold

    y = np.array([1, 1, 0, 1, 0, 0])
    p = np.array([0.9, 0.8, 0.7, 0.6, 0.2, 0.1])
    # thresholds 0.9: F1 2/4; 0.8: 4/5; 0.7: 4/6; 0.6: 6/7 (best); 0.2: 6/8
    t, f1 = best_f1_threshold(y, p)
    assert t == 0.6 and f1 == pytest.approx(6 / 7)
    # negatives weighted 10x: 0.8 (tp 2, fp 0, fn 1: F1 4/5) beats 0.6 (fp 10: F1 6/17)
    t, f1 = best_f1_threshold(y, p, weights=np.where(y == 1, 1.0, 10.0))
    assert t == 0.8 and f1 == pytest.approx(4 / 5)
    assert best_f1_threshold(np.zeros(3), p[:3])[0] == 0.5
