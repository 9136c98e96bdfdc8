"""Do more viable rows per training object help the ΣE_h regressor on held-out objects?

    python studies/more_viable_rows.py --data DATA --copies 3 --sigma 0.02 --epochs 20

Uniform sampling finds few viable grasps (5.8 % on the shipped models' dataset, ~90 per
training object), and ΣE_h is rough in the pregrasp (``target_roughness.py``). This adds
rows where they are cheap to find: each viable training grasp is perturbed ``--copies``
times by Gaussian noise of standard deviation σ in p0 (p0's own units, clipped; the use
direction kept) and simulated again; the copies that stay viable join the training rows,
with their depth images rendered (:mod:`affordgrasp.learning.augment`). The test objects
are the split's held-out objects, as in ``studies/learning_quality.py``; nothing of them
is simulated again. The same recipe (CNN, ranking loss, canonical depth, seed 0) is
trained on the original rows and on the augmented rows and both are scored on the same
test rows.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from affordgrasp.learning.augment import concatenate_samples, perturbed_rows


def within_objects(truth, scores, objects):
    from affordgrasp.learning.evaluation import comparison_accuracy

    names = sorted(set(objects))
    return float(
        np.nanmean([comparison_accuracy(truth[objects == n], scores[objects == n]) for n in names])
    )


def main() -> None:
    from affordgrasp.learning.api import (
        Inputs,
        predict_scores,
        prepare_split,
        report,
        train_on_dataset,
    )
    from affordgrasp.learning.training import TrainSettings

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--copies", type=int, default=3)
    parser.add_argument("--sigma", type=float, default=0.02)
    parser.add_argument("--epochs", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--models", type=Path, default=None, help="write the two models here")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()

    train, val, test, target, split = prepare_split(args.data, "hold_effort_sum", seed=0)
    cpu = time.process_time()
    extra, tried = perturbed_rows(train, copies=args.copies, sigma=args.sigma, seed=args.seed)
    extra_rows = sum(len(p) for p in extra)
    sim_cpu = time.process_time() - cpu
    print(
        f"{len(train)} viable training rows; {tried} perturbed copies simulated (σ "
        f"{args.sigma}), {extra_rows} still viable ({extra_rows / tried:.1%}); "
        f"{sim_cpu:.0f} CPU-s",
        flush=True,
    )
    augmented = concatenate_samples([train, *extra], train.meta)
    results = {"sigma": args.sigma, "copies": args.copies, "rows": {}, "simulation_cpu_s": sim_cpu}
    truth = test.y
    for label, rows in (("original", train), ("augmented", augmented)):
        cpu = time.process_time()
        settings = TrainSettings(epochs=args.epochs, seed=args.seed, rank_weight=1.0)
        out = None if args.models is None else args.models / f"reg_{label}.safetensors"
        if out is not None:
            out.parent.mkdir(parents=True, exist_ok=True)
        model, config = train_on_dataset(
            args.data,
            arch="cnn",
            target="hold_effort_sum",
            out=out,
            settings=settings,
            prepared=(rows, val, test, target, split),
            canonical=True,
        )
        scores = predict_scores(model, config, Inputs(config, test))
        rep = report(model, config, test, scores=scores)
        rep["within_object_comparison"] = within_objects(truth, scores, test.object)
        rep["train_rows"] = len(rows)
        rep["epochs"] = len(config["training"]["history"])
        rep["train_cpu_s"] = time.process_time() - cpu
        results["rows"][label] = rep
        print(
            f"{label:9s} {len(rows):6d} rows, {rep['epochs']} epochs, "
            f"{rep['train_cpu_s']:.0f} CPU-s: MSE {rep['mse']:.4f}  comparison "
            f"{rep['comparison_accuracy']:.3f}  within objects "
            f"{rep['within_object_comparison']:.3f}  E[GMS] {rep['expected_gms']:.3f}",
            flush=True,
        )
        if args.json:
            args.json.write_text(json.dumps(results, indent=2, default=float))


if __name__ == "__main__":
    main()
