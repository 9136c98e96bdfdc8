"""Preparing a large scan: reading, simplifying to 0.1 mm, repairing, surface samples.

Generates the mesh (not stored): a torus (R 50 mm, r 15 mm) of 2 M triangles, or an
icosphere (r 50 mm) of 1.3 M with ``--shape sphere``. Prints wall and CPU seconds per stage
(on a shared machine the CPU seconds are the steadier number) and the load warning.

    python benchmarks/bench_large_mesh.py [--shape torus|sphere]
"""

from __future__ import annotations

import argparse
import logging
import os
import tempfile
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shape", choices=("torus", "sphere"), default="torus")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    import trimesh

    if args.shape == "torus":
        mesh = trimesh.creation.torus(0.05, 0.015, major_sections=1000, minor_sections=1000)
    else:
        mesh = trimesh.creation.icosphere(subdivisions=8, radius=0.05)
    with tempfile.TemporaryDirectory() as folder:
        os.environ["AFFORDGRASP_CACHE_DIR"] = os.path.join(folder, "cache")  # a cold load
        path = os.path.join(folder, f"{args.shape}.ply")
        mesh.export(path)
        from affordgrasp.objects import load_object
        from affordgrasp.objects.prepared import derived_geometry

        stages = {}
        wall, cpu = time.perf_counter(), time.process_time()
        obj = load_object(path)
        stages["load (read, simplify, repair, mass)"] = (
            time.perf_counter() - wall,
            time.process_time() - cpu,
        )
        wall, cpu = time.perf_counter(), time.process_time()
        samples = derived_geometry(obj).samples
        stages["surface samples"] = (time.perf_counter() - wall, time.process_time() - cpu)
    print(f"{len(mesh.faces)} triangles -> {len(obj.faces)}; {len(samples.points)} samples")
    for name, (w, c) in stages.items():
        print(f"{name}: {w:.1f} s wall, {c:.1f} s CPU")
    total_wall = sum(w for w, _ in stages.values())
    total_cpu = sum(c for _, c in stages.values())
    print(f"total: {total_wall:.1f} s wall, {total_cpu:.1f} s CPU")


if __name__ == "__main__":
    main()
