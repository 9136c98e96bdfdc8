"""Why a pair search comes back empty: which test its best near misses fail, and by how much.

Runs :func:`affordgrasp.search.pairs.optimize_pairs` (with ``--targeted``, guided by the
task's thresholds) on scan-like objects and keeps every grasp it
simulated. For those grasps and the search's use points it reports, per test of the task
(:func:`affordgrasp.search.guidance.task_tests`):

* grasps: how many pass each test of the grasp alone (ε, thickness, width) and all of them;
* use points: how many pass the tests of the use point alone (the candidates);
* pairs of a grasp that passes its own tests with a candidate use point: how many fail each
  test of the pair, and the near misses (pairs that fail exactly one test), by test;
* the 10 grasps the search's guidance ranked highest: per test, how many fail it and the
  median of value / τ over those that fail.

Run: ``python studies/search_near_misses.py --objects knife:1~scan,meat_cleaver:0~scan
--task cut``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import pyarrow as pa

import affordgrasp.pipeline as pipeline
import affordgrasp.search.pairs as pairs
from affordgrasp.objects import load_object
from affordgrasp.search.guidance import (
    GRASP_ONLY,
    USE_ONLY,
    pair_columns,
    task_tests,
    use_only_passes,
)
from affordgrasp.tasks import get_task


def passes(t, v):
    with np.errstate(invalid="ignore"):
        return (v >= t.tau) if t.sense > 0 else (v <= t.tau)


def study(spec, task_name, budget, restarts, uses_n, seed, materials, targeted):
    obj = load_object(spec, materials=materials)
    task = get_task(task_name)
    seen: list[pa.Table] = []
    original = pairs.evaluate_inputs

    def recording(*a, **k):
        result = original(*a, **k)
        if k.get("volume") is False:
            seen.append(result.table)
        return result

    pairs.evaluate_inputs = recording
    pipeline.evaluate_inputs = recording
    t0 = time.perf_counter()
    try:
        settings = pairs.PairSearchSettings(
            task_name,
            uses=uses_n,
            seed=seed,
            budget=budget,
            restarts=restarts,
            threshold_guide=targeted,
        )
        found = pairs.optimize_pairs(obj, settings)
        uses = found.use_points
    finally:
        pairs.evaluate_inputs = original
        pipeline.evaluate_inputs = original
    elapsed = time.perf_counter() - t0
    rows = pa.concat_tables(seen)
    n = rows.num_rows
    tests = task_tests(task)
    touched = rows.column("n_contacts").to_numpy() > 0
    report = {
        "object": spec,
        "rows_found": found.table.num_rows,
        "seconds": round(elapsed, 1),
        "grasps": n,
        "touched": int(touched.sum()),
    }
    ok_grasp = touched.copy()
    for t in tests:
        if t.column in GRASP_ONLY:
            v = rows.column(t.column).to_numpy(zero_copy_only=False).astype(float)
            p = passes(t, v) & touched
            report[f"grasps passing {t.threshold}"] = int(p.sum())
            ok_grasp &= p
    report["grasps passing every grasp test"] = int(ok_grasp.sum())
    cand = np.flatnonzero(use_only_passes(task, "default", {}, uses))
    report["candidate use points"] = int(cand.size)
    pair_tests = [t for t in tests if t.column not in GRASP_ONLY and t.column not in USE_ONLY]
    good = np.flatnonzero(ok_grasp)
    if good.size and cand.size:
        gi, ui = np.meshgrid(good, cand, indexing="ij")
        gi, ui = gi.ravel(), ui.ravel()
        cols = pair_columns(obj, rows, uses, ui, gi)
        fails = np.stack([~passes(t, cols[t.column]) for t in pair_tests], axis=1)
        report["pairs (good grasp x candidate)"] = int(len(gi))
        report["pairs passing every test"] = int((~fails.any(axis=1)).sum())
        for j, t in enumerate(pair_tests):
            report[f"pairs failing {t.threshold}"] = int(fails[:, j].sum())
        one = fails.sum(axis=1) == 1
        for j, t in enumerate(pair_tests):
            sel = one & fails[:, j]
            if sel.any():
                v = cols[t.column][sel]
                report[f"near misses on {t.threshold} only"] = (
                    f"{int(sel.sum())} (value median {np.median(v):.3g}, tau {t.tau:.3g})"
                )
    # the old guidance's top grasps: which grasp-only tests they fail
    from affordgrasp.search.pairs import pair_guidance

    eps_column = tuple(c for c in ("epsilon_hand",) if c in task.requires)
    g = pair_guidance(rows, task, "default", {}, uses, eps_column)
    top = np.argsort(-g)[:10]
    for t in tests:
        if t.column in GRASP_ONLY:
            v = rows.column(t.column).to_numpy(zero_copy_only=False).astype(float)[top]
            f = ~passes(t, v)
            report[f"top-10 guidance failing {t.threshold}"] = (
                f"{int(f.sum())} (value/tau median {np.median(v[f] / t.tau):.2f})"
                if f.any()
                else "0"
            )
    return report


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--objects", required=True)
    p.add_argument("--task", default="cut")
    p.add_argument("--budget", type=int, default=600)
    p.add_argument("--restarts", type=int, default=1)
    p.add_argument("--uses", type=int, default=2000)
    p.add_argument("--materials", action="store_true")
    p.add_argument("--targeted", action="store_true")
    args = p.parse_args()
    for spec in args.objects.split(","):
        seed = int(spec.split(":")[1].split("~")[0])
        r = study(
            spec,
            args.task,
            args.budget,
            args.restarts,
            args.uses,
            seed,
            args.materials,
            args.targeted,
        )
        print(json.dumps(r, indent=1), flush=True)


if __name__ == "__main__":
    main()
