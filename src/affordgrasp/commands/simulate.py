"""``affordgrasp simulate``: run the grasp policy and summarise statuses and contacts."""

from __future__ import annotations

from .batches import (
    SAMPLING,
    add_sampling_arguments,
    check_counts,
    one_time_text,
    run_batches,
    status_summary,
)
from .output_files import check_output_file, write_table
from .task_options import optional_metrics

LIMITS = SAMPLING  # of the numeric options: see limits.check_limits


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp simulate`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    add_sampling_arguments(p)


def run(args, out) -> None:
    """Run ``affordgrasp simulate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..objects import load_object

    check_counts(args)
    if args.out:
        check_output_file(args.out, "--out", suffix=".parquet")
    obj = load_object(args.object, size_m=args.size_m, units=args.units, materials=args.materials)
    # Simulation only; ``--metrics +volume`` adds Φ with the GWS volume to the rows.
    table, spent, wall = run_batches(args, out, obj, metrics=bool(optional_metrics(args)))
    rows, doc = status_summary(table)
    rate = args.samples / spent["simulate"] if spent["simulate"] > 0 else float("inf")
    out.table(
        f"{obj.name}: {args.samples} grasps, hand {args.hand}, seed {args.seed}",
        ["status", "count", "share", "contacts/grasp"],
        rows,
    )
    out.text(
        f"simulation: {rate:,.0f} grasps/s on one core ({wall:.2f} s wall; {one_time_text(spent)})"
    )
    write_table(table, args.out, out)
    out.result(
        {
            "object": obj.name,
            "object_hash": obj.mesh_hash,
            "hand": args.hand,
            "samples": args.samples,
            "seed": args.seed,
            "status": doc,
            "grasps_per_second_per_core": rate,
            "seconds": wall,
            "one_time_seconds": {"kernels": spent["kernels"], "prepare": spent["prepare"]},
            "out": args.out,
        }
    )
