"""Task probabilities p_T: calibrated models of the task trials' success (docs/physics.md).

A model maps a row's metric columns (Φ, the task's geometry columns and, in its robust
variant, the ``robust_*`` columns) to the probability that the grasp succeeds in the task's
physical trial (:mod:`affordgrasp.physics.task_trials`): a boosted forest of binary trees or
a linear score, then a monotone calibration map (isotonic, stored as knots). Models are
fitted by ``tools/fit_task_probabilities.py`` on procedural families with whole families and
scan-like variants held out, and shipped as JSON package data with their card (objects,
protocol, held-out numbers). Evaluating one is plain numpy (no fitting library at run time):
each tree is walked for every row at once, one level per step.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numba import njit

from ..columns import (
    HOLD_DIRS,
    HOLD_EFFORT_SUM,
    METRIC_COLUMNS,
    PROBABILITY_COLUMNS,
    USE_METRICS,
)
from ..errors import TaskError
from ..runtime.kernel_cache import install_package_stamp

__all__ = [
    "MODEL_COLUMNS",
    "MODEL_FORMAT",
    "PICK_COLUMNS",
    "ROBUST_COLUMNS",
    "probability_columns",
    "TaskModel",
    "task_model",
    "task_probability",
]

MODEL_FORMAT = "affordgrasp-task-probability"
# The columns every model reads: Φ and the use geometry; a model finds what matters to its
# task. Not the on-request GWS volume, not the text reason, and not the inertia I, the one
# metric in units of mass: it differs 2,500-fold between the paper's unit density and a
# tool's materials (the efforts are per unit weight), so a model that read it would not carry
# from the objects it was fitted on (materials) to a mesh file at any uniform density.
# A robust model reads ROBUST_COLUMNS too.
_NOT_READ = ("gws_volume", "epsilon_reason", "inertia")
MODEL_COLUMNS = tuple(c for c in METRIC_COLUMNS if c not in _NOT_READ) + (
    HOLD_EFFORT_SUM,
    HOLD_DIRS,
)
# A pick does not use a use point: its model reads the grasp's columns only.
PICK_COLUMNS = tuple(c for c in MODEL_COLUMNS if c not in USE_METRICS)
ROBUST_COLUMNS = ("robust_fc", "robust_epsilon", "robust_hold_dirs", "robust_hold")
PROBABILITY_TASKS = tuple(c.removeprefix("p_") for c in PROBABILITY_COLUMNS)
_USE_TASKS = ("beat", "cut")  # no use point, no strike or stroke: p is 0
_BIG = 1e30  # ±inf (an infeasible effort) as a finite number the trees can split on
_TRANSFORMS = ("raw", "inv1p")


install_package_stamp()  # the cache of _forest is valid by content, shippable in a wheel


@njit(cache=True)
def _forest(x, feature, threshold, left, right, nan_left, value, roots, bias):
    """Sum of the trees' leaf values for every row (compiled: a search scores millions of
    grasp × use point pairs per generation, which a per-level numpy walk does in seconds)."""
    n = x.shape[0]
    out = np.full(n, bias)
    for i in range(n):
        total = 0.0
        for r in range(roots.shape[0]):
            node = roots[r]
            while feature[node] >= 0:
                v = x[i, feature[node]]
                if np.isnan(v):
                    node = left[node] if nan_left[node] else right[node]
                elif v <= threshold[node]:
                    node = left[node]
                else:
                    node = right[node]
            total += value[node]
        out[i] += total
    return out


def transform_column(values: np.ndarray, transform: str) -> np.ndarray:
    """A metric column as the model reads it.

    Parameters
    ----------
    values : (n,) float ndarray
    transform : str
        ``"raw"``: ±inf become ±1e30, NaN stays (missing); ``"inv1p"``: 1 / (1 + max(x, 0)),
        so an effort of +inf reads 0 and no effort reads 1.

    Returns
    -------
    (n,) float64 ndarray
    """
    x = np.asarray(values, dtype=np.float64)
    if transform == "raw":
        return np.clip(x, -_BIG, _BIG)
    if transform == "inv1p":
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.isnan(x), np.nan, 1.0 / (1.0 + np.maximum(x, 0.0)))
    raise TaskError(f"unknown feature transform {transform!r}; known: {', '.join(_TRANSFORMS)}")


@dataclass(frozen=True)
class TaskModel:
    """A fitted task probability model (see the module docstring).

    Attributes
    ----------
    task : str
        ``beat``, ``cut`` or ``pick``.
    robust : bool
        Reads the ``robust_*`` columns too.
    columns : tuple of str
        The metric columns read, in the model's feature order.
    transforms : tuple of str
        Per column, how it is read (:func:`transform_column`).
    kind : str
        ``"trees"`` or ``"linear"``.
    arrays : mapping of str to ndarray
        trees: ``feature``, ``threshold``, ``left``, ``right``, ``nan_left``, ``value`` per
        node (a leaf has feature -1) and ``roots``; linear: ``weights``, ``mean``, ``scale``.
    bias : float
        Added to the raw score.
    knots_x, knots_y : (k,) float64 ndarray
        The calibration map from raw score to probability (increasing; flat outside).
    card : mapping
        What the model was fitted on and how it did on held-out objects.
    """

    task: str
    robust: bool
    columns: tuple[str, ...]
    transforms: tuple[str, ...]
    kind: str
    arrays: Mapping[str, np.ndarray]
    bias: float
    knots_x: np.ndarray
    knots_y: np.ndarray
    card: Mapping[str, Any] = field(default_factory=dict)

    def features(self, metrics: Mapping[str, np.ndarray]) -> np.ndarray:
        """The model's columns of ``metrics``, transformed.

        Parameters
        ----------
        metrics : mapping of str to (n,) array
            Metric columns (a MetricColumns derives ΣE_h and hold_dirs).

        Returns
        -------
        (n, f) float64 ndarray
        """
        missing = [c for c in self.columns if c not in metrics]
        if missing:
            raise TaskError(
                f"p_{self.task} needs the metric columns {', '.join(missing)}; evaluate the "
                "rows again with this version (or with --robust for the robust columns)"
            )
        return np.stack(
            [
                transform_column(metrics[c], t)
                for c, t in zip(self.columns, self.transforms, strict=True)
            ],
            axis=1,
        )

    def raw_score(self, x: np.ndarray) -> np.ndarray:
        """The uncalibrated score of feature rows.

        Parameters
        ----------
        x : (n, f) float64 ndarray
            Rows of :meth:`features`.

        Returns
        -------
        (n,) float64 ndarray
        """
        a = self.arrays
        if self.kind == "linear":
            # a missing value reads 0, as in the fit (a linear score has no missing branch)
            z = (np.nan_to_num(x, nan=0.0) - a["mean"]) / a["scale"]
            return z @ a["weights"] + self.bias
        return _forest(
            np.ascontiguousarray(x, dtype=np.float64),
            a["feature"],
            a["threshold"],
            a["left"],
            a["right"],
            a["nan_left"],
            a["value"],
            a["roots"],
            float(self.bias),
        )

    def predict(self, metrics: Mapping[str, np.ndarray]) -> np.ndarray:
        """P(the task trial succeeds) of each row.

        Parameters
        ----------
        metrics : mapping of str to (n,) array
            The rows' metric columns.

        Returns
        -------
        (n,) float64 ndarray in [0, 1]
        """
        return np.interp(self.raw_score(self.features(metrics)), self.knots_x, self.knots_y)

    def to_dict(self) -> dict[str, Any]:
        """The model as JSON-ready data.

        Returns
        -------
        dict
            The package-data file's content.
        """
        return {
            "format": MODEL_FORMAT,
            "version": 1,
            "task": self.task,
            "robust": self.robust,
            "columns": list(self.columns),
            "transforms": list(self.transforms),
            "kind": self.kind,
            "arrays": {k: np.asarray(v).tolist() for k, v in self.arrays.items()},
            "bias": float(self.bias),
            "knots_x": np.asarray(self.knots_x).tolist(),
            "knots_y": np.asarray(self.knots_y).tolist(),
            "card": dict(self.card),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TaskModel:
        """Read a model written by :meth:`to_dict`.

        Parameters
        ----------
        data : mapping
            The file's content.

        Returns
        -------
        TaskModel

        Raises
        ------
        TaskError
            Not a task probability model.
        """
        if data.get("format") != MODEL_FORMAT:
            raise TaskError(f"not a task probability model (format {data.get('format')!r})")
        ints = {"feature", "left", "right", "roots"}
        arrays = {
            k: np.asarray(v, dtype=np.int64 if k in ints else bool if k == "nan_left" else float)
            for k, v in data["arrays"].items()
        }
        return cls(
            task=str(data["task"]),
            robust=bool(data["robust"]),
            columns=tuple(data["columns"]),
            transforms=tuple(data["transforms"]),
            kind=str(data["kind"]),
            arrays=arrays,
            bias=float(data["bias"]),
            knots_x=np.asarray(data["knots_x"], dtype=np.float64),
            knots_y=np.asarray(data["knots_y"], dtype=np.float64),
            card=data.get("card", {}),
        )


def _model_file(task: str, robust: bool) -> str:
    return f"{task}{'-robust' if robust else ''}.json"


PROBABILITY_CODE_VERSION = "1"


def recorded_digests(value: Mapping[str, str] | None) -> dict[str, str]:
    """A manifest's ``probability_models`` as :func:`model_digests` would write it now.

    Parameters
    ----------
    value : mapping or None
        The manifest's record (None: the dataset recorded none).

    Returns
    -------
    dict of str to str
        Empty when none was recorded; a record written before the code's version was
        recorded is version ``"1"``.
    """
    out = dict(value or {})
    if out:
        out.setdefault("code", "1")
    return out


@cache
def model_digests() -> dict[str, str]:
    """The content digest of every shipped task model (a dataset records them: its stored
    p_T columns are the current models' only while these agree).

    Returns
    -------
    dict of str to str
        ``beat``, ``beat-robust``, ... → the first 16 hex digits of the SHA-256 of the
        model file, and ``code`` → :data:`PROBABILITY_CODE_VERSION`.
    """
    import hashlib

    # the code that turns columns into p_T (features, transforms, the tree walk, the rule
    # for a missing use point): bump it when that code changes what it computes
    out = {"code": PROBABILITY_CODE_VERSION}
    for task in PROBABILITY_TASKS:
        for robust in (False, True):
            path = resources.files("affordgrasp.tasks").joinpath(
                "probabilities", _model_file(task, robust)
            )
            if path.is_file():
                name = _model_file(task, robust).removesuffix(".json")
                out[name] = hashlib.sha256(path.read_bytes()).hexdigest()[:16]
    return out


@cache
def task_model(task: str, robust: bool = False) -> TaskModel:
    """The shipped model of ``task`` (``beat``, ``cut`` or ``pick``), plain or robust.

    Parameters
    ----------
    task : str
        ``beat``, ``cut`` or ``pick``.
    robust : bool
        The model that reads the robust columns too.

    Returns
    -------
    TaskModel

    Raises
    ------
    TaskError
        No model ships for that task and variant.
    """
    if task not in PROBABILITY_TASKS:
        raise TaskError(
            f"no task probability for {task!r}; models ship for {', '.join(PROBABILITY_TASKS)}"
        )
    path = resources.files("affordgrasp.tasks").joinpath("probabilities", _model_file(task, robust))
    if not path.is_file():
        raise TaskError(f"the {'robust ' if robust else ''}model of p_{task} is not installed")
    return TaskModel.from_dict(json.loads(path.read_text(encoding="utf-8")))


def task_probability(task: str, metrics: Mapping[str, np.ndarray]) -> np.ndarray:
    """p_T of every row: the robust model when ``metrics`` has its columns, else the plain one.

    Parameters
    ----------
    task : str
        ``beat``, ``cut`` or ``pick``.
    metrics : mapping of str to (n,) array
        A :class:`~affordgrasp.tasks.metric_columns.MetricColumns` or any mapping of columns.

    Returns
    -------
    (n,) float64 ndarray in [0, 1]
        0 for beat and cut where the row has no use point (nothing to strike or cut with).
    """
    plain = task_model(task, False)
    try:
        robust = task_model(task, True)
    except TaskError:
        robust = None
    use = robust if robust is not None and all(c in metrics for c in robust.columns) else plain
    p = use.predict(metrics)
    if task in _USE_TASKS:
        p = np.where(np.isnan(np.asarray(metrics["use_depth"], dtype=np.float64)), 0.0, p)
    return p


def probability_columns(metrics: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``p_beat``, ``p_cut``, ``p_pick`` of every row (:func:`task_probability`).

    Parameters
    ----------
    metrics : mapping of str to (n,) array
        The rows' metric columns (and robust columns when they have them).

    Returns
    -------
    dict of str to (n,) float64 ndarray
        In [0, 1]; ``p_beat`` and ``p_cut`` are 0 where the row has no use point (its use
        ray missed the object: nothing to strike or cut with).
    """
    return {
        name: task_probability(task, metrics)
        for task, name in zip(PROBABILITY_TASKS, PROBABILITY_COLUMNS, strict=True)
    }
