"""``affordgrasp physics``: validate a dataset's grasps in MuJoCo; what do the metrics predict?"""

from __future__ import annotations

import math
import shlex
import sys

from ..errors import DatasetError, InputError, MissingDependencyError
from ..physics.settings import PROTOCOLS, TRIALS, PhysicsSettings, protocol_settings
from .batches import add_engine_arguments
from .limits import MAX_SEED, OWN_CHECK, ROBUST, SEED_BITS, WORKERS
from .task_options import add_robust_argument, robust_option

# Of the numeric options: see limits.check_limits; the settings check their physical ranges.
LIMITS = {
    "workers": WORKERS,
    "shard_size": (None, 100_000, "a shard's outcomes are held before they are written"),
    "max_per_object": (None, MAX_SEED, "row counts are 64-bit"),
    **dict.fromkeys(
        ("load_factor", "density", "grip_torque", "grip_force", "friction_margin", "timestep"),
        OWN_CHECK,
    ),
    "robust": ROBUST,
    "seed": SEED_BITS,
    "coacd_threshold": (None, 1.0, "CoACD's concavity threshold is a fraction of the size"),
    "coacd_max_hulls": (None, 256, "each convex part is a body of the MuJoCo scene"),
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp physics`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    d = PhysicsSettings()
    p.add_argument(
        "dataset", metavar="DATASET", help="a directory written by 'affordgrasp generate'"
    )
    p.add_argument(
        "--out", required=True, metavar="DIR", help="outcome shards (Parquet directory, resumable)"
    )
    p.add_argument("--report", default=None, metavar="DIR", help="write the report and plots here")
    p.add_argument(
        "--compare",
        action="append",
        default=None,
        metavar="OUT",
        help="with --report: the headline AUCs of another physics run (e.g. the other "
        "protocol) beside this run's (repeatable)",
    )
    p.add_argument(
        "--protocol",
        choices=PROTOCOLS,
        default="affordgrasp",
        help="affordgrasp (default) or dgb (DexGraspBench-compatible); docs/physics.md lists "
        "every constant of both",
    )
    p.add_argument(
        "--no-backoff",
        action="store_true",
        help="start where the dataset row puts the hand, even inside the object's convex parts",
    )
    add_engine_arguments(p)
    p.add_argument("--shard-size", type=int, default=128, metavar="ROWS", help="rows per shard")
    p.add_argument("--object", action="append", default=None, help="only this object (repeatable)")
    p.add_argument(
        "--max-per-object", type=int, default=None, metavar="N", help="first N grasps per object"
    )
    p.add_argument(
        "--load-factor",
        type=float,
        default=None,
        metavar="K",
        help=f"hold test load, k·m·g (default {d.load_factor}, dgb 10)",
    )
    p.add_argument(
        "--density",
        type=float,
        default=None,
        help=f"object density, kg/m^3 (default {d.density:g})",
    )
    p.add_argument(
        "--grip-torque",
        type=float,
        default=None,
        help=f"finger joint torque, N·m (default {d.grip_torque})",
    )
    p.add_argument(
        "--grip-force", type=float, default=None, help=f"jaw force, N (default {d.grip_force})"
    )
    p.add_argument(
        "--friction-margin",
        type=float,
        default=None,
        metavar="DEG",
        help="widen the material table's friction cones by this angle in the engine, degrees "
        f"(default {d.friction_margin_deg:g}: the convex parts' normal error; dgb 0, it "
        "sets μ 0.6)",
    )
    p.add_argument("--timestep", type=float, default=None, help=f"s (default {d.timestep})")
    p.add_argument("--gravity", action="store_true", help="gravity on (-z of the hand frame)")
    p.add_argument(
        "--backdrivable",
        action="store_true",
        help="fingers the load can push open (default: non-backdrivable drives)",
    )
    add_robust_argument(
        p,
        help="report the robust scores of the replayed rows beside their outcomes (the "
        "report's AUC tables gain robust_hold, robust_fc, ...): a dataset generated with "
        "--robust K keeps its columns; a plain dataset has them computed for the replayed "
        "rows from their stored pregrasps (K perturbed copies, docs/robust.md). Default 0: "
        "the dataset's robust columns are reported when it has them, none computed",
    )
    p.add_argument(
        "--trials",
        default=None,
        metavar="T[,T...]",
        help=f"also run these task trials ({', '.join(TRIALS)}): the grasp strikes a nail, "
        "draws an edge over a workpiece, holds its load (docs/physics.md#task-trials); "
        "columns beat_ok, cut_ok, pick_ok and their measurements",
    )
    p.add_argument("--seed", type=int, default=d.seed, help="seed of the convex decomposition")
    p.add_argument(
        "--coacd-threshold",
        type=float,
        default=d.coacd_threshold,
        help=f"concavity threshold of the convex decomposition (default {d.coacd_threshold})",
    )
    p.add_argument(
        "--coacd-max-hulls",
        type=int,
        default=d.coacd_max_hulls,
        help=f"most convex parts per object (default {d.coacd_max_hulls})",
    )


def _settings(args) -> PhysicsSettings:
    given = {
        name: getattr(args, name)
        for name in ("load_factor", "density", "grip_torque", "grip_force", "timestep")
        if getattr(args, name) is not None
    }
    if args.friction_margin is not None:
        given["friction_margin_deg"] = args.friction_margin
    return protocol_settings(
        args.protocol,
        gravity=args.gravity,
        backdrivable=args.backdrivable,
        seed=args.seed,
        backoff=not args.no_backoff,
        coacd_threshold=args.coacd_threshold,
        coacd_max_hulls=args.coacd_max_hulls,
        **given,
    )


def _trials(text: str | None) -> tuple[str, ...]:
    """The names of ``--trials`` (comma separated), checked."""
    if not text:
        return ()
    names = [t.strip() for t in text.split(",") if t.strip()]
    unknown = [t for t in names if t not in TRIALS]
    if unknown:
        raise InputError(
            f"--trials: unknown trial {', '.join(unknown)}; choose among {', '.join(TRIALS)}"
        )
    return tuple(names)


def _interval(v) -> str:
    auc, lo, hi = v
    return "—" if math.isnan(auc) else f"{auc:.3f} [{lo:.3f}–{hi:.3f}]"


def _dataset_with_objects(directory, names):
    """The dataset, its objects resolved (kept by the handle), before any output is written.

    A missing mesh is refused here, with a fix that ``physics`` offers: the message shared
    with ``show`` and ``plots`` names their ``--mesh``.
    """
    from ..dataset.handle import Dataset

    dataset = Dataset.open(directory)
    for name in names or dataset.objects:
        try:
            dataset.object(name)
        except DatasetError as exc:
            text, fix = str(exc), "; restore the mesh file"
            if fix not in text:
                raise
            raise DatasetError(
                text[: text.index(fix)] + "; restore the mesh file at the path the dataset's "
                "_manifest.json records, or copy it into the dataset directory"
            ) from None
    return dataset


def run(args, out) -> None:
    """Run ``affordgrasp physics``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..physics import deps
    from ..physics.report import DESIGNED_FOR, physics_report
    from ..physics.run import read_outcomes, run_physics
    from .output_files import check_output_dir

    settings = _settings(args)
    robust = robust_option(args)
    trials = _trials(args.trials)
    check_output_dir(args.out, "--out")
    if args.report:
        check_output_dir(args.report, "--report")
    try:
        deps.mujoco()
        deps.coacd()
    except MissingDependencyError as exc:
        raise InputError(str(exc)) from None
    dataset = _dataset_with_objects(args.dataset, args.object)
    try:
        summary = run_physics(
            dataset,
            args.out,
            settings=settings,
            workers=args.workers,
            engine=args.engine,
            address=args.address,
            shard_size=args.shard_size,
            objects=args.object,
            max_per_object=args.max_per_object,
            progress=lambda total: out.progress("validating", total),
            log_message=lambda m: print(m, file=sys.stderr) if not out.json_mode else None,
            robust=robust,
            trials=trials,
        )
    except KeyboardInterrupt:
        print(
            f"stopped; every finished shard is kept in {args.out}. Run the same command to "
            f"finish:\n  {shlex.join(sys.argv)}",
            file=sys.stderr,
        )
        raise
    rows = [
        [name, n, held, f"{100.0 * held / n:.1f}%" if n else "—"]
        for name, (held, n) in summary.hold_ok.items()
    ]
    out.table("Hold test", ["object", "validated", "held", "rate"], rows)
    for trial, per_object in summary.trials.items():
        out.table(
            f"Task trial: {trial}",
            ["object", "tried", "passed", "rate"],
            [
                [name, n, ok, f"{100.0 * ok / n:.1f}%" if n else "—"]
                for name, (ok, n) in per_object.items()
            ],
        )
    rate = summary.validations_per_core_hour
    out.table(
        "This run",
        ["shards written", "shards already there", "grasps", "seconds", "per CPU core-hour"],
        [
            [
                summary.shards_written,
                summary.shards_skipped,
                summary.rows_written,
                round(summary.elapsed_s, 1),
                round(rate) if rate else "—",
            ]
        ],
    )
    doc = {"summary": summary.to_dict(), "settings": settings.to_dict()}
    if args.report:
        others = [read_outcomes(o) for o in args.compare or ()]
        report = physics_report(read_outcomes(args.out), args.report, compare=others)
        headline = []
        for pred, outcome in DESIGNED_FOR.items():
            g = report["all"]
            if outcome in g["auc"]:
                value, kind = g["auc"][outcome].get(pred, math.nan), "ROC-AUC"
            else:
                value, kind = g["spearman"][outcome].get(pred, math.nan), "Spearman"
            if math.isnan(value):  # say why rather than nan
                value = "undefined: " + g["undefined"].get(outcome, {}).get(pred, "not computed")
            headline.append([pred, outcome, kind, value])
        out.table(
            f"Metrics vs outcomes (n={report['all']['n']})",
            ["predictor", "outcome", "statistic", "value"],
            headline,
        )
        h = report["headline"]
        groups = [("all", h["all"]), ("force closure", h["force_closure"])]
        groups += [("settled", h["settled"])]
        out.table(
            "ROC-AUC for hold_ok [95 % bootstrap interval]",
            ["predictor", *(f"{g} (n={v['n']})" for g, v in groups)],
            [[p, *(_interval(v["auc"][p]) for _, v in groups)] for p in h["predictors"]],
        )
        if "start" in report:
            st = report["start"]
            out.text(
                f"start: {100 * st['start_under_0.5mm']:.1f} % of rows below 0.5 mm of "
                f"penetration ({100 * st['initial_over_0.5mm']:.1f} % at 0.5 mm or more as "
                f"placed); the squeeze ejected {100 * st['force_closure']['ejected_rate']:.1f} % "
                "of the force-closure grasps"
            )
        out.text(f"report: {args.report}/report.md and PNG plots")
        doc["report"] = report
    out.result(doc)
