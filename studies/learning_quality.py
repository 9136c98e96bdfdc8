"""The paper's Table II protocol on held-out objects, classifier AP, and K-candidate ranking.

    python tools/train_default_models.py --data DATA        # dataset + shipped models
    python studies/learning_quality.py --data DATA --models DIR --plots DIR --json out.json

On the dataset of ``train_default_models.py`` (13 families x 5 instances x 1500 samples,
split by object instance, seed 0), it trains (or loads from ``--models``) the regressors of
ΣE_h on viable grasps (normalised from [0, 250] as the paper) — CNN, PointNet full, PointNet
slim, the pose-only baseline and the shipped CNN with a ranking loss — and the viability
classifiers, then prints

1. Table II: MSE, comparison accuracy, E[GMS] on the held-out test objects, our rows beside
   the paper's and beside predict-the-mean;
2. classifier average precision (natural class balance and balanced) beside the positive
   rate and the pose-only classifier;
3. K-candidate ranking, per task: on each held-out object, K candidate (p0, d) with their
   depth images; the models choose one; its simulated task score is compared with a random
   choice and with the simulation oracle (the best of the K).

``--shipped`` adds the shipped models (``affordgrasp predict default``) as rows and uses them
for the K-candidate choice (they must have been trained on this dataset and split).
``--skip`` leaves recipes out (e.g. the 12-epoch copy of the shipped regressor's recipe).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

PAPER = {  # Table II of the paper: MSE, comparison accuracy, expected GMS
    "cnn": (0.049, 0.66, 0.82),
    "pointnet": (0.050, 0.63, 0.63),
    "pointnet-slim": (0.049, 0.60, 0.73),
}
REGRESSORS = {
    "cnn": {"arch": "cnn", "rank_weight": 0.0},
    "cnn+rank": {"arch": "cnn", "rank_weight": 1.0},
    "cnn+rank+canonical": {"arch": "cnn", "rank_weight": 1.0, "canonical": True},
    "pose": {"arch": "pose", "rank_weight": 0.0},
    "pointnet-slim": {"arch": "pointnet-slim", "rank_weight": 0.0},
    "pointnet": {"arch": "pointnet", "rank_weight": 0.0},
}
CLASSIFIERS = {
    "cnn": {"arch": "cnn"},
    "cnn-canonical": {"arch": "cnn", "canonical": True},
    "pose": {"arch": "pose"},
    "pointnet-slim": {"arch": "pointnet-slim"},
}


def trained(models_dir: Path, name: str, target: str, recipe: dict, prepared, data, epochs, seed=0):
    """Load models_dir/name.safetensors if it is this recipe on this data, else train it."""
    from affordgrasp.learning.api import train_on_dataset
    from affordgrasp.learning.io import load_model
    from affordgrasp.learning.training import TrainSettings

    path = models_dir / f"{name}.safetensors"
    if path.exists():
        model, config = load_model(path)
        same = (
            config["arch"] == recipe["arch"]
            and config["target"]["name"] == target
            and config["training"]["settings"]["rank_weight"] == recipe.get("rank_weight", 0.0)
            and config["training"]["split"]["test"] == list(prepared[4].test)
            and bool(config.get("canonical")) == recipe.get("canonical", False)
            and config["training"]["settings"]["epochs"] == epochs
            and config["training"]["settings"]["seed"] == seed
        )
        if same:
            return model, config, 0.0, 0.0
    started, cpu = time.perf_counter(), time.process_time()
    settings = TrainSettings(epochs=epochs, seed=seed, rank_weight=recipe.get("rank_weight", 0.0))
    model, config = train_on_dataset(
        data,
        arch=recipe["arch"],
        target=target,
        out=path,
        settings=settings,
        prepared=prepared,
        canonical=recipe.get("canonical", False),
    )
    return model, config, time.perf_counter() - started, time.process_time() - cpu


def _check_split(config: dict, split, name: str) -> None:
    """Refuse a model whose held-out objects are not this split's (its test would leak)."""
    if config["training"]["split"]["test"] != list(split.test):
        raise SystemExit(
            f"the {name} model was trained with other test objects than this dataset's split; "
            "run without --shipped or on its dataset"
        )


def k_candidates(data, split, classifier, regressor, *, k=32, trials=40, rows=600, seed=0):
    """Per task: mean GMS-like rank, success rate and oracle-match of model vs random choice."""
    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.dataset.reading import read_dataset
    from affordgrasp.learning.api import predictions_of
    from affordgrasp.learning.data import load_depth, read_rows
    from affordgrasp.tasks import evaluate_task, list_tasks

    data = Dataset.open(data)
    samples, _ = read_rows(data, "viable", objects=list(split.test))
    keep = np.concatenate(
        [np.flatnonzero(samples.object == o)[:rows] for o in sorted(set(samples.object))]
    )
    samples = samples.take(keep)
    load_depth(samples, data)
    p_viable = predictions_of(*classifier, samples)
    effort = predictions_of(*regressor, samples)
    table = read_dataset(data, objects=list(split.test))
    names = np.asarray(table.column("object").to_pylist(), dtype=object)
    ids = table.column("sample").to_numpy()
    index = {(o, int(s)): i for i, (o, s) in enumerate(zip(names, ids, strict=True))}
    rows_idx = np.array(
        [index[(o, int(s))] for o, s in zip(samples.object, samples.sample, strict=True)]
    )
    table = table.take(rows_idx)
    rng = np.random.default_rng(seed)
    tasks = [t for t in list_tasks() if t != "viable"]
    out = {}
    for task in tasks:
        score = np.asarray(evaluate_task(task, table), dtype=np.float64)
        score = np.where(np.isnan(score), -np.inf, score)
        res = {"random": [], "oracle": []}
        for obj in sorted(set(samples.object)):
            pool = np.flatnonzero(samples.object == obj)
            for _ in range(trials):
                cand = rng.choice(pool, min(k, len(pool)), replace=False)
                s = score[cand]
                p, e = p_viable[cand], effort[cand]
                best = s.max()
                choices = {
                    # the paper's composition: the classifier filters (p >= 0.5), the
                    # regressor picks the smallest predicted effort among the kept
                    "model: filter+regress": np.lexsort((e, p < 0.5))[0],
                    # the most likely viable grasp
                    "model: most viable": int(np.argmax(p)),
                    # the smallest predicted effort among the 4 most likely viable
                    "model: top-4 + regress": np.argsort(-p)[:4][np.argmin(e[np.argsort(-p)[:4]])],
                }
                for who, i in choices.items():
                    value = s[i]
                    res.setdefault(who, []).append(
                        (np.isfinite(value), np.mean(s < value), value == best, value)
                    )
                res["oracle"].append((np.isfinite(best), np.mean(s < best), True, best))
                # random: the exact expectation over the K candidates
                res["random"].append(
                    (
                        np.mean(np.isfinite(s)),
                        np.mean([np.mean(s < v) for v in s]),
                        np.mean(s == best),
                        np.nan,
                    )
                )
        out[task] = {
            who: {
                "success_rate": float(np.mean([r[0] for r in rs])),
                "mean_rank": float(np.mean([r[1] for r in rs])),
                "oracle_match": float(np.mean([r[2] for r in rs])),
                "median_finite_score": (
                    float(np.median([r[3] for r in rs if np.isfinite(r[3])]))
                    if who != "random" and any(np.isfinite(r[3]) for r in rs)
                    else None
                ),
            }
            for who, rs in res.items()
        }
    return out


def main() -> None:
    from affordgrasp.learning.api import prepare_split
    from affordgrasp.learning.plots import plot_gms_cdf, plot_pr_curves

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--models", type=Path, required=True, help="trained models (cache)")
    parser.add_argument("--plots", type=Path, default=None)
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--epochs", type=int, default=40)
    parser.add_argument("--only", default=None, help="comma-separated regressors/classifiers")
    parser.add_argument("--k", type=int, default=32)
    parser.add_argument("--skip", default=None, help="comma-separated recipes to leave out")
    parser.add_argument(
        "--seeds", default="0", help="comma-separated training seeds of the regressors"
    )
    parser.add_argument(
        "--parts",
        default="regressors,classifiers,k",
        help="which parts to run: regressors, classifiers, k (K candidates)",
    )
    parser.add_argument(
        "--shipped", action="store_true", help="add the shipped models; use them for K candidates"
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every epoch")
    args = parser.parse_args()
    if args.verbose:
        import logging

        logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    args.models.mkdir(parents=True, exist_ok=True)
    only = set(args.only.split(",")) if args.only else None
    skip = set(args.skip.split(",")) if args.skip else set()
    seeds = [int(x) for x in args.seeds.split(",")]
    parts = set(args.parts.split(","))
    shipped = {}
    if args.shipped:
        from affordgrasp.learning.api import pretrained_path
        from affordgrasp.learning.io import load_model

        shipped = {k: load_model(pretrained_path(k)) for k in ("classifier", "regressor")}
    results: dict = {"regressors": {}, "classifiers": {}, "seconds": {}}

    t0 = time.perf_counter()
    reg = prepare_split(args.data, "hold_effort_sum", seed=0)
    print(
        f"regression rows: train {len(reg[0])}, val {len(reg[1])}, test {len(reg[2])}; "
        f"test objects {', '.join(reg[4].test)} ({time.perf_counter() - t0:.0f} s to load)"
    )
    runs = {}
    reg_recipes = {k: v for k, v in REGRESSORS.items() if (not only or k in only) and k not in skip}
    if "regressors" not in parts:
        reg_recipes = {}
    if "regressor" in shipped:
        reg_recipes["shipped"] = None
    keys = ("mse", "comparison_accuracy", "expected_gms")
    for name, recipe in reg_recipes.items():
        reports = []
        for seed in [0] if recipe is None else seeds:
            if recipe is None:
                model, config = shipped["regressor"]
                _check_split(config, reg[4], name)
                secs = cpu = 0.0
            else:
                model, config, secs, cpu = trained(
                    args.models,
                    f"reg_{name}" + (f"_s{seed}" if seed else ""),
                    "hold_effort_sum",
                    recipe,
                    reg,
                    args.data,
                    args.epochs,
                    seed,
                )
            from affordgrasp.learning.api import Inputs, predict_scores, report

            scores = predict_scores(model, config, Inputs(config, reg[2]))
            if seed == seeds[0] or recipe is None:
                runs[name] = scores
            reports.append(report(model, config, reg[2], scores=scores))
            reports[-1]["epochs"] = len(config["training"]["history"])
            tag = f"reg_{name}_s{seed}"
            results["seconds"][tag] = secs or config["training"]["seconds"]
            if cpu:
                results.setdefault("cpu_seconds", {})[tag] = cpu
                print(f"  trained {name} seed {seed} in {secs:.0f} s ({cpu:.0f} CPU-s)", flush=True)
            print(f"  {name} seed {seed}: {json.dumps(reports[-1])}", flush=True)
        results.setdefault("regressors_by_seed", {})[name] = reports
        results["regressors"][name] = {k: float(np.mean([r[k] for r in reports])) for k in keys}
        if args.json:
            args.json.write_text(json.dumps(results, indent=2, default=float))
    truth = reg[3].normalise(reg[2].y)
    print(
        "\nTable II (ΣE_h regressors, held-out objects; paper's values in brackets; "
        f"mean [min-max] over seeds {args.seeds} where trained)"
    )
    print(f"{'model':16s} {'MSE':>14s} {'comparison':>22s} {'E[GMS]':>22s}")
    mean = float(np.mean(reg[3].normalise(reg[0].y)))
    base = {
        "mse": float(np.mean((truth - mean) ** 2)),
        "comparison_accuracy": 0.5,
        "expected_gms": 0.5,
    }
    for name, rep in list(results["regressors"].items()) + [("predict-the-mean", base)]:
        paper = PAPER.get(name)
        by_seed = results.get("regressors_by_seed", {}).get(name, [])
        cells = []
        for i, key in enumerate(keys):
            cell = f"{rep[key]:.3f}"
            if len(by_seed) > 1 and key != "mse":
                vals = [r[key] for r in by_seed]
                cell += f" [{min(vals):.3f}-{max(vals):.3f}]"
            cells.append(cell + (f" ({paper[i]:.3f})" if paper else ""))
        print(f"{name:16s} {cells[0]:>14s} {cells[1]:>22s} {cells[2]:>22s}")
    results["regressors"]["predict-the-mean"] = base

    cls = prepare_split(args.data, "viable", seed=0)
    print(
        f"\nclassification rows: train {len(cls[0])} ({int(cls[0].y.sum())} viable), "
        f"test {len(cls[2])} ({int(cls[2].y.sum())} viable)"
    )
    cls_runs, cls_models = {}, {}
    cls_recipes = {
        k: v for k, v in CLASSIFIERS.items() if (not only or k in only) and k not in skip
    }
    if "classifiers" not in parts:
        cls_recipes = {}
    if "classifier" in shipped:
        cls_recipes["shipped"] = None
    for name, recipe in cls_recipes.items():
        if recipe is None:
            model, config = shipped["classifier"]
            _check_split(config, cls[4], name)
            secs = cpu = 0.0
        else:
            model, config, secs, cpu = trained(
                args.models, f"cls_{name}", "viable", recipe, cls, args.data, args.epochs
            )
        from affordgrasp.learning.api import Inputs, predict_scores, report

        cls_runs[name] = predict_scores(model, config, Inputs(config, cls[2]))
        results["classifiers"][name] = t = report(model, config, cls[2], scores=cls_runs[name])
        results["seconds"][f"cls_{name}"] = secs or config["training"]["seconds"]
        if cpu:
            results.setdefault("cpu_seconds", {})[f"cls_{name}"] = cpu
            print(f"  trained {name} in {secs:.0f} s ({cpu:.0f} CPU-s)", flush=True)
        cls_models[name] = (model, config)
        t["epochs"] = len(config["training"]["history"])
        print(
            f"  {name}: AP {t['average_precision']:.3f} (positive rate "
            f"{t['positive_rate']:.3f}), balanced AP {t['average_precision_balanced']:.3f}",
            flush=True,
        )
        if args.json:
            args.json.write_text(json.dumps(results, indent=2, default=float))

    if args.plots:
        args.plots.mkdir(parents=True, exist_ok=True)
        gms_runs = {k: (truth, v) for k, v in runs.items()}
        gms_runs["predict-the-mean"] = (truth, np.full(len(truth), mean))
        plot_gms_cdf(args.plots / "gms_cdf.png", gms_runs)
        plot_pr_curves(
            args.plots / "pr_curves.png",
            {k: (cls[2].y, v) for k, v in cls_runs.items()},
            float(np.mean(cls[2].y)),
        )

    cls_for_k = next((n for n in ("shipped", "cnn-canonical", "cnn") if n in cls_models), None)
    reg_for_k = ("shipped", "cnn+rank+canonical", "cnn+rank", "cnn")
    if "k" in parts and cls_for_k is not None and set(reg_for_k) & set(runs):
        from affordgrasp.learning.io import load_model

        reg_name = next(n for n in reg_for_k if n in runs)
        if reg_name == "shipped":
            regressor = shipped["regressor"]
        else:
            regressor = load_model(args.models / f"reg_{reg_name}.safetensors")
        t0 = time.perf_counter()
        kc = k_candidates(args.data, reg[4], cls_models[cls_for_k], regressor, k=args.k)
        results["k_candidates"] = {
            "k": args.k,
            "classifier": cls_for_k,
            "regressor": reg_name,
            "tasks": kc,
        }
        print(
            f"\nK = {args.k} candidates per choice, held-out objects "
            f"({time.perf_counter() - t0:.0f} s)"
        )
        print(
            f"{'task':10s} {'who':8s} {'success':>8s} {'mean rank':>10s} {'= oracle':>9s} "
            f"{'median score':>13s}"
        )
        for task, by in kc.items():
            for who, r in by.items():
                med = r["median_finite_score"]
                print(
                    f"{task:10s} {who:8s} {r['success_rate']:8.3f} {r['mean_rank']:10.3f} "
                    f"{r['oracle_match']:9.3f} {'-' if med is None else f'{med:.4g}':>13s}"
                )
    if args.json:
        args.json.write_text(json.dumps(results, indent=2, default=float))


if __name__ == "__main__":
    main()
