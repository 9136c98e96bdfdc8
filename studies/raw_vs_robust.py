"""Raw vs robust learning targets, judged on held-out objects by the grasps the models choose.

    python tools/train_default_models.py --data TRAIN --samples 300 --robust 25 \\
        --targets raw,robust --calibrate --out MODELS
    python studies/raw_vs_robust.py --data HELDOUT --models MODELS --out result.json

HELDOUT is a dataset generated with ``--robust K`` (so every row carries both the raw and
the robust truth) of objects the models never saw. MODELS holds the four models the first
command trains (``default_*``: ``viable`` and ``hold_effort_sum``; ``robust_*``:
``robust_viable>=0.5`` and ``robust_hold``); ``--shipped`` adds the shipped pair.

Every model predicts on every held-out row once; then, per object and averaged over
objects:

* each classifier's AP at the natural rate and its expected calibration error (10 bins),
  against both labels (``viable`` and ``robust_viable>=0.5``), pooled and within objects;
* each regressor's (and classifier's) comparison accuracy and E[GMS] against both graded
  targets: ΣE_h on the viable rows (less is better) and ``robust_hold`` on every row (more
  is better), within each object then the mean, and pooled;
* the decisions for pick: on each object, ``--draws`` sets of ``--candidates`` rows (the
  draws of ``model-eval``: seeded by (seed, the object's index in sorted order)); each
  decider's first choice is judged by the rows' stored truth: viable, robust viable rate
  (the share of its perturbed copies that stay viable), ``robust_viable >= 0.5``, the
  percentile of its pick score and of its ``robust_hold`` among the candidates; beside the
  exact expectation of a random choice and the two oracles (by raw pick score, by
  ``robust_hold``);
* the oracle's chance of having a viable (robust viable) candidate at all among N uniform
  candidates, exact (hypergeometric) from each object's rows, for N up to the rows.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from affordgrasp.dataset.handle import Dataset
from affordgrasp.learning.api import predictions_of
from affordgrasp.learning.data import Samples
from affordgrasp.learning.decision_eval import object_mean_baseline, within_object
from affordgrasp.learning.decisions import (
    decision_order,
    decision_threshold,
    oracle_hit_rate,
    true_percentiles,
)
from affordgrasp.learning.evaluation import (
    average_precision,
    comparison_accuracy,
    expected_calibration_error,
    gms_distribution,
)
from affordgrasp.learning.io import load_model
from affordgrasp.tasks import get_task, is_viable
from affordgrasp.vision.depth import decode_depth_column, depth_to_mm

MODEL_FILES = {
    "raw classifier": "default_classifier.safetensors",
    "raw regressor": "default_regressor.safetensors",
    "robust classifier": "robust_classifier.safetensors",
    "robust regressor": "robust_regressor.safetensors",
}
ROBUST_LEVEL = 0.5
# the shipped classifier's training objects' viable rate (docs/learning.md, "Shipped models")
SHIPPED_POSITIVE_RATE = 0.058


def predict_all(dataset: Dataset, models: dict):
    """Every model's predictions on every row, with the rows' truth, object by object."""
    families = dataset.families
    out: dict[str, list] = {k: [] for k in ("object", "sample", "table")}
    preds: dict[str, list] = {k: [] for k in models}
    for name in sorted(dataset.objects):
        table = dataset.read(columns=None, objects=[name])
        n = table.num_rows
        if n == 0:  # not generated (yet)
            continue
        samples = Samples(
            np.full(n, name, dtype=object),
            np.full(n, families.get(name, name), dtype=object),
            table.column("sample").to_numpy().astype(np.int64),
            np.asarray(table.column("p0").combine_chunks().flatten()).reshape(-1, 6),
            np.asarray(table.column("use_dir").combine_chunks().flatten()).reshape(-1, 2),
            np.full(n, np.nan),
        )
        samples.depth_mm = depth_to_mm(decode_depth_column(table.column("depth_mm")))
        for key, (model, config) in models.items():
            preds[key].append(predictions_of(model, config, samples))
        out["object"].append(samples.object)
        out["sample"].append(samples.sample)
        out["table"].append(table.drop_columns(["depth_mm"]))
    return out, {k: np.concatenate(v) for k, v in preds.items()}


def oriented_score(config: dict, values: np.ndarray) -> np.ndarray:
    """A model's output as a 'higher is better' score."""
    tgt = config["target"]
    return -values if tgt["kind"] == "regression" and tgt["lower_is_better"] else values


def graded_metrics(objects, truth, score, seed: int) -> dict:
    """Comparison accuracy and E[GMS], within objects (mean) and pooled; higher is better."""
    w = within_object(objects, truth, score, kind="regression", lower_is_better=False, seed=seed)
    g = gms_distribution(truth, score, seed=seed, n_subsets=1000, lower_is_better=False)
    return {
        "within_comparison": w["comparison_accuracy"],
        "within_gms": w["expected_gms"],
        "within_random_gms": w["random_expected_gms"],
        "objects": w["objects"],
        "pooled_comparison": comparison_accuracy(truth, score, seed=seed),
        "pooled_gms": float(np.mean(g)),
    }


def label_metrics(objects, labels, prob) -> dict:
    """AP (pooled, natural rate; within objects, mean) and ECE of probabilities."""
    w = within_object(objects, labels, prob, kind="classification")
    return {
        "rate": float(np.mean(labels)),
        "ap": average_precision(labels, prob),
        "within_ap": w["average_precision"],
        "within_rate": w["positive_rate"],
        "objects_with_positive": w["objects"],
        "ece": expected_calibration_error(labels, prob),
    }


def decide(deciders, objects, truth, *, candidates: int, draws: int, seed: int) -> dict:
    """Decision measures of each decider, per object then averaged over objects."""
    names = sorted(set(objects.tolist()))
    per: dict[str, dict[str, list[dict]]] = {}
    medians: dict[str, list[float]] = {}
    for k, name in enumerate(names):
        rows = np.flatnonzero(objects == name)
        n = len(rows)
        rng = np.random.default_rng(np.random.SeedSequence([seed, k]))
        sets = (
            [rng.permutation(n)]
            if n <= candidates
            else [rng.choice(n, candidates, replace=False) for _ in range(draws)]
        )
        per[name] = {}
        for draw in sets:
            i = rows[draw]
            score = truth["pick"][i]
            hold = truth["robust_hold"][i]
            pct = true_percentiles(score)
            pct_hold = true_percentiles(hold)
            viable = truth["viable"][i]
            rv = truth["robust_viable"][i]
            choices = {key: int(order_of(i)[0]) for key, order_of in deciders.items()}
            choices["oracle (pick)"] = int(
                np.lexsort((~viable, -np.nan_to_num(score, nan=-np.inf)))[0]
            )
            choices["oracle (robust_hold)"] = int(np.argmax(hold))
            for key, c in choices.items():
                m = {
                    "viable": float(viable[c]),
                    "robust_viable": float(rv[c]),
                    "robust_viable_ok": float(rv[c] >= ROBUST_LEVEL),
                    "feasible": float(np.isfinite(score[c])),
                    "percentile": float(pct[c]),
                    "percentile_robust_hold": float(pct_hold[c]),
                }
                per[name].setdefault(key, []).append(m)
                medians.setdefault(key, []).append(m["percentile"])
            m = {
                "viable": float(viable.mean()),
                "robust_viable": float(rv.mean()),
                "robust_viable_ok": float(np.mean(rv >= ROBUST_LEVEL)),
                "feasible": float(np.isfinite(score).mean()),
                "percentile": float(pct.mean()),
                "percentile_robust_hold": float(pct_hold.mean()),
            }
            per[name].setdefault("random", []).append(m)
            medians.setdefault("random", []).append(50.0)
    keys = list(next(iter(per.values())).keys())
    measures = list(next(iter(per.values()))[keys[0]][0].keys())
    per_object = {
        name: {
            key: {m: float(np.mean([r[m] for r in rs])) for m in measures} for key, rs in d.items()
        }
        for name, d in per.items()
    }
    mean = {
        key: {m: float(np.mean([per_object[o][key][m] for o in per_object])) for m in measures}
        for key in keys
    }
    for key in keys:
        mean[key]["median_percentile"] = float(np.median(medians[key]))
    return {"mean": mean, "per_object": per_object}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True, help="held-out dataset (--robust K)")
    parser.add_argument("--models", type=Path, required=True, help="directory of the 4 models")
    parser.add_argument("--shipped", action="store_true", help="also the shipped pair")
    parser.add_argument("--candidates", type=int, default=64)
    parser.add_argument("--draws", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None, help="write the results (JSON)")
    args = parser.parse_args()

    import torch

    torch.set_num_threads(1)
    started = time.process_time()
    models = {}
    for key, f in MODEL_FILES.items():
        if (args.models / f).exists():
            models[key] = load_model(args.models / f)
    if args.shipped:
        from affordgrasp.learning.api import pretrained_path

        models["shipped classifier"] = load_model(pretrained_path("classifier"))
        models["shipped regressor"] = load_model(pretrained_path("regressor"))
    dataset = Dataset.open(args.data)
    if "robust_viable" not in dataset.arrow().schema.names:
        parser.error(f"{args.data} has no robust labels: generate it with --robust K")
    rows, preds = predict_all(dataset, models)
    import pyarrow as pa

    table = pa.concat_tables(rows["table"])
    objects = np.concatenate(rows["object"])
    pick = np.asarray(get_task("pick").evaluate(table, "default"), dtype=np.float64)
    viable = is_viable(table)
    rv = table.column("robust_viable").to_numpy(zero_copy_only=False).astype(np.float64)
    hold = table.column("robust_hold").to_numpy(zero_copy_only=False).astype(np.float64)
    truth = {"pick": pick, "viable": viable, "robust_viable": rv, "robust_hold": hold}
    labels = {
        "viable": viable.astype(float),
        f"robust_viable>={ROBUST_LEVEL:g}": (rv >= ROBUST_LEVEL).astype(float),
    }
    from affordgrasp.learning.targets import target_values

    hold_sum = target_values("hold_effort_sum", table)
    result: dict = {
        "rows": int(len(objects)),
        "objects": sorted(set(objects.tolist())),
        "label_rates": {k: float(v.mean()) for k, v in labels.items()},
        "classifiers": {},
        "graded": {},
    }
    for key, (_model, config) in models.items():
        p = preds[key]
        s = oriented_score(config, p)
        if config["target"]["kind"] == "classification":
            result["classifiers"][key] = {
                lab: label_metrics(objects, y, p) for lab, y in labels.items()
            }
        result["graded"][key] = {
            "hold_effort_sum (viable rows)": graded_metrics(
                objects[viable], -hold_sum[viable], s[viable], args.seed
            ),
            "robust_hold (all rows)": graded_metrics(objects, hold, s, args.seed),
        }
    if "shipped classifier" in models:  # shipped without a calibration: the documented map
        rate = SHIPPED_POSITIVE_RATE
        p = preds["shipped classifier"]
        odds = p / np.maximum(1 - p, 1e-12) * rate / (1 - rate)
        result["classifiers"]["shipped classifier, prior shift"] = {
            lab: label_metrics(objects, y, odds / (1 + odds)) for lab, y in labels.items()
        }
    result["graded"]["object mean"] = {
        "hold_effort_sum (viable rows)": object_mean_baseline(
            objects[viable], -hold_sum[viable], lower_is_better=False, seed=args.seed
        ),
        "robust_hold (all rows)": object_mean_baseline(
            objects, hold, lower_is_better=False, seed=args.seed
        ),
    }

    def rule(classifier, regressor):
        c = models.get(classifier)
        r = models.get(regressor)
        if c is None and r is None:
            return None
        t = 0.5 if c is None else decision_threshold(c[1])
        lower = True if r is None else bool(r[1]["target"]["lower_is_better"])
        pc = None if c is None else preds[classifier]
        pr = None if r is None else preds[regressor]
        return lambda i: decision_order(
            None if pc is None else pc[i],
            None if pr is None else pr[i],
            threshold=t,
            lower_is_better=lower,
        )

    deciders = {
        "raw pair (classifier then least ΣE_h)": rule("raw classifier", "raw regressor"),
        "robust pair (classifier then most robust_hold)": rule(
            "robust classifier", "robust regressor"
        ),
        "raw classifier alone": rule("raw classifier", None),
        "robust classifier alone": rule("robust classifier", None),
        "raw regressor alone": rule(None, "raw regressor"),
        "robust regressor alone": rule(None, "robust regressor"),
        "shipped pair": rule("shipped classifier", "shipped regressor"),
    }
    deciders = {
        k: v
        for k, v in deciders.items()
        if v is not None and all(part in models for part in _parts(k))
    }
    result["decisions"] = decide(
        deciders, objects, truth, candidates=args.candidates, draws=args.draws, seed=args.seed
    )
    most = min(int((objects == o).sum()) for o in result["objects"])
    counts = [c for c in (16, 32, 64, 128, 256, 512, 1024) if c <= most]
    oracle = {}
    for lab, y in (("viable", viable), ("robust_viable>=0.5", rv >= ROBUST_LEVEL)):
        per = {}
        for name in result["objects"]:
            m = objects == name
            per[name] = {str(c): oracle_hit_rate(int(m.sum()), int(y[m].sum()), c) for c in counts}
        oracle[lab] = {str(c): float(np.nanmean([per[o][str(c)] for o in per])) for c in counts}
    result["oracle_by_candidates"] = oracle
    result["cpu_s"] = time.process_time() - started
    print(json.dumps(_rounded(result, drop=("per_object",)), indent=1))
    if args.out:
        args.out.write_text(json.dumps(result, indent=1))


def _parts(decider: str) -> list[str]:
    if decider.startswith("shipped"):
        return ["shipped classifier", "shipped regressor"]
    kind = "raw" if decider.startswith("raw") else "robust"
    if "pair" in decider:
        return [f"{kind} classifier", f"{kind} regressor"]
    return [f"{kind} {'classifier' if 'classifier' in decider else 'regressor'}"]


def _rounded(x, drop=()):
    if isinstance(x, dict):
        return {k: _rounded(v, drop) for k, v in x.items() if k not in drop}
    if isinstance(x, list):
        return [_rounded(v, drop) for v in x]
    if isinstance(x, float):
        return round(x, 4)
    return x


if __name__ == "__main__":
    main()
