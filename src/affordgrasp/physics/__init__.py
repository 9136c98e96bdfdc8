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


def __getattr__(name: str):
    if name in ("build_scene",):
        from .scene import build_scene

        return build_scene
    if name == "build_task_scene":
        from .task_scene import build_task_scene

        return build_task_scene
    if name == "run_task_trials":
        from .task_trials import run_task_trials

        return run_task_trials
    if name in ("validate_grasp", "GraspOutcome"):
        from . import trials

        return getattr(trials, name)
    if name in ("run_physics", "read_outcomes"):
        from . import run

        return getattr(run, name)
    if name == "physics_report":
        from .report import physics_report

        return physics_report
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
