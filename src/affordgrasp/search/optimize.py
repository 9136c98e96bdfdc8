"""Direct optimisation of an affordance F_T over (p0, d) in simulation (conventions: Datasets).

Beyond the paper's brute-force argmax: the cross-entropy method (CEM,
:mod:`affordgrasp.search.cem`) searches the 8-D box x = (p0, d) for the grasp with the largest
F_T. :func:`optimize` applies it to a task on an object, simulating on an engine (local
processes or Ray) with the hand and the object (its mass, materials included) it is given,
and, with the same simulation budget, runs uniform random sampling:

* the first generation of CEM is the run's uniform samples 0..m-1 (the samples ``generate``
  and the random baseline use), so CEM starts where random sampling starts, and the
  baseline reuses those rows;
* with ``uses`` > 0 each grasp is scored with its best use point
  (:mod:`affordgrasp.search.pairs`), and CEM's guidance is relative to the task's thresholds
  (:func:`~affordgrasp.search.guidance.threshold_guidance`); with ``passing_uses`` the use
  points are those that pass the task's tests of the use point alone
  (:func:`~affordgrasp.search.use_points.passing_use_points`).

The method itself (``cem_search``, ``CEMState``, ``CEMTrace``...) is
:mod:`affordgrasp.search.cem`; the pair searches, brute force and optimiser, are
:mod:`affordgrasp.search.pairs`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from ..errors import bad_parameter
from ..hands import Hand
from ..robust import task_scores
from .cem import CEMTrace, cem_search, plan_runs
from .guidance import guidance
from .pairs import best_use_per_grasp, pair_scores, pair_search_guidance
from .ranking import best_index
from .use_points import UseSampling, draw_use_points

log = logging.getLogger(__name__)


# -------------------------------------------------------------------------- on the simulator


@dataclass
class Found:
    """A grasp found by a search: its F_T, inputs and full row (every column of evaluate).

    Attributes
    ----------
    value : float
        F_T.
    p0 : (6,) float64 ndarray
    use_dir : (2,) float64 ndarray
    evaluations : int
        How many simulations the search had run when it found it.
    row : dict
        The evaluated row.
    """

    value: float
    p0: np.ndarray
    use_dir: np.ndarray
    evaluations: int  # how many simulations the search had run when it found it
    row: dict

    def to_dict(self) -> dict:
        """The grasp found as JSON-ready data.

        Returns
        -------
        dict
            ``value``, ``p0``, ``use_dir``, ``found_after`` (evaluations) and ``row`` (the
            sample row without its per-contact columns).
        """
        keep = {k: v for k, v in self.row.items() if not k.startswith("contact_")}
        return {
            "value": self.value,
            "p0": self.p0.tolist(),
            "use_dir": self.use_dir.tolist(),
            "found_after": self.evaluations,
            "row": keep,
        }


@dataclass
class OptimizationResult:
    """CEM against uniform random sampling at the same simulation budget.

    Attributes
    ----------
    object, task, mode : str
    budget, seed : int
    cem, random : Found or None
        The best grasp of each method (None: no finite F_T).
    cem_trace : CEMTrace
    random_values : (budget,) float64 ndarray or None
        F_T of the random samples (None without the baseline).
    elapsed_s : float
        Wall time, s.
    use_sampling : UseSampling or None
        How the use points were drawn (None without use points).
    """

    object: str
    task: str
    mode: str
    budget: int
    seed: int
    cem: Found | None
    random: Found | None
    cem_trace: CEMTrace
    random_values: np.ndarray | None
    elapsed_s: float
    use_sampling: UseSampling | None = None

    @property
    def cem_evaluations_to_match_random(self) -> int | None:
        """Simulations CEM needed to reach random sampling's best (None: never)."""
        if self.random is None:
            return 1 if self.cem is not None else None
        reached = np.nonzero(self.cem_trace.best_so_far() >= self.random.value)[0]
        return int(reached[0]) + 1 if len(reached) else None

    @property
    def random_fraction_at_least_cem(self) -> float | None:
        """Fraction of the random samples at least as good as CEM's best."""
        if self.random_values is None or self.cem is None:
            return None
        return float(np.mean(self.random_values >= self.cem.value))

    def to_dict(self) -> dict:
        """The result as JSON-ready data (``optimize --json``).

        Returns
        -------
        dict
            ``object``, ``task``, ``mode``, ``budget``, ``seed``; ``cem`` and ``random``
            (:meth:`Found.to_dict` or None); ``cem_finite`` and ``random_finite`` (finite
            evaluations); ``cem_evaluations_to_match_random``,
            ``random_fraction_at_least_cem``; ``generations``; ``elapsed_s``;
            ``use_points`` (:meth:`UseSampling.to_dict`, or None without use points).
        """
        return {
            "object": self.object,
            "task": self.task,
            "mode": self.mode,
            "budget": self.budget,
            "seed": self.seed,
            "cem": self.cem.to_dict() if self.cem else None,
            "random": self.random.to_dict() if self.random else None,
            "cem_finite": int(np.sum(self.cem_trace.values > -np.inf)),
            "random_finite": (
                int(np.sum(self.random_values > -np.inf))
                if self.random_values is not None
                else None
            ),
            "cem_evaluations_to_match_random": self.cem_evaluations_to_match_random,
            "random_fraction_at_least_cem": self.random_fraction_at_least_cem,
            "generations": self.cem_trace.generations,
            "elapsed_s": self.elapsed_s,
            "use_points": self.use_sampling.to_dict() if self.use_sampling else None,
        }


class _Simulator:
    """Scores batches of inputs with F_T on an engine.

    Every simulation, on the engine and again for a winner's full row, uses the search's
    hand and object (its mass, materials included).
    """

    def __init__(
        self, engine, task, mode, thresholds, seed, obj, hand, use_points=None, robust=False
    ):
        self.engine = engine
        self.robust = robust  # rank by the rows' robust score
        self.task = task
        self.mode = mode
        self.thresholds = dict(thresholds or {})
        self.seed = seed
        self.next_sample = 0
        self.obj = obj
        self.hand = hand
        self.use_points = use_points  # UsePoints: score a grasp with its best use

    def _run(self, jobs) -> pa.Table:
        handles = [self.engine.submit(j) for j in jobs]
        tables = {}
        pending = list(handles)
        while pending:
            for h in self.engine.wait(pending):
                tables[h] = self.engine.result(h)
                pending.remove(h)
        return pa.concat_tables([tables[h] for h in handles])

    def _split(self, n: int) -> list[tuple[int, int]]:
        parts = max(1, min(n, 2 * self.engine.workers))
        bounds = np.linspace(0, n, parts + 1).astype(int)
        return [(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]

    def score(self, table: pa.Table) -> _Scored:
        """F_T of every row (with use points: with its best use point)."""
        if self.use_points is not None:
            scores = pair_scores(
                self.obj, table, self.use_points, self.task.name, self.mode, **self.thresholds
            )
            values, use = best_use_per_grasp(scores, table.num_rows)
            return _Scored(values, table, use)
        values = task_scores(self.task, table, self.mode, self.thresholds, robust=self.robust)
        return _Scored(np.where(np.isnan(values), -np.inf, values), table)

    def found(self, scored: _Scored, offset: int) -> Found | None:
        """The best row of a scored batch; with use points, its grasp with its best use
        point, simulated once more (same hand, same object) to give the whole row."""
        i = best_index(scored.values)
        if i is None:
            return None
        row = scored.table.slice(i, 1).to_pylist()[0]
        p0 = np.asarray(row["p0"], dtype=np.float64)
        d = np.asarray(row["use_dir"], dtype=np.float64)
        if self.use_points is not None:
            from ..pipeline import evaluate_inputs

            d = np.asarray(self.use_points.use_dir[scored.use[i]], dtype=np.float64)
            again = evaluate_inputs(self.obj, p0[None], d[None], hand=self.hand, seed=self.seed)
            row = again.table.to_pylist()[0]
        return Found(float(scored.values[i]), p0, d, offset + i + 1, row)

    def inputs(self, x: np.ndarray) -> _Scored:
        """Simulate and score given inputs (rows numbered on from the last)."""
        from ..dataset.jobs import Job

        start = self.next_sample
        jobs = [
            Job(0, start + a, b - a, p0=x[a:b, :6].copy(), use_dir=x[a:b, 6:].copy())
            for a, b in self._split(len(x))
        ]
        self.next_sample += len(x)
        return self.score(self._run(jobs))

    def seeded(self, start: int, stop: int) -> _Scored:
        """Simulate and score samples ``start .. stop - 1`` of the run's seed."""
        from ..dataset.jobs import Job

        jobs = [Job(0, start + a, b - a) for a, b in self._split(stop - start)]
        self.next_sample = max(self.next_sample, stop)  # inputs() rows are numbered on
        return self.score(self._run(jobs))


@dataclass(frozen=True)
class _Scored:
    """A simulated batch: its rows, F_T and (with use points) each grasp's best use index."""

    values: np.ndarray
    table: pa.Table
    use: np.ndarray | None = None


def _better(a: Found | None, b: Found | None) -> Found | None:
    if a is None:
        return b
    if b is None:
        return a
    return b if b.value > a.value else a


def optimize(
    obj,
    task: str,
    *,
    mode: str = "default",
    budget: int = 20000,
    seed: int = 0,
    thresholds: Mapping[str, float] | None = None,
    hand: Hand | str = "barrett",
    workers: int | None = None,
    engine: str = "local",
    address: str | None = None,
    population: int | None = None,
    baseline: bool = True,
    progress=None,
    uses: int = 0,
    restarts: int = 1,
    refine: float = 0.0,
    robust=None,
    passing_uses: bool = False,
) -> OptimizationResult:
    """Maximise F_T of ``task`` on ``obj`` with CEM; also uniform random sampling, same budget.

    Parameters
    ----------
    obj : str or GraspObject
        An object spec or object (a resolved object keeps its mass, e.g. its materials).
    task : str
        A registered task.
    mode : str
        Threshold mode.
    budget : int
        Simulations for each method.
    seed : int
    thresholds : mapping of str to float, optional
        Threshold values that replace the mode's.
    hand : Hand or str
        The hand of every simulation, the winners' rows included.
    workers : int, optional
        Simulation processes.
    engine : str
        ``"local"`` or ``"ray"``.
    address : str, optional
        Ray cluster address.
    population : int, optional
        CEM population per generation.
    baseline : bool
        Also run random sampling (samples 0..budget-1 of the run ``seed``, the rows
        ``generate --seed --streams shared`` writes; the first generation of each CEM run
        is the next part of them, reused).
    progress : callable, optional
        ``progress(total)`` returns a context manager yielding ``advance(n)``.
    uses : int
        If > 0, each simulated grasp (of CEM and of the baseline) is scored with its best
        use point among ``uses`` use points drawn by surface area (run ``seed + 1``), as in
        :mod:`affordgrasp.search.pairs`: the search then moves the grasp only, and the use
        point is found by ray casts, which cost no simulation. CEM's guidance is then relative
        to the task's thresholds (:func:`~affordgrasp.search.guidance.threshold_guidance`).
    restarts, refine
        Independent CEM runs sharing the budget, and the share of it that continues the
        best of them (:func:`affordgrasp.search.cem.cem_search`); 1 and 0: one run.
    robust : RobustSettings or int, optional
        Score every grasp by its robust score (:mod:`affordgrasp.robust`: K perturbed
        copies each, so a grasp costs K + 1 simulations; ``budget`` counts grasps). Each
        grasp then keeps its own use direction (``uses`` is not applied).
    passing_uses : bool
        With ``uses``: the use points are
        :func:`~affordgrasp.search.use_points.passing_use_points` (drawn until ``uses`` pass
        the task's tests of the use point alone) instead of the plain sample.

    Returns
    -------
    OptimizationResult
    """
    from ..dataset.jobs import ObjectPayload, RunContext
    from ..grasp.pregrasp import sample_inputs
    from ..hands import get_hand
    from ..objects import load_object
    from ..robust import robust_settings
    from ..runtime.engines import check_engine, make_engine
    from ..runtime.interrupts import stop_on_signals
    from ..tasks import get_task

    if not isinstance(budget, int) or budget < 1:
        raise bad_parameter("budget", f"must be a positive integer, got {budget!r}")
    if isinstance(uses, bool) or not isinstance(uses, int) or uses < 0:
        raise bad_parameter("uses", f"must be a non-negative integer, got {uses!r}")
    if not isinstance(seed, int) or seed < 0:
        raise bad_parameter("seed", f"must be a non-negative integer, got {seed!r}")
    runs, _ = plan_runs(budget, restarts, refine, population)  # bad split: fail now
    check_engine(engine, workers, address)
    task_obj = get_task(task) if isinstance(task, str) else task
    task_obj.thresholds_for(mode, **dict(thresholds or {}))  # bad mode/threshold: fail now
    resolved = load_object(obj)
    hand_model = get_hand(hand)
    settings = robust_settings(robust)
    if settings is not None and not settings.scores(task_obj):
        raise bad_parameter(
            "robust",
            f"has no score for task {task_obj.name!r}; robust tasks: {', '.join(settings.tasks)}",
        )
    context = RunContext(
        objects=(ObjectPayload.from_object(resolved),), hand=hand_model, seed=seed, robust=settings
    )
    started = time.perf_counter()
    # The runs' first generations are samples 0..seeded-1 of the run: the baseline reuses them.
    seeded = sum(min(pop, b) for b, pop in runs)
    total = budget + (max(0, budget - seeded) if baseline else 0)
    bar = progress(total) if progress is not None else nullcontext(lambda n: None)
    with (
        stop_on_signals(),
        make_engine(context, engine=engine, workers=workers, address=address) as eng,
        bar as adv,
    ):
        use_points = sampling = None
        if uses and settings is None:
            use_points, sampling = draw_use_points(
                resolved, task_obj, uses, seed + 1, mode, dict(thresholds or {}), None, passing_uses
            )
        sim = _Simulator(
            eng,
            task_obj,
            mode,
            thresholds,
            seed,
            resolved,
            hand_model,
            use_points,
            robust=settings is not None,
        )
        first_blocks: list[tuple[int, int]] = []  # first generations still to simulate
        reused: list[tuple[int, _Scored]] = []  # (start, batch) of the seeded samples
        best: dict[str, Found | None] = {"cem": None}
        done = {"n": 0}  # simulations CEM has run

        def first_generation(start: int, stop: int) -> np.ndarray:
            first_blocks.append((start, stop))
            return np.concatenate(sample_inputs(seed, start, stop), axis=1)

        def objective(x: np.ndarray):
            if (
                first_blocks
            ):  # a run's first generation: seeded samples, as generate --streams shared draws
                start, stop = first_blocks.pop(0)
                scored = sim.seeded(start, stop)
                reused.append((start, scored))
            else:
                scored = sim.inputs(x)
            adv(len(x))
            best["cem"] = _better(best["cem"], sim.found(scored, done["n"]))
            done["n"] += len(x)
            if use_points is not None:  # pairs: the rows' own use points are not scored
                return scored.values, pair_search_guidance(
                    resolved, scored.table, task_obj, mode, dict(thresholds or {}), use_points
                )
            return scored.values, guidance(scored.table, task_obj.requires)

        trace = cem_search(
            objective,
            budget=budget,
            seed=seed,
            restarts=restarts,
            refine=refine,
            population=population,
            first_generation=first_generation,
        )
        random_best = random_values = None
        if baseline:
            parts = []
            for start, scored in reused:
                random_best = _better(random_best, sim.found(scored, start))
                parts.append(scored.values)
            pop = runs[0][1]
            step = max(pop, 256 * eng.workers)
            for start in range(seeded, budget, step):
                stop = min(budget, start + step)
                scored = sim.seeded(start, stop)
                random_best = _better(random_best, sim.found(scored, start))
                parts.append(scored.values)
                adv(stop - start)
            random_values = np.concatenate(parts)[:budget]
    return OptimizationResult(
        object=resolved.name,
        task=task,
        mode=mode,
        budget=budget,
        seed=seed,
        cem=best["cem"],
        random=random_best,
        cem_trace=trace,
        random_values=random_values,
        elapsed_s=time.perf_counter() - started,
        use_sampling=sampling,
    )
