"""Brute-force argmax of an affordance over a dataset (paper §IV-C, conventions: Datasets).

:func:`best_grasps` streams a dataset in batches, scores every row with a task's affordance
function F_T and keeps the ``top`` rows, so memory stays bounded however large the dataset.
Only values above −∞ rank (−∞ means a threshold failed; NaN never ranks); ties go to the
object given first, then the lower sample index, so the result is the same as sorting the
whole table by (F_T descending, object, sample) (the ranker:
:class:`affordgrasp.search.ranking.TopRows`).

A first pass reads only the metric columns; a second fetches the full rows of the winners,
reading only the row groups that hold them.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as pads
import pyarrow.parquet as pq

from ..columns import HOLD_EFFORT_COLUMNS, HOLD_EFFORT_SUM, METRIC_COLUMNS, hold_effort_sum
from ..errors import DatasetError, bad_parameter
from ..runtime.writing import atomic_write
from ..search.ranking import TopRows  # noqa: F401  (re-exported: its former home)
from ..tasks import Task, get_task
from .handle import Dataset, DatasetLike
from .reading import read_errors

AFFORDANCE_COLUMN = "affordance"
RANK_COLUMN = "rank"


@dataclass
class BestGrasps:
    """The top rows of a dataset for a task.

    Attributes
    ----------
    task : str
        The task name.
    mode : str
        The threshold mode.
    table : pyarrow.Table
        The rows (every dataset column) best first, plus ``rank`` (1 = best) and
        ``affordance`` (F_T).
    rows_scanned : int
        Rows scored.
    finite : int
        Rows whose F_T is above −∞.
    objects : list of str
        The objects scanned.
    """

    task: str
    mode: str
    table: pa.Table
    rows_scanned: int
    finite: int
    objects: list[str]

    def to_dict(self) -> dict:
        """The result as JSON-ready data (``best --json``).

        Returns
        -------
        dict
            ``task``, ``mode``, ``rows_scanned``, ``finite``, ``objects`` and ``best``: one dict
            per ranked row (rank, object, sample, affordance, status, p0, use_dir, the metric
            columns and the hold-effort sum).
        """
        rows = []
        for r in self.table.to_pylist():
            row = {
                "rank": r[RANK_COLUMN],
                "object": r["object"],
                "sample": r["sample"],
                "affordance": r[AFFORDANCE_COLUMN],
                "status": r["status"],
                "p0": r["p0"],
                "use_dir": r["use_dir"],
            }
            row.update({c: r[c] for c in METRIC_COLUMNS if c in r})
            if HOLD_EFFORT_COLUMNS[0] in r:
                row[HOLD_EFFORT_SUM] = hold_effort_sum(r)
            rows.append(row)
        return {
            "task": self.task,
            "mode": self.mode,
            "rows_scanned": self.rows_scanned,
            "finite": self.finite,
            "objects": self.objects,
            "best": rows,
        }


def numeric_columns(table: pa.Table) -> dict[str, np.ndarray]:
    """The numeric scalar columns of a table as float64 arrays (what tasks read).

    Parameters
    ----------
    table : pyarrow.Table

    Returns
    -------
    dict of str to (n,) float64 ndarray
    """
    out = {}
    for f in table.schema:
        if pa.types.is_integer(f.type) or pa.types.is_floating(f.type):
            out[f.name] = table.column(f.name).to_numpy().astype(np.float64)
    return out


def task_values(
    task, columns, mode: str = "default", thresholds: Mapping | None = None, robust: bool = False
):
    """F_T for every row of ``columns`` (its robust ranking score with ``robust``).

    Parameters
    ----------
    task : Task
        The task.
    columns : pyarrow.Table or mapping of str to (n,) ndarray
        The metric columns.
    mode : str
        Threshold mode.
    thresholds : mapping of str to float, optional
        Threshold values that replace the mode's.
    robust : bool
        Rank by the robust score instead (:func:`affordgrasp.robust.ranking_column`:
        ``robust_hold`` for pick, ``robust_<task>`` otherwise), read from the rows; the
        mode and thresholds are those the rows were evaluated with.

    Returns
    -------
    (n,) float64 ndarray
        −∞ where a requirement fails.
    """
    if robust:
        from ..robust import ranking_values

        return ranking_values(columns, task.name)
    if isinstance(columns, pa.Table):
        # Only the numeric columns: the task reads names, not strings like `object`.
        columns = numeric_columns(columns)
    values = task.evaluate(columns, mode=mode, **dict(thresholds or {}))
    return np.asarray(values, dtype=np.float64)


def best_grasps(
    directory: DatasetLike,
    task: str | Task,
    *,
    mode: str = "default",
    objects: list[str] | None = None,
    top: int = 5,
    thresholds: Mapping[str, float] | None = None,
    batch_size: int = 65536,
    robust: bool = False,
) -> BestGrasps:
    """The ``top`` rows of a dataset by the affordance F_T of ``task`` (paper §IV-C).

    Parameters
    ----------
    directory : path or Dataset
        A dataset written by :func:`affordgrasp.generate`.
    task : str or Task
        A registered task name or a :class:`~affordgrasp.tasks.Task`.
    mode : str
        Threshold mode (``affordgrasp tasks`` lists them).
    objects : list of str, optional
        Only these objects (``knife`` matches ``knife:0``).
    top : int
        How many rows to keep (>= 1).
    thresholds : mapping of str to float, optional
        Overrides of the task's thresholds, e.g. ``{"tau_eps": 0.01}``.
    batch_size : int
        Rows scored at a time (memory stays bounded).
    robust : bool
        Rank by the robust score (a dataset generated with ``--robust K``;
        :func:`affordgrasp.robust.ranking_column`).

    Returns
    -------
    BestGrasps
        The rows best first (``rank``, ``affordance`` added) and how many were scored.

    Raises
    ------
    DatasetError
        For a directory that is not a dataset or has no metrics.
    """
    if not isinstance(top, int) or top < 1:
        raise bad_parameter("top", f"must be a positive integer, got {top!r}")
    ds = Dataset.open(directory)
    directory = ds.directory
    if not ds.metrics:
        raise DatasetError(
            f"dataset {str(directory)!r} was generated with --no-metrics, so it has no metrics "
            "to score; generate it again without --no-metrics"
        )
    task_obj = get_task(task) if isinstance(task, str) else task
    task_obj.thresholds_for(mode, **dict(thresholds or {}))  # bad mode/threshold: fail now
    names = ds.objects
    chosen = ds.select(objects)
    dataset = ds.arrow()
    flt = pads.field("object").isin(chosen) if chosen else None
    metric_cols = [c for c in METRIC_COLUMNS if c in dataset.schema.names]
    if robust:
        from ..robust import ranking_column

        if ds.robust is None:
            raise DatasetError(
                f"dataset {str(directory)!r} has no robust columns; generate it with "
                "--robust K to rank by a robust score, or drop --robust"
            )
        metric_cols.append(ranking_column(task_obj.name))
    scanner = dataset.scanner(
        columns=["object", "sample", *metric_cols], filter=flt, batch_size=batch_size
    )
    name_set = pa.array(names, pa.string())
    best = TopRows(top, 2)  # ties: the object given first, then the lower sample index
    scanned = finite = 0
    with read_errors(directory):
        for batch in scanner.to_batches():
            if batch.num_rows == 0:
                continue
            table = pa.Table.from_batches([batch])
            values = task_values(task_obj, table, mode, thresholds, robust=robust)
            scanned += len(values)
            o = pc.index_in(table["object"], value_set=name_set).to_numpy(zero_copy_only=False)
            s = table["sample"].to_numpy()
            finite += best.add(values, o.astype(np.int64), s.astype(np.int64))
    best_v, (best_o, best_s) = best.values, best.keys

    with read_errors(directory):
        rows = _fetch_rows(dataset, names, best_o, best_s)
    rows = rows.append_column(RANK_COLUMN, pa.array(np.arange(1, len(best_v) + 1), pa.int64()))
    rows = rows.append_column(AFFORDANCE_COLUMN, pa.array(best_v, pa.float64()))
    return BestGrasps(
        task=task_obj.name,
        mode=f"{mode}, robust" if robust else mode,
        table=rows,
        rows_scanned=scanned,
        finite=finite,
        objects=chosen or names,
    )


def _fetch_rows(
    dataset: pads.Dataset, names: list[str], obj: np.ndarray, sample: np.ndarray
) -> pa.Table:
    """The full rows of (object, sample) pairs, in the order given."""
    if len(obj) == 0:
        return dataset.schema.empty_table()
    flt = None
    for o, s in zip(obj.tolist(), sample.tolist(), strict=True):
        term = (pads.field("object") == names[o]) & (pads.field("sample") == s)
        flt = term if flt is None else flt | term
    # One scan; row-group statistics on (object, sample) skip the shards without a winner.
    found = dataset.to_table(filter=flt)
    where = {
        (a, b): i
        for i, (a, b) in enumerate(
            zip(found["object"].to_pylist(), found["sample"].to_pylist(), strict=True)
        )
    }
    if len(where) != found.num_rows or len(where) != len(obj):  # pragma: no cover
        raise DatasetError("the dataset holds duplicate or missing rows; generate it again")
    order = [where[(names[o], s)] for o, s in zip(obj.tolist(), sample.tolist(), strict=True)]
    return found.take(pa.array(order, pa.int64()))


def write_best(result: BestGrasps, path: str | os.PathLike) -> Path:
    """Write the top rows as one Parquet file (the viewer reads it), task and mode in metadata.

    Parameters
    ----------
    result : BestGrasps
    path : path
        The file to write.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    if path.suffix != ".parquet":
        raise bad_parameter("path", f"must name a .parquet file, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = dict(result.table.schema.metadata or {})
    meta[b"affordgrasp_best"] = json.dumps(
        {"task": result.task, "mode": result.mode, "objects": result.objects}
    ).encode()
    sink = pa.BufferOutputStream()
    pq.write_table(result.table.replace_schema_metadata(meta), sink)
    # Whole or not at all: a full disk raises an InputError naming the path, no stub left.
    atomic_write(path, sink.getvalue().to_pybytes())
    return path
