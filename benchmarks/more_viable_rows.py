"""Do more viable rows per training object help the ΣE_h regressor on held-out objects?

    python benchmarks/more_viable_rows.py --data DATA --copies 3 --sigma 0.02 --epochs 20

Uniform sampling finds few viable grasps (5.8 % on the shipped models' dataset, ~90 per
training object), and ΣE_h is rough in the pregrasp (``target_roughness.py``). This adds
rows where they are cheap to find: each viable training grasp is perturbed ``--copies``
times by Gaussian noise of standard deviation σ in p0 (p0's own units, clipped; the use
direction kept) and simulated again; the copies that stay viable join the training rows,
with their depth images rendered. The test objects are the split's held-out objects, as
in ``bench_learning.py``; nothing of them is simulated again. The same recipe (CNN,
ranking loss, canonical depth, seed 0) is trained on the original rows and on the
augmented rows and both are scored on the same test rows.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def perturbed_rows(train, *, copies: int, sigma: float, seed: int, origins: bool = False):
    """Viable re-simulations of the training rows' perturbed pregrasps, as Samples.

    Returns the parts (one Samples per object with viable copies) and the number of copies
    simulated; with ``origins``, also each part's row numbers in ``train`` (the grasp each
    copy perturbs).
    """
    from affordgrasp.learning.data import Samples
    from affordgrasp.learning.targets import target_values
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_inputs
    from affordgrasp.tasks import MetricColumns, is_viable
    from affordgrasp.vision import depth_to_mm, renderer_for

    rng = np.random.default_rng(seed)
    parts = []
    sources = []
    tried = 0
    for name in sorted(set(train.object)):
        rows = np.flatnonzero(train.object == name)
        p0 = np.repeat(train.p0[rows], copies, axis=0)
        use = np.repeat(train.use_dir[rows], copies, axis=0)
        q = p0 + rng.normal(0.0, sigma, p0.shape)
        q[:, :5] = np.clip(q[:, :5], -1.0, 1.0)
        q[:, 5] = np.clip(q[:, 5], 0.0, 1.0)
        table = evaluate_inputs(name, q, use).table
        ok = is_viable(MetricColumns(table))
        tried += len(q)
        if not ok.any():
            continue
        y = target_values("hold_effort_sum", table)[ok]
        images = depth_to_mm(renderer_for(load_object(name)).render(q[ok]))
        sources.append(np.repeat(rows, copies)[ok])
        parts.append(
            Samples(
                np.full(int(ok.sum()), name, dtype=object),
                np.full(int(ok.sum()), train.family[rows[0]], dtype=object),
                np.full(int(ok.sum()), -1, dtype=np.int64),
                q[ok],
                use[ok],
                y,
                images,
                dict(train.meta),
            )
        )
    if origins:
        return parts, tried, sources
    return parts, tried


def concatenate(parts, meta):
    from affordgrasp.learning.data import Samples

    if not parts:
        raise SystemExit("no perturbed copy was viable: nothing to add (try a smaller --sigma)")
    return Samples(
        *(
            np.concatenate([getattr(p, f) for p in parts])
            for f in Samples.__dataclass_fields__
            if f not in ("meta",)
        ),
        meta=dict(meta),
    )


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
    augmented = concatenate([train, *extra], train.meta)
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
