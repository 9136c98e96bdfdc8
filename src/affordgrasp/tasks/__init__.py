"""Affordance functions F_T over the metric vector Φ, and their registry.

A task maps metric columns to one float64 score per grasp (higher is better, -inf for
"not usable for this task"). Thresholds are parameters: every task has default
thresholds, per-mode overrides (the paper's Table I modes) and accepts call-time
overrides::

    import affordgrasp as ag
    beat = ag.get_task("beat")
    scores = beat.evaluate(table, mode="extra-robustness")      # dict, Arrow or pandas
    scores = beat.evaluate(table, tau_delta=0.9)                # one threshold changed

Built-in tasks (paper §III; ``ΣE_h`` is the sum of the six hold efforts):

* ``beat``: -inf if ε < τ_ε (``epsilon_hand``: torques over min(r_max, 0.25 m)) or δ < τ_δ
  or ΣE_h = inf, or the use point is not blunt
  (``use_wedge_angle`` < τ_blunt, 135°) or a contact is within τ_clear (35 mm) of it
  (``use_clearance``) or one touches material thinner than τ_thick (8 mm,
  ``contact_thickness``) or U is nearer the wrist axis than the centre of mass
  (``use_lever_ratio`` < 1, signed: the centre of mass on U's side of the axis) or the
  mass is in the inner half of the lever (``use_lever_ratio`` > 2), or U is not a striking
  surface: less than τ_depth of solid behind it (``use_depth``), its surroundings off their
  plane by more than τ_relief within 5 mm (``use_relief``), or its normal off its swing
  velocity (``use_swing_cosine`` < τ_swing), else I / E_i (0 when E_i = inf);
* ``beat-paper``: the paper's beat (on ``epsilon``), without the tests of the use point and
  the hand;
* ``cut``: -inf if ε < τ_ε (``epsilon_hand``), or the use point is not on an edge
  (``use_wedge_angle``, the opening of the solid within 3 mm, > τ_wedge, 55°), or a
  contact is within τ_clear (35 mm) of it or on material thinner than τ_thick (8 mm: the
  blade), or past the centre
  of mass towards U along the long axis by more than half of U's offset (``contact_reach``
  > τ_reach, 0.5), or the use point is a thin flat, a tip or a thin part's corner rather
  than an edge (``use_wedge_angle_fine``, the same opening within 2 mm, > τ_wedge_fine, or
  ``use_edge_span`` < τ_span), or a thin plate's end such as a knife's spine
  (``use_edge_thickness``, the part's thickness at U from chords 1 and 3 mm behind it,
  > τ_edge_thickness, 0.7 mm, or NaN), or a contact is on a part narrower than τ_width (8 mm)
  across (``contact_width``: a finger on a blade's spine), else U_τ;
* ``cut-wedge``: cut with the 3 mm wedge test alone (without ``use_wedge_angle_fine``,
  ``use_edge_span`` and ``use_edge_thickness``) and without the width test;
* ``cut-dihedral``: the edge test on the sharpest mesh dihedral within 3 mm
  (``use_edge_angle`` <= τ_angle) instead, no clearance (crisp meshes only: a scanner
  rounds the mesh's edges away);
* ``cut-ug``: the paper's form, with the edge test U_g >= τ_Ug;

* ``pick``: -ΣE_h;
* ``viable``: 1.0 if ε > τ_ε,viable and ΣE_h < 250 and E_i < τ_Ei, else 0.0 (the learning
  ground truth; :func:`is_viable` returns the boolean mask).

A row without a use point (its use ray left a hollow object through its opening) has NaN
use metrics; every comparison with NaN is false, so such a row is -inf for beat and cut,
scores as usual for pick, and counts as not viable only through NaN ``impact_effort``.

Modes: ``default`` (τ_ε = 0.014, calibrated), ``no-robustness`` (τ_ε = -inf),
``extra-robustness`` (τ_ε = 0.024), and the paper's literal values ``paper`` (τ_ε = 0.3;
viable: ε > 0.15, E_i < 100) and ``paper-extra-robustness`` (τ_ε = 0.5); τ_δ = 0.95 and
the edge thresholds are the same in every mode. Why the defaults differ from the paper's
Table I, with the numbers, is in the comments of the thresholds below and in
``docs/validation.md``.

Adding tasks without editing the package:

* Python: ``register_task("pry", func, thresholds={...}, requires=[...])`` with
  ``func(metrics, thresholds) -> (n,) float array``; ``metrics`` maps column names to
  float arrays (plus the derived ``hold_effort_sum``);
* a TOML file, loaded with :func:`load_task_file` or listed in the ``AFFORDGRASP_TASKS``
  environment variable (paths separated by ``os.pathsep``; read once, at the first
  lookup)::

      [tasks.pry]
      description = "lever something open"
      value = "use_force / impact_effort"
      requires = "epsilon >= tau_eps and discharge >= 0.5"   # failing rows score -inf
      [tasks.pry.thresholds]
      tau_eps = 0.3
      [tasks.pry.modes.extra-robustness]
      tau_eps = 0.5

  Expressions are restricted (:mod:`affordgrasp.tasks.expressions`): names, numbers,
  arithmetic, comparisons, ``and``/``or``/``not`` and :data:`EXPRESSION_FUNCTIONS`.

Layout: :mod:`.task` (the :class:`Task` type), :mod:`.thresholds` (defaults and modes),
:mod:`.builtins`, :mod:`.expressions`, :mod:`.toml` (task files), :mod:`.metric_columns`
(reading columns from any table type) and :mod:`.registry` (:data:`TASKS`).
"""

from __future__ import annotations

from ..columns import DERIVED_COLUMNS, HOLD_EFFORT_COLUMNS
from .expressions import EXPRESSION_CONSTANTS, EXPRESSION_FUNCTIONS, Expression, expression_task
from .metric_columns import MetricColumns
from .registry import (
    ENV_VAR,
    TASKS,
    TaskRegistry,
    evaluate_task,
    get_task,
    is_viable,
    list_tasks,
    load_task_file,
    register_task,
    task_from_expressions,
    unregister_task,
)
from .task import Task, TaskFunction, make_task
from .thresholds import (
    MODES,
    TAU_BLUNT_DEFAULT,
    TAU_CLEARANCE_DEFAULT,
    TAU_DELTA_DEFAULT,
    TAU_DEPTH_DEFAULT,
    TAU_EDGE_ANGLE_DEFAULT,
    TAU_EDGE_THICKNESS_DEFAULT,
    TAU_EPS_DEFAULT,
    TAU_EPS_EXTRA,
    TAU_EPS_VIABLE,
    TAU_LEVER_DEFAULT,
    TAU_LEVER_MAX_DEFAULT,
    TAU_REACH_DEFAULT,
    TAU_RELIEF_DEFAULT,
    TAU_SPAN_DEFAULT,
    TAU_SWING_DEFAULT,
    TAU_THICKNESS_DEFAULT,
    TAU_UG_DEFAULT,
    TAU_WEDGE_DEFAULT,
    TAU_WEDGE_FINE_DEFAULT,
    TAU_WIDTH_DEFAULT,
    VIABLE_EPS_MIN,
    VIABLE_HOLD_MAX,
    VIABLE_IMPACT_MAX,
)
from .toml import read_task_file

__all__ = [
    "DERIVED_COLUMNS",
    "ENV_VAR",
    "EXPRESSION_CONSTANTS",
    "EXPRESSION_FUNCTIONS",
    "HOLD_EFFORT_COLUMNS",
    "MODES",
    "TASKS",
    "TAU_DELTA_DEFAULT",
    "TAU_DEPTH_DEFAULT",
    "TAU_RELIEF_DEFAULT",
    "TAU_SWING_DEFAULT",
    "TAU_BLUNT_DEFAULT",
    "TAU_CLEARANCE_DEFAULT",
    "TAU_EDGE_ANGLE_DEFAULT",
    "TAU_EDGE_THICKNESS_DEFAULT",
    "TAU_THICKNESS_DEFAULT",
    "TAU_EPS_DEFAULT",
    "TAU_EPS_EXTRA",
    "TAU_LEVER_DEFAULT",
    "TAU_LEVER_MAX_DEFAULT",
    "TAU_REACH_DEFAULT",
    "TAU_EPS_VIABLE",
    "TAU_UG_DEFAULT",
    "TAU_SPAN_DEFAULT",
    "TAU_WEDGE_DEFAULT",
    "TAU_WEDGE_FINE_DEFAULT",
    "TAU_WIDTH_DEFAULT",
    "VIABLE_EPS_MIN",
    "VIABLE_HOLD_MAX",
    "VIABLE_IMPACT_MAX",
    "Expression",
    "MetricColumns",
    "Task",
    "TaskFunction",
    "TaskRegistry",
    "evaluate_task",
    "expression_task",
    "get_task",
    "is_viable",
    "list_tasks",
    "load_task_file",
    "make_task",
    "read_task_file",
    "register_task",
    "task_from_expressions",
    "unregister_task",
]
