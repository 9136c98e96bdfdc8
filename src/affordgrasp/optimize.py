"""Direct optimisation of an affordance F_T over (p0, d) in simulation (conventions: Datasets).

Beyond the paper's brute-force argmax: the cross-entropy method (CEM) searches the 8-D box
x = (p0, d) ∈ [-1, 1]^5 × [0, 1] × [-1, 1]^2 for the grasp with the largest F_T.

* Generation 0 is the run's uniform samples 0..m-1 (the same samples ``generate`` and the
  random baseline use), so CEM starts where random sampling starts.
* Each later generation is drawn from a Gaussian with a diagonal covariance, fitted to the
  elites (the best ``elite_fraction`` of the population, plus the previous elites: the
  simulation is deterministic, so keeping them is safe) and smoothed with the previous fit.
  Angles (the approach azimuth u1, the roll u3 and the use azimuth d1) wrap around; the other
  coordinates are clipped to the box.
* −∞ (a failed threshold) ranks below every finite value and never becomes an elite once a
  finite value is known. Until then the elites are the samples with the best *guidance*:
  how close the grasp came to a usable one (contacts made, ε), which leads the search
  towards the feasible region instead of sampling blindly.
* A share of every generation (``explore_fraction``, and at least half while only guidance
  leads) is drawn uniformly, so feasible regions the fit has not seen keep being found.

:func:`cem_maximize` is the method on any vectorised objective; :func:`optimize` applies it to
a task on an object and, with the same simulation budget, runs uniform random sampling.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping
from contextlib import nullcontext
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from .errors import InputError, bad_parameter
from .hands import Hand

log = logging.getLogger(__name__)

DIM = 8
LOW = np.array([-1.0, -1.0, -1.0, -1.0, -1.0, 0.0, -1.0, -1.0])
HIGH = np.ones(DIM)
WIDTH = HIGH - LOW
# u1 (azimuth, π·u1), u3 (roll, π·u3) and d1 (use azimuth) are angles: period 2 in u.
PERIODIC = np.array([True, False, True, False, False, False, True, False])

Objective = Callable[[np.ndarray], np.ndarray]
MIN_STD = 0.01  # default floor of CEM's std, as a fraction of each coordinate's range


@dataclass
class CEMState:
    """Where a CEM run stands: its sampling distribution and its elites.

    Passed back to :func:`cem_maximize` (``state=``), it continues the run: the next
    generation is drawn from this distribution and ranked together with these elites.

    Attributes
    ----------
    mean, std : (8,) float64 ndarray or None
        The Gaussian of the next generation (None: no fit yet, the next is uniform).
    elite_x : (k, 8) float64 ndarray
        The elites' inputs, best first.
    elite_v : (k,) float64 ndarray
        Their values.
    elite_g : (k,) float64 ndarray
        Their guidance (NaN without).
    """

    mean: np.ndarray | None
    std: np.ndarray | None
    elite_x: np.ndarray
    elite_v: np.ndarray
    elite_g: np.ndarray

    @property
    def best(self) -> float:
        """The best elite value (−inf when no elite is finite)."""
        finite = self.elite_v[self.elite_v > -np.inf]
        return float(finite.max()) if len(finite) else -math.inf

    def around_best(self, std: float = MIN_STD) -> CEMState:
        """The same elites, the distribution centred on the best of them.

        A run that met its best point late or alone has fitted its distribution to few,
        scattered elites (two finite elites: their midpoint); centring on the best point
        with a narrow std searches that point's neighbourhood instead.

        Parameters
        ----------
        std : float
            The std as a fraction of each coordinate's range.

        Returns
        -------
        CEMState
            Unchanged when there are no elites.
        """
        if len(self.elite_x) == 0:
            return self
        return CEMState(
            mean=np.array(self.elite_x[0], dtype=np.float64),
            std=std * WIDTH,
            elite_x=self.elite_x,
            elite_v=self.elite_v,
            elite_g=self.elite_g,
        )


@dataclass
class CEMTrace:
    """Every point CEM evaluated, in order, and what each generation did.

    Attributes
    ----------
    x : (budget, 8) float64 ndarray
        Inputs (p0 (6), d (2)).
    values : (budget,) float64 ndarray
        Objective values (−inf allowed).
    generations : list of dict
        Per generation: evaluations so far, best so far, finite fraction, mean std.
    state : CEMState or None
        The run's final distribution and elites (pass it as ``state=`` to continue the run).
    """

    x: np.ndarray
    values: np.ndarray
    generations: list[dict] = field(default_factory=list)
    state: CEMState | None = None

    @property
    def best_index(self) -> int | None:
        """Index of the best evaluation (the first of ties), None when none is finite."""
        if not np.any(self.values > -np.inf):
            return None
        return int(np.argmax(self.values))

    def best_so_far(self) -> np.ndarray:
        """The best value among the first i + 1 evaluations, for every i.

        Returns
        -------
        (budget,) float64 ndarray
            Non-decreasing; NaN counts as −inf.
        """
        return np.maximum.accumulate(np.where(np.isnan(self.values), -np.inf, self.values))


def default_population(budget: int) -> int:
    """About 20 generations, each between 32 and 1000 samples.

    Parameters
    ----------
    budget : int
        Total evaluations.

    Returns
    -------
    int
    """
    return int(np.clip(budget // 20, 32, 1000))


def _wrap(u: np.ndarray) -> np.ndarray:
    return (u + 1.0) % 2.0 - 1.0


def _fit(elites: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std of elite points (k, 8), circular on the periodic coordinates."""
    mean = elites.mean(axis=0)
    ang = np.pi * elites[:, PERIODIC]
    mean[PERIODIC] = np.arctan2(np.sin(ang).mean(axis=0), np.cos(ang).mean(axis=0)) / np.pi
    dev = elites - mean
    dev[:, PERIODIC] = _wrap(dev[:, PERIODIC])
    return mean, np.sqrt((dev**2).mean(axis=0))


def _sample(rng: np.random.Generator, mean: np.ndarray, std: np.ndarray, n: int) -> np.ndarray:
    x = mean + std * rng.standard_normal((n, DIM))
    x[:, PERIODIC] = _wrap(x[:, PERIODIC])
    return np.clip(x, LOW, HIGH)


def uniform_inputs(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform samples of the (p0, d) box.

    Parameters
    ----------
    rng : numpy.random.Generator
    n : int

    Returns
    -------
    (n, 8) float64 ndarray
        p0 in [-1, 1]^5 × [0, 1], d in [-1, 1]^2.
    """
    return LOW + WIDTH * rng.random((n, DIM))


def cem_maximize(
    objective: Objective,
    *,
    budget: int,
    seed: int = 0,
    population: int | None = None,
    elite_fraction: float = 0.1,
    smoothing: float = 0.7,
    min_std: float = MIN_STD,
    explore_fraction: float = 0.1,
    initial: np.ndarray | None = None,
    on_generation: Callable[[int], None] | None = None,
    state: CEMState | None = None,
) -> CEMTrace:
    """Maximise ``objective`` over the (p0, d) box with the cross-entropy method.

    Parameters
    ----------
    objective : callable
        (m, 8) inputs → (m,) values; −inf for infeasible, NaN counts as −inf. It may return
        (values, guidance) instead: among infeasible points, a larger guidance (finite)
        ranks first, so the search heads for the feasible region while no or few feasible
        points are known; guidance never ranks an infeasible point above a feasible.
    budget : int
        Total evaluations.
    seed : int
    population : int, optional
        Per generation (default :func:`default_population`).
    elite_fraction : float
        Share of a generation that refits the distribution.
    smoothing : float
        Weight of the new fit against the old one.
    min_std : float
        Floor of the std, as a fraction of each coordinate's range.
    explore_fraction : float
        Share of every later generation drawn uniformly from the box (at least half while
        no feasible point is known).
    initial : (m, 8) float64 ndarray, optional
        The first generation (default: uniform from ``seed``).
    on_generation : callable, optional
        Called with the number of evaluations of each generation.
    state : CEMState, optional
        Continue a run (its ``CEMTrace.state``) instead of starting one: the first
        generation is drawn from its distribution and its elites stay elites until better
        points replace them (``initial`` must then be None).

    Returns
    -------
    CEMTrace
    """
    if not isinstance(budget, int) or budget < 1:
        raise bad_parameter("budget", f"must be a positive integer, got {budget!r}")
    pop = population or default_population(budget)
    if pop < 2:
        raise InputError(f"the population must be at least 2, got {pop}")
    if not 0 < elite_fraction <= 0.5:
        raise InputError(f"elite_fraction must lie in (0, 0.5], got {elite_fraction}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xCE]))
    n_elite = max(2, math.ceil(elite_fraction * pop))
    floor = min_std * WIDTH
    xs: list[np.ndarray] = []
    vs: list[np.ndarray] = []
    generations: list[dict] = []
    if state is not None and initial is not None:
        raise InputError("give either initial (a new run) or state (a run to continue)")
    mean = std = None
    elite_x = np.empty((0, DIM))
    elite_v = np.empty(0)
    elite_g = np.empty(0)
    if state is not None:
        mean = None if state.mean is None else np.array(state.mean, dtype=np.float64)
        std = None if state.std is None else np.array(state.std, dtype=np.float64)
        elite_x = np.array(state.elite_x, dtype=np.float64).reshape(-1, DIM)
        elite_v = np.array(state.elite_v, dtype=np.float64).reshape(-1)
        elite_g = np.array(state.elite_g, dtype=np.float64).reshape(-1)
    used = 0
    while used < budget:
        m = min(pop, budget - used)
        if used == 0 and initial is not None:
            x = np.asarray(initial, dtype=np.float64)[:m]
        elif mean is None:
            x = uniform_inputs(rng, m)
        else:
            x = _sample(rng, mean, std, m)
            # A share of uniform samples keeps finding feasible regions the fit has not seen;
            # half of the generation while the fit follows guidance only (it may mislead).
            share = explore_fraction if np.any(elite_v > -np.inf) else max(explore_fraction, 0.5)
            k = int(round(share * m))
            x[:k] = uniform_inputs(rng, k)
        got = objective(x)
        v, g = got if isinstance(got, tuple) else (got, None)
        v = np.asarray(v, dtype=np.float64)
        if v.shape != (len(x),):
            raise ValueError(f"objective returned shape {v.shape} for {len(x)} inputs")
        v = np.where(np.isnan(v), -np.inf, v)
        if g is None:
            g = np.full(len(x), np.nan)  # no guidance: infeasible points never become elites
        g = np.asarray(g, dtype=np.float64)
        xs.append(x)
        vs.append(v)
        used += len(x)
        # Elites among this generation and the previous elites: finite values first (best
        # first), then the infeasible ones with the best guidance, if any.
        cx = np.concatenate([elite_x, x])
        cv = np.concatenate([elite_v, v])
        cg = np.concatenate([elite_g, g])
        finite = cv > -np.inf  # +inf, if a task gives it, is a value too; NaN is not
        # Guidance only while nothing feasible is known: it is a heuristic, the values are not.
        usable = finite | (np.isfinite(cg) & ~finite.any())
        cx, cv, cg, finite = cx[usable], cv[usable], cg[usable], finite[usable]
        order = np.lexsort((-np.nan_to_num(cg), -np.where(finite, cv, 0.0), ~finite))[:n_elite]
        elite_x, elite_v, elite_g = cx[order], cv[order], cg[order]
        if len(elite_v) >= 2:
            new_mean, new_std = _fit(elite_x)
            if mean is None:
                mean, std = new_mean, np.maximum(new_std, floor)
            else:
                step = new_mean - mean
                step[PERIODIC] = _wrap(step[PERIODIC])
                mean = mean + smoothing * step
                mean[PERIODIC] = _wrap(mean[PERIODIC])
                std = np.maximum(smoothing * new_std + (1 - smoothing) * std, floor)
        elif len(elite_v) == 1:
            # One usable point: search around it, broadly.
            mean = elite_x[0].copy()
            std = WIDTH / 4 if std is None else std
        generations.append(
            {
                "generation": len(generations),
                "evaluations": used,
                "best": float(elite_v[0]) if len(elite_v) else -math.inf,
                "finite_elites": int(np.sum(elite_v > -np.inf)),
                "finite_fraction": float(np.mean(v > -np.inf)),
                "mean_std": float(np.mean(std / WIDTH)) if std is not None else None,
            }
        )
        if on_generation is not None:
            on_generation(len(x))
    return CEMTrace(
        x=np.concatenate(xs),
        values=np.concatenate(vs),
        generations=generations,
        state=CEMState(
            mean=None if mean is None else mean.copy(),
            std=None if std is None else std.copy(),
            elite_x=elite_x.copy(),
            elite_v=elite_v.copy(),
            elite_g=elite_g.copy(),
        ),
    )


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
            ``random_fraction_at_least_cem``; ``generations``; ``elapsed_s``.
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
        }


class _Simulator:
    """Scores batches of inputs with F_T on an engine, remembering the best row."""

    def __init__(
        self, engine, task, mode, thresholds, seed, obj=None, use_points=None, robust=False
    ):
        self.engine = engine
        self.robust = robust  # rank by the rows' robust score
        self.task = task
        self.mode = mode
        self.thresholds = dict(thresholds or {})
        self.seed = seed
        self.next_sample = 0
        self.obj = obj
        self.use_points = use_points  # pairs.UsePoints: score a grasp with its best use
        self.best_use: np.ndarray | None = None

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

    def score(self, table: pa.Table) -> np.ndarray:
        from .dataset.best import task_values

        if self.use_points is not None:
            from .pairs import best_use_per_grasp, pair_scores

            scores = pair_scores(
                self.obj, table, self.use_points, self.task.name, self.mode, **self.thresholds
            )
            values, self.best_use = best_use_per_grasp(scores, table.num_rows)
            return values
        values = task_values(self.task, table, self.mode, self.thresholds, robust=self.robust)
        return np.where(np.isnan(values), -np.inf, values)

    def found(self, values: np.ndarray, table: pa.Table, offset: int) -> Found | None:
        """The best row of a scored batch; with use points, its grasp with its best use
        point, simulated once more to give the whole row."""
        best = _found(values, table, offset)
        if best is None or self.use_points is None:
            return best
        from .pipeline import evaluate_inputs

        i = int(np.argmax(values))
        d = self.use_points.use_dir[self.best_use[i]]
        rows = evaluate_inputs(self.obj, best.p0[None], d[None], seed=self.seed).table
        row = rows.to_pylist()[0]
        return Found(best.value, best.p0, np.asarray(d, dtype=np.float64), best.evaluations, row)

    def inputs(self, x: np.ndarray) -> tuple[np.ndarray, pa.Table]:
        from .dataset.engines import Job

        start = self.next_sample
        jobs = [
            Job(0, start + a, b - a, p0=x[a:b, :6].copy(), use_dir=x[a:b, 6:].copy())
            for a, b in self._split(len(x))
        ]
        self.next_sample += len(x)
        table = self._run(jobs)
        return self.score(table), table

    def seeded(self, start: int, stop: int) -> tuple[np.ndarray, pa.Table]:
        from .dataset.engines import Job

        jobs = [Job(0, start + a, b - a) for a, b in self._split(stop - start)]
        table = self._run(jobs)
        return self.score(table), table


def _found(values: np.ndarray, table: pa.Table, offset: int) -> Found | None:
    if not np.any(values > -np.inf):
        return None
    i = int(np.argmax(values))
    row = table.slice(i, 1).to_pylist()[0]
    return Found(
        value=float(values[i]),
        p0=np.asarray(row["p0"], dtype=np.float64),
        use_dir=np.asarray(row["use_dir"], dtype=np.float64),
        evaluations=offset + i + 1,
        row=row,
    )


def guidance(table: pa.Table, requires=()) -> np.ndarray:
    """How close each grasp came to a usable one.

    Contacts made, plus 100 ε, plus, for a task that reads them (``requires``), how sharp
    the use point is (3 (1 - angle / π)) and how well it discharges the swing (3 δ).
    Ranks infeasible (−∞) samples among themselves while CEM has too few feasible ones: more
    links touching and force closure make every task's thresholds likelier to pass, and
    the use terms lead the use direction towards an edge or a discharging point, which
    uniform use directions rarely hit (a knife's cutting edge: 0.1 % of them).

    Parameters
    ----------
    table : pyarrow.Table
        Evaluated rows.
    requires : iterable of str
        Metric columns the task reads.

    Returns
    -------
    (n,) float64 ndarray
    """
    n = table["n_contacts"].to_numpy().astype(np.float64)
    eps = table["epsilon"].to_numpy() if "epsilon" in table.column_names else 0.0
    g = n + 100.0 * np.nan_to_num(eps)
    names = table.column_names
    if "use_edge_angle" in requires and "use_edge_angle" in names:
        angle = np.nan_to_num(table["use_edge_angle"].to_numpy(), nan=np.pi)
        g = g + 3.0 * (1.0 - angle / np.pi)
    if "discharge" in requires and "discharge" in names:
        g = g + 3.0 * np.nan_to_num(table["discharge"].to_numpy())
    return g


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
    robust=None,
) -> OptimizationResult:
    """Maximise F_T of ``task`` on ``obj`` with CEM; also uniform random sampling, same budget.

    Parameters
    ----------
    obj : str or GraspObject
        An object spec or object.
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
        ``generate --seed`` writes; CEM's first generation is their first part, reused).
    progress : callable, optional
        ``progress(total)`` returns a context manager yielding ``advance(n)``.
    uses : int
        If > 0, each simulated grasp (of CEM and of the baseline) is scored with its best
        use point among ``uses`` uniform use directions (run ``seed + 1``), as in
        :mod:`affordgrasp.pairs`: the search then moves the grasp only, and the use point
        is found by ray casts, which cost no simulation.
    robust : RobustSettings or int, optional
        Score every grasp by its robust score (:mod:`affordgrasp.robust`: K perturbed
        copies each, so a grasp costs K + 1 simulations; ``budget`` counts grasps). Each
        grasp then keeps its own use direction (``uses`` is not applied).

    Returns
    -------
    OptimizationResult
    """
    from .dataset.engines import (
        ObjectPayload,
        RunContext,
        check_engine,
        make_engine,
        stop_on_signals,
    )
    from .grasp.pregrasp import sample_inputs
    from .hands import get_hand
    from .objects import load_object
    from .robust import robust_settings
    from .tasks import get_task

    if not isinstance(budget, int) or budget < 1:
        raise bad_parameter("budget", f"must be a positive integer, got {budget!r}")
    if isinstance(uses, bool) or not isinstance(uses, int) or uses < 0:
        raise bad_parameter("uses", f"must be a non-negative integer, got {uses!r}")
    if not isinstance(seed, int) or seed < 0:
        raise bad_parameter("seed", f"must be a non-negative integer, got {seed!r}")
    check_engine(engine, workers, address)
    task_obj = get_task(task) if isinstance(task, str) else task
    task_obj.thresholds_for(mode, **dict(thresholds or {}))  # bad mode/threshold: fail now
    resolved = load_object(obj)
    hand_model = get_hand(hand)
    pop = population or default_population(budget)
    settings = robust_settings(robust)
    if settings is not None and task_obj.name not in settings.tasks:
        raise bad_parameter(
            "robust",
            f"has no score for task {task_obj.name!r}; robust tasks: {', '.join(settings.tasks)}",
        )
    context = RunContext(
        objects=(ObjectPayload.from_object(resolved),), hand=hand_model, seed=seed, robust=settings
    )
    started = time.perf_counter()
    total = budget + (max(0, budget - min(pop, budget)) if baseline else 0)
    bar = progress(total) if progress is not None else nullcontext(lambda n: None)
    with (
        stop_on_signals(),
        make_engine(context, engine=engine, workers=workers, address=address) as eng,
        bar as adv,
    ):
        use_points = None
        if uses and settings is None:
            from .pairs import UsePoints

            use_points = UsePoints.of(resolved, sample_inputs(seed + 1, 0, uses)[1])
        sim = _Simulator(
            eng,
            task_obj,
            mode,
            thresholds,
            seed,
            resolved,
            use_points,
            robust=settings is not None,
        )
        # The first generation is the random run's first samples: evaluate them once.
        p0, d = sample_inputs(seed, 0, min(pop, budget))
        first_values, first_table = sim.seeded(0, len(p0))
        sim.next_sample = len(p0)  # CEM's own rows are numbered on from there
        adv(len(p0))
        best = {"cem": sim.found(first_values, first_table, 0)}
        calls = {"n": 0}

        def objective(x: np.ndarray) -> np.ndarray:
            calls["n"] += 1
            if calls["n"] == 1:
                return first_values, guidance(first_table, task_obj.requires)
            offset = sim.next_sample
            values, table = sim.inputs(x)
            best["cem"] = _better(best["cem"], sim.found(values, table, offset))
            return values, guidance(table, task_obj.requires)

        trace = cem_maximize(
            objective,
            budget=budget,
            seed=seed,
            population=pop,
            initial=np.concatenate([p0, d], axis=1),
            on_generation=lambda n: adv(n) if calls["n"] > 1 else None,
        )
        random_best = random_values = None
        if baseline:
            random_best = sim.found(first_values, first_table, 0)
            parts = [first_values]
            step = max(pop, 256 * eng.workers)
            for start in range(len(p0), budget, step):
                stop = min(budget, start + step)
                values, table = sim.seeded(start, stop)
                random_best = _better(random_best, sim.found(values, table, start))
                parts.append(values)
                adv(stop - start)
            random_values = np.concatenate(parts)
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
    )
