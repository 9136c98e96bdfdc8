"""Learning curve: held-out scores against the amount of training data.

    python studies/learning_curve.py --data DATA --out DIR
    python studies/learning_curve.py --data DATA --out DIR --points none   # table + fit

The shipped regressor's recipe (``tools/train_default_models.py``: CNN on canonicalised depth,
ranking loss, ≤ 20 epochs with early stopping, the still-viable of 3 perturbed copies of
each viable training grasp, σ 0.02; one network, ``--seed``) is trained on nested subsets
of the training data and scored on the split's held-out test objects, always the same
rows:

* ``objects:F``: the first fraction F of the training objects, in an order that takes
  one object of every family in turn (families and each family's instances shuffled with
  ``--order-seed``), all their samples;
* ``samples:F``: every training object, the samples numbered below F × the samples per
  object (samples are i.i.d. uniform, so a prefix is a smaller uniform run);
* ``all``: the whole training set (with ``--seed 0`` and the copies: member 0 of the
  shipped ensemble).

The perturbed copies are simulated once for all training grasps (the shipped recipe's
random stream, cached in DIR) and a subset keeps the copies of its own grasps, so the
subsets are nested, copies included. Validation rows (early stopping) are the full
validation objects' at every point. ``--classifier`` also trains the shipped classifier's
recipe (CNN, canonical depth, balanced, ≤ 40 epochs) on the same subsets and reports its AP
at the natural balance and on a balanced subset.

Each point is saved as DIR/<model>-<point>.json (an existing one is not trained again, so
runs resume and can be split across processes with ``--points``); the table and a
least-squares fit of comparison accuracy against log(training rows), with the rows,
uniform samples and CPU-hours of simulation it would take to reach ``--goal`` if the trend
held, are printed from every file in DIR. ``--rate-file`` names a JSON with the measured
simulation cost (``cpu_s_per_sample``, from generating samples with depth) for the last.

The subsets, the fit and the settings check are :mod:`affordgrasp.learning.curve`; the
perturbed copies :mod:`affordgrasp.learning.augment`.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from affordgrasp.errors import InputError
from affordgrasp.learning.augment import concatenate_samples, perturbed_rows
from affordgrasp.learning.curve import (
    check_settings,
    curve_settings,
    fit_log_trend,
    keep_mask,
    object_order,
)

DEFAULT_POINTS = "objects:0.25,objects:0.5,samples:0.25,samples:0.5,all"


def copies_of(train, out: Path, copies: int, sigma: float, chunk: int):
    """Perturbed copies of training grasps (cached), with the row of ``train`` each perturbs.

    ``train`` is one chunk of the training rows (samples numbered in one block of
    ``--base-samples``); its copies use the random stream of seed ``chunk``, so chunk 0 is
    the shipped recipe's and a dataset with more samples per object only adds chunks.
    """
    from affordgrasp.learning.data import Samples

    cache = out / f"copies-{copies}-{sigma}-{chunk}.npz"
    if cache.exists():
        z = np.load(cache, allow_pickle=False)
        if not (
            np.array_equal(z["train_object"], train.object.astype(str))
            and np.array_equal(z["train_sample"], train.sample)
        ):
            raise SystemExit(f"{cache} was made from other training rows; use another --out")
        rows = Samples(
            z["object"].astype(object),
            z["family"].astype(object),
            z["sample"],
            z["p0"],
            z["use_dir"],
            z["y"],
            z["depth_mm"],
            dict(train.meta),
        )
        return rows, z["origin"], json.loads(str(z["info"]))
    cpu, wall = time.process_time(), time.perf_counter()
    parts, tried, sources = perturbed_rows(
        train, copies=copies, sigma=sigma, seed=chunk, origins=True
    )
    info = {
        "tried": tried,
        "viable": int(sum(len(p) for p in parts)),
        "cpu_s": time.process_time() - cpu,
        "wall_s": time.perf_counter() - wall,
    }
    rows = concatenate_samples(parts, train.meta)
    origin = np.concatenate(sources)
    np.savez_compressed(
        cache,
        object=rows.object.astype(str),
        family=rows.family.astype(str),
        sample=rows.sample,
        p0=rows.p0,
        use_dir=rows.use_dir,
        y=rows.y,
        depth_mm=rows.depth_mm,
        origin=origin,
        train_object=train.object.astype(str),
        train_sample=train.sample,
        info=json.dumps(info),
    )
    print(
        f"chunk {chunk}: {tried} perturbed copies simulated, {info['viable']} still viable, "
        f"{info['cpu_s']:.0f} CPU-s",
        flush=True,
    )
    return rows, origin, info


def classifier_split(data: Path, keep, seed: int = 0):
    """prepare_split for ``viable`` with only the kept training rows (same caps and draws)."""
    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.dataset.splits import split_by_object
    from affordgrasp.learning.api import _subsample
    from affordgrasp.learning.data import load_depth, read_rows

    data = Dataset.open(data)
    samples, target = read_rows(data, "viable")
    sp = split_by_object(samples.object, samples.family, seed=seed)
    parts = []
    for k, part in enumerate(("train", "val", "test")):
        idx = np.flatnonzero(sp.part_of(samples.object, part))
        if part == "train":
            idx = idx[keep(samples.take(idx))]
        cap = 20000 if part == "train" else 4000
        if part != "test":
            y = samples.y[idx]
            pos, neg = idx[y > 0.5], idx[y <= 0.5]
            pos = _subsample(pos, cap // 2, seed + k)
            idx = np.sort(
                np.r_[pos, _subsample(neg, int(round(3.0 * max(len(pos), 1))), seed + 10 + k)]
            )
        else:
            idx = _subsample(idx, cap, seed + k)
        parts.append(samples.take(idx))
    for p in parts:
        load_depth(p, data)
    return (*parts, target, sp)


def within_objects(truth, scores, objects, least: int = 3) -> float:
    """Comparison accuracy inside each object with at least ``least`` rows, averaged."""
    from affordgrasp.learning.evaluation import comparison_accuracy

    names = [n for n in sorted(set(objects)) if (objects == n).sum() >= least]
    return float(
        np.mean([comparison_accuracy(truth[objects == n], scores[objects == n]) for n in names])
    )


def train_point(model_kind: str, prepared, data: Path, seed: int) -> dict:
    from affordgrasp.learning.api import Inputs, predict_scores, report, train_on_dataset
    from affordgrasp.learning.targets import Target
    from affordgrasp.learning.training import TrainSettings

    regressor = model_kind == "regressor"
    settings = TrainSettings(
        epochs=20 if regressor else 40, seed=seed, rank_weight=float(regressor)
    )
    cpu, wall = time.process_time(), time.perf_counter()
    model, config = train_on_dataset(
        data,
        arch="cnn",
        target="hold_effort_sum" if regressor else "viable",
        settings=settings,
        prepared=prepared,
        canonical=True,
    )
    test = prepared[2]
    scores = predict_scores(model, config, Inputs(config, test))
    rep = report(model, config, test, scores=scores)
    if regressor:
        truth = Target.from_dict(config["target"]).normalise(test.y)
        rep["within_object_comparison"] = within_objects(truth, scores, test.object)
    tr = config["training"]
    rep.update(
        train_rows=len(prepared[0]),
        epochs=len(tr["history"]),
        best_epoch=tr["best_epoch"],
        train_cpu_s=time.process_time() - cpu,
        train_wall_s=time.perf_counter() - wall,
    )
    return rep


def split_rows(args, cache: dict):
    """The regression split; validation and test rows are the first ``base`` samples'."""
    from affordgrasp.learning.api import prepare_split

    if "reg" in cache:
        return cache["reg"]
    per_object = json.loads((args.data / "_manifest.json").read_text())["samples"]
    base = args.base_samples or per_object
    train, val, test, target, sp = prepare_split(
        args.data, "hold_effort_sum", seed=0, max_train=None, max_eval=None
    )
    val = val.take(np.flatnonzero(val.sample < base))
    test = test.take(np.flatnonzero(test.sample < base))
    order = object_order(train.object, train.family, args.order_seed)
    cache["reg"] = train, val, test, target, sp, order, per_object, base
    return cache["reg"]


def run_point(args, model_kind: str, point: str, cache: dict) -> dict:
    train, val, test, target, sp, order, per_object, base = split_rows(args, cache)
    kind, _, frac = point.partition(":")
    if kind == "samples" and round(float(frac) * base) > per_object:
        raise SystemExit(f"point {point!r}: the dataset has {per_object} samples per object")
    keep = keep_mask(train, point, order, base)
    objects = order[: max(1, round(float(frac) * len(order)))] if kind == "objects" else order
    per = round(float(frac) * base) if kind == "samples" else base
    keep &= train.sample < per
    result = {
        "model": model_kind,
        "point": point,
        "seed": args.seed,
        "copies": args.copies if model_kind == "regressor" else 0,
        "data": str(args.data),
        "training_objects": sorted(objects),
        "samples_per_object": per,
        "uniform_samples": len(objects) * per,
        "viable_originals": int(keep.sum()),
        "test_rows": len(test),
    }
    if model_kind == "regressor":
        parts = [train.take(np.flatnonzero(keep))]
        if args.copies:
            cpu, tried = 0.0, 0
            for chunk in range(math.ceil(per / base)):
                block = np.flatnonzero(
                    (train.sample >= chunk * base) & (train.sample < (chunk + 1) * base)
                )
                extra, origin, info = copies_of(
                    train.take(block), args.out, args.copies, args.sigma, chunk
                )
                parts.append(
                    extra.take(np.flatnonzero(np.isin(block[origin], np.flatnonzero(keep))))
                )
                cpu, tried = cpu + info["cpu_s"], tried + info["tried"]
            result["copies_simulated"] = int(keep.sum()) * args.copies
            result["copies_viable"] = int(sum(len(p) for p in parts[1:]))
            result["copies_cpu_s_per_copy"] = cpu / tried if tried else float("nan")
        prepared = (concatenate_samples(parts, train.meta), val, test, target, sp)
    else:
        if base != per_object:
            raise SystemExit("the classifier's points need --base-samples = the dataset's samples")
        prepared = classifier_split(args.data, lambda s: keep_mask(s, point, order, base))
        result["train_positives"] = int((prepared[0].y > 0.5).sum())
    result.update(train_point(model_kind, prepared, args.data, args.seed))
    return result


def summarise(out: Path, goal: float, rate: dict | None) -> None:
    results = [json.loads(p.read_text()) for p in sorted(out.glob("*.json")) if p.stem != "rate"]
    results.sort(key=lambda r: (r["model"], r["copies"], r["seed"], r["train_rows"]))
    for r in results:
        if r["model"] == "regressor":
            print(
                f"regressor copies {r['copies']} seed {r['seed']} {r['point']:13s} "
                f"{len(r['training_objects']):2d} objects "
                f"{r['uniform_samples']:6d} samples {r['viable_originals']:5d} viable "
                f"{r['train_rows']:6d} rows  MSE {r['mse']:.4f}  comparison "
                f"{r['comparison_accuracy']:.3f}  within {r['within_object_comparison']:.3f}  "
                f"E[GMS] {r['expected_gms']:.3f}  {r['epochs']} epochs (best {r['best_epoch']}) "
                f"{r['train_cpu_s']:.0f} CPU-s"
            )
        else:
            print(
                f"classifier seed {r['seed']} {r['point']:13s} "
                f"{r['train_rows']:6d} rows (a quarter viable)  AP "
                f"{r['average_precision']:.3f}  balanced "
                f"{r['average_precision_balanced']:.3f}  bal. acc. "
                f"{r['balanced_accuracy_at_0.5']:.3f}  {r['epochs']} epochs (best "
                f"{r['best_epoch']}) {r['train_cpu_s']:.0f} CPU-s"
            )
    groups: dict = {}
    for r in results:
        if r["model"] == "regressor":
            groups.setdefault(r["copies"], []).append(r)
    for copies, reg in sorted(groups.items()):  # every seed's points in one fit
        curves = {
            "objects": [r for r in reg if not r["point"].startswith("samples")],
            "samples": [r for r in reg if not r["point"].startswith("objects")],
            "both": reg,
        }
        full = [r for r in reg if r["point"] == "all"]
        seeds = ",".join(str(k) for k in sorted({r["seed"] for r in reg}))
        for name, pts in curves.items():
            f = fit_log_trend(pts, goal)
            if f is None:
                continue
            print(
                f"fit regressor, {copies} copies, seeds {seeds}, {name} ({f['n']} points): "
                f"comparison = a + {f['slope_per_ln_rows']:.4f} (± {f['slope_se']:.4f}) ln(rows), "
                f"{f['per_doubling']:+.4f} per doubling, residual sd {f['residual_sd']:.4f}; "
                f"{goal} at {f['rows_for_goal']:.3g} rows (slope ± se: "
                f"{f['rows_for_goal_slope_plus_se']:.3g} to "
                f"{f['rows_for_goal_slope_minus_se']:.3g})"
            )
            if full and rate:
                cost(full[0], f, rate)


def cost(full: dict, f: dict, rate: dict) -> None:
    """Uniform samples and CPU-hours of simulation for the rows a fit asks for."""
    rows_per_sample = full["train_rows"] / full["uniform_samples"]
    copies = full.get("copies_simulated", 0) / full["uniform_samples"]
    cpu_per_sample = rate["cpu_s_per_sample"] + copies * full.get("copies_cpu_s_per_copy", 0.0)
    for label, rows in (
        ("fit", f["rows_for_goal"]),
        ("slope + se", f["rows_for_goal_slope_plus_se"]),
        ("slope - se", f["rows_for_goal_slope_minus_se"]),
    ):
        samples = rows / rows_per_sample
        print(
            f"    {label:10s}: {rows:.3g} training rows = {samples:.3g} uniform training samples "
            f"({rows_per_sample:.4f} rows each, {samples / 1500:.3g} objects of 1500) = "
            f"{samples * cpu_per_sample / 3600:.3g} CPU-hours of simulation "
            f"({cpu_per_sample * 1000:.2f} CPU-ms per sample, copies included)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True, help="the shipped models' dataset")
    parser.add_argument("--out", type=Path, required=True, help="results (and the copies cache)")
    parser.add_argument(
        "--points", default=DEFAULT_POINTS, help=f"comma-separated (default {DEFAULT_POINTS}); none"
    )
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--order-seed", type=int, default=0, help="order of the training objects")
    parser.add_argument("--copies", type=int, default=3, help="perturbed copies (0: none)")
    parser.add_argument("--sigma", type=float, default=0.02)
    parser.add_argument(
        "--base-samples",
        type=int,
        default=None,
        help="samples per object of 'all' and of the validation and test rows (default: the "
        "dataset's; set it to use a dataset with more samples for points samples:F with F > 1)",
    )
    parser.add_argument("--classifier", action="store_true", help="also the classifier")
    parser.add_argument("--no-regressor", action="store_true", help="only the classifier")
    parser.add_argument("--goal", type=float, default=0.80, help="comparison accuracy to reach")
    parser.add_argument("--rate-file", type=Path, default=None, help="simulation cost (JSON)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    kinds = ([] if args.no_regressor else ["regressor"]) + (
        ["classifier"] if args.classifier else []
    )
    points = [] if args.points == "none" else args.points.split(",")
    settings = curve_settings(args.data, args.order_seed, args.sigma, args.base_samples)
    cache: dict = {}
    for kind in kinds:
        for point in points:
            tag = f"c{args.copies}-" if kind == "regressor" else ""
            path = args.out / f"{kind}-{tag}s{args.seed}-{point.replace(':', '_')}.json"
            if path.exists():
                check_settings(path, settings)
                continue
            started = time.perf_counter()
            result = run_point(args, kind, point, cache)
            result["settings"] = settings
            path.write_text(json.dumps(result, indent=2, default=float))
            print(f"{kind} {point}: {time.perf_counter() - started:.0f} s", flush=True)
    rate = json.loads(args.rate_file.read_text()) if args.rate_file else None
    summarise(args.out, args.goal, rate)


if __name__ == "__main__":
    try:
        main()
    except InputError as exc:
        raise SystemExit(f"learning_curve.py: error: {exc}") from None
