"""What a model learns (conventions: Vision): the target of a classifier or regressor, by name.

* ``viable``: classification, the learning ground truth of ``affordgrasp.tasks.is_viable``
  (ε, ΣE_h and E_i thresholds; paper §IV-D).
* ``hold_effort_sum``: regression of ΣE_h on viable grasps, normalised linearly from
  [0, 250] N (the viability bound) to [0, 1], as the paper does.
* any metric column (``epsilon``, ``impact_effort``, ...) or ``task:NAME`` (the task's
  affordance F_T in the default mode): regression on the rows where it is finite,
  normalised linearly from the training rows' [min, 99th percentile] to [0, 1].

* ``COLUMN>=LEVEL``, e.g. ``robust_viable>=0.5``: classification of the rows where a column
  reaches a level (a robust label: the share of perturbed copies that stay viable,
  docs/robust.md); every row is learned and evaluated.

``log`` (an option, not the paper's): the target is log1p(value − low) before the linear
normalisation, which tames the heavy tail of efforts.

A regressor's output is not bounded: predictions of an effort (``LOWER_IS_BETTER``), which
cannot be negative, are clamped at 0 where they are made (:meth:`Target.denormalise`; the
shipped ΣE_h regressor reaches -1.8 N unclamped).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..columns import HOLD_EFFORT_COLUMNS, HOLD_EFFORT_SUM
from ..errors import InputError, bad_parameter

# Columns where a smaller value is the better grasp (efforts); the rest are better larger.
LOWER_IS_BETTER = {HOLD_EFFORT_SUM, *HOLD_EFFORT_COLUMNS, "impact_effort"}
HOLD_EFFORT_MAX = 250.0  # N, the viability bound on ΣE_h (paper §IV-D)


@dataclass(frozen=True)
class Target:
    """A learning target: what is learned, on which rows, and its scaling.

    Attributes
    ----------
    name : str
        A metric column, task or derived target.
    kind : str
        ``"classification"`` or ``"regression"``.
    rows : str
        ``"all"``, ``"viable"`` or ``"finite"``: the rows learned and evaluated on.
    low, high : float
        Range mapped to [0, 1] for regression (after the log when ``log``).
    log : bool
        Learn log(value).
    lower_is_better : bool
        Rank low values first (efforts).
    """

    name: str
    kind: str  # "classification" or "regression"
    rows: str  # "all", "viable" or "finite"
    low: float = 0.0
    high: float = 1.0
    log: bool = False
    lower_is_better: bool = False

    def to_dict(self) -> dict:
        """The target as JSON-ready data (stored in a model's config).

        Returns
        -------
        dict
            Every attribute.
        """
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> Target:
        """The target a :meth:`to_dict` document describes.

        Parameters
        ----------
        d : dict

        Returns
        -------
        Target
        """
        return cls(**d)

    def normalise(self, values: np.ndarray) -> np.ndarray:
        """Target units → the model's [0, 1] scale (regression) or {0, 1} (classification).

        Parameters
        ----------
        values : (n,) array_like of float
            In the target's units.

        Returns
        -------
        (n,) float32 ndarray
            (v − low) / (high − low), or log1p(v − low) / log1p(high − low) when ``log``
            (values below ``low`` clipped there); classes as 0/1.
        """
        v = np.asarray(values, dtype=np.float64)
        if self.kind == "classification":
            return v.astype(np.float32)
        if self.log:
            v = np.log1p(np.maximum(v - self.low, 0.0))
            return (v / np.log1p(self.high - self.low)).astype(np.float32)
        return ((v - self.low) / (self.high - self.low)).astype(np.float32)

    def denormalise(self, scores: np.ndarray) -> np.ndarray:
        """The model's output → target units (a probability for classification).

        Parameters
        ----------
        scores : (n,) array_like of float
            On the [0, 1] scale (probabilities for a classifier).

        Returns
        -------
        (n,) float64 ndarray
            The inverse of :meth:`normalise`, an effort clamped at 0; probabilities
            unchanged.
        """
        s = np.asarray(scores, dtype=np.float64)
        if self.kind == "classification":
            return s
        if self.log:
            values = self.low + np.expm1(s * np.log1p(self.high - self.low))
        else:
            values = self.low + s * (self.high - self.low)
        return np.maximum(values, 0.0) if self.name in LOWER_IS_BETTER else values


def threshold_target(name: str) -> tuple[str, float] | None:
    """The column and level of a thresholded classification target ``COLUMN>=LEVEL``.

    Parameters
    ----------
    name : str
        A target name.

    Returns
    -------
    (str, float) or None
        The column and the level; None when ``name`` is not of that form.

    Raises
    ------
    InputError
        When the form is used but the column is empty or the level not a finite number.
    """
    if ">=" not in name:
        return None
    column, _, level = name.partition(">=")
    column = column.strip()
    try:
        value = float(level)
    except ValueError:
        value = float("nan")
    if not column or not np.isfinite(value):
        raise InputError(
            f"target {name!r}: a thresholded target is COLUMN>=LEVEL with a finite level, "
            "e.g. robust_viable>=0.5"
        )
    return column, value


def target_column(name: str) -> str | None:
    """The stored column a target reads beyond the metric inputs, if any.

    Parameters
    ----------
    name : str
        A target name.

    Returns
    -------
    str or None
        The column (a generic column, or the column of ``COLUMN>=LEVEL``); None for the
        derived targets (``viable``, ``hold_effort_sum``, ``task:NAME``).
    """
    thresholded = threshold_target(name)
    if thresholded is not None:
        return thresholded[0]
    if name in ("viable", HOLD_EFFORT_SUM) or name.startswith("task:"):
        return None
    return name


def target_values(name: str, columns) -> np.ndarray:
    """The raw value of a target on the rows of a table of metric columns.

    Parameters
    ----------
    name : str
        The target's name.
    columns : pyarrow.Table or mapping of str to ndarray

    Returns
    -------
    (n,) float64 ndarray
    """
    from ..tasks import MetricColumns, evaluate_task, is_viable

    metrics = columns if isinstance(columns, MetricColumns) else MetricColumns(columns)
    if name == "viable":
        return is_viable(metrics).astype(np.float64)
    thresholded = threshold_target(name)
    if thresholded is not None:
        column, level = thresholded
        return (np.asarray(metrics[column], dtype=np.float64) >= level).astype(np.float64)
    if name.startswith("task:"):
        return np.asarray(evaluate_task(name[5:], metrics), dtype=np.float64)
    return np.asarray(metrics[name], dtype=np.float64)


def target_rows(target: Target, columns) -> np.ndarray:
    """Boolean mask of the rows a target is learned and evaluated on.

    Parameters
    ----------
    target : Target
    columns : pyarrow.Table or mapping of str to ndarray

    Returns
    -------
    (n,) bool ndarray
    """
    from ..tasks import MetricColumns, is_viable

    metrics = columns if isinstance(columns, MetricColumns) else MetricColumns(columns)
    if target.rows == "all":
        return np.ones(metrics.n_rows, dtype=bool)
    if target.rows == "viable":
        return is_viable(metrics)
    return np.isfinite(target_values(target.name, metrics))


def make_target(name: str, train_values: np.ndarray | None = None, *, log: bool = False):
    """The Target called ``name``; a generic column's scale comes from its training values.

    Parameters
    ----------
    name : str
        A task, a metric column, ``COLUMN>=LEVEL`` or a derived target.
    train_values : (n,) float ndarray, optional
        Training values of a generic column: their finite minimum and 99th percentile
        set ``low``/``high``.
    log : bool
        Learn log(value).

    Returns
    -------
    Target
    """
    if not name or not isinstance(name, str):
        raise bad_parameter(
            "target", "must name 'viable', 'hold_effort_sum', a column or task:NAME"
        )
    lower = name in LOWER_IS_BETTER
    if name == "viable":
        return Target("viable", "classification", "all")
    thresholded = threshold_target(name)
    if thresholded is not None:
        column, level = thresholded
        return Target(f"{column}>={level:g}", "classification", "all")
    if name == "hold_effort_sum":
        return Target(name, "regression", "viable", 0.0, HOLD_EFFORT_MAX, log, lower)
    if train_values is None:
        raise InputError(f"target {name!r} needs training values to set its scale")
    v = np.asarray(train_values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if len(v) < 2:
        raise InputError(f"target {name!r} has fewer than 2 finite training values")
    low, high = float(v.min()), float(np.percentile(v, 99))
    if high <= low:
        high = low + 1.0
    return Target(name, "regression", "finite", low, high, log, lower)
