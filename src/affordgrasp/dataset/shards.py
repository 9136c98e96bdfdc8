"""A dataset's shards: planned, written atomically, checked against the plan.

A dataset directory holds::

    DIR/_manifest.json                    the plan: what the command asked for (written first)
    DIR/_card.json, DIR/_card.md          the dataset card (written when a run ends)
    DIR/_checksums.jsonl                  a BLAKE2b checksum of each shard file as written
    DIR/part-OOOOO-SSSSSSSSSSSS.parquet   one shard: object O, samples S .. S+shard_size-1

The plan is a pure function of the command (:mod:`.manifest`): object ``o`` gets samples
``0 .. samples-1`` and shard ``k`` of it holds samples ``k*shard_size ..
min((k+1)*shard_size, samples)-1`` in order. A shard is written to a hidden temporary name
and renamed into place only when complete and synced, so a shard file that exists is whole;
resuming skips every valid shard. A shard changed afterwards no longer matches the checksum
recorded when it was written (:mod:`.checksums`) or the plan: resuming writes it again, and
readers refuse it, naming the file, as they refuse a planned shard that was written and is
gone and a shard file outside the plan (:func:`check_shards`).

Names starting with ``_`` or ``.`` are ignored by Arrow datasets, so pandas, polars and
DuckDB read the directory (or ``DIR/*.parquet``) as one table.
"""

from __future__ import annotations

import json
import logging
import os
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from ..columns import METRIC_COLUMNS
from ..errors import DatasetError, InternalError
from ..runtime import writing
from .checksums import CHECKSUM_ALGORITHM, read_checksums, record_checksum, shard_damage
from .manifest import CARD_JSON_NAME, MANIFEST_NAME

log = logging.getLogger(__name__)

SHARD_META_KEY = b"affordgrasp_shard"
DEFAULT_SHARD_SIZE = 4096
COMPRESSION = "zstd"

_SHARD_RE = re.compile(r"^part-(\d{5})-(\d{12})\.parquet$")
_TMP_RE = re.compile(
    r"^\.(part-\d{5}-\d{12}\.parquet|_manifest\.json|_card\.json|_card\.md)\.tmp(-\d+)?$"
)


@dataclass(frozen=True)
class Shard:
    """One planned shard: samples ``start .. stop-1`` of object number ``object_index``.

    Attributes
    ----------
    object_index : int
        Index of the object in the manifest.
    start, stop : int
        First sample and one past the last.
    """

    object_index: int
    start: int
    stop: int

    @property
    def name(self) -> str:
        """The shard's file name, ``part-OOOOO-SSSSSSSSSSSS.parquet``."""
        return f"part-{self.object_index:05d}-{self.start:012d}.parquet"

    @property
    def rows(self) -> int:
        """Rows in the shard."""
        return self.stop - self.start


def plan_shards(n_objects: int, samples: int, shard_size: int) -> list[Shard]:
    """Every shard of a run, objects in order, then samples in order.

    Parameters
    ----------
    n_objects : int
    samples : int
        Samples per object.
    shard_size : int
        Rows per shard (the last shard of an object may be shorter).

    Returns
    -------
    list of Shard

    Raises
    ------
    DatasetError
        When ``shard_size`` < 1.
    """
    if shard_size < 1:
        raise DatasetError(f"shard size must be a positive integer, got {shard_size}")
    return [
        Shard(o, start, min(start + shard_size, samples))
        for o in range(n_objects)
        for start in range(0, samples, shard_size)
    ]


def shard_paths(directory: str | os.PathLike) -> list[Path]:
    """The shard files of a dataset directory, in plan order.

    Parameters
    ----------
    directory : path

    Returns
    -------
    list of pathlib.Path
    """
    directory = Path(directory)
    return sorted(p for p in directory.iterdir() if _SHARD_RE.match(p.name))


def shard_metadata(shard: Shard, object_name: str, status_counts: dict[str, int]) -> dict:
    """The facts a shard records in its Parquet footer.

    Parameters
    ----------
    shard : Shard
    object_name : str
    status_counts : dict of str to int
        Rows per grasp status.

    Returns
    -------
    dict
        ``object``, ``object_index``, ``start``, ``stop``, ``status_counts``.
    """
    return {
        "object": object_name,
        "object_index": shard.object_index,
        "start": shard.start,
        "stop": shard.stop,
        "status_counts": status_counts,
    }


def write_shard(directory: Path, shard: Shard, table: pa.Table, info: dict) -> Path:
    """Write one complete shard atomically, with its checksum.

    The checksum is recorded by :func:`~affordgrasp.runtime.writing.atomic_write`'s
    ``before_replace`` hook, so a shard in place always has one.

    Parameters
    ----------
    directory : pathlib.Path
    shard : Shard
    table : pyarrow.Table
        Exactly ``shard.rows`` rows.
    info : dict
        Footer facts (:func:`shard_metadata`).

    Returns
    -------
    pathlib.Path
        The shard file.

    Raises
    ------
    InputError
        When it cannot be written (:func:`~affordgrasp.runtime.writing.atomic_write`).
    InternalError
        When the table does not have the planned row count.
    """
    if table.num_rows != shard.rows:
        raise InternalError(f"shard {shard.name} has {table.num_rows} rows, expected {shard.rows}")
    metadata = dict(table.schema.metadata or {})
    metadata[SHARD_META_KEY] = json.dumps(info, sort_keys=True).encode()
    table = table.replace_schema_metadata(metadata)
    final = directory / shard.name
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink, compression=COMPRESSION, row_group_size=max(1, shard.rows))
    data = sink.getvalue().to_pybytes()
    # The checksum is on disk before the shard: a shard in place always has one.
    writing.atomic_write(
        final, data, before_replace=lambda: record_checksum(directory, shard.name, data)
    )
    return final


# Shards this process has found as planned: (path, size, mtime_ns, shard, seed, mesh hash, exact).
_AS_PLANNED: set[tuple] = set()
# The columns a shard's rows are checked on (whose object, which seed, which samples).
REQUIRED_KEYS = ("object", "object_hash", "seed", "sample")
# Columns added since the first release: a shard an earlier version wrote may lack them
# (they read as null); every other column of the dataset's schema it has.
ADDED_COLUMNS = frozenset(
    ("contact_parts", "use_part", *METRIC_COLUMNS[METRIC_COLUMNS.index("use_edge_angle") + 1 :])
)


def shard_foreign(
    path: Path, shard: Shard, manifest: dict, schema: pa.Schema, *, exact: bool = False
) -> str | None:
    """Why the shard file at ``path`` is not the planned ``shard`` of this dataset.

    Its footer must name the planned object and sample range, it must hold the planned rows
    of the dataset's object (``object_hash``) and seed, samples in order, and its columns
    must be the dataset's: all of them (``exact``), or all but some of ``ADDED_COLUMNS``
    (a shard written by an earlier version lacks those; they read as null). A file found as
    planned once in this process is not read again.

    Parameters
    ----------
    path : pathlib.Path
    shard : Shard
        What the plan puts under that name.
    manifest : dict
        The dataset's manifest (its objects, their hashes and seeds).
    schema : pyarrow.Schema
        The dataset's row schema (:func:`~affordgrasp.schema.dataset_schema`).
    exact : bool
        Require exactly ``schema`` (a resume writes no shard of another version).

    Returns
    -------
    str or None
        The reason, as a phrase; None when the file is the planned shard.
    """
    entry = manifest["objects"][shard.object_index]
    seed = int(entry.get("seed", manifest["seed"]))
    try:
        stat = path.stat()
        key = (path, stat.st_size, stat.st_mtime_ns, shard, seed, entry.get("mesh_hash"), exact)
        if key in _AS_PLANNED:
            return None
        file = pq.ParquetFile(path)
        meta = file.metadata
    except (OSError, pa.ArrowException) as exc:
        return f"it cannot be read as Parquet ({' '.join(str(exc).split())})"
    info = _footer_facts(meta)
    planned = (entry["name"], shard.object_index, shard.start, shard.stop)
    if info is None:
        return "it was not written by 'affordgrasp generate' (its footer has no shard facts)"
    if tuple(info.get(k) for k in ("object", "object_index", "start", "stop")) != planned:
        return (
            f"its footer says it holds {info.get('object')!r} samples {info.get('start')} to "
            f"{info.get('stop')}, the plan {entry['name']!r} samples {shard.start} to {shard.stop}"
        )
    if meta.num_rows != shard.rows:
        return f"it has {meta.num_rows} rows, the plan {shard.rows}"
    have, want = meta.schema.to_arrow_schema(), schema
    odd = [f.name for f in have if f.name not in want.names or want.field(f.name).type != f.type]
    absent = [n for n in want.names if n not in have.names and (exact or n not in ADDED_COLUMNS)]
    if odd or absent:
        listed = [", ".join(n[:4]) + f" (+{len(n) - 4})" * (len(n) > 4) for n in (absent, odd)]
        return (
            f"its columns are not the dataset's (missing: {listed[0] or 'none'}; unexpected or "
            f"of another type: {listed[1] or 'none'})"
        )
    try:
        rows = file.read(columns=list(REQUIRED_KEYS))
    except (OSError, pa.ArrowException) as exc:
        return f"its rows cannot be read ({' '.join(str(exc).split())})"
    for column, value, what in (
        ("object", entry["name"], "object"),
        ("object_hash", entry.get("mesh_hash"), "mesh (object_hash)"),
        ("seed", seed, "seed"),
    ):
        found = sorted(rows.column(column).unique().to_pylist(), key=str)
        if value is not None and found != [value]:
            return (
                f"its rows are of {what} {', '.join(map(str, found[:3]))}, "
                f"the dataset's {entry['name']!r} of {value} (it belongs to another dataset)"
            )
    samples = rows.column("sample").to_numpy()
    if not np.array_equal(samples, np.arange(shard.start, shard.stop)):
        return f"its rows are not samples {shard.start} to {shard.stop - 1} in order"
    _AS_PLANNED.add(key)
    return None


def check_shards(
    directory: Path, paths: list[Path], manifest: dict, schema: pa.Schema, *, content: bool = True
) -> None:
    """Refuse a dataset whose shards are not those of its plan, naming the file and the fix.

    The plan (:func:`plan_shards` of the manifest's objects, samples and shard size) is the
    shard list: a shard file outside it is refused; a planned shard that was written (its
    checksum is recorded, or the card says the run completed) and is gone is refused; planned
    shards never written (a run interrupted or still going) are named in a warning. With
    ``content``, each shard must also be as written (:func:`shard_damage`; datasets older than
    checksums, format version 1, skip this with a warning) and the planned one
    (:func:`shard_foreign`).

    Parameters
    ----------
    directory : pathlib.Path
    paths : list of pathlib.Path
        The shard files on disk (:func:`shard_paths`).
    manifest : dict
        The dataset's manifest (its plan, format version and command).
    schema : pyarrow.Schema
        Its row schema.
    content : bool
        Also check every shard's bytes and footer.

    Raises
    ------
    DatasetError
        Naming the first shard in question, how many more there are and what to do.
    """
    try:
        plan = {
            s.name: s
            for s in plan_shards(
                len(manifest["objects"]), int(manifest["samples"]), int(manifest["shard_size"])
            )
        }
    except (KeyError, TypeError, ValueError) as exc:
        raise DatasetError(
            f"{str(directory / MANIFEST_NAME)!r} is damaged (no valid {exc} entry); restore it "
            "or generate the dataset again"
        ) from exc
    command = manifest.get("command")
    rerun = (
        f"`{shlex.join(command)}`"
        if command
        else f"'affordgrasp generate' with the dataset's options and --out {str(directory)!r}"
    )

    def refuse(problem: str, names: list[str], fix: str) -> DatasetError:
        more = f" (and {len(names) - 1} more)" if len(names) > 1 else ""
        return DatasetError(f"dataset {str(directory)!r} {problem} {names[0]}{more}; {fix}")

    extra = [p.name for p in paths if p.name not in plan]
    if extra:
        raise refuse(
            "holds a shard file its plan has no place for,",
            extra,
            "remove the file (it belongs to another dataset)",
        )
    on_disk = {p.name for p in paths}
    missing = [name for name in plan if name not in on_disk]
    records = read_checksums(directory)
    if missing:
        try:  # the card of a run that completed (format version 1 records no checksums)
            finished = json.loads((directory / CARD_JSON_NAME).read_text())["complete"] is True
        except (OSError, ValueError, KeyError, TypeError):
            finished = False
        lost = [name for name in missing if finished or name in records]
        if lost:
            raise refuse("has lost the shard", lost, f"resume the generation with {rerun}")
        log.warning(
            "dataset %s is unfinished: %d of its %d shards (%d of %d rows) are not written yet; "
            "resume the generation with %s to finish it",
            directory,
            len(missing),
            len(plan),
            sum(plan[name].rows for name in missing),
            sum(s.rows for s in plan.values()),
            rerun,
        )
    if not content:
        return
    checksums = manifest.get("format_version", 1) >= 2
    if not checksums:
        log.warning(
            "dataset %s predates shard checksums: damaged shards cannot be detected", directory
        )
    bad = []
    record = _checked_record(directory, manifest, schema)
    checked = _read_checked(record)
    passed = set()

    def check(path: Path) -> tuple[str | None, str | None]:
        key = _checked_key(path, records.get(path.name))
        if key is not None and key in checked:
            return key, None
        why = shard_damage(path, records.get(path.name)) if checksums else None
        return key, why or shard_foreign(path, plan[path.name], manifest, schema)

    # threads: the hashing and the Parquet reads release the GIL (a 10⁷-row dataset's first
    # check, 5.5 GB, takes half the time on two cores)
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1)) as pool:
        for path, (key, why) in zip(paths, pool.map(check, paths), strict=True):
            if why is not None:
                bad.append(f"{path.name}: {why}")
            elif key is not None:
                passed.add(key)
    if passed != checked:
        _write_checked(record, passed)
    if bad:
        raise refuse(
            "has a damaged or foreign shard,",
            bad,
            f"run the command that made it again to rewrite it: {rerun}",
        )


# What this machine found as written and as planned, between processes: a shard whose name,
# size, modification time, inode and recorded checksum are those it had when checked is not
# read again (a 10⁷-row dataset: 2,500 shards, 5.5 GB, about 8 s to read, hash and check).
# One file per dataset under the user cache, for this code, manifest and schema.
CHECKED_VERSION = 1


def _checked_record(directory: Path, manifest: dict, schema: pa.Schema) -> Path:
    import hashlib

    from .._version import __version__
    from ..caching import cache_dir

    key = json.dumps(
        [
            CHECKED_VERSION,
            __version__,
            str(Path(directory).resolve()),
            manifest,
            schema.to_string(show_schema_metadata=False),
        ],
        sort_keys=True,
        default=str,
    )
    return cache_dir() / "checked" / f"{hashlib.sha256(key.encode()).hexdigest()[:32]}.json"


def _checked_key(path: Path, record: dict | None) -> str | None:
    try:
        st = path.stat()
    except OSError:
        return None
    checksum = None if record is None else record.get(CHECKSUM_ALGORITHM)
    return f"{path.name}:{st.st_size}:{st.st_mtime_ns}:{st.st_ino}:{checksum}"


def _read_checked(record: Path) -> set[str]:
    try:
        keys = json.loads(record.read_text())
    except (OSError, ValueError):
        return set()
    return set(keys) if isinstance(keys, list) else set()


def _write_checked(record: Path, keys: set[str]) -> None:
    try:
        record.parent.mkdir(parents=True, exist_ok=True)
        writing.atomic_write(record, json.dumps(sorted(keys)).encode())
    except OSError as exc:  # a cache that cannot be written: the next reader checks again
        log.debug("could not record the checked shards in %s: %s", record, exc)


def _footer_facts(meta: pq.FileMetaData) -> dict | None:
    """The shard facts (:func:`shard_metadata`) in a Parquet footer; None when it has none."""
    try:
        info = json.loads((meta.metadata or {}).get(SHARD_META_KEY, b"null"))
    except ValueError:
        return None
    return info if isinstance(info, dict) else None


def read_shard_info(path: Path) -> dict | None:
    """The shard's footer facts.

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    dict or None
        :func:`shard_metadata`'s facts plus ``num_rows`` and the Arrow ``schema``; None when
        the file or its footer cannot be read.
    """
    try:
        meta = pq.read_metadata(path)
    except (OSError, pa.ArrowException):
        return None
    info = _footer_facts(meta)
    if info is not None:
        info.update(num_rows=meta.num_rows, schema=meta.schema.to_arrow_schema())
    return info


def valid_shard_info(
    directory: Path,
    shard: Shard,
    manifest: dict,
    schema: pa.Schema,
    checksums: dict[str, dict] | None = None,
) -> dict | None:
    """The footer facts of a shard already on disk when it is whole and as planned.

    A shard that is damaged (:func:`shard_damage`) or not the planned one
    (:func:`shard_foreign`, schema exactly the run's) is deleted, so that it is written again.

    Parameters
    ----------
    directory : pathlib.Path
    shard : Shard
    manifest : dict
        The run's manifest.
    schema : pyarrow.Schema
        The run's row schema.
    checksums : dict, optional
        :func:`read_checksums` (read here when not given).

    Returns
    -------
    dict or None
        :func:`read_shard_info`'s facts; None when the shard must be (re)written.
    """
    path = directory / shard.name
    if not path.exists():
        return None
    if checksums is None:
        checksums = read_checksums(directory)
    damage = shard_damage(path, checksums.get(shard.name)) or shard_foreign(
        path, shard, manifest, schema, exact=True
    )
    info = read_shard_info(path) if damage is None else None
    if info is None:
        # Only a file changed after it was written gets here (writes are atomic): redo it.
        log.warning(
            "shard %s is damaged or not as planned (%s); it will be written again",
            path,
            damage or "its footer cannot be read",
        )
        path.unlink()
        return None
    return info


def remove_stale_temporaries(directory: Path) -> int:
    """Delete half-written files left by a run that was killed.

    Parameters
    ----------
    directory : pathlib.Path

    Returns
    -------
    int
        How many were removed.
    """
    removed = 0
    for p in directory.iterdir():
        if _TMP_RE.match(p.name):
            p.unlink(missing_ok=True)
            removed += 1
    return removed
