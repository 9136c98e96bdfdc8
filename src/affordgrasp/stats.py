"""Ranking statistics shared by the physics report and the learning evaluation.

One home per statistic (as scikit-learn's ``metrics/_ranking.py``): ROC-AUC and its curve,
a bootstrap interval of the AUC, Spearman's ρ, precision-recall, average precision, and the
calibration of probabilities (reliability bins, expected calibration error).
Plain numpy/scipy over 1-D arrays; plotting lives with the callers.

Validated against known cases in ``tests/test_stats.py``: a perfect ranking (AUC 1), its
reverse (0), all ties (1/2), the Mann-Whitney U statistic of scipy, and the AP of a
hand-counted ranking.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import rankdata

from .errors import InputError

__all__ = [
    "average_precision",
    "bootstrap_auc",
    "expected_calibration_error",
    "precision_recall",
    "reliability_bins",
    "roc_auc",
    "roc_curve",
    "spearman",
]


def _scored(score, label) -> tuple[np.ndarray, np.ndarray]:
    """float64 scores and bool labels of the rows whose score is not NaN."""
    score = np.asarray(score, dtype=np.float64)
    label = np.asarray(label, dtype=bool)
    keep = ~np.isnan(score)
    return score[keep], label[keep]


def roc_auc(score: np.ndarray, label: np.ndarray) -> float:
    """ROC-AUC of ``score`` for binary ``label`` (ties count 1/2); NaN if one class is empty.

    The Mann-Whitney probability that a random positive outranks a random negative.

    Parameters
    ----------
    score : (n,) float ndarray
        Larger = more likely positive (±inf allowed, NaN rows dropped).
    label : (n,) bool ndarray

    Returns
    -------
    float
    """
    score, label = _scored(score, label)
    n_pos, n_neg = int(label.sum()), int((~label).sum())
    if n_pos == 0 or n_neg == 0:
        return math.nan
    ranks = rankdata(score)  # average ranks: ties count one half
    return float((ranks[label].sum() - n_pos * (n_pos + 1) / 2) / (n_pos * n_neg))


def bootstrap_auc(
    score: np.ndarray, label: np.ndarray, *, n_boot: int = 1000, level: float = 0.95, seed: int = 0
) -> tuple[float, float, float]:
    """ROC-AUC and its percentile bootstrap interval (rows resampled with replacement).

    Parameters
    ----------
    score : (n,) float ndarray
        Larger = more likely positive (NaN rows dropped).
    label : (n,) bool ndarray
    n_boot : int
        Resamples.
    level : float
        Coverage of the interval, in (0, 1).
    seed : int
        Seed of the resampling (same seed, same interval).

    Returns
    -------
    auc, low, high : float
        NaN when a class is empty; resamples with one class empty are skipped.
    """
    if not 0.0 < level < 1.0:
        raise InputError(f"level must be in (0, 1), got {level!r}")
    if n_boot <= 0:
        raise InputError(f"n_boot must be a positive integer, got {n_boot!r}")
    score, label = _scored(score, label)
    auc = roc_auc(score, label)
    if math.isnan(auc):
        return math.nan, math.nan, math.nan
    n = len(score)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(n_boot, n))
    # Ranks of every resample at once: average ranks along each row.
    s, y = score[idx], label[idx]
    ranks = rankdata(s, axis=1)
    n_pos = y.sum(axis=1)
    n_neg = n - n_pos
    ok = (n_pos > 0) & (n_neg > 0)
    u = (ranks * y).sum(axis=1) - n_pos * (n_pos + 1) / 2
    aucs = u[ok] / (n_pos[ok] * n_neg[ok])
    if len(aucs) == 0:
        return auc, math.nan, math.nan
    tail = 0.5 * (1.0 - level)
    low, high = np.quantile(aucs, [tail, 1.0 - tail])
    return auc, float(low), float(high)


def roc_curve(score: np.ndarray, label: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ROC curve at every distinct threshold, from (0, 0).

    Parameters
    ----------
    score : (n,) float ndarray
    label : (n,) bool ndarray

    Returns
    -------
    fpr, tpr : float64 ndarray
        False and true positive rates.
    """
    score, label = _scored(score, label)
    order = np.argsort(-score, kind="stable")
    s, y = score[order], label[order]
    # The last index of every run of equal scores (±inf compare equal to themselves).
    distinct = np.r_[np.flatnonzero(s[1:] != s[:-1]), len(s) - 1] if len(s) else np.zeros(0, int)
    tp = np.cumsum(y)[distinct]
    fp = np.cumsum(~y)[distinct]
    p, n = max(int(y.sum()), 1), max(int((~y).sum()), 1)
    return np.r_[0.0, fp / n], np.r_[0.0, tp / p]


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's ρ (average ranks; ±inf rank at the ends); NaN pairs dropped.

    Parameters
    ----------
    x, y : (n,) float ndarray

    Returns
    -------
    float
        NaN with fewer than 3 pairs or a constant side.
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    keep = ~(np.isnan(x) | np.isnan(y))
    x, y = x[keep], y[keep]
    if len(x) < 3:
        return math.nan
    rx, ry = rankdata(x), rankdata(y)
    if rx.std() == 0 or ry.std() == 0:
        return math.nan
    return float(np.corrcoef(rx, ry)[0, 1])


def precision_recall(labels, scores) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Precision, recall and thresholds, one per distinct score (highest threshold first).

    A sample is predicted positive when its score >= the threshold.

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    scores : (n,) array_like of float
        Predicted scores.

    Returns
    -------
    precision, recall, thresholds : (k,) float64 ndarray
        k distinct scores, descending; recall is 0 throughout without a positive label.

    Raises
    ------
    InputError
        When the two lengths differ.
    """
    y = np.asarray(labels, dtype=np.float64).ravel() > 0.5
    s = np.asarray(scores, dtype=np.float64).ravel()
    if len(y) != len(s):
        raise InputError(f"{len(y)} labels but {len(s)} scores")
    order = np.argsort(-s, kind="mergesort")
    s, y = s[order], y[order]
    last = np.r_[np.flatnonzero(np.diff(s) != 0), len(s) - 1]  # end of each tie group
    tp = np.cumsum(y)[last]
    fp = (last + 1) - tp
    n_pos = max(int(y.sum()), 1)
    precision = tp / np.maximum(tp + fp, 1)
    recall = tp / n_pos
    return precision, recall, s[last]


def average_precision(labels, scores) -> float:
    """AP = Σ_k (R_k − R_{k−1}) P_k over the distinct thresholds.

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    scores : (n,) array_like of float
        Predicted scores.

    Returns
    -------
    float
        In [0, 1]; NaN without a positive label.
    """
    if not np.any(np.asarray(labels) > 0.5):
        return float("nan")
    precision, recall, _ = precision_recall(labels, scores)
    return float(np.sum(np.diff(np.r_[0.0, recall]) * precision))


def reliability_bins(labels, probabilities, *, bins: int = 10, weights=None) -> dict:
    """Observed positive rate against mean predicted probability, in equal-width bins.

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    probabilities : (n,) array_like of float
        Predicted probabilities in [0, 1].
    bins : int
        Equal-width bins over [0, 1]; a probability of exactly 1 falls in the last.
    weights : (n,) array_like of float, optional
        Row weights (e.g. to restore a natural class balance); 1 each when None.

    Returns
    -------
    dict
        ``edges`` (bins + 1,), and per bin ``count`` (weighted), ``mean_probability`` and
        ``positive_rate`` (NaN for an empty bin).
    """
    y = (np.asarray(labels, dtype=np.float64).ravel() > 0.5).astype(np.float64)
    p = np.asarray(probabilities, dtype=np.float64).ravel()
    if len(y) != len(p):
        raise InputError(f"{len(y)} labels but {len(p)} probabilities")
    if not isinstance(bins, int) or bins < 1:
        raise InputError(f"bins must be a positive integer, got {bins!r}")
    w = np.ones(len(y)) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.searchsorted(edges, p, side="right") - 1, 0, bins - 1)
    count = np.bincount(which, weights=w, minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = np.bincount(which, weights=w * p, minlength=bins) / count
        rate = np.bincount(which, weights=w * y, minlength=bins) / count
    return {"edges": edges, "count": count, "mean_probability": mean_p, "positive_rate": rate}


def expected_calibration_error(labels, probabilities, *, bins: int = 10, weights=None) -> float:
    """ECE: the count-weighted mean gap between predicted probability and observed rate.

    ECE = Σ_b (n_b / n) · |mean p_b − positive rate_b| over equal-width bins (Guo et al.
    2017, "On calibration of modern neural networks").

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    probabilities : (n,) array_like of float
        Predicted probabilities in [0, 1].
    bins : int
        Equal-width bins over [0, 1].
    weights : (n,) array_like of float, optional
        Row weights; 1 each when None.

    Returns
    -------
    float
        In [0, 1]; NaN for n = 0.
    """
    r = reliability_bins(labels, probabilities, bins=bins, weights=weights)
    total = r["count"].sum()
    if total <= 0:
        return float("nan")
    full = r["count"] > 0
    gaps = np.abs(r["mean_probability"][full] - r["positive_rate"][full])
    return float(np.sum(r["count"][full] * gaps) / total)
