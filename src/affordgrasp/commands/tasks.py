"""``affordgrasp tasks``: the registered affordance functions and their thresholds."""

from __future__ import annotations

# The metric column each built-in threshold is compared with: its unit is the column's.
THRESHOLD_COLUMNS = {
    "tau_eps": "epsilon",
    "tau_delta": "discharge",
    "tau_angle": "use_edge_angle",
    "tau_wedge": "use_wedge_angle",
    "tau_blunt": "use_wedge_angle",
    "tau_wedge_fine": "use_wedge_angle_fine",
    "tau_span": "use_edge_span",
    "tau_edge_thickness": "use_edge_thickness",
    "tau_clear": "use_clearance",
    "tau_thick": "contact_thickness",
    "tau_width": "contact_width",
    "tau_lever": "use_lever_ratio",
    "tau_lever_max": "use_lever_ratio",
    "tau_reach": "contact_reach",
    "tau_depth": "use_depth",
    "tau_relief": "use_relief",
    "tau_swing": "use_swing_cosine",
    "tau_ug": "use_edge",
    "eps_min": "epsilon",
    "hold_max": "hold_effort_sum",
    "impact_max": "impact_effort",
}


def threshold_text(name: str, value: float) -> str:
    """``tau_angle=45°``, ``tau_ug=30000 m⁻²``, ``tau_eps=0.3``: the value in its table unit.

    Parameters
    ----------
    name : str
        The threshold's name.
    value : float
        Its value (in the unit of the metric it bounds).

    Returns
    -------
    str
    """
    from ..columns import display_unit, display_value

    column = THRESHOLD_COLUMNS.get(name)
    if column is None:
        return f"{name}={value:g}"
    unit = display_unit(column)
    shown = f"{display_value(column, value):.4g}"
    if not unit:
        return f"{name}={shown}"
    return f"{name}={shown}{unit}" if unit == "°" else f"{name}={shown} {unit}"


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp tasks`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("--tasks-file", default=None, help="TOML file declaring more tasks")


def run(args, out) -> None:
    """Run ``affordgrasp tasks``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..tasks import get_task, list_tasks, load_task_file

    if args.tasks_file:
        load_task_file(args.tasks_file)
    rows, doc = [], {}
    for name in list_tasks():
        task = get_task(name)
        by_mode = task.thresholds_by_mode()
        for mode, values in by_mode.items():
            shown = ", ".join(threshold_text(k, v) for k, v in values.items()) or "-"
            rows.append(
                [
                    name if mode == "default" else "",
                    mode,
                    shown,
                    task.description if mode == "default" else "",
                ]
            )
        doc[name] = {
            "description": task.description,
            "requires": list(task.requires),
            "thresholds": by_mode,
        }
    out.table("tasks (affordance functions)", ["task", "mode", "thresholds", "description"], rows)
    out.result({"tasks": doc})
