"""Metric columns as float64 arrays, whatever table type holds them."""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..columns import (
    DERIVED_COLUMNS,
    HOLD_DIRS,
    HOLD_EFFORT_COLUMNS,
    HOLD_EFFORT_SUM,
    METRIC_COLUMNS,
    hold_dirs_count,
    hold_effort_sum,
)
from ..errors import TaskError

log = logging.getLogger(__name__)
EPSILON_HAND = "epsilon_hand"


class MetricColumns(Mapping):
    """Read-only view of metric columns as float64 arrays, with derived columns.

    Accepts a mapping of name -> array, a pyarrow Table or a pandas DataFrame. A missing
    column raises a :class:`TaskError` that lists the available ones.

    Parameters
    ----------
    columns : mapping, pyarrow.Table or pandas.DataFrame
        The metric columns of n rows; each is read once, as an (n,) float64 array, on
        first access. ``hold_effort_sum`` and ``hold_dirs`` are derived when the six hold
        efforts are there (a stored ``hold_dirs`` is read as it is); a missing
        ``epsilon_hand`` (rows of an earlier version) is read as ``epsilon``, with a warning.
    """

    def __init__(self, columns: Any):
        self._source = columns
        self._cache: dict[str, np.ndarray] = {}
        self._names = _column_names(columns)

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self._cache:
            return self._cache[name]
        if name == HOLD_EFFORT_SUM:
            value = hold_effort_sum({c: self[c] for c in HOLD_EFFORT_COLUMNS})
        elif name == HOLD_DIRS and name not in self._names:
            value = hold_dirs_count({c: self[c] for c in HOLD_EFFORT_COLUMNS})
        elif name in self._names:
            value = _column_as_float(self._source, name)
        elif name == EPSILON_HAND and "epsilon" in self._names:
            # rows written before the column existed: ε itself, which it equals on every
            # object within 0.25 m of its centre of mass (stricter on longer ones)
            log.warning(
                "no %s column (rows written by an earlier version): using epsilon, which is "
                "stricter on objects longer than 0.25 m; evaluate the rows again to get it",
                EPSILON_HAND,
            )
            value = self["epsilon"]
        else:
            # a column this version writes: the rows come from an earlier version
            hint = (
                "; rows written by an earlier version of affordgrasp lack it: evaluate or "
                "generate them again with this version"
                if name in METRIC_COLUMNS
                else ""
            )
            raise TaskError(
                f"metric column {name!r} is missing; available: "
                f"{', '.join(sorted(self._names))}{hint}"
            )
        self._cache[name] = value
        return value

    def __iter__(self):
        return iter(list(self._names) + [c for c in DERIVED_COLUMNS if c not in self._names])

    def __len__(self) -> int:
        return len(self._names) + len([c for c in DERIVED_COLUMNS if c not in self._names])

    def __contains__(self, name: object) -> bool:
        return name in self._names or name in DERIVED_COLUMNS

    @property
    def n_rows(self) -> int:
        """Number of rows, read without converting any column (some are strings)."""
        src = self._source
        if hasattr(src, "num_rows"):  # pyarrow
            return int(src.num_rows)
        if hasattr(src, "columns") and hasattr(src, "to_numpy"):  # pandas
            return len(src)
        for name in self._names:
            col = src[name]
            return len(col) if hasattr(col, "__len__") else int(np.shape(col)[0])
        return 0


def _column_names(columns: Any) -> tuple[str, ...]:
    if hasattr(columns, "column_names"):  # pyarrow Table / RecordBatch
        return tuple(columns.column_names)
    if hasattr(columns, "columns") and hasattr(columns, "to_numpy"):  # pandas DataFrame
        return tuple(str(c) for c in columns.columns)
    if isinstance(columns, Mapping):
        return tuple(str(c) for c in columns.keys())
    raise TaskError(
        "metric columns must be a mapping of name -> array, a pyarrow Table or a pandas "
        f"DataFrame, got {type(columns).__name__}"
    )


def _column_as_float(source: Any, name: str) -> np.ndarray:
    if hasattr(source, "column_names"):
        col = source.column(name)
        col = col.to_numpy() if hasattr(col, "to_numpy") else np.asarray(col)
    else:
        col = source[name]
        if hasattr(col, "to_numpy"):
            col = col.to_numpy()
    try:
        arr = np.asarray(col, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise TaskError(f"metric column {name!r} is not numeric") from exc
    return arr
