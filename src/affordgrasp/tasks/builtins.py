"""The built-in affordance functions of the paper (§III) and the learning ground truth."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..columns import HOLD_EFFORT_COLUMNS
from . import thresholds
from .probability import MODEL_COLUMNS, PICK_COLUMNS, task_probability
from .task import Task, make_task

# A probability task's value: (1 - 10⁻⁶) p_T + 10⁻⁶ × the paper's value squashed into (0, 1), so
# that grasps of equal p_T (a calibration map is flat between its knots) rank by the
# paper's formula and p_T shown to six decimals is unchanged.
_TIE = 1e-6


def _squash(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    return np.where(np.isnan(x), 0.0, 0.5 + np.arctan(np.nan_to_num(x, nan=0.0)) / np.pi)


# The paper's value of each task probability's task: its ties' order, and what it reads
TIE_COLUMNS = {
    "beat": ("inertia", "impact_effort"),
    "cut": ("use_force",),
    "pick": tuple(HOLD_EFFORT_COLUMNS),
}
_TIES = {
    "beat": lambda m: m["inertia"] / m["impact_effort"],
    "cut": lambda m: m["use_force"],
    "pick": lambda m: -m["hold_effort_sum"],
}


def probability_value(task: str, p: np.ndarray, metrics: Mapping[str, np.ndarray]) -> np.ndarray:
    """A task probability's value from p_T: ties broken by the paper's formula.

    Parameters
    ----------
    task : str
        ``beat``, ``cut`` or ``pick``.
    p : (n,) array_like of float
        p_T of the rows (computed, or a dataset's stored column of the same models).
    metrics : mapping of str to (n,) array
        The rows' metric columns (the paper's formula reads them).

    Returns
    -------
    (n,) float64 ndarray
        (1 − 10⁻⁶) p_T + 10⁻⁶ × the paper's value squashed into (0, 1).
    """
    return (1.0 - _TIE) * np.asarray(p, dtype=np.float64) + _TIE * _squash(_TIES[task](metrics))


def _probability_task(task: str):
    def func(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
        return probability_value(task, task_probability(task, m), m)

    func.__name__ = f"p_{task}"
    return func


def _beat(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    # the paper's beat, on a blunt use point with the hand off it
    ok = (
        (m["use_wedge_angle"] >= t["tau_blunt"])
        & (m["use_clearance"] >= t["tau_clear"])
        & (m["contact_thickness"] >= t["tau_thick"])
        & (m["use_lever_ratio"] >= t["tau_lever"])
        & (m["use_lever_ratio"] <= t["tau_lever_max"])
        & (m["use_depth"] >= t["tau_depth"])
        & (m["use_relief"] <= t["tau_relief"])
        & (m["use_swing_cosine"] >= t["tau_swing"])
    )
    # ε at a hand's torque length: the same gate as ε within 0.25 m, the same torque beyond
    return np.where(ok, _beat_formula(m, t, m["epsilon_hand"]), -np.inf)


def _beat_paper(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return _beat_formula(m, t, m["epsilon"])


def _beat_formula(
    m: Mapping[str, np.ndarray], t: Mapping[str, float], eps: np.ndarray
) -> np.ndarray:
    ok = (
        (eps >= t["tau_eps"])
        & (m["discharge"] >= t["tau_delta"])
        & np.isfinite(m["hold_effort_sum"])
    )
    # E_i = inf (the impact cannot be held) gives I / inf = 0, the paper's formula as is
    return np.where(ok, m["inertia"] / m["impact_effort"], -np.inf)


def _cut(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    # an edge, not a thin flat (the 2 mm ball) nor a tip or a thin part's corner (the span)
    # nor a thin plate's end (a spine: its flanks parallel behind U, the edge thickness);
    # every contact on a part at least tau_width across (a handle, not a blade's spine)
    ok = (
        (m["use_wedge_angle_fine"] <= t["tau_wedge_fine"])
        & (m["use_edge_span"] >= t["tau_span"])
        & (m["use_edge_thickness"] <= t["tau_edge_thickness"])
        & (m["contact_width"] >= t["tau_width"])
    )
    return np.where(ok, _cut_wedge(m, t), -np.inf)


def _cut_wedge(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (
        (m["epsilon_hand"] >= t["tau_eps"])
        & (m["use_wedge_angle"] <= t["tau_wedge"])
        & (m["use_clearance"] >= t["tau_clear"])
        & (m["contact_thickness"] >= t["tau_thick"])
        & (m["contact_reach"] <= t["tau_reach"])
    )
    return np.where(ok, m["use_force"], -np.inf)


def _cut_dihedral(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (m["epsilon"] >= t["tau_eps"]) & (m["use_edge_angle"] <= t["tau_angle"])
    return np.where(ok, m["use_force"], -np.inf)


def _cut_ug(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (m["epsilon"] >= t["tau_eps"]) & (m["use_edge"] >= t["tau_ug"])
    return np.where(ok, m["use_force"], -np.inf)


def _pick(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return -m["hold_effort_sum"]


def viable_mask(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    """Which grasps are viable: ε > eps_min, ΣE_h < hold_max and E_i < impact_max.

    Parameters
    ----------
    m : mapping of str to ndarray
        ``epsilon``, ``hold_effort_sum`` (N) and ``impact_effort`` (N per N·m), each (n,)
        float64.
    t : mapping of str to float
        ``eps_min``, ``hold_max`` (N) and ``impact_max`` (N per N·m).

    Returns
    -------
    (n,) bool ndarray
        True for a viable grasp (NaN metrics are not viable).
    """
    return (
        (m["epsilon"] > t["eps_min"])
        & (m["hold_effort_sum"] < t["hold_max"])
        & (m["impact_effort"] < t["impact_max"])
    )


def _viable(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return viable_mask(m, t).astype(np.float64)


def builtin_tasks() -> list[Task]:
    """Fresh Task objects of the built-in tasks: beat, beat-rules, beat-paper, cut, cut-rules,
    cut-wedge, cut-dihedral, cut-ug, pick, pick-paper, viable.

    ``beat``, ``cut`` and ``pick`` are the task probabilities p_T
    (:mod:`~affordgrasp.tasks.probability`: learned from the physical trials), ties broken by
    the paper's value (I / E_i, U_τ, −ΣE_h); ``beat-rules`` and ``cut-rules`` are the
    threshold versions that ranked before them, ``beat-paper``, ``cut-ug`` and ``pick-paper``
    the paper's formulas.

    Returns
    -------
    list of Task
        New objects on every call (a registry may replace them without touching others).
    """
    return [
        make_task(
            "beat",
            _probability_task("beat"),
            description="beating: p_beat, the probability that three wrist-swung strikes "
            "drive a nail with the use point (physics trial), ties by the paper's I / E_i",
            requires=MODEL_COLUMNS,
            probability=True,
        ),
        make_task(
            "cut",
            _probability_task("cut"),
            description="cutting: p_cut, the probability that a pressed 40 mm stroke bears "
            "on the edge at the use point (physics trial), ties by the paper's U_τ",
            requires=MODEL_COLUMNS,
            probability=True,
        ),
        make_task(
            "pick",
            _probability_task("pick"),
            description="picking: p_pick, the probability that the grasp holds the object "
            "against its weight in every direction (physics trial), ties by the paper's -ΣE_h",
            requires=PICK_COLUMNS,
            probability=True,
        ),
        make_task(
            "beat-rules",
            _beat,
            thresholds={
                "tau_eps": thresholds.TAU_EPS_DEFAULT,
                "tau_delta": thresholds.TAU_DELTA_DEFAULT,
                "tau_blunt": thresholds.TAU_BLUNT_DEFAULT,
                "tau_clear": thresholds.TAU_CLEARANCE_DEFAULT,
                "tau_thick": thresholds.TAU_THICKNESS_DEFAULT,
                "tau_lever": thresholds.TAU_LEVER_DEFAULT,
                "tau_lever_max": thresholds.TAU_LEVER_MAX_DEFAULT,
                "tau_depth": thresholds.TAU_DEPTH_DEFAULT,
                "tau_relief": thresholds.TAU_RELIEF_DEFAULT,
                "tau_swing": thresholds.TAU_SWING_DEFAULT,
            },
            description="beating by a wrist rotation: I / E_i if robust and discharging, "
            "on a flat, blunt use point at the end of a deep part, with the hand off it",
            requires=(
                "epsilon_hand",
                "discharge",
                *HOLD_EFFORT_COLUMNS,
                "inertia",
                "impact_effort",
                "use_wedge_angle",
                "use_clearance",
                "contact_thickness",
                "use_lever_ratio",
                "use_depth",
                "use_relief",
                "use_swing_cosine",
            ),
        ),
        make_task(
            "beat-paper",
            _beat_paper,
            thresholds={
                "tau_eps": thresholds.TAU_EPS_DEFAULT,
                "tau_delta": thresholds.TAU_DELTA_DEFAULT,
            },
            description="beating as in the paper: I / E_i if robust and discharging",
            requires=("epsilon", "discharge", *HOLD_EFFORT_COLUMNS, "inertia", "impact_effort"),
        ),
        make_task(
            "cut-rules",
            _cut,
            thresholds={
                "tau_eps": thresholds.TAU_EPS_DEFAULT,
                "tau_wedge": thresholds.TAU_WEDGE_DEFAULT,
                "tau_wedge_fine": thresholds.TAU_WEDGE_FINE_DEFAULT,
                "tau_span": thresholds.TAU_SPAN_DEFAULT,
                "tau_edge_thickness": thresholds.TAU_EDGE_THICKNESS_DEFAULT,
                "tau_clear": thresholds.TAU_CLEARANCE_DEFAULT,
                "tau_thick": thresholds.TAU_THICKNESS_DEFAULT,
                "tau_width": thresholds.TAU_WIDTH_DEFAULT,
                "tau_reach": thresholds.TAU_REACH_DEFAULT,
            },
            description="cutting: U_τ if robust, the use point on an edge (wedge angles at "
            "3 and 2 mm, edge span, edge thickness: not a thin flat, a tip, a corner or a "
            "spine) and the hand off it, on parts at least 8 mm across, behind the centre of "
            "mass",
            requires=(
                "epsilon_hand",
                "use_wedge_angle",
                "use_wedge_angle_fine",
                "use_edge_span",
                "use_edge_thickness",
                "use_clearance",
                "contact_thickness",
                "contact_width",
                "contact_reach",
                "use_force",
            ),
        ),
        make_task(
            "cut-wedge",
            _cut_wedge,
            thresholds={
                "tau_eps": thresholds.TAU_EPS_DEFAULT,
                "tau_wedge": thresholds.TAU_WEDGE_DEFAULT,
                "tau_clear": thresholds.TAU_CLEARANCE_DEFAULT,
                "tau_thick": thresholds.TAU_THICKNESS_DEFAULT,
                "tau_reach": thresholds.TAU_REACH_DEFAULT,
            },
            description="cutting with the 3 mm wedge test alone: U_τ if robust, the use point "
            "on an edge (wedge angle at 3 mm) and the hand off it, behind the centre of mass",
            requires=(
                "epsilon_hand",
                "use_wedge_angle",
                "use_clearance",
                "contact_thickness",
                "contact_reach",
                "use_force",
            ),
        ),
        make_task(
            "cut-dihedral",
            _cut_dihedral,
            thresholds={
                "tau_eps": thresholds.TAU_EPS_DEFAULT,
                "tau_angle": thresholds.TAU_EDGE_ANGLE_DEFAULT,
            },
            description="cutting: U_τ if robust and a mesh edge near U is sharp (dihedral)",
            requires=("epsilon", "use_edge_angle", "use_force"),
        ),
        make_task(
            "cut-ug",
            _cut_ug,
            thresholds={"tau_eps": thresholds.TAU_EPS_DEFAULT, "tau_ug": thresholds.TAU_UG_DEFAULT},
            description="cutting as in the paper: U_τ if robust and U_g >= τ_Ug",
            requires=("epsilon", "use_edge", "use_force"),
        ),
        make_task(
            "pick-paper",
            _pick,
            thresholds={},
            description="picking: minus the total hold effort",
            requires=HOLD_EFFORT_COLUMNS,
        ),
        make_task(
            "viable",
            _viable,
            thresholds={
                "eps_min": thresholds.VIABLE_EPS_MIN,
                "hold_max": thresholds.VIABLE_HOLD_MAX,
                "impact_max": thresholds.VIABLE_IMPACT_MAX,
            },
            modes={
                "paper": thresholds.PAPER_VIABLE,
                "paper-extra-robustness": thresholds.PAPER_VIABLE,
            },
            description="viable grasp (learning ground truth): 1 or 0",
            requires=("epsilon", *HOLD_EFFORT_COLUMNS, "impact_effort"),
        ),
    ]
