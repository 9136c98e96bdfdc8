"""A dataset's shard checksums, ``DIR/_checksums.jsonl``: one line per shard.

A shard's size and BLAKE2b checksum are appended (and synced) before the shard is renamed
into place, so a shard on disk always has one; a shard changed afterwards (overwritten,
truncated, replaced) no longer matches it (:func:`shard_damage`), and resuming writes it
again while readers refuse it.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from ..errors import DatasetError

CHECKSUMS_NAME = "_checksums.jsonl"
CHECKSUM_ALGORITHM = "blake2b-128"


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
        {"name": name, "bytes": len(data), CHECKSUM_ALGORITHM: file_checksum(data)}, sort_keys=True
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


# Shards this process has verified: (path, size, mtime_ns, checksum).
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
