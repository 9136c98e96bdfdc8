"""affordgrasp: task-oriented grasp quality metrics, datasets and learning.

The front door::

    import affordgrasp as ag

    knife = ag.load_object("knife:3")                 # a family variant, or a mesh path
    result = ag.evaluate(knife, samples=200, seed=0)  # simulate + metric vector Φ
    scores = result.scores("cut", mode="no-robustness")
    ag.generate(["knife", "mug"], samples=10_000, out="data/tools")
    table = ag.read_dataset("data/tools", columns=["object", "epsilon"])

=====================  ===================================================================
name                   what
=====================  ===================================================================
``load_object``        a :class:`GraspObject` from ``"knife"``, ``"knife:7"`` or a mesh path
``get_hand``           a :class:`Hand` by name or hand file; ``register_hand`` adds one
``get_task``           a :class:`Task` (affordance function) by name; ``register_task``
``ContactSet``         contacts from any source, for the metric functions
                       (:mod:`affordgrasp.metrics`)
``evaluate``           simulate and score grasps: an :class:`Evaluation`
``generate``           a sharded, resumable Parquet dataset (``.dataset`` opens it)
``Dataset``            a dataset directory opened once: plan, hand, objects, rows
``read_dataset``       a dataset as an Arrow table
``best_grasps``        the argmax of a task over a dataset
``plan``               a grasp chosen by learned models from camera-in-hand views, checked
                       in simulation: a :class:`Plan`
``RobustSettings``     perturbations of robust evaluation (``evaluate(..., robust=K)``)
=====================  ===================================================================

Names are imported on first use, so ``import affordgrasp`` stays fast. Units, frames and
the definitions of every metric are in docs/conventions.md; a docstring that says
"conventions: Metrics" refers to that page's section *Metrics*.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._version import __version__ as __version__

# public name -> module that defines it (imported on first access)
_EXPORTS = {
    "load_object": "affordgrasp.objects.resolve",
    "GraspObject": "affordgrasp.objects.resolve",
    "list_families": "affordgrasp.objects.resolve",
    "get_hand": "affordgrasp.hands",
    "register_hand": "affordgrasp.hands",
    "list_hands": "affordgrasp.hands",
    "load_hand": "affordgrasp.hands",
    "save_hand": "affordgrasp.hands",
    "Hand": "affordgrasp.hands",
    "get_task": "affordgrasp.tasks",
    "register_task": "affordgrasp.tasks",
    "list_tasks": "affordgrasp.tasks",
    "load_task_file": "affordgrasp.tasks",
    "Task": "affordgrasp.tasks",
    "ContactSet": "affordgrasp.metrics.contacts",
    "evaluate": "affordgrasp.pipeline",
    "Evaluation": "affordgrasp.pipeline",
    "generate": "affordgrasp.dataset.generate",
    "Dataset": "affordgrasp.dataset.handle",
    "read_dataset": "affordgrasp.dataset.reading",
    "best_grasps": "affordgrasp.search.best",
    "plan": "affordgrasp.learning.plan",
    "Plan": "affordgrasp.learning.plan",
    "RobustSettings": "affordgrasp.robust",
}

if TYPE_CHECKING:
    from .dataset.generate import generate
    from .dataset.handle import Dataset
    from .dataset.reading import read_dataset
    from .hands import Hand, get_hand, list_hands, load_hand, register_hand, save_hand
    from .learning.plan import Plan, plan
    from .metrics.contacts import ContactSet
    from .objects.resolve import GraspObject, list_families, load_object
    from .pipeline import Evaluation, evaluate
    from .robust import RobustSettings
    from .search.best import best_grasps
    from .tasks import Task, get_task, list_tasks, load_task_file, register_task


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


__all__ = [
    "ContactSet",
    "Dataset",
    "Evaluation",
    "GraspObject",
    "Hand",
    "Plan",
    "RobustSettings",
    "Task",
    "best_grasps",
    "evaluate",
    "generate",
    "get_hand",
    "get_task",
    "list_families",
    "list_hands",
    "list_tasks",
    "load_hand",
    "load_object",
    "load_task_file",
    "plan",
    "read_dataset",
    "register_hand",
    "register_task",
    "save_hand",
]
