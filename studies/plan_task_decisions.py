"""Does ``plan --task beat|cut|pick`` choose a grasp that does the task? Decisions from a
camera on unseen tools, with the pose error and the sensor model on.

For each family and variant seed (``~scan`` by default, per-part materials), ``plan`` decides
from the candidates' views (:func:`affordgrasp.learning.plan.plan`, its defaults: 256
candidates, 1 cm and 5° of pose error) with a sensor model, then the chosen grasp is
checked on the true object: task-feasible (p_T >= 0.5 for a task probability, viable for
pick), its task trial in MuJoCo (``beat_ok`` / ``cut_ok``; the hold test for pick), the use
point on the labelled working part and every contact on the hilt. Prints one line per
decision and the rates per family; ``--json`` keeps every decision.

    python studies/plan_task_decisions.py --seeds 401-405 [--families hammer,axe,...]
        [--crisp] [--no-pose-error] [--no-sensor] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

TASKS = {
    "hammer": "beat",
    "axe": "beat",
    "knife": "cut",
    "meat_cleaver": "cut",
    "dagger": "cut",
    "sword": "cut",
    "mug": "pick",
    "bottle": "pick",
    "tumbler": "pick",
}
WORKING = {"beat": ("striking_face", "poll"), "cut": ("cutting_edge",)}
HILT = {"handle", "guard", "pommel"}


def seeds_of(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def one(spec: str, task: str, args) -> dict:
    import affordgrasp as ag
    from affordgrasp.learning.plan import plan
    from affordgrasp.vision.sensor import SensorModel

    obj = ag.load_object(spec, materials=True)
    seed = args.seed
    t0 = time.process_time()
    p = plan(
        obj,
        task,
        seed=seed,
        sensor=None if args.no_sensor else SensorModel(seed=seed),
        pose_error=None if args.no_pose_error else (0.01, 5.0),
        physics=True,
    )
    cpu = time.process_time() - t0
    d = p.summary()
    c = d["chosen"]
    ph = d["physics"] or {}
    trial = f"{task}_ok" if task != "pick" else "hold_ok"
    parts = c.get("contact_parts") or []
    return {
        "feasible": bool(c["feasible"] if task != "pick" else c["viable"]),
        "trial": bool(ph.get(trial)),
        "on_part": None if task == "pick" else c.get("use_part") in WORKING[task],
        "on_hilt": bool(parts) and set(parts) <= HILT,
        "true_score": c["true_score"],
        "fused_score": c["fused_score"],
        "use_part": c.get("use_part"),
        "oracle_feasible": d["measures"]["oracle"]["top1_feasible"],
        "random_feasible": d["measures"]["random"]["top1_feasible"],
        "decision_s": sum(v for k, v in d["timings"].items() if k in ("render", "fuse", "predict")),
        "cpu_s": cpu,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="401-405")
    p.add_argument("--families", default="hammer,axe,knife,meat_cleaver,dagger,sword")
    p.add_argument("--crisp", action="store_true", help="the crisp variants (else ~scan)")
    p.add_argument("--seed", type=int, default=0, help="plan's seed")
    p.add_argument("--no-pose-error", action="store_true")
    p.add_argument("--no-sensor", action="store_true")
    p.add_argument("--json", default=None)
    args = p.parse_args()
    report: dict = {}
    for family in args.families.split(","):
        task = TASKS[family]
        rows = {}
        for s in seeds_of(args.seeds):
            spec = f"{family}:{s}" + ("" if args.crisp else "~scan")
            try:
                rows[spec] = one(spec, task, args)
            except Exception as exc:  # a variant that cannot be built is reported, not fatal
                rows[spec] = {"error": f"{type(exc).__name__}: {exc}"}
            print(f"  {spec} ({task}): {rows[spec]}", flush=True)
        done = [r for r in rows.values() if "error" not in r]
        n = max(len(done), 1)

        def rate(key, done=done, n=n):
            return sum(bool(r[key]) for r in done) / n

        line = (
            f"{family:13s} {task}: {len(done)} decisions: feasible {rate('feasible'):.2f}, "
            f"trial {rate('trial'):.2f}, hand on the hilt {rate('on_hilt'):.2f}"
        )
        if task != "pick":
            line += f", use point on the working part {rate('on_part'):.2f}"
        if done:
            line += f", decision CPU s median {np.median([r['decision_s'] for r in done]):.1f}"
        print(line, flush=True)
        report[family] = {"task": task, "decisions": rows}
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main()
