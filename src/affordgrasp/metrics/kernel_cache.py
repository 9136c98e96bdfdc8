"""Keep numba's on-disk caches of the metric kernels consistent with their sources.

numba (``cache=True``) stamps a cached function with the content hash of the one file that
defines it, but the metric kernels call kernels of sibling modules (ε calls the hull and
the LP solver, Φ calls all of them) and inline them: after an edit of ``hull.py`` a cached
``epsilon_kernel`` would silently keep running the old hull.

The fix is a cache *locator* (numba's hook that says where a function's cache lives and
which stamp validates it): for functions defined in this package it keeps numba's own
location and adds to numba's stamp a hash of every compiled module of the package. When
any of them changes, every index no longer matches and numba recompiles and overwrites it.
Nothing is deleted, and nothing happens on import of :mod:`affordgrasp.metrics`: the
locator is installed by the kernel modules that call across modules (:mod:`.cones`, which
:mod:`.epsilon` imports before the hull and the LP, :mod:`.effort`, :mod:`.transmission`,
:mod:`.phi`), just before their functions are decorated. A module whose kernels call only
its own functions (``hull.py``, ``lp.py``) is correct with numba's per-file stamp, so it
does not matter whether it was imported before or after the install.

Installed releases never change their sources, so the extra stamp only ever matters in a
development checkout.
"""

from __future__ import annotations

import hashlib
from functools import cache
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


@cache
def package_stamp(directory: Path = _PACKAGE_DIR) -> str:
    """Hash of the contents of every module under ``directory`` that defines compiled kernels.

    Computed once per process (a source edited while the process runs is seen by the next
    process, as for numba's own stamps).
    """
    digest = hashlib.sha256()
    for path in sorted(directory.glob("*.py")):
        text = path.read_bytes()
        if b"@njit" in text:
            digest.update(path.name.encode())
            digest.update(hashlib.sha256(text).digest())
    return digest.hexdigest()


def _cache_impl():
    from numba.core import caching

    # the class that picks a locator: CacheImpl in recent numba, _CacheImpl before
    return getattr(caching, "CacheImpl", None) or caching._CacheImpl


def _make_locator_class():
    from numba.core import caching

    class PackageStampLocator(caching._CacheLocator):
        """numba's own locator for a function of this package, with the package stamp."""

        def __init__(self, inner):
            self._inner = inner

        def ensure_cache_path(self):
            self._inner.ensure_cache_path()

        def get_cache_path(self):
            return self._inner.get_cache_path()

        def get_source_stamp(self):
            return (self._inner.get_source_stamp(), package_stamp())

        def get_disambiguator(self):
            return self._inner.get_disambiguator()

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                inside = Path(py_file).resolve().parent == _PACKAGE_DIR
            except OSError:
                return None
            if not inside:
                return None
            for other in _cache_impl()._locator_classes:
                if other is cls:
                    continue
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    return cls(inner)
            return None

    return PackageStampLocator


_installed: list[type] = []


def install_package_stamp() -> None:
    """Make numba validate this package's cached kernels against all their sources (once)."""
    if _installed:
        return
    locator = _make_locator_class()
    _cache_impl()._locator_classes.insert(0, locator)
    _installed.append(locator)
