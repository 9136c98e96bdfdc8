"""Searching for the best grasps: ranking rows by a score and the cross-entropy optimiser.

* :mod:`~affordgrasp.search.ranking`: :class:`TopRows` and :func:`top_indices`, the one ranker
  (highest score first, −∞ and NaN never rank, ties by keys);
* :mod:`~affordgrasp.search.cem`: :func:`cem_maximize` (the cross-entropy method over the
  (p0, d) box) and :func:`cem_search` (restarts sharing a budget, then a refinement);
* :mod:`~affordgrasp.search.guidance`: how close an infeasible grasp came to a usable one.

The searches on the simulator built on them are :func:`affordgrasp.optimize.optimize` and
:mod:`affordgrasp.pairs` (grasps × use points); the brute-force argmax over a dataset is
:func:`affordgrasp.dataset.best.best_grasps`.
"""

from .cem import CEMState, CEMTrace, cem_maximize, cem_search, plan_runs, uniform_inputs
from .guidance import guidance
from .ranking import TopRows, best_index, top_indices

__all__ = [
    "CEMState",
    "CEMTrace",
    "TopRows",
    "best_index",
    "cem_maximize",
    "cem_search",
    "guidance",
    "plan_runs",
    "top_indices",
    "uniform_inputs",
]
