"""End-to-end throughput: grasps/s per core for simulation + the full metric vector Φ.

    python benchmarks/bench_pipeline.py [--samples 1000] [--objects hammer knife mug]

Runs on one core (the pipeline is single-threaded per process; `affordgrasp generate` runs
one process per core). Object preparation (surface sampling, cached per object) and the
first call's compilation are timed apart and excluded from the rate.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--objects", nargs="+", default=["hammer", "knife", "mug"])
    parser.add_argument("--hand", default="barrett")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    from affordgrasp.grasp.policy import object_geometry
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_samples

    t0 = time.perf_counter()
    evaluate_samples("tumbler", 4, seed=123, hand=args.hand)  # compile / load the kernels
    print(f"first call (kernel compilation or cache load): {time.perf_counter() - t0:.2f} s")
    header = (
        f"{'object':<10}{'prepare s':>10}{'sim only':>10}{'sim + Φ':>10}"
        f"{'sim %':>7}{'Φ %':>6}{'table %':>8}"
    )
    print(header)
    rates = []
    sim_rates = []
    for spec in args.objects:
        t0 = time.perf_counter()
        obj = load_object(spec)
        object_geometry(obj)
        prepare = time.perf_counter() - t0
        t0 = time.perf_counter()
        result = evaluate_samples(obj, args.samples, seed=args.seed, hand=args.hand)
        table, spent = result.table, result.timings
        wall = time.perf_counter() - t0
        total = sum(spent.values())
        rate = args.samples / wall
        rates.append(rate)
        sim_rates.append(args.samples / spent["simulate"])
        status = np.asarray(table.column("status").to_pylist())
        print(
            f"{obj.name:<10}{prepare:>10.2f}{sim_rates[-1]:>10.0f}{rate:>10.0f}"
            f"{100 * spent['simulate'] / total:>7.0f}{100 * spent['metrics'] / total:>6.0f}"
            f"{100 * spent['table'] / total:>8.0f}"
            f"   ({', '.join(f'{s} {np.mean(status == s):.0%}' for s in np.unique(status))})"
        )
    print(
        f"mean: {np.mean(sim_rates):.0f} grasps/s/core simulation only, "
        f"{np.mean(rates):.0f} grasps/s/core simulation + every metric (one core)"
    )


if __name__ == "__main__":
    main()
