"""Reading a generated dataset back: the shards as one Arrow dataset, streamed in batches.

pandas, polars and DuckDB read a dataset directory directly as well (see docs/dataset.md);
these functions add the checks: that the directory is an affordgrasp dataset, which objects it
holds, and that the shards are the plan's, each the file written for it (see
:func:`affordgrasp.dataset.shards.check_shards`). A file that cannot be read is reported as
a :class:`~affordgrasp.errors.DatasetError` naming it, never as a raw Arrow error.

They take a directory and open it each call; :class:`~affordgrasp.dataset.handle.Dataset`
(which they use) opens it once for many reads.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import pyarrow as pa

from ..hands.model import Hand
from .handle import (
    REQUIRED_COLUMNS,
    Dataset,
    manifest_hand,
    match_objects,
    object_filter,
    open_dataset,
    read_errors,
)
from .manifest import read_manifest

__all__ = [
    "REQUIRED_COLUMNS",
    "Dataset",
    "dataset_dir",
    "dataset_hand",
    "dataset_objects",
    "dataset_volume",
    "iter_batches",
    "manifest_hand",
    "match_objects",
    "object_filter",
    "open_dataset",
    "read_dataset",
    "read_errors",
    "read_manifest",
    "select_objects",
]


def dataset_volume(directory: str | os.PathLike) -> bool:
    """Whether a dataset's ``gws_volume`` column holds computed GWS volumes.

    Generated with ``--metrics +volume`` (``volume=True``); otherwise the column is there,
    null. A dataset written before the volume became optional computed it with every
    metric (its manifest has no ``volume`` entry).

    Parameters
    ----------
    directory : path
        A dataset directory.

    Returns
    -------
    bool
    """
    return Dataset.open(directory).volume


def dataset_hand(directory: str | os.PathLike) -> Hand:
    """The hand a dataset directory was generated with (custom hands included).

    Parameters
    ----------
    directory : path
        A directory written by ``affordgrasp generate``.

    Returns
    -------
    Hand
        See :func:`manifest_hand`.
    """
    return Dataset.open(directory).hand


def dataset_objects(directory: str | os.PathLike) -> list[str]:
    """Names of the objects of a dataset, in the order they were given.

    Parameters
    ----------
    directory : path
        A dataset directory.

    Returns
    -------
    list of str
    """
    return Dataset.open(directory).objects


def select_objects(directory: str | os.PathLike, wanted: Sequence[str] | None) -> list[str] | None:
    """Object names in the dataset matching ``wanted`` (``knife`` matches ``knife:0``).

    Parameters
    ----------
    directory : path
        A dataset directory.
    wanted : sequence of str or None
        Names or families; None or empty selects every object.

    Returns
    -------
    list of str or None
        None when every object is selected.

    Raises
    ------
    DatasetError
        For a name that matches nothing (the message names the objects available).
    """
    return Dataset.open(directory).select(wanted)


def iter_batches(
    directory: str | os.PathLike,
    *,
    columns: Sequence[str] | None = None,
    objects: Sequence[str] | None = None,
    batch_size: int = 65536,
) -> Iterator[pa.RecordBatch]:
    """Stream the rows of a dataset (optionally some columns, some objects) in batches.

    Parameters
    ----------
    directory : path
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
    yield from Dataset.open(directory).batches(
        columns=columns, objects=objects, batch_size=batch_size
    )


def read_dataset(
    directory: str | os.PathLike,
    *,
    columns: Sequence[str] | None = None,
    objects: Sequence[str] | None = None,
) -> pa.Table:
    """A whole dataset (or some columns/objects of it) as one Arrow table: for small datasets.

    Parameters
    ----------
    directory : path
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
    return Dataset.open(directory).read(columns=columns, objects=objects)


def dataset_dir(path: str | os.PathLike) -> Path:
    """``path`` as a Path, after checking that it holds a dataset manifest.

    Parameters
    ----------
    path : path
        A dataset directory.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    DatasetError
        When it is not a dataset.
    """
    path = Path(path)
    read_manifest(path)
    return path
