"""Depth images per second per core: D(p0, O) on built-in objects, every engine in one run.

    python benchmarks/bench_depth.py --images 512 --objects hammer knife mug

Reports images per CPU-second (process time of one thread: the kernels run in the calling
thread, and numpy's BLAS is held to one thread so that its idle spinning is not counted)
and per wall-second (lower when the machine is shared), and the share of pixels hit, for
every engine in the same run: the default z-buffer rasteriser (``raster``), Embree 16-ray
packets (``packets``) and the one-ray-per-call reference (``embreex``). Each image is
checked against the first engine's (pixels whose hit/miss differ, depths beyond 1e-5
relative).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from affordgrasp.grasp.pregrasp import sample_inputs  # noqa: E402
from affordgrasp.objects import load_object  # noqa: E402
from affordgrasp.vision import DepthRenderer  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=512)
    parser.add_argument("--objects", nargs="+", default=["hammer", "knife", "mug", "bottle"])
    parser.add_argument("--engines", nargs="+", default=["raster", "packets", "embreex"])
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    p0, _ = sample_inputs(0, 0, args.images)
    rows = {}
    for spec in args.objects:
        obj = load_object(spec)
        first = None
        for engine in args.engines:
            renderer = DepthRenderer(obj.mesh, engine=engine)
            renderer.render(p0[:16])  # warm (the kernels load or compile once)
            cpu, wall = time.process_time(), time.perf_counter()
            depth = renderer.render(p0)
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
            r = rows.setdefault(obj.name, {"triangles": len(obj.mesh.faces)})
            r[engine] = {
                "images_per_cpu_s": args.images / cpu,
                "images_per_wall_s": args.images / wall,
                "pixels_hit": float((depth > 0).mean()),
            }
            if first is None:
                first = depth
            else:
                both = (first > 0) & (depth > 0)
                rel = np.abs(first[both] - depth[both]) / depth[both]
                r[engine]["hit_differs"] = int(((first > 0) != (depth > 0)).sum())
                r[engine]["beyond_1e-5"] = int((rel > 1e-5).sum())
            e = r[engine]
            print(
                f"{obj.name:10s} {engine:8s} {r['triangles']:6d} triangles  "
                f"{e['images_per_cpu_s']:7.0f} images/CPU-s  {e['images_per_wall_s']:7.0f} "
                f"images/wall-s  {e['pixels_hit']:.1%} hit"
                + (
                    f"  vs {args.engines[0]}: {e['hit_differs']} hit/miss, "
                    f"{e['beyond_1e-5']} beyond 1e-5"
                    if "hit_differs" in e
                    else ""
                ),
                flush=True,
            )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
