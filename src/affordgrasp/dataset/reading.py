"""Reading a generated dataset back: the shards as one Arrow dataset, streamed in batches.

pandas, polars and DuckDB read a dataset directory directly as well (see docs/dataset.md);
these functions add the checks: that the directory is an affordgrasp dataset, which objects it
holds, and that the shards are the plan's, each the file written for it (see
:func:`affordgrasp.dataset.shards.check_shards`). A file that cannot be read is reported as
a :class:`~affordgrasp.errors.DatasetError` naming it, never as a raw Arrow error.

Each takes a dataset (a directory, opened here, or a :class:`~affordgrasp.dataset.handle.Dataset`
already open, which many reads share).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import pyarrow as pa

from ..hands.model import Hand
from .handle import Dataset, DatasetLike

__all__ = ["dataset_hand", "dataset_volume", "iter_batches", "read_dataset", "select_objects"]


def dataset_volume(dataset: DatasetLike) -> bool:
    """Whether a dataset's ``gws_volume`` column holds computed GWS volumes.

    Generated with ``--metrics +volume`` (``volume=True``); otherwise the column is there,
    null. A dataset written before the volume became optional computed it with every
    metric (its manifest has no ``volume`` entry).

    Parameters
    ----------
    dataset : path or Dataset
        A dataset directory.

    Returns
    -------
    bool
    """
    return Dataset.open(dataset).volume


def dataset_hand(dataset: DatasetLike) -> Hand:
    """The hand a dataset was generated with (custom hands included).

    Parameters
    ----------
    dataset : path or Dataset

    Returns
    -------
    Hand
        See :func:`~affordgrasp.dataset.handle.manifest_hand`.
    """
    return Dataset.open(dataset).hand


def select_objects(dataset: DatasetLike, wanted: Sequence[str] | None) -> list[str] | None:
    """Object names in the dataset matching ``wanted`` (``knife`` matches ``knife:0``).

    Parameters
    ----------
    dataset : path or Dataset
        A dataset directory.
    wanted : sequence of str or None
        As for :meth:`~affordgrasp.dataset.handle.Dataset.select` (its result and errors).

    Returns
    -------
    list of str or None
    """
    return Dataset.open(dataset).select(wanted)


def iter_batches(
    dataset: DatasetLike,
    *,
    columns: Sequence[str] | None = None,
    objects: Sequence[str] | None = None,
    batch_size: int = 65536,
) -> Iterator[pa.RecordBatch]:
    """Stream the rows of a dataset (optionally some columns, some objects) in batches.

    Parameters
    ----------
    dataset : path or Dataset
        A dataset directory (checksums verified first).
    columns : sequence of str, optional
        Columns to read; all when None.
    objects : sequence of str, optional
        Objects to read (as for :func:`select_objects`); all when None.
    batch_size : int
        Rows per batch at most.

    Yields
    ------
    pyarrow.RecordBatch
    """
    yield from Dataset.open(dataset).batches(
        columns=columns, objects=objects, batch_size=batch_size
    )


def read_dataset(
    dataset: DatasetLike,
    *,
    columns: Sequence[str] | None = None,
    objects: Sequence[str] | None = None,
) -> pa.Table:
    """A whole dataset (or some columns/objects of it) as one Arrow table: for small datasets.

    Parameters
    ----------
    dataset : path or Dataset
        A directory written by :func:`affordgrasp.generate` / ``affordgrasp generate``.
    columns : sequence of str, optional
        Read only these columns (docs/conventions.md lists them).
    objects : sequence of str, optional
        Read only these objects (``knife`` matches ``knife:0``).

    Returns
    -------
    pyarrow.Table
        One row per sample, in plan order. Use :func:`iter_batches` for larger datasets.
    """
    return Dataset.open(dataset).read(columns=columns, objects=objects)
