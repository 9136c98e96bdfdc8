"""Cross-entropy optimisation against uniform random sampling at equal simulation budget.

For every object, one long uniform random run (a dataset written by ``generate``, resumable)
serves every task: ``random@B`` is the best F_T of a window of B consecutive samples of it
(all disjoint windows are replicates), and the number of random simulations needed to match
a value v is estimated as ``N / #{samples with F_T >= v}`` (the mean of a geometric law;
"> N" when no sample of the long run reaches v). CEM runs with budget B for a few seeds.

    python studies/optimizer_vs_random.py --budget 1000 --random 20000 --seeds 3
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

DEFAULT_TASKS = ["pick:default", "cut:default", "cut:no-robustness", "beat:no-robustness"]


def cem_run(spec: str, task: str, mode: str, budget: int, seed: int) -> dict:
    from affordgrasp.objects import load_object
    from affordgrasp.search.optimize import optimize

    try:
        r = optimize(spec, task, mode=mode, budget=budget, seed=seed, workers=1, baseline=False)
    except Exception as exc:  # noqa: BLE001 - report the failing case, keep benchmarking
        name = load_object(spec).name
        print(f"FAILED {name} {task}:{mode} seed {seed}: {type(exc).__name__}: {exc}", flush=True)
        return {
            "object": name,
            "task": task,
            "mode": mode,
            "seed": seed,
            "best": None,
            "error": f"{type(exc).__name__}: {exc}",
        }
    best = r.cem.value if r.cem else -np.inf
    trace = r.cem_trace.best_so_far()
    return {
        "object": r.object,
        "task": task,
        "mode": mode,
        "seed": seed,
        "best": best,
        "finite": int(np.sum(r.cem_trace.values > -np.inf)),
        "best_so_far": {str(k): float(trace[k - 1]) for k in (budget // 4, budget // 2, budget)},
        "seconds": r.elapsed_s,
    }


def random_stats(values: np.ndarray, budget: int, cem_best: list[float]) -> dict:
    n = len(values)
    windows = values[: n - n % budget].reshape(-1, budget)
    best_at_b = windows.max(axis=1)
    needed = []
    for v in cem_best:
        if not v > -np.inf:
            needed.append(None)  # CEM found nothing feasible: nothing to match
            continue
        hits = int(np.sum(values >= v))
        needed.append(n / hits if hits else f">{n}")
    return {
        "random_at_budget_median": float(np.median(best_at_b)),
        "random_at_budget_mean": float(np.mean(best_at_b[np.isfinite(best_at_b)]))
        if np.isfinite(best_at_b).any()
        else -np.inf,
        "random_at_budget_replicates": int(len(best_at_b)),
        "random_best_overall": float(values.max()),
        "random_finite_fraction": float(np.mean(values > -np.inf)),
        "random_needed_to_match_cem": needed,
        "cem_beats_random_windows": [float(np.mean(v > best_at_b)) for v in cem_best],
    }


def fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, float) and not np.isfinite(v):
        return str(v)
    return f"{v:.4g}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--objects", nargs="+", default=["knife", "hammer", "screwdriver"])
    p.add_argument("--tasks", nargs="+", default=DEFAULT_TASKS, help="task:mode")
    p.add_argument("--budget", type=int, default=1000)
    p.add_argument("--random", type=int, default=20000, help="length of the random run")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--data", default="bench-random-run", help="dataset dir (reused if there)")
    p.add_argument("--json", default=None)
    args = p.parse_args()

    from affordgrasp.dataset.generate import generate
    from affordgrasp.dataset.reading import read_dataset
    from affordgrasp.robust import task_scores
    from affordgrasp.runtime.engines import default_workers

    started = time.perf_counter()
    summary = generate(args.objects, args.random, args.data, seed=1000, workers=args.workers)
    print(
        f"random run: {summary.samples_written} new samples in {summary.elapsed_s:.0f} s "
        f"({summary.grasps_per_s:.1f} grasps/s on {summary.workers} workers)",
        flush=True,
    )
    combos = [
        (spec, *tm.split(":"), seed)
        for spec in args.objects
        for tm in args.tasks
        for seed in range(args.seeds)
    ]
    with ProcessPoolExecutor(max_workers=args.workers or default_workers()) as pool:
        futures = [pool.submit(cem_run, s, t, m, args.budget, seed) for s, t, m, seed in combos]
        runs = [f.result() for f in futures]

    results = []
    print(
        f"\nbudget {args.budget} simulations; random run {args.random} per object\n"
        f"{'object':14s} {'task':22s} {'random@B med':>12s} {'CEM (seeds)':>30s} "
        f"{'CEM>random@B':>12s} {'random sims to match CEM':>26s}"
    )
    for spec in args.objects:
        obj_runs = [r for r in runs if r["object"].split(":")[0] == spec.split(":")[0]]
        name = obj_runs[0]["object"]
        table = read_dataset(args.data, objects=[name])
        for tm in args.tasks:
            task, mode = tm.split(":")
            values = task_scores(task, table, mode)
            values = np.where(np.isnan(values), -np.inf, values)
            rr = [r for r in obj_runs if r["task"] == task and r["mode"] == mode]
            cem_best = [r["best"] for r in rr if r["best"] is not None]
            stats = random_stats(values, args.budget, cem_best)
            row = {"object": name, "task": task, "mode": mode, "cem": rr, **stats}
            results.append(row)
            print(
                f"{name:14s} {tm:22s} {fmt(stats['random_at_budget_median']):>12s} "
                f"{' '.join(fmt(v) for v in cem_best):>30s} "
                f"{' '.join(f'{v:.2f}' for v in stats['cem_beats_random_windows']):>12s} "
                f"{' '.join(fmt(v) for v in stats['random_needed_to_match_cem']):>26s}",
                flush=True,
            )
    doc = {
        "budget": args.budget,
        "random_run": args.random,
        "seeds": args.seeds,
        "results": results,
        "elapsed_s": time.perf_counter() - started,
    }
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=2, default=float))


if __name__ == "__main__":
    main()
