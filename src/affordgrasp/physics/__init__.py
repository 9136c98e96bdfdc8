"""Physical truth: validate grasps in MuJoCo and measure how well the metrics predict it.

Optional extra: ``pip install "affordgrasp[physics]"`` (MuJoCo and CoACD, imported on first
use). See docs/physics.md.

* :mod:`.settings` — the protocol's numbers (:class:`PhysicsSettings`);
* :mod:`.decompose` — convex decomposition of an object, cached per mesh hash;
* :mod:`.scene` — the MuJoCo model of a hand and an object, built from our data;
* :mod:`.trials` — squeeze, hold test, impact test, press test of one grasp;
* :mod:`.task_scene` — the task trials' model: the grasp scene, a wrist, a nail, a workpiece;
* :mod:`.task_trials` — the task trials: beat (blows on a nail), cut (an edge drawn over a
  workpiece), pick (the hold test);
* :mod:`.run` — a dataset's grasps validated into sharded, resumable Parquet;
* :mod:`.report` — ROC-AUC and Spearman of metrics and task scores against the outcomes.
"""

from __future__ import annotations

import importlib

from .settings import PhysicsSettings, TrialSettings

__all__ = [
    "GraspOutcome",
    "PhysicsSettings",
    "TrialSettings",
    "build_scene",
    "build_task_scene",
    "physics_report",
    "read_outcomes",
    "run_physics",
    "run_task_trials",
    "validate_grasp",
]


# Served from their modules on first access: MuJoCo and CoACD are imported only when needed.
_EXPORTS = {
    "build_scene": "scene",
    "build_task_scene": "task_scene",
    "run_task_trials": "task_trials",
    "validate_grasp": "trials",
    "GraspOutcome": "trials",
    "run_physics": "run",
    "read_outcomes": "run",
    "physics_report": "report",
}


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
