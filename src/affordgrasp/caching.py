"""The caching idioms of affordgrasp: in memory while an object lives, on disk between runs.

Meshes, objects and hands are mutable or unhashable (they hold numpy arrays), so caches key
them by identity, hold them weakly (an entry goes when its object is garbage collected, and
an id is never reused while the entry exists) and may carry a ``version`` (e.g. a mesh's
content hash) that invalidates the entry when the object was changed in place. Pure
functions of hashable values use :func:`functools.lru_cache` instead.

Between processes, :func:`read_arrays` and :func:`write_arrays` keep named numpy arrays in
one ``.npz`` file per entry under :func:`cache_dir`, with the entry's full key and a
checksum of its contents inside: an entry whose key differs (another version of the code or
of a library), that does not match its checksum or that cannot be read is ignored (and then
overwritten), never trusted. Entries are written to a temporary file and renamed into
place, so a reader never sees half an entry.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import weakref
from collections.abc import Callable, Hashable, Mapping
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np

log = logging.getLogger(__name__)

T = TypeVar("T")

_UNVERSIONED = object()


class IdentityCache(Generic[T]):
    """Values built from objects, keyed by the objects' identity and held weakly.

    A value lives as long as the object it was built from; ``get`` rebuilds it when the
    ``version`` given differs from the stored one. The cache takes no parameters.

    Attributes
    ----------
    get : method
        ``get(obj, build, *, version=...)``: the cached value of ``obj`` or ``build()``.
    clear : method
        Forget every value.

    Examples
    --------
    >>> normals = IdentityCache()
    >>> value = normals.get(mesh, lambda: expensive(mesh), version=hash(mesh))  # doctest: +SKIP
    """

    def __init__(self) -> None:
        self._entries: dict[int, tuple[weakref.ref, Any, T]] = {}

    def get(self, obj: Any, build: Callable[[], T], *, version: Hashable = _UNVERSIONED) -> T:
        """The value cached for ``obj`` (same ``version``), else ``build()``, cached.

        Parameters
        ----------
        obj : object
            The key, by identity; its entry goes when ``obj`` is garbage-collected.
        build : callable
            Makes the value (no arguments) when none is cached.
        version : hashable, optional
            A value cached with another version is built again.

        Returns
        -------
        object
            The cached or new value.
        """
        key = id(obj)
        entry = self._entries.get(key)
        if entry is not None and entry[0]() is obj and entry[1] == version:
            return entry[2]
        value = build()
        entries = self._entries

        def forget(ref: weakref.ref, key: int = key) -> None:
            current = entries.get(key)
            if current is not None and current[0] is ref:
                del entries[key]

        self._entries[key] = (weakref.ref(obj, forget), version, value)
        return value

    def clear(self) -> None:
        """Drop every entry."""
        self._entries.clear()

    def __len__(self) -> int:
        return len(self._entries)


def cache_dir() -> Path:
    """The user cache directory of affordgrasp (created on first write).

    ``$AFFORDGRASP_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/affordgrasp`` or
    ``~/.cache/affordgrasp``.

    Returns
    -------
    pathlib.Path
    """
    env = os.environ.get("AFFORDGRASP_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "affordgrasp"


_KEY = "__key__"
_CHECKSUM = "__checksum__"


def _checksum(arrays: Mapping[str, np.ndarray]) -> str:
    digest = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


def read_arrays(path: Path, key: Mapping[str, Any]) -> dict[str, np.ndarray] | None:
    """The arrays stored at ``path`` under exactly ``key``, or None.

    None when the file is missing or unreadable, was written under another key, or its
    contents do not match their checksum (a truncated or altered file).

    Parameters
    ----------
    path : pathlib.Path
        An ``.npz`` file written by :func:`write_arrays`.
    key : mapping
        JSON-serialisable; everything the arrays depend on.

    Returns
    -------
    dict of str to ndarray or None
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except FileNotFoundError:
        return None
    except Exception as exc:  # noqa: BLE001 - any unreadable entry is rebuilt
        log.warning("ignoring unreadable cache entry %s (%s)", path, exc)
        return None
    stored_key = arrays.pop(_KEY, None)
    stored_sum = arrays.pop(_CHECKSUM, None)
    if stored_key is None or str(stored_key) != json.dumps(key, sort_keys=True):
        return None
    if stored_sum is None or str(stored_sum) != _checksum(arrays):
        log.warning("ignoring corrupt cache entry %s (checksum mismatch)", path)
        return None
    return arrays


def write_arrays(path: Path, key: Mapping[str, Any], arrays: Mapping[str, np.ndarray]) -> None:
    """Store ``arrays`` at ``path`` under ``key`` (atomically; failures are only logged).

    Parameters
    ----------
    path : pathlib.Path
        The ``.npz`` file; its directory is created.
    key : mapping
        JSON-serialisable; :func:`read_arrays` must be given the same.
    arrays : mapping of str to ndarray
        Numeric, bool or str arrays (no objects).
    """
    data = {name: np.asarray(a) for name, a in arrays.items()}
    data[_CHECKSUM] = np.array(_checksum(data))
    data[_KEY] = np.array(json.dumps(key, sort_keys=True))
    from .errors import InputError
    from .runtime.writing import atomic_write

    save: Any = np.savez  # names are the arrays' keywords
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # A cache entry need not survive a power cut (its checksum catches a torn one).
        atomic_write(path, lambda f: save(f, **data), fsync=False)
    except (OSError, InputError) as exc:  # a read-only or full cache costs a rebuild later
        log.warning("could not write cache entry %s (%s)", path, exc)
