"""``affordgrasp train``: train a classifier or regressor on a dataset (safetensors out)."""

from __future__ import annotations

from contextlib import contextmanager

from ..errors import InputError, MissingDependencyError
from .limits import SEED, memory_cap

# Of the numeric options: see limits.check_limits.
LIMITS = {
    "epochs": (None, 10_000, "an epoch reads every training row"),
    "batch_size": (None, 8192, "a batch of images and activations is held at once"),
    "patience": (None, 10_000, "epochs"),
    "seed": SEED,
    "rank_weight": (0.0, 100.0, "a weight beside the mean squared error; 0: none"),
    "max_train": (None, 10**6, "the training images are held in memory unless --stream"),
    "members": (None, 100, "the networks are trained one after another"),
    "max_minutes": (0.01, 10_080.0, "a week"),
    "buffer_rows": (None, memory_cap(35_000), "rows of images held together, ~35 kB each"),
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp train`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("dataset", metavar="DATASET", help="a directory written by 'generate'")
    p.add_argument(
        "--model",
        default="cnn",
        choices=("cnn", "pointnet", "pointnet-slim", "pose"),
        help="architecture (default cnn; pose = the pose-only baseline)",
    )
    p.add_argument(
        "--target",
        default="viable",
        help="viable (classifier), hold_effort_sum (regressor on viable grasps, as the paper), "
        "COLUMN>=LEVEL (classifier, e.g. 'robust_viable>=0.5' on a --robust dataset), "
        "a metric column (regressor, e.g. robust_hold) or task:NAME (default viable)",
    )
    p.add_argument("-o", "--out", required=True, metavar="FILE", help="model.safetensors")
    p.add_argument("--split", choices=("object", "family"), default="object")
    p.add_argument(
        "--test-families", default=None, metavar="F1,F2", help="families held out (--split family)"
    )
    p.add_argument("--epochs", type=int, default=40, help="most epochs (default 40)")
    p.add_argument("--batch-size", type=int, default=64)
    p.add_argument("--patience", type=int, default=5, help="early stopping patience (default 5)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--rank-weight",
        type=float,
        default=0.0,
        help="add a pairwise ranking loss with this weight (regressors; default 0)",
    )
    p.add_argument("--log-target", action="store_true", help="regress log1p of the target")
    p.add_argument(
        "--canonical", action="store_true", help="canonicalised depth inputs (relative depth)"
    )
    p.add_argument(
        "--hand-view",
        action="store_true",
        help="cnn: read the hand view (the depth at a fixed metric scale around the approach "
        "line, the fingers and palm drawn in; implies --canonical) instead of the camera image",
    )
    p.add_argument(
        "--max-train", type=int, default=20000, help="most training rows kept (default 20000)"
    )
    p.add_argument(
        "--members",
        type=int,
        default=1,
        help="train an ensemble of this many networks (seeds SEED, SEED+1, ...) whose "
        "outputs are averaged (default 1)",
    )
    p.add_argument("--max-minutes", type=float, default=None, help="stop after this long")
    p.add_argument(
        "--calibrate",
        action="store_true",
        help="classifiers: probabilities corrected from the balanced training to the "
        "positive rate of the training objects (stored in the model)",
    )
    p.add_argument(
        "--stream",
        action="store_true",
        help="read the training images shard by shard every epoch instead of holding them "
        "(every training row is used; memory: --buffer-rows images)",
    )
    p.add_argument(
        "--buffer-rows",
        type=int,
        default=4096,
        help="with --stream: rows shuffled together (default 4096, about 140 MB)",
    )
    p.add_argument(
        "--sensor",
        action="store_true",
        help="train on the images a depth sensor would return (noise growing with depth, "
        "returns lost at grazing angles and at random; seeded by --seed); default: exact",
    )


@contextmanager
def _bar(out, settings):
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    columns = [
        TextColumn("epoch {task.fields[epoch]}"),
        BarColumn(),
        TextColumn("loss {task.fields[loss]}"),
        TextColumn("ETA {task.fields[eta]}"),
        TimeRemainingColumn(),
    ]
    with Progress(*columns, console=out.err, transient=True, disable=out.json_mode) as p:
        task = p.add_task("training", total=settings.epochs, epoch="-", loss="-", eta="-")

        def update(info: dict) -> None:
            done = info["epoch"] - 1 + info["batch"] / info["batches"]
            eta = info["eta_s"]
            p.update(
                task,
                completed=done,
                epoch=f"{info['epoch']}/{info['epochs']}",
                loss=f"{info['loss']:.4f}",
                eta=f"<= {eta / 60:.1f} min",
            )

        yield update


def run(args, out) -> None:
    """Run ``affordgrasp train``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..dataset.handle import Dataset
    from ..learning.training import TrainSettings
    from .output_files import check_output_file
    from .task_options import names_of

    check_output_file(args.out, "--out", suffix=".safetensors")
    for name in ("epochs", "batch_size", "patience", "max_train", "members", "buffer_rows"):
        if getattr(args, name) < 1:
            raise InputError(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    families = None
    if args.test_families is not None:
        families = names_of("--test-families", args.test_families, "axe,mug")
    try:
        from ..learning.api import train_on_dataset
        from ..learning.torch_support import require_safetensors, require_torch

        require_torch()
        require_safetensors()
    except MissingDependencyError as exc:
        raise InputError(str(exc)) from None
    settings = TrainSettings(
        epochs=args.epochs,
        batch_size=args.batch_size,
        patience=args.patience,
        seed=args.seed,
        rank_weight=args.rank_weight,
        max_seconds=None if args.max_minutes is None else 60 * args.max_minutes,
    )
    dataset = Dataset.open(args.dataset)
    dataset.arrow()  # a damaged dataset is refused before the progress bar starts
    with _bar(out, settings) as update:
        model, config = train_on_dataset(
            dataset,
            arch=args.model,
            target=args.target,
            out=args.out,
            split=args.split,
            test_families=families,
            settings=settings,
            log_target=args.log_target,
            canonical=args.canonical,
            max_train=args.max_train,
            progress=update,
            members=args.members,
            sensor=_sensor(args),
            stream=args.stream,
            calibrate=args.calibrate,
            buffer_rows=args.buffer_rows,
            view="hand" if args.hand_view else None,
        )
    tr = config["training"]
    out.table(
        f"Trained {args.model} on {args.target} -> {args.out}",
        ["quantity", "value"],
        [
            [
                "rows train / val / test",
                f"{tr['rows']['train']} / {tr['rows']['val']} / {tr['rows']['test']}",
            ],
            ["test objects", ", ".join(tr["split"]["test"])],
            ["epochs (best)", f"{len(tr['history'])} ({tr['best_epoch']})"],
            ["best validation loss", tr["best_val_loss"]],
            ["seconds", round(tr["seconds"], 1)],
            ["parameters", tr["parameters"]],
        ],
    )
    test = config.get("test", {})
    if test:
        out.table("Held-out test objects", ["metric", "model", "baseline"], _test_rows(test))
    out.result({"model": args.out, "config": config})


def _test_rows(test: dict) -> list[list]:
    if "average_precision" in test:
        return [
            ["average precision", test["average_precision"], test["baseline_average_precision"]],
            ["AP (balanced)", test["average_precision_balanced"], 0.5],
            ["balanced accuracy @0.5", test["balanced_accuracy_at_0.5"], 0.5],
            ["positives / rows", f"{test['positives']} / {test['n']}", ""],
        ]
    return [
        ["MSE", test["mse"], test["baseline_mean_mse"]],
        ["comparison accuracy", test["comparison_accuracy"], 0.5],
        ["E[GMS]", test["expected_gms"], 0.5],
        ["rows", test["n"], ""],
    ]


def _sensor(args):
    """The sensor model of ``--sensor`` (seeded by ``--seed``), else None."""
    if not getattr(args, "sensor", False):
        return None
    from ..vision.sensor import SensorModel

    return SensorModel(seed=args.seed)
