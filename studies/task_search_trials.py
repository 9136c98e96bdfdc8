"""Do the grasps a search ranks first for beat and cut do the task? Top-k trial success.

For each tool (hammer and axe for beat; knife, meat cleaver, dagger and sword for cut) and
each variant seed, crisp or ``~scan``, with per-part materials: the brute-force pair search
(:func:`affordgrasp.search.pairs.best_pairs`, ``per_grasp``: the top ``--top`` distinct
grasps, each with its best use point) ranks by the task, and each of its top grasps is tried
in the task's physical trial (:mod:`affordgrasp.physics.task_trials`). Prints, per family:
the share of the top grasps that succeed in the trial, whose use point lies on the labelled
working part (striking face or poll; cutting edge) and whose every contact lies on the hilt
(handle, guard, pommel); and whether the search returned anything.

    python studies/task_search_trials.py --seeds 60-64 [--scan] [--task beat|cut|both]
        [--grasps 2000] [--uses 1000] [--top 10] [--rank beat-rules] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

FAMILIES = {
    "beat": ("hammer", "axe"),
    "cut": ("knife", "meat_cleaver", "dagger", "sword"),
}
WORKING = {"beat": ("striking_face", "poll"), "cut": ("cutting_edge",)}
HILT = {"handle", "guard", "pommel"}


def seeds_of(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def one(spec: str, task: str, rank: str, args) -> dict:
    import affordgrasp as ag
    from affordgrasp.physics.run import validate_rows
    from affordgrasp.physics.settings import PhysicsSettings
    from affordgrasp.search.pairs import PairSearchSettings, best_pairs

    obj = ag.load_object(spec, materials=True)
    t0 = time.process_time()
    settings = PairSearchSettings(
        rank, grasps=args.grasps, uses=args.uses, top=args.top, per_grasp=True, seed=args.seed
    )
    found = best_pairs(obj, settings).table
    search_s = time.process_time() - t0
    if found.num_rows == 0:
        return {"rows": 0, "search_s": search_s}
    out = validate_rows(found, "barrett", {obj.name: obj}, PhysicsSettings(), trials=[task])
    ok = np.array([bool(v) for v in out.column(f"{task}_ok").to_pylist()])
    use_part = np.array(found.column("use_part").to_pylist())
    on_part = np.isin(use_part, WORKING[task])
    hilt = np.array([bool(p) and set(p) <= HILT for p in found.column("contact_parts").to_pylist()])
    value = found.column("value").to_numpy()
    return {
        "rows": int(found.num_rows),
        "success": int(ok.sum()),
        "on_part": int(on_part.sum()),
        "on_hilt": int(hilt.sum()),
        "part_and_hilt": int((on_part & hilt).sum()),
        "best_value": float(value[0]),
        "search_s": search_s,
        "trial_s": time.process_time() - t0 - search_s,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="60-64")
    p.add_argument("--scan", action="store_true", help="the ~scan variants (else crisp)")
    p.add_argument("--task", default="both", choices=("beat", "cut", "both"))
    p.add_argument("--rank", default=None, help="rank by this task (default: the task itself)")
    p.add_argument("--grasps", type=int, default=2000)
    p.add_argument("--uses", type=int, default=1000)
    p.add_argument("--top", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None)
    args = p.parse_args()
    tasks = ("beat", "cut") if args.task == "both" else (args.task,)
    report: dict = {}
    for task in tasks:
        rank = args.rank or task
        for family in FAMILIES[task]:
            rows = {}
            for s in seeds_of(args.seeds):
                spec = f"{family}:{s}" + ("~scan" if args.scan else "")
                rows[spec] = one(spec, task, rank, args)
                r = rows[spec]
                print(f"  {spec} ({rank}): {r}", flush=True)
            tot = {k: sum(r.get(k, 0) for r in rows.values()) for k in next(iter(rows.values()))}
            n = max(tot["rows"], 1)
            empty = sum(r["rows"] == 0 for r in rows.values())
            print(
                f"{family:13s} {task}: top {args.top} of {len(rows)} variants: trial success "
                f"{tot.get('success', 0) / n:.2f}, use point on the working part "
                f"{tot.get('on_part', 0) / n:.2f}, every contact on the hilt "
                f"{tot.get('on_hilt', 0) / n:.2f}, both {tot.get('part_and_hilt', 0) / n:.2f}; "
                f"empty results {empty}",
                flush=True,
            )
            report[family] = {"task": task, "rank": rank, "objects": rows, "empty": empty}
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main()
