"""A dataset of 10^7 grasps on one machine: generation, a crash and its resume, and reading it.

One command, ``affordgrasp generate`` over the 13 built-in families × ``--variants``
variants each (``family:0`` ... ``family:V-1``), ``--rows`` grasps in all, ``--workers``
local processes, into ``--out``. The benchmark

1. runs it as a fresh process and, once about ``--kill-at`` of the shards are written,
   kills the whole process group with SIGKILL (a power cut, not a Ctrl-C);
2. runs the same command again: it resumes from the shards on disk;
3. checks the result: every (object, sample) exactly once, every shard against its recorded
   checksum (``_checksums.jsonl``), and the
   rows of the object that was being written at the kill equal to a fresh, uninterrupted
   generation of that object alone (same seed; samples depend only on (object, seed, i));
4. times ``affordgrasp best DIR --task pick --top 10``, ``affordgrasp plots DIR`` and the
   DuckDB query of docs/dataset.md over the whole dataset, each as a fresh process, with its
   peak memory;
5. with ``--ray-objects N``: generates the first N objects again on the Ray engine (two
   workers) and checks that their rows equal the local run's.

It prints (and with ``--json`` writes) wall and CPU seconds, the peak resident memory of
any one process (``ru_maxrss`` of the reaped processes), bytes per row on disk and the card's
statistics. Its own command, not a test: the default size takes about an hour on 2 cores.

    python benchmarks/bench_scale.py --out /data/big --rows 10000000 --variants 8 --workers 2
    python benchmarks/bench_scale.py --out /tmp/small --rows 200000 --variants 2   # a rehearsal
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

FAMILIES = (
    "hammer knife meat_cleaver axe screwdriver spatula sword dagger bottle wine_glass tumbler "
    "mug ice_cream_cone"
).split()


def children_usage() -> tuple[float, int]:
    """CPU seconds and the largest peak RSS (bytes) of every reaped descendant so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime, r.ru_maxrss * 1024


def timed(cmd: list[str], **kwargs) -> dict:
    """Run a command as a fresh process (its own process group); wall, CPU and output."""
    cpu0, _ = children_usage()
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, **kwargs)
    wall = time.perf_counter() - t0
    cpu1, peak = children_usage()
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return {"wall_s": wall, "cpu_s": cpu1 - cpu0, "peak_rss_so_far": peak, "stdout": done.stdout}


def peak_of(cmd: list[str]) -> dict:
    """Wall seconds and the peak RSS of one command, measured by GNU time when present."""
    gnu = shutil.which("time") or "/usr/bin/time"
    if Path(gnu).exists():
        t0 = time.perf_counter()
        done = subprocess.run([gnu, "-v", *cmd], capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")
        rss = [ln for ln in done.stderr.splitlines() if "Maximum resident set size" in ln]
        peak = int(rss[0].split(":")[1]) * 1024 if rss else None
        return {"wall_s": wall, "peak_rss_bytes": peak, "stdout": done.stdout}
    out = timed(cmd)
    return {"wall_s": out["wall_s"], "peak_rss_bytes": None, "stdout": out["stdout"]}


def group_cpu(pgid: int) -> float:
    """CPU seconds of the live processes of a process group and of the children they reaped
    (from /proc: a killed group's time cannot be read after the kill)."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # it ended meanwhile
        if int(fields[2]) == pgid:  # fields after the name: state, ppid, pgrp, ...
            total += sum(int(v) for v in fields[11:15])  # utime stime cutime cstime
    return total / tick


def shard_count(directory: Path) -> int:
    return len(list(directory.glob("*.parquet")))


def first_run(report, args, cmd, objects, samples, expected, record) -> None:
    """Step 1: the generation, killed with SIGKILL at about ``--kill-at`` of its shards;
    its wall and CPU seconds and the object it interrupted go to ``report["first_run"]``
    and to ``record``."""
    t0 = time.perf_counter()
    cpu0, _ = children_usage()
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True
    )
    killed = None
    group = 0.0
    while proc.poll() is None:
        time.sleep(2)
        group = max(group, group_cpu(proc.pid))
        if args.kill_at and args.out.exists() and shard_count(args.out) >= args.kill_at * expected:
            group = max(group, group_cpu(proc.pid))
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            killed = {"after_s": time.perf_counter() - t0, "shards": shard_count(args.out)}
            break
    if killed is None and proc.returncode != 0:
        raise SystemExit(proc.stderr.read().decode()[-3000:])
    first_wall = time.perf_counter() - t0
    cpu1, _ = children_usage()
    # killed: the group's time read just before the kill; else what the reaped ones used
    first_cpu = group if killed is not None else cpu1 - cpu0
    report["first_run"] = {"wall_s": first_wall, "cpu_s": first_cpu, "killed": killed}
    if killed is not None:
        import duckdb

        # the objects the kill interrupted: fewer rows on disk than asked for
        counts = dict(
            duckdb.sql(
                f"SELECT object, count(*) FROM '{args.out}/*.parquet' GROUP BY object"
            ).fetchall()
        )
        partial = [o for o in objects if 0 < counts.get(o, 0) < samples]
        # none partial (the kill fell between objects): the first one not written yet
        unwritten = [o for o in objects if o not in counts]
        report["first_run"]["interrupted"] = (partial or unwritten or objects[-1:])[0]
        report["first_run"]["rows_on_disk"] = sum(counts.values())
    record.write_text(json.dumps(report["first_run"]))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True, type=Path)
    p.add_argument("--rows", type=int, default=10_000_000)
    p.add_argument("--variants", type=int, default=8)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--kill-at", type=float, default=0.5, help="share of shards; 0: no kill")
    p.add_argument("--ray-objects", type=int, default=0)
    p.add_argument("--json", default=None)
    args = p.parse_args()
    # the benchmark's own record of its first run: a rerun after the benchmark itself stopped
    # (not the generation it kills) goes on from the resume
    record = args.out.with_name(args.out.name + "-first-run.json")
    if args.out.exists() and not record.exists():
        raise SystemExit(f"{args.out} exists: give a new directory (the run measures a start)")
    objects = [f"{f}:{v}" for f in FAMILIES for v in range(args.variants)]
    samples = -(-args.rows // len(objects))  # at least --rows in all
    total = samples * len(objects)
    # the console script of this interpreter's environment
    script = Path(sys.executable).with_name("affordgrasp")
    ag = [str(script) if script.exists() else "affordgrasp"]
    cmd = [*ag, "generate", *objects, "--samples", str(samples)]
    cmd += ["--workers", str(args.workers), "--out", str(args.out)]
    report: dict = {"objects": len(objects), "samples": samples, "rows": total, "cmd": cmd}
    print(f"{len(objects)} objects x {samples} samples = {total} rows", flush=True)

    # 1. the run, killed at about --kill-at of its shards
    from affordgrasp.dataset.shards import DEFAULT_SHARD_SIZE as shard_size

    expected = sum(-(-samples // shard_size) for _ in objects)
    if record.exists():
        report["first_run"] = json.loads(record.read_text())
    else:
        first_run(report, args, cmd, objects, samples, expected, record)
    killed = report["first_run"]["killed"]
    first_wall = report["first_run"]["wall_s"]
    print(f"first run: {report['first_run']}", flush=True)

    # 2. the resume (the same command)
    if killed is not None:
        resumed = timed(cmd)
        resumed.pop("stdout")
        report["resume"] = resumed
        print(f"resume: {resumed}", flush=True)
    wall = first_wall + (report.get("resume", {}).get("wall_s", 0.0))
    cpu = report["first_run"]["cpu_s"] + report.get("resume", {}).get("cpu_s", 0.0)
    _, peak = children_usage()
    report["generate"] = {
        "wall_s": wall,
        "cpu_s": cpu,
        "grasps_per_cpu_s": total / cpu,
        "grasps_per_wall_s": total / wall,
        "peak_rss_bytes_any_process": peak,
    }
    size = sum(f.stat().st_size for f in args.out.glob("*.parquet"))
    report["disk"] = {"bytes": size, "bytes_per_row": size / total}
    print(f"generate: {report['generate']}; disk {report['disk']}", flush=True)

    # 3. exactly once, checksums, and the interrupted object against a fresh run of it alone
    import duckdb

    glob = str(args.out / "*.parquet")
    dup = duckdb.sql(
        f"SELECT count(*) AS n, count(DISTINCT (object, sample)) AS distinct_rows FROM '{glob}'"
    ).fetchall()[0]
    from affordgrasp.dataset.checksums import read_checksums, shard_damage

    records = read_checksums(args.out)
    shards = sorted(args.out.glob("*.parquet"))
    damaged = [f.name for f in shards if shard_damage(f, records.get(f.name)) is not None]
    report["rows_check"] = {
        "rows": dup[0],
        "distinct": dup[1],
        "expected": total,
        "shards": len(shards),
        "shards_damaged": damaged,
    }
    print(f"rows: {report['rows_check']}", flush=True)
    problems = [] if dup[0] == dup[1] == total else ["rows missing or repeated"]
    problems += ["damaged shards"] if damaged else []
    card = json.loads((args.out / "_card.json").read_text())
    report["card"] = {k: card[k] for k in list(card)[:12] if not isinstance(card[k], dict | list)}
    if killed is not None:
        name = report["first_run"]["interrupted"]
        ref = args.out.with_name(args.out.name + "-reference")
        shutil.rmtree(ref, ignore_errors=True)
        timed(
            [*ag, "generate", name, "--samples", str(samples), "--workers", "1", "--out", str(ref)]
        )
        mine = f"(SELECT * FROM '{glob}' WHERE object = '{name}')"
        theirs = f"(SELECT * FROM '{ref}/*.parquet')"
        differing = duckdb.sql(
            f"SELECT count(*) FROM (({mine} EXCEPT ALL {theirs}) UNION ALL "
            f"({theirs} EXCEPT ALL {mine}))"
        ).fetchall()[0][0]
        report["resume_exact"] = {"object": name, "rows_differing": differing}
        print(f"resume exact: {report['resume_exact']}", flush=True)
        problems += ["the resumed rows differ from a fresh run's"] if differing else []

    # 4. reading it
    best = peak_of([*ag, "best", str(args.out), "--task", "pick", "--top", "10"])
    report["best"] = {k: best[k] for k in ("wall_s", "peak_rss_bytes")}
    print(f"best: {report['best']}", flush=True)
    plots_dir = args.out.with_name(args.out.name + "-plots")
    shutil.rmtree(plots_dir, ignore_errors=True)
    plots = peak_of([*ag, "plots", str(args.out), "-o", str(plots_dir)])
    report["plots"] = {k: plots[k] for k in ("wall_s", "peak_rss_bytes")}
    print(f"plots: {report['plots']}", flush=True)
    query = (
        'import duckdb; duckdb.sql("SELECT object, status, count(*) FROM '
        f"'{glob}' GROUP BY ALL\").fetchall()"
    )
    q = peak_of([sys.executable, "-c", query])
    report["duckdb"] = {k: q[k] for k in ("wall_s", "peak_rss_bytes")}
    print(f"duckdb: {report['duckdb']}", flush=True)

    # 5. the Ray engine on the first objects: rows identical to the local run's
    if args.ray_objects:
        part = objects[: args.ray_objects]
        ray_dir = args.out.with_name(args.out.name + "-ray")
        shutil.rmtree(ray_dir, ignore_errors=True)
        r = timed(
            [*ag, "generate", *part, "--samples", str(samples), "--workers", "2"]
            + ["--engine", "ray", "--out", str(ray_dir)]
        )
        names = ", ".join(f"'{o}'" for o in part)
        diff = duckdb.sql(
            f"SELECT count(*) FROM ((SELECT * FROM '{ray_dir}/*.parquet' EXCEPT ALL SELECT * "
            f"FROM '{glob}' WHERE object IN ({names})) UNION ALL (SELECT * FROM '{glob}' "
            f"WHERE object IN ({names}) EXCEPT ALL SELECT * FROM '{ray_dir}/*.parquet'))"
        ).fetchall()[0][0]
        report["ray"] = {"objects": part, "wall_s": r["wall_s"], "rows_differing": diff}
        print(f"ray: {report['ray']}", flush=True)
        problems += ["the Ray rows differ from the local run's"] if diff else []
    report["problems"] = problems
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1, default=str))
    if problems:
        raise SystemExit("FAILED: " + "; ".join(problems))


if __name__ == "__main__":
    main()
