"""The fused views judged as a model: how well does simulating a grasp on the surface fused
from ``plan``'s views predict its true viability and robust hold, grasp by grasp?

    python studies/views_as_model.py --variants 5,6 --calibrate 7 --views 64 --json views_model.json

For every object: ``plan``'s first ``--views`` views (plan seed 0, its offsets near the centre) are
fused into a surface as ``plan`` fuses them; the held-out rows are uniform samples (the
dataset's draw, ``--sample-seed``, one shared stream: the same poses on every object),
simulated on the true object with ``--robust`` perturbed copies (the truth) and on the
fused surface with the same copies (the prediction). Reported as the learned models are
(docs/learning.md, "Raw vs robust targets"), pooled and within each object:

* classifier: the probability of ``viable`` is the share of the fused surface's copies
  that are viable (``robust_viable`` there), ties broken by the fused ε; average precision
  at the natural rate and the expected calibration error, raw and after a calibration map
  fitted on the ``--calibrate`` objects (the share truly viable in each of 10 bins of the
  fused probability);
* ranker: the fused ``robust_hold`` as a prediction of the true ``robust_hold`` (and the
  fused ΣE_h of the true ΣE_h on the truly viable rows): comparison accuracy and E[GMS]
  within each object, then the mean.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def object_rows(name: str, *, samples: int, sample_seed: int, copies: int, views: int) -> dict:
    """The truth and the fused surface's prediction for one object's rows."""
    from affordgrasp.columns import HOLD_EFFORT_COLUMNS, hold_effort_sum
    from affordgrasp.grasp.pregrasp import sample_inputs
    from affordgrasp.learning.views_model import fused_surface
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_inputs
    from affordgrasp.tasks import is_viable

    obj = load_object(name)
    fused = fused_surface(obj, views=views)  # plan's first views, seed 0
    p0, use_dir = sample_inputs(sample_seed, 0, samples)
    out = {}
    for key, target, frame in (("true", obj, None), ("fused", fused, obj)):
        table = evaluate_inputs(target, p0, use_dir, robust=copies, frame=frame).table
        out[f"{key}_viable"] = is_viable(table)
        for column in ("epsilon", "robust_viable", "robust_hold"):
            out[f"{key}_{column}"] = table.column(column).to_numpy(zero_copy_only=False)
        out[f"{key}_effort"] = hold_effort_sum(
            {c: table.column(c).to_numpy(zero_copy_only=False) for c in HOLD_EFFORT_COLUMNS}
        )
    return out


def probability(rows: dict) -> np.ndarray:
    """The fused surface's share of viable copies, ties broken by its ε (within 1e-6)."""
    eps = np.nan_to_num(rows["fused_epsilon"], nan=0.0)
    return np.nan_to_num(rows["fused_robust_viable"], nan=0.0) + 1e-6 * np.tanh(eps)


def fit_bins(p: np.ndarray, label: np.ndarray, bins: int = 10) -> np.ndarray:
    """The share of positives in each of ``bins`` equal bins of p (the bin's centre where
    empty)."""
    from affordgrasp.stats import reliability_bins

    r = reliability_bins(label, p, bins=bins)
    centres = (r["edges"][:-1] + r["edges"][1:]) / 2
    return np.where(r["count"] > 0, r["positive_rate"], centres)


def apply_bins(p: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """The calibrated probability: the rate of the bin p falls in (as
    :func:`~affordgrasp.stats.reliability_bins` bins it)."""
    edges = np.linspace(0.0, 1.0, len(rate) + 1)
    return rate[np.clip(np.searchsorted(edges, p, side="right") - 1, 0, len(rate) - 1)]


def main() -> None:
    from affordgrasp.learning.decision_eval import within_object
    from affordgrasp.learning.evaluation import comparison_accuracy, gms_distribution
    from affordgrasp.learning.plan import FUSED_VIEWS
    from affordgrasp.objects import list_families
    from affordgrasp.stats import average_precision, expected_calibration_error

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", default="5,6", help="held-out variants (comma-separated)")
    ap.add_argument("--calibrate", default="7", help="variants the calibration map is fit on")
    ap.add_argument("--families", help="only these families (comma-separated; default all)")
    ap.add_argument("--samples", type=int, default=512, help="uniform rows per object")
    ap.add_argument("--sample-seed", type=int, default=1)
    ap.add_argument("--robust", type=int, default=25, help="perturbed copies K")
    ap.add_argument(
        "--views", type=int, default=FUSED_VIEWS, help=f"views fused (default {FUSED_VIEWS})"
    )
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args()
    families = args.families.split(",") if args.families else list_families()

    def collect(variants: str) -> dict[str, dict]:
        rows = {}
        for family in families:
            for v in variants.split(","):
                name = f"{family}:{v}"
                t0 = time.process_time()
                rows[name] = object_rows(
                    name,
                    samples=args.samples,
                    sample_seed=args.sample_seed,
                    copies=args.robust,
                    views=args.views,
                )
                print(f"{name}: {time.process_time() - t0:.1f} CPU s", flush=True)
        return rows

    calib = collect(args.calibrate)
    held = collect(args.variants)
    cat = lambda rows, key: np.concatenate([r[key] for r in rows.values()])  # noqa: E731
    p_calib = np.concatenate([probability(r) for r in calib.values()])
    objects = np.concatenate([[n] * len(r["true_viable"]) for n, r in held.items()])
    p = np.concatenate([probability(r) for r in held.values()])
    report: dict = {"objects": len(held), "rows": len(p)}

    def labels(rows: dict[str, dict]) -> dict[str, np.ndarray]:
        return {
            "viable": cat(rows, "true_viable").astype(float),
            "robust viable>=0.5": (cat(rows, "true_robust_viable") >= 0.5).astype(float),
        }

    calib_labels = labels(calib)
    for label_name, label in labels(held).items():
        rate = fit_bins(p_calib, calib_labels[label_name])  # a map per label
        calibrated = apply_bins(p, rate)
        report[label_name] = {
            "calibration_bins": rate.tolist(),
            "rate": float(label.mean()),
            "ap": average_precision(label, p),
            "ap_within": within_object(objects, label, p, kind="classification")[
                "average_precision"
            ],
            "ece_raw": expected_calibration_error(label, p),
            "ece_calibrated": expected_calibration_error(label, calibrated),
        }
    truth = cat(held, "true_robust_hold")
    pred = cat(held, "fused_robust_hold")
    w = within_object(objects, truth, pred, kind="regression", lower_is_better=False)
    g = gms_distribution(truth, pred, lower_is_better=False, n_subsets=1000)
    report["robust_hold"] = {
        "within_comparison": w["comparison_accuracy"],
        "within_expected_gms": w["expected_gms"],
        "within_random_gms": w["random_expected_gms"],
        "pooled_comparison": comparison_accuracy(truth, pred),
        "pooled_expected_gms": float(np.mean(g)),
    }
    ok = cat(held, "true_viable")
    truth_e, pred_e = cat(held, "true_effort")[ok], cat(held, "fused_effort")[ok]
    pred_e = np.where(np.isfinite(pred_e), pred_e, np.inf)
    w = within_object(objects[ok], truth_e, np.nan_to_num(pred_e, posinf=1e9), kind="regression")
    report["effort_on_viable_rows"] = {
        "rows": int(ok.sum()),
        "within_comparison": w["comparison_accuracy"],
        "within_expected_gms": w["expected_gms"],
    }
    print(json.dumps(report, indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
