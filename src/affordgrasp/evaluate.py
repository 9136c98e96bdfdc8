"""The pipeline: pregrasp → grasp policy → contacts → metric vector Φ, for many grasps.

:func:`evaluate` runs it for given inputs; :func:`evaluate_samples` draws the inputs from a
seed so that a sample's content depends only on (seed, sample index). Both return an
:class:`Evaluation`: an Arrow table with one row per grasp (columns: :mod:`affordgrasp.schema`
and docs/conventions.md) and the time spent in each stage.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa

from .columns import USE_METRICS
from .errors import InputError
from .grasp.policy import SimulationBatch, simulate
from .grasp.pregrasp import sample_inputs
from .hands import Hand, get_hand
from .metrics.phi import compute_phi_batch
from .objects import GraspObject, resolve_object
from .schema import batch_to_table

STAGES = ("simulate", "metrics", "table")


@dataclass(frozen=True)
class Evaluation:
    """Grasps simulated and scored on one object.

    Attributes
    ----------
    table : pyarrow.Table
        One row per grasp, stable or not (columns: docs/conventions.md).
    timings : mapping of str to float
        Seconds spent per stage: ``simulate``, ``metrics``, ``table``.

    Notes
    -----
    An ``Evaluation`` also unpacks as ``table, timings`` (the return value of affordgrasp
    0.1), so ``table, timings = evaluate_samples(...)`` keeps working.
    """

    table: pa.Table
    timings: Mapping[str, float] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.table.num_rows)

    def __iter__(self) -> Iterator[Any]:
        yield self.table
        yield dict(self.timings)

    @property
    def seconds(self) -> float:
        """Total time spent, s."""
        return float(sum(self.timings.values()))

    def scores(self, task: Any, mode: str = "default", **thresholds: float) -> np.ndarray:
        """F_T of every grasp for ``task`` (a name or a :class:`~affordgrasp.tasks.Task`).

        Returns
        -------
        (n,) float64 ndarray
            -inf where the task's thresholds fail.
        """
        from .tasks import get_task

        task = get_task(task) if isinstance(task, str) else task
        return task.evaluate(self.table, mode, **thresholds)

    def to_pandas(self):
        """The table as a pandas DataFrame (needs pandas)."""
        return self.table.to_pandas()


def phi_of_batch(obj: GraspObject, batch: SimulationBatch, *, soft: bool = False) -> dict:
    """Φ for every row of a simulation batch: column name → (n,) array.

    A row whose use ray left the object without a hit (from the cavity of a hollow object
    through its opening) has no use point: its use metrics are NaN (undefined), the others
    are computed as usual.
    """
    no_use = batch.use_triangle < 0
    use_point = np.where(no_use[:, None], obj.mass.center_of_mass, batch.use_point)
    use_normal = np.where(no_use[:, None], [1.0, 0.0, 0.0], batch.use_normal)
    use_triangle = np.where(no_use, 0, batch.use_triangle)
    phi = compute_phi_batch(
        obj.mass,
        obj.mesh,
        batch.contacts,
        use_point,
        use_normal,
        use_triangle,
        batch.wrist_point,
        batch.wrist_axis,
        soft=soft,
    )
    if no_use.any():
        for name in USE_METRICS:
            phi[name] = np.where(no_use, np.nan, phi[name])
    return phi


def evaluate(
    obj: GraspObject | str,
    p0,
    use_dir,
    *,
    hand: Hand | str = "barrett",
    seed: int = -1,
    sample_start: int = 0,
    soft: bool = False,
    metrics: bool = True,
) -> Evaluation:
    """Simulate and score given inputs on one object.

    Parameters
    ----------
    obj : GraspObject or str
        The object, or an object spec (``"knife"``, ``"knife:3"``, a mesh path).
    p0 : (n, 6) array_like
        Pregrasps (docs/conventions.md).
    use_dir : (n, 2) array_like
        Use directions.
    hand : Hand or str
        The hand (a :class:`~affordgrasp.hands.Hand` or a registered name).
    seed : int
        Stored in the ``seed`` column (-1: inputs not drawn from a seed).
    sample_start : int
        Sample index of the first row.
    soft : bool
        Soft-finger contacts (torsional friction).
    metrics : bool
        Compute Φ (False: simulation columns only).

    Returns
    -------
    Evaluation
    """
    obj = resolve_object(obj)
    hand = get_hand(hand)
    t0 = time.perf_counter()
    batch = simulate(obj, p0, use_dir, hand=hand)
    t1 = time.perf_counter()
    phi = phi_of_batch(obj, batch, soft=soft) if metrics else None
    t2 = time.perf_counter()
    table = batch_to_table(
        obj, batch, hand=hand.name, seed=seed, sample_start=sample_start, metrics=phi
    )
    return Evaluation(
        table, {"simulate": t1 - t0, "metrics": t2 - t1, "table": time.perf_counter() - t2}
    )


def evaluate_samples(
    obj: GraspObject | str,
    n: int,
    *,
    seed: int = 0,
    start: int = 0,
    hand: Hand | str = "barrett",
    soft: bool = False,
    metrics: bool = True,
    batch_size: int | None = None,
    progress: Callable[[int], Any] | None = None,
) -> Evaluation:
    """Draw samples ``start .. start + n - 1`` of the run ``seed`` uniformly and evaluate them.

    Parameters
    ----------
    obj, hand, soft, metrics
        As for :func:`evaluate`.
    n : int
        Number of samples (> 0).
    seed : int
        The run's seed: sample ``i`` depends only on (seed, i).
    start : int
        Index of the first sample.
    batch_size : int, optional
        Evaluate at most this many samples at a time (bounded memory, progress); the rows
        are the same whatever the batch size.
    progress : callable, optional
        ``progress(k)`` after each batch of ``k`` samples.

    Returns
    -------
    Evaluation
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n <= 0:
        raise InputError(f"n must be a positive integer, got {n!r}")
    if batch_size is not None and (not isinstance(batch_size, int | np.integer) or batch_size <= 0):
        raise InputError(f"batch_size must be a positive integer, got {batch_size!r}")
    obj = resolve_object(obj)
    hand = get_hand(hand)
    step = int(batch_size or n)
    tables = []
    spent = dict.fromkeys(STAGES, 0.0)
    for first in range(start, start + n, step):
        k = min(step, start + n - first)
        p0, d = sample_inputs(seed, first, first + k)
        part = evaluate(
            obj, p0, d, hand=hand, seed=seed, sample_start=first, soft=soft, metrics=metrics
        )
        for stage, seconds in part.timings.items():
            spent[stage] = spent.get(stage, 0.0) + seconds
        tables.append(part.table)
        if progress is not None:
            progress(k)
    table = tables[0] if len(tables) == 1 else pa.concat_tables(tables)
    return Evaluation(table, spent)
