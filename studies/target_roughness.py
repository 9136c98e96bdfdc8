"""How rough is ΣE_h in the pregrasp? The ceiling it sets on any learned ranking.

    python studies/target_roughness.py --data DATA --objects axe:2 bottle:2 mug:1

For the viable grasps of each object of a generated dataset, the pregrasp p0 is perturbed
by Gaussian noise of standard deviation σ (in p0's own units: [-1, 1] for u1..u5, [0, 1]
for u6; clipped) and simulated again. Using the perturbed grasp's ΣE_h as the "prediction"
of the original's is what a model that knew the simulation exactly, but could only resolve
the pose to about σ, would do: its comparison accuracy and E[GMS] (same conventions as
``model-eval``; a grasp that loses viability counts as the worst) bound what a learned
model of that resolution can reach. σ = 0 checks that the simulation is deterministic.
"""

from __future__ import annotations

import argparse
import json

import numpy as np


def main() -> None:
    from affordgrasp.dataset.reading import read_dataset
    from affordgrasp.learning.evaluation import comparison_accuracy, gms_distribution
    from affordgrasp.learning.targets import target_values
    from affordgrasp.pipeline import evaluate_inputs
    from affordgrasp.tasks import MetricColumns, is_viable

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True)
    parser.add_argument("--objects", nargs="+", required=True)
    parser.add_argument(
        "--sigmas", default="0,0.0025,0.005,0.01,0.02,0.05", help="comma-separated σ"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = []
    for name in args.objects:
        table = read_dataset(args.data, objects=[name])
        viable = is_viable(MetricColumns(table))
        effort = target_values("hold_effort_sum", table)[viable]
        p0 = np.asarray(table.column("p0").combine_chunks().flatten()).reshape(-1, 6)[viable]
        use = np.asarray(table.column("use_dir").combine_chunks().flatten()).reshape(-1, 2)
        rows.append((name, p0, use[viable], effort))
    results = []
    for sigma in [float(s) for s in args.sigmas.split(",")]:
        truth, guess, owner, kept = [], [], [], []
        for name, p0, use, effort in rows:
            q = p0 + rng.normal(0.0, sigma, p0.shape) if sigma else p0.copy()
            q[:, :5] = np.clip(q[:, :5], -1.0, 1.0)
            q[:, 5] = np.clip(q[:, 5], 0.0, 1.0)
            table = evaluate_inputs(name, q, use).table
            again = target_values("hold_effort_sum", table)
            ok = is_viable(MetricColumns(table))
            truth.append(effort)
            guess.append(np.where(ok, again, np.inf))
            owner += [name] * len(effort)
            kept.append(ok)
        t, g, o = np.concatenate(truth), np.concatenate(guess), np.asarray(owner)
        g = np.where(np.isfinite(g), g, 1e9)  # lost viability: the worst
        within = [comparison_accuracy(t[o == n], g[o == n]) for n in sorted(set(o))]
        row = {
            "sigma": sigma,
            "grasps": int(len(t)),
            "still_viable": float(np.concatenate(kept).mean()),
            "identical": float(np.mean(g == t)),
            "comparison_accuracy": comparison_accuracy(t, g),
            "within_object_comparison": float(np.nanmean(within)),
            "expected_gms": float(gms_distribution(t, g).mean()),
        }
        results.append(row)
        print(
            f"σ {sigma:<7g} grasps {row['grasps']}  still viable {row['still_viable']:.3f}  "
            f"identical {row['identical']:.3f}  comparison {row['comparison_accuracy']:.3f}  "
            f"within objects {row['within_object_comparison']:.3f}  "
            f"E[GMS] {row['expected_gms']:.3f}",
            flush=True,
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)


if __name__ == "__main__":
    main()
