"""The pipeline: pregrasp → grasp policy → contacts → metric vector Φ, for many grasps.

:func:`evaluate` is the entry point (``affordgrasp.evaluate``): it runs the pipeline on
given inputs (:func:`evaluate_inputs`) or on ``samples`` drawn from a seed
(:func:`evaluate_samples`: a sample's content depends only on (seed, sample index)). All
return an :class:`Evaluation`: an Arrow table with one row per grasp (columns:
:mod:`affordgrasp.schema` and docs/conventions.md) and the time spent in each stage.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa

from .errors import InputError
from .grasp.policy import simulate
from .grasp.pregrasp import sample_inputs
from .hands import Hand, get_hand
from .metrics.phi_batch import phi_of_batch
from .objects import GraspObject, load_object
from .robust import RobustSettings, robust_columns, robust_settings, task_scores
from .schema import PROBABILITY_FIELDS, append_float_columns, batch_to_table, robust_fields
from .tasks.metric_columns import MetricColumns
from .tasks.probability import probability_columns

STAGES = ("simulate", "metrics", "table")  # and "robust" with robust evaluation


@dataclass(frozen=True)
class Evaluation:
    """Grasps simulated and scored on one object.

    Attributes
    ----------
    table : pyarrow.Table
        One row per grasp, stable or not (columns: docs/conventions.md).
    timings : mapping of str to float
        Seconds spent per stage: ``simulate``, ``metrics``, ``table``, and ``robust`` (the
        perturbed copies) with robust evaluation.

    Notes
    -----
    An ``Evaluation`` does not unpack: ``table, timings = result`` (the return value of
    affordgrasp 0.1) raises a ``TypeError`` that names ``result.table`` and
    ``result.timings``.
    """

    table: pa.Table
    timings: Mapping[str, float] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.table.num_rows)

    def __iter__(self) -> Iterator[Any]:
        raise TypeError(
            "an Evaluation does not unpack into (table, timings): "
            "use result.table and result.timings"
        )

    @property
    def seconds(self) -> float:
        """Total time spent, s."""
        return float(sum(self.timings.values()))

    def scores(
        self, task: Any, mode: str = "default", robust: bool = False, **thresholds: float
    ) -> np.ndarray:
        """F_T of every grasp for a task (its robust ranking score with ``robust``).

        Parameters
        ----------
        task : str or Task
            A registered name or a :class:`~affordgrasp.tasks.Task`.
        mode : str
            Threshold mode (``"default"``, ``"no-robustness"``, ...).
        robust : bool
            The robust score (:func:`affordgrasp.robust.ranking_column`; an evaluation with
            ``robust=K``); ``mode`` and ``thresholds`` do not apply.
        **thresholds : float
            Overrides of the task's thresholds.

        Returns
        -------
        (n,) float64 ndarray
            -inf where the task's thresholds fail.
        """
        return task_scores(task, self.table, mode, thresholds, robust=robust)

    def to_pandas(self):
        """The table as a pandas DataFrame (needs pandas).

        Returns
        -------
        pandas.DataFrame
            One row per sample, the columns of :attr:`table`.
        """
        return self.table.to_pandas()


def evaluate_inputs(
    obj: GraspObject | str,
    p0,
    use_dir,
    *,
    hand: Hand | str = "barrett",
    seed: int = -1,
    sample_start: int = 0,
    soft: bool = False,
    metrics: bool = True,
    volume: bool = False,
    robust: RobustSettings | int | None = None,
    frame: GraspObject | None = None,
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
    volume : bool
        Also compute ``gws_volume`` (default False: the column is null, every other
        column the same; see :func:`phi_of_batch`).
    robust : RobustSettings or int, optional
        Robust evaluation (:mod:`affordgrasp.robust`): K perturbed copies per grasp and the
        ``robust_*`` columns after the metric columns. An int is K with the default
        perturbations; None or 0: plain evaluation, the same table as without it.
    frame : GraspObject, optional
        The object whose geometry places the pregrasps, and the robust copies' starts
        (default: ``obj``; see :func:`~affordgrasp.grasp.policy.simulate`).

    Returns
    -------
    Evaluation
    """
    return _evaluate_batch(
        load_object(obj),
        get_hand(hand),
        p0,
        use_dir,
        seed=seed,
        sample_start=sample_start,
        soft=soft,
        metrics=metrics,
        volume=volume,
        settings=robust_settings(robust),
        frame=frame,
    )


def _evaluate_batch(
    obj: GraspObject,
    hand: Hand,
    p0,
    use_dir,
    *,
    seed: int,
    sample_start: int,
    soft: bool,
    metrics: bool,
    volume: bool,
    settings: RobustSettings | None,
    frame: GraspObject | None = None,
) -> Evaluation:
    """:func:`evaluate_inputs` of an object, a hand and robust settings already resolved."""
    t0 = time.perf_counter()
    batch = simulate(obj, p0, use_dir, hand=hand, frame=frame)
    t1 = time.perf_counter()
    phi = phi_of_batch(obj, batch, soft=soft, volume=volume) if metrics else None
    t2 = time.perf_counter()
    extra = None
    if settings is not None and phi is not None:
        extra = robust_columns(obj, batch, settings, hand=hand, phi=phi, soft=soft, frame=frame)
    t3 = time.perf_counter()
    table = batch_to_table(
        obj, batch, hand=hand.name, seed=seed, sample_start=sample_start, metrics=phi
    )
    if extra is not None and settings is not None:
        table = append_float_columns(table, robust_fields(settings.tasks), extra)
    if phi is not None:
        # from the arrays themselves (a table's columns would import pandas to convert)
        probabilities = probability_columns(MetricColumns({**phi, **(extra or {})}))
        table = append_float_columns(table, PROBABILITY_FIELDS, probabilities)
    timings = {"simulate": t1 - t0, "metrics": t2 - t1, "table": time.perf_counter() - t3}
    if extra is not None:
        timings["robust"] = t3 - t2
    return Evaluation(table, timings)


def evaluate_samples(
    obj: GraspObject | str,
    samples: int,
    *,
    seed: int = 0,
    start: int = 0,
    hand: Hand | str = "barrett",
    soft: bool = False,
    metrics: bool = True,
    batch_size: int | None = None,
    progress: Callable[[int], Any] | None = None,
    volume: bool = False,
    robust: RobustSettings | int | None = None,
) -> Evaluation:
    """Draw samples ``start .. start + samples - 1`` of the run ``seed`` and evaluate them.

    Parameters
    ----------
    obj, hand, soft, metrics, volume, robust
        As for :func:`evaluate_inputs`.
    samples : int
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
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples <= 0:
        raise InputError(f"samples must be a positive integer, got {samples!r}")
    if batch_size is not None and (not isinstance(batch_size, int | np.integer) or batch_size <= 0):
        raise InputError(f"batch_size must be a positive integer, got {batch_size!r}")
    obj, hand, settings = load_object(obj), get_hand(hand), robust_settings(robust)
    n = int(samples)
    step = int(batch_size or n)
    tables = []
    spent = dict.fromkeys(STAGES, 0.0)
    for first in range(start, start + n, step):
        k = min(step, start + n - first)
        p0, d = sample_inputs(seed, first, first + k)
        part = _evaluate_batch(
            obj,
            hand,
            p0,
            d,
            seed=seed,
            sample_start=first,
            soft=soft,
            metrics=metrics,
            volume=volume,
            settings=settings,
        )
        for stage, seconds in part.timings.items():
            spent[stage] = spent.get(stage, 0.0) + seconds
        tables.append(part.table)
        if progress is not None:
            progress(k)
    table = tables[0] if len(tables) == 1 else pa.concat_tables(tables)
    return Evaluation(table, spent)


def evaluate(
    obj: GraspObject | str,
    samples: int | None = None,
    *,
    p0=None,
    use_dir=None,
    seed: int = 0,
    start: int = 0,
    hand: Hand | str = "barrett",
    soft: bool = False,
    metrics: bool = True,
    batch_size: int | None = None,
    progress: Callable[[int], Any] | None = None,
    volume: bool = False,
    robust: RobustSettings | int | None = None,
) -> Evaluation:
    """Simulate grasps on an object and compute their metric vector Φ.

    Give either ``samples`` (uniform pregrasps and use directions drawn from ``seed``) or
    ``p0`` and ``use_dir`` (your own inputs).

    Parameters
    ----------
    obj : GraspObject or str
        The object: ``ag.load_object(...)``, a family (``"knife"``), ``"knife:7"`` or a mesh
        path.
    samples : int, optional
        Number of grasps drawn uniformly; sample ``i`` depends only on (seed, start + i).
    p0 : (n, 6) array_like, optional
        Pregrasps in [-1, 1]^5 x [0, 1] (docs/conventions.md).
    use_dir : (n, 2) array_like, optional
        Use directions in [-1, 1]^2.
    seed, start : int
        The run's seed and the first sample index (with ``samples``).
    hand : Hand or str
        A :class:`~affordgrasp.hands.Hand`, a registered name or a hand file.
    soft : bool
        Soft-finger contacts (torsional friction).
    metrics : bool
        Compute Φ (False: the simulation columns only).
    batch_size : int, optional
        With ``samples``: evaluate at most this many at a time (same rows).
    progress : callable, optional
        With ``samples``: ``progress(k)`` after each batch of ``k`` grasps.
    volume : bool
        Also compute the GWS volume (column ``gws_volume``; default False: the column is
        null). Not part of the paper's Φ and used by no built-in task; it costs the full
        6-D hull of every force-closure grasp.
    robust : RobustSettings or int, optional
        K perturbed re-simulations per grasp and the ``robust_*`` columns
        (:mod:`affordgrasp.robust`); None or 0: plain evaluation.

    Returns
    -------
    Evaluation
        ``.table`` (one row per grasp) and ``.timings``; ``.scores(task)`` scores a task.

    Examples
    --------
    >>> import affordgrasp as ag
    >>> result = ag.evaluate("mug", samples=20, seed=0)  # doctest: +SKIP
    >>> result.scores("pick").shape  # doctest: +SKIP
    (20,)
    """
    given = p0 is not None or use_dir is not None
    if given and samples is not None:
        raise InputError("give either samples (drawn from seed) or p0 and use_dir, not both")
    if given:
        if p0 is None or use_dir is None:
            raise InputError("p0 and use_dir go together: give both")
        return evaluate_inputs(
            obj,
            p0,
            use_dir,
            hand=hand,
            seed=-1,
            sample_start=start,
            soft=soft,
            metrics=metrics,
            volume=volume,
            robust=robust,
        )
    if samples is None:
        raise InputError("give samples (how many grasps to draw) or p0 and use_dir")
    return evaluate_samples(
        obj,
        samples,
        seed=seed,
        start=start,
        hand=hand,
        soft=soft,
        metrics=metrics,
        batch_size=batch_size,
        progress=progress,
        volume=volume,
        robust=robust,
    )
