"""Physics validation of a generated dataset: sharded, resumable, parallel.

Plan (a pure function of the dataset and the options): the dataset's rows with a validated
status (``grasped`` by default), objects in dataset order, samples in order, optionally the
first ``max_per_object`` of each object, cut into shards of ``shard_size`` rows. Shard *k*
is ``part-{k:05d}.parquet`` in the output directory, written atomically (temporary file,
fsync, rename) by the calling process when its rows come back; a run skips every shard
already there with the planned row count. ``_physics.json`` records the plan and the
settings; a run against a directory with another plan refuses and says what differs.

The shards run on the engines that generate uses (:mod:`affordgrasp.runtime.engines`: this
process, local worker processes or Ray, every core by default), with the same stopping
behaviour: the caller resolves each object once (:meth:`~affordgrasp.dataset.handle.Dataset.object`)
and decomposes it, and the workers get its mesh, mass properties and convex parts in the
run's :class:`ReplayContext`.
"""

from __future__ import annotations

import json
import logging
import os
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from .._version import __version__
from ..columns import METRIC_COLUMNS
from ..dataset.handle import Dataset
from ..errors import DatasetError, InputError, bad_parameter
from ..hands.model import Hand
from ..robust import RobustSettings, robust_column_names, robust_settings
from ..runtime.writing import atomic_write
from .settings import TRIALS, PhysicsSettings, TrialSettings

log = logging.getLogger(__name__)

__all__ = ["REPORTED_METRICS", "PhysicsSummary", "read_outcomes", "run_physics"]

FORMAT = "affordgrasp-physics"
FORMAT_VERSION = 2  # 2: start, settled and protocol columns
MANIFEST = "_physics.json"
DEFAULT_SHARD_SIZE = 128

KEY_COLUMNS = ("object", "object_hash", "sample", "seed", "status")
# The grasp state, read to replay it (and, for ``robust``, to re-evaluate it), not written.
STATE_COLUMNS = ("hand_pose", "joints", "use_point", "use_normal", "wrist_point", "p0", "use_dir")
# The dataset's numeric metric columns (not the text epsilon_reason) and the contact count,
# carried into the outcome table for the report.
REPORTED_METRICS = (*(c for c in METRIC_COLUMNS if c != "epsilon_reason"), "n_contacts")


@dataclass
class PhysicsSummary:
    """What a call to :func:`run_physics` did.

    Attributes
    ----------
    directory : str
    rows : int
        Rows planned.
    shards_written, shards_skipped : int
        Written by this call, already there.
    rows_written : int
    elapsed_s : float
        Wall time, s.
    workers : int
    robust : dict or None
        With ``robust``: ``{"copies": K, "source": "dataset"}`` (the dataset's columns) or
        ``"computed"`` (for the replayed rows); None without.
    trials : dict
        With ``trials``: per trial and object, ``[passed, rows with an outcome]``.
    """

    directory: str
    rows: int
    shards_written: int
    shards_skipped: int
    rows_written: int
    elapsed_s: float
    workers: int
    steps: int = 0
    busy_s: float = 0.0  # seconds the workers spent validating (sum over workers)
    cpu_s: float = 0.0  # CPU seconds the workers spent validating (fair on a shared machine)
    hold_ok: dict = field(default_factory=dict)  # object -> [held, validated]
    # The task trials run: {trial: {object: [passed, with a use point]}} (pick: hold_ok).
    trials: dict = field(default_factory=dict)
    # The robust columns reported: None, or {"copies": K, "source": "dataset" | "computed"}.
    robust: dict | None = None

    @property
    def validations_per_s(self) -> float:
        """Rows validated per second of wall time (0 when no time passed)."""
        return self.rows_written / self.elapsed_s if self.elapsed_s > 0 else 0.0

    @property
    def validations_per_core_hour(self) -> float:
        """Validations per hour of one worker's CPU time."""
        return 3600.0 * self.rows_written / self.cpu_s if self.cpu_s > 0 else 0.0

    def to_dict(self) -> dict:
        """The summary as JSON-ready data (``physics --json``).

        Returns
        -------
        dict
            Every attribute (the worker times as ``worker_wall_s`` and ``worker_cpu_s``) plus
            ``validations_per_s`` and ``validations_per_core_hour``.
        """
        return {
            "directory": self.directory,
            "rows": self.rows,
            "shards_written": self.shards_written,
            "shards_skipped": self.shards_skipped,
            "rows_written": self.rows_written,
            "elapsed_s": self.elapsed_s,
            "workers": self.workers,
            "steps": self.steps,
            "validations_per_s": self.validations_per_s,
            "validations_per_core_hour": self.validations_per_core_hour,
            "worker_wall_s": self.busy_s,
            "worker_cpu_s": self.cpu_s,
            "hold_ok": self.hold_ok,
            "trials": self.trials,
            "robust": self.robust,
        }


def _plan_rows(dataset, statuses, objects, max_per_object) -> pa.Table:
    if not dataset.metrics:
        raise DatasetError(
            f"dataset {str(dataset.directory)!r} was generated with --no-metrics; the physics "
            "report compares metrics with outcomes: generate it with metrics"
        )
    chosen = dataset.select(objects)
    # Robust metrics (``robust_*``) travel to the report when the dataset has them.
    robust = [c for c in dataset.arrow().schema.names if c.startswith("robust_")]
    columns = [*KEY_COLUMNS, *STATE_COLUMNS, *REPORTED_METRICS, *robust]
    table = dataset.read(columns=columns, objects=chosen)
    status = np.asarray(table.column("status").to_pylist(), dtype=object)
    keep = np.isin(status, list(statuses))
    order_of = {name: e["index"] for name, e in dataset.entries.items()}
    obj_index = np.array([order_of[n] for n in table.column("object").to_pylist()], dtype=np.int64)
    sample = table.column("sample").to_numpy()
    idx = np.flatnonzero(keep)
    idx = idx[np.lexsort((sample[idx], obj_index[idx]))]
    if max_per_object is not None:
        picked: list[int] = []
        counts: dict[int, int] = {}
        for i in idx:
            o = int(obj_index[i])
            if counts.get(o, 0) < max_per_object:
                counts[o] = counts.get(o, 0) + 1
                picked.append(int(i))
        idx = np.array(picked, dtype=np.int64)
    return table.take(pa.array(idx, type=pa.int64()))


def _plan_manifest(dataset, settings, statuses, objects, max_per_object, n, size):
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "affordgrasp_version": __version__,
        "dataset": str(dataset.directory.resolve()),
        "dataset_seed": dataset.seed,
        "hand": dataset.manifest["hand"],
        "objects": [
            {"name": o["name"], "mesh_hash": o["mesh_hash"], "source": o["source"]}
            for o in dataset.entries.values()
        ],
        "statuses": list(statuses),
        "object_filter": list(objects) if objects else None,
        "max_per_object": max_per_object,
        "rows": n,
        "shard_size": size,
        "settings": settings.to_dict(),
        "settings_digest": settings.digest(),
    }


_PLAN_KEYS = (
    "format",
    "dataset",
    "dataset_seed",
    "hand",
    "objects",
    "statuses",
    "object_filter",
    "max_per_object",
    "rows",
    "shard_size",
    "settings_digest",
    "robust",
    "trials",
)


def _prepare_out(out: Path, plan: dict) -> None:
    path = out / MANIFEST
    if path.is_file():
        existing = json.loads(path.read_text())
        diffs = [
            f"{k} {existing.get(k)!r} there vs {plan.get(k)!r} here"
            for k in _PLAN_KEYS
            if existing.get(k) != plan.get(k)
        ]
        if diffs:
            raise DatasetError(
                f"{str(out)!r} holds a physics run with another plan ({'; '.join(diffs)}); "
                "use another --out directory or the same options"
            )
        return
    if out.exists() and any(out.iterdir()):
        raise DatasetError(
            f"{str(out)!r} is not empty and holds no physics run; give a new or empty directory"
        )
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(path, json.dumps(plan, indent=2).encode())


def shard_path(out: Path, k: int) -> Path:
    """The file of shard ``k`` of a physics run.

    Parameters
    ----------
    out : pathlib.Path
        The run's directory.
    k : int

    Returns
    -------
    pathlib.Path
    """
    return out / f"part-{k:05d}.parquet"


def _shard_done(path: Path, rows: int) -> bool:
    try:
        return pq.ParquetFile(path).metadata.num_rows == rows
    except (OSError, pa.ArrowInvalid):
        return False


def run_physics(
    dataset: str | os.PathLike | Dataset,
    out: str | os.PathLike,
    *,
    settings: PhysicsSettings | None = None,
    workers: int | None = None,
    engine: str = "local",
    address: str | None = None,
    shard_size: int = DEFAULT_SHARD_SIZE,
    objects: Sequence[str] | None = None,
    statuses: Sequence[str] = ("grasped",),
    max_per_object: int | None = None,
    progress: Callable | None = None,
    log_message: Callable[[str], None] | None = None,
    robust: RobustSettings | int | None = None,
    trials: Sequence[str] = (),
    trial_settings: TrialSettings | None = None,
) -> PhysicsSummary:
    """Validate the grasps of a dataset in MuJoCo; write the outcomes as Parquet shards.

    Parameters
    ----------
    dataset : path or Dataset
        A dataset written by ``affordgrasp generate``: its rows are replayed with its hand
        on its objects (:meth:`~affordgrasp.dataset.handle.Dataset.object`, mass properties
        included: a dataset made with ``--materials`` is replayed with them).
    out : path
        The output directory (a finished shard is skipped when run again).
    settings : PhysicsSettings, optional
        The protocol; the defaults when None.
    workers : int, optional
        Processes (local) or CPUs (local Ray); default every core; 1 runs in this process
        (as for :func:`affordgrasp.generate`).
    engine : {"local", "ray"}
        Where the shards run.
    address : str, optional
        An existing Ray cluster (with ``engine="ray"``).
    shard_size : int
        Rows per shard.
    objects : sequence of str, optional
        Objects to validate; all when None.
    statuses : sequence of str
        Grasp statuses validated.
    max_per_object : int, optional
        Validate the first rows of each object only.
    progress : callable, optional
        ``progress(total)`` is a context manager yielding ``advance(n)``.
    log_message : callable, optional
        Receives one-line messages.
    robust : RobustSettings or int, optional
        Report the robust scores (:mod:`affordgrasp.robust`) of the replayed rows beside
        their outcomes: a dataset generated with the same K keeps its ``robust_*`` columns;
        a dataset without robust columns has them computed for the replayed rows (from each
        row's stored pregrasp, K perturbed copies, the dataset's hand and contact model).
        None or 0: the dataset's ``robust_*`` columns travel when it has them, nothing is
        computed.
    trials : sequence of str
        Task trials to run besides the hold, impact and press tests, among ``"beat"``,
        ``"cut"``, ``"pick"`` (:mod:`~affordgrasp.physics.task_trials`); their protocol cards
        go into the run's manifest. Rows without a use point get null beat and cut columns.
    trial_settings : TrialSettings, optional
        The task trials' protocol; the defaults when None.

    Returns
    -------
    PhysicsSummary

    Raises
    ------
    InputError
        For a dataset whose robust columns are of another K.

    Notes
    -----
    A KeyboardInterrupt (or SIGTERM) stops the workers and keeps every whole shard; calling
    again resumes. Local workers are started with 'spawn': a script calling this with
    ``workers > 1`` needs the ``if __name__ == "__main__":`` guard.
    """
    from ..runtime.engines import check_engine, default_workers

    settings = settings or PhysicsSettings()
    if shard_size <= 0:
        raise bad_parameter("shard_size", f"must be a positive integer, got {shard_size}")
    if max_per_object is not None and max_per_object <= 0:
        raise bad_parameter("max_per_object", f"must be a positive integer, got {max_per_object}")
    if workers is not None and (isinstance(workers, bool) or workers <= 0):
        raise bad_parameter("workers", f"must be a positive integer, got {workers}")
    check_engine(engine, workers, address)
    trials = check_trials(trials)
    trial_settings = trial_settings or TrialSettings()
    out = Path(out)
    dataset = Dataset.open(dataset)
    rows = _plan_rows(dataset, statuses, objects, max_per_object)
    n = rows.num_rows
    if n == 0:
        raise DatasetError(
            f"dataset {str(dataset.directory)!r} has no rows with status {', '.join(statuses)} to "
            "validate; generate more samples or choose other objects"
        )
    plan = _plan_manifest(dataset, settings, statuses, objects, max_per_object, n, shard_size)
    compute = _robust_plan(dataset, robust_settings(robust))
    plan["robust"] = None if compute is None else {"source": "computed", **compute.to_dict()}
    plan["trials"] = None
    if trials:
        from .task_trials import protocol_cards

        plan["trials"] = protocol_cards(trial_settings, trials)
    _prepare_out(out, plan)
    hand = dataset.hand  # the dataset's own hand, custom ones included
    for stale in out.glob(".part-*.tmp-*"):
        stale.unlink(missing_ok=True)
    shards = [(k, s, min(s + shard_size, n)) for k, s in enumerate(range(0, n, shard_size))]
    pending = [sh for sh in shards if not _shard_done(shard_path(out, sh[0]), sh[2] - sh[1])]
    needed = {
        name
        for _, s, e in pending
        for name in set(rows.column("object").slice(s, e - s).to_pylist())
    }
    # Resolve and decompose each object once, here: the workers get its mesh, mass
    # properties and convex parts (as generate's get its mesh), never its files or caches.
    from ..dataset.jobs import ObjectPayload

    payloads, parts = {}, {}
    for name in [o for o in dataset.objects if o in needed]:
        if log_message:
            log_message(f"convex decomposition of {name} (cached after the first run)")
        obj = dataset.object(name)
        parts[name] = convex_parts_of(obj, settings)
        payloads[name] = ObjectPayload.from_object(obj)
    context = ReplayContext(
        hand=hand,
        objects=payloads,
        parts=parts,
        settings=settings,
        robust=compute,
        soft=dataset.soft,
        trials=trials,
        trial_settings=trial_settings,
    )
    jobs = [ReplayJob(k, rows.slice(s, e - s)) for k, s, e in pending]
    started = time.perf_counter()
    summary = PhysicsSummary(
        str(out), n, 0, len(shards) - len(pending), 0, 0.0, workers or default_workers()
    )
    total = sum(e - s for _, s, e in pending)
    if jobs:
        with progress(total) if progress else _null_progress() as advance:
            _run_jobs(context, jobs, out, summary, advance, engine, workers, address)
    summary.elapsed_s = time.perf_counter() - started
    summary.hold_ok = _hold_counts(out, len(shards))
    summary.trials = _trial_counts(out, len(shards), trials)
    wanted = robust_settings(robust)
    if wanted is not None:
        summary.robust = {
            "copies": wanted.copies,
            "source": "dataset" if compute is None else "computed",
        }
    return summary


def _run_jobs(context, jobs, out: Path, summary, advance, engine, workers, address) -> None:
    """Run the shards' jobs on an engine; write each shard as its rows come back."""
    from ..runtime.engines import make_engine
    from ..runtime.interrupts import stop_on_signals

    with (
        stop_on_signals(),
        make_engine(context, engine=engine, workers=workers, address=address) as eng,
    ):
        summary.workers = eng.workers
        depth = 1 if eng.workers == 1 and eng.name == "local" else 2 * eng.workers
        waiting = iter(jobs)
        in_flight: dict = {}
        while True:
            while len(in_flight) < depth:
                job = next(waiting, None)
                if job is None:
                    break
                in_flight[eng.submit(job)] = job
            if not in_flight:
                return
            for handle in eng.wait(list(in_flight)):
                job = in_flight.pop(handle)
                result = eng.result(handle)
                write_outcome_shard(out, job.shard, result["table"], context.settings)
                _account(summary, result, advance)


@dataclass(frozen=True)
class ReplayJob:
    """The rows of one shard of a physics run.

    Attributes
    ----------
    shard : int
        Shard index.
    rows : pyarrow.Table
        Dataset rows (:data:`KEY_COLUMNS`, :data:`STATE_COLUMNS`, the metrics).
    """

    shard: int
    rows: pa.Table


@dataclass(frozen=True)
class ReplayContext:
    """What every shard of a physics run shares (sent once to each worker).

    Attributes
    ----------
    hand : Hand
        The dataset's hand, itself (custom hands included).
    objects : dict of str to ObjectPayload
        The objects as the dataset resolves them: mesh and mass properties.
    parts : dict of str to list of (vertices, faces)
        Their convex parts, so that no worker decomposes.
    settings : PhysicsSettings
    robust : RobustSettings or None
        Robust columns to compute for the replayed rows (``--robust K`` on a dataset
        without them; :func:`robust_of_rows`); None: none computed.
    soft : bool
        The dataset's contact model (for ``robust``).
    trials : tuple of str
        The task trials to run (:func:`run_physics`).
    trial_settings : TrialSettings or None
        Their protocol.
    key : str
        Identifies the run.
    """

    hand: Hand
    objects: dict
    parts: dict
    settings: PhysicsSettings
    robust: RobustSettings | None = None
    soft: bool = False
    trials: tuple = ()
    trial_settings: TrialSettings | None = None
    key: str = field(default_factory=lambda: uuid.uuid4().hex)

    def run(self, job: ReplayJob) -> dict:
        """Replay one shard's rows (in whichever process the engine runs it).

        Parameters
        ----------
        job : ReplayJob

        Returns
        -------
        dict
            ``table`` (the outcome table), ``rows``, simulation ``steps``, wall
            ``seconds`` and ``cpu_seconds``.
        """
        started, cpu = time.perf_counter(), time.process_time()
        table = validate_rows(
            job.rows,
            self.hand,
            self.objects,
            self.settings,
            self.robust,
            self.soft,
            parts=self.parts,
            trials=self.trials,
            trial_settings=self.trial_settings,
        )
        seconds, cpu = time.perf_counter() - started, time.process_time() - cpu
        steps = int(np.sum(table.column("steps").to_numpy())) if table.num_rows else 0
        return {
            "table": table,
            "rows": table.num_rows,
            "steps": steps,
            "seconds": seconds,
            "cpu_seconds": cpu,
        }


class _null_progress:
    def __enter__(self):
        return lambda n=1: None

    def __exit__(self, *exc):
        return False


def _account(summary: PhysicsSummary, result: dict, advance) -> None:
    summary.shards_written += 1
    summary.rows_written += result["rows"]
    summary.steps += result["steps"]
    summary.busy_s += result["seconds"]
    summary.cpu_s += result["cpu_seconds"]
    advance(result["rows"])


def convex_parts_of(obj, settings: PhysicsSettings) -> list:
    """The convex parts an object collides as (cached on disk per mesh and settings).

    Parameters
    ----------
    obj : GraspObject
    settings : PhysicsSettings

    Returns
    -------
    list of (vertices, faces)
    """
    from .decompose import convex_parts

    return convex_parts(obj.mesh, obj.mesh_hash, settings)


# Per process: compiled scenes by (hand, object, mass, settings). A scene compiles in tens
# of ms; a shard replays hundreds of rows on it.
_SCENES: dict[tuple, object] = {}


def _scene(hand: Hand, hand_key: str, obj, settings: PhysicsSettings, parts=None):
    """The compiled scene of a hand and an object, one per process."""
    from .scene import build_scene

    mass = obj.mass  # None only for a payload of a uniform-density object
    key = (
        hand_key,
        obj.name,
        obj.mesh_hash,
        bool(obj.materials),
        None if mass is None else (float(mass.mass), tuple(np.round(mass.center_of_mass, 12))),
        settings,
    )
    scene = _SCENES.get(key)
    if scene is None:
        if not hasattr(obj, "mesh"):  # an ObjectPayload: the object as the caller resolved it
            obj = obj.build()
        if parts is None:
            parts = convex_parts_of(obj, settings)
        scene = build_scene(hand, obj, settings, parts=parts)
        _SCENES[key] = scene
    return scene


def _robust_plan(dataset: Dataset, robust: RobustSettings | None):
    """The robust settings to compute for the replayed rows, or None (read or none wanted).

    A dataset generated with ``--robust K`` already holds the columns of K copies: asking
    for K reads them, another K is refused (its columns would not be the ones asked for).
    """
    if robust is None:
        return None
    there = dataset.robust
    if there is None:
        return robust
    if there.copies != robust.copies:
        raise InputError(
            f"--robust {robust.copies}: the dataset in {str(dataset.directory)!r} has robust "
            f"columns of K = {there.copies} copies; pass --robust {there.copies} (they are "
            "read) or replay a dataset without robust columns (they are computed)"
        )
    return None


def robust_of_rows(
    rows: pa.Table,
    hand: Hand | str,
    objects: dict,
    robust: RobustSettings | int,
    soft: bool = False,
) -> dict[str, np.ndarray]:
    """The robust columns of dataset rows, re-evaluated from their stored pregrasps.

    Each object's rows are simulated again from ``p0`` and ``use_dir`` with K perturbed
    copies (:func:`affordgrasp.pipeline.evaluate_inputs`); the copies depend on (seed, k)
    only, so the values equal those a ``generate --robust K`` run writes for the same rows.

    Parameters
    ----------
    rows : pyarrow.Table
        Dataset rows with ``object``, ``p0``, ``use_dir`` and ``hand_pose``.
    hand : Hand or str
        The dataset's hand.
    objects : dict of str to GraspObject or ObjectPayload
        The object of every name in ``rows``, as the dataset resolves it
        (:meth:`~affordgrasp.dataset.handle.Dataset.object`).
    robust : RobustSettings or int
        K >= 1 and the perturbations (an int: K with the default perturbations).
    soft : bool
        The dataset's contact model (soft-finger contacts).

    Returns
    -------
    dict of str to (n,) float64 ndarray
        :func:`affordgrasp.robust.robust_column_names` of the settings' tasks, in row order.

    Raises
    ------
    DatasetError
        When a row's grasp does not come out of its pregrasp again (the dataset was made by
        another version of the simulator), so its robust scores would describe another grasp.
    """
    from ..hands import get_hand
    from ..pipeline import evaluate_inputs

    wanted = robust_settings(robust)
    if wanted is None:
        raise InputError("robust scores need K >= 1 copies per grasp, got K = 0")
    hand = get_hand(hand)
    names = np.asarray(rows.column("object").to_pylist(), dtype=object)
    out = {c: np.full(len(names), np.nan) for c in robust_column_names(wanted.tasks)}
    for name in dict.fromkeys(names.tolist()):
        idx = np.flatnonzero(names == name)
        sub = rows.take(pa.array(idx, type=pa.int64()))
        p0 = np.asarray(sub.column("p0").to_pylist(), dtype=np.float64).reshape(-1, 6)
        use_dir = np.asarray(sub.column("use_dir").to_pylist(), dtype=np.float64)
        obj = objects[name]
        if not hasattr(obj, "mesh"):  # an ObjectPayload: the object as the caller resolved it
            obj = obj.build()
        table = evaluate_inputs(
            obj, p0, use_dir.reshape(len(idx), -1), hand=hand, soft=soft, robust=wanted
        ).table
        again = np.asarray(table.column("hand_pose").to_pylist(), dtype=np.float64)
        stored = np.asarray(sub.column("hand_pose").to_pylist(), dtype=np.float64)
        if again.shape != stored.shape or not np.allclose(again, stored, rtol=0, atol=1e-9):
            raise DatasetError(
                f"rows of {name!r} do not simulate to their stored grasp again (the dataset "
                "was made by another version of the grasp simulator), so robust scores "
                "computed now would describe other grasps; regenerate it with --robust K"
            )
        for c in out:
            out[c][idx] = table.column(c).to_numpy(zero_copy_only=False)
    return out


def validate_rows(
    rows: pa.Table,
    hand: Hand | str,
    objects: dict,
    settings,
    robust: RobustSettings | None = None,
    soft: bool = False,
    *,
    parts: dict | None = None,
    trials: Sequence[str] = (),
    trial_settings: TrialSettings | None = None,
) -> pa.Table:
    """The outcome table of some dataset rows (their key and metric columns + outcomes).

    Parameters
    ----------
    rows : pyarrow.Table
        Dataset rows.
    hand : Hand or str
        The hand the dataset was generated with
        (:func:`affordgrasp.dataset.reading.dataset_hand`), or a registered name.
    objects : dict of str to GraspObject or ObjectPayload
        The object of every name in ``rows``, as the dataset resolves it
        (:meth:`~affordgrasp.dataset.handle.Dataset.object`).
    settings : PhysicsSettings
    robust : RobustSettings, optional
        Also compute the rows' robust columns (:func:`robust_of_rows`) and add them.
    soft : bool
        The dataset's contact model (for ``robust``).
    parts : dict of str to list, optional
        Convex parts of the objects by name; default: decomposed (or read from the cache).
    trials : sequence of str
        Task trials to run as well (:func:`run_physics`); their columns follow the outcomes.
    trial_settings : TrialSettings, optional
        Their protocol; the defaults when None.

    Returns
    -------
    pyarrow.Table
    """
    from ..hands import get_hand, hand_to_dict
    from .trials import validate_grasp

    hand = get_hand(hand)
    hand_key = json.dumps(hand_to_dict(hand), sort_keys=True)
    names = rows.column("object").to_pylist()
    poses = rows.column("hand_pose").to_pylist()
    joints = rows.column("joints").to_pylist()
    ups = rows.column("use_point").to_pylist()
    uns = rows.column("use_normal").to_pylist()
    trials = check_trials(trials)
    tasks = _TaskRows(rows, hand, hand_key, objects, settings, trials, trial_settings, parts)
    outcomes = []
    for i in range(rows.num_rows):
        scene = _scene(hand, hand_key, objects[names[i]], settings, (parts or {}).get(names[i]))
        up = np.array(ups[i] if ups[i] is not None else [np.nan] * 3, dtype=np.float64)
        un = np.array(uns[i] if uns[i] is not None else [np.nan] * 3, dtype=np.float64)
        pose, q = np.array(poses[i]).reshape(4, 4), np.array(joints[i])
        if trials:
            outcome, row = tasks.row(i, scene, pose, q, up, un)
        else:
            outcome, row = validate_grasp(scene, pose, q, up, un), {}
        outcomes.append(outcome.to_row() | row)
    keep = [c for c in rows.column_names if c not in STATE_COLUMNS]
    table = rows.select(keep)
    for name in outcomes[0] if outcomes else ():
        values = [o[name] for o in outcomes]
        table = table.append_column(name, pa.array(values, type=_outcome_type(name)))
    if robust is not None and robust.enabled:
        scores = robust_of_rows(rows, hand, objects, robust, soft)
        for name, column in scores.items():
            if name in table.column_names:
                table = table.drop_columns([name])
            table = table.append_column(name, pa.array(column, type=pa.float64()))
    return table.append_column("protocol", pa.array([settings.protocol] * table.num_rows))


def check_trials(trials: Sequence[str]) -> tuple[str, ...]:
    """The task trials asked for, checked, in their columns' order.

    Parameters
    ----------
    trials : sequence of str
        Among ``"beat"``, ``"cut"``, ``"pick"``.

    Returns
    -------
    tuple of str

    Raises
    ------
    InputError
        For an unknown name.
    """
    unknown = sorted(set(trials) - set(TRIALS))
    if unknown:
        raise InputError(
            f"unknown task trial(s) {', '.join(unknown)}; choose among {', '.join(TRIALS)}"
        )
    return tuple(t for t in TRIALS if t in set(trials))


# Per process: the task trials' scenes, as _SCENES (one more compiled model per object).
_TASK_SCENES: dict[tuple, object] = {}


class _TaskRows:
    """The task trials of some dataset rows: their scenes and each row's edge at U."""

    def __init__(self, rows, hand, hand_key, objects, settings, trials, trial_settings, parts):
        self.names = rows.column("object").to_pylist()
        self.trials, self.trial_settings = trials, trial_settings or TrialSettings()
        self.hand, self.hand_key, self.objects = hand, hand_key, objects
        self.settings, self.parts = settings, parts or {}
        self.wrist = (
            np.array(
                [
                    w if w is not None else [np.nan] * 3
                    for w in rows.column("wrist_point").to_pylist()
                ],
                dtype=np.float64,
            ).reshape(-1, 3)
            if trials
            else None
        )
        self.edges: dict[int, tuple] = {}
        if "cut" in trials:
            self._edge_frames(rows)

    def _object(self, name: str):
        obj = self.objects[name]
        return obj.build() if not hasattr(obj, "mesh") else obj

    def _edge_frames(self, rows) -> None:
        """The edge's outward direction and direction at each row's U (one cast per object)."""
        from ..metrics.wedge import use_edge_frame

        names = np.asarray(self.names, dtype=object)
        up = np.array(
            [u if u is not None else [np.nan] * 3 for u in rows.column("use_point").to_pylist()],
            dtype=np.float64,
        ).reshape(-1, 3)
        un = np.array(
            [u if u is not None else [np.nan] * 3 for u in rows.column("use_normal").to_pylist()],
            dtype=np.float64,
        ).reshape(-1, 3)
        ok = np.isfinite(up).all(axis=1) & np.isfinite(un).all(axis=1)
        for name in dict.fromkeys(self.names):
            idx = np.flatnonzero((names == name) & ok)
            if len(idx) == 0:
                continue
            mesh = self._object(name).mesh
            t = self.trial_settings
            outward, along = use_edge_frame(
                mesh, up[idx], un[idx], radius=t.edge_radius_m, directions=t.edge_directions
            )
            for k, i in enumerate(idx):
                self.edges[int(i)] = (outward[k], along[k])

    def _scene(self, name: str):
        from .task_scene import build_task_scene

        obj = self.objects[name]
        mass = obj.mass
        key = (
            self.hand_key,
            obj.name,
            obj.mesh_hash,
            bool(obj.materials),
            None if mass is None else (float(mass.mass), tuple(np.round(mass.center_of_mass, 12))),
            self.settings,
            self.trial_settings,
        )
        ts = _TASK_SCENES.get(key)
        if ts is None:
            obj = self._object(name)
            parts = self.parts.get(name)
            if parts is None:
                parts = convex_parts_of(obj, self.settings)
            ts = build_task_scene(self.hand, obj, self.settings, self.trial_settings, parts=parts)
            _TASK_SCENES[key] = ts
        return ts

    def row(self, i: int, scene, pose, joints, use_point, use_normal):
        """Row ``i`` validated on ``scene`` and tried: (its GraspOutcome, the trials' columns)."""
        from .task_trials import run_task_trials, task_row

        grasp, outcome = run_task_trials(
            scene,
            self._scene(self.names[i]),
            pose,
            joints,
            self.trials,
            use_point,
            use_normal,
            self.wrist[i],
            self.edges.get(i),
        )
        return grasp, task_row(outcome, self.trials, grasp.hold_ok)


def _outcome_type(name: str) -> pa.DataType:
    if name in (
        "contacts",
        "hold_directions_ok",
        "steps",
        "distal_at_limit",
        "settled_contacts",
        "settled_hold_dirs",
    ):
        return pa.int64()
    if name in (
        "hold_ok",
        "settled",
        "impact_ok",
        "press_held",
        "ejected",
        "beat_ok",
        "cut_ok",
        "pick_ok",
    ):
        return pa.bool_()
    if name in ("settled_points", "settled_normals", "settled_mu"):
        return pa.list_(pa.float64())
    return pa.float64()


def write_outcome_shard(out, k: int, table: pa.Table, settings: PhysicsSettings) -> Path:
    """Write shard ``k``'s outcome table atomically (temporary file, fsync, rename).

    Parameters
    ----------
    out : path
        The run's directory.
    k : int
        Shard index.
    table : pyarrow.Table
        :func:`validate_rows`'s table.
    settings : PhysicsSettings
        Recorded in the file's metadata (their digest).

    Returns
    -------
    pathlib.Path
        The shard file.
    """
    path = shard_path(Path(out), k)
    meta = {
        b"affordgrasp_version": __version__.encode(),
        b"physics_settings": settings.digest().encode(),
    }
    table = table.replace_schema_metadata(meta)
    atomic_write(path, lambda fh: pq.write_table(table, fh))
    return path


def read_outcomes(out: str | os.PathLike) -> pa.Table:
    """Every shard of a physics run as one table (plan order).

    Parameters
    ----------
    out : path
        The run's directory.

    Returns
    -------
    pyarrow.Table
    """
    out = Path(out)
    if not (out / MANIFEST).is_file():
        raise DatasetError(
            f"{str(out)!r} is not a physics run (no {MANIFEST}); run 'affordgrasp physics' first"
        )
    paths = sorted(out.glob("part-*.parquet"))
    if not paths:
        raise DatasetError(f"physics run {str(out)!r} has no shards yet; run it again")
    table = pa.concat_tables([pq.read_table(p) for p in paths], promote_options="default")
    if "protocol" not in table.column_names:
        # Shards written before the column existed: the run's manifest names the protocol.
        settings = json.loads((out / MANIFEST).read_text()).get("settings", {})
        name = settings.get("protocol", "affordgrasp")
        table = table.append_column("protocol", pa.array([name] * table.num_rows, pa.string()))
    return table


def _trial_counts(out: Path, n_shards: int, trials: Sequence[str]) -> dict:
    """{trial: {object: [passed, rows with an outcome]}} over the run's shards."""
    counts: dict = {t: {} for t in trials}
    for k in range(n_shards):
        path = shard_path(out, k)
        if not path.is_file() or not trials:
            continue
        t = pq.read_table(path, columns=["object", *(f"{n}_ok" for n in trials)])
        names = t.column("object").to_pylist()
        for trial in trials:
            for name, ok in zip(names, t.column(f"{trial}_ok").to_pylist(), strict=True):
                if ok is None:
                    continue
                c = counts[trial].setdefault(name, [0, 0])
                c[0] += bool(ok)
                c[1] += 1
    return counts


def _hold_counts(out: Path, n_shards: int) -> dict:
    counts: dict = {}
    for k in range(n_shards):
        path = shard_path(out, k)
        if not path.is_file():
            continue
        t = pq.read_table(path, columns=["object", "hold_ok"])
        names, held = t.column("object").to_pylist(), t.column("hold_ok").to_pylist()
        for name, ok in zip(names, held, strict=True):
            c = counts.setdefault(name, [0, 0])
            c[0] += bool(ok)
            c[1] += 1
    return counts
