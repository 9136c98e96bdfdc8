"""Names of the per-sample metric columns, defined once (row schema, Φ and tasks read them).

Plain Python and numpy: no numba, no pyarrow, so that anything may import it cheaply.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

# Order of the six gravity directions of E_h (+x, -x, +y, -y, +z, -z) as column suffixes.
HOLD_EFFORT_SUFFIXES: tuple[str, ...] = ("px", "nx", "py", "ny", "pz", "nz")
HOLD_EFFORT_COLUMNS: tuple[str, ...] = tuple(f"hold_effort_{s}" for s in HOLD_EFFORT_SUFFIXES)
HOLD_EFFORT_SUM = "hold_effort_sum"  # derived column: ΣE_h
HOLD_DIRS = "hold_dirs"  # derived column: load directions with finite E_h (0-6)

# Metrics that need a use point (NaN for a row whose use ray missed the object).
USE_METRICS: tuple[str, ...] = (
    "impact_effort",
    "discharge",
    "use_force",
    "use_edge",
    "use_edge_angle",
    "use_wedge_angle",
    "use_wedge_angle_fine",
    "use_edge_span",
    "use_edge_thickness",
    "use_clearance",
    "use_lever_ratio",
    "contact_reach",
    "use_depth",
    "use_relief",
    "use_swing_cosine",
)

# Numeric metrics that depend on the grasp only (not on the use point).
GRASP_METRICS: tuple[str, ...] = (
    "epsilon",
    "gws_volume",
    "inertia",
    *HOLD_EFFORT_COLUMNS,
    "contact_thickness",
    "contact_width",
    "epsilon_hand",
)

# The task probabilities (affordgrasp.tasks.probability), after the metric columns (and the
# robust ones): P(the task's physical trial succeeds | the row's metrics).
PROBABILITY_COLUMNS: tuple[str, ...] = ("p_beat", "p_cut", "p_pick")

METRIC_COLUMNS: tuple[str, ...] = (
    "epsilon",
    "gws_volume",
    "epsilon_reason",
    "inertia",
    *HOLD_EFFORT_COLUMNS,
    *USE_METRICS,
    "contact_thickness",
    "contact_width",
    "epsilon_hand",
)

# Columns computed from the metric columns (tasks may read them by name).
DERIVED_COLUMNS: tuple[str, ...] = (HOLD_EFFORT_SUM, HOLD_DIRS)

# Unit of each metric column as stored (SI; "" when dimensionless). E_i is per 1 N·m of
# swing torque; I is at the object's mass properties: unit density by default, as in the
# paper, or a family's per-part materials when resolved with materials=True.
METRIC_UNITS: dict[str, str] = {
    "epsilon": "",
    "gws_volume": "",
    "inertia": "kg·m²",
    **{c: "N" for c in HOLD_EFFORT_COLUMNS},
    HOLD_EFFORT_SUM: "N",
    HOLD_DIRS: "",
    "impact_effort": "N per N·m",
    "discharge": "",
    "use_force": "N",
    "use_edge": "m⁻²",
    "use_edge_angle": "rad",
    "use_wedge_angle": "rad",
    "use_wedge_angle_fine": "rad",
    "use_edge_span": "",
    "use_edge_thickness": "m",
    "use_clearance": "m",
    "use_lever_ratio": "",
    "contact_reach": "",
    "contact_thickness": "m",
    "contact_width": "m",
    "epsilon_hand": "",
    "use_depth": "m",
    "use_relief": "m",
    "use_swing_cosine": "",
}

# Tables show these columns in another unit than the data: (unit shown, factor).
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "use_edge_angle": ("°", 180.0 / math.pi),
    "use_wedge_angle": ("°", 180.0 / math.pi),
    "use_wedge_angle_fine": ("°", 180.0 / math.pi),
    "use_edge_thickness": ("mm", 1000.0),
    "use_clearance": ("mm", 1000.0),
    "contact_thickness": ("mm", 1000.0),
    "contact_width": ("mm", 1000.0),
    "use_depth": ("mm", 1000.0),
    "use_relief": ("mm", 1000.0),
}


def display_unit(column: str) -> str:
    """The unit a table shows ``column`` in.

    Parameters
    ----------
    column : str
        A metric or derived column name (``use_edge_angle``, ``hold_effort_sum``, ...).

    Returns
    -------
    str
        The unit shown (``°`` for the edge angle, else the stored SI unit); ``""`` when the
        column is dimensionless or unknown.
    """
    if column in DISPLAY_UNITS:
        return DISPLAY_UNITS[column][0]
    return METRIC_UNITS.get(column, "")


def display_value(column: str, value: Any) -> Any:
    """``value`` of ``column`` converted to its table unit (degrees for the edge angle).

    Parameters
    ----------
    column : str
        The column the value belongs to.
    value : object
        A stored value (SI). Numbers of a column with a display unit are converted;
        anything else (text, arrays, None) is returned unchanged.

    Returns
    -------
    object
        ``float`` in the display unit, or ``value`` itself.
    """
    if column in DISPLAY_UNITS and isinstance(value, int | float | np.floating):
        return float(value) * DISPLAY_UNITS[column][1]
    return value


def column_heading(column: str, label: str | None = None) -> str:
    """A table heading with the unit: ``edge angle (°)``, ``ΣE_h (N)``, ``ε``.

    Parameters
    ----------
    column : str
        The column whose unit is shown (see :func:`display_unit`).
    label : str, optional
        The text shown instead of the column name.

    Returns
    -------
    str
        ``"<label or column> (<unit>)"``, or the bare name for a dimensionless column.
    """
    unit = display_unit(column)
    name = label or column
    return f"{name} ({unit})" if unit else name


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


def hold_dirs_count(values: Mapping[str, Any]) -> np.ndarray:
    """Number of the six load directions with finite E_h (the graded hold, docs/robust.md).

    Parameters
    ----------
    values : mapping
        Column name to an (n,) array of the six ``hold_effort_*`` columns (N).

    Returns
    -------
    (n,) float64 ndarray
        0 to 6; NaN and +inf efforts count as not held.
    """
    return hold_directions(values)[0]


def hold_directions(values: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The graded hold: how many of the six hold efforts are finite, and their sum.

    Parameters
    ----------
    values : mapping
        Column name to an (n,) array of each hold-effort column.

    Returns
    -------
    count : (n,) float64 ndarray
        Load directions with a finite E_h (0..6).
    finite_sum : (n,) float64 ndarray
        ΣE_h over those directions only, N (0 where none is finite).
    """
    parts = np.asarray([values[c] for c in HOLD_EFFORT_COLUMNS], dtype=np.float64)
    finite = np.isfinite(parts)
    return finite.sum(axis=0).astype(np.float64), np.where(finite, parts, 0.0).sum(axis=0)


def robust_column_names(tasks: Sequence[str]) -> tuple[str, ...]:
    """Names of the robust columns, in table order (:mod:`affordgrasp.robust` fills them).

    Parameters
    ----------
    tasks : sequence of str
        Tasks summarised.

    Returns
    -------
    tuple of str
        ``hold_dirs``, ``robust_fc``, ``robust_epsilon``, ``robust_viable``,
        ``robust_hold_dirs``, ``robust_hold``, then ``robust_p_<task>`` and
        ``robust_<task>`` per task.
    """
    names = [
        "hold_dirs",
        "robust_fc",
        "robust_epsilon",
        "robust_viable",
        "robust_hold_dirs",
        "robust_hold",
    ]
    for t in tasks:
        names += [f"robust_p_{t}", f"robust_{t}"]
    return tuple(names)
