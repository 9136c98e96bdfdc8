"""Data at scale (conventions: Datasets): the per-sample schema, generation, reading.

* ``schema``: the columns of a sample row (conventions: Sample columns);
* ``generate``: sharded, deterministic, resumable Parquet datasets (on disk: ``manifest``,
  ``shards`` and ``checksums``; ``jobs`` the work the engines of :mod:`affordgrasp.runtime`
  run, ``card`` for the dataset card);
* ``handle``: :class:`Dataset`, a dataset directory opened once (plan, hand, objects,
  rows): what every consumer of a dataset takes;
* ``reading``: a dataset directory as one Arrow dataset.

The argmax of a task over a dataset is :func:`affordgrasp.search.best.best_grasps`.

See docs/dataset.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .handle import Dataset

__all__ = ["Dataset"]


def __getattr__(name: str) -> Any:
    # Imported on first use, so that importing a sibling module stays light.
    if name == "Dataset":
        from .handle import Dataset

        return Dataset
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
