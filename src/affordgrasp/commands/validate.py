"""``affordgrasp validate``: the paper's validation: are the best grasps of each task right?

The best grasps of cut, beat and pick, found by brute force and by the optimiser on the
built-in families, judged by the families' semantic parts (:mod:`affordgrasp.validation`).
The defaults are a quick check (one seed of the hammer and the knife, small searches, a few
seconds); ``--full`` runs the study of docs/validation.md §5 (every judged family, five
seeds, the paper's search sizes, figures), and any option given beside it wins.
"""

from __future__ import annotations

import argparse

from ..errors import InputError
from .limits import OWN_CHECK, ROW_BYTES, USES, memory_cap
from .task_options import names_of

QUICK = {"seeds": 1, "grasps": 100, "uses": 200, "budget": 100, "families": "hammer,knife"}
FULL = {"seeds": 5, "grasps": 1000, "uses": 4000, "budget": 1000, "families": "all"}


# Of the numeric options: see limits.check_limits; ValidationSettings.check the rest.
LIMITS = {
    "seeds": (None, 1000, "each object instance is evaluated whole"),
    "grasps": (None, memory_cap(ROW_BYTES), "rows of about 2 kB are held per object"),
    "uses": (None, *USES[1:]),
    "budget": (None, 10**8, "the value of every simulation is kept"),
    "restarts": (None, 10_000, "each restart draws populations of its own from the budget"),
    **dict.fromkeys(("refine", "also_grasps"), OWN_CHECK),  # ValidationSettings
    "top": (None, 1000, "the top grasps are judged and drawn per object"),
    "cell_px": (None, 2048, "pixels of a figure cell"),
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp validate`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """

    def preset(name: str) -> str:
        return f"default {QUICK[name]}; --full: {FULL[name]}"

    p.add_argument("-o", "--out", required=True, metavar="OUTDIR", help="directory to write into")
    p.add_argument(
        "--full",
        action="store_true",
        help="the full study of docs/validation.md (every family, 5 seeds, figures; hours)",
    )
    p.add_argument("--tasks", default="cut,beat,pick", help="comma-separated (default all three)")
    p.add_argument(
        "--families",
        default=None,
        help=f"comma-separated families, or 'all' ({preset('families')})",
    )
    p.add_argument(
        "--seeds", type=int, default=None, metavar="N", help=f"instances 0..N-1 ({preset('seeds')})"
    )
    p.add_argument(
        "--grasps",
        type=int,
        default=None,
        help=f"uniform grasps of the brute force ({preset('grasps')})",
    )
    p.add_argument(
        "--uses", type=int, default=None, help=f"use points per grasp ({preset('uses')})"
    )
    p.add_argument(
        "--budget", type=int, default=None, help=f"optimiser simulations ({preset('budget')})"
    )
    p.add_argument(
        "--restarts",
        type=int,
        default=1,
        help="independent cross-entropy runs sharing the budget (default 1)",
    )
    p.add_argument(
        "--refine",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="share of --budget that continues the best restart around its best point (default 0)",
    )
    p.add_argument(
        "--also-grasps",
        type=int,
        default=0,
        metavar="K",
        help="also the brute force on the first K of the --grasps grasps (default 0: not)",
    )
    p.add_argument("--top", type=int, default=10, help="top grasps judged per object (default 10)")
    p.add_argument("--no-optimizer", action="store_true", help="skip the optimiser")
    p.add_argument("--no-brute-force", action="store_true", help="skip the brute force")
    p.add_argument(
        "--figures",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="render the figures of paper Figs. 3-7 (default off; --full: on)",
    )
    p.add_argument(
        "--cell-px", type=int, default=220, help="figure cell size, pixels (default 220)"
    )
    p.add_argument(
        "--cache",
        default=None,
        metavar="DIR",
        help="evaluated grasp tables, reused by later runs (default OUTDIR/cache)",
    )
    p.add_argument(
        "--materials",
        action="store_true",
        help="the families' per-part materials instead of uniform unit density",
    )


def settings_of(args):
    """The :class:`~affordgrasp.validation.ValidationSettings` the options ask for.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.

    Returns
    -------
    ValidationSettings
        Checked.

    Raises
    ------
    InputError
        For options the study cannot run, naming the option.
    """
    from ..validation import ValidationSettings

    preset = FULL if args.full else QUICK

    def pick(name):
        value = getattr(args, name)
        return preset[name] if value is None else value

    families = pick("families")
    figures = args.full if args.figures is None else args.figures
    if args.no_optimizer and args.no_brute_force:
        raise InputError("--no-optimizer and --no-brute-force leave nothing to run; drop one")
    return ValidationSettings(
        seeds=pick("seeds"),
        grasps=pick("grasps"),
        uses=pick("uses"),
        budget=pick("budget"),
        restarts=args.restarts,
        refine=args.refine,
        also_grasps=args.also_grasps,
        top=args.top,
        tasks=tuple(names_of("--tasks", args.tasks, "cut,beat")),
        families=() if families == "all" else tuple(names_of("--families", families, "knife")),
        optimizer=not args.no_optimizer,
        brute_force=not args.no_brute_force,
        figures=figures,
        cell_px=args.cell_px,
        materials=args.materials,
    ).check()


def run(args, out) -> None:
    """Run ``affordgrasp validate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..validation import validate_tasks
    from .output_files import check_output_dir

    settings = settings_of(args)
    check_output_dir(args.out, "--out")
    if args.cache is not None:
        check_output_dir(args.cache, "--cache")
    with out.progress("validating", settings.steps) as advance:
        report = validate_tasks(
            settings,
            args.out,
            cache=args.cache,
            on_object=lambda task, family, seed, entry: advance(),
        )
    methods = [
        m
        for m, on in (("brute_force", settings.brute_force), ("optimizer", settings.optimizer))
        if on
    ]
    rows = []
    for task, result in report["tasks"].items():
        for family, entry in result["families"].items():
            rows.append([task, family, *_cells(_entry_hits(entry, methods), methods)])
        summary = result["summary"]
        totals = {m: (summary[m]["hits"], summary[m]["top_grasps"]) for m in methods}
        rows.append([task, "all", *_cells(totals, methods)])
    out.table(
        f"top-{settings.top} grasps judged right ({settings.seeds} seed(s) per family; "
        f"{report['seconds']:.1f} s)",
        ["task", "family", *[f"{m.replace('_', ' ')}" for m in methods]],
        rows,
    )
    empty = [
        task
        for task, result in report["tasks"].items()
        if not any(result["summary"][m]["top_grasps"] for m in methods)
    ]
    if empty:
        out.text(
            f"no grasp passed the thresholds of {', '.join(empty)} in these searches: larger "
            "--grasps, --uses and --budget (or --full) find them"
        )
    out.text(f"report: {args.out}/validation.json")
    out.result(report)


def _cells(hits: dict, methods: list[str]) -> list[str]:
    """``right/judged (percent)`` of each method; ``hits[method]`` is (right, judged)."""
    cells = []
    for method in methods:
        right, judged = hits[method]
        cells.append(f"{right}/{judged} ({100 * right / judged:.0f}%)" if judged else "none found")
    return cells


def _entry_hits(entry: dict, methods: list[str]) -> dict:
    """(right, judged) of each method over the seeds of one family's entry."""
    return {m: (sum(h for h, _ in entry[m]), sum(n for _, n in entry[m])) for m in methods}
