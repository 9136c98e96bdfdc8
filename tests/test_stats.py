"""The shared ranking statistics against analytic cases and scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import mannwhitneyu

from affordgrasp.errors import InputError
from affordgrasp.stats import average_precision, bootstrap_auc, roc_auc


def test_auc_is_the_mann_whitney_statistic():
    rng = np.random.default_rng(0)
    score = rng.normal(size=80)
    label = rng.random(80) < 0.4
    score[label] += 0.7
    u = mannwhitneyu(score[label], score[~label]).statistic
    assert roc_auc(score, label) == pytest.approx(u / (label.sum() * (~label).sum()), abs=1e-12)


def test_bootstrap_interval_brackets_the_auc_and_is_seeded():
    rng = np.random.default_rng(1)
    score = rng.normal(size=120)
    label = rng.random(120) < 0.5
    score[label] += 0.5
    auc, lo, hi = bootstrap_auc(score, label, n_boot=300, seed=4)
    assert lo < auc < hi and 0.0 <= lo and hi <= 1.0
    assert bootstrap_auc(score, label, n_boot=300, seed=4) == (auc, lo, hi)
    assert bootstrap_auc(score, label, n_boot=300, seed=5) != (auc, lo, hi)
    # A wider level gives a wider interval; a perfect ranking a degenerate one.
    _, lo90, hi90 = bootstrap_auc(score, label, n_boot=300, seed=4, level=0.9)
    assert lo <= lo90 and hi90 <= hi
    assert bootstrap_auc(label.astype(float), label, n_boot=50) == (1.0, 1.0, 1.0)


def test_bootstrap_of_one_class_is_nan_and_bad_levels_are_refused():
    assert all(math.isnan(v) for v in bootstrap_auc(np.arange(5.0), np.ones(5, bool)))
    with pytest.raises(InputError, match="level"):
        bootstrap_auc(np.arange(4.0), np.array([0, 1, 0, 1], bool), level=1.5)


def test_average_precision_by_hand():
    # Ranking: + - + -  -> precision at the two recalls: 1, 2/3.
    assert average_precision([1, 0, 1, 0], [4, 3, 2, 1]) == pytest.approx(0.5 * 1 + 0.5 * 2 / 3)
    from affordgrasp.learning.evaluation import average_precision as learning_ap

    assert learning_ap is average_precision  # one home


def test_calibration_by_hand_and_in_one_home():
    from affordgrasp.learning import evaluation
    from affordgrasp.stats import expected_calibration_error, reliability_bins

    # Bin [0.2, 0.3): p = 0.2 twice, one positive (gap 0.3); bin [0.9, 1]: p = 1.0, positive.
    labels, probs = [1, 0, 1], [0.2, 0.2, 1.0]
    bins = reliability_bins(labels, probs, bins=10)
    assert bins["count"][2] == 2 and bins["count"][9] == 1
    assert expected_calibration_error(labels, probs) == pytest.approx(2 / 3 * 0.3)
    assert evaluation.expected_calibration_error is expected_calibration_error
    assert evaluation.reliability_bins is reliability_bins
