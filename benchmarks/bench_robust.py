"""Throughput of robust labelling: robust-labelled grasps/s per core at K copies per grasp.

    python benchmarks/bench_robust.py [--samples 200] [--copies 25] [--objects hammer mug]

One process, one core. Per object: the plain evaluation of the grasps (simulation + Φ), then
the K perturbed copies of every grasp (:func:`affordgrasp.robust.robust_columns`: one compiled
simulation call for all n·K copies, one compiled metric call, the summaries). The rate counts
a grasp once it has its plain and robust columns; CPU seconds of this process are used (the
machine may be shared), wall seconds are shown beside them. Targets (issue: robust task
quality): >= 60 grasps/s/core on the tool families, >= 30 on the containers.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

TOOLS = ("hammer", "knife", "meat_cleaver", "axe", "screwdriver", "spatula", "sword", "dagger")
CONTAINERS = ("bottle", "wine_glass", "tumbler", "mug", "ice_cream_cone")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--copies", type=int, default=25)
    parser.add_argument("--objects", nargs="+", default=[*TOOLS, *CONTAINERS])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    from affordgrasp.grasp.policy import object_geometry, simulate
    from affordgrasp.grasp.pregrasp import sample_inputs
    from affordgrasp.hands import get_hand
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import phi_of_batch
    from affordgrasp.robust import RobustSettings, robust_columns

    hand = get_hand("barrett")
    settings = RobustSettings(copies=args.copies)
    warm = load_object("tumbler")
    p0, d = sample_inputs(123, 0, 4)
    b = simulate(warm, p0, d, hand=hand)
    robust_columns(warm, b, RobustSettings(copies=2), hand=hand)  # load the kernels

    print(
        f"K = {args.copies}, {args.samples} grasps per object, one core "
        "(CPU s of this process; wall in brackets)"
    )
    header = (
        f"{'object':<15}{'kind':<10}{'grasps/s':>9}{'copies/s':>10}{'plain %':>8}"
        f"{'copy sim %':>11}{'copy Φ %':>9}{'summary %':>10}{'FC':>6}{'robust FC':>10}"
    )
    print(header)
    rates: dict[str, list[float]] = {"tool": [], "container": []}
    p0, d = sample_inputs(args.seed, 0, args.samples)
    for spec in args.objects:
        obj = load_object(spec)
        object_geometry(obj)
        kind = "container" if spec in CONTAINERS else "tool"
        c0, w0 = time.process_time(), time.perf_counter()
        batch = simulate(obj, p0, d, hand=hand)
        phi = phi_of_batch(obj, batch, volume=False)
        w1 = time.perf_counter()
        spent: dict[str, float] = {}
        cols = robust_columns(obj, batch, settings, hand=hand, phi=phi, timings=spent)
        c2, w2 = time.process_time(), time.perf_counter()
        cpu = c2 - c0
        rate = args.samples / cpu
        rates[kind].append(rate)
        wall = w2 - w0  # the stages' shares are of wall time (the stages are timed by wall)
        share = {k: 100 * v / wall for k, v in spent.items()}
        print(
            f"{obj.name:<15}{kind:<10}{rate:>9.1f}{rate * args.copies:>10.0f}"
            f"{100 * (w1 - w0) / wall:>8.0f}{share['simulate']:>11.0f}{share['metrics']:>9.0f}"
            f"{share['summary']:>10.0f}{np.mean(phi['epsilon'] > 0):>6.2f}"
            f"{np.mean(cols['robust_fc']):>10.2f}   [{args.samples / wall:.1f} wall]"
        )
    for kind, target in (("tool", 60), ("container", 30)):
        if rates[kind]:
            r = np.asarray(rates[kind])
            print(
                f"{kind}s: min {r.min():.1f}, median {np.median(r):.1f} grasps/s/core "
                f"(target >= {target})"
            )


if __name__ == "__main__":
    main()
