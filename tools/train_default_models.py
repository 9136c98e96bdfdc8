"""Rebuild the shipped models: the default viability classifier and ΣE_h regressor.

One command, deterministic (seed 0, one torch thread):

    python tools/train_default_models.py --data /tmp/affordgrasp-train65 \
        --classifier-data /tmp/affordgrasp-train390

1. generates (or resumes) the two training datasets: for the regressor 13 families x 5
   instances (variants 0-4) x 1500 uniform samples, seed 0, one sample stream shared by the
   objects (16 min on 2 shared cores); for the classifier 13 families x 30 instances
   (variants 9-38) x 200 uniform samples, seed 0, each object its own stream (about 8 min);
   both with depth images;
2. splits each by object instance (seed 0);
3. trains the CNN classifier (target ``viable``, balanced, calibrated to its training
   objects' positive rate, its decision threshold chosen on its validation objects) and
   the CNN regressor (target
   ``hold_effort_sum`` on viable grasps, normalised from [0, 250]; an ensemble of 3
   networks, trained on the viable training grasps plus the still-viable of 3 perturbed
   copies of each, simulated again: :mod:`affordgrasp.learning.augment`) and writes them to
   ``src/affordgrasp/learning/pretrained/`` (or ``--out``; ``--models regressor`` rebuilds
   one).

The printed test metrics are on the held-out objects. Every part is deterministic: on an
unchanged simulation the command reproduces the shipped files (docs/learning.md, "Shipped
models", with the time it took).

``--robust K`` generates the dataset with robust labels (docs/robust.md) and ``--targets
robust`` trains the same two recipes on the robust targets instead (the classifier on
``robust_viable>=0.5``, the regressor on the graded ``robust_hold`` over every row, without
the perturbed copies, which would need their own robust labels), written as
``robust_classifier.safetensors`` and ``robust_regressor.safetensors`` (docs/learning.md,
"Raw vs robust targets").
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

FAMILIES = (
    "axe bottle dagger hammer ice_cream_cone knife meat_cleaver mug screwdriver spatula sword "
    "tumbler wine_glass"
).split()
OBJECTS = [f"{f}:{i}" for f in FAMILIES for i in range(5)]
# The classifier's objects, variant by variant (the order they were generated in).
CLASSIFIER_OBJECTS = [f"{f}:{i}" for i in range(9, 39) for f in FAMILIES]
CLASSIFIER_SAMPLES = 200
HERE = Path(__file__).resolve().parent
PRETRAINED = HERE.parent / "src" / "affordgrasp" / "learning" / "pretrained"

# The shipped models' recipes: the CNN classifier on canonicalised depth (balanced AP 0.841
# on the held-out objects vs 0.829 for plain depth, on the previous dataset) and the CNN
# regressor on canonicalised depth with the ranking loss, an ensemble of 3 (seeds 0-2)
# trained up to 20 epochs each (comparison 0.674 vs 0.666-0.668 for its members and 0.662
# for one network of 12 epochs on the previous dataset; 0.670 vs 0.661-0.671 on the current
# one), with the perturbed copies (comparison 0.679, E[GMS] 0.770 vs 0.670 / 0.715 without;
# docs/learning.md).
CLASSIFIER = {
    "arch": "cnn",
    "target": "viable",
    "rank_weight": 0.0,
    "epochs": 40,
    "canonical": True,
}
# The shipped classifier learns from many objects with few samples each (the classifier
# dataset below), calibrated: with plan's candidates it chooses a viable grasp in 0.33-0.35
# of decisions alone against 0.22-0.28 for the same recipe on the 65 objects x 1500 samples
# (validation variants 7-8 and test variants 5-6; with training seed 1, 0.24-0.28: docs/
# learning.md, "The shipped classifier, many objects, and plan's default").
SHIPPED_CLASSIFIER = dict(CLASSIFIER, calibrate=True, data="classifier")
REGRESSOR = {
    "arch": "cnn",
    "target": "hold_effort_sum",
    "rank_weight": 1.0,
    # more viable rows near the viable training grasps (affordgrasp.learning.augment):
    # each perturbed 3 times (σ 0.02 in p0's units, seed 0) and simulated again
    "more_viable": {"copies": 3, "sigma": 0.02, "seed": 0},
    "epochs": 20,
    "canonical": True,
    "members": 3,
}


# The same recipes on the robust targets (docs/robust.md): the classifier learns whether at
# least half of the 25 perturbed copies stay viable (Dex-Net's robust label reads the same
# way: success more often than not under the perturbations); the regressor learns pick's
# graded robust score on every row (load directions held on average, then the effort).
ROBUST_CLASSIFIER = dict(CLASSIFIER, target="robust_viable>=0.5")
ROBUST_REGRESSOR = {
    k: v for k, v in dict(REGRESSOR, target="robust_hold").items() if k != "more_viable"
}


CLASSIFIER_DATASET = (
    "13 families x 30 instances (variants 9-38) x 200 uniform samples, seed 0, per-object streams"
)


def make_dataset(
    directory: Path, samples: int, workers: int | None, robust: int = 0, *, classifier=False
) -> None:
    """Generate (or resume) the regressor's dataset, or with ``classifier`` the shipped
    classifier's (its own objects and samples, per-object streams, default shards)."""
    from affordgrasp.dataset.generate import generate

    started = time.perf_counter()
    # The regressor's dataset was drawn with one stream for every object (the only draw
    # before streams were recorded); "shared" reproduces it (docs/dataset.md).
    options = dict(shard_size=samples, robust=robust or None, streams="shared")
    objects = OBJECTS
    if classifier:
        objects, samples, options = CLASSIFIER_OBJECTS, CLASSIFIER_SAMPLES, {}
    summary = generate(objects, samples, directory, seed=0, workers=workers, depth=True, **options)
    print(
        f"dataset {directory}: {summary.samples_written} samples written now, "
        f"{summary.shards_skipped} shards already there, {time.perf_counter() - started:.0f} s"
    )


DATASET = "13 families x 5 instances (variants 0-4) x 1500 uniform samples, seed 0"


def dataset_recipe(samples: int = 1500, robust: int = 0) -> str:
    """The training dataset in words (recorded in the model files)."""
    text = DATASET.replace("1500 uniform samples", f"{samples} uniform samples")
    return text + (f", robust labels K = {robust}" if robust else "")


def ship(path: Path, more_viable: dict | None = None, dataset: str = DATASET) -> None:
    """Record the dataset by its recipe, not by this machine's path (weights unchanged)."""
    from affordgrasp.learning.io import load_model, save_model

    model, config = load_model(path)
    if more_viable:
        dataset += (
            f"; + the still-viable of {more_viable['copies']} perturbed copies of each viable "
            f"training grasp (sigma {more_viable['sigma']}, seed {more_viable['seed']})"
        )
    config["training"]["dataset"] = f"{dataset} (tools/train_default_models.py)"
    save_model(path, model, config)


def train(
    directory: Path,
    recipe: dict,
    out: Path,
    epochs: int,
    *,
    calibrate: bool = False,
    dataset: str = DATASET,
) -> dict:
    from affordgrasp.learning.api import prepare_split, train_on_dataset
    from affordgrasp.learning.training import TrainSettings

    settings = TrainSettings(
        epochs=recipe.get("epochs", epochs), seed=0, rank_weight=recipe["rank_weight"]
    )
    started = time.perf_counter()
    prepared = None
    extra = recipe.get("more_viable")
    if extra:
        from affordgrasp.learning.augment import concatenate_samples, perturbed_rows

        rows, val, test, target, split = prepare_split(directory, recipe["target"], seed=0)
        parts, tried = perturbed_rows(
            rows, copies=extra["copies"], sigma=extra["sigma"], seed=extra["seed"]
        )
        added = sum(len(p) for p in parts)
        print(
            f"{len(rows)} training rows + {added} of {tried} perturbed copies still viable "
            f"({time.perf_counter() - started:.0f} s)",
            flush=True,
        )
        prepared = (concatenate_samples([rows, *parts], rows.meta), val, test, target, split)
    _, config = train_on_dataset(
        directory,
        arch=recipe["arch"],
        target=recipe["target"],
        out=out,
        settings=settings,
        canonical=recipe.get("canonical", False),
        log_target=recipe.get("log", False),
        members=recipe.get("members", 1),
        prepared=prepared,
        calibrate=calibrate or recipe.get("calibrate", False),
    )
    ship(out, extra, dataset)
    tr = config["training"]
    print(
        f"{out.name}: {tr['rows']} rows, {len(tr['history'])} epochs (best {tr['best_epoch']}), "
        f"{time.perf_counter() - started:.0f} s; test: {json.dumps(config.get('test'))}"
    )
    return config


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path("affordgrasp-train65"))
    parser.add_argument(
        "--classifier-data",
        type=Path,
        default=Path("affordgrasp-train390"),
        help="the shipped classifier's dataset (390 objects x 200 samples)",
    )
    parser.add_argument("--samples", type=int, default=1500, help="samples per object")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--epochs", type=int, default=40, help="for a recipe that names none")
    parser.add_argument("--out", type=Path, default=PRETRAINED)
    parser.add_argument(
        "--models", default="classifier,regressor", help="which models to rebuild (comma-separated)"
    )
    parser.add_argument(
        "--robust", type=int, default=0, help="robust labels with K copies (default 0: none)"
    )
    parser.add_argument(
        "--targets",
        default="raw",
        help="raw (viable, hold_effort_sum: the shipped models), robust (robust_viable>=0.5, "
        "robust_hold; needs a dataset with robust labels) or raw,robust",
    )
    parser.add_argument(
        "--calibrate",
        action="store_true",
        help="store the classifiers' prior-shift calibration (train --calibrate)",
    )
    parser.add_argument(
        "--members",
        type=int,
        default=None,
        help="networks per regressor ensemble (default: the recipe's, 3)",
    )
    args = parser.parse_args()
    models = set(args.models.split(","))
    if not models or models - {"classifier", "regressor"}:
        parser.error(f"--models {args.models!r}: name classifier, regressor or both")
    targets = args.targets.split(",")
    if not targets or set(targets) - {"raw", "robust"}:
        parser.error(f"--targets {args.targets!r}: name raw, robust or both")
    if "robust" in targets and args.robust <= 0:
        parser.error("--targets robust needs robust labels: pass --robust K (e.g. 25)")
    if "regressor" in models or "robust" in targets:  # the shipped classifier has its own
        make_dataset(args.data, args.samples, args.workers, args.robust)
    args.out.mkdir(parents=True, exist_ok=True)
    recipes = {
        "raw": (("default", SHIPPED_CLASSIFIER, REGRESSOR)),
        "robust": (("robust", ROBUST_CLASSIFIER, ROBUST_REGRESSOR)),
    }
    text = dataset_recipe(args.samples, args.robust)
    for name in targets:
        prefix, classifier, regressor = recipes[name]
        if args.members is not None:
            regressor = dict(regressor, members=args.members)
        for kind, recipe in (("classifier", classifier), ("regressor", regressor)):
            if kind not in models:
                continue
            out = args.out / f"{prefix}_{kind}.safetensors"
            data, described = args.data, text
            if recipe.get("data") == "classifier":
                data, described = args.classifier_data, CLASSIFIER_DATASET
                make_dataset(data, 0, args.workers, classifier=True)
            train(data, recipe, out, args.epochs, calibrate=args.calibrate, dataset=described)


if __name__ == "__main__":
    main()
