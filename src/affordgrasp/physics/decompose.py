"""Convex decomposition of an object for the physics engine, cached on disk per mesh hash.

MuJoCo collides a mesh as its convex hull, which would fill a mug's cavity and its handle's
hole. The object is therefore split into convex parts with CoACD (approximate convex
decomposition, collision-aware: concavities such as a hole are kept). Only the collision
geometry comes from the parts; the mass and inertia come from the original mesh.

Cache: ``$AFFORDGRASP_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/affordgrasp`` or
``~/.cache/affordgrasp``; one ``.npz`` per (mesh hash, decomposition settings).
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ..caching import cache_dir
from ..errors import InputError
from ..runtime.writing import atomic_write
from . import deps
from .settings import PhysicsSettings

log = logging.getLogger(__name__)

__all__ = ["cache_dir", "convex_parts"]


def _cache_path(mesh_hash: str, settings: PhysicsSettings) -> Path:
    key = json.dumps(settings.decomposition_key(), sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:12]
    return cache_dir() / "decomposition" / f"{mesh_hash[:32]}-{digest}.npz"


def convex_parts(
    mesh: trimesh.Trimesh,
    mesh_hash: str,
    settings: PhysicsSettings | None = None,
    *,
    use_cache: bool = True,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Convex parts of a closed mesh, in its frame.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Watertight, metres.
    mesh_hash : str
        The mesh's :func:`affordgrasp.objects.mesh_hash` (the cache key).
    settings : PhysicsSettings, optional
        The decomposition settings; the defaults when None.
    use_cache : bool
        Read and write the decomposition in :func:`cache_dir`.

    Returns
    -------
    list of (vertices, faces)
        vertices (n, 3) float64 m, faces (m, 3) int64; each a convex hull.
    """
    settings = settings or PhysicsSettings()
    path = _cache_path(mesh_hash, settings)
    if use_cache and path.is_file():
        try:
            with np.load(path) as data:
                n = int(data["count"])
                return [(data[f"v{i}"], data[f"f{i}"]) for i in range(n)]
        except (OSError, KeyError, ValueError):
            log.warning("dropping unreadable decomposition cache %s", path)
            path.unlink(missing_ok=True)
    parts = _decompose(mesh, settings)
    if use_cache:
        _write_atomic(path, parts)
    return parts


def _decompose(mesh: trimesh.Trimesh, settings: PhysicsSettings) -> list:
    coacd = deps.coacd()
    coacd.set_log_level("error")
    raw = coacd.run_coacd(
        coacd.Mesh(np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)),
        threshold=settings.coacd_threshold,
        max_convex_hull=int(settings.coacd_max_hulls),
        preprocess_mode="off",  # our meshes are watertight already (remeshing would move them)
        resolution=int(settings.coacd_resolution),
        mcts_iterations=int(settings.coacd_mcts_iterations),
        mcts_nodes=int(settings.coacd_mcts_nodes),
        mcts_max_depth=int(settings.coacd_mcts_depth),
        seed=int(settings.seed),
    )
    parts = []
    for vertices, faces in raw:
        hull = trimesh.Trimesh(np.asarray(vertices, dtype=np.float64), faces).convex_hull
        if hull.volume <= 0 or len(hull.vertices) < 4:
            continue  # a sliver: nothing to collide with
        parts.append(
            (np.asarray(hull.vertices, dtype=np.float64), np.asarray(hull.faces, dtype=np.int64))
        )
    if not parts:  # pragma: no cover - coacd always returns at least the hull
        hull = mesh.convex_hull
        parts = [(np.asarray(hull.vertices), np.asarray(hull.faces, dtype=np.int64))]
    return parts


def _write_atomic(path: Path, parts: list) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays: dict[str, Any] = {"count": np.array(len(parts))}
        for i, (v, f) in enumerate(parts):
            arrays[f"v{i}"] = v
            arrays[f"f{i}"] = f
        atomic_write(path, lambda fh: np.savez(fh, **arrays))
    except (OSError, InputError) as exc:  # a read-only or full cache only costs time
        log.warning("cannot cache the decomposition in %s: %s", path.parent, exc)
