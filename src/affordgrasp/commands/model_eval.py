"""``affordgrasp model-eval``: a model's metrics on held-out objects beside baselines, with
PNG plots (precision–recall for classifiers; GMS distributions and predicted vs true for
regressors)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp model-eval`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("model", metavar="MODEL", help="a .safetensors model, or classifier/regressor")
    p.add_argument("dataset", metavar="DATASET", help="a directory written by 'generate'")
    p.add_argument(
        "--objects",
        default="test",
        help="test (the model's held-out objects, default), all, or comma-separated names",
    )
    p.add_argument(
        "--baseline",
        default=None,
        metavar="MODEL",
        help="a second model (e.g. pose-only) to compare",
    )
    p.add_argument("--plots", default=None, metavar="DIR", help="write PNG plots here")
    p.add_argument(
        "--max-rows", type=int, default=20000, help="most rows evaluated (default 20000)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the random pairs and subsets")


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
    from ..learning.targets import Target
    from .predict import load_models

    if args.max_rows < 2:
        raise InputError(f"--max-rows must be >= 2, got {args.max_rows}")
    if args.model == "default":
        raise InputError("model-eval takes one model: 'classifier', 'regressor' or a file")
    if args.plots:
        from .common import check_output_dir

        check_output_dir(args.plots, "--plots")
    objects = args.objects if args.objects in ("test", "all") else args.objects.split(",")
    ((model, config),) = load_models(args.model)
    rep, samples, scores = evaluate_on_dataset(
        model, config, args.dataset, objects=objects, seed=args.seed, max_rows=args.max_rows
    )
    reports = {"model": rep}
    runs = {f"{config['arch']}": scores}
    if args.baseline:
        ((bmodel, bconfig),) = load_models(args.baseline)
        if bconfig["target"]["name"] != config["target"]["name"]:
            raise InputError("--baseline must be trained on the same target as MODEL")
        brep, bsamples, bscores = evaluate_on_dataset(
            bmodel,
            bconfig,
            args.dataset,
            objects=list(np.unique(samples.object)),
            seed=args.seed,
            max_rows=args.max_rows,
        )
        reports["baseline"] = brep
        runs[f"{bconfig['arch']} (baseline)"] = bscores
    tgt = Target.from_dict(config["target"])
    truth = tgt.normalise(samples.y)
    plots = []
    if tgt.kind == "classification":
        rows = [
            ["average precision", rep["average_precision"], rep["baseline_average_precision"]],
            ["AP on a balanced subset", rep["average_precision_balanced"], 0.5],
            ["balanced accuracy @0.5", rep["balanced_accuracy_at_0.5"], 0.5],
        ]
        header = ["metric", config["arch"], "predict-the-mean"]
        if "baseline" in reports:
            b = reports["baseline"]
            header.append("baseline model")
            for r, key in zip(
                rows,
                ["average_precision", "average_precision_balanced", "balanced_accuracy_at_0.5"],
                strict=True,
            ):
                r.append(b[key])
    else:
        rows = [
            ["MSE (normalised)", rep["mse"], rep["baseline_mean_mse"]],
            ["comparison accuracy", rep["comparison_accuracy"], 0.5],
            ["E[GMS]", rep["expected_gms"], 0.5],
        ]
        header = ["metric", config["arch"], "predict-the-mean"]
        if "baseline" in reports:
            b = reports["baseline"]
            header.append("baseline model")
            for r, key in zip(rows, ["mse", "comparison_accuracy", "expected_gms"], strict=True):
                r.append(b[key])
    if args.plots:
        from ..learning.plots import plot_gms_cdf, plot_pr_curves, plot_scatter

        d = Path(args.plots)
        d.mkdir(parents=True, exist_ok=True)
        if tgt.kind == "classification":
            curves = {k: (samples.y, v) for k, v in runs.items()}
            plots.append(plot_pr_curves(d / "pr_curve.png", curves, float(np.mean(samples.y))))
        else:
            gms_runs = {k: (truth, v) for k, v in runs.items()}
            gms_runs["predict-the-mean"] = (truth, np.full(len(truth), truth.mean()))
            plots.append(
                plot_gms_cdf(d / "gms_cdf.png", gms_runs, lower_is_better=tgt.lower_is_better)
            )
            plots.append(plot_scatter(d / "pred_vs_true.png", truth, scores, config["arch"]))
    held = ", ".join(sorted(set(samples.object)))
    out.table(f"{config['arch']} on {tgt.name}: {len(samples)} rows of {held}", header, rows)
    for p in plots:
        out.text(f"plot: {p}")
    out.result(
        {
            "reports": reports,
            "objects": sorted(set(samples.object)),
            "plots": [str(p) for p in plots],
            "target": tgt.to_dict(),
        }
    )
