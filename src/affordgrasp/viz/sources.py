"""Where the grasps to show come from: a dataset directory or an in-memory table.

A dataset directory is read by :func:`affordgrasp.dataset.reading.open_dataset` (its shards,
or every ``*.parquet`` file under a directory without a manifest), streamed in batches so
that datasets larger than memory can be ranked and plotted. :func:`top_grasps` keeps the
best ``k`` rows per object and task with one pass over the scalar columns (ranked by
:class:`affordgrasp.search.ranking.TopRows`), then reads back only those rows in full.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as pads

from ..dataset.best import numeric_columns, task_values
from ..dataset.handle import Dataset
from ..dataset.reading import open_dataset, read_errors
from ..errors import DatasetError, bad_parameter
from ..hands.model import Hand
from ..search.ranking import TopRows

BATCH_ROWS = 65536


class GraspSource:
    """Rows of grasps: scanned in batches, fetched by key.

    Attributes
    ----------
    name : str
        Shown in captions.
    hand : Hand or None
        The hand that made the rows, when the source knows it; None: the rows' ``hand``
        column names a registered hand.
    """

    name: str
    hand: Hand | None = None

    def schema(self) -> pa.Schema:
        """The rows' Arrow schema.

        Returns
        -------
        pyarrow.Schema
        """
        raise NotImplementedError

    def scan(self, columns: Sequence[str]) -> Iterator[pa.Table]:
        """The rows in batches, some columns only.

        Parameters
        ----------
        columns : sequence of str

        Yields
        ------
        pyarrow.Table
            A batch of rows.
        """
        raise NotImplementedError

    def fetch(self, obj: str, keys: Sequence[tuple[int, int]]) -> list[dict]:
        """Full rows of object ``obj`` with (seed, sample) in ``keys``, in the order of keys.

        Parameters
        ----------
        obj : str
            Object name.
        keys : sequence of (int, int)
            (seed, sample) of each row wanted.

        Returns
        -------
        list of dict
            One per key found (a missing key is skipped).
        """
        raise NotImplementedError

    def scalar_columns(self) -> list[str]:
        """Columns that are not lists (metrics, status, ids): cheap to scan.

        Returns
        -------
        list of str
        """
        return [
            f.name
            for f in self.schema()
            if not (pa.types.is_list(f.type) or pa.types.is_fixed_size_list(f.type))
        ]


def _order_rows(rows: list[dict], keys: Sequence[tuple[int, int]]) -> list[dict]:
    by_key = {(int(r["seed"]), int(r["sample"])): r for r in rows}
    return [by_key[k] for k in keys if k in by_key]


@dataclass
class TableSource(GraspSource):
    """Rows held in memory (e.g. samples just evaluated).

    Attributes
    ----------
    table : pyarrow.Table
        Sample rows.
    name : str
        Shown in captions.
    objects : dict of str to GraspObject
        The rows' objects, when known (saves loading them again).
    hand : Hand or None
        The hand that made the rows (a custom one included); None: the rows' ``hand``
        column names a registered hand.
    """

    table: pa.Table
    name: str = "samples"
    objects: dict = field(default_factory=dict)  # name -> GraspObject, when known
    hand: Hand | None = None

    def schema(self) -> pa.Schema:
        return self.table.schema

    def scan(self, columns: Sequence[str]) -> Iterator[pa.Table]:
        t = self.table.select(list(columns))
        for start in range(0, max(t.num_rows, 1), BATCH_ROWS):
            yield t.slice(start, BATCH_ROWS)

    def fetch(self, obj: str, keys: Sequence[tuple[int, int]]) -> list[dict]:
        samples = pa.array([k[1] for k in keys], pa.int64())
        mask = pc.and_(
            pc.equal(self.table.column("object"), obj),
            pc.is_in(self.table.column("sample"), value_set=samples),
        )
        return _order_rows(self.table.filter(mask).to_pylist(), keys)


@dataclass
class DatasetSource(GraspSource):
    """Every Parquet file under a directory, as one dataset.

    Attributes
    ----------
    directory : pathlib.Path
        A dataset, or any directory of sample-row Parquet files (read loosely).
    name : str
        Shown in captions (the directory when empty).
    files : list of str
        The Parquet files found (filled in on construction).
    hand : Hand or None
        The hand the dataset's manifest records (filled in on construction; None for a
        directory without a manifest).
    dataset : Dataset or None
        The opened dataset (filled in on construction; None for a directory of loose
        Parquet files, whose rows alone say what they are).
    """

    directory: Path
    name: str = ""
    files: list[str] = field(default_factory=list)
    hand: Hand | None = None
    dataset: Dataset | None = None

    def __post_init__(self) -> None:
        if isinstance(self.directory, Dataset):
            self.dataset = self.directory
        self.directory = Path(self.directory)
        self.name = self.name or str(self.directory)
        if self.dataset is None:
            try:
                self.dataset = Dataset.open(self.directory)
            except DatasetError:
                self.dataset = None  # loose Parquet files: the rows' hand column names the hand
        if self.dataset is not None:
            self._dataset = self.dataset.arrow()
        else:
            self._dataset = open_dataset(self.directory, loose=True)
        self.files = list(self._dataset.files)
        if self.hand is None and self.dataset is not None:
            self.hand = self.dataset.hand

    def schema(self) -> pa.Schema:
        return self._dataset.schema

    def scan(self, columns: Sequence[str]) -> Iterator[pa.Table]:
        scanner = self._dataset.scanner(columns=list(columns), batch_size=BATCH_ROWS)
        with read_errors(self.directory):
            for batch in scanner.to_batches():
                if batch.num_rows:
                    yield pa.Table.from_batches([batch])

    def fetch(self, obj: str, keys: Sequence[tuple[int, int]]) -> list[dict]:
        samples = pa.array(sorted({k[1] for k in keys}), pa.int64())
        flt = (pads.field("object") == obj) & pads.field("sample").isin(samples)
        with read_errors(self.directory):
            table = self._dataset.to_table(filter=flt)
        return _order_rows(table.to_pylist(), keys)


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
    source: GraspSource,
    tasks: Sequence,
    *,
    mode: str = "default",
    top: int = 4,
    thresholds: dict[str, dict[str, float]] | None = None,
    progress=None,
    robust: bool = False,
) -> dict[tuple[str, str], TaskRanking]:
    """The ``top`` best rows per (object, task) by the tasks' scores.

    Higher is better; -inf and NaN never count.

    Parameters
    ----------
    source : GraspSource
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
    thresholds = thresholds or {}
    columns = source.scalar_columns()
    kept: dict[tuple[str, str], TopRows] = {}  # ties by (seed, sample)
    counts: dict[tuple[str, str], list[int]] = {}
    for table in source.scan(columns):
        objects = table.column("object").combine_chunks().dictionary_encode()
        names = objects.dictionary.to_pylist()
        codes = objects.indices.to_numpy(zero_copy_only=False)
        seeds = table.column("seed").to_numpy().astype(np.int64)
        samples = table.column("sample").to_numpy().astype(np.int64)
        numeric = numeric_columns(table)
        # Rows grouped by object once per batch (a batch may hold many objects).
        order = np.argsort(codes, kind="stable")
        bounds = np.concatenate([[0], np.cumsum(np.bincount(codes, minlength=len(names)))])
        for task in tasks:
            scores = task_values(task, numeric, mode, thresholds.get(task.name), robust=robust)
            for code, name in enumerate(names):
                rows = order[bounds[code] : bounds[code + 1]]
                key = (name, task.name)
                c = counts.setdefault(key, [0, 0])
                c[0] += len(rows)
                ranking = kept.setdefault(key, TopRows(top, 2))
                c[1] += ranking.add(scores[rows], seeds[rows], samples[rows])
        if progress is not None:
            progress(table.num_rows)
    out: dict[tuple[str, str], TaskRanking] = {}
    for key, (scored, accepted) in counts.items():
        ranking = TaskRanking(key[0], key[1], scored, accepted)
        if key in kept and len(kept[key].values):
            scores, (seeds, samples) = kept[key].values, kept[key].keys
            keys = [(int(a), int(b)) for a, b in zip(seeds, samples, strict=True)]
            rows = source.fetch(key[0], keys)
            by_key = {(int(r["seed"]), int(r["sample"])): r for r in rows}
            for rank, (s, k) in enumerate(zip(scores, keys, strict=True), start=1):
                if k in by_key:
                    ranking.best.append(
                        RankedGrasp(key[0], key[1], rank, float(s), k[0], k[1], by_key[k])
                    )
        out[key] = ranking
    return out


def is_dataset_path(spec: str | os.PathLike) -> bool:
    """Whether ``spec`` names a directory (read as a dataset) rather than an object.

    Parameters
    ----------
    spec : str or os.PathLike

    Returns
    -------
    bool
    """
    return Path(spec).expanduser().is_dir()
