"""The on-disk layout of a dataset: the plan, the manifest and the shards (conventions: Datasets).

A dataset directory holds::

    DIR/_manifest.json                    the plan: what the command asked for (written first)
    DIR/_card.json, DIR/_card.md          the dataset card (written when a run ends)
    DIR/_checksums.jsonl                  a BLAKE2b checksum of each shard file as written
    DIR/part-OOOOO-SSSSSSSSSSSS.parquet   one shard: object O, samples S .. S+shard_size-1

The plan is a pure function of the command: object ``o`` gets samples ``0 .. samples-1`` and
shard ``k`` of it holds samples ``k*shard_size .. min((k+1)*shard_size, samples)-1`` in order.
A shard is written to a hidden temporary name and renamed into place only when complete and
synced, so a shard file that exists is whole; resuming skips every valid shard. A shard
changed afterwards (overwritten in place, truncated) no longer matches the checksum recorded
when it was written: resuming writes it again, and readers refuse it, naming the file.

Names starting with ``_`` or ``.`` are ignored by Arrow datasets, so pandas, polars and
DuckDB read the directory (or ``DIR/*.parquet``) as one table.
"""

from __future__ import annotations

import errno
import hashlib
import json
import logging
import os
import re
from dataclasses import dataclass
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import DatasetError, InternalError

log = logging.getLogger(__name__)

FORMAT = "affordgrasp-dataset"
# 2: shard checksums in _checksums.jsonl.
FORMAT_VERSION = 2
MANIFEST_NAME = "_manifest.json"
CARD_JSON_NAME = "_card.json"
CARD_MD_NAME = "_card.md"
CHECKSUMS_NAME = "_checksums.jsonl"
CHECKSUM_ALGORITHM = "blake2b-128"
SHARD_META_KEY = b"affordgrasp_shard"
DEFAULT_SHARD_SIZE = 4096
COMPRESSION = "zstd"

_SHARD_RE = re.compile(r"^part-(\d{5})-(\d{12})\.parquet$")
_TMP_RE = re.compile(
    r"^\.(part-\d{5}-\d{12}\.parquet|_manifest\.json|_card\.json|_card\.md)\.tmp(-\d+)?$"
)

# Manifest keys that define the content of the dataset; a resume must match all of them.
PLAN_KEYS = (
    "robust",
    "format_version",
    "affordgrasp_version",
    "seed",
    "samples",
    "shard_size",
    "hand",
    "hand_spec",
    "metrics",
    "volume",
    "soft",
    "depth",
    "materials",
    "sample_streams",
    "objects",
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


# ---------------------------------------------------------------------------------- manifest


def write_json_atomic(path: Path, document: dict) -> None:
    """Write a JSON file so that readers see the old or the new version, never a mix.

    Parameters
    ----------
    path : pathlib.Path
    document : dict
        JSON-ready; written indented, keys in their order.
    """
    text = json.dumps(document, indent=2, sort_keys=False) + "\n"
    write_bytes_atomic(path, text.encode("utf-8"))


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write a file whole or not at all: a hidden temporary file, synced, then renamed.

    Parameters
    ----------
    path : pathlib.Path
    data : bytes

    Raises
    ------
    DatasetError
        Naming ``path`` when it cannot be written (no space left, no permission, read-only
        file system); nothing half-written is left behind.
    """
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        write_file(tmp, data)
        os.replace(tmp, path)
    except BaseException as exc:  # Ctrl-C too: no temporary left behind
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise write_error(path, exc) from exc
        raise
    _sync_directory(path.parent)


def write_file(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` and sync it to the disk (the one place files are written).

    Parameters
    ----------
    path : pathlib.Path
    data : bytes
    """
    with open(path, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())


def write_error(path: Path, exc: OSError) -> DatasetError:
    """A one-line DatasetError for a failed write, naming the path and what to do.

    Parameters
    ----------
    path : pathlib.Path
        What could not be written.
    exc : OSError
        Why (no space, no permission, ...).

    Returns
    -------
    DatasetError
        Not raised.
    """
    reason = exc.strerror or str(exc)
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        fix = "free some space (finished shards are kept) or choose another --out"
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        fix = "make it writable or choose another --out"
    else:
        fix = "check the disk and the path, or choose another --out"
    return DatasetError(f"cannot write {str(path)!r}: {reason}; {fix}")


def check_writable(directory: Path) -> None:
    """Refuse an output directory that cannot be written, before any work is done.

    The directory is created (with its parents) and a probe file written and removed.

    Parameters
    ----------
    directory : pathlib.Path

    Raises
    ------
    DatasetError
        From :func:`write_error`.
    """
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise write_error(directory, exc) from exc
    probe = directory / f".write-test-{os.getpid()}"
    try:
        write_file(probe, b"")
    except OSError as exc:
        raise write_error(directory, exc) from exc
    finally:
        try:
            probe.unlink(missing_ok=True)
        except OSError:
            pass


def read_manifest(directory: str | os.PathLike) -> dict:
    """The manifest of a dataset directory.

    Parameters
    ----------
    directory : path

    Returns
    -------
    dict
        The parsed ``_manifest.json``.

    Raises
    ------
    DatasetError
        Saying why there is none: no directory, no manifest, unreadable or foreign JSON.
    """
    directory = Path(directory)
    path = directory / MANIFEST_NAME
    if not directory.is_dir():
        raise DatasetError(
            f"dataset directory {str(directory)!r} does not exist; create one with "
            "'affordgrasp generate OBJECT... --samples N --out DIR'"
        )
    if not path.is_file():
        raise DatasetError(
            f"{str(directory)!r} is not an affordgrasp dataset (no {MANIFEST_NAME}); give the "
            "directory that 'affordgrasp generate --out' wrote"
        )
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise DatasetError(f"cannot read {str(path)!r}: {exc}") from exc
    if manifest.get("format") != FORMAT:
        raise DatasetError(f"{str(path)!r} is not an affordgrasp dataset manifest")
    return manifest


def manifest_volume(manifest: dict) -> bool:
    """Whether a dataset's ``gws_volume`` column holds computed volumes.

    Parameters
    ----------
    manifest : dict
        A dataset manifest.

    Returns
    -------
    bool
        Its ``volume`` entry; a manifest written before the volume became optional has
        none, and computed the volume whenever it computed metrics.
    """
    if "volume" in manifest:
        return bool(manifest["volume"])
    return bool(manifest.get("metrics"))


def manifest_streams(manifest: dict) -> str:
    """How a dataset's objects drew their samples: ``"per-object"`` or ``"shared"``.

    Parameters
    ----------
    manifest : dict
        A dataset manifest.

    Returns
    -------
    str
        Its ``sample_streams`` entry; a manifest written before it was recorded has none,
        and every object of it drew the run's samples (``"shared"``).
    """
    return str(manifest.get("sample_streams", "shared"))


def manifest_differences(existing: dict, requested: dict) -> list[str]:
    """Readable differences between two manifests' plans (``PLAN_KEYS``).

    Parameters
    ----------
    existing : dict
        The manifest on disk.
    requested : dict
        The manifest of the run asked for.

    Returns
    -------
    list of str
        One phrase per difference, e.g. ``"seed 0 there vs 1 here"``; empty when they agree.
    """
    diffs = []
    for key in PLAN_KEYS:
        a, b = existing.get(key), requested.get(key)
        if key == "hand_spec":
            changed = hand_spec_differences(a, b)
            if changed and existing.get("hand") == requested.get("hand"):
                diffs.append(
                    f"hand {existing.get('hand')!r}: same name, different {', '.join(changed)}"
                )
        elif key == "objects":
            a = [(o.get("name"), o.get("mesh_hash")) for o in a or []]
            b = [(o.get("name"), o.get("mesh_hash")) for o in b or []]
            if a != b:
                diffs.append(
                    f"objects {[n for n, _ in a]} there vs {[n for n, _ in b]} here"
                    + (
                        " (same names, different meshes)"
                        if [n for n, _ in a] == [n for n, _ in b]
                        else ""
                    )
                )
        elif key == "volume":
            a, b = manifest_volume(existing), manifest_volume(requested)
            if a != b:
                diffs.append(
                    "GWS volume "
                    + ("computed (--metrics +volume)" if a else "not computed")
                    + " there vs "
                    + ("computed (--metrics +volume)" if b else "not computed")
                    + " here"
                )
        elif key == "sample_streams":
            a, b = manifest_streams(existing), manifest_streams(requested)
            if a != b:
                diffs.append(f"samples drawn with {a} streams there vs {b} here (--streams)")
        elif key == "materials":
            # absent from manifests written before it was recorded: unit density
            a, b = bool(a), bool(b)
            if a != b:
                diffs.append(
                    "mass properties from "
                    + ("per-part materials (--materials)" if a else "unit density")
                    + " there vs "
                    + ("per-part materials (--materials)" if b else "unit density")
                    + " here"
                )
        elif key in ("depth", "robust") and a != b:  # tables of settings: in words
            diffs.append(f"{_plan_text(key, a)} there vs {_plan_text(key, b)} here")
        elif a != b:
            diffs.append(f"{key} {a!r} there vs {b!r} here")
    return diffs


def _plan_text(key: str, value: dict | None) -> str:
    """The ``depth`` or ``robust`` settings of a manifest in words, with their option."""
    if not value:
        return f"no {'depth images' if key == 'depth' else 'robust columns'} (--{key})"
    if key == "depth":
        return f"depth images of {value.get('size')} px at {value.get('fov_deg')}° (--depth)"
    return f"robust columns of {value.get('copies')} copies (--robust {value.get('copies')})"


def hand_spec_differences(there: dict | None, here: dict | None) -> list[str]:
    """The parts of two recorded hands that differ (``links``, ``dofs``, ...).

    A manifest written before hands were recorded whole (no ``hand_spec``) is compared by
    the hand's name alone, so it yields no difference here; the description is not compared
    (it does not change a single row).

    Parameters
    ----------
    there, here : dict or None
        ``hand_spec`` of two manifests (:func:`~affordgrasp.hands.hand_to_dict`).

    Returns
    -------
    list of str
        Sorted top-level keys whose values differ.
    """
    if there is None or here is None:
        return []
    there, here = json.loads(json.dumps(there)), json.loads(json.dumps(here))
    keys = sorted((set(there) | set(here)) - {"description"})
    return [k for k in keys if there.get(k) != here.get(k)]


def prepare_directory(directory: Path, manifest: dict) -> dict:
    """Create the dataset directory with its manifest, or check it matches for a resume.

    Parameters
    ----------
    directory : pathlib.Path
    manifest : dict
        The manifest of the run asked for.

    Returns
    -------
    dict
        The manifest in force (the existing one when resuming).

    Raises
    ------
    DatasetError
        When the directory holds a dataset of another plan (what differs is named; a
        different hand of the same name with ``parameter="hand"``), or is not empty and not
        a dataset.
    """
    check_writable(directory)
    path = directory / MANIFEST_NAME
    if path.exists():
        existing = read_manifest(directory)
        diffs = manifest_differences(existing, manifest)
        if existing.get("hand") == manifest.get("hand") and hand_spec_differences(
            existing.get("hand_spec"), manifest.get("hand_spec")
        ):
            raise DatasetError(
                f"hand {manifest.get('hand')!r} is not the hand the dataset in "
                f"{str(directory)!r} was generated with (same name, different "
                + ", ".join(hand_spec_differences(existing["hand_spec"], manifest["hand_spec"]))
                + f"); resume it with that hand, {str(directory / MANIFEST_NAME)!r} "
                "records it and reads as a hand file, or write to a new output directory",
                parameter="hand",
            )
        if diffs:
            raise DatasetError(
                f"{str(directory)!r} holds a dataset made by a different command ("
                + "; ".join(diffs)
                + "). Resume it with its original options (see its _manifest.json) or "
                "write to a new --out directory"
            )
        return existing
    foreign = [
        p.name
        for p in directory.iterdir()
        if not p.name.startswith(".") and p.name not in (CARD_JSON_NAME, CARD_MD_NAME)
    ]
    if foreign:
        raise DatasetError(
            f"{str(directory)!r} is not empty and is not an affordgrasp dataset (it holds "
            f"{', '.join(sorted(foreign)[:3])}{', ...' if len(foreign) > 3 else ''}); give a "
            "new or empty --out directory"
        )
    write_json_atomic(path, manifest)
    return manifest


# ------------------------------------------------------------------------------------ shards


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
    """Write one complete shard: a hidden temporary file, synced, then renamed into place.

    Its checksum is recorded before the rename, so a shard in place always has one.

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
    DatasetError
        When it cannot be written.
    InternalError
        When the table does not have the planned row count.
    """
    if table.num_rows != shard.rows:
        raise InternalError(f"shard {shard.name} has {table.num_rows} rows, expected {shard.rows}")
    metadata = dict(table.schema.metadata or {})
    metadata[SHARD_META_KEY] = json.dumps(info, sort_keys=True).encode()
    table = table.replace_schema_metadata(metadata)
    final = directory / shard.name
    tmp = directory / f".{shard.name}.tmp-{os.getpid()}"
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink, compression=COMPRESSION, row_group_size=max(1, shard.rows))
    data = sink.getvalue().to_pybytes()
    try:
        write_file(tmp, data)
        # The checksum is on disk before the shard: a shard in place always has one.
        record_checksum(directory, shard.name, data)
        os.replace(tmp, final)
    except BaseException as exc:  # Ctrl-C too: no temporary left behind
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise write_error(final, exc) from exc
        raise
    _sync_directory(directory)
    return final


# ---------------------------------------------------------------------------------- checksums


def file_checksum(data: bytes | memoryview) -> str:
    """BLAKE2b (128-bit) hex digest of a file's bytes (``CHECKSUM_ALGORITHM``).

    Parameters
    ----------
    data : bytes or memoryview

    Returns
    -------
    str
        32 hex digits.
    """
    return hashlib.blake2b(data, digest_size=16).hexdigest()


def record_checksum(directory: Path, name: str, data: bytes) -> None:
    """Append a shard's size and checksum to ``_checksums.jsonl`` (synced).

    Parameters
    ----------
    directory : pathlib.Path
    name : str
        The shard's file name.
    data : bytes
        The shard's bytes.
    """
    line = json.dumps(
        {"name": name, "bytes": len(data), CHECKSUM_ALGORITHM: file_checksum(data)},
        sort_keys=True,
    )
    with open(directory / CHECKSUMS_NAME, "ab") as f:
        f.write(line.encode() + b"\n")
        f.flush()
        os.fsync(f.fileno())


def read_checksums(directory: Path) -> dict[str, dict]:
    """The checksums recorded in a dataset directory (a torn last line is skipped).

    Parameters
    ----------
    directory : pathlib.Path

    Returns
    -------
    dict of str to dict
        Shard name -> ``{"name", "bytes", CHECKSUM_ALGORITHM}`` as last recorded; empty
        without a checksum file.

    Raises
    ------
    DatasetError
        When the checksum file exists but cannot be read.
    """
    path = Path(directory) / CHECKSUMS_NAME
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except FileNotFoundError:
        return {}
    except OSError as exc:
        raise DatasetError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from exc
    records = {}
    for line in text.splitlines():
        try:
            entry = json.loads(line)
            records[entry["name"]] = entry
        except (ValueError, KeyError, TypeError):
            continue  # a line cut short by a crash: its shard was never renamed into place
    return records


# Shards this process has verified: (path, size, mtime_ns, checksum) -> True.
_VERIFIED: set[tuple[str, int, int, str]] = set()


def shard_damage(path: Path, record: dict | None) -> str | None:
    """Why the shard file at ``path`` is not the one written.

    A file verified once in this process (same size, modification time and checksum) is not
    read again.

    Parameters
    ----------
    path : pathlib.Path
    record : dict or None
        Its entry of :func:`read_checksums`; None: no checksum was recorded.

    Returns
    -------
    str or None
        The reason, as a phrase; None when the file is as written.
    """
    if record is None:
        return "no checksum was recorded for it (it was not written by this dataset's runs)"
    try:
        stat = path.stat()
    except OSError as exc:
        return f"it cannot be read ({exc.strerror or exc})"
    expected = record.get(CHECKSUM_ALGORITHM)
    key = (str(path), stat.st_size, stat.st_mtime_ns, str(expected))
    if key in _VERIFIED:
        return None
    if stat.st_size != record.get("bytes"):
        return f"it is {stat.st_size} bytes long, {record.get('bytes')} were written"
    try:
        actual = file_checksum(path.read_bytes())
    except OSError as exc:
        return f"it cannot be read ({exc.strerror or exc})"
    if actual != expected:
        return "its content differs from what was written (checksum mismatch)"
    _VERIFIED.add(key)
    return None


def verify_shards(directory: Path, paths: list[Path], manifest: dict) -> None:
    """Refuse shards changed since they were written, naming each damaged file and the fix.

    Datasets older than checksums (format version 1) are not checked (a warning says so).

    Parameters
    ----------
    directory : pathlib.Path
    paths : list of pathlib.Path
        The shards to check.
    manifest : dict
        The dataset's manifest (its format version and command).

    Raises
    ------
    DatasetError
        Naming the first damaged shard, how many more there are and the command that
        rewrites them.
    """
    if manifest.get("format_version", 1) < 2:
        log.warning(
            "dataset %s predates shard checksums: damaged shards cannot be detected", directory
        )
        return
    records = read_checksums(directory)
    damaged = []
    for path in paths:
        why = shard_damage(path, records.get(path.name))
        if why is not None:
            damaged.append(f"{path.name}: {why}")
    if damaged:
        command = manifest.get("command")
        fix = (
            "run the command that made it again to rewrite the damaged shards: " + " ".join(command)
            if command
            else "run 'affordgrasp generate' with the dataset's options again to rewrite them"
        )
        more = f" (and {len(damaged) - 1} more)" if len(damaged) > 1 else ""
        raise DatasetError(
            f"dataset {str(directory)!r} has a damaged shard, {damaged[0]}{more}; {fix}"
        )


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
    kv = meta.metadata or {}
    raw = kv.get(SHARD_META_KEY)
    if raw is None:
        return None
    try:
        info = json.loads(raw)
    except ValueError:
        return None
    info["num_rows"] = meta.num_rows
    info["schema"] = meta.schema.to_arrow_schema()
    return info


def valid_shard_info(
    directory: Path, shard: Shard, schema: pa.Schema, checksums: dict[str, dict] | None = None
) -> dict | None:
    """The footer facts of a shard already on disk when it is whole and as planned.

    A shard that is damaged (:func:`shard_damage`) or not as planned (rows, range, object,
    schema) is deleted, so that it is written again.

    Parameters
    ----------
    directory : pathlib.Path
    shard : Shard
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
    damage = shard_damage(path, checksums.get(shard.name))
    info = read_shard_info(path) if damage is None else None
    ok = (
        info is not None
        and info["num_rows"] == shard.rows
        and info.get("start") == shard.start
        and info.get("stop") == shard.stop
        and info.get("object_index") == shard.object_index
        and info["schema"].remove_metadata().equals(schema.remove_metadata())
    )
    if not ok:
        # Only a file damaged after it was written gets here (writes are atomic): redo it.
        log.warning(
            "shard %s is damaged or not as planned (%s); it will be written again",
            path,
            damage or "its footer does not match the plan",
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


def _sync_directory(directory: Path) -> None:
    # Make the rename itself durable (POSIX); not possible (nor needed) on every platform.
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
