"""The dataset card: what a dataset is, for machines (``_card.json``) and people (``_card.md``).

Written beside the shards whenever a generation run ends (also when interrupted, then marked
incomplete). It records the hand, the friction table, the simulation tolerances, the task
thresholds in force, every object with its mass properties and mesh hash, the software
version, the command lines that built the dataset and the counts per status. Everything it
says about the rows is read from the shard footers, so it is right after a resume too.
"""

from __future__ import annotations

import json
import logging
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._version import __version__
from ..jsonable import to_jsonable
from ..runtime.writing import atomic_write
from .manifest import (
    CARD_JSON_NAME,
    CARD_MD_NAME,
    FORMAT,
    FORMAT_VERSION,
    manifest_volume,
    write_json_atomic,
)

log = logging.getLogger(__name__)


def hand_description(hand) -> dict:
    """The hand's card entry: name, DOFs (limits in rad or m), links and fingers.

    Parameters
    ----------
    hand : Hand

    Returns
    -------
    dict
    """
    return {
        "name": hand.name,
        "description": hand.description,
        "pregrasp_dof": hand.pregrasp_dof,
        "dofs": [
            {"name": d.name, "lower": d.lower, "upper": d.upper, "role": d.role} for d in hand.dofs
        ],
        "links": [
            {"name": link.name, "parent": link.parent, "material": link.material}
            for link in hand.links
        ],
        "fingers": [
            {"name": f.name, "dofs": list(f.dofs), "speeds": list(f.speeds)} for f in hand.fingers
        ],
    }


def object_description(obj) -> dict:
    """The object's card entry: identity, mesh size and mass properties (SI units).

    Parameters
    ----------
    obj : GraspObject

    Returns
    -------
    dict
    """
    m = obj.mass
    return {
        "name": obj.name,
        "category": obj.category,
        "source": obj.source,
        "mesh_hash": obj.mesh_hash,
        "vertices": int(len(obj.vertices)),
        "faces": int(len(obj.faces)),
        "materials": bool(getattr(obj, "materials", False)),
        "density_kg_m3": float(m.density),
        "volume_m3": float(m.volume),
        "mass_kg": float(m.mass),
        "center_of_mass_m": np.asarray(m.center_of_mass, dtype=float).tolist(),
        "inertia_kg_m2": np.asarray(m.inertia, dtype=float).tolist(),
        "r_max_m": float(m.r_max),
        "bounds_m": np.asarray(m.bounds, dtype=float).tolist(),
        # repairs and simplification (with its measured distance) of a mesh file
        "load_warnings": list(getattr(obj, "load_warnings", ())),
    }


def simulation_settings() -> dict:
    """The grasp simulator's settings (distances in m) and the friction cone edges.

    Returns
    -------
    dict
    """
    from ..grasp import policy
    from ..materials import DEFAULT_OBJECT_MATERIAL
    from ..metrics.cones import N_EDGES

    return {
        "hit_eps_m": policy.HIT_EPS,
        "contact_tol_m": policy.CONTACT_TOL,
        "merge_radius_m": policy.MERGE_RADIUS,
        "object_material": DEFAULT_OBJECT_MATERIAL,
        "friction_cone_edges": N_EDGES,
    }


def task_thresholds() -> dict:
    """The thresholds of every registered task in every mode, as far as the tasks say.

    Returns
    -------
    dict
        Task name → mode → threshold name → value (in the unit of the metric it bounds);
        a task that cannot say is left out.
    """
    from .. import tasks

    try:
        names = tasks.list_tasks()
    except Exception:  # noqa: BLE001 - a card must not fail because of a task plug-in
        return {}
    out = {}
    for name in names:
        try:
            out[name] = to_jsonable(tasks.get_task(name).thresholds_by_mode())
        except Exception:  # noqa: BLE001
            log.debug("no thresholds for task %r", name, exc_info=True)
    return out


def schema_description(metrics: bool, depth: bool = False, robust=None) -> list[dict]:
    """Every field of the shards' schema with its Arrow type.

    Parameters
    ----------
    metrics, depth : bool
        As for :func:`affordgrasp.schema.dataset_schema`.
    robust : RobustSettings, optional
        The robust settings of the run (their columns are listed).

    Returns
    -------
    list of dict
        ``{"name": ..., "type": ...}``.
    """
    from ..schema import dataset_schema

    schema = dataset_schema(metrics, depth, robust)
    return [{"name": f.name, "type": str(f.type)} for f in schema]


def build_card(
    *,
    manifest: dict,
    objects: Sequence,
    hand,
    shards: dict,
    plan: Sequence,
    previous: dict | None,
    run: dict,
) -> dict:
    """The dataset card of a run as a JSON-ready document.

    Parameters
    ----------
    manifest : dict
        The run's plan.
    objects : sequence of GraspObject
    hand : Hand
    shards : dict
        The shards written so far.
    plan : sequence
        The planned shards.
    previous : dict or None
        The card of an earlier run in the same directory.
    run : dict
        This run's facts (command, engine, workers, start, elapsed s, rows written,
        complete).

    Returns
    -------
    dict
    """
    from ..materials import friction_table
    from ..robust import manifest_robust

    per_object: dict[str, Counter] = {o.name: Counter() for o in objects}
    closure: Counter = Counter()
    rows = 0
    for shard, info in shards.items():
        name = objects[shard.object_index].name
        per_object[name].update(info.get("status_counts", {}))
        closure[name] += int(info.get("force_closure", 0))
        rows += shard.rows
    totals: Counter = Counter()
    for c in per_object.values():
        totals.update(c)
    planned_rows = sum(s.rows for s in plan)
    runs = list((previous or {}).get("runs", [])) + [run]
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "affordgrasp_version": __version__,
        "complete": rows == planned_rows,
        "rows": rows,
        "rows_planned": planned_rows,
        "shards": len(shards),
        "shards_planned": len(plan),
        "seed": manifest["seed"],
        "samples_per_object": manifest["samples"],
        "shard_size": manifest["shard_size"],
        "metrics": manifest["metrics"],
        "gws_volume": manifest_volume(manifest),
        "soft_contacts": manifest["soft"],
        "materials": bool(manifest.get("materials", False)),
        "command": manifest.get("command"),
        "created": manifest.get("created"),
        "runs": runs,
        "status_counts": dict(sorted(totals.items())),
        "status_counts_per_object": {k: dict(sorted(v.items())) for k, v in per_object.items()},
        "force_closure_per_object": (
            {o.name: closure[o.name] for o in objects} if manifest["metrics"] else None
        ),
        "objects": [object_description(o) for o in objects],
        "hand": hand_description(hand),
        "friction_table": friction_table(),
        "simulation": simulation_settings(),
        "task_thresholds": task_thresholds(),
        "depth": manifest.get("depth"),
        "robust": manifest.get("robust"),
        "columns": schema_description(
            manifest["metrics"], bool(manifest.get("depth")), manifest_robust(manifest)
        ),
    }


def card_markdown(card: dict) -> str:
    """The card as a short Markdown page.

    Parameters
    ----------
    card : dict
        From :func:`build_card`.

    Returns
    -------
    str
    """
    state = "complete" if card["complete"] else "INCOMPLETE (run the same command to finish it)"
    lines = [
        "# affordgrasp dataset",
        "",
        f"* state: {state}; {card['rows']:,} of {card['rows_planned']:,} rows in "
        f"{card['shards']} of {card['shards_planned']} shards",
        f"* affordgrasp {card['affordgrasp_version']}, format {card['format_version']}",
        f"* seed {card['seed']}, {card['samples_per_object']:,} samples per object, "
        f"shards of {card['shard_size']} rows, metrics: {'yes' if card['metrics'] else 'no'}, "
        f"soft contacts: {'yes' if card['soft_contacts'] else 'no'}, GWS volume: "
        + (
            "computed (--metrics +volume)"
            if card.get("gws_volume", card["metrics"])
            else "not computed (column gws_volume null)"
        ),
        "* mass properties: "
        + (
            "per-part materials of the built-in families (--materials)"
            if card.get("materials")
            else "uniform unit density (1 kg/m³), as in the paper"
        ),
        f"* created {card.get('created')} by: `{_command_text(card.get('command'))}`",
        "",
        "## Status counts",
        "",
        "| object | " + " | ".join(_statuses(card)) + " |",
        "|---|" + "---:|" * len(_statuses(card)),
    ]
    for name, counts in card["status_counts_per_object"].items():
        cells = " | ".join(f"{counts.get(s, 0):,}" for s in _statuses(card))
        lines.append(f"| {name} | {cells} |")
    if card.get("force_closure_per_object"):
        lines += [
            "",
            "Force closure (ε > 0): "
            + ", ".join(f"{k} {v:,}" for k, v in card["force_closure_per_object"].items()),
        ]
    lines += [
        "",
        "## Objects",
        "",
        "| object | category | mass (kg) | volume (m³) | r_max (m) | mesh hash |",
        "|---|---|---:|---:|---:|---|",
    ]
    for o in card["objects"]:
        lines.append(
            f"| {o['name']} | {o['category']} | {o['mass_kg']:.4g} | {o['volume_m3']:.4g} | "
            f"{o['r_max_m']:.4g} | `{o['mesh_hash'][:16]}…` |"
        )
    notes = [(o["name"], w) for o in card["objects"] for w in o.get("load_warnings", ())]
    if notes:
        lines += ["", "Loading the mesh files:", ""]
        lines += [f"* {name}: {warning}" for name, warning in notes]
    hand = card["hand"]
    lines += [
        "",
        f"## Hand: {hand['name']}",
        "",
        hand.get("description") or "",
        "",
        "| DOF | lower | upper | role |",
        "|---|---:|---:|---|",
    ]
    for d in hand["dofs"]:
        lines.append(f"| {d['name']} | {d['lower']:.4g} | {d['upper']:.4g} | {d['role']} |")
    lines += [
        "",
        "Link materials: " + ", ".join(f"{x['name']} {x['material']}" for x in hand["links"]),
    ]
    lines += ["", "## Simulation", ""]
    lines += [f"* {k}: {v}" for k, v in card["simulation"].items()]
    if card.get("robust"):
        lines += ["", "## Robust evaluation (robust_* columns)", ""]
        lines += [f"* {k}: {v}" for k, v in card["robust"].items()]
    lines += ["", "## Friction table (μ)", ""]
    lines.append(", ".join(f"{k} {v}" for k, v in card["friction_table"].items()))
    if card["task_thresholds"]:
        lines += ["", "## Task thresholds", "", "```json"]
        lines.append(json.dumps(card["task_thresholds"], indent=2))
        lines.append("```")
    lines += ["", "## Runs", ""]
    for r in card["runs"]:
        lines.append(
            f"* {r.get('started')}: `{_command_text(r.get('command'))}`, engine {r.get('engine')} "
            f"× {r.get('workers')}, {r.get('samples_written', 0):,} samples in "
            f"{r.get('elapsed_s', 0):.1f} s{'' if r.get('complete') else ' (interrupted)'}"
        )
    lines += ["", "## Columns", "", "See docs/dataset.md for meanings and units.", ""]
    lines += [f"* `{c['name']}`: {c['type']}" for c in card["columns"]]
    return "\n".join(lines) + "\n"


def _statuses(card: dict) -> list[str]:
    from ..grasp.policy import STATUSES

    known = list(STATUSES)
    seen = sorted({s for c in card["status_counts_per_object"].values() for s in c})
    return known + [s for s in seen if s not in known]


def _command_text(command) -> str:
    if not command:
        return "(Python API)"
    import shlex

    return shlex.join(command)


def read_card(directory: str | Path) -> dict | None:
    """The card of a dataset directory.

    Parameters
    ----------
    directory : path

    Returns
    -------
    dict or None
        None when there is none or it cannot be read.
    """
    path = Path(directory) / CARD_JSON_NAME
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def write_card(directory: Path, **kwargs) -> dict:
    """Build the card from the run's facts and write both files atomically.

    Parameters
    ----------
    directory : pathlib.Path
        The dataset directory.
    **kwargs
        As for :func:`build_card`.

    Returns
    -------
    dict
        The card.
    """
    card = build_card(previous=read_card(directory), **kwargs)
    write_json_atomic(directory / CARD_JSON_NAME, card)
    atomic_write(directory / CARD_MD_NAME, card_markdown(card).encode("utf-8"))
    return card
