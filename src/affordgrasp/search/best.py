"""The best rows of tables and datasets by a task's score (paper §IV-C, conventions: Datasets).

:func:`scan_top` is the one top-k scan of the package: it streams rows in batches, scores
them (:func:`affordgrasp.robust.task_scores`: F_T, or the robust score) and keeps the ``top``
rows of every task, or of every (object, task), so memory stays bounded however large the
source. Only values above −∞ rank (−∞ means a threshold failed; NaN never ranks); ties go to
the object named first, then the lower sample index, then the lower seed, so the result is
the same as sorting every row by (score descending, object, sample, seed) (the ranker:
:class:`affordgrasp.search.ranking.TopRows`).

* :func:`best_grasps`: the top rows of a dataset for a task (``affordgrasp best``); a first
  pass reads only the metric columns, a second fetches the full rows of the winners,
  reading only the row groups that hold them.
* :func:`top_grasps`: the top rows per object and task of a dataset or an in-memory table
  (``affordgrasp show``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as pads
import pyarrow.parquet as pq

from ..columns import HOLD_EFFORT_COLUMNS, HOLD_EFFORT_SUM, METRIC_COLUMNS, hold_effort_sum
from ..dataset.handle import Dataset, DatasetLike, read_errors, scan_files
from ..errors import DatasetError, bad_parameter
from ..robust import task_scores
from ..runtime.writing import atomic_write
from ..tasks import MetricColumns, Task, get_task
from ..tasks.builtins import TIE_COLUMNS, probability_value
from .ranking import TopRows

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


@dataclass
class TopScan:
    """What :func:`scan_top` kept of one task (or one object and task).

    Attributes
    ----------
    best : TopRows
        The top rows: their scores, and their keys (object index, sample, seed).
    scanned : int
        Rows scored.
    finite : int
        Rows whose score is above −∞.
    """

    best: TopRows
    scanned: int = 0
    finite: int = 0


def scan_top(
    tables: Iterable[pa.Table],
    tasks: Sequence[Task],
    top: int,
    *,
    mode: str = "default",
    thresholds: Mapping[str, Mapping[str, float]] | None = None,
    robust: bool = False,
    objects: Sequence[str] = (),
    per_object: bool = False,
    progress: Callable[[int], object] | None = None,
    stored: Collection[str] = (),
) -> tuple[list[str], dict[tuple[str | None, str], TopScan]]:
    """One pass over batches of rows: the ``top`` rows of every task (of every object and
    task with ``per_object``).

    Ties go to the object named first (``objects``, then the others in the order met),
    then the lower sample index, then the lower seed: the order of ``affordgrasp best``.

    Parameters
    ----------
    tables : iterable of pyarrow.Table
        Batches of rows: ``object``, ``sample``, ``seed`` (optional) and the columns the
        tasks read.
    tasks : sequence of Task
    top : int
        Rows kept per task (or per object and task).
    mode : str
        Threshold mode.
    thresholds : mapping of str to mapping, optional
        Task name -> threshold overrides.
    robust : bool
        Rank by the rows' robust scores (:func:`affordgrasp.robust.task_scores`).
    objects : sequence of str
        Object names in the order their ties go.
    per_object : bool
        Keep the top rows of each object apart.
    progress : callable, optional
        Called with the number of rows after each batch.
    stored : collection of str
        Task probabilities whose ``p_T`` column the rows carry from the models in use
        (:func:`stored_probabilities`): read, not computed again.

    Returns
    -------
    names : list of str
        The object names that the kept object indices refer to.
    kept : dict of (str or None, str) to TopScan
        Keyed by (object, task name), the object None without ``per_object``; in the order
        met.
    """
    names = list(objects)
    index = {name: i for i, name in enumerate(names)}
    thresholds = thresholds or {}
    kept: dict[tuple[str | None, str], TopScan] = {}
    for table in tables:
        met = pc.unique(table.column("object")).to_pylist() if table.num_rows else []
        for name in met:
            if name not in index:
                index[name] = len(names)
                names.append(name)
        code = pc.index_in(table.column("object"), value_set=pa.array(names, pa.string()))
        code = code.to_numpy(zero_copy_only=False).astype(np.int64)
        sample = table.column("sample").to_numpy().astype(np.int64)
        seed = (
            table.column("seed").to_numpy().astype(np.int64)
            if "seed" in table.column_names
            else np.zeros(table.num_rows, dtype=np.int64)
        )
        if per_object:  # rows grouped by object once per batch (a batch may hold many)
            order = np.argsort(code, kind="stable")
            bounds = np.concatenate([[0], np.cumsum(np.bincount(code, minlength=len(names)))])
            groups = [(n, order[bounds[index[n]] : bounds[index[n] + 1]]) for n in met]
        else:
            groups = [(None, np.arange(table.num_rows))] if table.num_rows else []
        metrics = MetricColumns(table)
        for task in tasks:
            if not groups:
                break
            if task.name in stored:
                p = table.column(f"p_{task.name}").to_numpy(zero_copy_only=False)
                values = probability_value(task.name, p, metrics)
            else:
                values = task_scores(task, metrics, mode, thresholds.get(task.name), robust=robust)
            for name, rows in groups:
                entry = kept.setdefault((name, task.name), TopScan(TopRows(top, 3)))
                entry.scanned += len(rows)
                entry.finite += entry.best.add(values[rows], code[rows], sample[rows], seed[rows])
        if progress is not None:
            progress(table.num_rows)
    return names, kept


def best_grasps(
    dataset: DatasetLike,
    task: str | Task,
    *,
    mode: str = "default",
    objects: list[str] | None = None,
    top: int = 5,
    thresholds: Mapping[str, float] | None = None,
    batch_size: int = 65536,
    robust: bool = False,
    progress: Callable[[int], object] | None = None,
) -> BestGrasps:
    """The ``top`` rows of a dataset by the affordance F_T of ``task`` (paper §IV-C).

    Parameters
    ----------
    dataset : path or Dataset
        A dataset written by :func:`affordgrasp.generate` (opened once).
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
    progress : callable, optional
        Called with the number of rows after each batch scanned.

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
    ds = Dataset.open(dataset)
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
    arrow = ds.arrow()
    flt = pads.field("object").isin(chosen) if chosen else None
    metric_cols = [c for c in METRIC_COLUMNS if c in arrow.schema.names]
    if robust:
        from ..robust import ranking_column
        from ..tasks.probability import ROBUST_COLUMNS

        if ds.robust is None:
            raise DatasetError(
                f"dataset {str(directory)!r} has no robust columns; generate it with "
                "--robust K to rank by a robust score, or drop --robust"
            )
        if task_obj.probability:  # its robust model reads the generic robust columns
            metric_cols += [c for c in ROBUST_COLUMNS if c in arrow.schema.names]
        else:
            metric_cols.append(ranking_column(task_obj.name))
    stored = stored_probabilities(ds, [task_obj], robust)
    if stored:  # p_T and the columns of its ties only: a tenth of the bytes to read
        metric_cols = [f"p_{task_obj.name}", *TIE_COLUMNS[task_obj.name]]
    batches = scan_files(arrow, ["object", "sample", *metric_cols], flt, batch_size)
    with read_errors(directory):
        _, kept = scan_top(
            (pa.Table.from_batches([batch]) for batch in batches),
            [task_obj],
            top,
            mode=mode,
            thresholds={task_obj.name: thresholds or {}},
            robust=robust,
            objects=names,
            stored=stored,
            progress=progress,
        )
    found = kept.get((None, task_obj.name), TopScan(TopRows(top, 3)))
    best_v, (best_o, best_s, _) = found.best.values, found.best.keys
    # the winners' shards, from the plan (an object's sample s lies in the shard starting at
    # s rounded down to the shard size): the fetch opens those files only
    index = {o["name"]: int(o["index"]) for o in ds.manifest["objects"]}
    size = ds.shard_size
    files = sorted(
        {
            str(directory / f"part-{index[names[o]]:05d}-{(int(s) // size) * size:012d}.parquet")
            for o, s in zip(best_o.tolist(), best_s.tolist(), strict=True)
        }
    )
    with read_errors(directory):
        rows = _fetch_rows(arrow, names, best_o, best_s, files)
    rows = rows.append_column(RANK_COLUMN, pa.array(np.arange(1, len(best_v) + 1), pa.int64()))
    rows = rows.append_column(AFFORDANCE_COLUMN, pa.array(best_v, pa.float64()))
    return BestGrasps(
        task=task_obj.name,
        mode=f"{mode}, robust" if robust else mode,
        table=rows,
        rows_scanned=found.scanned,
        finite=found.finite,
        objects=chosen or names,
    )


def stored_probabilities(ds: Dataset, tasks: Sequence[Task], robust: bool) -> list[str]:
    """The task probabilities a scan can read from a dataset's ``p_T`` columns.

    A dataset stores ``p_beat``, ``p_cut`` and ``p_pick``, computed when it was generated
    (with its robust columns when it has them). They are the ranking's own values when the
    dataset's manifest records the digests of the models in use
    (:func:`~affordgrasp.tasks.probability.model_digests`) and the ranking reads the same
    model (robust or plain, as the dataset); reading them skips the trees, most of the cost
    of a scan (10⁷ rows: about 24 s of tree walks).

    Parameters
    ----------
    ds : Dataset
    tasks : sequence of Task
    robust : bool
        The ranking is robust.

    Returns
    -------
    list of str
        Task names.
    """
    from ..tasks.probability import model_digests, recorded_digests

    recorded = recorded_digests(ds.manifest.get("probability_models"))
    names = set(ds.arrow().schema.names)
    if bool(robust) != (ds.robust is not None):
        return []
    current = model_digests()

    def of(digests: dict, task: str) -> dict:  # the task's models and the code's version
        return {k: v for k, v in digests.items() if k == "code" or k.split("-")[0] == task}

    return [
        t.name
        for t in tasks
        if t.probability and f"p_{t.name}" in names and of(recorded, t.name) == of(current, t.name)
    ]


def _fetch_rows(
    dataset: pads.Dataset,
    names: list[str],
    obj: np.ndarray,
    sample: np.ndarray,
    files: Sequence[str] | None = None,
) -> pa.Table:
    """The full rows of (object, sample) pairs, in the order given."""
    if len(obj) == 0:
        return dataset.schema.empty_table()
    flt = None
    for o, s in zip(obj.tolist(), sample.tolist(), strict=True):
        term = (pads.field("object") == names[o]) & (pads.field("sample") == s)
        flt = term if flt is None else flt | term
    # One scan; row-group statistics on (object, sample) skip the shards without a winner.
    if files is not None:  # the files that hold them
        dataset = pads.dataset(list(files), schema=dataset.schema, format="parquet")
    found = pa.Table.from_batches(list(scan_files(dataset, None, flt)), schema=dataset.schema)
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


@dataclass(frozen=True)
class RankedGrasp:
    """One of the best grasps of an object for a task (rank 1 is the best).

    Attributes
    ----------
    object, task : str
    rank : int
    score : float
        F_T.
    seed, sample : int
        The row's key.
    row : dict
        The full sample row.
    """

    object: str
    task: str
    rank: int
    score: float
    seed: int
    sample: int
    row: dict


@dataclass
class TaskRanking:
    """The best grasps of one object for one task, and how many rows were scored.

    Attributes
    ----------
    object, task : str
    scored : int
        Rows scored.
    accepted : int
        Rows with a score above -inf.
    best : list of RankedGrasp
        Best first.
    """

    object: str
    task: str
    scored: int = 0
    accepted: int = 0  # rows with a score above -inf
    best: list[RankedGrasp] = field(default_factory=list)


def top_grasps(
    source,
    tasks: Sequence[Task],
    *,
    mode: str = "default",
    top: int = 4,
    thresholds: dict[str, dict[str, float]] | None = None,
    progress=None,
    robust: bool = False,
) -> dict[tuple[str, str], TaskRanking]:
    """The ``top`` best rows per (object, task) by the tasks' scores (:func:`scan_top`).

    Higher is better; -inf and NaN never count.

    Parameters
    ----------
    source : GraspSource
        Where the rows come from (:mod:`affordgrasp.viz.sources`: a dataset or a table);
        its scalar columns are scanned, then the winners' full rows fetched.
    tasks : sequence of Task
        Task objects (:func:`affordgrasp.get_task`).
    mode : str
        Threshold mode.
    top : int
        Rows kept per (object, task).
    thresholds : dict of str to dict, optional
        Task name -> threshold overrides.
    progress : callable, optional
        Called with the number of rows after each batch.
    robust : bool
        Rank by the rows' robust scores (:func:`affordgrasp.robust.ranking_column`).

    Returns
    -------
    dict of (str, str) to TaskRanking
        Keyed by (object, task).
    """
    if top < 1:
        raise bad_parameter("top", f"must be at least 1, got {top}")
    _, kept = scan_top(
        source.scan(source.scalar_columns()),
        tasks,
        top,
        mode=mode,
        thresholds=thresholds,
        robust=robust,
        per_object=True,
        progress=progress,
    )
    out: dict[tuple[str, str], TaskRanking] = {}
    for (obj, task), found in kept.items():
        ranking = TaskRanking(obj, task, found.scanned, found.finite)
        _, samples, seeds = found.best.keys
        keys = [(int(a), int(b)) for a, b in zip(seeds, samples, strict=True)]
        rows = source.fetch(obj, keys) if keys else []
        by_key = {(int(r["seed"]), int(r["sample"])): r for r in rows}
        for rank, (score, k) in enumerate(zip(found.best.values, keys, strict=True), start=1):
            if k in by_key:
                ranking.best.append(RankedGrasp(obj, task, rank, float(score), *k, by_key[k]))
        out[obj, task] = ranking
    return out
