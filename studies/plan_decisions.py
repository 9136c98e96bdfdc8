"""How often does ``plan`` choose a grasp that works, on objects it never tuned on?

    python studies/plan_decisions.py --variants 5,6 --seeds 0,1,2 --candidates 64 --physics
    python studies/plan_decisions.py --variants 7 --seeds 0,1,2 --model classifier

Runs ``ag.plan`` on every family's variants (task pick, ``plan``'s own candidates), one
decision per (object, seed), and prints, per object then averaged over objects: the share
of decisions whose chosen grasp is truly viable, the oracle's and a random choice's, the
median true percentile of the choice, the top-5 viable share, with ``--physics`` the share
whose MuJoCo replay holds, and the CPU seconds of a decision. ``--sensor`` fuses (or
shows the models) the images of the default sensor model, seeded by the decision's seed.
``--scan`` decides on the scan-like variants (``knife:5~scan``: 1 mm triangles, rounded
creases, noise, capped holes; docs/validation.md) of the same instances. ``--open-base MM``
decides on mesh files of the objects with the faces within MM millimetres of their lowest
point removed (a scan whose base was never seen), which the loader caps.
docs/learning.md ("Deciding on the fused views") reports its numbers: variant 7 was used
to choose the fusion's settings, variants 5-6 only to measure them.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np


def open_base_file(spec: str, height_m: float, folder: str) -> str:
    """A PLY file of an object without the faces whose centre lies within ``height_m`` of
    its lowest point (written once per spec and height)."""
    import trimesh

    from affordgrasp.objects import load_object

    path = os.path.join(folder, f"{spec.replace(':', '_')}_open{height_m * 1000:g}mm.ply")
    if not os.path.exists(path):
        obj = load_object(spec)
        mesh = trimesh.Trimesh(obj.vertices, obj.faces, process=False)
        keep = mesh.triangles_center[:, 2] > mesh.bounds[0, 2] + height_m
        cut = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
        cut.remove_unreferenced_vertices()
        cut.export(path)
    return path


def main() -> None:
    import affordgrasp as ag
    from affordgrasp.objects import list_families

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", default="5,6", help="family variants (comma-separated)")
    ap.add_argument("--seeds", default="0,1,2", help="plan seeds (comma-separated)")
    ap.add_argument("--candidates", type=int, default=64)
    ap.add_argument("--model", default="views", help="plan's --model (default views)")
    ap.add_argument("--physics", action="store_true", help="replay each choice in MuJoCo")
    ap.add_argument("--sensor", action="store_true", help="the default sensor model's images")
    ap.add_argument(
        "--scan", action="store_true", help="the scan-like variants (knife:5~scan) instead"
    )
    ap.add_argument(
        "--open-base",
        type=float,
        metavar="MM",
        help="decide on mesh files cut open at their base (faces within MM of the lowest z)",
    )
    ap.add_argument("--families", help="only these families (comma-separated; default all)")
    ap.add_argument("--robust-check", type=int, help="plan's robust_check (default: plan's own)")
    ap.add_argument("--refine", type=int, help="plan's refine (default: plan's own)")
    ap.add_argument("--json", help="write every decision to this file")
    args = ap.parse_args()
    variants = [int(v) for v in args.variants.split(",")]
    seeds = [int(s) for s in args.seeds.split(",")]
    rows = []
    families = args.families.split(",") if args.families else list_families()
    folder = tempfile.mkdtemp(prefix="open-base-")
    for family in families:
        for variant in variants:
            for seed in seeds:
                sensor = None
                if args.sensor:
                    from affordgrasp.vision.sensor import SensorModel

                    sensor = SensorModel(seed=seed)
                started = time.process_time()
                spec = f"{family}:{variant}" + ("~scan" if args.scan else "")
                if args.open_base is not None:
                    spec = open_base_file(spec, args.open_base / 1000.0, folder)
                p = ag.plan(
                    spec,
                    "pick",
                    candidates=args.candidates,
                    seed=seed,
                    models=args.model,
                    physics=args.physics,
                    sensor=sensor,
                    **({} if args.robust_check is None else {"robust_check": args.robust_check}),
                    **({} if args.refine is None else {"refine": args.refine}),
                )
                drawn = len(p.p0) if p.drawn is None else p.drawn
                seconds = time.process_time() - started - p.timings.get("physics", 0.0)
                rows.append(
                    {
                        "object": p.object,
                        "seed": seed,
                        "viable": bool(p.viable[p.chosen]),
                        # the refined candidates are drawn near the best ones: the oracle
                        # counts them, a random choice is among the drawn ones
                        "oracle": bool(p.viable.any()),
                        "oracle_drawn": bool(p.viable[:drawn].any()),
                        "random": float(p.viable[:drawn].mean()),
                        "percentile": p.percentile,
                        "top5": p.measures["model"]["topk_precision"],
                        "hold": None if p.physics is None else bool(p.physics.get("hold_ok")),
                        "cpu_s": seconds,
                        "decide_s": sum(
                            p.timings.get(k, 0.0) for k in ("render", "fuse", "predict")
                        ),
                        "predict_s": p.timings.get("predict", 0.0),
                    }
                )
                print(json.dumps(rows[-1]), flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    objects = sorted({r["object"] for r in rows})

    def per_object(key: str) -> float:
        return float(
            np.mean([np.mean([float(r[key]) for r in rows if r["object"] == o]) for o in objects])
        )

    print(f"{len(rows)} decisions on {len(objects)} objects, {args.candidates} candidates")
    for key in ("viable", "oracle", "oracle_drawn", "random", "top5"):
        print(f"  {key:8s} {per_object(key):.3f}")
    print(f"  median percentile {np.median([r['percentile'] for r in rows]):.1f}")
    if args.physics:
        print(f"  holds    {per_object('hold'):.3f}")
    print(f"  CPU s per decision: median {np.median([r['cpu_s'] for r in rows]):.2f}")
    print(
        f"  wall s of the decision (render, fuse, predict): median "
        f"{np.median([r['decide_s'] for r in rows]):.2f}, of which predict "
        f"{np.median([r['predict_s'] for r in rows]):.3f}"
    )


if __name__ == "__main__":
    main()
