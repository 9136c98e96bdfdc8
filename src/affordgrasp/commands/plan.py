"""``affordgrasp plan``: choose a grasp of an object from camera-in-hand views (fused into a
surface, or read by learned models), then simulate every candidate to say how good the
choice truly was."""

from __future__ import annotations

import sys

from ..errors import InputError, MissingDependencyError
from ..grasp.pregrasp import (
    PLAN_CANDIDATES,
    PLAN_OFFSET_RANGE,
    PLAN_REFINE,
    PLAN_REFINE_NEIGHBOURS,
    PLAN_ROBUST_CHECK,
    PLAN_USES,
    PLAN_VERIFY,
    POSE_ERROR_DEG,
    POSE_ERROR_M,
)
from .limits import OWN_CHECK, SEED_BITS, SIZE_M

# Of the numeric options: see limits.check_limits.
LIMITS = {
    **dict.fromkeys(("candidates", "threshold", "offset_range"), OWN_CHECK),
    "seed": SEED_BITS,
    "robust_check": (None, 1000, "each is re-simulated under perturbations"),
    "uses": (1, 100_000, "every grasp is paired with each"),
    "refine": (None, 1000, f"{PLAN_REFINE_NEIGHBOURS} more candidates are drawn near each"),
    "verify": (None, 100_000, "each is simulated on the fused surface"),
    "size_m": SIZE_M,
}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp plan`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    from .object_options import HAND_HELP, add_scale_arguments

    p.add_argument("object", help="family (knife), family:seed (knife:7) or a mesh path")
    p.add_argument("--task", default="pick", help="task that judges the choice (default pick)")
    p.add_argument("--mode", default="default", help="threshold mode of the task")
    p.add_argument(
        "--candidates",
        type=int,
        default=PLAN_CANDIDATES,
        help=f"candidate grasps drawn (default {PLAN_CANDIDATES})",
    )
    p.add_argument(
        "--model",
        default="views",
        help="views (the default; no learned model: the first 64 candidates' views fused "
        "into a surface, every candidate simulated on it, more drawn near the best ones, of "
        "the viable ones with the widest epsilon there the one that keeps it best under small "
        "perturbations chosen; needs scikit-image), "
        "learned (the same fused surface read as a cloud by the shipped scorer network: "
        "the most probably viable candidate, in milliseconds; pick and other tasks without "
        "a use point), "
        "classifier (the shipped classifier "
        "alone: the most probably viable candidate), default (shipped classifier + "
        "regressor: the classifier's threshold, then least predicted effort), regressor, "
        "or model files separated by commas (at most one classifier and one regressor)",
    )
    p.add_argument(
        "--threshold",
        type=float,
        default=None,
        help="classifier decision threshold (default: the one stored in the model, else 0.5)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the candidates (default 0)")
    p.add_argument(
        "--offset-range",
        type=float,
        default=None,
        metavar="R",
        help="the candidates' approach-line offsets (u4, u5) are drawn in [-R, R]^2 (default "
        f"{PLAN_OFFSET_RANGE}: near the object's centre; 1: uniform, as datasets are generated)",
    )
    p.add_argument(
        "--robust-check",
        type=int,
        default=None,
        metavar="N",
        help="with --model views: re-simulate the first N candidates on the fused surface "
        "under small perturbations and choose the one whose copies keep the widest epsilon "
        f"(default {PLAN_ROBUST_CHECK}; 0: the widest epsilon as it is)",
    )
    p.add_argument(
        "--refine",
        type=int,
        default=None,
        metavar="N",
        help=f"with --model views: draw {PLAN_REFINE_NEIGHBOURS} more candidates near each of "
        "the first N on the fused surface and rank them with the others (default "
        f"{PLAN_REFINE}; 0: none)",
    )
    p.add_argument(
        "--verify",
        type=int,
        default=None,
        metavar="N",
        help="with --model learned: simulate the scorer's first N candidates on the fused "
        f"surface and take the viable one with the widest epsilon there (default "
        f"{PLAN_VERIFY}; 0: the scorer's first)",
    )
    p.add_argument("--hand", default="barrett", help=HAND_HELP)
    p.add_argument(
        "--physics",
        action="store_true",
        help="replay the chosen grasp in MuJoCo (needs affordgrasp[physics])",
    )
    p.add_argument(
        "--sensor",
        action="store_true",
        help="the models see the images a depth sensor would return (noise, lost returns; "
        "seeded by --seed); default: exact images",
    )
    p.add_argument(
        "--pose-error",
        default=f"{POSE_ERROR_M * 100:g},{POSE_ERROR_DEG:g}",
        metavar="CM,DEG",
        help="the error of the robot's estimate of the object's pose: the views are aimed "
        "from the object moved by CM centimetres and turned by DEG degrees (directions "
        f"drawn from --seed; default {POSE_ERROR_M * 100:g},{POSE_ERROR_DEG:g}; 0: aimed "
        "from the true object)",
    )
    p.add_argument(
        "--uses",
        type=int,
        default=None,
        help="with --model views and a task that reads the use point (beat, cut): use "
        f"points drawn on the fused surface and paired with every grasp (default {PLAN_USES})",
    )
    add_scale_arguments(p)


def pose_error_option(text: str) -> tuple[float, float] | None:
    """``--pose-error CM,DEG`` as (metres, degrees); ``0`` or ``0,0``: None.

    Parameters
    ----------
    text : str

    Returns
    -------
    (float, float) or None

    Raises
    ------
    InputError
        For anything but one or two numbers >= 0.
    """
    parts = [t.strip() for t in str(text).split(",")]
    try:
        values = [float(t) for t in parts]
    except ValueError:
        values = []
    if len(values) not in (1, 2) or not all(v >= 0 and v < float("inf") for v in values):
        raise InputError(
            f"--pose-error takes CM,DEG (two numbers >= 0, e.g. 1,5) or 0, got {text!r}"
        )
    cm, deg = (values[0], values[0]) if len(values) == 1 else values
    if len(values) == 1 and cm != 0:
        raise InputError(f"--pose-error takes CM,DEG (e.g. 1,5) or 0, got {text!r}")
    return None if cm == 0 and deg == 0 else (cm / 100.0, deg)


def run(args, out) -> None:
    """Run ``affordgrasp plan``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..objects import load_object
    from .limits import check_fits_in_memory
    from .object_options import materials_option, scale_options

    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    pose_error = pose_error_option(args.pose_error)
    check_fits_in_memory("--candidates", args.candidates, CANDIDATE_BYTES)
    models = args.model.split(",") if "," in args.model else args.model
    try:
        from ..learning.plan import LEARNED, VIEWS, plan, trial_names
        from ..learning.torch_support import require_safetensors, require_torch

        options = (
            (args.robust_check, "--robust-check"),
            (args.refine, "--refine"),
            (args.uses, "--uses"),
        )
        for value, option in options:
            if value is not None and models != VIEWS:
                raise InputError(
                    f"{option} simulates candidates on the fused views' surface: it needs "
                    "--model views (the default)"
                )
        if args.verify is not None and models != LEARNED:
            raise InputError("--verify checks the learned scorer's first candidates: it needs "
                             "--model learned")  # fmt: skip
        if models in (VIEWS, LEARNED):
            from ..vision.fusion import require_marching_cubes

            require_marching_cubes()
        if models not in (VIEWS, LEARNED):
            require_torch()
            require_safetensors()
        if args.physics:
            from ..physics import deps

            deps.mujoco()
            deps.coacd()
    except MissingDependencyError as exc:
        raise InputError(str(exc)) from None
    obj = load_object(args.object, **scale_options(args), materials=materials_option(args))

    def progress(step: str) -> None:
        if not args.json:
            print(f"plan: {step} ({args.candidates} candidates)", file=sys.stderr, flush=True)

    result = plan(
        obj,
        args.task,
        candidates=args.candidates,
        models=models,
        seed=args.seed,
        hand=args.hand,
        mode=args.mode,
        physics=args.physics,
        threshold=args.threshold,
        sensor=_sensor(args),
        **({} if args.offset_range is None else {"offset_range": args.offset_range}),
        **({} if args.robust_check is None else {"robust_check": args.robust_check}),
        **({} if args.refine is None else {"refine": args.refine}),
        pose_error=pose_error,
        **({} if args.uses is None else {"uses": args.uses}),
        **({} if args.verify is None else {"verify": args.verify}),
        progress=progress,
    )
    doc = result.summary()
    c = doc["chosen"]
    m = doc["measures"]
    rows = [
        ["true task score", c["true_score"], "-", m["oracle"]["top1_score"]],
        ["viable", c["viable"], m["random"]["top1_viable"], m["oracle"]["top1_viable"]],
        [
            "task-feasible",
            c["feasible"],
            m["random"]["top1_feasible"],
            m["oracle"]["top1_feasible"],
        ],
        [
            "percentile",
            c["percentile"],
            m["random"]["top1_percentile"],
            m["oracle"]["top1_percentile"],
        ],
        [
            "top-5 viable share",
            m["model"]["topk_precision"],
            m["random"]["topk_precision"],
            m["oracle"]["topk_precision"],
        ],
    ]
    out.table(
        f"{doc['object']}, task {doc['task']}: candidate {c['index']} of {doc['candidates']}"
        + (f" and {doc['refined']} refined" if doc["refined"] else "")
        + f" ({doc['rule']}); {doc['candidates_viable']} viable, "
        f"{doc['candidates_feasible']} task-feasible",
        ["quantity", "chosen", "random (expected)", "oracle"],
        rows,
    )
    if c["probability"] is not None:
        out.text(f"viability probability {c['probability']:.3f}")
    if c["predicted"] is not None:
        out.text(f"predicted value {c['predicted']:.4g}")
    if c["fused_score"] is not None:
        out.text(
            f"on the fused surface: task score {c['fused_score']:.4g}, viable {c['fused_viable']}"
        )
    if c["fused_viable"] is False:
        # measured on unseen objects (docs/learning.md): a choice viable on the fused surface
        # was truly viable in 0.92 of the decisions, one that was not in none of 10
        print(
            "plan: no candidate is viable on the fused surface, so the choice is probably not "
            "viable either; draw more candidates (--candidates) or another seed (--seed)",
            file=sys.stderr,
        )
    if c.get("use_part") is not None or c.get("contact_parts"):
        touched = ", ".join(sorted(set(c.get("contact_parts") or []))) or "nothing"
        out.text(f"on the true object: use point on {c.get('use_part')}, contacts on {touched}")
    if doc["physics"] is not None:
        ph = doc["physics"]
        line = (
            f"physics replay: hold {'held' if ph.get('hold_ok') else 'failed'} "
            f"({ph.get('hold_directions_ok', 0)}/6 directions), settled {ph.get('settled')}"
        )
        for trial in trial_names(doc["task"]):
            ok = ph.get(f"{trial}_ok")
            said = "succeeded" if ok else "failed" if ok is not None else "not run"
            line += f"; {trial} trial {said}"
        out.text(line)
    out.text("seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in doc["timings"].items()))
    out.result(doc)


def _sensor(args):
    """The sensor model of ``--sensor`` (seeded by ``--seed``), else None."""
    if not args.sensor:
        return None
    from ..vision.sensor import SensorModel

    return SensorModel(seed=args.seed)


# Bytes per candidate while plan holds it: its float32 and uint16 depth images (64 + 32 kB
# at 128 px), its simulated row and its share of the network's batch activations.
CANDIDATE_BYTES = 128 * 1024
