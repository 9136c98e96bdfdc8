"""Decisions of models on a dataset's held-out objects (conventions: Vision): for each
object, draw sets of candidate grasps from its rows, let the models choose
(:func:`~affordgrasp.learning.decisions.decision_order`), and measure the choice against
the simulated truth stored in the rows, beside random choice, the oracle and an optional
baseline model (e.g. pose-only). Per object first, then averaged over objects.

Within-object pooled metrics (:func:`within_object`) sit beside: comparison accuracy and
E[GMS] computed per object then averaged, which is what choosing a grasp on one object
needs, while pooled numbers also reward telling objects apart.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..errors import InputError
from .decisions import (
    decision_measures,
    decision_order,
    oracle_good,
    oracle_order,
    random_measures,
    task_feasible,
)
from .evaluation import average_precision, comparison_accuracy, gms_distribution

MEASURES = ("top1_viable", "top1_feasible", "top1_percentile", "topk_precision")


def within_object(objects, truth, scores, *, kind: str, lower_is_better: bool = True, seed=0):
    """Metrics computed within each object, then averaged over objects.

    Parameters
    ----------
    objects : (n,) array_like of str
        Object of each row.
    truth : (n,) array_like of float
        True values (regression, on the target's scale) or labels (classification).
    scores : (n,) array_like of float
        The model's outputs.
    kind : str
        ``"regression"``: comparison accuracy and E[GMS] per object; ``"classification"``:
        average precision per object (objects without a positive are skipped).
    lower_is_better : bool
        As for :func:`~affordgrasp.learning.evaluation.global_min_score`.
    seed : int
        Seeds the random pairs and subsets.

    Returns
    -------
    dict
        ``per_object`` (object → metrics) and the mean over objects of each metric
        (``comparison_accuracy``, ``expected_gms`` and ``random_expected_gms``, the E[GMS]
        of a random choice on the same subsets; or ``average_precision`` and
        ``positive_rate``, the AP of a random score), NaN where no object qualifies.
    """
    objects = np.asarray(objects, dtype=object)
    t = np.asarray(truth, dtype=np.float64)
    s = np.asarray(scores, dtype=np.float64)
    per: dict[str, dict] = {}
    for name in sorted(set(objects.tolist())):
        m = objects == name
        if kind == "regression":
            if m.sum() < 2:
                continue
            g = gms_distribution(
                t[m], s[m], seed=seed, n_subsets=200, lower_is_better=lower_is_better
            )
            # a random choice on the same subsets: small objects have small subsets, whose
            # GMS is low whatever the model (at most (k - 1) / k for k rows)
            noise = np.random.default_rng(seed).random(int(m.sum()))
            r = gms_distribution(
                t[m], noise, seed=seed, n_subsets=200, lower_is_better=lower_is_better
            )
            per[name] = {
                "n": int(m.sum()),
                "comparison_accuracy": comparison_accuracy(t[m], s[m], seed=seed),
                "expected_gms": float(np.mean(g)) if len(g) else float("nan"),
                "random_expected_gms": float(np.mean(r)) if len(r) else float("nan"),
            }
        else:
            if not np.any(t[m] > 0.5):
                continue
            per[name] = {
                "n": int(m.sum()),
                "positive_rate": float(np.mean(t[m] > 0.5)),
                "average_precision": average_precision(t[m], s[m]),
            }
    keys = (
        ("comparison_accuracy", "expected_gms", "random_expected_gms")
        if kind == "regression"
        else ("average_precision", "positive_rate")
    )
    out: dict[str, Any] = {"per_object": per, "objects": len(per)}
    for k in keys:
        vals = [v[k] for v in per.values() if np.isfinite(v[k])]
        out[k] = float(np.mean(vals)) if vals else float("nan")
    return out


def object_mean_baseline(objects, truth, *, lower_is_better: bool = True, seed: int = 0) -> dict:
    """Pooled metrics of predicting each object's own mean true value.

    Parameters
    ----------
    objects : (n,) array_like of str
    truth : (n,) array_like of float
    lower_is_better : bool
    seed : int

    Returns
    -------
    dict
        ``comparison_accuracy`` and ``expected_gms`` pooled over objects (within one object
        this predictor ties everywhere: 0.5, and its choice is random).
    """
    objects = np.asarray(objects, dtype=object)
    t = np.asarray(truth, dtype=np.float64)
    pred = np.empty_like(t)
    for name in set(objects.tolist()):
        m = objects == name
        pred[m] = t[m].mean()
    g = gms_distribution(t, pred, seed=seed, n_subsets=1000, lower_is_better=lower_is_better)
    return {
        "comparison_accuracy": comparison_accuracy(t, pred, seed=seed),
        "expected_gms": float(np.mean(g)) if len(g) else float("nan"),
    }


def _mean(rows: list[dict]) -> dict:
    keys = [*MEASURES, *(["top1_robust_viable"] if "top1_robust_viable" in rows[0] else [])]
    return {k: float(np.mean([r[k] for r in rows])) for k in keys}


def evaluate_decisions(
    models: Sequence[tuple[Any, dict]],
    dataset,
    objects: Sequence[str],
    *,
    task: str = "pick",
    mode: str = "default",
    candidates: int = 64,
    draws: int = 20,
    seed: int = 0,
    baseline: Sequence[tuple[Any, dict]] | None = None,
    threshold: float | None = None,
    physics: bool = False,
    progress: Callable[[int], Any] | None = None,
) -> dict:
    """The decisions of models on some objects of a dataset, beside baselines.

    For each object, ``draws`` sets of ``candidates`` rows are drawn (without replacement
    within a set; one set of all rows when the object has no more than ``candidates``);
    the models predict on their rows (depth read or rendered) and choose; the rows' stored
    metrics give the truth.

    Parameters
    ----------
    models : sequence of (torch.nn.Module, dict)
        At most one classifier and one regressor.
    dataset : path or Dataset
        A dataset generated with metrics (opened once).
    objects : sequence of str
        The objects to decide on (held out from the models' training).
    task : str
        The task whose F_T is the truth.
    mode : str
        Its threshold mode.
    candidates : int
        Candidates per decision.
    draws : int
        Candidate sets per object.
    seed : int
        Seeds the draws.
    baseline : sequence of (torch.nn.Module, dict), optional
        A second set of models (e.g. pose-only) deciding on the same candidates.
    threshold : float, optional
        Overrides the classifier's stored decision threshold.
    physics : bool
        Replay the model's choice of each object's first draw in MuJoCo.
    progress : callable, optional
        Called with 1 after each object.

    Returns
    -------
    dict
        ``per_object`` (object → ``rows``, ``draws``, ``model``, ``random``, ``oracle``
        and ``baseline`` measures averaged over its draws, with ``top1_robust_viable``
        when the dataset has robust labels, ``physics``), ``mean`` (each
        decider's measures averaged over objects), ``median_percentile`` (each decider's
        median over every decision), ``physics_hold_rate`` (with ``physics``), ``rule``
        and the settings.
    """
    from ..dataset.handle import Dataset
    from ..tasks import get_task, is_viable
    from ..vision.depth import decode_depth_column, depth_to_mm
    from .data import Samples, load_depth, reads_depth
    from .plan import model_order, replay, rule_of, split_models

    if candidates < 1 or draws < 1:
        raise InputError(f"candidates and draws must be >= 1, got {candidates} and {draws}")
    task_obj = get_task(task)
    task_obj.thresholds_for(mode)
    classifier, regressor = split_models(models)
    base = split_models(baseline) if baseline else None
    dataset = Dataset.open(dataset)
    families = dataset.families
    needs_depth = any(reads_depth(c) for _, c in [*models, *(baseline or [])])
    stored = dataset.depth and needs_depth
    names = [c for c in dataset.arrow().schema.names if c != "depth_mm" or stored]
    per: dict[str, dict] = {}
    decisions: dict[str, list[float]] = {"model": [], "random": [], "oracle": []}
    if base:
        decisions["baseline"] = []
    holds = []
    for k, name in enumerate(sorted(objects)):
        table = dataset.read(columns=names, objects=[name])
        n = table.num_rows
        if n == 0:
            continue
        rng = np.random.default_rng(np.random.SeedSequence([seed, k]))
        sets = (
            [rng.permutation(n)]
            if n <= candidates
            else [rng.choice(n, candidates, replace=False) for _ in range(draws)]
        )
        used = np.unique(np.concatenate(sets))
        sub = table.take(used)
        p0 = np.asarray(sub.column("p0").combine_chunks().flatten()).reshape(-1, 6)
        d = np.asarray(sub.column("use_dir").combine_chunks().flatten()).reshape(-1, 2)
        obj_names = np.full(len(used), name, dtype=object)
        samples = Samples(
            obj_names,
            np.full(len(used), families.get(name, name), dtype=object),
            sub.column("sample").to_numpy().astype(np.int64),
            p0,
            d,
            np.full(len(used), np.nan),
            meta={"dataset": dataset},
        )
        if stored:  # read with the rows: one pass over the object's shards
            samples.depth_mm = depth_to_mm(decode_depth_column(sub.column("depth_mm")))
        elif needs_depth:
            load_depth(samples, dataset)
        _, prob, pred = model_order(classifier, regressor, samples, threshold=threshold)
        if base:
            _, bprob, bpred = model_order(*base, samples)
        true_score = task_obj.evaluate(sub, mode)
        viable = is_viable(sub)
        robust = (
            sub.column("robust_viable").to_numpy(zero_copy_only=False).astype(np.float64)
            if "robust_viable" in sub.column_names
            else None
        )
        where = {int(r): i for i, r in enumerate(used)}
        rows: dict[str, list[dict]] = {key: [] for key in decisions}
        first_choice = None
        for draw in sets:
            i = np.array([where[int(r)] for r in draw])
            s, v = true_score[i], viable[i]
            rv = None if robust is None else robust[i]
            order = _draw_order(classifier, regressor, prob, pred, i, threshold)
            f = task_feasible(task_obj, s)
            rows["model"].append(decision_measures(order, s, v, robust_viable=rv, feasible=f))
            if first_choice is None:
                first_choice = int(used[i[order[0]]])
            rows["random"].append(random_measures(s, v, robust_viable=rv, feasible=f))
            best = oracle_order(s, oracle_good(task_obj, s, v))
            rows["oracle"].append(decision_measures(best, s, v, robust_viable=rv, feasible=f))
            if base:
                border = _draw_order(*base, bprob, bpred, i, None)
                rows["baseline"].append(
                    decision_measures(border, s, v, robust_viable=rv, feasible=f)
                )
        entry = {"rows": n, "draws": len(sets), "candidates": min(n, candidates)}
        for key, rs in rows.items():
            entry[key] = _mean(rs)
            decisions[key] += [r["top1_percentile"] for r in rs]
        if physics and first_choice is not None:
            obj = dataset.object(name)
            outcome = replay(obj, dataset.hand, table.slice(first_choice, 1))
            entry["physics"] = outcome
            holds.append(bool(outcome.get("hold_ok")))
        per[name] = entry
        if progress is not None:
            progress(1)
    if not per:
        raise InputError(
            f"none of the objects {list(objects)} has rows in {str(dataset.directory)!r}"
        )
    out = {
        "task": task_obj.name,
        "mode": mode,
        "candidates": candidates,
        "draws": draws,
        "rule": rule_of(classifier, regressor, threshold),
        "baseline_rule": rule_of(*base) if base else None,
        "objects": len(per),
        "per_object": per,
        "mean": {key: _mean([e[key] for e in per.values()]) for key in decisions},
        "median_percentile": {key: float(np.median(v)) for key, v in decisions.items()},
    }
    if physics:
        out["physics_hold_rate"] = float(np.mean(holds)) if holds else float("nan")
    return out


def _draw_order(classifier, regressor, prob, pred, i, threshold):
    """The decision order of one draw of candidates ``i`` for a (classifier, regressor) pair."""
    return decision_order(
        None if prob is None else prob[i],
        None if pred is None else pred[i],
        threshold=0.5 if classifier is None else _threshold(classifier, threshold),
        lower_is_better=True if regressor is None else regressor[1]["target"]["lower_is_better"],
    )


def _threshold(classifier, override):
    from .decisions import decision_threshold

    return decision_threshold(classifier[1]) if override is None else float(override)
