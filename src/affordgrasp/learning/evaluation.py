"""Metrics of learned models (conventions: Vision; paper §IV-D): MSE, comparison accuracy,
Global Min Score, precision–recall and average precision. numpy only (no torch needed).

Conventions where the paper is silent:

* comparison accuracy counts pairs whose true values differ; a pair whose predictions tie
  counts one half. ``pairs=None`` uses every such pair exactly (n ≤ 4000), else ``pairs``
  random pairs (seeded).
* GMS for a lower-is-better target (the paper's ΣE_h): the sample with the smallest
  prediction is chosen, GMS = fraction of the set whose true value is strictly greater than
  the chosen one's. For a higher-is-better target the largest prediction is chosen and
  GMS = fraction strictly smaller. Ties of the prediction go to the first sample.
* the GMS distribution draws ``n_subsets`` random subsets of ``fraction`` of the samples
  (without replacement, at least 2 samples), seeded; E[GMS] is its mean.
* average precision = Σ_k (R_k − R_{k−1}) P_k over the distinct score thresholds (the step
  integral, as scikit-learn); a constant score gives the positive rate.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..stats import (  # noqa: F401 - re-exported
    average_precision,
    expected_calibration_error,
    precision_recall,
    reliability_bins,
)


def _pair(y_true, y_pred) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(y_true, dtype=np.float64).ravel()
    p = np.asarray(y_pred, dtype=np.float64).ravel()
    if t.shape != p.shape:
        raise InputError(f"{len(t)} true values but {len(p)} predictions")
    return t, p


def mse(y_true, y_pred) -> float:
    """Mean squared error of predictions against true values.

    Parameters
    ----------
    y_true, y_pred : (n,) array_like of float
        True values and predictions, in the target's unit.

    Returns
    -------
    float
        In the target's unit squared; NaN for n = 0.

    Raises
    ------
    InputError
        When the two lengths differ.
    """
    t, p = _pair(y_true, y_pred)
    return float(np.mean((t - p) ** 2)) if len(t) else float("nan")


def comparison_accuracy(y_true, y_pred, *, pairs: int | None = None, seed: int = 0) -> float:
    """Share of pairs whose predicted order is their true order (see the module docstring).

    Parameters
    ----------
    y_true, y_pred : (n,) array_like of float
        True values and predictions.
    pairs : int, optional
        Random pairs to draw; None: every pair when n <= 4000, else 200 000 random pairs.
    seed : int
        Seed of the random pairs.

    Returns
    -------
    float
        In [0, 1]; a predicted tie counts one half. NaN when n < 2 or every true value ties.
    """
    t, p = _pair(y_true, y_pred)
    n = len(t)
    if n < 2:
        return float("nan")
    if pairs is None and n <= 4000:
        i, j = np.triu_indices(n, k=1)
    else:
        rng = np.random.default_rng(seed)
        k = pairs or 200_000
        i = rng.integers(0, n, k)
        j = rng.integers(0, n, k)
    dt = np.sign(t[i] - t[j])
    dp = np.sign(p[i] - p[j])
    keep = dt != 0
    if not keep.any():
        return float("nan")
    score = np.where(dp[keep] == 0, 0.5, (dp[keep] == dt[keep]).astype(np.float64))
    return float(score.mean())


def global_min_score(y_true, y_pred, *, lower_is_better: bool = True) -> float:
    """GMS of one set: the share of the set truly worse than the model's choice.

    Parameters
    ----------
    y_true, y_pred : (n,) array_like of float
        True values and predictions.
    lower_is_better : bool
        The target is better when lower (ΣE_h): the smallest prediction is chosen and the
        share with a strictly greater true value counted; else the largest prediction and a
        strictly smaller true value.

    Returns
    -------
    float
        In [0, 1); NaN for n = 0.
    """
    t, p = _pair(y_true, y_pred)
    if len(t) == 0:
        return float("nan")
    if lower_is_better:
        chosen = t[int(np.argmin(p))]
        return float(np.mean(t > chosen))
    chosen = t[int(np.argmax(p))]
    return float(np.mean(t < chosen))


def gms_distribution(
    y_true,
    y_pred,
    *,
    fraction: float = 0.1,
    n_subsets: int = 1000,
    seed: int = 0,
    lower_is_better: bool = True,
) -> np.ndarray:
    """GMS over random subsets of the samples.

    Parameters
    ----------
    y_true, y_pred : (n,) array_like of float
        True values and predictions.
    fraction : float
        Subset size as a share of n (at least 2 samples, drawn without replacement).
    n_subsets : int
        Subsets drawn.
    seed : int
        Seed of the draws.
    lower_is_better : bool
        As for :func:`global_min_score`.

    Returns
    -------
    (n_subsets,) float64 ndarray
        GMS of each subset; empty when n < 2.
    """
    t, p = _pair(y_true, y_pred)
    n = len(t)
    if n < 2:
        return np.full(0, np.nan)
    k = max(2, int(round(fraction * n)))
    rng = np.random.default_rng(seed)
    out = np.empty(n_subsets)
    for s in range(n_subsets):
        idx = rng.choice(n, k, replace=False)
        out[s] = global_min_score(t[idx], p[idx], lower_is_better=lower_is_better)
    return out


def regression_report(y_true, y_pred, *, lower_is_better: bool = True, seed: int = 0) -> dict:
    """MSE, comparison accuracy and E[GMS] (with its quartiles) of predictions vs truth.

    Parameters
    ----------
    y_true, y_pred : (n,) array_like of float
        True values and predictions.
    lower_is_better : bool
        As for :func:`global_min_score`.
    seed : int
        Seed of the random pairs and the GMS distribution's 1000 subsets (10 % of the
        samples each).

    Returns
    -------
    dict
        ``n``, ``mse``, ``comparison_accuracy``, ``expected_gms`` and ``gms_quartiles``
        (25th, 50th, 75th percentiles; empty when n < 2).
    """
    g = gms_distribution(y_true, y_pred, seed=seed, lower_is_better=lower_is_better)
    return {
        "n": int(len(np.ravel(y_true))),
        "mse": mse(y_true, y_pred),
        "comparison_accuracy": comparison_accuracy(y_true, y_pred, seed=seed),
        "expected_gms": float(np.mean(g)) if len(g) else float("nan"),
        "gms_quartiles": [float(q) for q in np.percentile(g, [25, 50, 75])] if len(g) else [],
    }


def classification_report(labels, scores, *, seed: int = 0) -> dict:
    """AP on the natural class balance and on a balanced subset, accuracy at 0.5.

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    scores : (n,) array_like of float
        Predicted probabilities.
    seed : int
        Seed of the balanced subset (as many negatives as positives, or the reverse).

    Returns
    -------
    dict
        ``n``, ``positives``, ``positive_rate``, ``average_precision``,
        ``average_precision_balanced``, ``accuracy_at_0.5`` and ``balanced_accuracy_at_0.5``
        (NaN where a class is missing).
    """
    y = np.asarray(labels, dtype=np.float64) > 0.5
    s = np.asarray(scores, dtype=np.float64)
    pos, neg = np.flatnonzero(y), np.flatnonzero(~y)
    rng = np.random.default_rng(seed)
    k = min(len(pos), len(neg))
    bal = np.r_[rng.choice(pos, k, replace=False), rng.choice(neg, k, replace=False)]
    return {
        "n": int(len(y)),
        "positives": int(y.sum()),
        "positive_rate": float(y.mean()) if len(y) else float("nan"),
        "average_precision": average_precision(y, s),
        "average_precision_balanced": average_precision(y[bal], s[bal]) if k else float("nan"),
        "accuracy_at_0.5": float(np.mean((s >= 0.5) == y)) if len(y) else float("nan"),
        "balanced_accuracy_at_0.5": (
            float(0.5 * (np.mean(s[pos] >= 0.5) + np.mean(s[neg] < 0.5))) if k else float("nan")
        ),
    }


def best_f1_threshold(labels, probabilities, *, weights=None) -> tuple[float, float]:
    """The probability threshold of largest F1 (predicted positive when p >= threshold).

    Parameters
    ----------
    labels : (n,) array_like
        True classes; positive when > 0.5.
    probabilities : (n,) array_like of float
        Predicted probabilities.
    weights : (n,) array_like of float, optional
        Row weights (to restore a natural class balance from a subsample); 1 each when None.

    Returns
    -------
    threshold : float
        One of the distinct probabilities (the largest among equal F1); 0.5 without a
        positive label.
    f1 : float
        Its F1 (NaN without a positive label).
    """
    y = np.asarray(labels, dtype=np.float64).ravel() > 0.5
    p = np.asarray(probabilities, dtype=np.float64).ravel()
    if len(y) != len(p):
        raise InputError(f"{len(y)} labels but {len(p)} probabilities")
    w = np.ones(len(y)) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
    if not y.any():
        return 0.5, float("nan")
    order = np.argsort(-p, kind="mergesort")
    ps, ys, ws = p[order], y[order], w[order]
    last = np.r_[np.flatnonzero(np.diff(ps) != 0), len(ps) - 1]
    tp = np.cumsum(ws * ys)[last]
    fp = np.cumsum(ws * ~ys)[last]
    fn = np.sum(ws * ys) - tp
    f1 = 2 * tp / np.maximum(2 * tp + fp + fn, 1e-300)
    k = int(np.flatnonzero(f1 == f1.max())[0])
    return float(ps[last][k]), float(f1[k])
