"""The argmax of a task over grasps × use points (paper §IV-C, conventions: Datasets).

The paper maximises F_T over (G, U): the grasp and the use point are independent inputs
(G = GP(p0, O) depends only on p0, U = DM(d, O) only on d). A dataset row pairs one p0
with one d, so a row is a candidate for ``beat`` or ``cut`` only when *both* are good: a
robust grasp (1-15 % of uniform p0 on the built-in families) and a use point at the
right spot (δ ≥ 0.95: about 1.5 % of uniform d; a knife's cutting edge: 0.1 %). On 4000
rows that is 0.01-1 expected candidate.

This module scores every simulated grasp with every sampled use point instead: n
simulations and m ray casts give n × m pairs. The metrics split cleanly:

* per grasp (computed once, by the simulation of its row): ε, GWS volume, E_h, I;
* per use point (one ray cast): U, its normal, U_g and the edge angle;
* per pair: δ (closed form), and the LPs E_i and U_τ, which need the grasp's contacts.

A pair's metrics are exactly those :func:`affordgrasp.pipeline.evaluate_inputs` computes for the
row (p0 of the grasp, d of the use point); the tests check it. Pairs that the task rejects
on the cheap metrics alone are skipped before the LPs: the screen evaluates the task with
the most favourable U_τ (+∞... a large value) and E_i (0), so it is exact for tasks that
improve with U_τ and with 1 / E_i and fail only through thresholds, as every built-in task
does; a task for which that is not true can pass ``screen=False``.

Two searches share one parameter list (:class:`PairSearchSettings`) and one result
(:class:`PairSearch`) and differ by strategy only: :func:`best_pairs` scores every grasp of
a sample (or of evaluated rows), :func:`optimize_pairs` moves the grasps with the
cross-entropy method. Either scores the plain sample of use points by area or those that
pass the task's tests of the use point alone (:mod:`affordgrasp.search.use_points`).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa
from numba import njit

from ..columns import GRASP_METRICS, USE_METRICS
from ..grasp.pregrasp import sample_inputs
from ..hands import Hand
from ..metrics.cones import wrench_matrix_kernel
from ..metrics.effort import impact_effort, impact_effort_kernel, use_wrench
from ..metrics.epsilon_hand import epsilon_hand
from ..metrics.hand_placement import contact_thickness, contact_width
from ..metrics.lp import OPTIMAL
from ..metrics.transmission import use_force, use_force_kernel
from ..objects import GraspObject, load_object
from ..pipeline import evaluate_inputs, evaluate_samples
from ..tasks import MetricColumns, get_task
from ..tasks.probability import task_probability
from .cem import cem_search, plan_runs
from .guidance import USE_ONLY, guidance, pair_geometry, swing_alignment, threshold_guidance
from .ranking import TopRows, top_indices
from .use_points import UsePoints, UseSampling, draw_use_points

log = logging.getLogger(__name__)

GRASP_COLUMNS = GRASP_METRICS
# columns that depend on the use point: a task that reads none of them scores a grasp the
# same with every use point, so one use point per grasp is enough
USE_COLUMNS = frozenset(USE_METRICS)
# grasp columns that tables evaluated by earlier versions lack (computed from the contacts)
_LATER_GRASP_COLUMNS = frozenset({"contact_thickness", "contact_width", "epsilon_hand"})
# most favourable values of the LP metrics, for the screen
_SCREEN_FORCE = 1e12
_SCREEN_IMPACT = 0.0
# a probability task (never -inf): the LPs of each grasp's _SCREEN_TOP use points with the
# largest screened value (a task probability's model rises with U_τ and 1 / E_i, so the
# screen is its most favourable value; the best use point of a grasp is among them unless
# the LPs reorder more than _SCREEN_TOP of its use points)
_SCREEN_TOP = 8
# a probability task that reads the use point scores the pairs of this many grasps per call:
# those most likely to hold the tool (p_pick)
PAIR_GRASPS = 512
# pairs screened at a time (bounds the memory of a search over G × U)
_BLOCK_PAIRS = 1 << 20


@njit(cache=True)
def pair_lp_metrics(points, normals, mu, offsets, center, grasp, use_point, use_normal, axis):
    """E_i and U_τ of pairs (grasp[i], use i), compiled.

    Parameters
    ----------
    points, normals : (K, 3) float64 ndarray
        Contacts of all grasps (m; outward unit normals), grasp g owning rows
        ``offsets[g]:offsets[g + 1]``.
    mu : (K,) float64 ndarray
    offsets : (G + 1,) int64 ndarray
    center : (3,) float64 ndarray
        Centre of mass, m.
    grasp : (p,) int64 ndarray
        Grasp index of each pair.
    use_point, use_normal, axis : (p, 3) float64 ndarray
        Use point (m), its outward unit normal and the grasp's unit wrist axis.

    Returns
    -------
    impact : (p,) float64 ndarray
        E_i, N per N·m.
    force : (p,) float64 ndarray
        U_τ, N.
    redo : (p,) bool ndarray
        A compiled LP gave up (the caller recomputes with HiGHS).
    """
    p = grasp.shape[0]
    impact = np.empty(p)
    force = np.empty(p)
    redo = np.zeros(p, dtype=np.bool_)
    for i in range(p):
        g = grasp[i]
        s = offsets[g]
        e = offsets[g + 1]
        W = wrench_matrix_kernel(
            np.ascontiguousarray(points[s:e]),
            np.ascontiguousarray(normals[s:e]),
            np.ascontiguousarray(mu[s:e]),
            center,
            1.0,
            False,
        )
        w_use = use_wrench(use_point[i], use_normal[i], center)
        ok, impact[i] = impact_effort_kernel(W, w_use, axis[i])
        status, force[i] = use_force_kernel(W, w_use, e - s)
        redo[i] = (not ok) or status != OPTIMAL
    return impact, force, redo


def _contacts(table: pa.Table, rows: np.ndarray):
    pts = table.column("contact_points").to_pylist()
    nrm = table.column("contact_normals").to_pylist()
    mus = table.column("contact_mu").to_pylist()
    chunks = [
        (np.asarray(pts[r], float).reshape(-1, 3), np.asarray(nrm[r], float).reshape(-1, 3))
        for r in rows
    ]
    counts = np.array([len(c[0]) for c in chunks], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    if counts.sum():
        points = np.ascontiguousarray(np.concatenate([c[0] for c in chunks]))
        normals = np.ascontiguousarray(np.concatenate([c[1] for c in chunks]))
        mu = np.ascontiguousarray(np.concatenate([np.asarray(mus[r], float) for r in rows]))
    else:
        points, normals, mu = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    return points, normals, mu, offsets


def _top_per_grasp(values: np.ndarray, uses: int, k: int) -> np.ndarray:
    """Mask of the ``k`` largest of each grasp's ``uses`` consecutive values (grasp-major)."""
    v = np.nan_to_num(values.reshape(-1, uses), nan=-np.inf)
    keep = np.zeros(v.shape, dtype=bool)
    if uses <= k:
        keep[:] = True
    else:
        top = np.argpartition(-v, k - 1, axis=1)[:, :k]
        np.put_along_axis(keep, top, True, axis=1)
    return keep.ravel()


def pair_scores(
    obj: GraspObject,
    grasps: pa.Table,
    uses: UsePoints,
    task: str,
    mode: str = "default",
    *,
    screen: bool = True,
    **overrides: float,
) -> dict[str, np.ndarray]:
    """F_T and Φ of every pair (grasp row, use point) that the screen keeps.

    Parameters
    ----------
    obj : GraspObject
    grasps : pyarrow.Table
        Evaluated rows (``evaluate``/``evaluate_samples`` output, metrics included).
    uses : UsePoints
        The use points.
    task : str
        A registered task.
    mode : str
        Threshold mode.
    screen : bool
        Skip the LPs of pairs that the grasp-only metrics already rule out.
    **overrides : float
        Threshold values that replace the mode's.

    Returns
    -------
    dict of str to ndarray
        ``grasp`` (row in ``grasps``), ``use`` (index in ``uses``), ``value`` (F_T), and the
        metric columns of the pairs (float64), for the kept pairs only.
    """
    obj = load_object(obj)
    t = get_task(task)
    n, m = grasps.num_rows, len(uses.triangle)
    names = set(grasps.column_names)
    col = {
        c: grasps.column(c).to_numpy(zero_copy_only=False)
        for c in GRASP_COLUMNS
        if c in names or c not in _LATER_GRASP_COLUMNS
    }
    wrist_point = np.asarray(grasps.column("wrist_point").to_pylist(), float).reshape(n, 3)
    wrist_axis = np.asarray(grasps.column("wrist_axis").to_pylist(), float).reshape(n, 3)
    has_contacts = grasps.column("n_contacts").to_numpy() > 0
    hit = uses.triangle >= 0
    use_rows = np.flatnonzero(hit)
    if not USE_COLUMNS & set(t.requires):
        use_rows = use_rows[:1]
    # grasps in blocks of at most _BLOCK_PAIRS pairs: the screened pairs are a small part of
    # G × U, so memory follows them, not the product (the same pairs in the same order)
    with_contacts = np.flatnonzero(has_contacts)
    all_points, all_normals, all_mu, all_offsets = _contacts(grasps, np.arange(n))
    # rows evaluated before these columns existed: computed from their contacts
    if "contact_thickness" not in col:
        col["contact_thickness"] = contact_thickness(
            obj.mesh_data, all_points, all_normals, all_offsets
        )
    if "epsilon_hand" not in col:
        col["epsilon_hand"] = epsilon_hand(
            all_points,
            all_normals,
            all_mu,
            all_offsets,
            obj.mass.center_of_mass,
            obj.mass.r_max,
            col["epsilon"],
        )
    if "contact_width" not in col:
        col["contact_width"] = contact_width(obj.mesh_data, all_points, all_normals, all_offsets)
    if t.probability and USE_COLUMNS & set(t.requires) and len(with_contacts) > PAIR_GRASPS:
        # a grasp that does not hold the tool strikes or cuts with nothing: the pairs of the
        # PAIR_GRASPS grasps most likely to hold it (p_pick), in their original order
        p_pick = task_probability("pick", MetricColumns({c: col[c] for c in GRASP_COLUMNS}))
        best = np.argsort(-p_pick[with_contacts], kind="stable")[:PAIR_GRASPS]
        with_contacts = np.sort(with_contacts[best])
    step = max(1, _BLOCK_PAIRS // max(len(use_rows), 1))
    blocks = []
    for first in range(0, len(with_contacts), step):
        gi, ui = np.meshgrid(with_contacts[first : first + step], use_rows, indexing="ij")
        gi, ui = gi.ravel(), ui.ravel()
        cols = {c: col[c][gi] for c in GRASP_COLUMNS}
        for c in USE_ONLY:
            cols[c] = getattr(uses, c)[ui]
        cols.update(
            pair_geometry(obj, uses, ui, gi, wrist_point, wrist_axis, all_points, all_offsets)
        )
        if screen and len(gi):
            cols["use_force"] = np.full(len(gi), _SCREEN_FORCE)
            cols["impact_effort"] = np.full(len(gi), _SCREEN_IMPACT)
            screened = t.evaluate(MetricColumns(cols), mode, **overrides)
            if t.probability:  # never -inf: each grasp's most promising use points
                keep = _top_per_grasp(screened, len(use_rows), _SCREEN_TOP)
            else:
                keep = screened > -np.inf
            gi, ui = gi[keep], ui[keep]
            cols = {k: v[keep] for k, v in cols.items()}
        blocks.append((gi, ui, cols))
    if blocks:
        gi = np.concatenate([b[0] for b in blocks])
        ui = np.concatenate([b[1] for b in blocks])
        cols = {k: np.concatenate([b[2][k] for b in blocks]) for k in blocks[0][2]}
    else:
        gi = ui = np.zeros(0, dtype=np.int64)
        cols = {c: np.zeros(0) for c in (*GRASP_COLUMNS, *USE_COLUMNS)}
    log.info("%s on %s: %d of %d pairs need the LPs", task, obj.name, len(gi), n * m)
    rows = np.unique(gi)
    points, normals, mu, offsets = _contacts(grasps, rows)
    local = np.searchsorted(rows, gi)
    # a writable copy: one kernel signature in process and in workers (see metrics.phi)
    center = np.array(obj.mass.center_of_mass, dtype=np.float64)
    impact, force, redo = pair_lp_metrics(
        points,
        normals,
        mu,
        offsets,
        center,
        local.astype(np.int64),
        np.ascontiguousarray(uses.point[ui]),
        np.ascontiguousarray(uses.normal[ui]),
        np.ascontiguousarray(wrist_axis[gi]),
    )
    for i in np.flatnonzero(redo):
        from ..metrics.contacts import ContactSet

        g = local[i]
        s, e = offsets[g], offsets[g + 1]
        cs = ContactSet.from_arrays(points[s:e], normals[s:e], mu[s:e])
        U, N, a = uses.point[ui[i]], uses.normal[ui[i]], wrist_axis[gi[i]]
        impact[i] = impact_effort(cs, center, U, N, a, backend="highs")
        force[i] = use_force(cs, center, U, N, backend="highs")
    cols["impact_effort"] = impact
    cols["use_force"] = force
    values = t.evaluate(MetricColumns(cols), mode, **overrides) if len(gi) else np.zeros(0)
    return {"grasp": gi, "use": ui, "value": np.where(np.isnan(values), -np.inf, values), **cols}


def pair_guidance(rows: pa.Table, task, mode, overrides, uses: UsePoints, eps_column=()):
    """A pair search's guidance: :func:`~affordgrasp.search.guidance.guidance` of the rows
    plus 3 × their :func:`~affordgrasp.search.guidance.swing_alignment` with ``uses``
    (grasps with contacts only).

    Parameters
    ----------
    rows : pyarrow.Table
        The simulated grasps (evaluated rows; their own use points are not read).
    task : Task
        The task searched.
    mode : str
        Threshold mode.
    overrides : mapping of str to float
        Threshold values that replace the mode's.
    uses : UsePoints
        The search's use points.
    eps_column : tuple of str
        ``("epsilon_hand",)`` to rank by it instead of ``epsilon``.

    Returns
    -------
    (n,) float64 ndarray
    """
    n = rows.num_rows
    g = guidance(rows, eps_column)
    if n:
        wp = np.asarray(rows.column("wrist_point").to_pylist(), float).reshape(n, 3)
        wa = np.asarray(rows.column("wrist_axis").to_pylist(), float).reshape(n, 3)
        touched = rows.column("n_contacts").to_numpy() > 0
        align = np.nan_to_num(swing_alignment(task, mode, overrides, uses, wp, wa))
        g = g + 3.0 * np.where(touched, align, 0.0)
    return g


def pair_search_guidance(obj, rows, task, mode, overrides, uses, thresholds=True):
    """The guidance of a pair search's grasps while none is feasible.

    Relative to the task's thresholds (:func:`~affordgrasp.search.guidance.threshold_guidance`:
    each test of the task a hinge at its threshold); for a task without known threshold tests,
    or with ``thresholds`` False, :func:`pair_guidance` (contacts, ε and the use terms).

    Parameters
    ----------
    obj : GraspObject
    rows : pyarrow.Table
        The simulated grasps (their own use points are not read).
    task : Task
    mode : str
    overrides : mapping of str to float
    uses : UsePoints
        The search's use points.
    thresholds : bool

    Returns
    -------
    (n,) float64 ndarray
    """
    g = threshold_guidance(obj, rows, task, mode, overrides, uses) if thresholds else None
    if g is not None:
        return g
    eps_column = tuple(c for c in ("epsilon_hand",) if c in task.requires)
    return pair_guidance(rows, task, mode, overrides, uses, eps_column)


@dataclass(frozen=True)
class PairSearchSettings:
    """What a pair search looks for, and with what budget: the one parameter list of
    :func:`best_pairs` (brute force) and :func:`optimize_pairs` (the cross-entropy method).

    Attributes
    ----------
    task : str
        A registered task.
    mode : str
        Threshold mode.
    thresholds : mapping of str to float
        Threshold values that replace the mode's.
    uses : int
        Use points scored, drawn from run ``seed + 1`` (independent of the rows' own d).
    seed : int
        Run seed of the grasps (the brute force's samples, the optimiser's first generation
        and stream); the top pairs are re-simulated with it.
    top : int
        Distinct pairs returned (with ``per_grasp``, distinct grasps).
    hand : str or Hand
        The hand of every simulation.
    passing_uses : bool
        Score :func:`~affordgrasp.search.use_points.passing_use_points` (drawn until
        ``uses`` pass the task's tests of the use point alone) instead of the plain sample
        by area. The best of many candidates then also finds the few use points that pass
        those tests off the working part (a thin knife spine, a hammer's claw), where F_T
        can be larger (docs/validation.md §7, "Searches aimed at the task's tests").
    max_draws : int, optional
        With ``passing_uses``: use points drawn at most (default ``16 uses``).
    grasps : int
        Brute force: uniform samples 0..grasps-1 of run ``seed`` simulated when no
        evaluated rows are given.
    per_grasp : bool
        Brute force: the top ``top`` distinct grasps, each with its best use point (F_T of
        a grasp is its maximum over U), instead of the top pairs (which may repeat one
        grasp with several use points).
    budget : int
        Optimiser: simulations.
    population : int, optional
        Optimiser: CEM population; chosen from each run's budget when None.
    restarts : int
        Optimiser: independent CEM runs that share the budget (each ``budget // restarts``
        simulations, its own first generation and random stream); the pairs met by all of
        them are ranked together. One run settles on the first good region it meets (on a
        hammer, a hold of the head with 5× the hold effort of the best hold on the handle);
        several runs make that less likely.
    refine : float
        Optimiser: share of ``budget`` (in [0, 1)) spent after the restarts on continuing
        the best of them (the run with the largest F_T; without one, the best guidance)
        around its best point: its elites carry on and its distribution restarts centred
        there with CEM's narrowest std
        (:meth:`affordgrasp.search.cem.CEMState.around_best`). The restarts share the rest.
        A run can meet its best point alone (its fit to two scattered elites then samples
        between them); refining finds that point's neighbours, so the top pairs are
        neighbours of the best pair rather than the best of weaker regions that other
        restarts settled in.
    threshold_guide : bool
        Optimiser: while no grasp is feasible, rank the grasps by the guidance relative to
        the task's thresholds (:func:`pair_search_guidance`), so that CEM climbs towards
        passing every test at once (ε-robust, the hand off the working part, a swing that
        meets the face) rather than towards more contacts; False: :func:`pair_guidance`.
    """

    task: str
    mode: str = "default"
    thresholds: Mapping[str, float] = field(default_factory=dict)
    uses: int = 2000
    seed: int = 0
    top: int = 10
    hand: Hand | str = "barrett"
    passing_uses: bool = False
    max_draws: int | None = None
    grasps: int = 4000
    per_grasp: bool = False
    budget: int = 2000
    population: int | None = None
    restarts: int = 1
    refine: float = 0.0
    threshold_guide: bool = False


@dataclass(frozen=True)
class PairSearch:
    """Result of a pair search (:func:`best_pairs`, :func:`optimize_pairs`).

    Attributes
    ----------
    table : pyarrow.Table
        The top pairs as ordinary evaluated rows (p0 of the grasp, d of the use point), best
        first, with a ``value`` column.
    grasps : int
        Grasps simulated (or given, for the brute force).
    candidates : int
        Pairs with a finite F_T.
    lp_pairs : int
        Pairs that needed the LPs.
    use_points : UsePoints
        The use points scored.
    sampling : UseSampling
        How they were drawn.
    """

    table: pa.Table
    grasps: int
    candidates: int
    lp_pairs: int
    use_points: UsePoints
    sampling: UseSampling

    @property
    def uses(self) -> int:
        """Use points scored."""
        return len(self.use_points.triangle)


def _start(obj, settings: PairSearchSettings, optimiser: bool):
    """The object, the task and the use points of a search; bad settings fail here."""
    obj = load_object(obj)
    task = get_task(settings.task)
    task.thresholds_for(settings.mode, **settings.thresholds)  # bad mode or threshold
    if optimiser:  # a budget that cannot be split: too
        plan_runs(settings.budget, settings.restarts, settings.refine, settings.population)
    use, sampling = draw_use_points(
        obj,
        task,
        settings.uses,
        settings.seed + 1,
        settings.mode,
        dict(settings.thresholds),
        settings.max_draws,
        settings.passing_uses,
    )
    return obj, task, use, sampling


def best_pairs(
    obj, settings: PairSearchSettings, grasp_table: pa.Table | None = None
) -> PairSearch:
    """Brute force: the top pairs of a task over grasps × use points.

    The grasps are the samples 0..``grasps``-1 of run ``seed`` (as ``generate --streams
    shared`` draws them), or the evaluated rows of ``grasp_table``; every one is scored with
    every use point (:func:`pair_scores`). The top pairs are re-simulated with
    :func:`affordgrasp.pipeline.evaluate_inputs`, so the returned rows carry every column of
    the dataset schema; a pair's value is recomputed on that row.

    Parameters
    ----------
    obj : GraspObject or str
        The object or its spec.
    settings : PairSearchSettings
        The task, thresholds, use points, ``top``, ``grasps`` and ``per_grasp``.
    grasp_table : pyarrow.Table, optional
        Evaluated rows to reuse instead of simulating.

    Returns
    -------
    PairSearch
    """
    s = settings
    obj, _, use, sampling = _start(obj, s, optimiser=False)
    if grasp_table is None:
        # ε only: the search never reads the GWS volume; the returned rows carry it
        grasp_table = evaluate_samples(obj, s.grasps, seed=s.seed, hand=s.hand, volume=False).table
    scores = pair_scores(obj, grasp_table, use, s.task, s.mode, **s.thresholds)
    # The one ranker of the package: highest F_T first, ties to the smaller grasp, then use.
    values = scores["value"]
    best = TopRows(s.top, 2)
    if s.per_grasp:  # each grasp once, with its best use point (ties: the lowest use index)
        best_value, best_use = best_use_per_grasp(scores, grasp_table.num_rows)
        best.add(best_value, np.arange(grasp_table.num_rows), best_use)
        candidates = int(np.count_nonzero(values > -np.inf))
    else:
        candidates = best.add(values, scores["grasp"], scores["use"])
    grasp_index, use_index = best.keys
    p0 = np.asarray(grasp_table.column("p0").to_pylist(), float).reshape(-1, 6)
    rows = _top_rows(obj, p0[grasp_index], use.use_dir[use_index], s)
    return PairSearch(rows, grasp_table.num_rows, candidates, int(len(values)), use, sampling)


def optimize_pairs(obj, settings: PairSearchSettings) -> PairSearch:
    """The cross-entropy method over p0, each grasp scored with its best use point.

    The search space splits as the metrics do: CEM (:func:`affordgrasp.search.cem.cem_search`,
    the optimiser of :func:`affordgrasp.search.optimize.optimize`) moves the pregrasp, and
    each simulated grasp takes the best of the search's use points, found as in
    :func:`pair_scores` (ray casts and the pair LPs). ``budget`` counts simulations, as for
    ``optimize``.

    Parameters
    ----------
    obj : GraspObject or str
    settings : PairSearchSettings
        The task, thresholds, use points, ``top``, and the optimiser's ``budget``,
        ``population``, ``restarts``, ``refine`` and ``threshold_guide``.

    Returns
    -------
    PairSearch
        The ``top`` best distinct (grasp, use point) pairs met during the search,
        re-simulated.
    """
    s = settings
    obj, task, use, sampling = _start(obj, s, optimiser=True)
    found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    counts = {"lp": 0, "finite": 0}

    def objective(x: np.ndarray):
        # ε only (volume=False): the search never reads the GWS volume, whose 6-D hull is
        # most of the metric cost on enveloping grasps; the returned rows are re-simulated
        rows = evaluate_inputs(obj, x[:, :6], x[:, 6:], hand=s.hand, seed=s.seed, volume=False)
        rows = rows.table
        scores = pair_scores(obj, rows, use, s.task, s.mode, **s.thresholds)
        best, best_use = best_use_per_grasp(scores, len(x))
        counts["lp"] += len(scores["value"])
        counts["finite"] += int(np.sum(scores["value"] > -np.inf))
        found.append((x[:, :6].copy(), best, best_use))
        # the rows' own use points are not the pairs'
        guide = pair_search_guidance(obj, rows, task, s.mode, s.thresholds, use, s.threshold_guide)
        return best, guide

    def first_generation(start: int, stop: int) -> np.ndarray:
        # run r's first generation: the next uniform samples of run ``seed``; run 0 is the
        # search of a single run
        return np.concatenate(sample_inputs(s.seed, start, stop), axis=1)

    cem_search(
        objective,
        budget=s.budget,
        seed=s.seed,
        restarts=s.restarts,
        refine=s.refine,
        population=s.population,
        first_generation=first_generation,
    )
    p0 = np.concatenate([f[0] for f in found])
    value = np.concatenate([f[1] for f in found])
    use_idx = np.concatenate([f[2] for f in found])
    ok = np.flatnonzero(value > -np.inf)
    # distinct pairs only: CEM keeps its elites, which may be simulated again
    key = np.concatenate([p0[ok], use_idx[ok, None].astype(float)], axis=1)
    _, first = np.unique(key, axis=0, return_index=True)
    ok = ok[np.sort(first)]
    pick = ok[top_indices(value[ok], s.top)]
    rows = _top_rows(obj, p0[pick], use.use_dir[use_idx[pick]], s)
    return PairSearch(rows, int(len(value)), counts["finite"], counts["lp"], use, sampling)


def _top_rows(obj, p0, use_dir, settings: PairSearchSettings) -> pa.Table:
    """The pairs (p0, d) re-simulated as ordinary rows, with their F_T as ``value``."""
    s = settings
    p0, use_dir = np.reshape(p0, (-1, 6)), np.reshape(use_dir, (-1, 2))
    rows = evaluate_inputs(obj, p0, use_dir, hand=s.hand, seed=s.seed).table
    task = get_task(s.task)
    value = task.evaluate(rows, s.mode, **s.thresholds) if rows.num_rows else np.zeros(0)
    return rows.append_column("value", pa.array(np.asarray(value, dtype=np.float64)))


def best_use_per_grasp(scores: dict, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Each grasp's best F_T over the scored pairs and the use index that gives it.

    Parameters
    ----------
    scores : dict
        Output of :func:`pair_scores`.
    n : int
        Number of grasps.

    Returns
    -------
    values : (n,) float64 ndarray
    use : (n,) int ndarray
        -1 where no pair of the grasp is finite.
    """
    best = np.full(n, -np.inf)
    use = np.full(n, -1, dtype=np.int64)
    v = scores["value"]
    ok = np.flatnonzero(v > -np.inf)
    if len(ok):
        order = ok[np.lexsort((scores["use"][ok], -v[ok], scores["grasp"][ok]))]
        g = scores["grasp"][order]
        first = np.ones(len(order), dtype=bool)
        first[1:] = g[1:] != g[:-1]
        best[g[first]] = v[order[first]]
        use[g[first]] = scores["use"][order[first]]
    return best, use
