"""The options that say what grasps are scored by: tasks, threshold modes and overrides,
optional metrics, robust copies.
"""

from __future__ import annotations

import math

from ..errors import InputError

MODE_HELP = (
    "threshold mode: default, no-robustness, extra-robustness, paper (the paper's literal "
    "τ_ε = 0.3) or paper-extra-robustness (default: default)"
)


# Metrics computed only on request, beyond the paper's Φ: ``--metrics +NAME``.
OPTIONAL_METRICS = ("volume",)


def add_metrics_argument(p) -> None:
    """``--metrics +volume``: the optional metrics (the GWS volume) to compute as well.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "--metrics",
        default=None,
        metavar="+NAME",
        help="also compute an optional metric: +volume (the GWS volume, column gws_volume; "
        "not in the paper's metric vector, it costs the full 6-D hull of every "
        "force-closure grasp; null when not asked for)",
    )


def optional_metrics(args) -> set[str]:
    """The optional metrics a parsed command line asks for (``--metrics +volume``).

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    set of str
        Names from :data:`OPTIONAL_METRICS`; empty when the option is absent.

    Raises
    ------
    InputError
        For a word that is not ``+NAME`` of a known optional metric, or a value that names
        none.
    """
    wanted = set()
    given = getattr(args, "metrics", None)
    for word in [] if given is None else names_of("--metrics", given.replace(" ", ","), "+volume"):
        name = word[1:] if word.startswith("+") else None
        if name not in OPTIONAL_METRICS:
            raise InputError(
                f"--metrics {word!r} is not one of "
                + ", ".join(f"+{m}" for m in OPTIONAL_METRICS)
                + " (the paper's metric vector is always computed; e.g. --metrics +volume)"
            )
        wanted.add(name)
    return wanted


def parse_thresholds(items: list[str]) -> dict[str, float]:
    """``--threshold`` values as a dict.

    Parameters
    ----------
    items : list of str
        ``NAME=VALUE`` items, e.g. ``["tau_eps=0.1"]``.

    Returns
    -------
    dict of str to float

    Raises
    ------
    InputError
        Naming the first item that is not ``NAME=VALUE`` with a number.
    """
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or math.isnan(number):
            raise InputError(
                f"--threshold {item!r} must be NAME=VALUE with a number, e.g. tau_eps=0.1"
            )
        out[name.strip()] = number
    return out


def add_task_arguments(
    p,
    *,
    several: bool = True,
    required: bool = True,
    thresholds: bool = True,
    help: str | None = None,
) -> None:
    """The task options of every command: ``--task``, ``--mode`` and ``--threshold``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    several : bool
        ``--task`` is repeatable and takes comma lists (``--task beat,cut``); else one task
        name.
    required : bool
        ``--task`` must be given.
    thresholds : bool
        Add ``--threshold NAME=VALUE``.
    help : str, optional
        Help text of ``--task``.
    """
    if several:
        p.add_argument(
            "--task",
            action="append",
            required=required,
            default=None,
            metavar="TASK[,TASK...]",
            help=help or "task(s) to rank by, e.g. cut or beat,cut,pick (see 'affordgrasp tasks')",
        )
    else:
        p.add_argument(
            "--task", required=required, help=help or "task name (see 'affordgrasp tasks')"
        )
    p.add_argument("--mode", default="default", help=MODE_HELP)
    if thresholds:
        p.add_argument(
            "--threshold",
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help="override a threshold of the task(s) that have it, e.g. tau_eps=0.1 (repeatable)",
        )


def names_of(option: str, text: str, example: str) -> list[str]:
    """The names of a comma-separated option value, refused when it names none.

    Parameters
    ----------
    option : str
        The option (``--task``), for the message.
    text : str
        Its value (``"beat,cut"``).
    example : str
        A value to suggest (``"cut"``).

    Returns
    -------
    list of str
        The names, stripped, in order.

    Raises
    ------
    InputError
        For a value with no name in it (``''``, ``','``): an empty option would otherwise
        run as if it had not been given.
    """
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise InputError(f"{option} {text!r} names nothing; give a name, e.g. {option} {example}")
    return names


def task_names(values: list[str] | str | None) -> list[str]:
    """Task names from ``--task`` values (repeated and/or comma-separated).

    Parameters
    ----------
    values : list of str, str or None
        The option's values.

    Returns
    -------
    list of str
        In order, the first of duplicates kept.

    Raises
    ------
    InputError
        For a value that names no task (``--task ''``).
    """
    if isinstance(values, str):
        values = [values]
    names: list[str] = []
    for value in values or []:
        names.extend(names_of("--task", value, "cut (see 'affordgrasp tasks')"))
    return list(dict.fromkeys(names))


def parse_tasks(values: list[str] | None, mode: str, threshold_items: list[str]):
    """Task objects, and per-task threshold overrides, from the command line.

    Parameters
    ----------
    values : list of str or None
        ``--task`` values.
    mode : str
        ``--mode`` (checked against every task now).
    threshold_items : list of str
        ``--threshold`` items.

    Returns
    -------
    tasks : list of Task
    per_task : dict of str to dict of str to float
        Task name -> the overrides of its thresholds.

    Raises
    ------
    InputError
        Without a task name, or for a threshold no task has; a TaskError for an unknown
        task or mode.
    """
    from ..tasks import get_task

    names = task_names(values)
    if not names:
        raise InputError(
            "--task needs at least one task name, e.g. --task cut (see 'affordgrasp tasks')"
        )
    tasks = [get_task(n) for n in names]
    overrides = parse_thresholds(threshold_items)
    per_task: dict[str, dict[str, float]] = {}
    for name, value in overrides.items():
        having = [t for t in tasks if name in t.thresholds_for(mode)]
        if not having:
            raise InputError(
                f"--threshold {name}: none of the tasks {', '.join(t.name for t in tasks)} has a "
                "threshold of that name (see 'affordgrasp tasks')"
            )
        for t in having:
            per_task.setdefault(t.name, {})[name] = value
    for t in tasks:
        t.thresholds_for(mode, **per_task.get(t.name, {}))  # checks the mode now
    return tasks, per_task


ROBUST_HELP = (
    "K perturbed re-simulations per grasp (hand pose 5 mm / 3°, friction ±0.1, centre of "
    "mass 2.5 mm) and the robust_* columns; tasks rank by their robust score (default 0: "
    "plain, the paper's behaviour)"
)


def add_robust_argument(p, help: str = ROBUST_HELP) -> None:
    """The ``--robust K`` option.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    help : str
        Its help text.
    """
    p.add_argument("--robust", type=int, default=0, metavar="K", help=help)


def robust_option(args):
    """``--robust K`` as settings (None when K = 0), refused when negative.

    Parameters
    ----------
    args : argparse.Namespace
        With ``robust`` (absent: 0) and optionally ``mode``.

    Returns
    -------
    RobustSettings or None
    """
    from ..robust import RobustSettings

    k = getattr(args, "robust", 0) or 0
    if k < 0:
        raise InputError(f"--robust must be an integer >= 0 (copies per grasp), got {k}")
    mode = getattr(args, "mode", None) or "default"
    return RobustSettings(copies=k, mode=mode) if k > 0 else None


def probability_note(task, best: float | None, where: str = "") -> str | None:
    """What to say when a task probability's best grasp is not likely to succeed.

    Parameters
    ----------
    task : Task
        The task ranked by.
    best : float or None
        Its best value (p_T up to the tie-break), None when nothing was scored.
    where : str
        The object or dataset, for the message.

    Returns
    -------
    str or None
        None for a formula task or a best grasp with p_T ≥ 0.5.
    """
    from ..tasks.task import PROBABLE

    if not task.probability or (best is not None and best >= PROBABLE):
        return None
    at = f"{where}: " if where else ""
    best_text = "nothing was scored" if best is None else f"the best is p = {best:.3f}"
    return (
        f"{at}no grasp reaches p_{task.name} ≥ {PROBABLE} ({best_text}): the grasps shown are "
        "the most likely ones, not likely to succeed; a larger search (--samples, --budget) "
        "may find better ones, or the object may not afford the task"
    )
