"""The paper's validation (§IV-C, Figs. 3-7): are the best grasps of each task semantically right?

* :mod:`~affordgrasp.validation.judges`: the judges by the families' semantic parts (the
  cutting edge for cut, the working end for beat, contacts around the centre of mass for
  pick);
* :mod:`~affordgrasp.validation.study`: :func:`validate_tasks`, the brute force and the
  optimiser on every judged family and seed, with figures (``affordgrasp validate``).

docs/validation.md §5 has the results and how they were run.
"""

from .judges import (
    TASK_FAMILIES,
    WORKING_END,
    WORKING_END_GROW_M,
    judge,
    scored,
    surrounds_com,
    working_end_box,
)
from .study import (
    MODES,
    ValidationSettings,
    brute_force,
    grasp_table,
    render_figures,
    validate_tasks,
)

__all__ = [
    "MODES",
    "TASK_FAMILIES",
    "WORKING_END",
    "WORKING_END_GROW_M",
    "ValidationSettings",
    "brute_force",
    "grasp_table",
    "judge",
    "render_figures",
    "scored",
    "surrounds_com",
    "validate_tasks",
    "working_end_box",
]
