"""Throughput of dataset generation: grasps/s and grasps/s per core, end to end.

Runs ``affordgrasp.dataset.generate`` on a few built-in objects, first on one core (in
process), then on every core (local worker processes), optionally on a local Ray, into
fresh directories, and reports the rates and the split between simulation and metrics.

    python benchmarks/bench_generate.py --samples 1000 --objects knife hammer mug
    python benchmarks/bench_generate.py --samples 1000 --ray --json out.json

``--process SRC [SRC ...]`` measures instead what a user's command costs, whole process:
``affordgrasp generate OBJECT --samples N --workers 1`` run as a fresh process for each
object and each source tree (e.g. this checkout's ``src`` and a copy of the previous
``src``, measured in turn in the same run), grasps per CPU-second of that process, start-up,
kernel loading, object preparation and Parquet writing included (warm kernel caches: an
untimed first process per tree builds them)::

    nice -n 10 python benchmarks/bench_generate.py --process /tmp/prev/src src --samples 4000

``--repeats 3`` runs every command three times (the trees alternating) and keeps the
smallest CPU time of each: the least disturbed run on a shared machine.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from affordgrasp.dataset.generate import generate
from affordgrasp.objects import load_object
from affordgrasp.pipeline import evaluate_samples
from affordgrasp.runtime.engines import default_workers


def stage_split(objects: list[str], n: int, seed: int) -> dict:
    """Seconds per sample spent in simulation and in metrics, one core, warm."""
    out = {}
    for spec in objects:
        obj = load_object(spec)
        evaluate_samples(obj, 8, seed=seed, start=10**6)  # warm caches and compiled kernels
        timing = evaluate_samples(obj, n, seed=seed).timings
        out[obj.name] = {k: v / n * 1e3 for k, v in timing.items()}
    return out


def cpu_seconds() -> float:
    """CPU time of this process and of its finished children (the local workers)."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def run(objects, samples, seed, workers, engine, root: Path) -> dict:
    out = root / f"{engine}-{workers}"
    cpu0 = cpu_seconds()
    summary = generate(
        objects, samples, out, seed=seed, workers=workers, engine=engine, shard_size=1024
    )
    d = summary.to_dict()
    d["grasps_per_s_per_core"] = summary.grasps_per_s / summary.workers
    if engine == "local":
        # Robust to other load on the machine: grasps per CPU-second, start-up included.
        d["cpu_s"] = cpu_seconds() - cpu0
        d["grasps_per_cpu_s"] = summary.samples_written / d["cpu_s"]
    return d


FAMILIES = [
    "hammer", "knife", "meat_cleaver", "axe", "screwdriver", "spatula", "sword", "dagger",
    "bottle", "wine_glass", "tumbler", "mug", "ice_cream_cone",
]  # fmt: skip


def command_process(src: str, argv: list[str]) -> dict:
    """Run ``affordgrasp ARGV`` from the sources ``src`` in a fresh process; its costs."""
    env = dict(os.environ, PYTHONPATH=str(Path(src).resolve()))
    env.pop("NUMBA_CACHE_DIR", None)
    # An installed package has its bytecode compiled (pip does it); without it every process
    # compiles the package's Python sources again, about 0.6 s of CPU: let the warm-up run
    # write it, as an installed package has it.
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    code = "import sys; from affordgrasp.cli import main; sys.exit(main(sys.argv[1:]))"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, *argv], env=env, capture_output=True)
    wall = time.perf_counter() - w0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{src}: {' '.join(argv)}: {proc.stderr.decode()[-1500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"cpu_s": cpu, "wall_s": wall}


def process_rates(
    sources: list[str], objects: list[str], samples: int, seed: int, repeats: int = 1
) -> dict:
    """Whole-process ``generate --workers 1`` rates per object and source tree.

    With ``repeats`` > 1 every command runs that many times (the trees alternating) and the
    rate of its smallest CPU time is kept: on a shared machine other jobs only ever add to
    a process's CPU time (they compete for the cores' caches and shared units)."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, src in enumerate(sources):  # warm the caches (kernels, prepared objects)
            for spec in objects:
                gen = ["generate", spec, "--samples", "2", "--workers", "1"]
                command_process(src, [*gen, "--out", f"{tmp}/warm-{k}-{spec}"])
        labels = [Path(s).resolve().parent.name[-14:] for s in sources]
        print(f"{'object':<16}" + "".join(f"{label:>16}" for label in labels))
        for spec in objects:
            row = {}
            for attempt in range(repeats):
                for k, src in enumerate(sources):
                    gen = ["generate", spec, "--samples", str(samples), "--workers", "1"]
                    gen += ["--seed", str(seed), "--out", f"{tmp}/{k}-{spec}-{attempt}"]
                    r = command_process(src, gen)
                    r["grasps_per_cpu_s"] = samples / r["cpu_s"]
                    if src not in row or r["cpu_s"] < row[src]["cpu_s"]:
                        row[src] = {**r, "cpu_s_all": row.get(src, {}).get("cpu_s_all", [])}
                    row[src]["cpu_s_all"].append(r["cpu_s"])
            out[spec] = row
            print(
                f"{spec:<16}" + "".join(f"{row[s]['grasps_per_cpu_s']:>16.0f}" for s in sources),
                flush=True,
            )
        for src in sources:  # start-up: a one-sample command, warm caches
            times = []
            for _ in range(3):
                gen = ["simulate", "knife", "--samples", "1"]
                times.append(command_process(src, gen))
            out.setdefault("_startup", {})[src] = {
                "wall_s": sorted(t["wall_s"] for t in times)[1],
                "cpu_s": sorted(t["cpu_s"] for t in times)[1],
            }
            print(f"start-up ({src}): simulate knife --samples 1: {out['_startup'][src]}")
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--objects", nargs="+", default=["knife", "hammer", "mug", "screwdriver"])
    p.add_argument("--samples", type=int, default=500, help="per object")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--ray", action="store_true", help="also run the Ray engine")
    p.add_argument("--json", default=None, help="write the results to this file")
    p.add_argument(
        "--process",
        nargs="+",
        metavar="SRC",
        help="whole-process generate --workers 1 of every family (or --objects) for each of "
        "these source trees",
    )
    p.add_argument(
        "--repeats", type=int, default=1, help="with --process: runs per command, the fastest kept"
    )
    args = p.parse_args()
    if args.process:
        objects = FAMILIES if args.objects == p.get_default("objects") else args.objects
        results = process_rates(args.process, objects, args.samples, args.seed, args.repeats)
        if args.json:
            Path(args.json).write_text(json.dumps(results, indent=2))
        return

    cores = default_workers()
    results = {"cores": cores, "samples_per_object": args.samples, "objects": args.objects}
    started = time.perf_counter()
    results["ms_per_sample_one_core"] = stage_split(args.objects, min(200, args.samples), 1)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        runs = [("local", 1), ("local", cores)] + ([("ray", cores)] if args.ray else [])
        results["runs"] = []
        for engine, workers in runs:
            r = run(args.objects, args.samples, args.seed, workers, engine, root)
            results["runs"].append(r)
            cpu = f", {r['grasps_per_cpu_s']:.1f} per CPU-second" if "grasps_per_cpu_s" in r else ""
            print(
                f"{engine:5s} x{r['workers']}: {r['samples_written']} grasps in "
                f"{r['elapsed_s']:.1f} s = {r['grasps_per_s']:.1f} grasps/s, "
                f"{r['grasps_per_s_per_core']:.1f} per core{cpu}",
                flush=True,
            )
    for name, t in results["ms_per_sample_one_core"].items():
        print(
            f"{name:16s} simulate {t['simulate']:.1f} ms  metrics {t['metrics']:.1f} ms "
            f"per sample (one core)"
        )
    results["elapsed_s"] = time.perf_counter() - started
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
