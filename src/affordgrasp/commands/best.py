"""``affordgrasp best``: brute-force argmax of a task over a dataset (paper §IV-C)."""

from __future__ import annotations

import math

from ..columns import column_heading
from .limits import ROBUST
from .task_options import (
    add_robust_argument,
    add_task_arguments,
    parse_thresholds,
    probability_note,
)

# Of the numeric options: see limits.check_limits.
LIMITS = {"top": (None, 100_000, "the top rows are held and printed"), "robust": ROBUST}


METRICS_SHOWN = (
    ("ε", "epsilon"),
    ("ΣE_h", "hold_effort_sum"),
    ("E_i", "impact_effort"),
    ("I", "inertia"),
    ("δ", "discharge"),
    ("U_τ", "use_force"),
    ("U_g", "use_edge"),
    ("edge angle", "use_edge_angle"),
)


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp best`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("directory", metavar="DIR", help="a dataset written by 'affordgrasp generate'")
    add_task_arguments(p, several=False)
    p.add_argument("--object", action="append", default=None, help="only this object (repeatable)")
    p.add_argument("--top", type=int, default=5, help="how many grasps to show (default 5)")
    p.add_argument("--out", default=None, help="write the top rows to this .parquet file")
    add_robust_argument(
        p,
        help="rank by the robust score of a dataset generated with --robust K (K must be "
        "the dataset's; default 0: plain F_T)",
    )


def shown_metrics(task_name: str) -> list[tuple[str, str]]:
    """(label, column) of the metrics a task reads, ε first; all of them if it does not say.

    Parameters
    ----------
    task_name : str
        A registered task.

    Returns
    -------
    list of (str, str)
    """
    from ..columns import HOLD_EFFORT_COLUMNS
    from ..tasks import get_task

    requires = set(getattr(get_task(task_name), "requires", ()) or ())
    if not requires:
        return list(METRICS_SHOWN)
    if requires & set(HOLD_EFFORT_COLUMNS):
        requires.add("hold_effort_sum")
    requires.add("epsilon")
    return [(label, name) for label, name in METRICS_SHOWN if name in requires]


def metric_cells(row: dict, shown=METRICS_SHOWN) -> list:
    """The table cells of one row's metrics, in their table units.

    Parameters
    ----------
    row : dict
        A sample row (a missing metric shows as NaN).
    shown : sequence of (str, str)
        (label, column) pairs, as :func:`shown_metrics` gives.

    Returns
    -------
    list
        One value per shown metric (ΣE_h computed from the six hold efforts).
    """
    from ..columns import HOLD_EFFORT_SUM, display_value, hold_effort_sum

    cells = []
    for _, name in shown:
        if name == HOLD_EFFORT_SUM:
            cells.append(hold_effort_sum(row))
        else:
            cells.append(display_value(name, row.get(name, math.nan)))
    return cells


def metric_headings(shown=METRICS_SHOWN) -> list[str]:
    """Table headings of ``shown`` with their units (the edge angle in degrees).

    Parameters
    ----------
    shown : sequence of (str, str)
        (label, column) pairs.

    Returns
    -------
    list of str
    """
    return [column_heading(name, label) for label, name in shown]


def check_dataset_robust(directory, k: int) -> bool:
    """Whether ``--robust K`` ranks a dataset by its robust score; K must be the dataset's.

    Parameters
    ----------
    directory : path
        A dataset.
    k : int
        ``--robust K`` (0: plain).

    Returns
    -------
    bool
        True for K > 0 (the dataset holds robust columns of K copies; a folder of tables
        without a manifest is not checked here, its rows are when ranked).

    Raises
    ------
    InputError
        For K < 0, or K > 0 on a dataset without robust columns or with another K.
    """
    from pathlib import Path

    from ..dataset.handle import Dataset
    from ..dataset.manifest import MANIFEST_NAME
    from ..errors import InputError

    if k < 0:
        raise InputError(f"--robust must be an integer >= 0, got {k}")
    if k == 0:
        return False
    manifest_path = Path(directory).expanduser() / MANIFEST_NAME
    if not manifest_path.exists():
        return True  # a folder of evaluated tables: its rows must carry the robust columns
    settings = Dataset.open(directory).robust
    there = settings.copies if settings is not None else 0
    if there != k:
        raise InputError(
            f"--robust {k}: the dataset in {str(directory)!r} has "
            + (
                f"robust columns of K = {there} copies; pass --robust {there}"
                if there
                else "no robust columns; generate it with --robust K"
            )
        )
    return True


def loosen_hint(mode: str) -> str:
    """What to try when no grasp passes a task's thresholds in ``mode``.

    Parameters
    ----------
    mode : str
        The ``--mode`` of the run.

    Returns
    -------
    str
        ``--mode no-robustness`` unless that is the mode, and a lower ``--threshold``.
    """
    lower = "a lower --threshold"
    return lower if mode == "no-robustness" else f"--mode no-robustness or {lower}"


def run(args, out) -> None:
    """Run ``affordgrasp best``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..search.best import best_grasps, write_best
    from ..tasks import get_task

    if args.out:
        from .output_files import check_output_file

        check_output_file(args.out, "--out", suffix=".parquet")

    robust = check_dataset_robust(args.directory, args.robust)
    from ..dataset.handle import Dataset

    ds = Dataset.open(args.directory)
    with out.progress(f"best {args.task}", total=ds.count_rows(args.object)) as advance:
        result = best_grasps(
            ds,
            args.task,
            mode=args.mode,
            objects=args.object,
            top=args.top,
            thresholds=parse_thresholds(args.threshold),
            robust=robust,
            progress=advance,
        )
    shown = shown_metrics(args.task)
    rows = [
        [r["rank"], r["object"], r["sample"], r["affordance"], r["status"], *metric_cells(r, shown)]
        for r in result.table.to_pylist()
    ]
    out.table(
        f"Best {len(rows)} for task {result.task} ({result.mode}) in {args.directory}",
        ["rank", "object", "sample", "F_T", "status", *metric_headings(shown)],
        rows,
    )
    out.text(
        f"scanned {result.rows_scanned:,} samples of "
        + (
            ", ".join(result.objects)
            if len(result.objects) <= 8
            else f"{len(result.objects)} objects ({', '.join(result.objects[:3])}, ...)"
        )
        + "; "
        f"{result.finite:,} have a finite F_T"
    )
    best = float(result.table.column("affordance")[0].as_py()) if rows else None
    note = probability_note(get_task(result.task), best, str(args.directory))
    if note:
        out.text(note)
    if result.finite == 0:
        out.text(
            f"no sample passes the task's thresholds; try {loosen_hint(args.mode)}, or "
            "generate more samples"
        )
    document = result.to_dict()
    if args.out:
        path = write_best(result, args.out)
        out.text(f"wrote the top {result.table.num_rows} rows to {path}")
        document["out"] = str(path)
    out.result(document)
