"""Calibrate beat's striking-surface tests (``use_depth``, ``use_relief``) on hammers and axes.

Use points drawn by area (:meth:`affordgrasp.search.use_points.UsePoints.sample`) on crisp
and scan-like (``~scan``) hammers and axes; only the blunt ones (``use_wedge_angle`` >=
beat's τ_blunt: the others fail beat already). Each is labelled by the part the family gives
its face: "strike" (a hammer's ``striking_face``, an axe's ``poll``), "head" (the rest of
the head: its side faces, a claw, a ball peen, an axe's cheeks) and "handle". Prints, per
group, percentiles of the two columns and the fraction of each group that passes candidate
thresholds, so that the thresholds are chosen on the calibration seeds (0-1) and checked on
the held-out ones (2-6).

Run: ``python studies/calibrate_striking.py --seeds 0-1 --uses 3000``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from affordgrasp.metrics.striking import use_depth, use_relief
from affordgrasp.objects import load_object
from affordgrasp.search.use_points import UsePoints
from affordgrasp.tasks.thresholds import TAU_BLUNT_DEFAULT

STRIKE = {"striking_face", "poll"}
HEAD = {"head", "claw", "peen", "cutting_edge"}


def seed_list(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-1")
    parser.add_argument("--uses", type=int, default=3000)
    parser.add_argument("--families", default="hammer,axe")
    parser.add_argument("--depths", default="0.03,0.04,0.045,0.05,0.06")
    parser.add_argument("--reliefs", default="0.0003,0.0005,0.0007,0.001")
    parser.add_argument("--out", default="")
    args = parser.parse_args()
    depths = [float(x) for x in args.depths.split(",")]
    reliefs = [float(x) for x in args.reliefs.split(",")]
    t0 = time.perf_counter()
    values: dict[str, dict[str, list]] = {}
    for family in args.families.split(","):
        for seed in seed_list(args.seeds):
            for variant in ("", "~scan"):
                spec = f"{family}:{seed}{variant}"
                obj = load_object(spec)
                uses = UsePoints.sample(obj, args.uses, seed=0)
                ok = (uses.triangle >= 0) & (uses.use_wedge_angle >= TAU_BLUNT_DEFAULT)
                P, N, T = uses.point[ok], uses.normal[ok], uses.triangle[ok]
                parts = obj.parts_of_faces(T)
                depth = use_depth(obj.mesh_data, P, N)
                relief = use_relief(obj.mesh_data, P, N)
                group = np.where(
                    np.isin(parts, list(STRIKE)),
                    "strike",
                    np.where(np.isin(parts, list(HEAD)), "head", "handle"),
                )
                for g in ("strike", "head", "handle"):
                    key = f"{family} {'scan' if variant else 'crisp'} {g}"
                    v = values.setdefault(key, {"depth": [], "relief": [], "parts": []})
                    v["depth"] += depth[group == g].tolist()
                    v["relief"] += relief[group == g].tolist()
                    v["parts"] += parts[group == g].tolist()
                print(spec, f"{time.perf_counter() - t0:.0f}s", flush=True)
    report = {}
    for key, v in sorted(values.items()):
        d, r = np.asarray(v["depth"]), np.asarray(v["relief"])
        if not len(d):
            continue
        q = [1, 5, 50, 95, 99]
        row = {
            "n": len(d),
            "depth_mm_pct_1_5_50_95_99": np.round(1000 * np.percentile(d, q), 1).tolist(),
            "relief_mm_pct_1_5_50_95_99": np.round(
                1000 * np.percentile(np.minimum(r, 1.0), q), 2
            ).tolist(),
            "pass_depth": {f"{x * 1000:g}mm": round(float(np.mean(d >= x)), 3) for x in depths},
            "pass_relief": {f"{x * 1000:g}mm": round(float(np.mean(r <= x)), 3) for x in reliefs},
            "pass_both": {
                f"{x * 1000:g}/{y * 1000:g}mm": round(float(np.mean((d >= x) & (r <= y))), 3)
                for x in depths
                for y in reliefs
            },
        }
        parts, counts = np.unique(v["parts"], return_counts=True)
        row["parts"] = dict(zip(parts.tolist(), counts.tolist(), strict=True))
        report[key] = row
        print(key, json.dumps({k: row[k] for k in row if k != "pass_both"}))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
