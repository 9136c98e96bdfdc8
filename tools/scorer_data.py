"""The rows the learned scorer (``plan --model learned``) is fitted on: one file per object.

    python tools/scorer_data.py --out DIR [--seeds 100-139] [--candidates 256]
        [--families hammer,...] [--crisp-only] [--workers 2]

Per object (every family × seed, crisp and ``~scan``): ``plan``'s candidates (its draw and
offset range, seeded by the object), their views rendered as ``plan`` renders them (aimed
from a believed pose 1 cm and 5° off, through the default sensor model) and fused; then
every candidate simulated twice, placed on the fused surface's hull as ``plan`` places it:
on the fused surface (the views decider's label) and on the true object (the simulator's
label). Written: 4096 points of the fused surface in a seeded order, the
candidates' start poses on it, p0, and per candidate the viability, ε and pick score of both
simulations. Deterministic; an object whose file exists is skipped (resumable).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import zlib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from affordgrasp.runtime.writing import atomic_write

sys.path.insert(0, str(Path(__file__).parent))
from task_trial_data import FAMILIES, seeds_of  # noqa: E402


def object_seed(spec: str) -> int:
    """The plan seed of an object: a function of its name alone."""
    return zlib.crc32(spec.encode()) & 0x7FFFFFFF


def cloud_of(fused) -> np.ndarray:
    """4096 of the fused surface's simulation samples, a seeded subset in a seeded order."""
    from affordgrasp.grasp.policy import object_geometry

    points = np.asarray(object_geometry(fused).samples.points, dtype=np.float64)
    return points[np.random.default_rng(0x5C0E).permutation(len(points))[:4096]]


def object_rows(spec: str, candidates: int) -> dict:
    """One object's rows (see the module's docstring)."""
    from affordgrasp.grasp.pregrasp import POSE_ERROR_DEG, POSE_ERROR_M, sample_inputs
    from affordgrasp.learning.plan import FUSED_VIEWS, OFFSET_RANGE, candidate_views
    from affordgrasp.learning.scorer import candidate_starts
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_inputs
    from affordgrasp.tasks import get_task, is_viable
    from affordgrasp.vision.sensor import SensorModel

    seed = object_seed(spec)
    obj = load_object(spec)
    p0, use_dir = sample_inputs(seed, 0, candidates)
    p0[:, 3:5] *= OFFSET_RANGE
    k = min(candidates, FUSED_VIEWS)
    seen = candidate_views(
        obj,
        p0[:k],
        seed=seed,
        pose_error=(POSE_ERROR_M, POSE_ERROR_DEG),
        sensor=SensorModel(seed=seed),
    )
    fused = seen.fuse()
    out = {
        # 4096 of the surface's samples in a seeded order (the scorer reads the first ones)
        "cloud": cloud_of(fused).astype(np.float32),
        "starts": candidate_starts(fused, p0).astype(np.float32),
        "p0": p0.astype(np.float32),
    }
    for name, target in (("fused", fused), ("true", obj)):
        t = evaluate_inputs(target, p0, use_dir, seed=seed, volume=False, frame=fused).table
        out[f"{name}_viable"] = np.asarray(is_viable(t), dtype=bool)
        out[f"{name}_epsilon"] = t.column("epsilon").to_numpy(zero_copy_only=False)
        out[f"{name}_pick"] = get_task("pick").evaluate(t, "default")
    return out


def file_name(spec: str) -> str:
    """An object's file."""
    return f"{spec.replace(':', '_').replace('~', '-')}.npz"


def one(job: tuple[str, int, str]) -> tuple[str, float, int]:
    spec, candidates, out_dir = job
    path = Path(out_dir) / file_name(spec)
    if path.exists():
        return spec, 0.0, -1
    t0 = time.process_time()
    rows = object_rows(spec, candidates)
    from io import BytesIO

    buf = BytesIO()
    np.savez_compressed(buf, spec=np.array(spec), **rows)
    atomic_write(path, buf.getvalue())
    return spec, time.process_time() - t0, int(rows["true_viable"].sum())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    p.add_argument("--seeds", default="100-139")
    p.add_argument("--families", default=",".join(FAMILIES))
    p.add_argument("--candidates", type=int, default=256)
    p.add_argument("--crisp-only", action="store_true")
    p.add_argument("--scan-only", action="store_true")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    kinds = [""] if args.crisp_only else ["~scan"] if args.scan_only else ["", "~scan"]
    specs = [
        f"{f}:{s}{k}" for s in seeds_of(args.seeds) for f in args.families.split(",") for k in kinds
    ]
    jobs = [(s, args.candidates, args.out) for s in specs]
    todo = [j for j in jobs if not (Path(j[2]) / file_name(j[0])).exists()]
    done = len(jobs) - len(todo)
    # fresh workers every 32 objects: each object's caches (its geometry, its renderer) stay
    # with the process that made them (a worker that had made 190 grew past 10 GB)
    for first in range(0, len(todo), 32):
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            for spec, cpu, viable in pool.map(one, todo[first : first + 32]):
                done += 1
                print(f"[{done}/{len(jobs)}] {spec}: {cpu:.1f} s CPU, {viable} viable", flush=True)


if __name__ == "__main__":
    main()
