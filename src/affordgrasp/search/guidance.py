"""Guidance for a search over simulated grasps: how close an infeasible grasp came to a usable one.

While too few grasps pass a task's thresholds, the cross-entropy method
(:mod:`affordgrasp.search.cem`) ranks the failed ones by this number instead of sampling blindly.
"""

from __future__ import annotations

from dataclasses import dataclass

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
    "contact_width": 1.0,
    "use_lever_ratio": 1.5,
    "contact_reach": -1.0,
    "use_swing_cosine": 1.0,
    **{f"hold_effort_{s}": 1.0 for s in ("px", "nx", "py", "ny", "pz", "nz")},
}


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

    n = len(wrist_point)
    requires = set(task.requires)
    if "discharge" not in requires or n == 0:
        return np.zeros(n)
    if any(c not in _FAVOURABLE and c not in USE_ONLY for c in requires):
        return np.zeros(n)
    t = task.thresholds_for(mode, **overrides)
    cand = np.flatnonzero(use_only_passes(task, mode, overrides, uses))
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


# The tests of the built-in tasks, by threshold name: (column, sense), where sense +1 asks
# ``column >= τ`` and -1 asks ``column <= τ``. ``tau_eps`` tests the ε the task reads
# (``epsilon_hand`` or ``epsilon``). A user task whose thresholds carry these names and that
# reads the column is guided by them too; a task with none of them keeps the contacts-and-ε
# guidance.
THRESHOLD_TESTS: dict[str, tuple[str, int]] = {
    "tau_eps": ("epsilon", +1),
    "tau_delta": ("discharge", +1),
    "tau_blunt": ("use_wedge_angle", +1),
    "tau_clear": ("use_clearance", +1),
    "tau_thick": ("contact_thickness", +1),
    "tau_width": ("contact_width", +1),
    "tau_lever": ("use_lever_ratio", +1),
    "tau_lever_max": ("use_lever_ratio", -1),
    "tau_reach": ("contact_reach", -1),
    "tau_depth": ("use_depth", +1),
    "tau_relief": ("use_relief", -1),
    "tau_swing": ("use_swing_cosine", +1),
    "tau_wedge": ("use_wedge_angle", -1),
    "tau_wedge_fine": ("use_wedge_angle_fine", -1),
    "tau_span": ("use_edge_span", +1),
    "tau_edge_thickness": ("use_edge_thickness", -1),
    "tau_angle": ("use_edge_angle", -1),
    "tau_ug": ("use_edge", +1),
}
# columns a grasp sets alone (the simulated row's), and columns of the use point alone
GRASP_ONLY = frozenset({"epsilon", "epsilon_hand", "contact_thickness", "contact_width"})
USE_ONLY = frozenset(
    {
        "use_edge",
        "use_edge_angle",
        "use_wedge_angle",
        "use_wedge_angle_fine",
        "use_edge_span",
        "use_edge_thickness",
        "use_depth",
        "use_relief",
    }
)


@dataclass(frozen=True)
class ThresholdTest:
    """One test of a task: ``column >= tau`` (sense +1) or ``column <= tau`` (sense -1).

    Attributes
    ----------
    threshold : str
        The threshold's name (``tau_eps``).
    column : str
        The metric column it tests.
    sense : int
        +1 or -1.
    tau : float
        Its value in the mode searched.
    """

    threshold: str
    column: str
    sense: int
    tau: float


def task_tests(task, mode: str = "default", overrides=None) -> list[ThresholdTest]:
    """The tests of a task's thresholds that :data:`THRESHOLD_TESTS` knows.

    Tests whose threshold is ±∞ in this mode (``tau_eps`` in ``no-robustness``) always pass
    and are left out; so are thresholds of columns the task does not read.

    Parameters
    ----------
    task : Task
    mode : str
        Threshold mode.
    overrides : mapping of str to float, optional
        Threshold values that replace the mode's.

    Returns
    -------
    list of ThresholdTest
    """
    values = task.thresholds_for(mode, **dict(overrides or {}))
    requires = set(task.requires)
    tests = []
    for name, tau in values.items():
        if name not in THRESHOLD_TESTS or not np.isfinite(tau):
            continue
        column, sense = THRESHOLD_TESTS[name]
        if name == "tau_eps" and "epsilon_hand" in requires:
            column = "epsilon_hand"
        if column in requires:
            tests.append(ThresholdTest(name, column, sense, float(tau)))
    return tests


def threshold_closeness(tests, columns) -> np.ndarray:
    """How close each row comes to passing each test: a hinge at the threshold.

    1 for a row that passes; below, 1 - shortfall / |τ| (a column at half an ``>=``
    threshold scores 0.5), floored at 0; 0 for NaN. A threshold of 0 measures the
    shortfall in the column's own units.

    Parameters
    ----------
    tests : sequence of ThresholdTest
    columns : mapping of str to (n,) ndarray
        The tests' columns.

    Returns
    -------
    (n, len(tests)) float64 ndarray
        In [0, 1].
    """
    cols = []
    for t in tests:
        v = np.asarray(columns[t.column], dtype=np.float64)
        with np.errstate(invalid="ignore"):
            short = np.maximum(t.sense * (t.tau - v), 0.0)
            scale = abs(t.tau) if t.tau != 0.0 else 1.0
            c = np.clip(1.0 - short / scale, 0.0, 1.0)
        cols.append(np.where(np.isnan(v), 0.0, c))
    if not cols:
        n = len(next(iter(columns.values()))) if len(columns) else 0
        return np.zeros((n, 0))
    return np.stack(cols, axis=1)


def use_only_passes(task, mode, overrides, uses) -> np.ndarray:
    """Which use points pass the task's tests of the use point alone.

    Every column a use point does not set is given its most favourable value, so a use
    point that fails here fails with any grasp. A task that reads a column neither set
    knows has every hit use point pass.

    Parameters
    ----------
    task : Task
    mode : str
    overrides : mapping of str to float
    uses : UsePoints
        Use points (``triangle`` -1 where the ray missed).

    Returns
    -------
    (m,) bool ndarray
    """
    from ..tasks import MetricColumns

    hit = np.asarray(uses.triangle) >= 0
    requires = set(task.requires)
    if any(c not in _FAVOURABLE and c not in USE_ONLY for c in requires):
        return hit
    idx = np.flatnonzero(hit)
    cols = {c: np.full(idx.size, v) for c, v in _FAVOURABLE.items()}
    for c in USE_ONLY:
        cols[c] = np.asarray(getattr(uses, c), dtype=np.float64)[idx]
    with np.errstate(invalid="ignore"):
        ok = task.evaluate(MetricColumns(cols), mode, **dict(overrides or {})) > -np.inf
    out = np.zeros(len(hit), dtype=bool)
    out[idx[ok]] = True
    return out


def _contact_points(rows: pa.Table) -> tuple[np.ndarray, np.ndarray]:
    """Stacked contact points (k, 3) and offsets (n + 1,) of evaluated rows."""
    pts = rows.column("contact_points").combine_chunks()
    offsets = np.asarray(pts.offsets, dtype=np.int64)
    flat = pts.flatten().flatten().to_numpy(zero_copy_only=False)
    offsets = offsets - offsets[0]
    return np.asarray(flat, dtype=np.float64).reshape(-1, 3), offsets


def pair_columns(obj, rows: pa.Table, uses, use_index: np.ndarray, grasp_index: np.ndarray):
    """The columns of pairs (grasp, use point) that both set, as the pair searches compute
    them: δ, the swing cosine, the clearance, the reach and the lever ratio.

    Parameters
    ----------
    obj : GraspObject
        Its centre of mass and inertia are read.
    rows : pyarrow.Table
        Evaluated rows (the grasps).
    uses : UsePoints
    use_index, grasp_index : (p,) int ndarray
        The pairs.

    Returns
    -------
    dict of str to (p,) float64 ndarray
    """
    n = rows.num_rows
    wp = np.asarray(rows.column("wrist_point").to_pylist(), float).reshape(n, 3)
    wa = np.asarray(rows.column("wrist_axis").to_pylist(), float).reshape(n, 3)
    points, offsets = _contact_points(rows)
    return pair_geometry(obj, uses, use_index, grasp_index, wp, wa, points, offsets)


PAIR_GEOMETRY_COLUMNS = (
    "discharge",
    "use_swing_cosine",
    "use_clearance",
    "contact_reach",
    "use_lever_ratio",
)


def pair_geometry(obj, uses, use_index, grasp_index, wrist_point, wrist_axis, points, offsets):
    """:func:`pair_columns` from the grasps' arrays (what
    :func:`affordgrasp.search.pairs.pair_scores` holds already, block after block).

    Parameters
    ----------
    obj : GraspObject
        Its centre of mass and inertia are read.
    uses : UsePoints
    use_index, grasp_index : (p,) int ndarray
        The pairs.
    wrist_point, wrist_axis : (n, 3) float64 ndarray
        Every grasp's palm centre (m) and unit approach direction.
    points : (k, 3) float64 ndarray
        Every grasp's contact points stacked, m.
    offsets : (n + 1,) int ndarray
        Grasp i's contacts are ``points[offsets[i]:offsets[i + 1]]``.

    Returns
    -------
    dict of str to (p,) float64 ndarray
        :data:`PAIR_GEOMETRY_COLUMNS`.
    """
    from ..metrics.discharge import discharge
    from ..metrics.hand_placement import contact_reach, long_axis, use_clearance
    from ..metrics.striking import use_lever_ratio, use_swing_cosine

    if not len(grasp_index):
        return {c: np.zeros(0) for c in PAIR_GEOMETRY_COLUMNS}
    P, N = uses.point[use_index], uses.normal[use_index]
    W, A = wrist_point[grasp_index], wrist_axis[grasp_index]
    com = np.asarray(obj.mass.center_of_mass, dtype=np.float64)
    return {
        "discharge": np.asarray(discharge(P, N, W, A), dtype=np.float64),
        "use_swing_cosine": use_swing_cosine(P, N, W, A),
        "use_clearance": use_clearance(points, offsets, P, grasp_index),
        "contact_reach": contact_reach(
            points, offsets, P, com, long_axis(obj.mass.inertia), grasp_index
        ),
        "use_lever_ratio": use_lever_ratio(P, com, W, A),
    }


def threshold_guidance(
    obj, rows: pa.Table, task, mode, overrides, uses, max_uses: int = 512
) -> np.ndarray | None:
    """A pair search's guidance relative to the task's thresholds.

    Each test of the task (:func:`task_tests`) scores a hinge, 1 when passed and its share
    of the threshold below (:func:`threshold_closeness`); a grasp scores the largest sum of
    hinges over the use points that pass the tests of the use point alone (all hit use
    points when none does), plus 0.05 per contact as a tie-break. Grasps without contacts
    score 0. A grasp that passes more tests, or comes closer to them, ranks higher, so the
    search climbs towards passing every test at once (ε at τ_ε, the hand off the working
    part, a swing that meets the face) rather than towards more contacts.

    Parameters
    ----------
    obj : GraspObject
    rows : pyarrow.Table
        The simulated grasps (evaluated rows; their own use points are not read).
    task : Task
    mode : str
    overrides : mapping of str to float
    uses : UsePoints
        The search's use points.
    max_uses : int
        At most this many candidate use points are scored against every grasp (the first
        ones: the sample is in random order), which bounds the cost per generation.

    Returns
    -------
    (n,) float64 ndarray or None
        None for a task with no known threshold test (the caller keeps its guidance).
    """
    tests = task_tests(task, mode, overrides)
    if not tests:
        return None
    n = rows.num_rows
    n_contacts = rows.column("n_contacts").to_numpy().astype(np.float64)
    touched = np.flatnonzero(n_contacts > 0)
    out = np.zeros(n)
    if not touched.size:
        return out
    passing = np.flatnonzero(use_only_passes(task, mode, overrides, uses))
    if not passing.size:
        passing = np.flatnonzero(np.asarray(uses.triangle) >= 0)
    passing = passing[:max_uses]
    names = set(rows.column_names)
    grasp_tests = [t for t in tests if t.column in GRASP_ONLY]
    use_tests = [t for t in tests if t.column in USE_ONLY]
    pair_tests = [t for t in tests if t.column not in GRASP_ONLY and t.column not in USE_ONLY]
    base = np.zeros(n)
    if grasp_tests:
        cols = {
            t.column: (
                rows.column(t.column).to_numpy(zero_copy_only=False).astype(np.float64)
                if t.column in names
                else np.full(n, np.nan)
            )
            for t in grasp_tests
        }
        base = threshold_closeness(grasp_tests, cols).sum(axis=1)
    best = np.zeros(n)
    if passing.size:
        use_score = np.zeros(passing.size)
        if use_tests:
            ucols = {t.column: np.asarray(getattr(uses, t.column))[passing] for t in use_tests}
            use_score = threshold_closeness(use_tests, ucols).sum(axis=1)
        gi, ui = np.meshgrid(touched, np.arange(passing.size), indexing="ij")
        gi, ui = gi.ravel(), ui.ravel()
        score = use_score[ui]
        if pair_tests:
            pcols = pair_columns(obj, rows, uses, passing[ui], gi)
            score = score + threshold_closeness(pair_tests, pcols).sum(axis=1)
        best[touched] = score.reshape(touched.size, passing.size).max(axis=1)
    out[touched] = base[touched] + best[touched] + 0.05 * n_contacts[touched]
    return out
