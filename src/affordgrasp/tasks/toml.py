"""Tasks declared in TOML files (``[tasks.<name>]`` tables of expressions and thresholds)."""

from __future__ import annotations

import os
import tomllib
from pathlib import Path
from typing import Any

from ..columns import DERIVED_COLUMNS, METRIC_COLUMNS
from ..errors import TaskError
from .expressions import expression_task
from .task import Task


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or value != value:
        raise TaskError(f"{where} must be a number (inf and -inf switch a test off), got {value!r}")
    return float(value)


def read_task_file(path: str | os.PathLike) -> list[Task]:
    """Every task of a TOML file (see :mod:`affordgrasp.tasks`), checked, not registered.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (``[tasks.<name>]`` tables).

    Returns
    -------
    list of Task
        In file order; a bad task raises :class:`TaskError` naming the file and the task.
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            doc = tomllib.load(fh)
    except FileNotFoundError:
        raise TaskError(f"task file {str(path)!r} does not exist") from None
    except IsADirectoryError:
        raise TaskError(f"task file {str(path)!r} is a directory; give a .toml file") from None
    except PermissionError:
        raise TaskError(f"task file {str(path)!r} cannot be read (permission denied)") from None
    except UnicodeDecodeError as exc:
        raise TaskError(f"task file {str(path)!r} is not UTF-8 text ({exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise TaskError(f"task file {str(path)!r} is not valid TOML: {exc}") from None
    section = doc.get("tasks")
    if not isinstance(section, dict) or not section:
        raise TaskError(f"task file {str(path)!r} has no [tasks.<name>] tables")
    found: list[Task] = []
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
        task = expression_task(
            str(name),
            spec["value"],
            spec.get("requires"),
            thresholds,
            modes,
            str(spec.get("description", "")),
        )
        _check_metric_names(task.requires, where)
        found.append(task)
    return found


def _check_metric_names(names, where: str) -> None:
    """Refuse a name that is neither a metric column nor a threshold, before any simulation.

    Robust columns (``robust_<metric>``) are accepted when their metric is known.
    """
    import difflib

    known = set(METRIC_COLUMNS) | set(DERIVED_COLUMNS)
    for name in names:
        base = name[len("robust_") :] if name.startswith("robust_") else name
        if base in known:
            continue
        close = difflib.get_close_matches(name, sorted(known), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise TaskError(
            f"{where}: unknown metric {name!r} ({hint}known metrics: {', '.join(sorted(known))}; "
            "or declare it under thresholds)"
        )
