"""The on-disk layout of a dataset: the plan, the manifest and the shards (conventions: Datasets).

A dataset directory holds::

    DIR/_manifest.json                    the plan: what the command asked for (written first)
    DIR/_card.json, DIR/_card.md          the dataset card (written when a run ends)
    DIR/part-OOOOO-SSSSSSSSSSSS.parquet   one shard: object O, samples S .. S+shard_size-1

The plan is a pure function of the command: object ``o`` gets samples ``0 .. samples-1`` and
shard ``k`` of it holds samples ``k*shard_size .. min((k+1)*shard_size, samples)-1`` in order.
A shard is written to a hidden temporary name and renamed into place only when complete and
synced, so a shard file that exists is whole; resuming skips every valid shard.

Names starting with ``_`` or ``.`` are ignored by Arrow datasets, so pandas, polars and
DuckDB read the directory (or ``DIR/*.parquet``) as one table.
"""

from __future__ import annotations

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
FORMAT_VERSION = 1
MANIFEST_NAME = "_manifest.json"
CARD_JSON_NAME = "_card.json"
CARD_MD_NAME = "_card.md"
SHARD_META_KEY = b"affordgrasp_shard"
DEFAULT_SHARD_SIZE = 4096
COMPRESSION = "zstd"

_SHARD_RE = re.compile(r"^part-(\d{5})-(\d{12})\.parquet$")
_TMP_RE = re.compile(
    r"^\.(part-\d{5}-\d{12}\.parquet|_manifest\.json|_card\.json|_card\.md)\.tmp(-\d+)?$"
)

# Manifest keys that define the content of the dataset; a resume must match all of them.
PLAN_KEYS = (
    "format_version",
    "affordgrasp_version",
    "seed",
    "samples",
    "shard_size",
    "hand",
    "metrics",
    "soft",
    "depth",
    "objects",
)


@dataclass(frozen=True)
class Shard:
    """One planned shard: samples ``start .. stop-1`` of object number ``object_index``."""

    object_index: int
    start: int
    stop: int

    @property
    def name(self) -> str:
        return f"part-{self.object_index:05d}-{self.start:012d}.parquet"

    @property
    def rows(self) -> int:
        return self.stop - self.start


def plan_shards(n_objects: int, samples: int, shard_size: int) -> list[Shard]:
    """Every shard of a run, objects in order, then samples in order."""
    if shard_size < 1:
        raise DatasetError(f"shard size must be a positive integer, got {shard_size}")
    return [
        Shard(o, start, min(start + shard_size, samples))
        for o in range(n_objects)
        for start in range(0, samples, shard_size)
    ]


def shard_paths(directory: str | os.PathLike) -> list[Path]:
    """The shard files of a dataset directory, in plan order."""
    directory = Path(directory)
    return sorted(p for p in directory.iterdir() if _SHARD_RE.match(p.name))


# ---------------------------------------------------------------------------------- manifest


def write_json_atomic(path: Path, document: dict) -> None:
    """Write a JSON file so that readers see the old or the new version, never a mix."""
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(document, f, indent=2, sort_keys=False)
        f.write("\n")
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    _sync_directory(path.parent)


def read_manifest(directory: str | os.PathLike) -> dict:
    """The manifest of a dataset directory, or a DatasetError saying why there is none."""
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


def manifest_differences(existing: dict, requested: dict) -> list[str]:
    """Readable differences between two manifests' plans (empty when they agree)."""
    diffs = []
    for key in PLAN_KEYS:
        a, b = existing.get(key), requested.get(key)
        if key == "objects":
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
        elif a != b:
            diffs.append(f"{key} {a!r} there vs {b!r} here")
    return diffs


def prepare_directory(directory: Path, manifest: dict) -> dict:
    """Create the dataset directory with its manifest, or check it matches for a resume.

    Returns the manifest in force (the existing one when resuming). Raises DatasetError when
    the directory belongs to another command or to something else.
    """
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / MANIFEST_NAME
    if path.exists():
        existing = read_manifest(directory)
        diffs = manifest_differences(existing, manifest)
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
    return {
        "object": object_name,
        "object_index": shard.object_index,
        "start": shard.start,
        "stop": shard.stop,
        "status_counts": status_counts,
    }


def write_shard(directory: Path, shard: Shard, table: pa.Table, info: dict) -> Path:
    """Write one complete shard: a hidden temporary file, synced, then renamed into place."""
    if table.num_rows != shard.rows:
        raise InternalError(f"shard {shard.name} has {table.num_rows} rows, expected {shard.rows}")
    metadata = dict(table.schema.metadata or {})
    metadata[SHARD_META_KEY] = json.dumps(info, sort_keys=True).encode()
    table = table.replace_schema_metadata(metadata)
    final = directory / shard.name
    tmp = directory / f".{shard.name}.tmp-{os.getpid()}"
    with open(tmp, "wb") as f:
        pq.write_table(table, f, compression=COMPRESSION, row_group_size=max(1, shard.rows))
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, final)
    _sync_directory(directory)
    return final


def read_shard_info(path: Path) -> dict | None:
    """The shard's footer facts (rows, plan range, status counts), or None if unreadable."""
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


def valid_shard_info(directory: Path, shard: Shard, schema: pa.Schema) -> dict | None:
    """The footer facts of a shard already on disk when it is whole and as planned, else None."""
    path = directory / shard.name
    if not path.exists():
        return None
    info = read_shard_info(path)
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
        log.warning("shard %s is damaged or not as planned; it will be written again", path)
        path.unlink()
        return None
    return info


def remove_stale_temporaries(directory: Path) -> int:
    """Delete half-written shards left by a run that was killed; returns how many."""
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
