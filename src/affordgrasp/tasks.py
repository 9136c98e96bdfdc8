"""Affordance functions F_T over the metric vector Φ, and their registry (SPEC §2.5).

A task maps metric columns to one float64 score per grasp (higher is better, -inf for
"not usable for this task"). Thresholds are parameters: every task has default
thresholds, per-mode overrides (the paper's Table I modes) and accepts call-time
overrides::

    from affordgrasp import tasks
    beat = tasks.get_task("beat")
    scores = beat.evaluate(table, mode="extra-robustness")      # dict, Arrow or pandas
    scores = beat.evaluate(table, tau_delta=0.9)                # one threshold changed

Built-in tasks (paper §III; ``ΣE_h`` is the sum of the six hold efforts):

* ``beat``: -inf if ε < τ_ε or δ < τ_δ or ΣE_h = inf, else I / E_i (0 when E_i = inf);
* ``cut``: -inf if ε < τ_ε or U_g < τ_Ug, else U_τ;
* ``cut-angle``: as ``cut`` with the resolution-independent edge test
  ``use_edge_angle <= τ_angle`` instead of U_g;
* ``pick``: -ΣE_h;
* ``viable``: 1.0 if ε > 0.15 and ΣE_h < 250 and E_i < 100, else 0.0 (the learning
  ground truth; :func:`is_viable` returns the boolean mask).

Modes: ``default`` (τ_ε = 0.3), ``no-robustness`` (τ_ε = -inf), ``extra-robustness``
(τ_ε = 0.5); τ_δ = 0.95 and the edge thresholds are the same in every mode.

Adding tasks without editing the package:

* Python: ``register_task("pry", func, thresholds={...}, requires=[...])`` with
  ``func(metrics, thresholds) -> (n,) float array``; ``metrics`` maps column names to
  float arrays (plus the derived ``hold_effort_sum``);
* a TOML file, loaded with :func:`load_task_file` or listed in the ``AFFORDGRASP_TASKS``
  environment variable (paths separated by ``os.pathsep``)::

      [tasks.pry]
      description = "lever something open"
      value = "use_force / impact_effort"
      requires = "epsilon >= tau_eps and discharge >= 0.5"   # failing rows score -inf
      [tasks.pry.thresholds]
      tau_eps = 0.3
      [tasks.pry.modes.extra-robustness]
      tau_eps = 0.5

  Expressions are parsed with :mod:`ast` and evaluated by a restricted evaluator: names
  (metric columns, ``hold_effort_sum``, the task's thresholds, ``inf``, ``pi``), numbers,
  arithmetic, comparisons, ``and``/``or``/``not`` (element-wise) and the functions
  :data:`EXPRESSION_FUNCTIONS`; anything else is refused with a :class:`TaskError`
  naming the offending token.
"""

from __future__ import annotations

import ast
import logging
import math
import os
import tomllib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .errors import TaskError

log = logging.getLogger(__name__)

HOLD_EFFORT_COLUMNS = tuple(f"hold_effort_{s}" for s in ("px", "nx", "py", "ny", "pz", "nz"))
DERIVED_COLUMNS = ("hold_effort_sum",)

# --------------------------------------------------------------------------------------
# thresholds
# --------------------------------------------------------------------------------------

TAU_EPS_DEFAULT = 0.3  # paper, Table I
TAU_EPS_EXTRA = 0.5  # paper, Table I, "extra robustness required"
TAU_DELTA_DEFAULT = 0.95  # paper, Table I

# Edge thresholds, calibrated with benchmarks/calibrate_use_edge.py on the built-in
# families (knife, meat_cleaver, axe, dagger, sword; 6 seeds each; 300 direction-mapping
# use points + 300 surface samples + 100 cutting-edge samples per mesh; "edge" = within
# 0.5 mm of the geometric cutting edge, about 3.1k points; "other" = farther than 3 mm on
# the blades, about 17.1k points, plus every point of hammer, screwdriver, bottle and mug,
# 14.2k). Run-to-run differences of ray casting move these numbers in the second digit.
#
# U_g does not separate them: percentiles 5/50/95 are about 0.1 / 800 / 4.5e4 m^-2 on the
# cutting edges and 70 / 2.4e3 / 3.7e4 on blade flats, spines and handles. Two causes,
# both intrinsic to the definition: (1) resolution: U_g scales as 1/h² with the size h of
# the fitted neighbourhood, and the blades' cutting edges are lines of long mesh edges
# (median 3 mm, up to 0.1-0.5 m) with sliver triangles, while spines, bolsters and
# handles have small triangles at their creases; (2) the height function fitted over one
# flank of an acute wedge sees the other flank fold back under the same tangent plane, so
# a sharp edge scores lower than a blunt crease (on one isotropic mesh a 20° edge gives a
# third of a 60° one; tests/metrics/test_use_geometry.py). The threshold that maximises
# the balanced accuracy is kept as the default (3e4 m^-2, balanced accuracy 0.50-0.51:
# about 7% of edge points pass, 94% of the others fail); use the "cut-angle" task
# (use_edge_angle) for cutting with the built-in blades.
TAU_UG_DEFAULT = 3.0e4
# The sharpest-edge angle separates perfectly: cutting-edge points have 14.3-24.5 degrees
# (all of them), other points 89-180 degrees (1st-100th percentile; the lowest non-edge
# value is 65.7 degrees); 45 degrees is the middle of the threshold
# plateau [25, 65] degrees where the balanced accuracy is 1.0.
TAU_EDGE_ANGLE_DEFAULT = math.radians(45.0)

# viable grasp (paper §III-B / SPEC §2.5)
VIABLE_EPS_MIN = 0.15
VIABLE_HOLD_MAX = 250.0
VIABLE_IMPACT_MAX = 100.0

MODES: tuple[str, ...] = ("default", "no-robustness", "extra-robustness")
_MODE_EPS = {
    "default": TAU_EPS_DEFAULT,
    "no-robustness": -math.inf,
    "extra-robustness": TAU_EPS_EXTRA,
}


def _standard_modes(thresholds: Mapping[str, float]) -> dict[str, dict[str, float]]:
    """Table I modes restricted to the thresholds a task has (only τ_ε changes)."""
    modes: dict[str, dict[str, float]] = {}
    for mode, tau in _MODE_EPS.items():
        modes[mode] = {"tau_eps": tau} if "tau_eps" in thresholds else {}
    return modes


# --------------------------------------------------------------------------------------
# metric access
# --------------------------------------------------------------------------------------


class MetricColumns(Mapping):
    """Read-only view of metric columns as float64 arrays, with derived columns.

    Accepts a mapping of name -> array, a pyarrow Table or a pandas DataFrame. A missing
    column raises a :class:`TaskError` that lists the available ones.
    """

    def __init__(self, columns: Any):
        self._source = columns
        self._cache: dict[str, np.ndarray] = {}
        self._names = _column_names(columns)

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self._cache:
            return self._cache[name]
        if name == "hold_effort_sum":
            value = np.sum([self[c] for c in HOLD_EFFORT_COLUMNS], axis=0)
        elif name in self._names:
            value = _column_as_float(self._source, name)
        else:
            raise TaskError(
                f"metric column {name!r} is missing; available: {', '.join(sorted(self._names))}"
            )
        self._cache[name] = value
        return value

    def __iter__(self):
        return iter(list(self._names) + list(DERIVED_COLUMNS))

    def __len__(self) -> int:
        return len(self._names) + len(DERIVED_COLUMNS)

    def __contains__(self, name: object) -> bool:
        return name in self._names or name in DERIVED_COLUMNS

    @property
    def n_rows(self) -> int:
        """Number of rows, read without converting any column (some are strings)."""
        src = self._source
        if hasattr(src, "num_rows"):  # pyarrow
            return int(src.num_rows)
        if hasattr(src, "columns") and hasattr(src, "to_numpy"):  # pandas
            return len(src)
        for name in self._names:
            col = src[name]
            return len(col) if hasattr(col, "__len__") else int(np.shape(col)[0])
        return 0


def _column_names(columns: Any) -> tuple[str, ...]:
    if hasattr(columns, "column_names"):  # pyarrow Table / RecordBatch
        return tuple(columns.column_names)
    if hasattr(columns, "columns") and hasattr(columns, "to_numpy"):  # pandas DataFrame
        return tuple(str(c) for c in columns.columns)
    if isinstance(columns, Mapping):
        return tuple(str(c) for c in columns.keys())
    raise TaskError(
        "metric columns must be a mapping of name -> array, a pyarrow Table or a pandas "
        f"DataFrame, got {type(columns).__name__}"
    )


def _column_as_float(source: Any, name: str) -> np.ndarray:
    if hasattr(source, "column_names"):
        col = source.column(name)
        col = col.to_numpy() if hasattr(col, "to_numpy") else np.asarray(col)
    else:
        col = source[name]
        if hasattr(col, "to_numpy"):
            col = col.to_numpy()
    try:
        arr = np.asarray(col, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise TaskError(f"metric column {name!r} is not numeric") from exc
    return arr


# --------------------------------------------------------------------------------------
# tasks
# --------------------------------------------------------------------------------------

TaskFunction = Callable[[Mapping[str, np.ndarray], Mapping[str, float]], np.ndarray]


@dataclass(frozen=True)
class Task:
    """An affordance function with its thresholds.

    name : registry name
    func : ``func(metrics, thresholds) -> (n,) float64``
    thresholds : default threshold values by name
    modes : mode name -> threshold overrides of that mode
    description : one line for listings
    requires : metric columns the function reads
    """

    name: str
    func: TaskFunction
    thresholds: Mapping[str, float] = field(default_factory=dict)
    modes: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    description: str = ""
    requires: tuple[str, ...] = ()

    def thresholds_for(self, mode: str = "default", **overrides: float) -> dict[str, float]:
        """Threshold values in ``mode`` with call-time ``overrides`` applied."""
        if mode not in self.modes:
            raise TaskError(
                f"task {self.name!r} has no mode {mode!r}; modes: {', '.join(self.modes)}"
            )
        values = dict(self.thresholds)
        values.update(self.modes[mode])
        for key, value in overrides.items():
            if key not in values:
                raise TaskError(
                    f"task {self.name!r} has no threshold {key!r}; thresholds: "
                    f"{', '.join(values) or 'none'}"
                )
            try:
                values[key] = float(value)
            except (TypeError, ValueError) as exc:
                raise TaskError(f"threshold {key!r} must be a number, got {value!r}") from exc
        return values

    def thresholds_by_mode(self) -> dict[str, dict[str, float]]:
        """Every mode's threshold values (for dataset cards and listings)."""
        return {mode: self.thresholds_for(mode) for mode in self.modes}

    def evaluate(self, columns: Any, mode: str = "default", **overrides: float) -> np.ndarray:
        """Score every row of ``columns`` (mapping, pyarrow Table or pandas DataFrame).

        Returns (n,) float64; -inf where the task's requirements fail.
        """
        values = self.thresholds_for(mode, **overrides)
        metrics = columns if isinstance(columns, MetricColumns) else MetricColumns(columns)
        for name in self.requires:
            metrics[name]  # fail early, naming the missing column
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            out = np.asarray(self.func(metrics, MappingProxyType(values)), dtype=np.float64)
        n = metrics.n_rows
        if out.ndim == 0:
            out = np.full(n, float(out))
        if out.shape != (n,):
            raise TaskError(
                f"task {self.name!r} returned shape {out.shape}, expected ({n},) scores"
            )
        return out

    __call__ = evaluate


def _beat(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (
        (m["epsilon"] >= t["tau_eps"])
        & (m["discharge"] >= t["tau_delta"])
        & np.isfinite(m["hold_effort_sum"])
    )
    # E_i = inf (the impact cannot be held) gives I / inf = 0, the paper's formula as is
    return np.where(ok, m["inertia"] / m["impact_effort"], -np.inf)


def _cut(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (m["epsilon"] >= t["tau_eps"]) & (m["use_edge"] >= t["tau_ug"])
    return np.where(ok, m["use_force"], -np.inf)


def _cut_angle(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    ok = (m["epsilon"] >= t["tau_eps"]) & (m["use_edge_angle"] <= t["tau_angle"])
    return np.where(ok, m["use_force"], -np.inf)


def _pick(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return -m["hold_effort_sum"]


def _viable_mask(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return (
        (m["epsilon"] > t["eps_min"])
        & (m["hold_effort_sum"] < t["hold_max"])
        & (m["impact_effort"] < t["impact_max"])
    )


def _viable(m: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
    return _viable_mask(m, t).astype(np.float64)


# --------------------------------------------------------------------------------------
# registry
# --------------------------------------------------------------------------------------

_REGISTRY: dict[str, Task] = {}
_ENV_LOADED: set[str] = set()
ENV_VAR = "AFFORDGRASP_TASKS"


def register_task(
    name: str,
    func: TaskFunction,
    thresholds: Mapping[str, float] | None = None,
    modes: Mapping[str, Mapping[str, float]] | None = None,
    description: str = "",
    requires: Iterable[str] = (),
    *,
    replace: bool = False,
) -> Task:
    """Register an affordance function under ``name`` and return its :class:`Task`.

    func : ``func(metrics, thresholds) -> (n,) float64`` (vectorised over rows)
    thresholds : default values; modes : mode -> overrides, added to the Table I modes
        (``default``, ``no-robustness``, ``extra-robustness``: they set ``tau_eps`` when
        the task has that threshold)
    requires : metric columns read by ``func`` (checked before every evaluation)
    replace : allow replacing an existing task of that name
    """
    if not isinstance(name, str) or not name.strip():
        raise TaskError(f"a task name must be a non-empty string, got {name!r}")
    if not callable(func):
        raise TaskError(f"task {name!r}: func must be callable, got {type(func).__name__}")
    if name in _REGISTRY and not replace:
        raise TaskError(f"task {name!r} is already registered (pass replace=True to replace it)")
    thresholds = {str(k): float(v) for k, v in (thresholds or {}).items()}
    # the Table I modes always exist; a task's own modes add to or refine them
    merged = _standard_modes(thresholds)
    for mode, over in (modes or {}).items():
        merged[str(mode)] = {
            **merged.get(str(mode), {}),
            **{str(k): float(v) for k, v in over.items()},
        }
    modes = merged
    for mode, over in modes.items():
        unknown = set(over) - set(thresholds)
        if unknown:
            raise TaskError(
                f"task {name!r}, mode {mode!r}: unknown thresholds {sorted(unknown)}; "
                f"declare them in thresholds ({', '.join(thresholds) or 'none'})"
            )
    task = Task(
        name=name,
        func=func,
        thresholds=MappingProxyType(thresholds),
        modes=MappingProxyType({k: MappingProxyType(v) for k, v in modes.items()}),
        description=description,
        requires=tuple(requires),
    )
    _REGISTRY[name] = task
    return task


def unregister_task(name: str) -> None:
    """Remove a task (built-in ones included) from the registry."""
    _load_env_tasks()
    if name not in _REGISTRY:
        raise TaskError(f"unknown task {name!r}; available: {', '.join(sorted(_REGISTRY))}")
    del _REGISTRY[name]


def get_task(name: str) -> Task:
    """The registered task ``name``; unknown names raise a TaskError listing the known."""
    _load_env_tasks()
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise TaskError(
            f"unknown task {name!r}; available tasks: {', '.join(sorted(_REGISTRY))}"
        ) from None


def list_tasks() -> list[str]:
    """Names of the registered tasks, sorted."""
    _load_env_tasks()
    return sorted(_REGISTRY)


def evaluate_task(name: str, columns: Any, mode: str = "default", **overrides: float) -> np.ndarray:
    """Shorthand for ``get_task(name).evaluate(columns, mode, **overrides)``."""
    return get_task(name).evaluate(columns, mode, **overrides)


def is_viable(columns: Any, **overrides: float) -> np.ndarray:
    """Boolean mask of viable grasps (ε > 0.15, ΣE_h < 250, E_i < 100 by default)."""
    task = get_task("viable")
    values = task.thresholds_for("default", **overrides)
    metrics = columns if isinstance(columns, MetricColumns) else MetricColumns(columns)
    with np.errstate(invalid="ignore"):
        return np.asarray(_viable_mask(metrics, values), dtype=bool)


# --------------------------------------------------------------------------------------
# restricted expressions for declarative tasks
# --------------------------------------------------------------------------------------


def _elementwise_min(*args):
    if len(args) < 2:
        raise TaskError("min() needs at least two arguments")
    out = args[0]
    for a in args[1:]:
        out = np.minimum(out, a)
    return out


def _elementwise_max(*args):
    if len(args) < 2:
        raise TaskError("max() needs at least two arguments")
    out = args[0]
    for a in args[1:]:
        out = np.maximum(out, a)
    return out


EXPRESSION_FUNCTIONS: Mapping[str, Callable] = MappingProxyType(
    {
        "abs": np.abs,
        "min": _elementwise_min,
        "max": _elementwise_max,
        "log": np.log,
        "log10": np.log10,
        "exp": np.exp,
        "sqrt": np.sqrt,
        "where": np.where,
        "isfinite": np.isfinite,
        "clip": np.clip,
    }
)
EXPRESSION_CONSTANTS: Mapping[str, float] = MappingProxyType({"inf": math.inf, "pi": math.pi})

_BINOPS = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: np.power,
    ast.Mod: np.mod,
}
_CMPOPS = {
    ast.Lt: np.less,
    ast.LtE: np.less_equal,
    ast.Gt: np.greater,
    ast.GtE: np.greater_equal,
    ast.Eq: np.equal,
    ast.NotEq: np.not_equal,
}


class Expression:
    """A parsed, checked task expression over metric and threshold names."""

    def __init__(self, source: str, *, where: str = "expression"):
        if not isinstance(source, str) or not source.strip():
            raise TaskError(f"{where} must be a non-empty string, got {source!r}")
        self.source = source
        try:
            tree = ast.parse(source.strip(), mode="eval")
        except SyntaxError as exc:
            raise TaskError(f"{where} {source!r} is not a valid expression: {exc.msg}") from None
        self._tree = tree.body
        self.names: set[str] = set()
        self._check(self._tree, where)

    def _check(self, node: ast.AST, where: str) -> None:
        bad = None
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, int | float):
                bad = repr(node.value)
        elif isinstance(node, ast.Name):
            if node.id.startswith("_"):
                bad = node.id
            elif node.id not in EXPRESSION_CONSTANTS:
                self.names.add(node.id)
        elif isinstance(node, ast.BinOp):
            if type(node.op) not in _BINOPS:
                bad = type(node.op).__name__
            else:
                self._check(node.left, where)
                self._check(node.right, where)
        elif isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, ast.USub | ast.UAdd | ast.Not):
                bad = type(node.op).__name__
            else:
                self._check(node.operand, where)
        elif isinstance(node, ast.BoolOp):
            for v in node.values:
                self._check(v, where)
        elif isinstance(node, ast.Compare):
            if any(type(op) not in _CMPOPS for op in node.ops):
                bad = ", ".join(type(op).__name__ for op in node.ops)
            else:
                self._check(node.left, where)
                for c in node.comparators:
                    self._check(c, where)
        elif isinstance(node, ast.Call):
            fname = node.func.id if isinstance(node.func, ast.Name) else None
            if fname is None or fname not in EXPRESSION_FUNCTIONS:
                token = fname if fname is not None else ast.unparse(node.func)
                raise TaskError(
                    f"{where} {self.source!r}: function {token!r} is not allowed; "
                    f"allowed functions: {', '.join(EXPRESSION_FUNCTIONS)}"
                )
            if node.keywords:
                bad = f"keyword argument {node.keywords[0].arg!r}"
            else:
                for a in node.args:
                    self._check(a, where)
        else:
            bad = type(node).__name__
            try:
                bad = f"{bad} `{ast.unparse(node)}`"
            except Exception:  # noqa: BLE001 - only for the message
                pass
        if bad is not None:
            raise TaskError(
                f"{where} {self.source!r}: {bad} is not allowed (only names, numbers, "
                "arithmetic, comparisons, and/or/not and the functions "
                f"{', '.join(EXPRESSION_FUNCTIONS)})"
            )

    def evaluate(self, names: Mapping[str, Any]) -> Any:
        return self._eval(self._tree, names)

    def _eval(self, node: ast.AST, env: Mapping[str, Any]) -> Any:
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id in EXPRESSION_CONSTANTS:
                return EXPRESSION_CONSTANTS[node.id]
            return env[node.id]
        if isinstance(node, ast.BinOp):
            return _BINOPS[type(node.op)](self._eval(node.left, env), self._eval(node.right, env))
        if isinstance(node, ast.UnaryOp):
            v = self._eval(node.operand, env)
            if isinstance(node.op, ast.Not):
                return np.logical_not(v)
            return np.negative(v) if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.BoolOp):
            combine = np.logical_and if isinstance(node.op, ast.And) else np.logical_or
            out = self._eval(node.values[0], env)
            for v in node.values[1:]:
                out = combine(out, self._eval(v, env))
            return out
        if isinstance(node, ast.Compare):
            left = self._eval(node.left, env)
            out = None
            for op, comp in zip(node.ops, node.comparators, strict=True):
                right = self._eval(comp, env)
                r = _CMPOPS[type(op)](left, right)
                out = r if out is None else np.logical_and(out, r)
                left = right
            return out
        if isinstance(node, ast.Call):
            fn = EXPRESSION_FUNCTIONS[node.func.id]
            return fn(*(self._eval(a, env) for a in node.args))
        raise TaskError(f"cannot evaluate {type(node).__name__}")  # unreachable after _check


class _ExpressionTask:
    """A task function built from ``value`` and ``requires`` expressions."""

    def __init__(self, value: Expression, requires: Expression | None, thresholds: set[str]):
        self.value = value
        self.requires = requires
        self.threshold_names = thresholds

    def __call__(self, metrics: Mapping[str, np.ndarray], t: Mapping[str, float]) -> np.ndarray:
        env = _Env(metrics, t)
        n = metrics.n_rows if isinstance(metrics, MetricColumns) else None
        value = np.asarray(self.value.evaluate(env), dtype=np.float64)
        if n is not None:
            value = np.broadcast_to(value, (n,))
        if self.requires is not None:
            ok = np.asarray(self.requires.evaluate(env), dtype=bool)
            value = np.where(ok, value, -np.inf)
        return value


class _Env(Mapping):
    def __init__(self, metrics: Mapping[str, np.ndarray], thresholds: Mapping[str, float]):
        self._m = metrics
        self._t = thresholds

    def __getitem__(self, name: str):
        if name in self._t:
            return self._t[name]
        return self._m[name]

    def __iter__(self):
        return iter(list(self._t) + list(self._m))

    def __len__(self) -> int:
        return len(self._t) + len(self._m)


def task_from_expressions(
    name: str,
    value: str,
    requires: str | None = None,
    thresholds: Mapping[str, float] | None = None,
    modes: Mapping[str, Mapping[str, float]] | None = None,
    description: str = "",
    *,
    replace: bool = False,
) -> Task:
    """Register a declarative task from ``value`` / ``requires`` expressions."""
    thresholds = dict(thresholds or {})
    value_expr = Expression(value, where=f"task {name!r} value")
    req_expr = Expression(requires, where=f"task {name!r} requires") if requires else None
    names = set(value_expr.names) | (req_expr.names if req_expr else set())
    metric_names = sorted(names - set(thresholds))
    func = _ExpressionTask(value_expr, req_expr, set(thresholds))
    return register_task(
        name,
        func,
        thresholds=thresholds,
        modes=modes,
        description=description,
        requires=[n for n in metric_names if n not in DERIVED_COLUMNS]
        + [n for n in metric_names if n in DERIVED_COLUMNS],
        replace=replace,
    )


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TaskError(f"{where} must be a number, got {value!r}")
    return float(value)


def load_task_file(path: str | os.PathLike, *, replace: bool = False) -> list[str]:
    """Register every task of a TOML file (see the module docstring); returns their names."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            doc = tomllib.load(fh)
    except FileNotFoundError:
        raise TaskError(f"task file {str(path)!r} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise TaskError(f"task file {str(path)!r} is not valid TOML: {exc}") from None
    section = doc.get("tasks")
    if not isinstance(section, dict) or not section:
        raise TaskError(f"task file {str(path)!r} has no [tasks.<name>] tables")
    names = []
    for name, spec in section.items():
        where = f"{path.name}: task {name!r}"
        if not isinstance(spec, dict):
            raise TaskError(f"{where} must be a table")
        unknown = set(spec) - {"value", "requires", "thresholds", "modes", "description"}
        if unknown:
            raise TaskError(
                f"{where}: unknown keys {sorted(unknown)} "
                "(allowed: value, requires, thresholds, modes, description)"
            )
        if "value" not in spec:
            raise TaskError(f"{where} needs a 'value' expression")
        thresholds = {
            str(k): _number(v, f"{where} threshold {k!r}")
            for k, v in dict(spec.get("thresholds", {})).items()
        }
        modes_in = spec.get("modes")
        modes = None
        if modes_in is not None:
            if not isinstance(modes_in, dict):
                raise TaskError(f"{where}: 'modes' must be a table of tables")
            modes = {
                str(mode): {
                    str(k): _number(v, f"{where} mode {mode!r} threshold {k!r}")
                    for k, v in dict(over).items()
                }
                for mode, over in modes_in.items()
            }
        task_from_expressions(
            str(name),
            spec["value"],
            spec.get("requires"),
            thresholds,
            modes,
            str(spec.get("description", "")),
            replace=replace,
        )
        names.append(str(name))
    log.info("loaded tasks %s from %s", ", ".join(names), path)
    return names


def _load_env_tasks() -> None:
    """Load the task files named by AFFORDGRASP_TASKS (each file once per process)."""
    value = os.environ.get(ENV_VAR, "")
    for entry in value.split(os.pathsep):
        entry = entry.strip()
        if entry and entry not in _ENV_LOADED:
            _ENV_LOADED.add(entry)
            load_task_file(entry, replace=True)


# --------------------------------------------------------------------------------------
# built-in tasks
# --------------------------------------------------------------------------------------


def _register_builtins() -> None:
    register_task(
        "beat",
        _beat,
        thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_delta": TAU_DELTA_DEFAULT},
        description="beating by a wrist rotation: I / E_i if robust and discharging",
        requires=("epsilon", "discharge", *HOLD_EFFORT_COLUMNS, "inertia", "impact_effort"),
        replace=True,
    )
    register_task(
        "cut",
        _cut,
        thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_ug": TAU_UG_DEFAULT},
        description="cutting: U_τ if robust and the use point is an edge (U_g test)",
        requires=("epsilon", "use_edge", "use_force"),
        replace=True,
    )
    register_task(
        "cut-angle",
        _cut_angle,
        thresholds={"tau_eps": TAU_EPS_DEFAULT, "tau_angle": TAU_EDGE_ANGLE_DEFAULT},
        description="cutting with the resolution-independent edge test (use_edge_angle)",
        requires=("epsilon", "use_edge_angle", "use_force"),
        replace=True,
    )
    register_task(
        "pick",
        _pick,
        thresholds={},
        description="picking: minus the total hold effort",
        requires=HOLD_EFFORT_COLUMNS,
        replace=True,
    )
    register_task(
        "viable",
        _viable,
        thresholds={
            "eps_min": VIABLE_EPS_MIN,
            "hold_max": VIABLE_HOLD_MAX,
            "impact_max": VIABLE_IMPACT_MAX,
        },
        description="viable grasp (learning ground truth): 1 or 0",
        requires=("epsilon", *HOLD_EFFORT_COLUMNS, "impact_effort"),
        replace=True,
    )


_register_builtins()
