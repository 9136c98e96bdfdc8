"""``affordgrasp generate``: a sharded, resumable Parquet dataset of evaluated grasps."""

from __future__ import annotations

import shlex
import sys

from ..dataset.generate import DEFAULT_CHUNK_SIZE, generate
from ..dataset.shards import DEFAULT_SHARD_SIZE
from .batches import add_engine_arguments
from .limits import OWN_CHECK, ROBUST, SEED_BITS, SIZE_M, WORKERS
from .object_options import HAND_HELP, add_scale_arguments, load_objects, scale_options
from .task_options import add_metrics_argument, add_robust_argument, optional_metrics, robust_option

# Of the numeric options: see limits.check_limits.
LIMITS = {
    "samples": OWN_CHECK,  # dataset.generate: at most 100,000 shard files
    "seed": SEED_BITS,
    "workers": WORKERS,
    "size_m": SIZE_M,
    "shard_size": (None, 100_000, "a shard is held whole before it is written, ~10 kB a row"),
    "chunk_size": (None, 100_000, "a chunk is one job's rows, held whole"),
    "robust": ROBUST,
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp generate`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("objects", nargs="+", metavar="OBJECT", help="knife, knife:7 or a mesh path")
    p.add_argument("--samples", type=int, required=True, metavar="N", help="samples per object")
    p.add_argument("--out", required=True, metavar="DIR", help="dataset directory (resumable)")
    p.add_argument("--seed", type=int, default=0, help="seed of the uniform samples (default 0)")
    p.add_argument(
        "--streams",
        choices=("per-object", "shared"),
        default=None,
        help="per-object: each object draws its own samples (the default for a new dataset; "
        "what a learning dataset needs); shared: sample i is the same pregrasp on every "
        "object. A resume keeps the dataset's own",
    )
    add_engine_arguments(p)
    p.add_argument("--hand", default="barrett", help=HAND_HELP)
    add_scale_arguments(p)
    p.add_argument(
        "--shard-size",
        type=int,
        default=DEFAULT_SHARD_SIZE,
        metavar="ROWS",
        help=f"rows per shard file (default {DEFAULT_SHARD_SIZE})",
    )
    p.add_argument(
        "--chunk-size",
        type=int,
        default=DEFAULT_CHUNK_SIZE,
        metavar="ROWS",
        help="most samples per unit of work (does not change the output)",
    )
    p.add_argument(
        "--no-metrics", action="store_true", help="simulate only; write no metric columns"
    )
    add_metrics_argument(p)
    p.add_argument(
        "--depth",
        action="store_true",
        help="also store each row's 128x128 depth image D(p0, O) (uint16 mm, ~3-8 kB/row)",
    )
    add_robust_argument(p)


def command_line(args) -> list[str]:
    """The command as a user would type it, every option that shapes the output explicit.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``affordgrasp generate``.

    Returns
    -------
    list of str
        Recorded in the manifest and the dataset card.
    """
    cmd = ["affordgrasp", "generate", *args.objects, "--samples", str(args.samples)]
    cmd += ["--out", str(args.out), "--seed", str(args.seed), "--hand", args.hand]
    cmd += ["--shard-size", str(args.shard_size)]
    if getattr(args, "streams", None):
        cmd += ["--streams", args.streams]
    if args.size_m is not None:
        cmd += ["--size-m", repr(args.size_m)]
    if args.units is not None:
        cmd += ["--units", args.units]
    if args.no_metrics:
        cmd.append("--no-metrics")
    for name in sorted(optional_metrics(args)):
        cmd += ["--metrics", f"+{name}"]
    if args.depth:
        cmd.append("--depth")
    if getattr(args, "robust", 0):
        cmd += ["--robust", str(args.robust)]
    if args.engine != "local":
        cmd += ["--engine", args.engine]
    if args.address:
        cmd += ["--address", args.address]
    if args.workers:
        cmd += ["--workers", str(args.workers)]
    return cmd


def run(args, out) -> None:
    """Run ``affordgrasp generate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..errors import InputError
    from .output_files import check_output_dir

    volume = "volume" in optional_metrics(args)
    if volume and args.no_metrics:
        raise InputError("--metrics +volume adds to the metric columns; drop --no-metrics")
    check_output_dir(args.out, "--out")
    robust = robust_option(args)
    cmd = command_line(args)
    objects = args.objects
    if any(v is not None for v in scale_options(args).values()) or args.materials:
        objects = load_objects(args.objects, args)
    try:
        summary = generate(
            objects,
            args.samples,
            args.out,
            seed=args.seed,
            workers=args.workers,
            engine=args.engine,
            address=args.address,
            hand=args.hand,
            shard_size=args.shard_size,
            chunk_size=args.chunk_size,
            metrics=not args.no_metrics,
            volume=volume,
            depth=args.depth,
            materials=args.materials,
            command=cmd,
            progress=lambda total: out.progress("generating", total),
            robust=robust,
            streams=args.streams,
        )
    except KeyboardInterrupt:
        print(
            f"stopped; every finished shard is kept in {args.out}. Run the same command to "
            f"finish:\n  {shlex.join(cmd)}",
            file=sys.stderr,
        )
        raise
    statuses = sorted({s for c in summary.status_counts.values() for s in c})
    rows = []
    for name, counts in summary.status_counts.items():
        total = sum(counts.values())
        rows.append([name, total, *[counts.get(s, 0) for s in statuses]])
    out.table(f"Dataset {summary.directory}", ["object", "samples", *statuses], rows)
    rate = summary.grasps_per_s
    per_worker = rate / summary.workers if summary.workers else 0.0
    out.table(
        "This run",
        ["shards written", "shards already there", "samples", "seconds", "grasps/s", "per worker"],
        [
            [
                summary.shards_written,
                summary.shards_skipped,
                summary.samples_written,
                round(summary.elapsed_s, 1),
                round(rate, 1),
                round(per_worker, 1),
            ]
        ],
    )
    out.text(f"card: {summary.directory}/_card.md  ·  engine {summary.engine} × {summary.workers}")
    out.result(summary.to_dict())
