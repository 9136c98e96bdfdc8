"""Throughput of this checkout against the previous release, measured in the same run.

    python benchmarks/bench_release.py [--samples 1000] [--previous 2671c7c] [--objects ...]

For each object, the current sources and a checkout of the previous release (a temporary
``git worktree`` in the temporary directory, outside the repository, kept for the next run
unless ``--remove-previous``) run the same measurement in
fresh processes, one after the other, under the same conditions: load the kernels (warm
caches: a first untimed process per version builds them), prepare the object, then time
``evaluate_samples`` (simulation + every metric) and the Parquet write of the table, end to
end. The rate is grasps per second of CPU time of that process (one core: the pipeline is
single-threaded), which other work on a shared machine disturbs much less than wall time;
wall-clock rates are printed too. That first run on the object also pays what the object
needs once per process (e.g. importing trimesh for the closest face of a contact whose ray
misses); a second run of as many grasps (seed 1) in the same process gives the steady
rate, printed beside it ("again"). Objects: the 13 built-in families and an 80 mm sphere
(an enveloping case; the mug is the other one).

Start-up is the wall time of a process that imports the pipeline and loads every kernel it
calls (warm caches), measured the same way for both versions.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FAMILIES = [
    "hammer", "knife", "meat_cleaver", "axe", "screwdriver", "spatula", "sword", "dagger",
    "bottle", "wine_glass", "tumbler", "mug", "ice_cream_cone",
]  # fmt: skip

WORKER = textwrap.dedent(
    """
    import json, os, sys, tempfile, time
    t_start = time.perf_counter()
    try:
        from affordgrasp.pipeline import evaluate_samples
    except ImportError:  # releases before the pipeline module
        from affordgrasp.evaluate import evaluate_samples
    from affordgrasp.grasp.policy import object_geometry
    try:
        from affordgrasp.objects import load_object
    except ImportError:  # releases before the rename
        from affordgrasp.objects import resolve_object as load_object
    import pyarrow.parquet as pq

    spec, n = sys.argv[1], int(sys.argv[2])
    evaluate_samples("tumbler", 4, seed=123)  # load (or compile) every kernel
    startup = time.perf_counter() - t_start
    if n == 0:
        print(json.dumps({"startup": startup}))
        raise SystemExit
    obj = load_object(spec)
    object_geometry(obj)
    out = os.path.join(tempfile.mkdtemp(), "rows.parquet")
    runs = []
    for seed in (0, 1):  # the first run pays what the object needs once per process
        c0, w0 = time.process_time(), time.perf_counter()
        result = evaluate_samples(obj, n, seed=seed)
        table = result[0] if isinstance(result, tuple) else result.table
        pq.write_table(table, out)
        runs.append((time.process_time() - c0, time.perf_counter() - w0))
        if seed == 0:
            eps = table.column("epsilon").to_numpy()
    print(json.dumps({"startup": startup, "cpu": runs[0][0], "wall": runs[0][1], "n": n,
                      "cpu_again": runs[1][0], "closure": float((eps > 0).mean())}))
    """
)


def previous_checkout(commit: str) -> Path:
    """A checkout of ``commit`` (a detached ``git worktree`` in the temporary directory).

    Kept between runs, its compiled kernels with it (see :func:`remove_previous_checkout`).

    Parameters
    ----------
    commit : str
        The previous release's commit.

    Returns
    -------
    pathlib.Path
        The checkout's root; its sources are under ``src``.
    """
    previous = Path(tempfile.gettempdir()) / f"affordgrasp-previous-{commit}"
    if not (previous / "src").is_dir():
        subprocess.run(
            ["git", "-C", str(REPO), "worktree", "add", "--detach", str(previous), commit],
            check=True,
            capture_output=True,
        )
    return previous


def remove_previous_checkout(previous: Path) -> None:
    """Remove a checkout made by :func:`previous_checkout`."""
    subprocess.run(
        ["git", "-C", str(REPO), "worktree", "remove", "--force", str(previous)],
        check=False,
        capture_output=True,
    )


def run_worker(src: Path, spec: str, n: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: bytecode compiled once, kept
    proc = subprocess.run(
        [sys.executable, "-c", WORKER, spec, str(n)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{src} {spec}: {proc.stderr.strip().splitlines()[-1]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--previous", default="2671c7c", help="commit of the previous release")
    parser.add_argument("--objects", nargs="+", default=[*FAMILIES, "sphere"])
    parser.add_argument(
        "--current-src", default=str(REPO / "src"), help="sources to measure as the current code"
    )
    parser.add_argument(
        "--remove-previous", action="store_true", help="remove the previous release's worktree"
    )
    args = parser.parse_args()

    tmp = Path(tempfile.mkdtemp(prefix="affordgrasp-bench-"))
    previous = previous_checkout(args.previous)
    import trimesh

    sphere = tmp / "sphere.stl"
    trimesh.creation.icosphere(subdivisions=4, radius=0.04).export(sphere)
    versions = {"previous": previous / "src", "current": Path(args.current_src)}
    try:
        for name, src in versions.items():
            print(f"{name}: warming the kernel caches ({src})", flush=True)
            run_worker(src, "tumbler", 0)
        startup = {
            name: float(np.median([run_worker(src, "", 0)["startup"] for _ in range(3)]))
            for name, src in versions.items()
        }
        print(
            f"start-up (import + kernels, warm caches, wall): previous "
            f"{startup['previous']:.2f} s, current {startup['current']:.2f} s"
        )
        header = (
            f"{'object':<16}{'previous':>10}{'current':>10}{'ratio':>8}"
            f"{'prev wall':>11}{'cur wall':>10}{'closure':>9}"
            f"{'prev again':>12}{'cur again':>11}{'ratio':>8}"
        )
        print(f"grasps/s per core (CPU time; simulation + every metric + Parquet), "
              f"{args.samples} samples")  # fmt: skip
        print(header)
        ratios = []
        ratios_again = []
        current_rates = []
        current_again = []
        for spec in args.objects:
            target = str(sphere) if spec == "sphere" else spec
            res = {name: run_worker(src, target, args.samples) for name, src in versions.items()}
            rate = {k: v["n"] / v["cpu"] for k, v in res.items()}
            wall = {k: v["n"] / v["wall"] for k, v in res.items()}
            again = {k: v["n"] / v["cpu_again"] for k, v in res.items()}
            ratio = rate["current"] / rate["previous"]
            ratio_again = again["current"] / again["previous"]
            ratios.append(ratio)
            ratios_again.append(ratio_again)
            current_rates.append(rate["current"])
            current_again.append(again["current"])
            print(
                f"{spec:<16}{rate['previous']:>10.0f}{rate['current']:>10.0f}{ratio:>8.2f}"
                f"{wall['previous']:>11.0f}{wall['current']:>10.0f}"
                f"{res['current']['closure']:>9.0%}"
                f"{again['previous']:>12.0f}{again['current']:>11.0f}{ratio_again:>8.2f}",
                flush=True,
            )
        for label, rs, cur in (
            ("first run", ratios, current_rates),
            ("again", ratios_again, current_again),
        ):
            print(
                f"{label}: geometric mean ratio {np.exp(np.mean(np.log(rs))):.2f}; current: min "
                f"{min(cur):.0f}, median {np.median(cur):.0f} grasps/s per core"
            )
    finally:
        if args.remove_previous:
            remove_previous_checkout(previous)


if __name__ == "__main__":
    main()
