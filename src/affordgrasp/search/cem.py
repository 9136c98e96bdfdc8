"""The cross-entropy method (CEM) over the (p0, d) box, with restarts and refinement.

The one optimiser of the package: :func:`affordgrasp.search.optimize.optimize` (a task on
the simulator, on an engine) and :func:`affordgrasp.search.pairs.optimize_pairs` (grasps with
their best use point) both search with :func:`cem_search`.

CEM searches the 8-D box x = (p0, d) ∈ [-1, 1]^5 × [0, 1] × [-1, 1]^2 for the largest value:

* Generation 0 is given (a search over the simulator passes the run's uniform samples 0..m-1,
  the samples ``generate`` and the random baseline use) or drawn uniformly.
* Each later generation is drawn from a Gaussian with a diagonal covariance, fitted to the
  elites (the best ``elite_fraction`` of the population, plus the previous elites: the
  objective is deterministic, so keeping them is safe) and smoothed with the previous fit.
  Angles (the approach azimuth u1, the roll u3 and the use azimuth d1) wrap around; the other
  coordinates are clipped to the box.
* −∞ (a failed threshold) ranks below every finite value and never becomes an elite once a
  finite value is known. Until then the elites are the samples with the best *guidance*
  (:func:`affordgrasp.search.guidance.guidance`: how close a grasp came to a usable one),
  which leads the search towards the feasible region instead of sampling blindly.
* A share of every generation (``explore_fraction``, and at least half while only guidance
  leads) is drawn uniformly, so feasible regions the fit has not seen keep being found.
* :func:`cem_search` splits a budget between independent runs (restarts) and, optionally,
  a refinement that continues the best run around its best point.

Plain numpy: no simulation here; the objective is a callable over batches of inputs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, bad_parameter

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


def nearby_inputs(
    centres: np.ndarray, std: np.ndarray | float, count: int, rng: np.random.Generator
) -> np.ndarray:
    """Inputs drawn around given ones, as a generation is drawn around its fit.

    Each coordinate moves by a normal draw; the angles wrap around, the rest is clipped to
    the box (``plan`` draws its refined candidates so).

    Parameters
    ----------
    centres : (m, 8) array_like
        Points x = (p0, d) of the box.
    std : float or (8,) array_like
        The draws' standard deviation per coordinate, in its own units (0: that coordinate
        kept).
    count : int
        Draws per centre (>= 0).
    rng : numpy.random.Generator

    Returns
    -------
    (m count, 8) float64 ndarray
        Centre i's draws in rows i count .. (i + 1) count - 1.
    """
    x = np.asarray(centres, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != DIM:
        raise InputError(f"centres must have shape (m, {DIM}), got {x.shape}")
    s = np.broadcast_to(np.asarray(std, dtype=np.float64), (DIM,))
    if not (np.isfinite(s).all() and (s >= 0).all()):
        raise InputError(f"std must be finite and >= 0, got {std!r}")
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 0:
        raise InputError(f"count must be an integer >= 0, got {count!r}")
    if len(x) == 0 or count == 0:
        return np.zeros((0, DIM))
    return np.concatenate([_sample(rng, centre, s, int(count)) for centre in x])


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
    pop = default_population(budget) if population is None else population
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


def plan_runs(
    budget: int, restarts: int = 1, refine: float = 0.0, population: int | None = None
) -> tuple[list[tuple[int, int]], int]:
    """How :func:`cem_search` splits a budget: per restart its budget and population.

    Parameters
    ----------
    budget : int
        Total evaluations.
    restarts : int
        Independent runs (>= 1).
    refine : float
        Share of ``budget`` in [0, 1) kept for the refinement.
    population : int, optional
        Per generation; chosen from each run's budget (:func:`default_population`) when None.

    Returns
    -------
    runs : list of (int, int)
        (budget, population) of each restart; the budgets sum to ``budget - refinement``.
    refinement : int
        Evaluations of the refinement (0: none).

    Raises
    ------
    InputError
        For a restart count, share or budget that cannot be split.
    """
    if isinstance(restarts, bool) or not isinstance(restarts, int | np.integer) or restarts < 1:
        raise bad_parameter("restarts", f"must be a positive integer, got {restarts!r}")
    if population is not None and (
        isinstance(population, bool)
        or not isinstance(population, int | np.integer)
        or population < 2
    ):
        # Checked here, before any work: 0 must not silently mean the default.
        raise bad_parameter(
            "population", f"must be an integer >= 2 (or None for the default), got {population!r}"
        )
    if isinstance(refine, bool) or not isinstance(refine, float | int) or not 0 <= refine < 1:
        raise bad_parameter("refine", f"must be a share in [0, 1), got {refine!r}")
    n_refine = int(round(float(refine) * budget)) if isinstance(budget, int | np.integer) else 0
    if (
        isinstance(budget, bool)
        or not isinstance(budget, int | np.integer)
        or budget - n_refine < restarts
    ):
        raise bad_parameter(
            "budget", f"must be an integer >= restarts / (1 - refine), got {budget!r}"
        )
    if refine > 0 and n_refine == 0:
        raise bad_parameter(
            "refine",
            f"{refine!r} of a budget of {budget} rounds to no simulation; raise the budget "
            "or pass refine=0",
        )
    explore = int(budget) - n_refine
    runs = []
    for run in range(int(restarts)):
        run_budget = explore // int(restarts) + (run < explore % int(restarts))
        runs.append((run_budget, population or default_population(run_budget)))
    return runs, n_refine


def _run_seed(*words: int) -> int:
    return int(np.random.SeedSequence(list(words)).generate_state(1)[0])


def _rank(state: CEMState) -> tuple[float, float]:
    """A run's standing: its largest value, then the best guidance of its elites."""
    g = state.elite_g[np.isfinite(state.elite_g)]
    return state.best, float(g.max()) if len(g) else -math.inf


def cem_search(
    objective: Objective,
    *,
    budget: int,
    seed: int = 0,
    restarts: int = 1,
    refine: float = 0.0,
    population: int | None = None,
    first_generation: Callable[[int, int], np.ndarray] | None = None,
    on_generation: Callable[[int], None] | None = None,
) -> CEMTrace:
    """Maximise ``objective`` with CEM: restarts that share a budget, then a refinement.

    Parameters
    ----------
    objective : callable
        As for :func:`cem_maximize`.
    budget : int
        Total evaluations.
    seed : int
        Run 0 uses it; restart r > 0 uses a seed derived from (seed, r).
    restarts : int
        Independent CEM runs that share the budget (:func:`plan_runs`); the best of them is
        the one with the largest value. One run settles on the first good region it meets;
        several make that less likely.
    refine : float
        Share of ``budget`` in [0, 1) spent after the restarts on continuing the best of
        them (largest value; without one, the best guidance; ties: the first) around its
        best point: its elites carry on and its distribution restarts centred there with
        the narrowest std (:meth:`CEMState.around_best`).
    population : int, optional
        Per generation (default :func:`default_population` of each run's budget).
    first_generation : callable, optional
        ``first_generation(start, stop)`` gives the first generation of a run, (stop - start,
        8) inputs: run r's is ``start .. stop`` = the next block after run r - 1's (run 0:
        0 .. m), e.g. the uniform samples of a seeded run. None: drawn from each run's seed.
    on_generation : callable, optional
        Called with the number of evaluations of each generation.

    Returns
    -------
    CEMTrace
        Every evaluation of the restarts, then of the refinement, in order. With more than
        one run, each generation's record also names its ``run`` (restart index; the
        refinement is ``restarts``) and ``evaluations`` counts over the whole search. Its
        ``state`` is the refinement's, else the best run's.
    """
    runs, n_refine = plan_runs(budget, restarts, refine, population)
    traces: list[CEMTrace] = []
    first = 0
    for run, (run_budget, pop) in enumerate(runs):
        m = min(pop, run_budget)
        initial = None
        if first_generation is not None:
            initial = np.asarray(first_generation(first, first + m), dtype=np.float64)
        first += m
        traces.append(
            cem_maximize(
                objective,
                budget=run_budget,
                seed=seed if run == 0 else _run_seed(seed, run),
                population=pop,
                initial=initial,
                on_generation=on_generation,
            )
        )
    best = max(range(len(traces)), key=lambda r: _rank(traces[r].state))
    if n_refine:
        traces.append(
            cem_maximize(
                objective,
                budget=n_refine,
                seed=_run_seed(seed, len(runs), best),
                population=runs[best][1],
                state=traces[best].state.around_best(),
                on_generation=on_generation,
            )
        )
    if len(traces) == 1:
        return traces[0]
    generations = []
    done = 0
    for run, trace in enumerate(traces):
        for g in trace.generations:
            generations.append({**g, "run": run, "evaluations": done + g["evaluations"]})
        done += len(trace.values)
    return CEMTrace(
        x=np.concatenate([t.x for t in traces]),
        values=np.concatenate([t.values for t in traces]),
        generations=generations,
        state=traces[-1].state if n_refine else traces[best].state,
    )
