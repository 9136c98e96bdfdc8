"""Throughput of the physics validation: validations per core-hour, per object.

    python benchmarks/bench_physics.py DATASET [--rows 100] [--protocol affordgrasp|dgb]

Validates the first ROWS grasped rows of each object of DATASET (a directory written by
``affordgrasp generate``) in this process, one core, after building each object's scene
(the convex decomposition is cached; its first computation is not counted). Prints wall
time and CPU time per validation: on a shared machine the CPU time is the fairer figure.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("--rows", type=int, default=100, help="grasped rows per object")
    parser.add_argument("--protocol", default="affordgrasp", choices=("affordgrasp", "dgb"))
    args = parser.parse_args()

    from affordgrasp.dataset import Dataset
    from affordgrasp.physics.run import _plan_rows, validate_rows
    from affordgrasp.physics.settings import protocol_settings

    settings = protocol_settings(args.protocol)
    dataset = Dataset.open(args.dataset)
    rows = _plan_rows(dataset, ("grasped",), None, args.rows)
    hand = dataset.hand
    names = np.array(rows.column("object").to_pylist())
    print("| object | rows | wall ms/validation | CPU ms/validation | per core-hour (CPU) |")
    print("|---|---:|---:|---:|---:|")
    total_rows, total_cpu, total_wall = 0, 0.0, 0.0
    for name in dict.fromkeys(names):
        objects = {name: dataset.object(name)}
        idx = np.flatnonzero(names == name)
        part = rows.take(idx)
        validate_rows(part.slice(0, 1), hand, objects, settings)  # compile, not timed
        wall, cpu = time.perf_counter(), time.process_time()
        validate_rows(part, hand, objects, settings)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        n = len(idx)
        total_rows, total_cpu, total_wall = total_rows + n, total_cpu + cpu, total_wall + wall
        print(
            f"| {name} | {n} | {1e3 * wall / n:.1f} | {1e3 * cpu / n:.1f} | {3600 * n / cpu:,.0f} |"
        )
    print(
        f"| **all** | {total_rows} | {1e3 * total_wall / total_rows:.1f} | "
        f"{1e3 * total_cpu / total_rows:.1f} | {3600 * total_rows / total_cpu:,.0f} |"
    )
    print(f"wall-clock rate: {3600 * total_rows / total_wall:,.0f} validations/hour on one core")


if __name__ == "__main__":
    main()
