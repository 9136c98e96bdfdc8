"""Generate a sharded Parquet dataset of evaluated grasps (conventions: Datasets, paper §IV-B).

:func:`generate` samples (p0, d) uniformly for every object, simulates the grasp policy,
computes Φ, and writes every sample, stable or not, as Parquet shards (see
``affordgrasp.dataset.shards`` for the directory layout and ``docs/dataset.md`` for the
schema). Guarantees:

* deterministic: sample ``i`` of an object depends only on (seed, i, object, hand), never on
  the engine, the number of workers or shard boundaries;
* resumable: shards are renamed into place only when whole, so after Ctrl-C, a crash or
  ``kill -9`` the same call finishes the job and the rows equal an uninterrupted run's;
* memory-bounded: only the chunks of shards still being computed are held, at most one
  shard's worth plus two chunks per worker, however large the run.

The work is cut into chunks (a few hundred samples) so that every worker is busy even on a
small run and progress is reported often; the caller's process alone writes files.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa

from .._version import __version__
from ..errors import DatasetError, InputError, InternalError, bad_parameter
from ..grasp.pregrasp import SAMPLE_STREAMS, object_stream_seed
from ..hands import Hand, hand_to_dict
from ..robust import RobustSettings, robust_settings
from ..runtime.engines import Engine, check_engine, make_engine
from ..runtime.interrupts import stop_on_signals
from ..schema import column_numbers
from . import card as card_module
from .checksums import read_checksums
from .handle import Dataset
from .jobs import Job, ObjectPayload, RunContext
from .manifest import (
    FORMAT,
    FORMAT_VERSION,
    MANIFEST_NAME,
    manifest_streams,
    prepare_directory,
    read_manifest,
)
from .shards import (
    DEFAULT_SHARD_SIZE,
    Shard,
    plan_shards,
    remove_stale_temporaries,
    shard_metadata,
    valid_shard_info,
    write_shard,
)

log = logging.getLogger(__name__)

DEFAULT_CHUNK_SIZE = 256
MAX_SHARDS = 100_000  # files in one folder, and the plan of a run held in memory
MIN_CHUNK_SIZE = 8

ProgressFactory = Callable[[int], AbstractContextManager[Callable[[int], None]]]


@dataclass
class GenerationSummary:
    """What a call to :func:`generate` did and what the dataset now holds.

    Attributes
    ----------
    directory : str
    complete : bool
        Every planned shard is written.
    samples_per_object : int
    shards_total, shards_written, shards_skipped : int
        Planned, written by this call, already there.
    samples_written : int
    elapsed_s : float
        Wall time, s.
    engine : str
    workers : int
    status_counts : dict
        Object -> status -> rows.
    dataset : Dataset or None
        The dataset, opened (:class:`~affordgrasp.dataset.handle.Dataset`): what every
        consumer of it takes (``train_on_dataset(summary.dataset)``...).
    """

    directory: str
    complete: bool
    samples_per_object: int
    shards_total: int
    shards_written: int
    shards_skipped: int
    samples_written: int
    elapsed_s: float
    engine: str
    workers: int
    status_counts: dict[str, dict[str, int]] = field(default_factory=dict)
    dataset: Dataset | None = field(default=None, repr=False, compare=False)

    @property
    def grasps_per_s(self) -> float:
        """Samples written per second of wall time (0 when no time passed)."""
        return self.samples_written / self.elapsed_s if self.elapsed_s > 0 else 0.0

    def to_dict(self) -> dict:
        """The summary as JSON-ready data (``generate --json``).

        Returns
        -------
        dict
            Every attribute and ``grasps_per_s``.
        """
        return {
            "directory": self.directory,
            "complete": self.complete,
            "samples_per_object": self.samples_per_object,
            "shards_total": self.shards_total,
            "shards_written": self.shards_written,
            "shards_skipped": self.shards_skipped,
            "samples_written": self.samples_written,
            "elapsed_s": self.elapsed_s,
            "grasps_per_s": self.grasps_per_s,
            "engine": self.engine,
            "workers": self.workers,
            "status_counts": self.status_counts,
        }


def build_manifest(
    objects: Sequence,
    *,
    samples: int,
    seed: int,
    hand: Hand,
    shard_size: int,
    metrics: bool,
    soft: bool,
    command: Sequence[str] | None,
    depth: bool = False,
    materials: bool = False,
    volume: bool = False,
    robust: RobustSettings | None = None,
    streams: str = "per-object",
) -> dict:
    """The plan of a run as a JSON document (``_manifest.json``).

    Parameters
    ----------
    objects : sequence of GraspObject
    samples : int
        Samples per object.
    seed : int
    hand : Hand
        The hand: its name under ``hand``, its whole specification (the document of
        :func:`~affordgrasp.hands.hand_to_dict`, as a hand file holds it) under
        ``hand_spec``.
    shard_size : int
        Rows per shard.
    metrics, soft, depth : bool
        Metric columns, soft-finger cones, depth images.
    materials : bool
        Whether the families' mass properties follow their per-part materials (recorded
        always: a resume must use the same mass properties).
    command : sequence of str or None
        The command line, recorded.
    volume : bool
        Whether the GWS volume is computed (``gws_volume``; null otherwise). Recorded
        always (a resume must match); a manifest written before it was recorded computed
        it whenever it computed metrics (:func:`~affordgrasp.dataset.manifest.manifest_volume`).
    robust : RobustSettings, optional
        Robust evaluation's parameters (recorded under ``robust`` when K > 0; a resume
        must use the same).
    streams : {"per-object", "shared"}
        How the objects draw their samples (``sample_streams``; per object, its ``seed``:
        :func:`~affordgrasp.grasp.pregrasp.object_stream_seed`, or the run's seed when
        shared).

    Returns
    -------
    dict
    """
    manifest = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "affordgrasp_version": __version__,
        "seed": seed,
        "samples": samples,
        "shard_size": shard_size,
        "hand": hand.name,
        "hand_spec": hand_to_dict(hand),
        "metrics": metrics,
        "volume": bool(metrics and volume),
        "soft": soft,
        "materials": bool(materials),
        "sample_streams": streams,
        "objects": [
            {
                "index": i,
                "name": o.name,
                "category": o.category,
                "mesh_hash": o.mesh_hash,
                "source": o.source,
                "seed": object_stream_seed(seed, o.name) if streams == "per-object" else seed,
            }
            for i, o in enumerate(objects)
        ],
        "command": list(command) if command is not None else None,
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    if depth:  # absent without depth images, so earlier datasets still resume
        from ..vision.depth import depth_manifest

        manifest["depth"] = depth_manifest()
    if robust is not None and robust.enabled:  # absent for plain runs: earlier ones resume
        manifest["robust"] = robust.to_dict()
    if metrics:  # the models of the stored p_T columns (search.best reads them when current)
        from ..tasks.probability import model_digests

        manifest["probability_models"] = model_digests()
    return manifest


def load_objects(specs: Sequence, materials: bool = False) -> list:
    """Resolve object specs once, refusing duplicates (they would duplicate rows).

    Parameters
    ----------
    specs : sequence
        Object specs or GraspObjects.
    materials : bool
        Per-part materials for the built-in families (``load_object(..., materials=True)``);
        mesh files among ``specs`` keep their uniform density, and all mesh files is an
        error.

    Returns
    -------
    list of GraspObject
    """
    from ..objects import GraspObject, load_object
    from ..objects.resolve import is_family_spec

    if not specs:
        raise InputError("no objects given; name at least one object (e.g. 'knife', 'knife:7')")

    def family(s) -> bool:
        return is_family_spec(s) or (isinstance(s, GraspObject) and s.source == "family")

    if materials and not any(family(s) for s in specs):
        load_object(specs[0], materials=True)  # refused: names the problem and the fix
    # materials apply to the families; mesh files keep their uniform density
    objects = [load_object(s, materials=materials and family(s)) for s in specs]
    seen: dict[str, int] = {}
    for i, o in enumerate(objects):
        if o.name in seen:
            raise InputError(
                f"object {o.name!r} is named twice ({specs[seen[o.name]]!r} and {specs[i]!r}); "
                "name each object once"
            )
        seen[o.name] = i
    return objects


def _check_counts(
    samples: int, seed: int, shard_size: int, chunk_size: int, n_objects: int = 1
) -> None:
    for name, value, low in (
        ("samples", samples, 1),
        ("seed", seed, 0),
        ("shard_size", shard_size, 1),
        ("chunk_size", chunk_size, 1),
    ):
        if not isinstance(value, int) or isinstance(value, bool) or value < low:
            raise bad_parameter(name, f"must be an integer >= {low}, got {value!r}")
    shards = n_objects * -(-samples // shard_size)
    if shards > MAX_SHARDS:  # the plan holds every shard, before any is written
        most = MAX_SHARDS // max(n_objects, 1) * shard_size
        raise bad_parameter(
            "samples",
            f"{samples:,} per object in shards of {shard_size:,} rows would make {shards:,} "
            f"shard files; at most {MAX_SHARDS:,}: use at most {most:,} samples per object, or "
            "a larger shard size",
        )


def generate(
    objects: Sequence,
    samples: int,
    out: str | Path,
    *,
    seed: int = 0,
    workers: int | None = None,
    engine: str = "local",
    address: str | None = None,
    hand: Hand | str = "barrett",
    shard_size: int = DEFAULT_SHARD_SIZE,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    metrics: bool = True,
    soft: bool = False,
    depth: bool = False,
    materials: bool = False,
    command: Sequence[str] | None = None,
    progress: ProgressFactory | None = None,
    volume: bool = False,
    robust: RobustSettings | int | None = None,
    streams: str | None = None,
) -> GenerationSummary:
    """Generate (or finish) the dataset of ``samples`` uniform samples per object in ``out``.

    Parameters
    ----------
    objects : sequence of str or GraspObject
        Object specs (``"knife"``, ``"knife:7"``, a mesh path) or loaded objects.
    samples : int
        Samples per object.
    out : path
        The dataset directory (created; an existing one of the same plan is resumed).
    seed : int
        The run's seed: sample ``i`` of an object depends only on (seed, i, the object's
        name) (``streams="per-object"``) or on (seed, i) (``"shared"``).
    workers : int, optional
        Processes (local) or CPUs (local Ray); default every core; 1 runs in-process.
    engine : {"local", "ray"}
        Where the jobs run.
    address : str, optional
        An existing Ray cluster (with ``engine="ray"``).
    hand : Hand or str
        A :class:`~affordgrasp.hands.Hand`, a registered name or a hand file; the Hand
        object itself is sent to the workers.
    shard_size : int
        Rows per shard file.
    chunk_size : int
        Most samples per unit of work.
    metrics : bool
        Compute Φ (False writes the simulation columns only).
    soft : bool
        Soft-finger contacts.
    depth : bool
        Also store the depth image D(p0, O) of every row (column ``depth_mm``).
    materials : bool
        Mass properties of the built-in families from their per-part materials instead of
        the paper's uniform unit density (recorded in the manifest; a resume must match).
    command : sequence of str, optional
        The command line, recorded in the manifest and the card.
    progress : callable, optional
        ``progress(total_samples)`` returns a context manager yielding ``advance(n)``.
    volume : bool
        Also compute the GWS volume (column ``gws_volume``, null otherwise; recorded in the
        manifest and the card). Not in the paper's Φ; it costs the full 6-D hull of every
        force-closure grasp.
    robust : RobustSettings or int, optional
        K perturbed copies per grasp and the ``robust_*`` columns (:mod:`affordgrasp.robust`);
        None or 0: plain. Needs ``metrics``.
    streams : {"per-object", "shared"}, optional
        ``"per-object"``: each object draws its samples from its own seed
        (:func:`~affordgrasp.grasp.pregrasp.object_stream_seed`, in the rows' ``seed``
        column and the manifest), so no two objects share a pregrasp; what a learning
        dataset needs. ``"shared"``: every object draws the run's samples (sample i is the
        same pregrasp and use direction on every object; a paired comparison of objects).
        None: per-object for a new dataset, the dataset's own when resuming (a dataset
        whose manifest does not record it shares its stream).

    Returns
    -------
    GenerationSummary

    Raises
    ------
    DatasetError
        When ``out`` holds another command's dataset or something else.

    Notes
    -----
    A KeyboardInterrupt stops the workers and leaves only whole shards (and an up-to-date
    card marked incomplete); calling again resumes. Local workers are started with 'spawn':
    a script calling this with ``workers > 1`` needs the ``if __name__ == "__main__":`` guard.
    """
    from ..hands import get_hand

    _check_counts(samples, seed, shard_size, chunk_size, len(objects))
    check_engine(engine, workers, address)
    hand_model = get_hand(hand)
    robust = robust_settings(robust)
    if robust is not None and not metrics:
        raise bad_parameter("robust", "needs the metric columns; drop --no-metrics or --robust")
    resolved = load_objects(list(objects), materials=materials)
    directory = Path(out)
    if directory.exists() and not directory.is_dir():
        raise bad_parameter("out", f"{str(directory)!r} is a file; give a directory", DatasetError)
    if streams is not None and streams not in SAMPLE_STREAMS:
        raise bad_parameter(
            "streams", f"must be one of {', '.join(SAMPLE_STREAMS)}, got {streams!r}"
        )
    if streams is None:
        # a resume keeps the dataset's own streams; a new dataset gets per-object streams
        on_disk = (directory / MANIFEST_NAME).exists()
        streams = manifest_streams(read_manifest(directory)) if on_disk else SAMPLE_STREAMS[0]
    manifest = build_manifest(
        resolved,
        samples=samples,
        seed=seed,
        hand=hand_model,
        shard_size=shard_size,
        metrics=metrics,
        soft=soft,
        command=command,
        depth=depth,
        materials=materials or any(o.materials for o in resolved),
        volume=volume,
        robust=robust,
        streams=streams,
    )
    manifest = prepare_directory(directory, manifest)
    removed = remove_stale_temporaries(directory)
    if removed:
        log.info("removed %d half-written file(s) left by an interrupted run", removed)

    from ..schema import dataset_schema

    schema = dataset_schema(metrics, depth, robust)
    plan = plan_shards(len(resolved), samples, shard_size)
    infos: dict[Shard, dict] = {}
    checksums = read_checksums(directory)
    for shard in plan:
        info = valid_shard_info(directory, shard, manifest, schema, checksums)
        if info is not None:
            infos[shard] = info
    todo = [s for s in plan if s not in infos]
    skipped = len(infos)

    context = RunContext(
        objects=tuple(ObjectPayload.from_object(o) for o in resolved),
        hand=hand_model,
        seed=seed,
        object_seeds=(
            tuple(int(o["seed"]) for o in manifest["objects"])
            if manifest_streams(manifest) == "per-object"
            else None
        ),
        metrics=metrics,
        soft=soft,
        depth=depth,
        volume=bool(metrics and volume),
        robust=robust,
    )
    started = time.perf_counter()
    started_at = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    written_rows = 0
    complete = False
    engine_name, n_workers = engine, 0
    try:
        if todo:
            with (
                stop_on_signals(),
                make_engine(context, engine=engine, workers=workers, address=address) as eng,
            ):
                engine_name, n_workers = eng.name, eng.workers
                total = sum(s.rows for s in todo)
                bar = progress(total) if progress is not None else nullcontext(lambda n: None)
                with bar as advance:
                    for shard, info in _run_shards(
                        eng, todo, resolved, directory, chunk_size, advance
                    ):
                        infos[shard] = info
                        written_rows += shard.rows
        complete = True
    finally:
        if not complete:
            # An interrupt can land between a shard's rename into place and its bookkeeping:
            # the card counts what is on disk, valid, not what the loop had recorded.
            checksums = read_checksums(directory)
            for shard in todo:
                if shard not in infos:
                    info = valid_shard_info(directory, shard, manifest, schema, checksums)
                    if info is not None:
                        infos[shard] = info
                        written_rows += shard.rows
        elapsed = time.perf_counter() - started
        summary = GenerationSummary(
            directory=str(directory),
            complete=complete,
            samples_per_object=samples,
            shards_total=len(plan),
            shards_written=len(infos) - skipped,
            shards_skipped=skipped,
            samples_written=written_rows,
            elapsed_s=elapsed,
            engine=engine_name,
            workers=n_workers,
            status_counts=_status_counts(resolved, infos),
            dataset=Dataset(directory, manifest),
        )
        if todo or card_module.read_card(directory) is None:  # a no-op run changes nothing
            _write_card_after(
                complete,
                card_module.write_card,
                directory,
                manifest=manifest,
                objects=resolved,
                hand=hand_model,
                shards=infos,
                plan=plan,
                run={
                    "command": list(command) if command is not None else None,
                    "engine": engine_name,
                    "workers": n_workers,
                    "started": started_at,
                    "elapsed_s": round(elapsed, 3),
                    "samples_written": written_rows,
                    "complete": complete,
                },
            )
    return summary


def _write_card_after(complete: bool, write_card, *args, **kwargs) -> None:
    """Write the card; after a failed run (a full disk...) a failure here is only logged,
    so that the error the user sees is the one that stopped the run."""
    try:
        write_card(*args, **kwargs)
    except InputError as exc:  # a DatasetError, or a write the file system refused
        if complete:
            raise
        log.warning("could not update the dataset card: %s", exc)


def _status_counts(objects: Sequence, infos: dict[Shard, dict]) -> dict[str, dict[str, int]]:
    counts: dict[str, Counter] = {o.name: Counter() for o in objects}
    for shard, info in infos.items():
        counts[objects[shard.object_index].name].update(info.get("status_counts", {}))
    return {name: dict(sorted(c.items())) for name, c in counts.items()}


def _run_shards(
    engine: Engine,
    todo: list[Shard],
    objects: Sequence,
    directory: Path,
    chunk_size: int,
    advance: Callable[[int], None],
):
    """Compute the shards in ``todo`` on ``engine``, write each when whole; yield (shard, info).

    At most ``2 * workers`` chunks run at once and at most one shard's chunks plus those are
    held in memory.
    """
    total_rows = sum(s.rows for s in todo)
    # Small runs: smaller chunks so every worker has work; content does not depend on it.
    chunk = max(MIN_CHUNK_SIZE, min(chunk_size, math.ceil(total_rows / (4 * engine.workers))))
    jobs = (
        (shard, Job(shard.object_index, start, min(start + chunk, shard.stop) - start))
        for shard in todo
        for start in range(shard.start, shard.stop, chunk)
    )
    depth = 1 if engine.workers == 1 and engine.name == "local" else 2 * engine.workers
    # A slow chunk must not let finished chunks of later shards pile up: cap the chunks held
    # (running or waiting for their shard). Chunks go out in plan order, so the first open
    # shard can always be submitted whole under this cap and the run never stalls.
    cap = depth + max(math.ceil(s.rows / chunk) for s in todo)
    in_flight: dict = {}
    parts: dict[Shard, dict[int, pa.Table]] = {}
    held = 0
    exhausted = False
    while True:
        while not exhausted and len(in_flight) < depth and held < cap:
            item = next(jobs, None)
            if item is None:
                exhausted = True
                break
            shard, job = item
            in_flight[engine.submit(job)] = (shard, job)
            held += 1
        if not in_flight:
            return
        for handle in engine.wait(list(in_flight)):
            shard, job = in_flight.pop(handle)
            table = engine.result(handle)
            if table.num_rows != job.n:  # pragma: no cover - a broken worker
                raise InternalError(f"a job returned {table.num_rows} rows instead of {job.n}")
            pieces = parts.setdefault(shard, {})
            pieces[job.start] = table
            advance(job.n)
            if sum(t.num_rows for t in pieces.values()) == shard.rows:
                whole = pa.concat_tables([pieces[k] for k in sorted(pieces)]).combine_chunks()
                held -= len(pieces)
                del parts[shard]
                counts = _count_statuses(whole)
                info = shard_metadata(shard, objects[shard.object_index].name, counts)
                if "epsilon" in whole.column_names:
                    info["force_closure"] = int((column_numbers(whole["epsilon"]) > 0).sum())
                write_shard(directory, shard, whole, info)
                log.info("wrote %s (%d rows)", shard.name, shard.rows)
                yield shard, info


def _count_statuses(table: pa.Table) -> dict[str, int]:
    # plain Python, not pyarrow.compute: importing it is ~30 ms of every command's start-up
    counts = Counter(table.column("status").to_pylist())
    return {status: int(counts[status]) for status in sorted(counts)}
