"""Depth images per second per core: D(p0, O) by Embree on built-in objects.

    python benchmarks/bench_depth.py --images 512 --objects hammer knife mug

Reports images per CPU-second (process time, one thread: Embree is called from this thread)
and per wall-second (lower when the machine is shared), and the share of pixels hit, for
the default engine (16-ray packets) and, in the same run, the one-ray-per-call reference
(``embreex``).
"""

from __future__ import annotations

import argparse
import json
import time

from affordgrasp.grasp.pregrasp import sample_inputs
from affordgrasp.objects import load_object
from affordgrasp.vision import DepthRenderer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=512)
    parser.add_argument("--objects", nargs="+", default=["hammer", "knife", "mug", "bottle"])
    parser.add_argument("--engines", nargs="+", default=["packets", "embreex"])
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    p0, _ = sample_inputs(0, 0, args.images)
    rows = {}
    for spec in args.objects:
        obj = load_object(spec)
        for engine in args.engines:
            renderer = DepthRenderer(obj.mesh, engine=engine)
            renderer.render(p0[:16])  # warm (the packet kernel loads or compiles once)
            cpu, wall = time.process_time(), time.perf_counter()
            depth = renderer.render(p0)
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
            r = rows.setdefault(obj.name, {"triangles": len(obj.mesh.faces)})
            r[engine] = {
                "images_per_cpu_s": args.images / cpu,
                "images_per_wall_s": args.images / wall,
                "pixels_hit": float((depth > 0).mean()),
            }
            e = r[engine]
            print(
                f"{obj.name:10s} {engine:8s} {r['triangles']:6d} triangles  "
                f"{e['images_per_cpu_s']:7.0f} images/CPU-s  {e['images_per_wall_s']:7.0f} "
                f"images/wall-s  {e['pixels_hit']:.1%} hit"
            )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
