"""``affordgrasp show``: the best grasps of tasks as a PNG grid and an interactive HTML page.

SOURCE is a dataset directory (every ``*.parquet`` under it) or an object (``knife``,
``knife:7``, a mesh path), in which case ``--samples`` grasps are drawn with ``--seed`` and
evaluated first. Several sources and several tasks (``--task beat,cut,pick``) may be given.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from .batches import check_counts
from .limits import OWN_CHECK, ROBUST, USES
from .object_options import (
    HAND_HELP,
    add_scale_arguments,
    check_mesh_files,
    load_objects,
    scale_options,
)
from .output_files import check_output_dir
from .task_options import (
    add_robust_argument,
    add_task_arguments,
    parse_tasks,
    probability_note,
    robust_option,
)

DEFAULT_SAMPLES = 1000
EVALUATION_BATCH = 250


# Of the numeric options (see limits.check_limits): those of add_source_arguments, then show's.
SOURCE = {**dict.fromkeys(("samples", "seed", "size_m"), OWN_CHECK), "uses": USES, "robust": ROBUST}
LIMITS = {**SOURCE, "top": (None, 100, "each grasp is rendered")}
LIMITS |= dict.fromkeys(("cell", "grasp_size"), OWN_CHECK)  # 64 to 2048 pixels


def add_source_arguments(p) -> None:
    """The source options ``show`` and ``plots`` share.

    ``SOURCE...``, ``--samples``, ``--seed``, ``--uses``, ``--hand``, ``--mesh``, the scale
    options and ``--out``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "source",
        nargs="+",
        metavar="SOURCE",
        help="a dataset directory, or an object: family (knife), family:seed (knife:7) or a "
        "mesh path",
    )
    p.add_argument(
        "--samples",
        type=int,
        default=DEFAULT_SAMPLES,
        help=f"grasps to evaluate for an object SOURCE (default {DEFAULT_SAMPLES})",
    )
    p.add_argument(
        "--seed", type=int, default=0, help="sampling seed for an object SOURCE (default 0)"
    )
    p.add_argument(
        "--uses",
        type=int,
        default=2000,
        metavar="M",
        help="for an object SOURCE, also score every grasp with each of M use points drawn by area "
        "(affordgrasp.search.pairs; default 2000, 0: only the samples' own use points)",
    )
    p.add_argument(
        "--hand",
        default="barrett",
        help="hand for an object SOURCE: " + HAND_HELP,
    )
    p.add_argument(
        "--mesh",
        action="append",
        default=[],
        metavar="PATH",
        help="mesh file of a dataset object that is not a built-in family (repeatable)",
    )
    add_scale_arguments(p)
    add_robust_argument(
        p,
        help="rank by the robust score: an object SOURCE is evaluated with K perturbed "
        "copies per grasp; a dataset SOURCE must have been generated with --robust K "
        "(default 0: plain F_T)",
    )
    p.add_argument("-o", "--out", required=True, metavar="OUTDIR", help="directory to write into")


def add_arguments(p) -> None:
    """The options of ``affordgrasp show``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, extended in place.
    """
    add_source_arguments(p)
    add_task_arguments(p)
    p.add_argument("--top", type=int, default=4, help="grasps per object and task (default 4)")
    p.add_argument(
        "--cell", type=int, default=320, help="size of a grid cell, pixels (default 320)"
    )
    p.add_argument("--cones", action="store_true", help="draw the friction cones of the contacts")
    p.add_argument(
        "--each",
        action="store_true",
        help="also write one PNG per grasp under OUTDIR/grasps/",
    )
    p.add_argument(
        "--grasp-size", type=int, default=512, help="size of the --each PNGs, pixels (default 512)"
    )
    p.add_argument("--no-html", action="store_true", help="skip the interactive HTML page")
    p.add_argument(
        "--name", default="best_grasps", help="base name of the grid and page (default best_grasps)"
    )
    p.add_argument("--title", default="", help="title of the grid and page")


# --------------------------------------------------------------------------- shared helpers


def open_sources(args, out, tasks=(), thresholds=None) -> list:
    """One GraspSource per SOURCE.

    Datasets are read as they are; objects are evaluated now (with, when ``--uses`` is set,
    the best pairs of their grasps and ``--uses`` use points per task), and the source keeps
    the hand they were evaluated with.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    out : Output
        The command's output (progress bars).
    tasks : sequence of Task
        The tasks the pairs are searched for.
    thresholds : dict, optional
        Task name -> threshold overrides.

    Returns
    -------
    list of GraspSource
        :class:`~affordgrasp.viz.sources.DatasetSource` or
        :class:`~affordgrasp.viz.sources.TableSource`, in the order of the sources.

    Raises
    ------
    InputError
        When ``--units`` / ``--size-m`` are given without a mesh file to apply them to.
    """
    from ..hands import get_hand
    from ..objects import load_object
    from ..objects.resolve import is_family_spec
    from ..pipeline import evaluate_samples
    from ..viz.sources import DatasetSource, TableSource, is_dataset_path

    sources = []
    specs = [s for s in args.source if not is_dataset_path(s)]
    scaled = [s for s in [*specs, *args.mesh] if not is_family_spec(s)]
    scale = scale_options(args)
    if not scaled and any(v is not None for v in scale.values()):
        if specs:
            load_objects(specs, args)  # refuses the options for families, saying why
        raise InputError(
            "--units / --size-m rescale mesh files, and no SOURCE or --mesh is one; drop "
            "the option, or pass the dataset's mesh with --mesh PATH"
        )
    if getattr(args, "materials", False) and specs:
        load_objects(specs, args)  # refuses --materials when every spec is a mesh file
    objects = {
        s: load_object(s, materials=bool(getattr(args, "materials", False)))
        if is_family_spec(s)
        else load_object(s, **scale)
        for s in specs
    }
    robust = robust_option(args)
    for spec in args.source:
        if is_dataset_path(spec):
            if robust is not None:
                from .best import check_dataset_robust

                check_dataset_robust(Path(spec).expanduser(), robust.copies)
            sources.append(DatasetSource(Path(spec).expanduser()))
            continue
        obj = objects[spec]
        with out.progress(f"evaluating {obj.name}", args.samples) as advance:
            table = evaluate_samples(
                obj,
                args.samples,
                seed=args.seed,
                hand=args.hand,
                batch_size=EVALUATION_BATCH,
                progress=advance,
                robust=robust,
            ).table
        if getattr(args, "uses", 0) and robust is None:  # robust scores keep their own use
            table = with_best_pairs(obj, table, tasks, thresholds or {}, args, out)
        sources.append(
            TableSource(table, name=obj.name, objects={obj.name: obj}, hand=get_hand(args.hand))
        )
    return sources


def with_best_pairs(obj, table, tasks, thresholds, args, out=None):
    """A table plus, per task, its best (grasp, use point) pairs.

    The pairs are searched over the table's grasps and ``args.uses`` use points drawn by area
    (:func:`affordgrasp.search.pairs.best_pairs`) and appended as ordinary rows, numbered
    after the samples. Tasks that do not read the use point add nothing. Where that finds no
    pair (on a scan-like blade 1000 grasps hold a handful of ε-robust ones), a search aimed
    at the task's tests (:func:`affordgrasp.search.pairs.optimize_pairs` with
    ``threshold_guide``, the guidance of ``optimize --uses``) simulates 4 × ``args.samples``
    more grasps in two restarts, and ``out`` says so.

    Parameters
    ----------
    obj : GraspObject
    table : pyarrow.Table
        The object's evaluated samples.
    tasks : sequence of Task
    thresholds : dict
        Task name -> threshold overrides.
    args : argparse.Namespace
        ``uses``, ``samples``, ``mode``, ``seed``, ``top`` and ``hand``.
    out : Output, optional
        Where the fallbacks are reported.

    Returns
    -------
    pyarrow.Table
        With the table's schema.

    Raises
    ------
    InputError
        When ``--uses`` is negative.
    """
    from dataclasses import replace

    import pyarrow as pa

    from ..search.pairs import USE_COLUMNS, PairSearchSettings, best_pairs, optimize_pairs

    if args.uses < 0:
        raise InputError(f"--uses must be a non-negative integer, got {args.uses}")
    say = out.text if out is not None else (lambda text: None)
    extra = []
    for task in tasks:
        if not USE_COLUMNS & set(task.requires):
            continue  # the task ignores the use point: the samples already say it all
        settings = PairSearchSettings(
            task.name,
            mode=args.mode,
            thresholds=thresholds.get(task.name) or {},
            uses=args.uses,
            seed=args.seed,
            top=args.top,
            hand=args.hand,
        )
        found = best_pairs(obj, settings, grasp_table=table).table
        if not found.num_rows and args.samples > 0:
            # two runs of 2 x --samples each: on the scan-like blades, hammers and axes, runs
            # of 1000 met no feasible grasp where longer ones did; scoring the same grasps
            # with use points that pass the use-point tests found none (docs/validation.md §7)
            budget = 4 * max(int(args.samples), 40)
            aimed = replace(settings, budget=budget, restarts=2, threshold_guide=True)
            found = optimize_pairs(obj, aimed).table
            say(
                f"{task.name}: no pair of the {table.num_rows:,} grasps with {args.uses:,} use "
                f"points by area passes; a search aimed at the task's tests, {budget:,} more "
                f"simulations in 2 restarts: {found.num_rows} grasps found"
            )
        if found.num_rows:
            extra.append(found.drop_columns(["value"]))
    if not extra:
        return table
    rows = pa.concat_tables(extra).select(table.schema.names).cast(table.schema)
    start = table.num_rows
    number = pa.array(range(start, start + rows.num_rows), pa.int64())
    rows = rows.set_column(rows.schema.get_field_index("sample"), "sample", number)
    return pa.concat_tables([table, rows])


def resolve_dataset_object(
    name: str,
    object_hash: str | None,
    source,
    meshes: list[str],
    out,
    scale: dict | None = None,
    materials: bool = False,
):
    """The GraspObject a dataset's rows were simulated on, found by name and checked by hash.

    The rule of :meth:`affordgrasp.dataset.handle.Dataset.object` (for loose Parquet files,
    :func:`~affordgrasp.dataset.handle.find_object` on what the rows say): the ``--mesh``
    files of that name, the recorded mesh path, files of that name under the directory,
    then the name itself (a family or a path).

    Parameters
    ----------
    name : str
        The object's name in the rows.
    object_hash : str or None
        The rows' ``object_hash``; a candidate with another mesh is skipped (a family that
        now builds another mesh is drawn anyway, with a warning).
    source : GraspSource
        Where the rows come from (its ``directory``, when it has one).
    meshes : list of str
        ``--mesh`` paths.
    out : Output
        For the warning.
    scale : dict, optional
        ``size_m`` / ``units`` for mesh files, as when the dataset was made.
    materials : bool
        Per-part materials for a family of loose rows (``--materials``); a dataset says so
        itself.

    Returns
    -------
    GraspObject

    Raises
    ------
    DatasetError
        When no candidate loads with the right mesh; the message names ``--mesh``.
    """
    from ..dataset.handle import find_object

    dataset = getattr(source, "dataset", None)
    scale = scale or {}
    if dataset is not None and name in dataset.entries:
        obj = dataset.object(name, meshes=meshes, changed_family="accept", **scale)
        object_hash = object_hash or dataset.mesh_hash(name)
    else:  # loose Parquet files: the rows alone say which object they are
        obj = find_object(
            name,
            source=None,
            mesh_hash=object_hash,
            meshes=meshes,
            directory=getattr(source, "directory", None),
            materials=materials,
            changed_family="accept",
            **scale,
        )
    if object_hash and obj.mesh_hash != object_hash:  # only a family is accepted so
        out.text(
            f"[yellow]warning:[/] object {name!r}: the family now builds a different mesh "
            "than the dataset's (another affordgrasp version?); drawing it anyway"
        )
    return obj


def objects_of(rankings, sources_by_object, args, out) -> dict:
    """The object of every ranking, loaded once each.

    Parameters
    ----------
    rankings : list of TaskRanking
    sources_by_object : dict of str to GraspSource
        Where each object's rows come from.
    args : argparse.Namespace
        ``mesh`` and the scale options.
    out : Output

    Returns
    -------
    dict of str to GraspObject
        Object name -> object, from the source when it holds it, else
        :func:`resolve_dataset_object`.
    """
    objects = {}
    for r in rankings:
        if r.object in objects:
            continue
        source = sources_by_object[r.object]
        known = getattr(source, "objects", None) or {}
        if r.object in known:
            objects[r.object] = known[r.object]
            continue
        row = r.best[0].row if r.best else {}
        objects[r.object] = resolve_dataset_object(
            r.object,
            row.get("object_hash"),
            source,
            args.mesh,
            out,
            scale_options(args),
            materials=bool(getattr(args, "materials", False)),
        )
    return objects


# --------------------------------------------------------------------------- the command


def run(args, out) -> None:
    """Run ``affordgrasp show``: rank, draw, write the grid, the page and the summary.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).
    out : Output
        Where text, tables and the ``--json`` result go.

    Raises
    ------
    InputError
        For bad options or sources without rows.
    """
    from ..search.best import top_grasps
    from ..viz.showcase import draw_best

    check_counts(args)
    check_mesh_files(args)
    check_output_dir(args.out, "--out")
    if args.top < 1:
        raise InputError(f"--top must be at least 1, got {args.top}")
    for flag, value in (("--cell", args.cell), ("--grasp-size", args.grasp_size)):
        if not 64 <= value <= 2048:
            raise InputError(f"{flag} must be between 64 and 2048 pixels, got {value}")
    tasks, thresholds = parse_tasks(args.task, args.mode, args.threshold)
    sources = open_sources(args, out, tasks, thresholds)
    rankings = []
    sources_by_object = {}
    for source in sources:
        found = top_grasps(
            source,
            tasks,
            mode=args.mode,
            top=args.top,
            thresholds=thresholds,
            robust=bool(getattr(args, "robust", 0)),
        )
        for (obj_name, _), ranking in found.items():
            sources_by_object.setdefault(obj_name, source)
            rankings.append(ranking)
    if not rankings:
        raise InputError("the sources hold no rows; nothing to show")
    # Objects in the order they were met, tasks in the order asked.
    order = {t.name: i for i, t in enumerate(tasks)}
    first = {}
    for r in rankings:
        first.setdefault(r.object, len(first))
    rankings.sort(key=lambda r: (first[r.object], order[r.task]))
    objects = objects_of(rankings, sources_by_object, args, out)
    n_draw = sum(len(r.best) for r in rankings)
    with out.progress("drawing", max(n_draw, 1)) as advance:
        result = draw_best(
            rankings,
            objects,
            args.out,
            mode=args.mode,
            top=args.top,
            cell_px=args.cell,
            grasp_px=args.grasp_size,
            each=args.each,
            html=not args.no_html,
            cones=args.cones,
            name=args.name,
            title=args.title,
            progress=advance,
            hands={o: s.hand for o, s in sources_by_object.items() if s.hand is not None},
        )
    out.table(
        f"best grasps ({args.mode})",
        ["object", "task", "rank", "score", "sample", "seed", "status", "contacts", "ε"],
        [
            [
                b["object"],
                b["task"],
                b["rank"],
                b["score"],
                b["sample"],
                b["seed"],
                b["status"],
                b["n_contacts"],
                b.get("epsilon", math.nan),
            ]
            for b in result.best
        ],
    )
    by_task = {t.name: t for t in tasks}
    for r in rankings:
        note = probability_note(by_task[r.task], r.best[0].score if r.best else None, r.object)
        if note:
            out.text(note)
    empty = [r for r in rankings if not r.best]
    for r in empty:
        more = "more --samples"
        if getattr(sources_by_object[r.object], "directory", None) is not None:
            more = "a dataset with more samples ('affordgrasp generate --samples N')"
        out.text(
            f"{r.object}: no grasp scores above −∞ for {r.task} in mode {args.mode} "
            f"({r.accepted} of {r.scored} samples accepted); try "
            + (
                more
                if args.mode == "no-robustness" or args.robust
                else f"--mode no-robustness or {more}"
            )
        )
    out.text(f"wrote {result.grid}")
    if result.html:
        out.text(f"wrote {result.html}")
    elif not args.no_html:
        out.text("no grasp to show in 3D: the HTML page was not written")
    for p in result.grasps:
        out.text(f"wrote {p}")
    out.result(
        {
            "files": {
                "grid": str(result.grid),
                "html": str(result.html) if result.html else None,
                "grasps": [str(p) for p in result.grasps],
            },
            "tasks": [t.name for t in tasks],
            "mode": args.mode,
            "top": args.top,
            "rankings": [
                {"object": r.object, "task": r.task, "scored": r.scored, "accepted": r.accepted}
                for r in rankings
            ],
            "best": result.best,
        }
    )
