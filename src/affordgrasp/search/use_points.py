"""Use points: where the use rays of use directions d meet an object, and how a pair search
draws them (paper §IV-C, conventions: Datasets).

:class:`UsePoints` holds the use-point columns of m use directions (one ray cast each, no
simulation). A pair search scores either the plain sample by surface area
(:meth:`UsePoints.sample`) or :func:`passing_use_points`, drawn until enough pass the task's
tests of the use point alone; :func:`draw_use_points` chooses between them and says how they
were drawn (:class:`UseSampling`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from ..errors import bad_parameter
from ..grasp.pregrasp import surface_use_directions, use_points
from ..metrics.edges import use_edge, use_edge_angle
from ..metrics.striking import use_depth, use_relief
from ..metrics.wedge import use_wedge_shape
from ..objects import GraspObject, load_object
from ..tasks import get_task
from .guidance import USE_ONLY, use_only_passes


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


@dataclass(frozen=True)
class UseSampling:
    """How a pair search's use points were drawn (:func:`passing_use_points`).

    Attributes
    ----------
    drawn : int
        Use points drawn by area, in all.
    passing : int
        Of them, how many pass the task's tests of the use point alone.
    kept : int
        Use points the search scores (``passing`` capped at the number asked for, or the
        plain sample on a fallback).
    fallback : bool
        No drawn use point passed (or the task has no test of the use point alone): the
        search scores the plain sample by area.
    tested : bool
        The task has tests of the use point alone.
    only_passing : bool
        The use points were drawn until enough pass (:func:`passing_use_points`); False:
        the plain sample by area (``passing`` then counts those of it that pass).
    """

    drawn: int
    passing: int
    kept: int
    fallback: bool
    tested: bool = True
    only_passing: bool = True

    def describe(self) -> str:
        """One line for the command's output.

        Returns
        -------
        str
        """
        if not self.tested:
            return f"use points: {self.kept:,} drawn by area"
        if not self.only_passing:
            return (
                f"use points: {self.kept:,} drawn by area, {self.passing:,} of them pass the "
                "task's tests of the use point alone"
            )
        if self.fallback:
            return (
                f"use points: none of {self.drawn:,} drawn by area passes the task's tests of "
                f"the use point alone; scoring {self.kept:,} plain area samples"
            )
        return (
            f"use points: {self.kept:,} that pass the task's tests of the use point alone "
            f"({self.passing:,} of {self.drawn:,} drawn by area)"
        )

    def to_dict(self) -> dict:
        """JSON-ready fields.

        Returns
        -------
        dict
            ``drawn``, ``passing``, ``kept``, ``fallback``, ``tested``, ``only_passing``.
        """
        return {
            "drawn": self.drawn,
            "passing": self.passing,
            "kept": self.kept,
            "fallback": self.fallback,
            "tested": self.tested,
            "only_passing": self.only_passing,
        }


def passing_use_points(
    obj,
    task,
    n: int,
    seed: int,
    *,
    mode: str = "default",
    thresholds: Mapping[str, float] | None = None,
    max_draws: int | None = None,
):
    """``n`` use points, drawn by area, that pass the task's tests of the use point alone.

    Use points are drawn by surface area in batches of ``n`` (batch 0 is
    :meth:`UsePoints.sample` with ``seed``; batch k ≥ 1 uses a seed
    derived from (``seed``, k)) until ``n`` of them pass the tests of ``task`` that the use
    point alone decides (:func:`~affordgrasp.search.guidance.use_only_passes`: a cutting
    edge for ``cut``, a deep, flat, blunt face for ``beat``), or ``max_draws`` have been
    drawn. A cutting edge is about 1 % of a blade's surface: the plain sample of 2000 holds
    some 20 edge points, this one up to ``n``. When none passes, or the task has no such
    test, the plain sample (batch 0) is returned and ``fallback`` says so.

    Parameters
    ----------
    obj : GraspObject or str
    task : str or Task
    n : int
        Use points wanted.
    seed : int
        Same seed, same use points.
    mode : str
        Threshold mode.
    thresholds : mapping of str to float, optional
        Threshold values that replace the mode's.
    max_draws : int, optional
        At most this many use points are drawn (default ``16 n``).

    Returns
    -------
    uses : UsePoints
        The use points, in the order drawn; only the columns the task reads are computed
        (the others are NaN).
    sampling : UseSampling
    """
    obj = load_object(obj)
    t = get_task(task) if isinstance(task, str) else task
    overrides = dict(thresholds or {})
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise bad_parameter("uses", f"must be a positive integer, got {n!r}")
    limit = 16 * n if max_draws is None else int(max_draws)
    if limit < n:
        raise bad_parameter("max_draws", f"must be at least uses ({n}), got {max_draws!r}")
    columns = set(t.requires) & USE_ONLY
    center = obj.mass.center_of_mass
    tested = bool(columns) and not t.probability  # a probability has no use point tests
    kept, first, drawn, passing = [], None, 0, 0
    k = 0
    while drawn < limit:
        batch_seed = seed if k == 0 else int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
        size = min(n, limit - drawn)
        d = surface_use_directions(obj.mesh_data, center, size, batch_seed)
        batch = UsePoints.of(obj, d, columns if tested else None)
        drawn += size
        k += 1
        if first is None:
            first = batch
        if not tested:
            break
        ok = np.flatnonzero(use_only_passes(t, mode, overrides, batch))
        passing += ok.size
        if ok.size:
            kept.append(batch.take(ok))
        if sum(len(p.triangle) for p in kept) >= n:
            break
    if not kept:
        return first, UseSampling(drawn, passing, len(first.triangle), True, tested)
    uses = UsePoints.concat(kept)
    uses = uses.take(np.arange(min(n, len(uses.triangle))))
    return uses, UseSampling(drawn, passing, len(uses.triangle), False)


def draw_use_points(obj, task, n: int, seed: int, mode: str, overrides, max_draws, passing: bool):
    """The use points of a pair search: :func:`passing_use_points`, or (``passing`` False) the
    plain sample by area (:meth:`UsePoints.sample`).

    Parameters
    ----------
    obj : GraspObject
    task : Task
    n : int
        Use points wanted.
    seed : int
        Their run seed (a search draws them from run ``seed + 1`` of its grasps).
    mode : str
        Threshold mode.
    overrides : mapping of str to float
        Threshold values that replace the mode's.
    max_draws : int or None
        With ``passing``: use points drawn at most.
    passing : bool

    Returns
    -------
    uses : UsePoints
    sampling : UseSampling
    """
    if passing:
        return passing_use_points(
            obj, task, n, seed, mode=mode, thresholds=overrides, max_draws=max_draws
        )
    use = UsePoints.sample(obj, n, seed)
    passing_count = int(use_only_passes(task, mode, overrides, use).sum())
    tested = bool(set(task.requires) & USE_ONLY) and not task.probability
    return use, UseSampling(n, passing_count, n, False, tested=tested, only_passing=False)
