"""The built-in affordance functions of the paper (§III) and the learning ground truth."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..columns import HOLD_EFFORT_COLUMNS
from .task import Task, make_task
from .thresholds import (
    PAPER_VIABLE,
    TAU_DELTA_DEFAULT,
    TAU_EDGE_ANGLE_DEFAULT,
    TAU_EPS_DEFAULT,
    TAU_UG_DEFAULT,
    VIABLE_EPS_MIN,
    VIABLE_HOLD_MAX,
    VIABLE_IMPACT_MAX,
)


def _beat(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (
        (m["epsilon"] >= t["tau_eps"])
        & (m["discharge"] >= t["tau_delta"])
        & np.isfinite(m["hold_effort_sum"])
    )
    # E_i = inf (the impact cannot be held) gives I / inf = 0, the paper's formula as is
    return np.where(ok, m["inertia"] / m["impact_effort"], -np.inf)


def _cut(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
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
    """Fresh Task objects of the built-in tasks: beat, cut, cut-ug, pick, viable.

    Returns
    -------
    list of Task
        New objects on every call (a registry may replace them without touching others).
    """
    return [
        make_task(
            "beat",
            _beat,
            thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_delta": TAU_DELTA_DEFAULT},
            description="beating by a wrist rotation: I / E_i if robust and discharging",
            requires=("epsilon", "discharge", *HOLD_EFFORT_COLUMNS, "inertia", "impact_effort"),
        ),
        make_task(
            "cut",
            _cut,
            thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_angle": TAU_EDGE_ANGLE_DEFAULT},
            description="cutting: U_τ if robust and the use point is on a sharp edge (angle)",
            requires=("epsilon", "use_edge_angle", "use_force"),
        ),
        make_task(
            "cut-ug",
            _cut_ug,
            thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_ug": TAU_UG_DEFAULT},
            description="cutting as in the paper: U_τ if robust and U_g >= τ_Ug",
            requires=("epsilon", "use_edge", "use_force"),
        ),
        make_task(
            "pick",
            _pick,
            thresholds={},
            description="picking: minus the total hold effort",
            requires=HOLD_EFFORT_COLUMNS,
        ),
        make_task(
            "viable",
            _viable,
            thresholds={
                "eps_min": VIABLE_EPS_MIN,
                "hold_max": VIABLE_HOLD_MAX,
                "impact_max": VIABLE_IMPACT_MAX,
            },
            modes={"paper": PAPER_VIABLE, "paper-extra-robustness": PAPER_VIABLE},
            description="viable grasp (learning ground truth): 1 or 0",
            requires=("epsilon", *HOLD_EFFORT_COLUMNS, "impact_effort"),
        ),
    ]
