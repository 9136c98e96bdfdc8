"""Names of the per-sample metric columns, defined once (row schema, Φ and tasks read them).

Plain Python and numpy: no numba, no pyarrow, so that anything may import it cheaply.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

# Order of the six gravity directions of E_h (+x, -x, +y, -y, +z, -z) as column suffixes.
HOLD_EFFORT_SUFFIXES: tuple[str, ...] = ("px", "nx", "py", "ny", "pz", "nz")
HOLD_EFFORT_COLUMNS: tuple[str, ...] = tuple(f"hold_effort_{s}" for s in HOLD_EFFORT_SUFFIXES)
HOLD_EFFORT_SUM = "hold_effort_sum"  # derived column: ΣE_h

# Metrics that need a use point (NaN for a row whose use ray missed the object).
USE_METRICS: tuple[str, ...] = (
    "impact_effort",
    "discharge",
    "use_force",
    "use_edge",
    "use_edge_angle",
)

METRIC_COLUMNS: tuple[str, ...] = (
    "epsilon",
    "gws_volume",
    "epsilon_reason",
    "inertia",
    *HOLD_EFFORT_COLUMNS,
    *USE_METRICS,
)

# Columns computed from the metric columns (tasks may read them by name).
DERIVED_COLUMNS: tuple[str, ...] = (HOLD_EFFORT_SUM,)


def hold_effort_sum(values: Mapping[str, Any]) -> Any:
    """ΣE_h: the sum of the six hold efforts.

    Parameters
    ----------
    values : mapping
        Column name to a number (one row) or to an (n,) array (many rows).

    Returns
    -------
    float or (n,) float64 ndarray
        +inf where any direction is infeasible; NaN (one row) when a column is missing.
    """
    parts = [values.get(c) if hasattr(values, "get") else values[c] for c in HOLD_EFFORT_COLUMNS]
    if any(p is None for p in parts):
        return math.nan
    total = np.sum(np.asarray(parts, dtype=np.float64), axis=0)
    return float(total) if np.ndim(total) == 0 else total
