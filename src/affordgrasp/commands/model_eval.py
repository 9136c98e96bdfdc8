"""``affordgrasp model-eval``: models on held-out objects beside baselines: pooled and
within-object metrics, calibration, and the decisions they make (the grasp each would
choose among candidates of one object, judged by the simulated truth), with PNG plots
(precision–recall and reliability for classifiers; GMS distributions and predicted vs true
for regressors)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..errors import InputError
from .limits import OWN_CHECK, SEED, WORKERS

DECISION_ROWS = (
    ("chosen grasp viable (rate)", "top1_viable"),
    ("chosen grasp task-feasible (rate)", "top1_feasible"),
    ("chosen grasp percentile (mean)", "top1_percentile"),
    ("top-5 precision (viable)", "topk_precision"),
)


# Of the numeric options: see limits.check_limits.
LIMITS = {
    "max_rows": (None, 2**63 - 1, "row counts are 64-bit"),
    "seed": SEED,
    "candidates": (None, 10_000, "a decision's candidates are rendered and scored together"),
    "draws": (None, 10_000, "each candidate set is rendered"),
    "threshold": OWN_CHECK,
    "workers": WORKERS,
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp model-eval`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument(
        "model",
        metavar="MODEL",
        help="a .safetensors model, classifier, regressor, default (both shipped models), "
        "a classifier and a regressor file separated by a comma, or views (the fused views "
        "plan decides with, judged as a classifier of viable and a ranker of robust_hold, "
        "or with views:raw of the raw hold_effort_sum; about 8 s of CPU per 512 rows)",
    )
    p.add_argument("dataset", metavar="DATASET", help="a directory written by 'generate'")
    p.add_argument(
        "--objects",
        default="test",
        help="test (the model's held-out objects, default; every object when the dataset "
        "has none of them, said in the output), all, or comma-separated names",
    )
    p.add_argument(
        "--baseline",
        default=None,
        metavar="MODEL",
        help="a second model, or classifier,regressor pair (e.g. pose-only) to compare",
    )
    p.add_argument("--plots", default=None, metavar="DIR", help="write PNG plots here")
    p.add_argument(
        "--max-rows",
        type=int,
        default=20000,
        help="most rows for the pooled metrics (default 20000; a uniform subsample, said in "
        "the output when taken; 0: every row)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the random pairs and subsets")
    p.add_argument("--task", default="pick", help="task that judges decisions (default pick)")
    p.add_argument("--mode", default="default", help="threshold mode of the task")
    p.add_argument(
        "--candidates", type=int, default=64, help="candidates per decision (default 64)"
    )
    p.add_argument("--draws", type=int, default=20, help="candidate sets per object (default 20)")
    p.add_argument(
        "--threshold",
        type=float,
        default=None,
        help="classifier decision threshold (default: stored in the model, else 0.5)",
    )
    p.add_argument(
        "--no-decisions", action="store_true", help="skip the decision metrics (pooled only)"
    )
    p.add_argument(
        "--physics",
        action="store_true",
        help="replay the chosen grasp of each object's first draw in MuJoCo",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="K",
        help="with the views: processes simulating objects side by side (default: all cores)",
    )


def _split_spec(spec: str):
    return spec.split(",") if "," in spec else spec


def _load(spec, workers: int = 1):
    from .predict import load_models

    if isinstance(spec, list):
        return [m for s in spec for m in load_models(s, workers=workers)]
    return load_models(spec, workers=workers)


def _judged(models, dataset):
    """The models whose target the dataset holds: the views' ranker of robust_hold needs
    robust labels (said when left out)."""
    from ..dataset.handle import Dataset

    def views_ranker(config: dict) -> bool:
        return config.get("arch") == "views" and config["target"]["name"] == "robust_hold"

    if not any(views_ranker(c) for _, c in models):
        return models
    if "robust_hold" in Dataset.open(dataset).arrow().schema.names:
        return models
    kept = [(m, c) for m, c in models if not views_ranker(c)]
    if len(kept) < len(models):
        print(
            "model-eval: views: the dataset has no robust labels (generate it with --robust "
            "K): its ranker of robust_hold is not judged, the classifier alone decides",
            file=sys.stderr,
        )
    return kept


def run(args, out) -> None:
    """Run ``affordgrasp model-eval``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..learning.api import evaluate_on_dataset
    from ..runtime.engines import default_workers

    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers must be >= 1, got {args.workers}")
    if args.max_rows < 0 or args.max_rows == 1:
        raise InputError(f"--max-rows must be 0 (every row) or >= 2, got {args.max_rows}")
    if args.candidates < 1 or args.draws < 1:
        raise InputError(
            f"--candidates and --draws must be >= 1, got {args.candidates} and {args.draws}"
        )
    if args.threshold is not None and not 0.0 <= args.threshold <= 1.0:
        raise InputError(f"--threshold must be a probability in [0, 1], got {args.threshold}")
    if not args.no_decisions:
        from ..tasks import get_task

        get_task(args.task).thresholds_for(args.mode)  # an unknown task or mode: refused now
    if args.plots:
        from .output_files import check_output_dir

        check_output_dir(args.plots, "--plots")
    max_rows = args.max_rows or None
    objects = args.objects if args.objects in ("test", "all") else args.objects.split(",")
    workers = args.workers or default_workers()
    models = _judged(_load(_split_spec(args.model), workers), args.dataset)
    baseline = _load(_split_spec(args.baseline)) if args.baseline else []
    from ..learning.plan import split_models

    split_models(models)  # at most one classifier and one regressor
    if baseline:
        split_models(baseline)
    document: dict = {"models": [], "plots": []}
    plots: list = []
    chosen_objects: set[str] = set()
    for model, config in models:
        rep, samples, scores = evaluate_on_dataset(
            model, config, args.dataset, objects=objects, seed=args.seed, max_rows=max_rows
        )
        chosen_objects |= set(samples.object)
        base = None
        for bmodel, bconfig in baseline:
            if bconfig["target"]["name"] == config["target"]["name"]:
                base = evaluate_on_dataset(
                    bmodel,
                    bconfig,
                    args.dataset,
                    objects=sorted(set(samples.object)),
                    seed=args.seed,
                    max_rows=max_rows,
                )
                bsel = base[0]["selection"]
                if bsel["subsampled"]:  # said, as for the model (never silently)
                    print(
                        f"model-eval: baseline {bconfig['arch']} on {bconfig['target']['name']}: "
                        f"evaluating a uniform subsample of {bsel['rows_evaluated']} of "
                        f"{bsel['rows_available']} rows (--max-rows)",
                        file=sys.stderr,
                    )
        document["models"].append(
            _pooled(args, out, model, config, rep, samples, scores, base, plots)
        )
    if not baseline:
        out.text(
            "pose-only baseline: none given (train one with 'affordgrasp train --model pose' "
            "and pass it with --baseline); no pose-only model is shipped"
        )
    if not args.no_decisions:
        document["decisions"] = _decisions(args, out, models, baseline, sorted(chosen_objects))
    for p in plots:
        out.text(f"plot: {p}")
    document["plots"] = [str(p) for p in plots]
    document["objects"] = sorted(chosen_objects)
    # the first model's report under the name earlier versions used
    document["reports"] = {"model": document["models"][0]["report"]}
    if document["models"][0].get("baseline") is not None:
        document["reports"]["baseline"] = document["models"][0]["baseline"]
    document["target"] = document["models"][0]["target"]
    out.result(document)


def _pooled(args, out, model, config, rep, samples, scores, base, plots) -> dict:
    """The pooled and within-object table of one model; its plots."""
    from ..learning.decision_eval import object_mean_baseline, within_object
    from ..learning.targets import Target

    tgt = Target.from_dict(config["target"])
    sel = rep["selection"]
    note = f"{sel['rows_evaluated']} rows of {len(set(samples.object))} objects ({sel['objects']})"
    if sel["subsampled"]:
        note += (
            f"; a uniform subsample of the {sel['rows_available']} rows (--max-rows "
            f"{args.max_rows}; 0 evaluates every row)"
        )
        print(
            f"model-eval: {config['arch']} on {tgt.name}: evaluating a uniform subsample of "
            f"{sel['rows_evaluated']} of {sel['rows_available']} rows (--max-rows)",
            file=sys.stderr,
        )
    truth = tgt.normalise(samples.y)
    header = ["metric", config["arch"], "predict-the-mean", "object mean"]
    brep = None if base is None else base[0]
    if brep is not None:
        header.append("baseline model")
    if tgt.kind == "classification":
        within = within_object(samples.object, samples.y, scores, kind="classification")
        rows = [
            ["AP (pooled)", rep["average_precision"], rep["baseline_average_precision"], "-"],
            ["AP (within object, mean)", within["average_precision"], within["positive_rate"], "-"],
            ["AP on a balanced subset", rep["average_precision_balanced"], 0.5, "-"],
            ["balanced accuracy @0.5", rep["balanced_accuracy_at_0.5"], 0.5, "-"],
            ["ECE", rep["expected_calibration_error"], "-", "-"],
        ]
        keys = [
            "average_precision",
            None,
            "average_precision_balanced",
            "balanced_accuracy_at_0.5",
            "expected_calibration_error",
        ]
        mean_base = None
    else:
        within = within_object(
            samples.object,
            truth,
            scores,
            kind="regression",
            lower_is_better=tgt.lower_is_better,
            seed=args.seed,
        )
        mean_base = object_mean_baseline(
            samples.object, truth, lower_is_better=tgt.lower_is_better, seed=args.seed
        )
        rows = [
            ["MSE (normalised)", rep["mse"], rep["baseline_mean_mse"], "-"],
            [
                "comparison accuracy (pooled)",
                rep["comparison_accuracy"],
                0.5,
                mean_base["comparison_accuracy"],
            ],
            ["comparison accuracy (within object)", within["comparison_accuracy"], 0.5, 0.5],
            ["E[GMS] (pooled)", rep["expected_gms"], 0.5, mean_base["expected_gms"]],
            [
                "E[GMS] (within object)",
                within["expected_gms"],
                within["random_expected_gms"],
                within["random_expected_gms"],
            ],
        ]
        keys = ["mse", "comparison_accuracy", None, "expected_gms", None]
    if brep is not None:
        for r, key in zip(rows, keys, strict=True):
            r.append(brep.get(key, "-") if key else "-")
    out.table(f"{config['arch']} on {tgt.name}: {note}", header, rows)
    if args.plots:
        from ..learning.plots import plot_gms_cdf, plot_pr_curves, plot_reliability, plot_scatter

        d = Path(args.plots)
        d.mkdir(parents=True, exist_ok=True)
        runs = {config["arch"]: scores}
        if base is not None:
            runs["baseline"] = base[2]
        stem = tgt.name.replace(":", "_")
        if tgt.kind == "classification":
            curves = {k: (samples.y, v) for k, v in runs.items() if len(v) == len(samples.y)}
            rate = float(np.mean(samples.y))
            plots.append(plot_pr_curves(d / "pr_curve.png", curves, rate))
            plots.append(plot_reliability(d / "reliability.png", curves))
        else:
            gms_runs = {k: (truth, v) for k, v in runs.items() if len(v) == len(truth)}
            gms_runs["predict-the-mean"] = (truth, np.full(len(truth), truth.mean()))
            plots.append(
                plot_gms_cdf(d / "gms_cdf.png", gms_runs, lower_is_better=tgt.lower_is_better)
            )
            plots.append(
                plot_scatter(d / f"pred_vs_true_{stem}.png", truth, scores, config["arch"])
            )
    return {
        "arch": config["arch"],
        "target": tgt.to_dict(),
        "report": rep,
        "within_object": within,
        "object_mean_baseline": mean_base,
        "baseline": brep,
    }


def _decisions(args, out, models, baseline, objects) -> dict:
    """The decision table: the models' choices beside random, object-mean, baseline, oracle."""
    from ..learning.decision_eval import evaluate_decisions

    with out.progress("deciding", len(objects)) as advance:
        res = evaluate_decisions(
            models,
            args.dataset,
            objects,
            task=args.task,
            mode=args.mode,
            candidates=args.candidates,
            draws=args.draws,
            seed=args.seed,
            baseline=baseline or None,
            threshold=args.threshold,
            physics=args.physics,
            progress=advance,
        )
    deciders = ["model"] + (["baseline"] if baseline else []) + ["random", "oracle"]
    header = ["measure", "models", *(["baseline"] if baseline else []), "random", "oracle"]
    rows = []
    labels = list(DECISION_ROWS)
    if "top1_robust_viable" in res["mean"]["model"]:  # a dataset with robust labels
        labels.insert(2, ("chosen grasp robust viable rate (mean)", "top1_robust_viable"))
    for label, key in labels:
        rows.append([label, *[res["mean"][d][key] for d in deciders]])
    rows.append(
        ["chosen grasp percentile (median)", *[res["median_percentile"][d] for d in deciders]]
    )
    if args.physics:
        rows.append(
            ["physics replay holds (rate)", res["physics_hold_rate"], *["-"] * (len(deciders) - 1)]
        )
    out.table(
        f"decisions on {res['objects']} objects, task {res['task']}: up to {args.draws} sets of "
        f"{args.candidates} candidates per object, averaged per object then over objects "
        f"({res['rule']}); predict-the-object-mean ranks an object's candidates alike, so its "
        "choice is the random one",
        header,
        rows,
    )
    per_rows = [
        [
            name,
            e["candidates"],
            e["model"]["top1_viable"],
            e["model"]["top1_percentile"],
            e["model"]["topk_precision"],
            e["random"]["top1_viable"],
            e["oracle"]["top1_viable"],
        ]
        for name, e in res["per_object"].items()
    ]
    out.table(
        "decisions per object (means over its draws)",
        [
            "name",
            "candidates",
            "viable",
            "percentile",
            "top-5 prec.",
            "random viable",
            "oracle viable",
        ],
        per_rows,
    )
    return res
