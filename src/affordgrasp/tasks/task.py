"""An affordance function F_T with its thresholds and threshold modes."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ..errors import TaskError, did_you_mean
from .metric_columns import MetricColumns
from .thresholds import standard_modes

# A probability task's grasps are called likely to succeed from this value on.
PROBABLE = 0.5

TaskFunction = Callable[[Mapping[str, np.ndarray], Mapping[str, float]], np.ndarray]


@dataclass(frozen=True)
class Task:
    """An affordance function F_T with its thresholds (make one with :func:`make_task`).

    Attributes
    ----------
    name : str
        Registry name.
    func : callable
        ``func(metrics, thresholds) -> (n,) float64``; ``metrics`` maps column names to
        float arrays (plus ``hold_effort_sum``), ``thresholds`` names to floats.
    thresholds : mapping of str to float
        Default threshold values.
    modes : mapping of str to mapping
        Mode name to the threshold overrides of that mode.
    description : str
        One line for listings.
    requires : tuple of str
        Metric columns the function reads (checked before every evaluation).
    probability : bool
        The function's value is a probability of success (plus a tie-break below 10⁻⁶):
        never −∞, so a search ranks every grasp and says when none reaches 0.5
        (:data:`PROBABLE`).
    """

    name: str
    func: TaskFunction
    thresholds: Mapping[str, float] = field(default_factory=dict)
    modes: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    description: str = ""
    requires: tuple[str, ...] = ()
    probability: bool = False

    def thresholds_for(self, mode: str = "default", **overrides: float) -> dict[str, float]:
        """Threshold values in ``mode`` with call-time ``overrides`` applied.

        Parameters
        ----------
        mode : str
            One of the task's modes.
        **overrides : float
            New values of some of its thresholds.

        Returns
        -------
        dict of str to float
            Every threshold of the task.

        Raises
        ------
        TaskError
            For an unknown mode or threshold, or a value that is not a number.
        """
        if mode not in self.modes:
            raise TaskError(
                f"task {self.name!r} has no mode {mode!r}{did_you_mean(mode, self.modes)}; "
                f"modes: {', '.join(self.modes)}"
            )
        values = dict(self.thresholds)
        values.update(self.modes[mode])
        for key, value in overrides.items():
            if key not in values:
                raise TaskError(
                    f"task {self.name!r} has no threshold {key!r}; thresholds: "
                    f"{', '.join(values) or 'none'}"
                )
            values[key] = _threshold(key, value)
        return values

    def thresholds_by_mode(self) -> dict[str, dict[str, float]]:
        """Every mode's threshold values (for dataset cards and listings).

        Returns
        -------
        dict of str to dict of str to float
            Mode -> :meth:`thresholds_for` of that mode.
        """
        return {mode: self.thresholds_for(mode) for mode in self.modes}

    def evaluate(self, columns: Any, mode: str = "default", **overrides: float) -> np.ndarray:
        """Score every row of ``columns``.

        Parameters
        ----------
        columns : mapping, pyarrow.Table or pandas.DataFrame
            Metric columns by name, n rows.
        mode : str
            Threshold mode.
        **overrides : float
            Threshold values that replace the mode's.

        Returns
        -------
        (n,) float64 ndarray
            F_T per row; -inf where the task's requirements fail.
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


def _threshold(name: str, value: Any) -> float:
    """A threshold as a float: a number or ±inf (a test switched off), never NaN."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if math.isnan(number):  # every comparison with NaN is false: a test that passes nothing
        raise TaskError(
            f"threshold {name!r} must be a number (inf and -inf switch a test off), got {value!r}"
        )
    return number


def make_task(
    name: str,
    func: TaskFunction,
    thresholds: Mapping[str, float] | None = None,
    modes: Mapping[str, Mapping[str, float]] | None = None,
    description: str = "",
    requires: Iterable[str] = (),
    probability: bool = False,
) -> Task:
    """A checked :class:`Task`; the Table I modes are added to the task's own ``modes``.

    The Table I modes (``default``, ``no-robustness``, ``extra-robustness``) set ``tau_eps``
    when the task has that threshold; a task's own modes add to or refine them.

    Parameters
    ----------
    name : str
        Registry name.
    func : callable
        ``func(metrics, thresholds) -> (n,) float64``, vectorised over rows.
    thresholds : mapping of str to float, optional
        Default threshold values.
    modes : mapping of str to mapping, optional
        Mode name to threshold overrides.
    description : str
        One line for listings.
    requires : iterable of str
        Metric columns ``func`` reads.
    probability : bool
        ``func`` returns probabilities (:attr:`Task.probability`).

    Returns
    -------
    Task
        Checked (names, finite thresholds, callable), not registered.
    """
    if not isinstance(name, str) or not name.strip():
        raise TaskError(f"a task name must be a non-empty string, got {name!r}")
    if not callable(func):
        raise TaskError(f"task {name!r}: func must be callable, got {type(func).__name__}")
    thresholds = {str(k): _threshold(k, v) for k, v in (thresholds or {}).items()}
    merged = standard_modes(thresholds)
    for mode, over in (modes or {}).items():
        merged[str(mode)] = {
            **merged.get(str(mode), {}),
            **{str(k): _threshold(k, v) for k, v in over.items()},
        }
    for mode, over in merged.items():
        unknown = set(over) - set(thresholds)
        if unknown:
            raise TaskError(
                f"task {name!r}, mode {mode!r}: unknown thresholds {sorted(unknown)}; "
                f"declare them in thresholds ({', '.join(thresholds) or 'none'})"
            )
    return Task(
        name=name,
        func=func,
        thresholds=MappingProxyType(thresholds),
        modes=MappingProxyType({k: MappingProxyType(v) for k, v in merged.items()}),
        description=description,
        requires=tuple(requires),
        probability=bool(probability),
    )
