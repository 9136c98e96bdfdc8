"""Decisions from predictions (conventions: Vision): which candidate grasp a model chooses,
and how good that choice truly is. numpy only (no torch needed).

A model is judged by the grasp it picks on one object, not by pooled metrics:

* **the rule** (:func:`decision_order`): with a classifier and a regressor, the candidates
  whose viability probability reaches the classifier's decision threshold come first, in
  the order of the regressor's prediction (least predicted effort first); the others
  follow by decreasing probability. With one model, its own score orders the candidates
  (highest probability; best predicted value). Ties keep the candidates' order.
* **the truth**: the task score F_T of each candidate, simulated (−inf where the task's
  requirements fail; NaN counts as −inf), and its viability.
* **the measures** (:func:`decision_measures`): is the first choice viable and
  task-feasible (finite F_T), its percentile among the candidates' true scores (the mean
  of the strict and weak percentile ranks, so that ties share their ranks: 100 = strictly
  better than every other candidate, a constant set gives 50), and the precision of the
  first k choices (how many are viable).
* **baselines**: random choice (its expectation, computed exactly: the viable share, 50th
  percentile), and the oracle (the candidates ordered by their true score).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def decision_order(
    probability: np.ndarray | None = None,
    predicted: np.ndarray | None = None,
    *,
    threshold: float = 0.5,
    lower_is_better: bool = True,
) -> np.ndarray:
    """The candidates in the order a model would choose them (best first).

    Parameters
    ----------
    probability : (n,) array_like of float, optional
        A classifier's probability that each candidate is viable.
    predicted : (n,) array_like of float, optional
        A regressor's prediction for each candidate (e.g. ΣE_h, N).
    threshold : float
        The classifier's decision threshold (a probability).
    lower_is_better : bool
        The regressor's target is better when lower (efforts).

    Returns
    -------
    (n,) int64 ndarray
        Candidate indices, the chosen one first.

    Raises
    ------
    InputError
        When neither score is given, or their lengths differ.
    """
    if probability is None and predicted is None:
        raise InputError("a decision needs a classifier's probabilities or a regressor's values")
    p = None if probability is None else np.asarray(probability, dtype=np.float64).ravel()
    v = None if predicted is None else np.asarray(predicted, dtype=np.float64).ravel()
    if p is not None and v is not None and len(p) != len(v):
        raise InputError(f"{len(p)} probabilities but {len(v)} predicted values")
    if v is not None:
        value_key = v if lower_is_better else -v
        value_key = np.where(np.isnan(value_key), np.inf, value_key)
    if p is None:
        return np.argsort(value_key, kind="stable")
    prob_key = -np.where(np.isnan(p), -np.inf, p)
    if v is None:
        return np.argsort(prob_key, kind="stable")
    passed = p >= threshold
    # lexsort: the last key is the primary one
    return np.lexsort((prob_key, np.where(passed, value_key, 0.0), ~passed))


def true_percentiles(true_score: np.ndarray) -> np.ndarray:
    """Percentile of every candidate among all candidates' true scores.

    Parameters
    ----------
    true_score : (n,) array_like of float
        F_T per candidate; NaN counts as −inf (the task is undefined there).

    Returns
    -------
    (n,) float64 ndarray
        In [0, 100]: 50 · (share strictly below + share at or below); ties share their rank.
    """
    s = np.asarray(true_score, dtype=np.float64).ravel()
    return percentile_among(s, s) if len(s) else np.zeros(0)


def percentile_among(scores: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Percentiles of scores among reference scores, as :func:`true_percentiles` counts.

    Parameters
    ----------
    scores : (m,) array_like of float
        The scores placed (NaN counts as −inf).
    reference : (n,) array_like of float
        The scores they are placed among (NaN counts as −inf; n >= 1).

    Returns
    -------
    (m,) float64 ndarray
        In [0, 100]: 50 · (share of the reference strictly below + share at or below).
        A score that is one of the reference's gets its :func:`true_percentiles` value.
    """
    s = np.asarray(scores, dtype=np.float64).ravel()
    s = np.where(np.isnan(s), -np.inf, s)
    ref = np.asarray(reference, dtype=np.float64).ravel()
    if len(ref) == 0:
        raise InputError("no reference scores to place scores among")
    ordered = np.sort(np.where(np.isnan(ref), -np.inf, ref))
    below = np.searchsorted(ordered, s, side="left")
    at_or_below = np.searchsorted(ordered, s, side="right")
    return 50.0 * (below + at_or_below) / len(ordered)


def decision_measures(
    order: np.ndarray,
    true_score: np.ndarray,
    viable: np.ndarray,
    *,
    k: int = 5,
    robust_viable: np.ndarray | None = None,
    among: int | None = None,
    feasible: np.ndarray | None = None,
) -> dict:
    """How good a ranking's choices truly are.

    Parameters
    ----------
    order : (n,) int array_like
        Candidate indices, the chosen one first (:func:`decision_order`).
    true_score : (n,) array_like of float
        Simulated F_T per candidate (NaN or −inf: the task fails there).
    viable : (n,) array_like of bool
        Simulated viability per candidate.
    k : int
        How many first choices the precision counts.
    robust_viable : (n,) array_like of float, optional
        The candidates' robust viable rate (the share of their perturbed copies that stay
        viable, docs/robust.md), when known.
    among : int, optional
        Place the chosen grasp among the first ``among`` candidates' true scores only
        (``plan``'s drawn candidates, before the refined ones); None: among all.
    feasible : (n,) array_like of bool, optional
        Which candidates are task-feasible (:func:`task_feasible`); None: a finite score.

    Returns
    -------
    dict
        ``chosen`` (index), ``top1_viable`` and ``top1_feasible`` (0 or 1),
        ``top1_percentile`` (:func:`percentile_among`), ``top1_score`` (F_T) and
        ``topk_precision`` (viable share of the first min(k, n) choices); with
        ``robust_viable``, ``top1_robust_viable`` (the chosen grasp's rate).
    """
    order = np.asarray(order, dtype=np.int64)
    s = np.asarray(true_score, dtype=np.float64).ravel()
    ok = np.asarray(viable, dtype=bool).ravel()
    if len(order) == 0:
        raise InputError("no candidates to choose from")
    c = int(order[0])
    out = {
        "chosen": c,
        "top1_viable": float(ok[c]),
        "top1_feasible": float(_feasible(s, feasible)[c]),
        "top1_percentile": float(percentile_among(s[[c]], s[:among])[0]),
        "top1_score": float(s[c]),
        "topk_precision": float(ok[order[:k]].mean()),
    }
    if robust_viable is not None:
        out["top1_robust_viable"] = float(np.asarray(robust_viable, dtype=np.float64)[c])
    return out


def oracle_order(true_score: np.ndarray, good: np.ndarray) -> np.ndarray:
    """The best a decider could do: the good candidates first, each group by its true score.

    Parameters
    ----------
    true_score : (n,) array_like of float
    good : (n,) array_like of bool
        What a choice must be (:func:`oracle_good`: viable for a task without a use point,
        task-feasible for one with).

    Returns
    -------
    (n,) int64 ndarray
        Best first; ties keep the candidates' order.
    """
    s = np.asarray(true_score, dtype=np.float64).ravel()
    s = np.where(np.isnan(s), -np.inf, s)
    return np.lexsort((-s, ~np.asarray(good, dtype=bool).ravel()))


# a task probability's decision is task-feasible when its success is at least as likely as not
PROBABLE = 0.5


def task_feasible(task, true_score: np.ndarray) -> np.ndarray:
    """Which candidates can serve a task: p_T >= :data:`PROBABLE` for a task probability, a
    finite score for a task of tests.

    Parameters
    ----------
    task : Task
    true_score : (n,) array_like of float
        The task's values.

    Returns
    -------
    (n,) bool ndarray
    """
    s = np.asarray(true_score, dtype=np.float64).ravel()
    return np.nan_to_num(s, nan=-1.0) >= PROBABLE if task.probability else np.isfinite(s)


def oracle_good(task, true_score: np.ndarray, viable: np.ndarray) -> np.ndarray:
    """What the oracle's choice must be: viable for a task that reads no use point (pick),
    task-feasible (:func:`task_feasible`) for one that does.

    Parameters
    ----------
    task : Task
    true_score : (n,) array_like of float
    viable : (n,) array_like of bool

    Returns
    -------
    (n,) bool ndarray
    """
    from ..columns import USE_METRICS

    if set(USE_METRICS) & set(task.requires):
        return task_feasible(task, true_score)
    return np.asarray(viable, dtype=bool).ravel()


def _feasible(score: np.ndarray, feasible: np.ndarray | None) -> np.ndarray:
    return np.isfinite(score) if feasible is None else np.asarray(feasible, dtype=bool).ravel()


def margin_order(viable: np.ndarray, score: np.ndarray, epsilon: np.ndarray) -> np.ndarray:
    """Candidates judged by a simulation of their own (on a surface fused from views): the
    viable ones first, then the task-feasible ones (finite score), each by decreasing ε.

    ε is the margin: on a surface a millimetre off the true one, a grasp that is viable with
    a wide ε stays viable more often than one chosen for its effort (``plan --model
    views``, docs/learning.md).

    Parameters
    ----------
    viable : (n,) array_like of bool
    score : (n,) array_like of float
        F_T (−inf or NaN where the task fails).
    epsilon : (n,) array_like of float
        ε (NaN counts as 0).

    Returns
    -------
    (n,) int64 ndarray
        The best first; ties keep the candidates' order.
    """
    v = np.asarray(viable, dtype=bool).ravel()
    s = np.asarray(score, dtype=np.float64).ravel()
    e = np.nan_to_num(np.asarray(epsilon, dtype=np.float64).ravel(), nan=0.0)
    if not len(v) == len(s) == len(e):
        raise InputError(f"{len(v)} viable flags, {len(s)} scores and {len(e)} ε values")
    return np.lexsort((-e, ~np.isfinite(s), ~v))  # lexsort is stable


def robust_first(
    order: np.ndarray, viable: np.ndarray, robust_viable: np.ndarray, checked: int
) -> np.ndarray:
    """An order's first candidates re-ranked by how they fare under perturbation.

    The first ``checked`` candidates of ``order`` are compared by ``robust_viable``, a
    score of their perturbed copies, higher better (the share of them viable, or, as
    ``plan`` uses it, a quantile of their ε); where some of them are viable themselves,
    only those can come first. The best of them moves to the front; every other candidate
    keeps its place. Ties keep ``order``'s order.

    Parameters
    ----------
    order : (n,) array_like of int
        Candidates, best first (e.g. :func:`margin_order`).
    viable : (n,) array_like of bool
        Each candidate's own viability (indexed by candidate, not by rank).
    robust_viable : (min(checked, n),) array_like of float
        The robust score of ``order[:checked]``, in that order (NaN counts as 0).
    checked : int
        How many of the first candidates were re-simulated (>= 1; at most n count).

    Returns
    -------
    (n,) int64 ndarray
        ``order`` with the chosen one of its first ``checked`` candidates first.
    """
    o = np.asarray(order, dtype=np.int64).ravel()
    v = np.asarray(viable, dtype=bool).ravel()
    r = np.nan_to_num(np.asarray(robust_viable, dtype=np.float64).ravel(), nan=0.0)
    m = min(int(checked), len(o))
    if m < 1 or len(r) != m:
        raise InputError(f"{len(r)} robust viabilities for the first {m} of {len(o)} candidates")
    first = v[o[:m]]
    score = np.where(first, r, -np.inf) if first.any() else r
    best = int(np.lexsort((np.arange(m), -score))[0])  # the highest; the earliest of ties
    return np.concatenate([o[best : best + 1], np.delete(o, best)])


def random_measures(
    true_score: np.ndarray,
    viable: np.ndarray,
    *,
    robust_viable: np.ndarray | None = None,
    feasible: np.ndarray | None = None,
) -> dict:
    """The expected measures of a uniformly random choice (exact, no draws).

    Parameters
    ----------
    true_score : (n,) array_like of float
    viable : (n,) array_like of bool
    robust_viable : (n,) array_like of float, optional
        As for :func:`decision_measures`.
    feasible : (n,) array_like of bool, optional
        As for :func:`decision_measures`.

    Returns
    -------
    dict
        ``top1_viable``, ``top1_feasible``, ``top1_percentile`` (50 by construction) and
        ``topk_precision`` (the viable share), each an expectation; with
        ``robust_viable``, ``top1_robust_viable`` (its mean).
    """
    s = np.asarray(true_score, dtype=np.float64).ravel()
    ok = np.asarray(viable, dtype=bool).ravel()
    out = {
        "top1_viable": float(ok.mean()),
        "top1_feasible": float(_feasible(s, feasible).mean()),
        "top1_percentile": float(true_percentiles(s).mean()),
        "topk_precision": float(ok.mean()),
    }
    if robust_viable is not None:
        out["top1_robust_viable"] = float(np.mean(np.asarray(robust_viable, dtype=np.float64)))
    return out


DEFAULT_THRESHOLD = 0.5


def decision_threshold(config: dict) -> float:
    """A classifier's decision threshold: the one chosen on its validation objects and
    stored in its model file, else 0.5 (model files written before it was stored).

    Parameters
    ----------
    config : dict
        The model's config.

    Returns
    -------
    float
        A probability.
    """
    stored = config.get("decision_threshold")
    if not isinstance(stored, dict) or stored.get("value") is None:
        return DEFAULT_THRESHOLD
    value = stored["value"]
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value <= 1:
        raise InputError(
            f"the model's stored decision threshold {value!r} is not a probability in [0, 1]; "
            "pass a threshold explicitly or retrain the model"
        )
    return float(value)


def oracle_hit_rate(rows: int, good: int, candidates: int) -> float:
    """Chance that ``candidates`` rows drawn without replacement hold at least one good row.

    The best a decider can do: the oracle chooses a good (e.g. viable) grasp exactly when
    one is among the candidates. Exact (hypergeometric), no draws.

    Parameters
    ----------
    rows : int
        Rows to draw from (an object's simulated grasps).
    good : int
        How many of them are good, 0 <= good <= rows.
    candidates : int
        Candidates drawn; more than ``rows`` gives NaN (the rows do not allow it).

    Returns
    -------
    float
        1 − C(rows − good, candidates) / C(rows, candidates), in [0, 1]; NaN when
        ``candidates > rows``.

    Raises
    ------
    InputError
        When the counts are negative or ``good > rows``.
    """
    if rows < 0 or good < 0 or candidates < 0 or good > rows:
        raise InputError(
            f"oracle_hit_rate needs 0 <= good <= rows and candidates >= 0, got rows={rows}, "
            f"good={good}, candidates={candidates}"
        )
    if candidates > rows:
        return float("nan")
    from scipy.stats import hypergeom

    return float(hypergeom(rows, good, candidates).sf(0))
