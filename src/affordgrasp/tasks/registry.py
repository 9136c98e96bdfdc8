"""The task registry: built-in tasks, tasks registered in Python and tasks from TOML files.

One :class:`TaskRegistry` object, :data:`TASKS`, serves the module-level functions. The
task files named by the ``AFFORDGRASP_TASKS`` environment variable are read once, at the
first lookup, not at every lookup; :meth:`TaskRegistry.load_environment` reads the
variable again (after changing it in a running process).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from ..errors import TaskError, did_you_mean
from ..registry import Registry
from .builtins import builtin_tasks, viable_mask
from .expressions import expression_task
from .metric_columns import MetricColumns
from .task import Task, TaskFunction, make_task
from .toml import read_task_file

log = logging.getLogger(__name__)

ENV_VAR = "AFFORDGRASP_TASKS"


class TaskRegistry(Registry[Task]):
    """Tasks by name: ``register``, ``unregister``, ``get`` and ``names()`` (sorted) of
    :class:`affordgrasp.registry.Registry`, and task files.

    Parameters
    ----------
    builtins : bool
        Start with the built-in tasks (beat, cut, cut-ug, pick, viable).
    environment : bool
        Read the task files of ``AFFORDGRASP_TASKS`` at the first lookup.
    """

    def __init__(self, *, builtins: bool = True, environment: bool = True):
        super().__init__("task", Task, TaskError)
        for task in builtin_tasks() if builtins else ():
            self._put(task)
        self._environment_pending = environment

    def _prepare(self) -> None:
        if self._environment_pending:
            self.load_environment()

    def _unknown_message(self, name: object, *, lookup: bool) -> str:
        return (
            f"unknown task {name!r}{did_you_mean(name, self._factories)}; "
            f"available{' tasks' if lookup else ''}: {', '.join(self.names())}"
        )

    def names(self) -> list[str]:
        """Names of the registered tasks, sorted.

        Returns
        -------
        list of str
        """
        return sorted(super().names())

    def load_environment(self) -> list[str]:
        """Register the tasks of every file in ``AFFORDGRASP_TASKS`` (``os.pathsep``-separated).

        Called once by the first lookup; call it again after changing the variable. A task of
        a file replaces a registered task of the same name.

        Returns
        -------
        list of str
            The names registered.
        """
        self._environment_pending = False
        names: list[str] = []
        for entry in os.environ.get(ENV_VAR, "").split(os.pathsep):
            if entry.strip():
                names += self.load_file(entry.strip(), replace=True)
        return names

    def load_file(self, path: str | os.PathLike, *, replace: bool = False) -> list[str]:
        """Register every task of a TOML task file (all or none: a bad task registers none).

        Parameters
        ----------
        path : path
            A TOML file of ``[tasks.<name>]`` tables (:func:`~.toml.read_task_file`; the README
            shows one).
        replace : bool
            Allow replacing registered tasks of the same names.

        Returns
        -------
        list of str
            The names registered, in the file's order.

        Raises
        ------
        TaskError
            For a bad file or task, or a taken name without ``replace``.
        """
        found = read_task_file(path)
        for task in found:
            self._check_free(task.name, replace)
        for task in found:
            self._put(task)
        names = [t.name for t in found]
        log.info("loaded tasks %s from %s", ", ".join(names), path)
        return names


TASKS = TaskRegistry()


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

    Parameters
    ----------
    name : str
        Registry name.
    func : callable
        ``func(metrics, thresholds) -> (n,) float64``, vectorised over rows.
    thresholds : mapping of str to float, optional
        Default threshold values.
    modes : mapping of str to mapping, optional
        Mode name to threshold overrides, added to the Table I modes (``default``,
        ``no-robustness``, ``extra-robustness``: they set ``tau_eps`` when the task has
        that threshold).
    description : str
        One line for listings.
    requires : iterable of str
        Metric columns read by ``func`` (checked before every evaluation).
    replace : bool
        Allow replacing an existing task of that name.

    Returns
    -------
    Task
        The registered task.
    """
    task = make_task(name, func, thresholds, modes, description, requires)
    return TASKS.register(task, replace=replace)


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
    """Register a declarative task from ``value`` / ``requires`` expressions.

    Parameters
    ----------
    name, value, requires, thresholds, modes, description
        As for :func:`affordgrasp.tasks.expressions.expression_task`.
    replace : bool
        Allow replacing an existing task of that name.

    Returns
    -------
    Task
        The registered task.
    """
    task = expression_task(name, value, requires, thresholds, modes, description)
    return TASKS.register(task, replace=replace)


def load_task_file(path: str | os.PathLike, *, replace: bool = False) -> list[str]:
    """Register every task of a TOML file (format: :mod:`affordgrasp.tasks`).

    Parameters
    ----------
    path : path
        The TOML file (``[tasks.<name>]`` tables).
    replace : bool
        Allow replacing registered tasks of the same names.

    Returns
    -------
    list of str
        The names registered (none when one task of the file is bad).
    """
    return TASKS.load_file(path, replace=replace)


def unregister_task(name: str) -> None:
    """Remove a task (built-in ones included) from the registry.

    Parameters
    ----------
    name : str
        A registered task name; an unknown one raises :class:`TaskError`.
    """
    TASKS.unregister(name)


def get_task(name: str) -> Task:
    """The registered task ``name`` (the one lookup verb of the task registry).

    Parameters
    ----------
    name : str
        ``beat``, ``cut``, ``pick``, ... or a name given to :func:`register_task` or
        declared in a task file (``affordgrasp tasks`` lists them).

    Returns
    -------
    Task

    Raises
    ------
    TaskError
        For an unknown name (the message lists the known ones).
    """
    return TASKS.get(name)


def list_tasks() -> list[str]:
    """Names of the registered tasks, sorted.

    Returns
    -------
    list of str
        Built-in tasks, registered ones and those of ``AFFORDGRASP_TASKS`` files.
    """
    return TASKS.names()


def evaluate_task(name: str, columns: Any, mode: str = "default", **overrides: float) -> np.ndarray:
    """Shorthand for ``get_task(name).evaluate(columns, mode, **overrides)``.

    Parameters
    ----------
    name : str
        A registered task.
    columns : mapping, pyarrow.Table or pandas.DataFrame
        The metric columns of n rows.
    mode : str
        Threshold mode (``default``, ``no-robustness``, ``extra-robustness``, ...).
    **overrides : float
        Threshold values that replace the mode's.

    Returns
    -------
    (n,) float64 ndarray
        The task value of each row; -inf where the task's requirements fail.
    """
    return get_task(name).evaluate(columns, mode, **overrides)


def is_viable(columns: Any, mode: str = "default", **overrides: float) -> np.ndarray:
    """Boolean mask of viable grasps (ε > τ_ε,viable, ΣE_h < 250, E_i < τ_Ei).

    ``mode="paper"`` gives the paper's literal ε > 0.15, ΣE_h < 250, E_i < 100.

    Parameters
    ----------
    columns : mapping, pyarrow.Table or pandas.DataFrame
        The metric columns of n rows.
    mode : str
        Threshold mode of the ``viable`` task.
    **overrides : float
        Threshold values that replace the mode's.

    Returns
    -------
    (n,) bool ndarray
    """
    task = get_task("viable")
    values = task.thresholds_for(mode, **overrides)
    metrics = columns if isinstance(columns, MetricColumns) else MetricColumns(columns)
    with np.errstate(invalid="ignore"):
        return np.asarray(viable_mask(metrics, values), dtype=bool)
