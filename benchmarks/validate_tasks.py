"""The paper's validation (§IV-C, Figs. 3-7) as numbers: are the best grasps semantically right?

For each task and each relevant family, over several seeds (object instances), the top-10
grasps of the default mode are found two ways:

* brute force: every one of ``--grasps`` uniform grasps scored with every one of
  ``--uses`` uniform use points; the top 10 distinct grasps, each with its best use point
  (:func:`affordgrasp.pairs.best_pairs` with ``per_grasp=True``);
* the optimiser: the cross-entropy method over p0, each grasp with its best use point of
  ``--uses`` (:func:`affordgrasp.pairs.optimize_pairs`), ``--budget`` simulations.

and judged by the semantic parts of the families:

* cut: the use point lies on the ``cutting_edge``;
* beat: the use point lies on the working end: the head of a hammer (``head``,
  ``striking_face``, ``claw``, ``peen``) or of an axe (the same, ``poll`` and its
  ``cutting_edge``), the blade of a meat cleaver (``blade``, ``cutting_edge``, ``spine``,
  ``tip``);
* pick: the contacts surround the centre of mass: projected along the wrist axis onto
  the palm plane, the centre of mass lies inside the convex hull of the contact points
  (at least three contacts not on one line; hull from scipy, margin 0).

It also renders one figure per task with the best grasp of each family in each mode
(paper Figs. 3-6), and the paper's threshold-mode comparison on the knife (Fig. 7).
Results go to ``--out`` (JSON + PNG); intermediate tables are cached in ``--cache``.

Mass properties: uniform unit density by default (the paper's, and the library's default);
``--materials`` gives the families their per-part materials (steel, wood, ...), which moves
the centre of mass (pick's judge) and I, E_h, E_i.

Run: ``python benchmarks/validate_tasks.py --seeds 5 --out /tmp/validation``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from scipy.spatial import ConvexHull, QhullError

from affordgrasp.objects import load_object
from affordgrasp.pairs import best_pairs, optimize_pairs
from affordgrasp.pipeline import evaluate_samples

TASK_FAMILIES = {
    "cut": ("knife", "meat_cleaver", "axe", "sword", "dagger"),
    "beat": ("hammer", "axe", "meat_cleaver"),
    "pick": (
        "hammer",
        "knife",
        "meat_cleaver",
        "axe",
        "screwdriver",
        "spatula",
        "sword",
        "dagger",
        "bottle",
        "wine_glass",
        "tumbler",
        "mug",
        "ice_cream_cone",
    ),
}
HEAD = {"head", "striking_face", "claw", "peen", "poll"}
WORKING_END = {
    "hammer": HEAD,
    "axe": HEAD | {"cutting_edge"},
    "meat_cleaver": {"blade", "cutting_edge", "spine", "tip"},
}
MODES = ("no-robustness", "default", "extra-robustness")


def surrounds_com(row: dict, com: np.ndarray) -> bool:
    """CoM inside the hull of the contacts projected along the wrist axis (see above)."""
    pts = np.asarray(row["contact_points"], dtype=float).reshape(-1, 3)
    if len(pts) < 3:
        return False
    a = np.asarray(row["wrist_axis"], dtype=float)
    e1 = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    q = np.stack([pts @ e1, pts @ e2], axis=1)
    c = np.array([com @ e1, com @ e2])
    try:
        hull = ConvexHull(q)
    except QhullError:  # collinear contacts
        return False
    # facet equations: n·x + b <= 0 inside
    return bool(np.all(hull.equations[:, :2] @ c + hull.equations[:, 2] <= 0.0))


def judge(task: str, family: str, rows: pa.Table, com: np.ndarray) -> list[bool]:
    out = []
    for row in rows.to_pylist():
        if task == "cut":
            out.append(row["use_part"] == "cutting_edge")
        elif task == "beat":
            out.append(row["use_part"] in WORKING_END[family])
        else:
            out.append(surrounds_com(row, com))
    return out


def grasp_table(cache: Path, family: str, seed: int, n: int, materials: bool = False) -> pa.Table:
    """The uniform grasps of one object (cached: they serve every task)."""
    mass = "materials" if materials else "unit"
    path = cache / f"{family}_{seed}_{n}_{mass}.parquet"
    if path.exists():
        return pq.read_table(path)
    obj = load_object(f"{family}:{seed}", materials=materials)
    table = evaluate_samples(obj, n, seed=0).table
    pq.write_table(table, path)
    return table


def render(cells_rows, row_labels, col_labels, title, path):
    from affordgrasp.viz.grid import save_grid

    save_grid(cells_rows, path, row_labels=row_labels, col_labels=col_labels, title=title)


def cell(obj, table: pa.Table, size: int, caption: str):
    from affordgrasp.viz.overlays import grasp_image
    from affordgrasp.viz.scene import grasp_scene

    if table.num_rows == 0:
        return "no grasp above −∞"
    row = table.slice(0, 1).to_pylist()[0]
    image, _ = grasp_image(grasp_scene(obj, row), size_px=size, caption=caption)
    return image


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--grasps", type=int, default=1000)
    parser.add_argument("--uses", type=int, default=4000)
    parser.add_argument("--budget", type=int, default=1000)
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("--tasks", default="cut,beat,pick")
    parser.add_argument("--no-optimizer", action="store_true")
    parser.add_argument("--no-brute-force", action="store_true")
    parser.add_argument("--families", default="", help="comma-separated subset (default: all)")
    parser.add_argument("--no-figures", action="store_true")
    parser.add_argument("--cell", type=int, default=220)
    parser.add_argument("--cache", default="/tmp/affordgrasp-validation")
    parser.add_argument("--out", default="validation-out")
    parser.add_argument(
        "--materials",
        action="store_true",
        help="the families' per-part materials instead of uniform unit density (the default)",
    )
    args = parser.parse_args()
    cache, out = Path(args.cache), Path(args.out)
    cache.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    report: dict = {"settings": vars(args), "tasks": {}}
    t0 = time.perf_counter()
    for task in args.tasks.split(","):
        per_family = {}
        wanted = [f for f in args.families.split(",") if f]
        for family in TASK_FAMILIES[task]:
            if wanted and family not in wanted:
                continue
            entry = {"brute_force": [], "optimizer": [], "candidates": [], "seeds": []}
            for seed in range(args.seeds):
                obj = load_object(f"{family}:{seed}", materials=args.materials)
                com = obj.mass.center_of_mass
                entry["seeds"].append(seed)
                if not args.no_brute_force:
                    table = grasp_table(cache, family, seed, args.grasps, args.materials)
                    found = best_pairs(
                        obj,
                        task,
                        grasps=args.grasps,
                        uses=args.uses,
                        seed=0,
                        top=args.top,
                        grasp_table=table,
                        per_grasp=True,
                    )
                    ok = judge(task, family, found.table, com)
                    entry["brute_force"].append([int(sum(ok)), len(ok)])
                    entry["candidates"].append(found.candidates)
                    pq.write_table(found.table, cache / f"top_{task}_{family}_{seed}_bf.parquet")
                if not args.no_optimizer:
                    opt = optimize_pairs(
                        obj, task, budget=args.budget, uses=args.uses, seed=seed, top=args.top
                    )
                    ok = judge(task, family, opt.table, com)
                    entry["optimizer"].append([int(sum(ok)), len(ok)])
                    pq.write_table(opt.table, cache / f"top_{task}_{family}_{seed}_opt.parquet")
                print(
                    task,
                    family,
                    seed,
                    entry["brute_force"][-1] if entry["brute_force"] else "",
                    entry["optimizer"][-1] if entry["optimizer"] else "",
                    flush=True,
                )
            for method in ("brute_force", "optimizer"):
                hits = sum(h for h, _ in entry[method])
                total = sum(n for _, n in entry[method])
                entry[f"{method}_fraction"] = hits / total if total else None
            per_family[family] = entry
        summary = {}
        for method in ("brute_force", "optimizer"):
            hits = sum(h for e in per_family.values() for h, _ in e[method])
            total = sum(n for e in per_family.values() for _, n in e[method])
            summary[method] = {
                "hits": hits,
                "top_grasps": total,
                "fraction": hits / total if total else None,
            }
        report["tasks"][task] = {"families": per_family, "summary": summary}
        print(task, json.dumps(summary), flush=True)
    report["seconds"] = round(time.perf_counter() - t0, 1)
    (out / "validation.json").write_text(json.dumps(report, indent=1))
    if not (args.no_figures or args.no_brute_force):
        figures(args, out, cache, report)


def figures(args, out: Path, cache: Path, report: dict) -> None:
    """Per task: best grasp of each family (seed 0) in each mode; Fig. 7 on the knife."""
    for task in report["tasks"]:
        families = TASK_FAMILIES[task][:5]
        rows = []
        for family in families:
            obj = load_object(f"{family}:0", materials=args.materials)
            table = grasp_table(cache, family, 0, args.grasps, args.materials)
            cells = []
            for mode in MODES:
                found = best_pairs(
                    obj,
                    task,
                    mode=mode,
                    grasps=args.grasps,
                    uses=args.uses,
                    top=1,
                    grasp_table=table,
                )
                caption = ""
                if found.table.num_rows:
                    r = found.table.slice(0, 1).to_pylist()[0]
                    caption = f"ε {r['epsilon']:.3f} · U on {r['use_part'] or '-'}"
                cells.append(cell(obj, found.table, args.cell, caption))
            rows.append(cells)
        render(
            rows,
            families,
            list(MODES),
            f"best {task} grasp per mode (brute force)",
            out / f"validation_{task}.png",
        )
    # Fig. 7: beat and cut on the knife, three robustness requirements
    obj = load_object("knife:0", materials=args.materials)
    table = grasp_table(cache, "knife", 0, args.grasps, args.materials)
    rows, numbers = [], {}
    for task in ("beat", "cut"):
        cells = []
        for mode in MODES:
            found = best_pairs(
                obj, task, mode=mode, grasps=args.grasps, uses=args.uses, top=1, grasp_table=table
            )
            r = found.table.slice(0, 1).to_pylist()[0] if found.table.num_rows else None
            numbers[f"{task}/{mode}"] = (
                None
                if r is None
                else {
                    "value": r["value"],
                    "epsilon": r["epsilon"],
                    "use_part": r["use_part"],
                    "contact_parts": sorted(set(r["contact_parts"])),
                }
            )
            caption = "" if r is None else f"ε {r['epsilon']:.3f} · {r['use_part']}"
            cells.append(cell(obj, found.table, args.cell, caption))
        rows.append(cells)
    render(
        rows,
        ["beat", "cut"],
        list(MODES),
        "knife: robustness modes (paper Fig. 7)",
        out / "validation_modes_knife.png",
    )
    (out / "modes_knife.json").write_text(json.dumps(numbers, indent=1))


if __name__ == "__main__":
    main()
