"""``affordgrasp evaluate``: simulate, compute Φ, score the tasks and show the best grasps."""

from __future__ import annotations

import numpy as np

from ..columns import column_heading
from ..errors import InputError
from ..schema import column_numbers
from .batches import (
    SAMPLING,
    add_sampling_arguments,
    check_counts,
    one_time_text,
    run_batches,
    status_summary,
)
from .limits import ROBUST
from .output_files import check_output_file, write_table
from .task_options import (
    add_robust_argument,
    add_task_arguments,
    probability_note,
    robust_option,
    task_names,
)

SHOWN_METRICS = (
    "epsilon",
    "inertia",
    "hold_effort_sum",
    "impact_effort",
    "discharge",
    "use_force",
    "use_edge",
    "use_edge_angle",
)


LIMITS = {**SAMPLING, "robust": ROBUST}  # of the numeric options: see limits.check_limits


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp evaluate`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    add_sampling_arguments(p)
    add_task_arguments(
        p,
        required=False,
        thresholds=False,
        help="task(s) to rank by, e.g. beat,cut (repeatable; default: every registered task)",
    )
    p.add_argument("--tasks-file", default=None, help="TOML file declaring more tasks")
    add_robust_argument(p)


def best_rows(
    table, task_names: list[str], mode: str, robust: bool = False
) -> tuple[list[list], dict]:
    """The best sample of every task, as table rows and a JSON-ready dict.

    Parameters
    ----------
    table : pyarrow.Table
        Evaluated rows.
    task_names : list of str
    mode : str
        Threshold mode.
    robust : bool
        Rank by the robust score (:func:`affordgrasp.robust.ranking_column`); the value
        shown is that score.

    Returns
    -------
    rows : list of list
        One table row per task (metrics in their table units).
    doc : dict
        Task name -> the best sample (None when no row scores above −inf).
    """
    from ..columns import display_value
    from ..robust import task_scores
    from ..schema import metric_arrays
    from ..search.ranking import best_index
    from ..tasks import MetricColumns, get_task
    from ..tasks.task import PROBABLE

    metrics = MetricColumns(metric_arrays(table))
    rows, doc = [], {}
    for name in task_names:
        values = task_scores(name, table, mode, robust=robust)
        finite = np.isfinite(values)
        if not finite.any():
            rows.append([name, "-", "-inf", *["-"] * len(SHOWN_METRICS)])
            doc[name] = None
            continue
        i = best_index(np.where(finite, values, -np.inf))  # +inf does not rank here either
        shown = [float(metrics[m][i]) for m in SHOWN_METRICS]
        cells = [display_value(m, v) for m, v in zip(SHOWN_METRICS, shown, strict=True)]
        rows.append([name, int(table.column("sample")[i].as_py()), float(values[i]), *cells])
        doc[name] = {
            "sample": int(table.column("sample")[i].as_py()),
            "value": float(values[i]),
            "probable": bool(values[i] >= PROBABLE) if get_task(name).probability else None,
            "feasible": int(finite.sum()),
            "p0": table.column("p0")[i].as_py(),
            "use_dir": table.column("use_dir")[i].as_py(),
            "metrics": dict(zip(SHOWN_METRICS, shown, strict=True)),
        }
    return rows, doc


def run(args, out) -> None:
    """Run ``affordgrasp evaluate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..objects import load_object
    from ..tasks import MetricColumns, get_task, is_viable, list_tasks, load_task_file

    check_counts(args)
    if args.out:
        check_output_file(args.out, "--out", suffix=".parquet")
    if args.tasks_file:
        load_task_file(args.tasks_file)
    robust = robust_option(args)
    names = task_names(args.task) or [
        t for t in list_tasks() if t != "viable" and (robust is None or robust.scores(get_task(t)))
    ]
    for name in names:
        get_task(name).thresholds_for(args.mode)  # unknown task or mode: fail before the work
        if robust is not None and not robust.scores(get_task(name)):
            raise InputError(
                f"task {name!r} has no robust score; --robust ranks the built-in tasks "
                f"({', '.join(robust.tasks)}): drop --robust or choose among them"
            )
    obj = load_object(args.object, size_m=args.size_m, units=args.units, materials=args.materials)
    table, spent, wall = run_batches(args, out, obj, metrics=True)
    from ..schema import metric_arrays

    rows, status_doc = status_summary(table)
    metrics = MetricColumns(metric_arrays(table))
    closure = float(np.mean(metrics["epsilon"] > 0))
    viable = float(np.mean(is_viable(metrics, args.mode)))
    busy = spent["simulate"] + spent["metrics"] + spent.get("robust", 0.0)
    rate = args.samples / busy if busy > 0 else float("inf")
    out.table(
        f"{obj.name}: {args.samples} grasps, hand {args.hand}, seed {args.seed}",
        ["status", "count", "share", "contacts/grasp"],
        rows,
    )
    out.text(
        f"force closure (ε > 0): {100 * closure:.1f}%   viable: {100 * viable:.1f}%   "
        f"{rate:,.0f} grasps/s on one core (simulation {spent['simulate']:.2f} s, "
        f"metrics {spent['metrics']:.2f} s"
        + (f", robust copies {spent['robust']:.2f} s" if "robust" in spent else "")
        + f"; {one_time_text(spent)})"
    )
    if robust is not None:
        r_fc = float(np.mean(column_numbers(table.column("robust_fc"))))
        r_dirs = float(np.mean(column_numbers(table.column("robust_hold_dirs"))))
        out.text(
            f"robust (K = {robust.copies}, q = {robust.quantile}): mean fraction of copies in "
            f"force closure {r_fc:.3f}, mean load directions held {r_dirs:.2f} of 6"
        )
    best, best_doc = best_rows(table, names, args.mode, robust=robust is not None)
    # One column per task, one row per quantity: fits a terminal for any number of metrics.
    labels = ["sample", "value", *[column_heading(m) for m in SHOWN_METRICS]]
    out.table(
        f"best grasp per task (mode {args.mode}"
        + (f", robust score over K = {robust.copies} copies" if robust is not None else "")
        + "; value: p_T for beat, cut, pick; '-' when no sample passes the thresholds)",
        ["quantity", *[r[0] for r in best]],
        [[label, *[r[k + 1] for r in best]] for k, label in enumerate(labels)],
    )
    for name in names:
        found = best_doc[name]
        note = probability_note(get_task(name), found and found["value"], obj.name)
        if note:
            out.text(note)
    write_table(table, args.out, out)
    out.result(
        {
            "object": obj.name,
            "object_hash": obj.mesh_hash,
            "hand": args.hand,
            "samples": args.samples,
            "seed": args.seed,
            "mode": args.mode,
            "status": status_doc,
            "force_closure_fraction": closure,
            "viable_fraction": viable,
            "best": best_doc,
            "grasps_per_second_per_core": rate,
            "seconds": wall,
            "one_time_seconds": {"kernels": spent["kernels"], "prepare": spent["prepare"]},
            "robust": robust.to_dict() if robust is not None else None,
            "out": args.out,
        }
    )
