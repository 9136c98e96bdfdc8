"""Where the grasps to show come from: a dataset directory or an in-memory table.

A dataset directory is read by :func:`affordgrasp.dataset.handle.open_dataset` (its shards,
or every ``*.parquet`` file under a directory without a manifest), streamed in batches so
that datasets larger than memory can be ranked and plotted:
:func:`affordgrasp.search.best.top_grasps` keeps the best ``k`` rows per object and task
with one pass over the scalar columns, then fetches only those rows in full.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as pads

from ..dataset.handle import Dataset, open_dataset, read_errors, scan_files
from ..errors import DatasetError
from ..hands.model import Hand

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

    def count_rows(self) -> int:
        """How many rows :meth:`scan` yields.

        Returns
        -------
        int
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

    def count_rows(self) -> int:
        """Rows held.

        Returns
        -------
        int
        """
        return self.table.num_rows

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

    def count_rows(self) -> int:
        """Rows in the files (a dataset's from its plan, loose files' from their footers).

        Returns
        -------
        int
        """
        if self.dataset is not None:
            return self.dataset.count_rows()
        with read_errors(self.directory):
            return self._dataset.count_rows()

    def scan(self, columns: Sequence[str]) -> Iterator[pa.Table]:
        with read_errors(self.directory):
            for batch in scan_files(self._dataset, list(columns), batch_size=BATCH_ROWS):
                if batch.num_rows:
                    yield pa.Table.from_batches([batch])

    def fetch(self, obj: str, keys: Sequence[tuple[int, int]]) -> list[dict]:
        samples = pa.array(sorted({k[1] for k in keys}), pa.int64())
        flt = (pads.field("object") == obj) & pads.field("sample").isin(samples)
        with read_errors(self.directory):
            table = self._dataset.to_table(filter=flt)
        return _order_rows(table.to_pylist(), keys)


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
