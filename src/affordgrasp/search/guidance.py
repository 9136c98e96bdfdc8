"""Guidance for a search over simulated grasps: how close an infeasible grasp came to a usable one.

While too few grasps pass a task's thresholds, the cross-entropy method
(:mod:`affordgrasp.search.cem`) ranks the failed ones by this number instead of sampling blindly.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa


def guidance(table: pa.Table, requires=()) -> np.ndarray:
    """How close each grasp came to a usable one.

    Contacts made, plus 100 ε (``epsilon_hand`` for a task that reads it), plus, for a task
    that reads them (``requires``), how sharp the use point is (3 (1 - angle / π)) and how
    well it discharges the swing (3 δ).
    Ranks infeasible (−∞) samples among themselves while CEM has too few feasible ones: more
    links touching and force closure make every task's thresholds likelier to pass, and
    the use terms lead the use direction towards an edge or a discharging point, which
    uniform use directions rarely hit (a knife's cutting edge: 0.1 % of them).

    Parameters
    ----------
    table : pyarrow.Table
        Evaluated rows.
    requires : iterable of str
        Metric columns the task reads.

    Returns
    -------
    (n,) float64 ndarray
    """
    n = table["n_contacts"].to_numpy().astype(np.float64)
    # the ε the task gates on: at a hand's torque length for beat and cut (long objects)
    eps_column = "epsilon_hand" if "epsilon_hand" in requires else "epsilon"
    eps = table[eps_column].to_numpy() if eps_column in table.column_names else 0.0
    g = n + 100.0 * np.nan_to_num(eps)
    names = table.column_names
    if "use_edge_angle" in requires and "use_edge_angle" in names:
        angle = np.nan_to_num(table["use_edge_angle"].to_numpy(), nan=np.pi)
        g = g + 3.0 * (1.0 - angle / np.pi)
    if "use_wedge_angle" in requires and "use_wedge_angle" in names and "use_force" in requires:
        wedge = np.nan_to_num(table["use_wedge_angle"].to_numpy(), nan=np.pi)
        g = g + 3.0 * np.clip(1.0 - wedge / np.pi, 0.0, 1.0)
    if "use_clearance" in requires and "use_clearance" in names:
        clear = np.nan_to_num(table["use_clearance"].to_numpy(), nan=0.0, posinf=0.0)
        g = g + 3.0 * np.clip(clear / 0.035, 0.0, 1.0)
    if "discharge" in requires and "discharge" in names:
        g = g + 3.0 * np.nan_to_num(table["discharge"].to_numpy())
    return g
