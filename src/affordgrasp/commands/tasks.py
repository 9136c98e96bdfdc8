"""``affordgrasp tasks``: the registered affordance functions and their thresholds."""

from __future__ import annotations


def add_arguments(p) -> None:
    p.add_argument("--tasks-file", default=None, help="TOML file declaring more tasks")


def run(args, out) -> None:
    from ..tasks import get_task, list_tasks, load_task_file

    if args.tasks_file:
        load_task_file(args.tasks_file)
    rows, doc = [], {}
    for name in list_tasks():
        task = get_task(name)
        by_mode = task.thresholds_by_mode()
        for mode, values in by_mode.items():
            shown = ", ".join(f"{k}={v:g}" for k, v in values.items()) or "-"
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
