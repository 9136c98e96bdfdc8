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


# Values of the columns a use point alone does not set, each the most favourable to the
# built-in tasks: a use point that fails a task with these fails it with any grasp.
_FAVOURABLE = {
    "epsilon": 1.0,
    "epsilon_hand": 1.0,
    "gws_volume": 1.0,
    "inertia": 1.0,
    "impact_effort": 0.0,
    "discharge": 1.0,
    "use_force": 1e12,
    "use_clearance": 1.0,
    "contact_thickness": 1.0,
    "use_lever_ratio": 1.5,
    "contact_reach": -1.0,
    "use_swing_cosine": 1.0,
    **{f"hold_effort_{s}": 1.0 for s in ("px", "nx", "py", "ny", "pz", "nz")},
}
_USE_ONLY = ("use_edge", "use_edge_angle", "use_wedge_angle", "use_depth", "use_relief")


def swing_alignment(task, mode, overrides, uses, wrist_point, wrist_axis) -> np.ndarray:
    """How well each grasp's swing meets the task's best-placed use points, for a pair search.

    For a task that reads the discharge δ (beat), the use points that pass the task's tests
    of the use point alone (every other column at its most favourable value) are the
    candidates; a grasp scores the best, over them, of the mean of min(δ / τ_δ, 1) and
    min(cosine / τ_swing, 1) (``use_swing_cosine``, when the task reads it). A grasp's hold
    decides which way its swing goes, and a striking face is a small target of the use
    points: this term leads a search's infeasible grasps towards swings that some candidate
    would discharge, where ε and the contacts alone do not.

    Parameters
    ----------
    task : Task
        The task (its ``requires`` and thresholds are read).
    mode : str
        Threshold mode.
    overrides : mapping of str to float
        Threshold values that replace the mode's.
    uses : UsePoints
        The search's use points.
    wrist_point, wrist_axis : (n, 3) float
        The grasps' palm centres (m) and unit approach directions.

    Returns
    -------
    (n,) float64 ndarray
        In [0, 1]; 0 for a task that does not read δ or when no use point is a candidate.
    """
    from ..metrics.discharge import discharge
    from ..metrics.striking import use_swing_cosine
    from ..tasks import MetricColumns

    n = len(wrist_point)
    requires = set(task.requires)
    if "discharge" not in requires or n == 0:
        return np.zeros(n)
    hit = np.flatnonzero(uses.triangle >= 0)
    if any(c not in _FAVOURABLE and c not in _USE_ONLY for c in requires) or not hit.size:
        return np.zeros(n)
    cols = {c: np.full(hit.size, v) for c, v in _FAVOURABLE.items()}
    for c in _USE_ONLY:
        cols[c] = np.asarray(getattr(uses, c), dtype=np.float64)[hit]
    t = task.thresholds_for(mode, **overrides)
    with np.errstate(invalid="ignore"):
        ok = task.evaluate(MetricColumns(cols), mode, **overrides) > -np.inf
    cand = hit[ok]
    if not cand.size:
        return np.zeros(n)
    gi, ui = np.meshgrid(np.arange(n), cand, indexing="ij")
    gi, ui = gi.ravel(), ui.ravel()
    P, N = uses.point[ui], uses.normal[ui]
    W = np.asarray(wrist_point, dtype=np.float64)[gi]
    A = np.asarray(wrist_axis, dtype=np.float64)[gi]
    tau_delta = max(float(t.get("tau_delta", 1.0)), 1e-9)
    terms = [np.minimum(np.asarray(discharge(P, N, W, A)) / tau_delta, 1.0)]
    if "use_swing_cosine" in requires:
        tau_swing = max(float(t.get("tau_swing", 1.0)), 1e-9)
        cosine = np.nan_to_num(use_swing_cosine(P, N, W, A))
        terms.append(np.clip(cosine / tau_swing, 0.0, 1.0))
    score = np.mean(terms, axis=0).reshape(n, cand.size)
    return score.max(axis=1)
