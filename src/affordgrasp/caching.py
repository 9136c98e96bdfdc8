"""The one caching idiom of affordgrasp: data derived from an object, kept while it lives.

Meshes, objects and hands are mutable or unhashable (they hold numpy arrays), so caches key
them by identity, hold them weakly (an entry goes when its object is garbage collected, and
an id is never reused while the entry exists) and may carry a ``version`` (e.g. a mesh's
content hash) that invalidates the entry when the object was changed in place. Pure
functions of hashable values use :func:`functools.lru_cache` instead.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Hashable
from typing import Any, Generic, TypeVar

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
