"""ROC-AUC and Spearman against brute-force definitions and scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import spearmanr

from affordgrasp.physics.report import roc_auc, roc_curve, spearman


def _auc_by_pairs(score, label):
    pos, neg = score[label], score[~label]
    wins = (pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()
    return wins / (len(pos) * len(neg))


def test_auc_analytic_cases():
    label = np.array([False, False, True, True])
    assert roc_auc(np.array([0.0, 1.0, 2.0, 3.0]), label) == 1.0
    assert roc_auc(np.array([3.0, 2.0, 1.0, 0.0]), label) == 0.0
    assert roc_auc(np.full(4, -np.inf), label) == 0.5  # all tied: no credit
    assert math.isnan(roc_auc(np.arange(4.0), np.ones(4, dtype=bool)))


def test_auc_equals_pair_count_with_ties_and_infinities():
    rng = np.random.default_rng(0)
    score = rng.integers(0, 5, 200).astype(float)
    score[rng.random(200) < 0.3] = -np.inf
    label = rng.random(200) < 0.4
    assert roc_auc(score, label) == pytest.approx(_auc_by_pairs(score, label), abs=1e-12)
    fpr, tpr = roc_curve(score, label)
    assert np.trapezoid(tpr, fpr) == pytest.approx(roc_auc(score, label), abs=1e-12)


def test_spearman_matches_scipy_and_drops_nan():
    rng = np.random.default_rng(1)
    x, y = rng.normal(size=100), rng.normal(size=100)
    y += x
    assert spearman(x, y) == pytest.approx(spearmanr(x, y).statistic, abs=1e-12)
    x2 = np.r_[x, np.nan]
    y2 = np.r_[y, 5.0]
    assert spearman(x2, y2) == pytest.approx(spearman(x, y), abs=1e-12)
