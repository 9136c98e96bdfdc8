"""The task trials that the shipped task probabilities are fitted on (one Parquet file per object).

    python tools/task_trial_data.py --out DIR [--seeds 20-27] [--grasps 60] [--uses 3]
        [--families hammer,axe,...] [--robust 25]

Per object (every family × seed, crisp and ``~scan``, per-part materials): ``--samples``
uniform pregrasps are simulated; up to ``--grasps`` of the force-closure ones (and a tenth as
many that are not, so that the models see failures of the grip too) are kept. Each kept
grasp is paired with ``--uses`` use points of each task the family serves (beat: hammers and
axes; cut: knives, cleavers, daggers, swords): half drawn among those that pass the task's
rule tests of the use point alone (a blunt face, an edge), half by area, so that the pairs
cover both what a search proposes and what it must reject. Every pair is evaluated with the
robust columns (K copies) and tried in MuJoCo (``beat``/``cut`` where the family serves it,
``pick`` on every row) with the default protocol. Containers get pick rows only.
Deterministic; an object whose file exists is skipped (resumable).
"""

from __future__ import annotations

import argparse
import time
import zlib
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from affordgrasp.errors import MeshError
from affordgrasp.pipeline import evaluate_inputs

SERVES = {
    "hammer": ("beat",),
    "axe": ("beat",),
    "knife": ("cut",),
    "meat_cleaver": ("cut",),
    "dagger": ("cut",),
    "sword": ("cut",),
}
STATE = ("use_point", "use_normal", "wrist_point", "hand_pose", "joints", "p0", "use_dir")
HILT = {"handle", "guard", "pommel"}
WORKING = ["striking_face", "poll", "cutting_edge"]
FAMILIES = (
    "hammer axe knife meat_cleaver dagger sword screwdriver spatula bottle wine_glass tumbler "
    "mug ice_cream_cone"
).split()


def seeds_of(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def tried(obj, family: str, p0, use_dir, trials, args) -> pa.Table:
    """The pairs (p0, d) evaluated with the robust columns and tried in ``trials`` (and pick),
    with their state (a later protocol can be run on the same rows) and their family."""
    from affordgrasp.physics.run import validate_rows
    from affordgrasp.physics.settings import PhysicsSettings
    from affordgrasp.robust import RobustSettings

    robust = RobustSettings(copies=args.robust) if args.robust else None
    table = evaluate_inputs(
        obj,
        np.asarray(p0, dtype=float),
        np.asarray(use_dir, dtype=float),
        seed=args.seed,
        robust=robust,
    ).table
    settings = PhysicsSettings()
    out = validate_rows(table, "barrett", {obj.name: obj}, settings, trials=(*trials, "pick"))
    for c in STATE:
        if c not in out.column_names:
            out = out.append_column(c, table.column(c))
    return out.append_column("family", pa.array([family] * out.num_rows))


def object_rows(spec: str, args) -> pa.Table:
    import affordgrasp as ag
    from affordgrasp.search.use_points import UsePoints, passing_use_points

    family = spec.split(":")[0].split("~")[0]
    obj = ag.load_object(spec, materials=True)
    rng = np.random.default_rng(zlib.crc32(spec.encode()))  # which rows and use points
    rows = ag.evaluate(obj, samples=args.samples, seed=args.seed).table
    eps = rows.column("epsilon").to_numpy(zero_copy_only=False)
    parts = rows.column("contact_parts").to_pylist()
    on_hilt = np.array([bool(p) and set(p) <= HILT for p in parts])
    # half the grasps held by the hilt alone (where a person holds a tool), half any
    # force-closure grasp, and a tenth as many that are not force closure
    hilt = rng.permutation(np.flatnonzero((eps > 0) & on_hilt))[: args.grasps // 2]
    fc = np.setdiff1d(np.flatnonzero(eps > 0), hilt)
    fc = rng.permutation(fc)[: args.grasps - len(hilt)]
    other = rng.permutation(np.flatnonzero(~(eps > 0)))[: max(1, (len(hilt) + len(fc)) // 10)]
    keep = np.sort(np.concatenate([hilt, fc, other]))
    p0 = np.asarray(rows.column("p0").to_pylist(), dtype=float).reshape(-1, 6)[keep]
    tasks = SERVES.get(family, ())
    pairs_p0, pairs_d = [], []
    uniform = UsePoints.sample(obj, 20 * max(len(keep), 50), args.seed + 2)
    labelled = np.flatnonzero(
        np.isin(np.asarray(obj.part_names)[np.asarray(obj.face_parts)[uniform.triangle]], WORKING)
        & (uniform.triangle >= 0)
    )
    for task in tasks:
        # a third each: use points that pass the rule tests of the use point alone, points on
        # the labelled working part (striking face, poll, cutting edge), points by area
        passing, _ = passing_use_points(obj, task, 4 * len(keep), args.seed + 1)
        sources = [passing.use_dir, uniform.use_dir[labelled], uniform.use_dir]
        sources = [src for src in sources if len(src)]
        for g in range(len(keep)):
            for k in range(args.uses):
                src = sources[k % len(sources)]
                pairs_p0.append(p0[g])
                pairs_d.append(src[rng.integers(len(src))])
    if not tasks:
        pairs_p0, pairs_d = list(p0), list(uniform.use_dir[: len(keep)])
    return tried(obj, family, pairs_p0, pairs_d, tasks, args)


def search_rows(spec: str, args) -> pa.Table:
    """The top ``--grasps`` distinct grasps of the search for the family's task (the shipped
    task probabilities rank them), tried: the rows a search proposes, where a model fitted
    on sampled rows alone is most often wrong (it is maximised over them)."""
    import affordgrasp as ag
    from affordgrasp.search.pairs import PairSearchSettings, best_pairs

    family = spec.split(":")[0].split("~")[0]
    (task,) = SERVES[family]
    obj = ag.load_object(spec, materials=True)
    settings = PairSearchSettings(
        task, grasps=args.samples, uses=1000, top=args.grasps, per_grasp=True, seed=args.seed
    )
    found = best_pairs(obj, settings).table
    p0, d = found.column("p0").to_pylist(), found.column("use_dir").to_pylist()
    return tried(obj, family, p0, d, (task,), args)


def other_rows(table: pa.Table, args) -> pa.Table:
    """Up to ``--other-trials`` of an object's rows tried in the trials of the tasks its
    family does not serve (a hammer's cut, a blade's beat, both on the other families):
    the negatives, and the surprises, that a model fitted on a task's own tools never sees."""
    import affordgrasp as ag

    family = table.column("family")[0].as_py()
    trials = tuple(t for t in ("beat", "cut") if t not in SERVES.get(family, ()))
    spec = table.column("object")[0].as_py()
    rng = np.random.default_rng(zlib.crc32(f"other {spec}".encode()))
    rows = table.take(np.sort(rng.permutation(table.num_rows)[: args.other_trials]))
    p0, d = rows.column("p0").to_pylist(), rows.column("use_dir").to_pylist()
    return tried(ag.load_object(spec, materials=True), family, p0, d, trials, args)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    p.add_argument("--seeds", default="20-27")
    p.add_argument("--families", default=",".join(FAMILIES))
    p.add_argument("--samples", type=int, default=1500)
    p.add_argument("--grasps", type=int, default=60)
    p.add_argument("--uses", type=int, default=4)
    p.add_argument("--robust", type=int, default=25)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-scan", action="store_true")
    p.add_argument(
        "--from-search",
        action="store_true",
        help="the top --grasps grasps of the pair search ranked by the shipped models "
        "(--samples grasps × 1000 use points) instead of sampled pairs",
    )
    p.add_argument(
        "--other-trials",
        type=int,
        default=0,
        metavar="N",
        help="also try N of each object's rows in the trials of the tasks its family does "
        "not serve, written to OUT/other/",
    )
    args = p.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    specs = []
    for s in seeds_of(args.seeds):
        for fam in args.families.split(","):
            specs.append(f"{fam}:{s}")
            if not args.no_scan:
                specs.append(f"{fam}:{s}~scan")
    for spec in specs:
        path = out / (spec.replace(":", "_").replace("~", "-") + ".parquet")
        if path.exists():
            continue
        t0 = time.process_time()
        try:
            table = search_rows(spec, args) if args.from_search else object_rows(spec, args)
        except MeshError as exc:  # a variant that cannot be built is skipped, and said
            print(f"{spec}: skipped ({exc})", flush=True)
            continue
        if args.other_trials and not args.from_search:
            other = out / "other" / path.name
            other.parent.mkdir(exist_ok=True)
            pq.write_table(other_rows(table, args), other.with_suffix(".tmp"))
            other.with_suffix(".tmp").replace(other)
        tmp = path.with_suffix(".tmp")
        pq.write_table(table, tmp)
        tmp.replace(path)
        print(f"{spec}: {table.num_rows} rows, {time.process_time() - t0:.1f} s CPU", flush=True)


if __name__ == "__main__":
    main()
