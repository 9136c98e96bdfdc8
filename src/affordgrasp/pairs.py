"""Brute-force argmax of a task over grasps × use points (paper §IV-C, conventions: Datasets).

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
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np
import pyarrow as pa
from numba import njit

from .columns import GRASP_METRICS, USE_METRICS
from .grasp.pregrasp import sample_inputs, surface_use_directions, use_points
from .hands import Hand
from .metrics.cones import wrench_matrix_kernel
from .metrics.effort import impact_effort, impact_effort_kernel, use_wrench
from .metrics.epsilon_hand import epsilon_hand
from .metrics.lp import OPTIMAL
from .metrics.striking import use_depth, use_relief
from .metrics.transmission import use_force, use_force_kernel
from .metrics.use_geometry import (
    contact_thickness,
    contact_width,
    use_edge,
    use_edge_angle,
    use_wedge_shape,
)
from .objects import GraspObject, load_object
from .pipeline import evaluate_inputs, evaluate_samples
from .search.cem import cem_search, plan_runs
from .search.guidance import USE_ONLY, guidance, pair_geometry, swing_alignment
from .search.ranking import TopRows, top_indices
from .tasks import MetricColumns, get_task

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


@dataclass(frozen=True)
class UsePoints:
    """Use points of m use directions on one object.

    Attributes
    ----------
    use_dir : (m, 2) float64 ndarray
    point, normal : (m, 3) float64 ndarray
        m; outward unit normals.
    triangle : (m,) int ndarray
        Face index, -1 for no hit.
    use_edge : (m,) float64 ndarray
        U_g, m⁻².
    use_edge_angle : (m,) float64 ndarray
        rad.
    use_wedge_angle : (m,) float64 ndarray
        rad.
    use_wedge_angle_fine : (m,) float64 ndarray
        rad (2 mm ball).
    use_edge_span : (m,) float64 ndarray
        Dimensionless.
    use_edge_thickness : (m,) float64 ndarray
        m (NaN where no chord behind U lies inside the solid).
    use_depth, use_relief : (m,) float64 ndarray
        m (:mod:`affordgrasp.metrics.striking`).
    """

    use_dir: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    triangle: np.ndarray
    use_edge: np.ndarray
    use_edge_angle: np.ndarray
    use_wedge_angle: np.ndarray
    use_wedge_angle_fine: np.ndarray
    use_edge_span: np.ndarray
    use_edge_thickness: np.ndarray
    use_depth: np.ndarray
    use_relief: np.ndarray

    @classmethod
    def of(cls, obj: GraspObject | str, use_dir: np.ndarray, columns=None) -> UsePoints:
        """Cast the use rays of ``use_dir`` on an object.

        Parameters
        ----------
        obj : GraspObject or str
            An object or a spec (``knife:3``, a mesh path).
        use_dir : (m, 2) array_like of float
            Use directions, in [0, 1].
        columns : iterable of str, optional
            Compute only these use-point columns (the others NaN): a search that tests a
            few of them skips the rest (the dihedral angle alone costs more than the rest
            together). Default every one.

        Returns
        -------
        UsePoints
            NaN edge metrics where a ray misses the object.
        """
        obj = load_object(obj)
        use_dir = np.asarray(use_dir, dtype=np.float64).reshape(-1, 2)
        wanted = set(USE_ONLY if columns is None else columns)
        P, N, T = use_points(obj.mesh, obj.mass.center_of_mass, use_dir)
        hit = T >= 0
        out = {c: np.full(len(T), np.nan) for c in sorted(USE_ONLY)}
        if hit.any():
            Ph, Nh = P[hit], N[hit]
            if "use_edge" in wanted:
                out["use_edge"][hit] = use_edge(obj.mesh, T[hit], Ph)
            if "use_edge_angle" in wanted:
                out["use_edge_angle"][hit] = use_edge_angle(obj.mesh, Ph, use_normal=Nh)
            wedge_columns = {
                "use_wedge_angle",
                "use_wedge_angle_fine",
                "use_edge_span",
                "use_edge_thickness",
            }
            if wedge_columns & wanted:
                shape = use_wedge_shape(obj.mesh_data, Ph, Nh)
                out["use_wedge_angle"][hit] = shape.angle
                out["use_wedge_angle_fine"][hit] = shape.inner_angle
                out["use_edge_span"][hit] = shape.span
                out["use_edge_thickness"][hit] = shape.edge_thickness
            if "use_depth" in wanted:
                out["use_depth"][hit] = use_depth(obj.mesh_data, Ph, Nh)
            if "use_relief" in wanted:
                out["use_relief"][hit] = use_relief(obj.mesh_data, Ph, Nh)
        return cls(use_dir, P, N, T, **out)

    def take(self, index: np.ndarray) -> UsePoints:
        """The use points ``index``, in that order.

        Parameters
        ----------
        index : (k,) int ndarray

        Returns
        -------
        UsePoints
        """
        return UsePoints(**{f.name: getattr(self, f.name)[index] for f in fields(self)})

    @staticmethod
    def concat(parts: list[UsePoints]) -> UsePoints:
        """One set of use points of several, in order.

        Parameters
        ----------
        parts : list of UsePoints
            At least one.

        Returns
        -------
        UsePoints
        """
        names = [f.name for f in fields(parts[0])]
        return UsePoints(**{n: np.concatenate([getattr(p, n) for p in parts]) for n in names})

    @classmethod
    def sample(cls, obj: GraspObject | str, n: int, seed: int) -> UsePoints:
        """``n`` use points that cover the surface by area (their d towards surface points
        drawn uniformly by area, :func:`~affordgrasp.grasp.pregrasp.surface_use_directions`).

        Parameters
        ----------
        obj : GraspObject or str
        n : int
        seed : int

        Returns
        -------
        UsePoints
        """
        obj = load_object(obj)
        d = surface_use_directions(obj.mesh_data, obj.mass.center_of_mass, n, seed)
        return cls.of(obj, d)


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
            keep = t.evaluate(MetricColumns(cols), mode, **overrides) > -np.inf
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
        from .metrics.contacts import ContactSet

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


@dataclass(frozen=True)
class PairSearch:
    """Result of :func:`best_pairs`.

    Attributes
    ----------
    table : pyarrow.Table
        The top pairs as ordinary evaluated rows (p0 of the grasp, d of the use point), best
        first, with a ``value`` column.
    grasps, uses : int
        How many grasps were simulated and use points cast.
    candidates : int
        Pairs with a finite F_T.
    lp_pairs : int
        Pairs that needed the LPs.
    """

    table: pa.Table
    grasps: int
    uses: int
    candidates: int
    lp_pairs: int


def best_pairs(
    obj,
    task: str,
    *,
    mode: str = "default",
    grasps: int = 4000,
    uses: int = 4000,
    seed: int = 0,
    top: int = 10,
    hand: Hand | str = "barrett",
    grasp_table: pa.Table | None = None,
    per_grasp: bool = False,
    given_uses: UsePoints | None = None,
    **overrides: float,
) -> PairSearch:
    """Top ``top`` (p0, d) pairs of ``task`` over ``grasps`` uniform samples × ``uses`` use
    points drawn by surface area (:meth:`UsePoints.sample`).

    The grasps are the samples 0..grasps-1 of run ``seed`` (as ``generate --streams
    shared`` draws them; pass ``grasp_table`` to reuse evaluated rows); the use directions
    are drawn from run ``seed + 1`` so that they are independent of the rows' own d. The
    top pairs are re-simulated with :func:`affordgrasp.pipeline.evaluate_inputs`, so the
    returned rows carry every column of the dataset schema; a pair's value is recomputed on
    that row.

    Parameters
    ----------
    obj : GraspObject or str
        The object or its spec.
    task : str
        A registered task.
    mode : str
        Threshold mode.
    grasps, uses : int
        Sample counts.
    seed : int
        Run seed.
    top : int
        Pairs returned.
    hand : str or Hand
        The hand.
    grasp_table : pyarrow.Table, optional
        Evaluated rows to reuse instead of simulating.
    per_grasp : bool
        Top ``top`` distinct grasps, each with its best use point (F_T of a grasp is its
        maximum over U), instead of the top pairs (which may repeat one grasp with
        several use points).
    given_uses : UsePoints, optional
        The use points to score (``uses`` is then ignored); default the sample by area
        (:func:`affordgrasp.optimize.targeted_best_pairs` passes the use points that pass
        the task's use-point tests).
    **overrides : float
        Threshold values that replace the mode's.

    Returns
    -------
    PairSearch
    """
    obj = load_object(obj)
    if grasp_table is None:
        # ε only: the search never reads the GWS volume; the returned rows carry it
        grasp_table = evaluate_samples(obj, grasps, seed=seed, hand=hand, volume=False).table
    use = UsePoints.sample(obj, uses, seed + 1) if given_uses is None else given_uses
    d = use.use_dir
    scores = pair_scores(obj, grasp_table, use, task, mode, **overrides)
    # The one ranker of the package: highest F_T first, ties to the smaller grasp, then use.
    values = scores["value"]
    best = TopRows(top, 2)
    if per_grasp:  # each grasp once, with its best use point (ties: the lowest use index)
        best_value, best_use = best_use_per_grasp(scores, grasp_table.num_rows)
        best.add(best_value, np.arange(grasp_table.num_rows), best_use)
        candidates = int(np.count_nonzero(values > -np.inf))
    else:
        candidates = best.add(values, scores["grasp"], scores["use"])
    grasp_index, use_index = best.keys
    p0 = np.asarray(grasp_table.column("p0").to_pylist(), float).reshape(-1, 6)
    rows = _top_rows(
        obj,
        p0[grasp_index],
        use.use_dir[use_index],
        task,
        mode,
        hand,
        seed,
        overrides,
    )
    return PairSearch(
        table=rows,
        grasps=grasp_table.num_rows,
        uses=len(d),
        candidates=candidates,
        lp_pairs=int(len(values)),
    )


def _top_rows(obj, p0, use_dir, task, mode, hand, seed, overrides) -> pa.Table:
    """The pairs (p0, d) re-simulated as ordinary rows, with their F_T as ``value``."""
    rows = evaluate_inputs(
        obj, np.reshape(p0, (-1, 6)), np.reshape(use_dir, (-1, 2)), hand=hand, seed=seed
    ).table
    value = get_task(task).evaluate(rows, mode, **overrides) if rows.num_rows else np.zeros(0)
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


def optimize_pairs(
    obj,
    task: str,
    *,
    mode: str = "default",
    budget: int = 2000,
    uses: int = 2000,
    seed: int = 0,
    top: int = 10,
    population: int | None = None,
    hand: Hand | str = "barrett",
    restarts: int = 1,
    refine: float = 0.0,
    given_uses: UsePoints | None = None,
    guide: Callable[[pa.Table], np.ndarray] | None = None,
    **overrides: float,
) -> PairSearch:
    """The cross-entropy method over p0, each grasp scored with its best of ``uses`` use points.

    The search space splits as the metrics do: CEM (:func:`affordgrasp.search.cem.cem_search`,
    the optimiser of :func:`affordgrasp.optimize.optimize`) moves the pregrasp, and each
    simulated grasp takes the best use point of a fixed sample of ``uses`` use
    points drawn by surface area (run ``seed + 1``), found as in :func:`pair_scores`.
    ``budget`` counts simulations, as for ``optimize``.

    Parameters
    ----------
    obj : GraspObject or str
    task : str
    mode : str
    budget : int
        Simulations.
    uses : int
        Use directions sampled once.
    seed : int
    top : int
        Distinct pairs returned.
    population : int, optional
        CEM population; chosen from each run's budget when None.
    hand : str or Hand
    restarts : int
        Independent CEM runs that share the budget (each ``budget // restarts``
        simulations, its own first generation and random stream); the pairs met by all of
        them are ranked together. One run settles on the first good region it meets (on a
        hammer, a hold of the head with 5× the hold effort of the best hold on the handle);
        several runs make that less likely.
    refine : float
        Share of ``budget`` (in [0, 1)) spent after the restarts on continuing the best of
        them (the run with the largest F_T; without one, the best guidance) around its best
        point: its elites carry on and its distribution restarts centred there with CEM's
        narrowest std (:meth:`affordgrasp.search.cem.CEMState.around_best`). The restarts
        share the rest. A run can meet its best point alone (its fit to two scattered
        elites then samples between them); refining finds that point's neighbours, so the
        top pairs are neighbours of the best pair rather than the best of weaker regions
        that other restarts settled in.
    given_uses : UsePoints, optional
        The use points to score (``uses`` is then ignored); default the sample by area.
    guide : callable, optional
        ``guide(rows)``: the guidance of a generation's simulated rows, (n,) floats, that
        ranks them while none is feasible; default :func:`pair_guidance` (contacts, ε and
        the use terms). :func:`affordgrasp.optimize.targeted_pairs` passes the guidance
        relative to the task's thresholds.
    **overrides : float
        Threshold values that replace the mode's.

    Returns
    -------
    PairSearch
        The ``top`` best distinct (grasp, use point) pairs met during the search,
        re-simulated.
    """
    obj = load_object(obj)
    get_task(task).thresholds_for(mode, **overrides)  # bad mode or threshold: fail now
    plan_runs(budget, restarts, refine, population)  # a budget that cannot be split: too
    use = UsePoints.sample(obj, uses, seed + 1) if given_uses is None else given_uses
    d = use.use_dir
    found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    counts = {"lp": 0, "finite": 0}
    t = get_task(task)
    # the rows' own use points are not the pairs': the guidance reads their ε column only
    eps_column = tuple(c for c in ("epsilon_hand",) if c in t.requires)

    def objective(x: np.ndarray):
        # ε only (volume=False): the search never reads the GWS volume, whose 6-D hull is
        # most of the metric cost on enveloping grasps; the returned rows are re-simulated
        rows = evaluate_inputs(obj, x[:, :6], x[:, 6:], hand=hand, seed=seed, volume=False).table
        scores = pair_scores(obj, rows, use, task, mode, **overrides)
        best, best_use = best_use_per_grasp(scores, len(x))
        counts["lp"] += len(scores["value"])
        counts["finite"] += int(np.sum(scores["value"] > -np.inf))
        found.append((x[:, :6].copy(), best, best_use))
        if guide is not None:
            return best, guide(rows)
        return best, pair_guidance(rows, t, mode, overrides, use, eps_column)

    def first_generation(start: int, stop: int) -> np.ndarray:
        # run r's first generation: the next uniform samples of run ``seed``; run 0 is the
        # search of a single run
        return np.concatenate(sample_inputs(seed, start, stop), axis=1)

    cem_search(
        objective,
        budget=budget,
        seed=seed,
        restarts=restarts,
        refine=refine,
        population=population,
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
    pick = ok[top_indices(value[ok], top)]
    rows = _top_rows(obj, p0[pick], use.use_dir[use_idx[pick]], task, mode, hand, seed, overrides)
    return PairSearch(
        table=rows,
        grasps=int(len(value)),
        uses=len(d),
        candidates=counts["finite"],
        lp_pairs=counts["lp"],
    )
