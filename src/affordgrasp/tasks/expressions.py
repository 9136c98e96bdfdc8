"""Restricted expressions over metric and threshold names, for declarative tasks.

Expressions are parsed with :mod:`ast` and evaluated by a small evaluator: names (metric
columns, ``hold_effort_sum``, the task's thresholds, ``inf``, ``pi``), numbers, arithmetic,
comparisons, ``and``/``or``/``not`` (element-wise) and the functions
:data:`EXPRESSION_FUNCTIONS`; anything else is refused with a :class:`TaskError` naming
the offending token.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, cast

import numpy as np

from ..columns import DERIVED_COLUMNS
from ..errors import TaskError
from .metric_columns import MetricColumns
from .task import Task, make_task


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


# A task expression is a formula over a few dozen names: these bounds keep the parser and
# the recursive checker and evaluator far from Python's limits (a sum of n terms nests n
# deep), whatever a task file holds.
MAX_EXPRESSION_CHARS = 2000
MAX_EXPRESSION_DEPTH = 100


def _depth(tree: ast.AST) -> int:
    """Nesting depth of a syntax tree, counted without recursion."""
    deepest, stack = 0, [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))
    return deepest


class Expression:
    """A parsed, checked task expression over metric and threshold names.

    Parameters
    ----------
    source : str
        The expression (``"use_force * (epsilon > tau_eps)"``): numbers, names, arithmetic,
        comparisons, ``and``/``or``/``not`` and the functions the task format allows.
    where : str
        How error messages name the expression (``"task 'cut': value"``).
    """

    def __init__(self, source: str, *, where: str = "expression"):
        if not isinstance(source, str) or not source.strip():
            raise TaskError(f"{where} must be a non-empty string, got {source!r}")
        if len(source) > MAX_EXPRESSION_CHARS:
            raise TaskError(
                f"{where} is {len(source):,} characters long; a task expression may have at "
                f"most {MAX_EXPRESSION_CHARS:,} (split it with thresholds or several tasks)"
            )
        self.source = source
        try:
            tree = ast.parse(source.strip(), mode="eval")
        except (SyntaxError, RecursionError, MemoryError) as exc:
            why = getattr(exc, "msg", None) or "it nests too deep"
            raise TaskError(f"{where} {source!r} is not a valid expression: {why}") from None
        if _depth(tree) > MAX_EXPRESSION_DEPTH:
            raise TaskError(
                f"{where} nests {_depth(tree)} levels deep; a task expression may nest at most "
                f"{MAX_EXPRESSION_DEPTH} (a sum of n terms nests n deep: use fewer terms)"
            )
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
        """The expression's value with ``names`` bound.

        Parameters
        ----------
        names : mapping of str to float or ndarray
            A value for every name of :attr:`names` (metric columns as (n,) arrays, thresholds
            as floats); numpy broadcasting applies.

        Returns
        -------
        float, bool or ndarray
            Of the broadcast shape of the inputs.
        """
        return self._eval(self._tree, names)

    def _eval(self, node: ast.AST, env: Mapping[str, Any]) -> Any:
        if isinstance(node, ast.Constant):
            return float(cast(float, node.value))  # _check admitted numbers only
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
            fn = EXPRESSION_FUNCTIONS[cast(ast.Name, node.func).id]
            return fn(*(self._eval(a, env) for a in node.args))
        raise TaskError(f"cannot evaluate {type(node).__name__}")  # unreachable after _check


class _ExpressionTask:
    """A task function built from ``value`` and ``requires`` expressions."""

    def __init__(self, value: Expression, requires: Expression | None):
        self.value = value
        self.requires = requires

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


def expression_task(
    name: str,
    value: str,
    requires: str | None = None,
    thresholds: Mapping[str, float] | None = None,
    modes: Mapping[str, Mapping[str, float]] | None = None,
    description: str = "",
) -> Task:
    """A declarative task: ``value`` where the ``requires`` expression holds, else -inf.

    Parameters
    ----------
    name : str
        Registry name.
    value : str
        Expression of the task value over metric columns and thresholds.
    requires : str, optional
        Boolean expression a grasp must satisfy; elsewhere the value is -inf.
    thresholds : mapping of str to float, optional
        Default threshold values (names used by the expressions).
    modes : mapping of str to mapping, optional
        Mode name to threshold overrides.
    description : str
        One line for listings.

    Returns
    -------
    Task
        Checked, not registered; its ``requires`` are the columns the expressions read.
    """
    thresholds = dict(thresholds or {})
    value_expr = Expression(value, where=f"task {name!r} value")
    req_expr = Expression(requires, where=f"task {name!r} requires") if requires else None
    names = set(value_expr.names) | (req_expr.names if req_expr else set())
    metric_names = sorted(names - set(thresholds))
    func = _ExpressionTask(value_expr, req_expr)
    return make_task(
        name,
        func,
        thresholds=thresholds,
        modes=modes,
        description=description,
        requires=[n for n in metric_names if n not in DERIVED_COLUMNS]
        + [n for n in metric_names if n in DERIVED_COLUMNS],
    )
