"""Keep numba's on-disk caches of the metric kernels consistent with their sources.

numba (``cache=True``) revalidates a cached function only against the file that defines
it, but the metric kernels call kernels of sibling modules (ε calls the hull and the LP
solver, Φ calls all of them) and inline them. After an edit of ``hull.py`` the cached
``epsilon_kernel`` would silently keep running the old hull. This module fingerprints the
sources of the package's compiled modules and drops their cache files when any of them
changed. It runs once, on import of :mod:`affordgrasp.metrics`, before any kernel is
loaded (numba loads caches lazily, at the first call). Installed releases never change
their sources, so this only ever acts in a development checkout.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)

_PACKAGE_DIR = Path(__file__).resolve().parent
_STAMP_NAME = "affordgrasp_metrics_kernels.json"


def _fingerprint() -> dict[str, list[int]]:
    """(mtime, size) of every module of the package that defines compiled kernels."""
    out = {}
    for path in sorted(_PACKAGE_DIR.glob("*.py")):
        if "@njit" not in path.read_text(encoding="utf-8", errors="replace"):
            continue
        st = path.stat()
        out[path.name] = [st.st_mtime_ns, st.st_size]
    return out


def _cache_dirs() -> list[Path]:
    dirs = [_PACKAGE_DIR / "__pycache__"]
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        # numba mirrors the source tree below NUMBA_CACHE_DIR
        dirs.append(Path(env) / _PACKAGE_DIR.relative_to(_PACKAGE_DIR.anchor))
    return dirs


def invalidate_stale_kernel_caches() -> None:
    """Delete the metric kernels' numba cache files if any metrics source changed."""
    try:
        current = _fingerprint()
    except OSError:  # pragma: no cover - unreadable package directory
        return
    modules = {name[: -len(".py")] for name in current}
    for cache_dir in _cache_dirs():
        stamp = cache_dir / _STAMP_NAME
        try:
            if stamp.exists() and json.loads(stamp.read_text()) == current:
                continue
            if not cache_dir.is_dir():
                continue
            removed = 0
            for f in cache_dir.iterdir():
                if f.suffix in (".nbi", ".nbc") and f.name.split(".", 1)[0] in modules:
                    f.unlink(missing_ok=True)
                    removed += 1
            stamp.write_text(json.dumps(current))
            if removed:
                log.debug("dropped %d stale numba cache files in %s", removed, cache_dir)
        except (OSError, ValueError):  # read-only install or a concurrent writer: harmless
            continue
