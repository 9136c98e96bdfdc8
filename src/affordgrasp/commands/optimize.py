"""``affordgrasp optimize``: maximise a task's F_T in simulation (cross-entropy method)."""

from __future__ import annotations

from .best import loosen_hint, metric_cells, metric_headings, shown_metrics
from .limits import OWN_CHECK, ROBUST, SEED, SIZE_M, USES, WORKERS
from .object_options import HAND_HELP, add_scale_arguments, load_objects
from .task_options import (
    add_robust_argument,
    add_task_arguments,
    parse_thresholds,
    probability_note,
    robust_option,
)

# Of the numeric options: see limits.check_limits.
LIMITS = {
    "budget": (None, 10**8, "the value of every simulation is kept"),
    "seed": SEED,
    "size_m": SIZE_M,
    "population": (None, 10**6, "a generation is simulated and held at once"),
    "workers": WORKERS,
    "uses": (None, *USES[1:]),
    "robust": ROBUST,
    "restarts": (None, 10_000, "each restart draws populations of its own from the budget"),
    "refine": OWN_CHECK,
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp optimize`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument("object", metavar="OBJECT", help="knife, knife:7 or a mesh path")
    add_task_arguments(p, several=False)
    p.add_argument("--budget", type=int, default=20000, help="simulations (default 20000)")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--hand", default="barrett", help=HAND_HELP)
    add_scale_arguments(p)
    p.add_argument(
        "--population", type=int, default=None, help="samples per generation (default budget/20)"
    )
    p.add_argument(
        "--workers", type=int, default=None, metavar="K", help="processes (default: all cores)"
    )
    p.add_argument(
        "--engine", choices=("local", "ray"), default="local", help="local processes or Ray"
    )
    p.add_argument("--address", default=None, help="an existing Ray cluster (--engine ray)")
    p.add_argument(
        "--uses",
        type=int,
        default=2000,
        metavar="M",
        help="score each grasp with its best of M use points drawn by surface area (ray casts, no "
        "simulation; default 2000); 0: each sample keeps its own use direction",
    )
    p.add_argument(
        "--passing-uses",
        action="store_true",
        help="draw use points by area until M pass the task's tests of the use point alone "
        "(an edge for cut, a face for beat) and score only those",
    )
    add_robust_argument(
        p,
        help="maximise the robust score over K perturbed copies per grasp (each grasp keeps "
        "its own use direction; --budget counts grasps; default 0: plain F_T)",
    )
    p.add_argument(
        "--restarts",
        type=int,
        default=1,
        metavar="R",
        help="independent cross-entropy runs sharing the budget (default 1)",
    )
    p.add_argument(
        "--refine",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="share of the budget, in [0, 1), that continues the best run around its best "
        "grasp (default 0)",
    )
    p.add_argument(
        "--no-baseline",
        action="store_true",
        help="skip uniform random sampling with the same budget",
    )


def run(args, out) -> None:
    """Run ``affordgrasp optimize``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..search.optimize import optimize
    from ..tasks import get_task

    (obj,) = load_objects([args.object], args)
    result = optimize(
        obj,
        args.task,
        mode=args.mode,
        budget=args.budget,
        seed=args.seed,
        thresholds=parse_thresholds(args.threshold),
        hand=args.hand,
        workers=args.workers,
        engine=args.engine,
        address=args.address,
        population=args.population,
        baseline=not args.no_baseline,
        uses=args.uses,
        restarts=args.restarts,
        refine=args.refine,
        progress=lambda total: out.progress("optimising", total),
        robust=robust_option(args),
        passing_uses=args.passing_uses,
    )
    if result.use_sampling is not None:
        out.text(result.use_sampling.describe())
    shown = shown_metrics(args.task)
    rows = []
    for label, found in (("cross-entropy", result.cem), ("uniform random", result.random)):
        if found is None:
            if label == "uniform random" and args.no_baseline:
                continue
            rows.append([label, "-inf", "", "", *[""] * len(shown)])
            continue
        row = found.row
        rows.append(
            [
                label,
                found.value,
                found.evaluations,
                row["status"],
                *metric_cells(row, shown),
            ]
        )
    out.table(
        f"{result.object}: task {result.task} ({result.mode}), {result.budget:,} simulations "
        f"each, seed {result.seed}",
        [
            "method",
            "F_T",
            "found after",
            "status",
            *metric_headings(shown),
        ],
        rows,
    )
    match = result.cem_evaluations_to_match_random
    if result.random is not None and result.cem is not None:
        out.text(
            f"cross-entropy reached random sampling's best after {match:,} simulations"
            if match
            else "cross-entropy did not reach random sampling's best"
        )
        share = result.random_fraction_at_least_cem
        out.text(f"{100 * share:.3g}% of the random samples are as good as the cross-entropy best")
    best = max((f.value for f in (result.cem, result.random) if f is not None), default=None)
    note = probability_note(get_task(args.task), best, result.object)
    if note:
        out.text(note)
    if result.cem is None and result.random is None:
        out.text(
            "no simulation passed the task's thresholds (every F_T = -inf); try "
            f"{loosen_hint(args.mode)} or a larger --budget"
        )
    out.text(f"{result.elapsed_s:.1f} s")
    out.result(result.to_dict())
