"""The paper's validation (§IV-C, Figs. 3-7) as numbers: are the best grasps semantically right?

For each task and each relevant family, over several seeds (object instances), the top-10
grasps of the default mode are found two ways:

* brute force: every one of ``--grasps`` uniform grasps scored with every one of
  ``--uses`` uniform use points; the top 10 distinct grasps, each with its best use point
  (:func:`affordgrasp.pairs.best_pairs` with ``per_grasp=True``);
* the optimiser: the cross-entropy method over p0, each grasp with its best use point of
  ``--uses`` (:func:`affordgrasp.pairs.optimize_pairs`), ``--budget`` simulations shared
  by ``--restarts`` independent runs; with ``--refine f`` the share f of the budget then
  continues the best run around its best point.

The searches score with ε alone (no GWS volume: ``volume=False``), which leaves every score
unchanged and skips the 6-D hull of enveloping grasps.

and judged by the semantic parts of the families:

* cut: the use point lies on the ``cutting_edge``;
* beat: the use point lies on the working end: the head of a hammer (``head``,
  ``striking_face``, ``claw``, ``peen``) or of an axe (the same, ``poll`` and its
  ``cutting_edge``), the blade of a meat cleaver (``blade``, ``cutting_edge``, ``spine``,
  ``tip``), by its face's part or by lying within 3 mm of the box of those parts' faces
  (the handle's end shows through the eye of a head; ``*_labels`` in the JSON: by the
  part alone);
* pick: the contacts surround the centre of mass: projected along the wrist axis onto
  the palm plane, the centre of mass lies inside the convex hull of the contact points
  (at least three contacts not on one line; hull from scipy, margin 0).

It also renders one figure per task with the best grasp of each family in each mode
(paper Figs. 3-6), and the paper's threshold-mode comparison on the knife (Fig. 7).
Results go to ``--out`` (JSON + PNG); intermediate tables are cached in ``--cache``.

``--also-grasps K`` repeats the brute force on the first K of the ``--grasps`` uniform grasps
(sample i of a run depends only on the run's seed and i, so they are exactly the grasps a
K-grasp brute force draws) and reports it beside the full one (``brute_force_at_K``): the
acceptance count "finite scores with 4000 uniform samples" and the effect of the count.

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
# A hammer's or an axe's handle runs through the eye of the head and its end shows on the
# head (hammer:4: 15 mm² of handle faces beside the head's top, 462 mm² on it): a use point
# there strikes with the head, yet its face is labelled handle. So beat counts a use point
# inside the box of the working-end faces (grown by the 3 mm contact merge distance) too.
WORKING_END_GROW_M = 0.003
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


def working_end_box(obj, family: str, grow: float = WORKING_END_GROW_M) -> np.ndarray:
    """(2, 3) box around the faces of the family's working-end parts, grown by ``grow`` m."""
    faces = np.isin(obj.parts_of_faces(np.arange(len(obj.mesh.faces))), list(WORKING_END[family]))
    corners = obj.mesh.vertices[obj.mesh.faces[faces].ravel()]
    return np.stack([corners.min(axis=0) - grow, corners.max(axis=0) + grow])


def judge(
    task: str, family: str, rows: pa.Table, com: np.ndarray, box: np.ndarray | None = None
) -> list[bool]:
    """Is each top row right? ``box``: beat's working-end region (strict part labels if None)."""
    out = []
    for row in rows.to_pylist():
        if task == "cut":
            out.append(row["use_part"] == "cutting_edge")
        elif task == "beat":
            inside = box is not None and bool(
                np.all(
                    (np.asarray(row["use_point"]) >= box[0])
                    & (np.asarray(row["use_point"]) <= box[1])
                )
            )
            out.append(row["use_part"] in WORKING_END[family] or inside)
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
    # ε only: the search never reads the GWS volume (NaN here for force-closure grasps)
    table = evaluate_samples(obj, n, seed=0, volume=False, batch_size=2000).table
    pq.write_table(table, path)
    return table


def scored(task: str, family: str, top: pa.Table, com, box) -> dict:
    """Judge a top table: hits with the working-end box, hits by labels alone, top-1."""
    ok = judge(task, family, top, com, box)
    strict = judge(task, family, top, com)
    return {
        "hits": [int(sum(ok)), len(ok)],
        "labels": [int(sum(strict)), len(strict)],
        "top1": bool(ok[0]) if ok else None,
    }


def brute_force(obj, task: str, table: pa.Table, uses: int, top: int) -> object:
    """Top ``top`` distinct grasps of ``table`` × ``uses`` use points."""
    return best_pairs(
        obj,
        task,
        grasps=table.num_rows,
        uses=uses,
        seed=0,
        top=top,
        grasp_table=table,
        per_grasp=True,
    )


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
    parser.add_argument(
        "--restarts", type=int, default=1, help="independent CEM runs sharing the budget"
    )
    parser.add_argument(
        "--refine",
        type=float,
        default=0.0,
        help="share of --budget that continues the best restart around its best point",
    )
    parser.add_argument(
        "--also-grasps",
        type=int,
        default=0,
        help="also the brute force on the first K of the --grasps grasps (0: not)",
    )
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
    if not 0 <= args.also_grasps < args.grasps:
        parser.error(f"--also-grasps must lie in [0, --grasps), got {args.also_grasps}")
    also = args.also_grasps
    cache, out = Path(args.cache), Path(args.out)
    cache.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    report: dict = {"settings": vars(args), "tasks": {}}
    t0 = time.perf_counter()
    methods = ["brute_force", "optimizer", "brute_force_labels", "optimizer_labels"]
    if also:
        methods += [f"brute_force_at_{also}", f"brute_force_at_{also}_labels"]
    for task in args.tasks.split(","):
        per_family = {}
        wanted = [f for f in args.families.split(",") if f]
        for family in TASK_FAMILIES[task]:
            if wanted and family not in wanted:
                continue
            entry = {
                "brute_force": [],
                "optimizer": [],
                "brute_force_labels": [],  # beat judged by the part labels alone
                "optimizer_labels": [],
                "top1": {"brute_force": [], "optimizer": []},
                "candidates": [],
                "opt_candidates": [],
                "seeds": [],
            }
            if also:
                entry[f"brute_force_at_{also}"] = []
                entry[f"brute_force_at_{also}_labels"] = []
                entry["top1"][f"brute_force_at_{also}"] = []
            for seed in range(args.seeds):
                obj = load_object(f"{family}:{seed}", materials=args.materials)
                com = obj.mass.center_of_mass
                box = working_end_box(obj, family) if task == "beat" else None
                entry["seeds"].append(seed)
                if not args.no_brute_force:
                    table = grasp_table(cache, family, seed, args.grasps, args.materials)
                    found = brute_force(obj, task, table, args.uses, args.top)
                    bf = scored(task, family, found.table, com, box)
                    entry["brute_force"].append(bf["hits"])
                    entry["brute_force_labels"].append(bf["labels"])
                    entry["top1"]["brute_force"].append(bf["top1"])
                    entry["candidates"].append(found.candidates)
                    pq.write_table(found.table, cache / f"top_{task}_{family}_{seed}_bf.parquet")
                    if also:
                        head = brute_force(obj, task, table.slice(0, also), args.uses, args.top)
                        first = scored(task, family, head.table, com, box)
                        entry[f"brute_force_at_{also}"].append(first["hits"])
                        entry[f"brute_force_at_{also}_labels"].append(first["labels"])
                        entry["top1"][f"brute_force_at_{also}"].append(first["top1"])
                if not args.no_optimizer:
                    opt = optimize_pairs(
                        obj,
                        task,
                        budget=args.budget,
                        uses=args.uses,
                        seed=seed,
                        top=args.top,
                        restarts=args.restarts,
                        refine=args.refine,
                    )
                    judged = scored(task, family, opt.table, com, box)
                    entry["optimizer"].append(judged["hits"])
                    entry["optimizer_labels"].append(judged["labels"])
                    entry["top1"]["optimizer"].append(judged["top1"])
                    entry["opt_candidates"].append(opt.candidates)
                    pq.write_table(opt.table, cache / f"top_{task}_{family}_{seed}_opt.parquet")
                print(
                    task,
                    family,
                    seed,
                    entry["brute_force"][-1] if entry["brute_force"] else "",
                    entry["optimizer"][-1] if entry["optimizer"] else "",
                    entry[f"brute_force_at_{also}"][-1] if also and entry["brute_force"] else "",
                    flush=True,
                )
            for method in methods:
                hits = sum(h for h, _ in entry[method])
                total = sum(n for _, n in entry[method])
                entry[f"{method}_fraction"] = hits / total if total else None
            per_family[family] = entry
        summary = {}
        for method in methods:
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
    mass = ", with the materials" if args.materials else ""
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
            f"best {task} grasp per mode (brute force{mass})",
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
