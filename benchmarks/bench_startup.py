"""Start-up of the command line with warm caches, against the previous release, same run.

    python benchmarks/bench_startup.py [--runs 7] [--object hammer] [--previous 2671c7c ...]
                                       [--samples 1] [--seed S]

What is measured ("start-up"): a fresh process running the README's main job form,
``affordgrasp generate OBJECT --samples 1 --workers 1 --out DIR`` into a new directory, timed
as a whole, from the parent's ``fork`` to the child's exit: wall time and CPU time (user +
system, from the parent's ``RUSAGE_CHILDREN``). "Warm caches": the same command ran before
in an untimed process, so numba's kernel caches and affordgrasp's object cache exist. One
grasp's steady cost (a few ms) is inside the number and is not subtracted; it is below the
noise. ``--samples N --seed S`` time a longer job instead (e.g. one whose grasps reach a
cost that only some grasps pay, such as a ray that misses the surface).

Each version (the current sources, and checkouts of the previous release or of other
commits given with ``--previous``, made by ``bench_release.previous_checkout``) runs
``--runs`` times, interleaved, and the medians are reported with their ratios. Then
``--runs`` more processes of each version run the same command with timers around its
phases (exclusive times; a nested phase is not counted in its parent), and the medians per
phase are printed:

* ``imports``: executing modules (every ``import``, wherever it happens), except those that
  numba's kernel loading does (they belong to ``kernels``);
* ``kernels``: numba's dispatch of a kernel's first call (loading its cache, or compiling);
* ``object``: resolving the object, rebuilding it in the job, its surface samples and hull;
* ``hand``: the hand's flat arrays and reach;
* ``grasps``: simulation, metrics and the Arrow table of the one grasp;
* ``dataset``: preparing the directory, writing the shard, the manifest and the card;
* ``rest``: everything else (interpreter start, argument parsing, output), i.e. the total
  wall time minus the phases above.

Each phase is reported in wall and CPU time (``time.process_time`` of the child; ``rest``
takes the child's whole CPU time from the parent). The phase timers cost a few
milliseconds; totals come from the untimed runs.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_release import REPO, previous_checkout  # noqa: E402

PHASES = ("imports", "kernels", "object", "hand", "grasps", "dataset", "rest")

# Runs the command line in this process with exclusive timers around its phases; prints the
# phase times as JSON on the last line of stderr. Names missing from a version are skipped.
TIMED = textwrap.dedent(
    """
    import importlib._bootstrap as _bootstrap, json, sys, time
    t0 = time.perf_counter()
    times = {}
    stack = []

    marks = []
    cpu = {}

    def clocks():
        return time.perf_counter(), time.process_time()

    def add(name, now, mark):
        times[name] = times.get(name, 0.0) + now[0] - mark[0]
        cpu[name] = cpu.get(name, 0.0) + now[1] - mark[1]

    def enter(name):
        now = clocks()
        if stack:
            add(stack[-1], now, marks[-1])
        stack.append(name)
        marks.append(now)

    def leave():
        now = clocks()
        add(stack.pop(), now, marks.pop())
        if marks:
            marks[-1] = now

    def timed(name, fn):
        def wrapper(*args, **kwargs):
            enter(name)
            try:
                return fn(*args, **kwargs)
            finally:
                leave()
        wrapper.__wrapped__ = fn
        return wrapper

    TARGETS = {
        "numba.core.dispatcher": [("Dispatcher", "_compile_for_args", "kernels")],
        "affordgrasp.dataset.generate": [
            (None, "load_objects", "object"),
            (None, "prepare_directory", "dataset"),
            (None, "write_shard", "dataset"),
        ],
        "affordgrasp.dataset.card": [(None, "write_card", "dataset")],
        "affordgrasp.dataset.jobs": [("ObjectPayload", "build", "object")],
        "affordgrasp.grasp.policy": [
            (None, "object_geometry", "object"),
            (None, "hand_arrays", "hand"),
            (None, "hand_reach", "hand"),
        ],
        "affordgrasp.pipeline": [(None, "evaluate_inputs", "grasps")],
    }

    def patch(module):
        for owner, attr, phase in TARGETS.get(module.__name__, ()):
            target = getattr(module, owner, None) if owner else module
            fn = getattr(target, attr, None) if target is not None else None
            if fn is not None and not hasattr(fn, "__wrapped__"):
                setattr(target, attr, timed(phase, fn))

    original = _bootstrap._find_and_load

    def find_and_load(name, import_):
        if name in sys.modules:
            return original(name, import_)
        inside_kernels = bool(stack) and stack[-1] == "kernels"
        if not inside_kernels:
            enter("imports")
        try:
            module = original(name, import_)
        finally:
            if not inside_kernels:
                leave()
        patch(module)
        return module

    _bootstrap._find_and_load = find_and_load
    from affordgrasp.cli import main
    try:
        sys.argv[0] = "affordgrasp"
        code = main()
    finally:
        _bootstrap._find_and_load = original
        times["in_process"] = time.perf_counter() - t0
        times["cpu"] = cpu
        print(json.dumps(times), file=sys.stderr)
    raise SystemExit(code)
    """
)


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_once(
    src: Path, spec: str, out: Path, timed: bool = False, extra: tuple[str, ...] = ()
) -> dict:
    """One fresh process of ``affordgrasp generate OBJECT --samples 1 --workers 1 --out OUT``.

    Parameters
    ----------
    src : pathlib.Path
        The sources to run (put on PYTHONPATH).
    spec : str
        The object.
    out : pathlib.Path
        A directory that does not exist yet.
    timed : bool
        Run with the phase timers and return the phases too.
    extra : tuple of str
        More options for ``generate`` (a later ``--samples`` wins).

    Returns
    -------
    dict
        ``wall`` and ``cpu`` (s), and with ``timed`` one entry per phase (s).
    """
    env = dict(os.environ, PYTHONPATH=str(src))
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: bytecode compiled once, kept
    args = ["generate", spec, "--samples", "1", "--workers", "1", "--out", str(out), *extra]
    entry = ["-c", TIMED] if timed else ["-m", "affordgrasp.cli"]
    cmd = [sys.executable, *entry, *args]
    cpu0 = _children_cpu()
    w0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - w0
    cpu = _children_cpu() - cpu0
    if proc.returncode != 0:
        raise RuntimeError(f"{src}: {proc.stderr.strip()[-2000:]}")
    result = {"wall": wall, "cpu": cpu}
    if timed:
        phases = json.loads(proc.stderr.strip().splitlines()[-1])
        phase_cpu = phases.pop("cpu")
        result["in_process"] = phases.pop("in_process")
        for p in PHASES[:-1]:
            result[p] = phases.get(p, 0.0)
            result[f"{p}_cpu"] = phase_cpu.get(p, 0.0)
        result["rest"] = wall - sum(result[p] for p in PHASES[:-1])
        result["rest_cpu"] = cpu - sum(result[f"{p}_cpu"] for p in PHASES[:-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="processes per version (median)")
    parser.add_argument("--object", default="hammer")
    parser.add_argument("--samples", type=int, default=1, help="grasps of the timed job")
    parser.add_argument("--seed", type=int, help="the job's seed (default: generate's)")
    parser.add_argument(
        "--previous",
        nargs="+",
        default=["2671c7c"],
        help="commits to measure beside the current sources (default: the previous release)",
    )
    parser.add_argument("--no-previous", action="store_true", help="measure the current only")
    parser.add_argument(
        "--current-src", default=str(REPO / "src"), help="sources to measure as the current code"
    )
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    args = parser.parse_args()

    extra = ("--samples", str(args.samples))
    if args.seed is not None:
        extra += ("--seed", str(args.seed))
    versions = {} if args.no_previous else {c: previous_checkout(c) / "src" for c in args.previous}
    versions["current"] = Path(args.current_src)
    tmp = Path(tempfile.mkdtemp(prefix="affordgrasp-startup-"))
    try:
        load = os.getloadavg()
        print(f"load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; {os.cpu_count()} cores")
        for name, src in versions.items():  # warm the caches: kernels, objects
            for i in range(2):
                run_once(src, args.object, tmp / f"warm-{name}-{i}", extra=extra)
        runs: dict[str, list[dict]] = {name: [] for name in versions}
        timed: dict[str, list[dict]] = {name: [] for name in versions}
        for i in range(args.runs):
            for name, src in versions.items():
                runs[name].append(run_once(src, args.object, tmp / f"{name}-{i}", extra=extra))
        for i in range(args.runs):
            for name, src in versions.items():
                timed[name].append(
                    run_once(src, args.object, tmp / f"t-{name}-{i}", timed=True, extra=extra)
                )
        load = os.getloadavg()
        summary: dict = {"object": args.object, "runs": args.runs, "load_after": load[:3]}
        print(
            f"start-up: affordgrasp generate {args.object} --samples {args.samples} --workers 1"
            f"{'' if args.seed is None else f' --seed {args.seed}'}, warm caches, "
            f"median of {args.runs} fresh processes"
        )
        print(f"{'':<10}{'wall s':>9}{'cpu s':>9}{'min wall':>10}")
        for name in versions:
            wall = [r["wall"] for r in runs[name]]
            cpu = [r["cpu"] for r in runs[name]]
            summary[name] = {"wall": float(np.median(wall)), "cpu": float(np.median(cpu))}
            summary[name]["min_wall"] = float(min(wall))
            s = summary[name]
            print(f"{name:<10}{s['wall']:>9.2f}{s['cpu']:>9.2f}{s['min_wall']:>10.2f}")
        for name in versions:
            if name != "current":
                ratio = {k: summary["current"][k] / summary[name][k] for k in ("wall", "cpu")}
                summary[f"current/{name}"] = ratio
                print(f"current / {name}: wall {ratio['wall']:.2f}, cpu {ratio['cpu']:.2f}")
        print("phases, median s (exclusive; timed runs): " + ", ".join(
            f"{n} wall, {n} cpu" for n in versions))  # fmt: skip
        for phase in PHASES:
            line = f"  {phase:<10}"
            for n in versions:
                for key in (phase, f"{phase}_cpu"):
                    v = float(np.median([r[key] for r in timed[n]]))
                    summary[n].setdefault("phases", {})[key] = v
                    line += f"{v:>10.3f}"
            print(line)
        print(f"load average after: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
        if args.json:
            Path(args.json).write_text(json.dumps(summary, indent=2))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
