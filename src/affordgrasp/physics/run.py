"""Physics validation of a generated dataset: sharded, resumable, parallel.

Plan (a pure function of the dataset and the options): the dataset's rows with a validated
status (``grasped`` by default), objects in dataset order, samples in order, optionally the
first ``max_per_object`` of each object, cut into shards of ``shard_size`` rows. Shard *k*
is ``part-{k:05d}.parquet`` in the output directory, written atomically (temporary file,
fsync, rename) by the worker that computed it; a run skips every shard already there with
the planned row count. ``_physics.json`` records the plan and the settings; a run against
a directory with another plan refuses and says what differs.
"""

from __future__ import annotations

import functools
import json
import logging
import multiprocessing
import os
import signal
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from .. import __version__
from ..columns import METRIC_COLUMNS
from ..errors import DatasetError, InputError, bad_parameter
from ..hands.model import Hand
from ..robust import RobustSettings, manifest_robust, robust_column_names, robust_settings
from ..worker_lifetime import die_with_parent
from ..writing import atomic_write
from .settings import PhysicsSettings

log = logging.getLogger(__name__)

__all__ = ["REPORTED_METRICS", "PhysicsSummary", "read_outcomes", "run_physics"]

FORMAT = "affordgrasp-physics"
FORMAT_VERSION = 2  # 2: start, settled and protocol columns
MANIFEST = "_physics.json"
DEFAULT_SHARD_SIZE = 128

KEY_COLUMNS = ("object", "object_hash", "sample", "seed", "status")
# The grasp state, read to replay it (and, for ``robust``, to re-evaluate it), not written.
STATE_COLUMNS = ("hand_pose", "joints", "use_point", "use_normal", "p0", "use_dir")
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
            "robust": self.robust,
        }


def _plan_rows(dataset_dir, statuses, objects, max_per_object) -> tuple[pa.Table, dict]:
    from ..dataset.layout import read_manifest
    from ..dataset.reading import read_dataset, select_objects

    manifest = read_manifest(dataset_dir)
    if not manifest.get("metrics", True):
        raise DatasetError(
            f"dataset {str(dataset_dir)!r} was generated with --no-metrics; the physics "
            "report compares metrics with outcomes: generate it with metrics"
        )
    from ..dataset.reading import open_dataset

    chosen = select_objects(dataset_dir, objects)
    # Robust metrics (``robust_*``) travel to the report when the dataset has them.
    robust = [c for c in open_dataset(dataset_dir).schema.names if c.startswith("robust_")]
    columns = [*KEY_COLUMNS, *STATE_COLUMNS, *REPORTED_METRICS, *robust]
    table = read_dataset(dataset_dir, columns=columns, objects=chosen)
    status = np.asarray(table.column("status").to_pylist(), dtype=object)
    keep = np.isin(status, list(statuses))
    order_of = {o["name"]: o["index"] for o in manifest["objects"]}
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
    return table.take(pa.array(idx, type=pa.int64())), manifest


def _plan_manifest(dataset_dir, manifest, settings, statuses, objects, max_per_object, n, size):
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "affordgrasp_version": __version__,
        "dataset": str(Path(dataset_dir).resolve()),
        "dataset_seed": manifest["seed"],
        "hand": manifest["hand"],
        "objects": [
            {"name": o["name"], "mesh_hash": o["mesh_hash"], "source": o["source"]}
            for o in manifest["objects"]
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
    dataset_dir: str | os.PathLike,
    out: str | os.PathLike,
    *,
    settings: PhysicsSettings | None = None,
    workers: int | None = 1,
    shard_size: int = DEFAULT_SHARD_SIZE,
    objects: Sequence[str] | None = None,
    statuses: Sequence[str] = ("grasped",),
    max_per_object: int | None = None,
    progress: Callable | None = None,
    log_message: Callable[[str], None] | None = None,
    robust: RobustSettings | int | None = None,
) -> PhysicsSummary:
    """Validate the grasps of a dataset in MuJoCo; write the outcomes as Parquet shards.

    Parameters
    ----------
    dataset_dir : path
        A dataset written by ``affordgrasp generate``.
    out : path
        The output directory (a finished shard is skipped when run again).
    settings : PhysicsSettings, optional
        The protocol; the defaults when None.
    workers : int, optional
        Processes.
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

    Returns
    -------
    PhysicsSummary

    Raises
    ------
    InputError
        For a dataset whose robust columns are of another K.
    """
    settings = settings or PhysicsSettings()
    if shard_size <= 0:
        raise bad_parameter("shard_size", f"must be a positive integer, got {shard_size}")
    if max_per_object is not None and max_per_object <= 0:
        raise bad_parameter("max_per_object", f"must be a positive integer, got {max_per_object}")
    workers = workers or len(os.sched_getaffinity(0))
    if workers <= 0:
        raise bad_parameter("workers", f"must be a positive integer, got {workers}")
    out = Path(out)
    rows, manifest = _plan_rows(dataset_dir, statuses, objects, max_per_object)
    n = rows.num_rows
    if n == 0:
        raise DatasetError(
            f"dataset {str(dataset_dir)!r} has no rows with status {', '.join(statuses)} to "
            "validate; generate more samples or choose other objects"
        )
    plan = _plan_manifest(
        dataset_dir, manifest, settings, statuses, objects, max_per_object, n, shard_size
    )
    compute = _robust_plan(dataset_dir, manifest, robust_settings(robust))
    plan["robust"] = None if compute is None else {"source": "computed", **compute.to_dict()}
    _prepare_out(out, plan)
    from ..dataset.reading import manifest_hand

    hand = manifest_hand(manifest)  # the dataset's own hand, custom ones included
    for stale in out.glob(".part-*.tmp-*"):
        stale.unlink(missing_ok=True)
    shards = [(k, s, min(s + shard_size, n)) for k, s in enumerate(range(0, n, shard_size))]
    pending = [sh for sh in shards if not _shard_done(shard_path(out, sh[0]), sh[2] - sh[1])]
    needed = {rows.column("object")[s].as_py() for _, s, _ in pending}
    entries = [o for o in plan["objects"] if o["name"] in needed]
    # Decompose each object once, here, so the workers read the cache.
    for entry in entries:
        if log_message:
            log_message(f"convex decomposition of {entry['name']} (cached after the first run)")
        _entry_object(entry, settings)
    started = time.perf_counter()
    summary = PhysicsSummary(str(out), n, 0, len(shards) - len(pending), 0, 0.0, workers)
    soft = bool(manifest.get("soft", False))
    jobs = [
        (str(out), k, rows.slice(s, e - s), hand, plan["objects"], settings, compute, soft)
        for k, s, e in pending
    ]
    total = sum(e - s for _, s, e in pending)
    with progress(total) if progress else _null_progress() as advance:
        if workers == 1 or len(jobs) <= 1:
            for job in jobs:
                _account(summary, validate_shard(*job), advance)
        else:
            ctx = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(
                max_workers=workers,
                mp_context=ctx,
                initializer=_worker_init,
                initargs=(os.getpid(),),
            ) as pool:
                try:
                    for result in pool.map(_validate_job, jobs):
                        _account(summary, result, advance)
                except BaseException:
                    _stop_workers(pool)
                    raise
    summary.elapsed_s = time.perf_counter() - started
    summary.hold_ok = _hold_counts(out, len(shards))
    wanted = robust_settings(robust)
    if wanted is not None:
        summary.robust = {
            "copies": wanted.copies,
            "source": "dataset" if compute is None else "computed",
        }
    return summary


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


def _worker_init(parent_pid: int) -> None:
    # Ctrl-C and a hangup reach the whole process group: the parent stops the workers (a
    # worker's own KeyboardInterrupt would only print its traceback). A parent killed
    # outright takes them along.
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)


def _stop_workers(pool) -> None:
    """Stop a pool at once: cancel what waits, terminate what runs (its shard is redone)."""
    processes = list(getattr(pool, "_processes", {}).values())  # the executor's own
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=5)
        if proc.is_alive():  # pragma: no cover - stuck in native code
            proc.kill()
            proc.join(timeout=5)


def _validate_job(job) -> dict:
    return validate_shard(*job)


@functools.cache
def _scene_object(name: str, source: str, mesh_hash: str, settings: PhysicsSettings):
    """The GraspObject of a manifest entry (checked against its hash) and its parts.

    Cached per process (the idiom of :mod:`affordgrasp.caching` for hashable values): the
    decomposition depends on the settings, so they are part of the key.
    """
    from ..objects import load_object
    from .decompose import convex_parts

    obj = load_object(name if source == "family" else source)
    if obj.mesh_hash != mesh_hash:
        raise DatasetError(
            f"object {name!r} resolves to another mesh than the dataset's "
            f"(hash {obj.mesh_hash[:12]} here vs {mesh_hash[:12]} there); "
            "validate on the machine and software version that generated it"
        )
    return obj, convex_parts(obj.mesh, obj.mesh_hash, settings)


def _entry_object(entry: dict, settings: PhysicsSettings):
    return _scene_object(entry["name"], entry["source"], entry["mesh_hash"], settings)


@functools.cache
def _scene(hand_spec: str, name: str, source: str, mesh_hash: str, settings: PhysicsSettings):
    """The compiled scene of a hand (its JSON document) and an object, one per process."""
    from ..hands import hand_from_dict
    from .scene import build_scene

    obj, parts = _scene_object(name, source, mesh_hash, settings)
    return build_scene(hand_from_dict(json.loads(hand_spec)), obj, settings, parts=parts)


def _robust_plan(dataset_dir, manifest: dict, robust: RobustSettings | None):
    """The robust settings to compute for the replayed rows, or None (read or none wanted).

    A dataset generated with ``--robust K`` already holds the columns of K copies: asking
    for K reads them, another K is refused (its columns would not be the ones asked for).
    """
    if robust is None:
        return None
    there = manifest_robust(manifest)
    if there is None:
        return robust
    if there.copies != robust.copies:
        raise InputError(
            f"--robust {robust.copies}: the dataset in {str(dataset_dir)!r} has robust "
            f"columns of K = {there.copies} copies; pass --robust {there.copies} (they are "
            "read) or replay a dataset without robust columns (they are computed)"
        )
    return None


def robust_of_rows(
    rows: pa.Table,
    hand: Hand | str,
    objects: list[dict],
    robust: RobustSettings | int,
    settings: PhysicsSettings | None = None,
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
    objects : list of dict
        The dataset manifest's object entries.
    robust : RobustSettings or int
        K >= 1 and the perturbations (an int: K with the default perturbations).
    settings : PhysicsSettings, optional
        Only to find the objects already loaded for the replay.
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
    settings = settings or PhysicsSettings()
    by_name = {o["name"]: o for o in objects}
    names = np.asarray(rows.column("object").to_pylist(), dtype=object)
    out = {c: np.full(len(names), np.nan) for c in robust_column_names(wanted.tasks)}
    for name in dict.fromkeys(names.tolist()):
        idx = np.flatnonzero(names == name)
        sub = rows.take(pa.array(idx, type=pa.int64()))
        p0 = np.asarray(sub.column("p0").to_pylist(), dtype=np.float64).reshape(-1, 6)
        use_dir = np.asarray(sub.column("use_dir").to_pylist(), dtype=np.float64)
        obj, _parts = _entry_object(by_name[name], settings)
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
    objects: list[dict],
    settings,
    robust: RobustSettings | None = None,
    soft: bool = False,
) -> pa.Table:
    """The outcome table of some dataset rows (their key and metric columns + outcomes).

    Parameters
    ----------
    rows : pyarrow.Table
        Dataset rows.
    hand : Hand or str
        The hand the dataset was generated with
        (:func:`affordgrasp.dataset.reading.dataset_hand`), or a registered name.
    objects : list of dict
        The dataset manifest's object entries.
    settings : PhysicsSettings
    robust : RobustSettings, optional
        Also compute the rows' robust columns (:func:`robust_of_rows`) and add them.
    soft : bool
        The dataset's contact model (for ``robust``).

    Returns
    -------
    pyarrow.Table
    """
    from ..hands import get_hand, hand_to_dict
    from .trials import validate_grasp

    hand = get_hand(hand)
    hand_key = json.dumps(hand_to_dict(hand), sort_keys=True)
    by_name = {o["name"]: o for o in objects}
    names = rows.column("object").to_pylist()
    poses = rows.column("hand_pose").to_pylist()
    joints = rows.column("joints").to_pylist()
    ups = rows.column("use_point").to_pylist()
    uns = rows.column("use_normal").to_pylist()
    outcomes = []
    for i in range(rows.num_rows):
        entry = by_name[names[i]]
        scene = _scene(hand_key, entry["name"], entry["source"], entry["mesh_hash"], settings)
        up = np.array(ups[i] if ups[i] is not None else [np.nan] * 3, dtype=np.float64)
        un = np.array(uns[i] if uns[i] is not None else [np.nan] * 3, dtype=np.float64)
        outcome = validate_grasp(
            scene, np.array(poses[i]).reshape(4, 4), np.array(joints[i]), up, un
        )
        outcomes.append(outcome.to_row())
    keep = [c for c in rows.column_names if c not in STATE_COLUMNS]
    table = rows.select(keep)
    for name in outcomes[0] if outcomes else ():
        values = [o[name] for o in outcomes]
        table = table.append_column(name, pa.array(values, type=_outcome_type(name)))
    if robust is not None and robust.enabled:
        scores = robust_of_rows(rows, hand, objects, robust, settings, soft)
        for name, column in scores.items():
            if name in table.column_names:
                table = table.drop_columns([name])
            table = table.append_column(name, pa.array(column, type=pa.float64()))
    return table.append_column("protocol", pa.array([settings.protocol] * table.num_rows))


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
    if name in ("hold_ok", "settled", "impact_ok", "press_held", "ejected"):
        return pa.bool_()
    if name in ("settled_points", "settled_normals", "settled_mu"):
        return pa.list_(pa.float64())
    return pa.float64()


def validate_shard(out, k, rows, hand, objects, settings, robust=None, soft=False) -> dict:
    """Validate one shard's rows and write its Parquet file atomically.

    Parameters
    ----------
    out : pathlib.Path
        The run's directory.
    k : int
        Shard index.
    rows, hand, objects, settings, robust, soft
        As for :func:`validate_rows`.

    Returns
    -------
    dict
        ``rows``, simulation ``steps``, wall ``seconds`` and ``cpu_seconds``.
    """
    started, cpu = time.perf_counter(), time.process_time()
    table = validate_rows(rows, hand, objects, settings, robust, soft)
    seconds, cpu = time.perf_counter() - started, time.process_time() - cpu
    path = shard_path(Path(out), k)
    meta = {b"affordgrasp_version": __version__.encode(), b"physics_settings": b""}
    meta[b"physics_settings"] = settings.digest().encode()
    table = table.replace_schema_metadata(meta)
    atomic_write(path, lambda fh: pq.write_table(table, fh))
    steps = int(np.sum(table.column("steps").to_numpy())) if table.num_rows else 0
    return {"rows": table.num_rows, "steps": steps, "seconds": seconds, "cpu_seconds": cpu}


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
