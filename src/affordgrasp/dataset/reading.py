"""Reading a generated dataset back: the shards as one Arrow dataset, streamed in batches.

pandas, polars and DuckDB read a dataset directory directly as well (see docs/dataset.md);
these functions add the checks: that the directory is an affordgrasp dataset, which objects it
holds, and that every shard is the file that was written (its checksum, see
:func:`affordgrasp.dataset.layout.verify_shards`). A file that cannot be read is reported as
a :class:`~affordgrasp.errors.DatasetError` naming it, never as a raw Arrow error.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Iterator, Sequence
from pathlib import Path

import pyarrow as pa
import pyarrow.dataset as pads
import pyarrow.parquet as pq

from ..errors import DatasetError
from ..hands.model import Hand
from .layout import manifest_volume, read_manifest, shard_paths, verify_shards

# Columns without which Parquet files are not affordgrasp samples (see docs/conventions.md).
REQUIRED_COLUMNS = ("object", "sample", "seed", "hand_pose", "joints")


def open_dataset(
    directory: str | os.PathLike,
    *,
    loose: bool = False,
    verify: bool = True,
    manifest: dict | None = None,
) -> pads.Dataset:
    """The shards of a dataset directory as one ``pyarrow.dataset.Dataset`` (plan order).

    Parameters
    ----------
    directory : path
        A directory written by ``affordgrasp generate``.
    loose : bool
        Also accept a directory without a (valid) manifest: every ``*.parquet`` file under it
        (not in hidden folders) whose columns are those of sample rows, e.g. files written
        by ``affordgrasp evaluate --out``. Their footers are checked, not checksums.
    verify : bool
        Check every shard against the checksum recorded when it was written (reads each
        file once per process; see docs/dataset.md for the cost).
    manifest : dict, optional
        The directory's manifest when already read (:class:`~affordgrasp.dataset.handle.Dataset`
        passes its own); read here otherwise.

    Returns
    -------
    pyarrow.dataset.Dataset

    Raises
    ------
    DatasetError
        When the directory is missing, not a dataset, empty or unreadable, or a shard is
        damaged (the message names it and the command that rewrites it).
    """
    from ..schema import dataset_schema

    try:
        manifest = read_manifest(directory) if manifest is None else manifest
    except DatasetError:
        if not loose:
            raise
        return _open_loose_files(Path(directory))
    paths = shard_paths(directory)
    if not paths:
        raise DatasetError(
            f"dataset {str(directory)!r} has no shards yet; run the command in its "
            "_manifest.json to generate them"
        )
    if verify:
        verify_shards(Path(directory), paths, manifest)
    from ..robust import manifest_robust

    schema = dataset_schema(
        manifest.get("metrics", True), bool(manifest.get("depth")), manifest_robust(manifest)
    )
    return pads.dataset([str(p) for p in paths], format="parquet", schema=schema)


@contextlib.contextmanager
def read_errors(where: str | os.PathLike):
    """Turn an Arrow or OS error while reading into a DatasetError naming the damaged file.

    A context manager.

    Parameters
    ----------
    where : path
        Named in the message when the error does not name a file.
    """
    try:
        yield
    except (pa.ArrowException, OSError) as exc:
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        match = re.search(r"[\w./\\:-]*\.parquet", text)
        culprit = match.group(0) if match else str(where)
        raise DatasetError(
            f"cannot read {culprit!r}: {text}; the file is damaged or not Parquet: delete it "
            "(and, for a dataset, run its generate command again to rewrite it)"
        ) from exc


def _open_loose_files(directory: Path) -> pads.Dataset:
    if not directory.is_dir():
        raise DatasetError(f"{str(directory)!r} is not a directory")
    files = sorted(
        str(p)
        for p in directory.rglob("*.parquet")
        if p.is_file() and not any(part.startswith(".") for part in p.relative_to(directory).parts)
    )
    if not files:
        raise DatasetError(
            f"no Parquet files under {str(directory)!r}; give a dataset directory "
            "written by 'affordgrasp generate', or an object (family, family:seed or mesh path)"
        )
    for file in files:
        # Footers only: a truncated or foreign file is named before any scan.
        with read_errors(file):
            try:
                pq.read_metadata(file)
            except (pa.ArrowException, OSError) as exc:
                raise pa.ArrowInvalid(f"{file}: {exc}") from exc
    with read_errors(directory):
        dataset = pads.dataset(files, format="parquet")
    missing = set(REQUIRED_COLUMNS) - set(dataset.schema.names)
    if missing:
        raise DatasetError(
            f"the Parquet files under {str(directory)!r} lack the columns {sorted(missing)}; "
            "they do not look like an affordgrasp dataset (see docs/conventions.md)"
        )
    return dataset


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
    return manifest_volume(read_manifest(directory))


def manifest_hand(manifest: dict) -> Hand:
    """The hand a dataset was generated with, rebuilt from its manifest.

    Parameters
    ----------
    manifest : dict
        A dataset's ``_manifest.json`` (:func:`~affordgrasp.dataset.layout.read_manifest`).

    Returns
    -------
    Hand
        The hand recorded whole under ``hand_spec``; for a manifest written before hands
        were recorded whole (``hand`` holds only a name), the registered hand of that name.
    """
    from ..hands import get_hand, hand_from_dict

    spec = manifest.get("hand_spec")
    if isinstance(spec, dict):
        return hand_from_dict(spec)
    return get_hand(str(manifest.get("hand") or "barrett"))


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
    return manifest_hand(read_manifest(directory))


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
    return [o["name"] for o in read_manifest(directory)["objects"]]


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
    if not wanted:
        return None
    return match_objects(dataset_objects(directory), wanted, directory)


def match_objects(
    names: Sequence[str], wanted: Sequence[str], where: str | os.PathLike
) -> list[str]:
    """The names among a dataset's objects that ``wanted`` means (``knife`` is ``knife:0``).

    Parameters
    ----------
    names : sequence of str
        The dataset's objects.
    wanted : sequence of str
        Names, families or mesh paths.
    where : path
        The dataset, named in the error.

    Returns
    -------
    list of str

    Raises
    ------
    DatasetError
        For a name that matches nothing (the message names the objects available).
    """
    names = list(names)
    chosen = []
    for w in wanted:
        w = w.strip()
        if w in names:
            chosen.append(w)
        elif f"{w}:0" in names:
            chosen.append(f"{w}:0")
        elif os.path.basename(w) in names:
            chosen.append(os.path.basename(w))
        else:
            raise DatasetError(
                f"object {w!r} is not in dataset {str(where)!r}; it holds: {', '.join(names)}"
            )
    return chosen


def object_filter(objects: Sequence[str] | None) -> pads.Expression | None:
    """An Arrow filter keeping the rows of some objects.

    Parameters
    ----------
    objects : sequence of str or None
        Object names; None or empty keeps every row.

    Returns
    -------
    pyarrow.dataset.Expression or None
    """
    if not objects:
        return None
    return pads.field("object").isin(list(objects))


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
    dataset = open_dataset(directory)
    scanner = dataset.scanner(
        columns=list(columns) if columns is not None else None,
        filter=object_filter(select_objects(directory, objects)),
        batch_size=batch_size,
    )
    with read_errors(directory):
        yield from scanner.to_batches()


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
    dataset = open_dataset(directory)
    with read_errors(directory):
        return dataset.to_table(
            columns=list(columns) if columns is not None else None,
            filter=object_filter(select_objects(directory, objects)),
        )


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
