"""Acceptance of the tasks on scan-like objects: right use point, hand off the working part.

For each task and family, over ``--seeds`` instances, the scan-like variant
(``family:seed~scan``, :mod:`affordgrasp.objects.scan`; beat with the families' materials)
is searched two ways, as in ``affordgrasp validate``: brute force (``--grasps`` uniform
grasps × ``--uses`` use points drawn by area, top ``--top`` distinct grasps) and the optimiser
(``--budget`` simulations). Each top grasp is judged by the part labels the scan-like mesh
keeps from its family:

* cut: the use point on the ``cutting_edge`` ("use"), no contact on the blade or head
  (``blade``, ``cutting_edge``, ``spine``, ``tip``, the axe's head parts: "hand");
* beat: the use point on the striking face (a hammer's ``striking_face``, an axe's
  ``poll``: "use"), every contact on the handle (``handle``, ``shaft``, ``pommel``:
  "hand"); "working end" also counts the use points anywhere on the head (its side
  faces, a peen or claw, an axe's edge: the massive end, but not the striking face);
* pick: the centre of mass inside the contacts' hull seen along the wrist axis
  (:func:`affordgrasp.validation.surrounds_com`).

``--crisp`` judges the crisp families instead (the regression check). Prints one line per
object and a JSON summary (fractions over all top grasps; empty searches counted).

Seeds: the wedge angle and the beat thresholds were calibrated on seeds 0-1, so the
acceptance numbers are measured on the held-out seeds 2-6 (``--seeds 2-6``, the default);
``--seeds 0-1`` gives the calibration seeds' numbers.

Run: ``python studies/validate_scan.py --seeds 2-6 --tasks cut,beat,pick``.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from affordgrasp.objects import load_object
from affordgrasp.pipeline import evaluate_samples
from affordgrasp.search.pairs import PairSearchSettings, best_pairs, optimize_pairs
from affordgrasp.validation import surrounds_com

FAMILIES = {
    "cut": ("knife", "meat_cleaver", "dagger", "sword", "axe"),
    "beat": ("hammer", "axe"),
    "pick": ("hammer", "knife", "mug", "bottle"),
}
HEAD = {"head", "striking_face", "claw", "peen", "poll", "cutting_edge"}
WORKING = {"blade", "cutting_edge", "spine", "tip"}
STRIKE = {"hammer": {"striking_face"}, "axe": {"poll"}}
HANDLE = {"handle", "shaft", "pommel"}


def judge(task: str, family: str, rows: list[dict], com: np.ndarray) -> tuple[int, int, int]:
    """(use right, hand right, use on the working end) counts over the rows."""
    use = hand = end = 0
    for r in rows:
        end += r["use_part"] in (HEAD | {"blade", "spine", "tip"})
        parts = set(r["contact_parts"])
        if task == "cut":
            use += r["use_part"] == "cutting_edge"
            hand += not parts & (HEAD if family == "axe" else WORKING)
        elif task == "beat":
            use += r["use_part"] in STRIKE[family]
            hand += bool(parts) and parts <= HANDLE
        else:
            ok = surrounds_com(r, com)
            use += ok
            hand += ok
    return use, hand, end


def show_search(obj, task: str, line: list):
    """The rows ``affordgrasp show OBJECT --task TASK`` adds with its defaults (its brute
    force, then its fallbacks), as a result with a ``table``; what it said goes on ``line``."""
    from types import SimpleNamespace

    from affordgrasp.commands.show import with_best_pairs
    from affordgrasp.tasks import get_task

    samples = evaluate_samples(obj, 1000, seed=0).table
    args = SimpleNamespace(uses=2000, samples=1000, mode="default", seed=0, top=4, hand="barrett")
    said: list[str] = []
    table = with_best_pairs(
        obj, samples, [get_task(task)], {}, args, SimpleNamespace(text=said.append)
    )
    line.extend(f"[show: {s}]" for s in said)
    return SimpleNamespace(table=table.slice(samples.num_rows))


def seed_list(text: str) -> list[int]:
    """``2-6`` or ``0,1,4`` to a list of seeds."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out.extend(range(int(lo), int(hi or lo) + 1))
    return out


def figure(objects: list[dict], path: str) -> None:
    """Bars per task and family: the fractions of top rows with the use point right and with
    the hand right, brute force and optimiser side by side (counts over all seeds)."""
    from matplotlib.figure import Figure

    keys = sorted({(o["task"], o["object"].split(":")[0]) for o in objects})
    fig = Figure(figsize=(1.4 * len(keys) + 2, 3.6))
    ax = fig.add_subplot()
    width = 0.2
    for j, (method, measure) in enumerate(
        (
            ("brute_force", "use_right"),
            ("brute_force", "hand_right"),
            ("optimizer", "use_right"),
            ("optimizer", "hand_right"),
        )
    ):
        values = []
        for task, family in keys:
            sel = [
                o
                for o in objects
                if o["task"] == task
                and o["object"].startswith(family + ":")
                and o["method"] == method
            ]
            rows = sum(o["rows"] for o in sel)
            values.append(sum(o[measure] for o in sel) / rows if rows else np.nan)
        x = np.arange(len(keys)) + (j - 1.5) * width
        ax.bar(x, np.nan_to_num(values), width, label=f"{method}: {measure}")
        for xi, v in zip(x, values, strict=True):
            if np.isnan(v):
                ax.text(xi, 0.02, "none", rotation=90, ha="center", va="bottom", fontsize=7)
    ax.set_xticks(np.arange(len(keys)), [f"{t}\n{f}" for t, f in keys], fontsize=8)
    ax.axhline(0.9, color="k", lw=0.8, ls="--")
    ax.set_ylim(0, 1.4)
    ax.set_yticks([0, 0.2, 0.4, 0.6, 0.8, 0.9, 1.0])
    ax.set_ylabel("fraction of top-10 rows")
    ax.legend(fontsize=7, loc="upper center", ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="2-6", help="held out: 2-6; calibration: 0-1")
    parser.add_argument("--grasps", type=int, default=3000)
    parser.add_argument("--uses", type=int, default=2000)
    parser.add_argument("--budget", type=int, default=1000)
    parser.add_argument("--restarts", type=int, default=2)
    parser.add_argument("--refine", type=float, default=0.0)
    parser.add_argument("--out", default="", help="also write the JSON report and rows here")
    parser.add_argument(
        "--figure", default="", help="bars from the rows of these --out files (no run)", nargs="*"
    )
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("--tasks", default="cut,beat")
    parser.add_argument("--families", default="", help="comma-separated subset")
    parser.add_argument("--crisp", action="store_true", help="the crisp families instead")
    parser.add_argument("--no-optimizer", action="store_true")
    parser.add_argument("--no-brute-force", action="store_true")
    parser.add_argument(
        "--show",
        action="store_true",
        help="also the search of `affordgrasp show OBJECT --task T` with its defaults (1000 "
        "grasps of seed 0, 2000 use points, top 4, and its fallbacks)",
    )
    parser.add_argument("--cache", default="/tmp/affordgrasp-validation-scan")
    parser.add_argument(
        "--search",
        choices=("plain", "guidance", "uses", "targeted"),
        default="targeted",
        help="plain: use points by area and contacts-and-ε guidance; targeted: use points "
        "that pass the task's use-point tests (passing_uses) and guidance relative to the "
        "thresholds (threshold_guide); guidance / uses: one of the two changes alone in the "
        "optimiser (the brute force scores the passing use points whenever not plain)",
    )
    args = parser.parse_args()
    if args.figure:
        *sources, target = args.figure
        objects = [o for src in sources for o in json.loads(Path(src).read_text())["objects"]]
        figure(objects, target)
        return
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    wanted = [f for f in args.families.split(",") if f]
    t0 = time.perf_counter()
    report: dict = {"settings": vars(args), "tasks": {}, "objects": []}
    for task in args.tasks.split(","):
        methods = ("brute_force", "optimizer", "show")
        totals = {m: [0, 0, 0, 0] for m in methods}  # use, hand, rows, end
        empty = {m: [] for m in methods}
        for family in FAMILIES[task]:
            if wanted and family not in wanted:
                continue
            for seed in seed_list(args.seeds):
                spec = f"{family}:{seed}" + ("" if args.crisp else "~scan")
                materials = task == "beat"
                obj = load_object(spec, materials=materials)
                com = obj.mass.center_of_mass
                path = cache / f"{spec.replace(':', '_')}_{args.grasps}_{materials}.parquet"
                if path.exists():
                    table = pq.read_table(path)
                else:
                    table = evaluate_samples(obj, args.grasps, seed=0, volume=False).table
                    pq.write_table(table, path)
                line = [task, spec]
                targeted = args.search != "plain"
                passing = args.search in ("uses", "targeted")
                guide = args.search in ("guidance", "targeted")
                common = PairSearchSettings(task, uses=args.uses, seed=0, top=args.top)
                started = time.perf_counter()
                found = (
                    None
                    if args.no_brute_force
                    else best_pairs(
                        obj, replace(common, per_grasp=True, passing_uses=targeted), table
                    )
                )
                seconds = {"brute_force": time.perf_counter() - started}
                searches = [] if args.no_brute_force else [("brute_force", found)]
                if not args.no_optimizer:
                    started = time.perf_counter()
                    aimed = replace(
                        common,
                        seed=seed,
                        budget=args.budget,
                        restarts=args.restarts,
                        refine=args.refine,
                        passing_uses=passing,
                        threshold_guide=guide,
                    )
                    opt = optimize_pairs(obj, aimed)
                    seconds["optimizer"] = time.perf_counter() - started
                    searches.append(("optimizer", opt))
                if args.show:
                    started = time.perf_counter()
                    searches.append(("show", show_search(obj, task, line)))
                    seconds["show"] = time.perf_counter() - started
                for method, result in searches:
                    rows = result.table.to_pylist()
                    use, hand, end = judge(task, family, rows, com)
                    totals[method][0] += use
                    totals[method][1] += hand
                    totals[method][2] += len(rows)
                    totals[method][3] += end
                    report["objects"].append(
                        {
                            "task": task,
                            "object": spec,
                            "method": method,
                            "rows": len(rows),
                            "use_right": use,
                            "hand_right": hand,
                            "working_end": end,
                            "seconds": round(seconds[method], 1),
                            "use_parts": [r["use_part"] for r in rows],
                            "contact_parts": [sorted(set(r["contact_parts"])) for r in rows],
                        }
                    )
                    sampling = getattr(result, "sampling", None)
                    if sampling is not None:
                        report["objects"][-1]["use_sampling"] = sampling.to_dict()
                    if not rows:
                        empty[method].append(spec)
                    line.append(f"{method} use {use}/{len(rows)} hand {hand}/{len(rows)}")
                print(*line, f"{time.perf_counter() - t0:.0f}s", flush=True)
        report["tasks"][task] = {
            m: {
                "use_right": totals[m][0] / max(totals[m][2], 1),
                "hand_right": totals[m][1] / max(totals[m][2], 1),
                "use_on_working_end": totals[m][3] / max(totals[m][2], 1),
                "rows": totals[m][2],
                "empty_searches": empty[m],
            }
            for m in totals
            if totals[m][2] or empty[m]
        }
    report["seconds"] = round(time.perf_counter() - t0, 1)
    if args.out:
        Path(args.out).write_text(json.dumps(report, indent=1))
    report.pop("objects")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
