"""From a camera view to a grasp: sample candidates, look, predict, choose, check
(conventions: Vision).

:func:`plan` (``affordgrasp.plan``) does what a robot with a camera in its hand would do,
then says how good the decision truly was:

1. draw ``candidates`` pregrasps p0 and use directions d (sample i depends only on
   (seed, i), as in a generated dataset), uniform but for the approach line's offsets
   (u4, u5), drawn in [-r, r]² with r = ``offset_range`` (default :data:`OFFSET_RANGE`:
   a planner aims near the object; 1 is the dataset's uniform draw);
2. render the candidates' camera-in-hand depth images D(p0, O) in one batch (every
   candidate's for learned models; the first :data:`FUSED_VIEWS`, those it fuses, for
   ``models="views"``);
3. by default (``models="views"``) fuse the first :data:`FUSED_VIEWS` images into a
   surface (:mod:`affordgrasp.vision.fusion`) and simulate every candidate on it; or
   predict with learned models in one batch;
4. choose: on the fused surface's simulation by
   :func:`~affordgrasp.learning.decisions.margin_order` (viable, then task-feasible, then
   the widest ε); more candidates drawn near its first ``refine`` ones, simulated there
   and ranked with them; the first ``robust_check`` of all simulated there again under
   small perturbations and the one whose copies keep the widest ε first
   (:func:`~affordgrasp.learning.decisions.robust_first`); with models by
   :func:`~affordgrasp.learning.decisions.decision_order` (a classifier alone: the most
   probably viable; with a regressor as well, the classifier's decision threshold, then
   least predicted effort);
5. simulate every candidate (not only the chosen one), so the chosen grasp's true task
   score, viability and percentile among the candidates' true scores are known; with
   ``physics=True`` replay the chosen grasp in MuJoCo (the physics extra).

The simulation of step 5 is the check, not part of the decision: the deciders see only the
depth images and the poses (the fused surface is made from the images alone).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa

from ..errors import InputError
from ..grasp.pregrasp import (
    PLAN_CANDIDATES,
    PLAN_OFFSET_RANGE,
    PLAN_REFINE,
    PLAN_REFINE_NEIGHBOURS,
    PLAN_REFINE_SIGMA,
    PLAN_ROBUST_CHECK,
)
from ..robust import RobustSettings
from .decisions import (
    decision_measures,
    decision_order,
    decision_threshold,
    margin_order,
    oracle_order,
    random_measures,
    robust_first,
)

OFFSET_RANGE = PLAN_OFFSET_RANGE  # the candidates' offsets (u4, u5) lie in [-R, R]² (pregrasp)
VIEWS = "views"  # the decider that fuses the candidates' views and simulates on the surface
# Views fused at most (the first candidates'). 128 was tried with the robust check (256
# candidates): validation 0.949 viable choices against 0.923, test (nine seeds) 0.880
# against 0.897; the two disagree, so 64 stays (docs/learning.md).
FUSED_VIEWS = 64
# With a sensor model the views are fused more cautiously (docs/learning.md, measured on
# validation objects): pixels without a return this close to a return say nothing (lost at
# a grazing angle, not empty space), and a voxel needs this many views to see past it (the
# depth noise, 0.5-0.8 mm, carves into the surface where two views suffice).
SENSOR_UNKNOWN_PX = 6
SENSOR_VOTES = 3
# The perturbations of plan's robust check (grasp.pregrasp.PLAN_ROBUST_CHECK): half the
# robust labels' hand-pose and centre-of-mass scales, K = 12 (docs/learning.md).
ROBUST_CHECK_SETTINGS = RobustSettings(
    copies=12, translation_m=0.0025, rotation_rad=math.radians(1.5), com_m=0.00125, tasks=()
)
# The robust check ranks the candidates it re-simulates by this quantile of their copies'
# ε (the ε three copies in four reach): on validation objects it chose a viable grasp more
# often than the share of copies viable or the median (docs/learning.md).
ROBUST_CHECK_QUANTILE = 0.25
REFINE_STREAM = 0x4EB5  # the refined candidates' draws: SeedSequence([seed, REFINE_STREAM])


@dataclass(frozen=True)
class Plan:
    """A model's choice among candidate grasps on one object, and its simulated truth.

    Attributes
    ----------
    object : str
        The object's name.
    task : str
        The task whose true score judges the choice.
    chosen : int
        Index of the chosen candidate.
    order : (n,) int64 ndarray
        Every candidate in the order the models rank them (``order[0] == chosen``).
    p0 : (n, 6) float64 ndarray
        Candidate pregrasps.
    use_dir : (n, 2) float64 ndarray
        Candidate use directions.
    probability : (n,) float64 ndarray or None
        The classifier's viability probabilities (None without a classifier).
    predicted : (n,) float64 ndarray or None
        The regressor's predictions in its target's units (None without a regressor).
    true_score : (n,) float64 ndarray
        Simulated F_T of every candidate (−inf where the task fails).
    viable : (n,) bool ndarray
        Simulated viability of every candidate.
    percentile : float
        The chosen grasp's percentile among the drawn candidates' true scores, in [0, 100]
        (:func:`~affordgrasp.learning.decisions.percentile_among`; a refined candidate
        is placed among the drawn ones).
    measures : dict
        The decision's measures, the random-choice expectation and the oracle's
        (``model``, ``random``, ``oracle``; see
        :func:`~affordgrasp.learning.decisions.decision_measures`).
    rule : str
        How the choice was made, in words.
    table : pyarrow.Table
        The simulated candidates (one row each; columns: docs/conventions.md).
    physics : dict or None
        The chosen grasp's replay outcome (``GraspOutcome.to_row()``), when asked for.
    timings : dict of str to float
        Seconds per step: ``render``, ``predict`` (or ``fuse`` and ``predict``, the
        simulation on the fused surface, for ``models="views"``), ``simulate``,
        ``physics``.
    offset_range : float
        The candidates' offsets (u4, u5) were drawn in [-offset_range, offset_range]².
    fused_score : (n,) float64 ndarray or None
        With ``models="views"``: every candidate's F_T simulated on the surface fused from
        the views (−inf where the task fails there); else None.
    fused_viable : (n,) bool ndarray or None
        With ``models="views"``: viability simulated on the fused surface; else None.
    fused_epsilon : (n,) float64 ndarray or None
        With ``models="views"``: ε simulated on the fused surface; else None.
    fused_robust_viable : (n,) float64 ndarray or None
        With ``models="views"`` and ``robust_check``: the share of perturbed copies viable
        on the fused surface, for the candidates re-simulated (NaN for the others); else
        None.
    fused_robust_epsilon : (n,) float64 ndarray or None
        With ``models="views"`` and ``robust_check``: the :data:`ROBUST_CHECK_QUANTILE`
        quantile of the perturbed copies' ε on the fused surface (what the check ranks
        by), for the candidates re-simulated (NaN for the others); else None.
    drawn : int or None
        How many of the candidates were drawn (the first ones); the rest were drawn near
        the best of them (``refine``). None: all were drawn.
    """

    object: str
    task: str
    chosen: int
    order: np.ndarray
    p0: np.ndarray
    use_dir: np.ndarray
    probability: np.ndarray | None
    predicted: np.ndarray | None
    true_score: np.ndarray
    viable: np.ndarray
    percentile: float
    measures: dict
    rule: str
    table: pa.Table
    physics: dict | None = None
    timings: dict = field(default_factory=dict)
    offset_range: float = 1.0
    fused_score: np.ndarray | None = None
    fused_viable: np.ndarray | None = None
    fused_epsilon: np.ndarray | None = None
    fused_robust_viable: np.ndarray | None = None
    fused_robust_epsilon: np.ndarray | None = None
    drawn: int | None = None

    def summary(self) -> dict:
        """The plan as JSON-ready data (without the per-candidate arrays).

        Returns
        -------
        dict
            Object, task, rule, the chosen candidate (p0, d, probability, prediction,
            true score, viable, percentile), the measures, physics and timings;
            ``candidates`` counts the drawn candidates, ``refined`` those drawn near them,
            ``candidates_viable`` and ``candidates_feasible`` both.
        """
        c = self.chosen
        return {
            "object": self.object,
            "task": self.task,
            "candidates": int(len(self.p0) if self.drawn is None else self.drawn),
            "refined": int(0 if self.drawn is None else len(self.p0) - self.drawn),
            "offset_range": self.offset_range,
            "rule": self.rule,
            "chosen": {
                "index": c,
                "p0": self.p0[c].tolist(),
                "use_dir": self.use_dir[c].tolist(),
                "probability": None if self.probability is None else float(self.probability[c]),
                "predicted": None if self.predicted is None else float(self.predicted[c]),
                "fused_score": None if self.fused_score is None else float(self.fused_score[c]),
                "fused_viable": None if self.fused_viable is None else bool(self.fused_viable[c]),
                "fused_epsilon": (
                    None if self.fused_epsilon is None else float(self.fused_epsilon[c])
                ),
                "fused_robust_viable": (
                    None
                    if self.fused_robust_viable is None
                    or not np.isfinite(self.fused_robust_viable[c])
                    else float(self.fused_robust_viable[c])
                ),
                "fused_robust_epsilon": (
                    None
                    if self.fused_robust_epsilon is None
                    or not np.isfinite(self.fused_robust_epsilon[c])
                    else float(self.fused_robust_epsilon[c])
                ),
                "true_score": float(self.true_score[c]),
                "viable": bool(self.viable[c]),
                "feasible": bool(np.isfinite(self.true_score[c])),
                "percentile": self.percentile,
            },
            "candidates_viable": int(self.viable.sum()),
            "candidates_feasible": int(np.isfinite(self.true_score).sum()),
            "measures": self.measures,
            "physics": self.physics,
            "timings": dict(self.timings),
        }


def split_models(models: Sequence[tuple[Any, dict]]):
    """The classifier and the regressor among some models.

    Parameters
    ----------
    models : sequence of (torch.nn.Module, dict)
        One classifier and/or one regressor, each with its config.

    Returns
    -------
    classifier, regressor : (torch.nn.Module, dict) or None

    Raises
    ------
    InputError
        With no model, or two of the same kind.
    """
    classifier = regressor = None
    for model, config in models:
        if config["target"]["kind"] == "classification":
            if classifier is not None:
                raise InputError("give at most one classifier to decide with")
            classifier = (model, config)
        else:
            if regressor is not None:
                raise InputError("give at most one regressor to decide with")
            regressor = (model, config)
    if classifier is None and regressor is None:
        raise InputError("give a classifier and/or a regressor to decide with")
    return classifier, regressor


def rule_of(classifier, regressor, threshold: float | None = None) -> str:
    """The decision rule of a pair of models, in words.

    Parameters
    ----------
    classifier, regressor : (torch.nn.Module, dict) or None
    threshold : float, optional
        The threshold used instead of the classifier's own.

    Returns
    -------
    str
    """
    if classifier is not None and regressor is not None:
        t = decision_threshold(classifier[1]) if threshold is None else float(threshold)
        best = "least" if regressor[1]["target"]["lower_is_better"] else "largest"
        return (
            f"viability probability >= {t:.3g}, then {best} predicted "
            f"{regressor[1]['target']['name']}"
        )
    if classifier is not None:
        return "highest viability probability"
    tgt = regressor[1]["target"]
    return f"{'least' if tgt['lower_is_better'] else 'largest'} predicted {tgt['name']}"


def model_order(classifier, regressor, samples, *, threshold: float | None = None):
    """Predict for candidates and rank them (see :func:`decision_order`).

    Parameters
    ----------
    classifier, regressor : (torch.nn.Module, dict) or None
    samples : Samples
        The candidates, with depth images.
    threshold : float, optional
        Overrides the classifier's decision threshold.

    Returns
    -------
    order : (n,) int64 ndarray
    probability, predicted : (n,) float64 ndarray or None
    """
    from .api import predictions_of

    probability = predicted = None
    lower = True
    t = 0.5
    if classifier is not None:
        probability = predictions_of(classifier[0], classifier[1], samples)
        t = decision_threshold(classifier[1]) if threshold is None else float(threshold)
    if regressor is not None:
        predicted = predictions_of(regressor[0], regressor[1], samples)
        lower = bool(regressor[1]["target"]["lower_is_better"])
    order = decision_order(probability, predicted, threshold=t, lower_is_better=lower)
    return order, probability, predicted


def plan(
    obj,
    task: str = "pick",
    *,
    candidates: int = PLAN_CANDIDATES,
    models=VIEWS,
    seed: int = 0,
    hand="barrett",
    mode: str = "default",
    physics: bool = False,
    threshold: float | None = None,
    sensor=None,
    offset_range: float = OFFSET_RANGE,
    robust_check: int = PLAN_ROBUST_CHECK,
    refine: int = PLAN_REFINE,
    progress: Callable[[str], Any] | None = None,
) -> Plan:
    """Choose a grasp of an object from camera-in-hand views, and check the choice.

    Parameters
    ----------
    obj : GraspObject or str
        The object: ``ag.load_object(...)``, a family (``"knife"``), ``"knife:7"`` or a mesh
        path.
    task : str
        The task that judges the choice (its simulated F_T in ``mode``).
    candidates : int
        How many candidate grasps to draw (>= 1; default 256, ``grasp.pregrasp.PLAN_CANDIDATES``).
    models : str, path or sequence
        ``"views"`` (the default; no learned model): the first :data:`FUSED_VIEWS`
        candidates' depth images are fused into a surface
        (:func:`affordgrasp.vision.fusion.fused_object`), every candidate is simulated on
        it from the pose it has on the object, and the candidates are ranked by
        :func:`~affordgrasp.learning.decisions.margin_order` on that simulation: viable
        there first, then task-feasible, by decreasing ε; the first ``refine`` of them get
        neighbours, simulated there as well, and the first ``robust_check`` of all are
        checked under perturbation (needs scikit-image, the ``learn`` extra; the chosen
        grasp's viability on unseen objects: docs/learning.md; the shipped classifier's:
        0.37).
        ``"classifier"``: the shipped classifier alone, the most probably viable candidate
        first. ``"default"``: the shipped classifier and regressor, the classifier's
        threshold, then least predicted effort. ``"regressor"``, a model file, or a
        sequence of files and/or loaded ``(model, config)`` pairs: at most one classifier
        and one regressor.
    seed : int
        Seeds the candidates (candidate i depends only on (seed, i)).
    hand : Hand or str
        The hand simulated (the models were trained with the Barrett hand).
    mode : str
        Threshold mode of the task.
    physics : bool
        Replay the chosen grasp in MuJoCo (needs ``affordgrasp[physics]``).
    threshold : float, optional
        Overrides the classifier's stored decision threshold.
    sensor : SensorModel, optional
        The models see the images a depth sensor would return
        (:mod:`affordgrasp.vision.sensor`; candidate i's noise keyed by i); None: exact.
    offset_range : float
        The candidates' approach-line offsets (u4, u5) lie in [-r, r]² (r in (0, 1]; the
        dataset's uniform draw scaled by r, so candidate i is the same draw whatever r).
        Default :data:`OFFSET_RANGE`; 1: uniform, as the datasets are generated.
    robust_check : int
        With ``models="views"``: how many of the first candidates on the fused surface are
        simulated again there under :data:`ROBUST_CHECK_SETTINGS` (K perturbed copies of
        the hand pose, friction and centre of mass, :mod:`affordgrasp.robust`); the one
        whose copies' ε has the highest :data:`ROBUST_CHECK_QUANTILE` quantile (among
        those viable there, if any) is chosen
        (:func:`~affordgrasp.learning.decisions.robust_first`). 0: the first as it is.
        Default ``grasp.pregrasp.PLAN_ROBUST_CHECK``.
    refine : int
        With ``models="views"``: how many of the first candidates on the fused surface get
        ``grasp.pregrasp.PLAN_REFINE_NEIGHBOURS`` new candidates drawn near them
        (:func:`~affordgrasp.search.cem.nearby_inputs`, σ = ``PLAN_REFINE_SIGMA`` on
        every coordinate of p0, the use direction kept), simulated there and ranked with
        the others before the robust check; they are appended to the candidates
        (``Plan.drawn`` says where). 0: none. Default ``grasp.pregrasp.PLAN_REFINE``.
    progress : callable, optional
        Called with the name of each step as it starts.

    Returns
    -------
    Plan

    Raises
    ------
    InputError
        For a bad number of candidates, unknown task or model, or missing extras.

    Notes
    -----
    The measures judge the chosen grasp among every candidate simulated, refined ones
    included (its percentile, the oracle); the random choice's expectation is over the
    drawn candidates alone, the uniform draw a planner without a decider would choose from.
    """
    from ..grasp.policy import simulate
    from ..grasp.pregrasp import sample_inputs
    from ..objects import load_object
    from ..pipeline import evaluate_inputs
    from ..robust import copy_metrics
    from ..search.cem import nearby_inputs
    from ..tasks import get_task, is_viable
    from ..tasks.metric_columns import MetricColumns
    from ..vision.depth import depth_to_mm, renderer_for
    from .data import Samples

    if isinstance(candidates, bool) or not isinstance(candidates, int | np.integer):
        raise InputError(f"candidates must be a positive integer, got {candidates!r}")
    if candidates < 1:
        raise InputError(f"candidates must be >= 1, got {candidates}")
    if threshold is not None and not 0.0 <= float(threshold) <= 1.0:
        raise InputError(f"threshold must be a probability in [0, 1], got {threshold!r}")
    try:
        offset_range = float(offset_range)
    except (TypeError, ValueError):
        raise InputError(f"offset_range must be a number in (0, 1], got {offset_range!r}") from None
    if not 0.0 < offset_range <= 1.0:  # NaN fails too
        raise InputError(f"offset_range must be in (0, 1] (1: uniform), got {offset_range!r}")
    if isinstance(robust_check, bool) or not isinstance(robust_check, int | np.integer):
        raise InputError(f"robust_check must be an integer >= 0, got {robust_check!r}")
    if robust_check < 0:
        raise InputError(f"robust_check must be an integer >= 0, got {robust_check}")
    if isinstance(refine, bool) or not isinstance(refine, int | np.integer) or refine < 0:
        raise InputError(f"refine must be an integer >= 0, got {refine!r}")
    task_obj = get_task(task)
    task_obj.thresholds_for(mode)  # an unknown mode fails before any work
    step = progress or (lambda name: None)
    timings: dict[str, float] = {}
    views = isinstance(models, str) and models == VIEWS
    if not views and is_views_spec(models):
        raise InputError(
            f"plan decides on the fused views with models='views' (its own rule: margin "
            f"order, refined candidates, the robust check); {str(models)!r} is for "
            "model-eval and predict, which judge the views row by row"
        )
    if views and threshold is not None:
        raise InputError("threshold is a classifier's decision threshold; models='views' has none")
    classifier, regressor = (None, None) if views else split_models(load_models(models))
    obj = load_object(obj)
    n = int(candidates)
    p0, use_dir = sample_inputs(seed, 0, n)
    p0[:, 3:5] *= offset_range

    step("render")
    t0 = time.perf_counter()
    renderer = renderer_for(obj)
    k = min(n, FUSED_VIEWS) if views else n  # the views fusion reads: the first ones only
    depth = renderer.render(p0[:k])
    if sensor is not None:
        from ..vision.sensor import apply_sensor

        depth = apply_sensor(depth, sensor, np.arange(k))
    depth_mm = depth_to_mm(depth)
    timings["render"] = time.perf_counter() - t0

    probability = predicted = fused_score = fused_viable = fused_epsilon = None
    fused_robust_viable = fused_robust_epsilon = None
    if views:
        step("fuse")
        t0 = time.perf_counter()
        fused = fuse_candidate_views(
            depth_mm, renderer.poses(p0[:k]), renderer.camera, obj.name, sensed=sensor is not None
        )
        timings["fuse"] = time.perf_counter() - t0
        step("predict")
        t0 = time.perf_counter()

        def on_fused(q0, q_dir):
            # the task score, viability and ε of pregrasps simulated on the fused surface
            t = evaluate_inputs(
                fused, q0, q_dir, hand=hand, seed=seed, volume=False, frame=obj
            ).table
            eps = t.column("epsilon").to_numpy(zero_copy_only=False)
            return task_obj.evaluate(t, mode), is_viable(t), eps

        fused_score, fused_viable, fused_epsilon = on_fused(p0, use_dir)
        order = margin_order(fused_viable, fused_score, fused_epsilon)
        rule = (
            f"on the surface fused from {k} view{'' if k == 1 else 's'}: viable, then "
            f"{task_obj.name}-feasible, "
            "then the widest epsilon"
        )
        r = min(int(refine), n)
        if r > 0:
            # the pregrasp moves, the use direction stays
            drawn_near = nearby_inputs(
                np.concatenate([p0[order[:r]], use_dir[order[:r]]], axis=1),
                np.r_[np.full(6, PLAN_REFINE_SIGMA), 0.0, 0.0],
                PLAN_REFINE_NEIGHBOURS,
                np.random.default_rng(np.random.SeedSequence([int(seed), REFINE_STREAM])),
            )
            near_p0, near_dir = (
                drawn_near[:, :6],
                use_dir[np.repeat(order[:r], PLAN_REFINE_NEIGHBOURS)],
            )
            near_score, near_viable, near_epsilon = on_fused(near_p0, near_dir)
            p0 = np.concatenate([p0, near_p0])
            use_dir = np.concatenate([use_dir, near_dir])
            fused_score = np.concatenate([fused_score, near_score])
            fused_viable = np.concatenate([fused_viable, near_viable])
            fused_epsilon = np.concatenate([fused_epsilon, near_epsilon])
            order = margin_order(fused_viable, fused_score, fused_epsilon)
            rule += (
                f"; {PLAN_REFINE_NEIGHBOURS} candidates drawn near each of the first {r} "
                "and ranked with them"
            )
        m = min(int(robust_check), len(p0))
        if m > 0:
            top = order[:m]
            settings = ROBUST_CHECK_SETTINGS
            batch = simulate(fused, p0[top], use_dir[top], hand=hand, frame=obj)
            cols = MetricColumns(copy_metrics(fused, batch, settings, hand=hand, frame=obj))
            copies_eps = np.nan_to_num(
                np.asarray(cols["epsilon"], dtype=np.float64).reshape(m, settings.copies)
            )
            copies_viable = np.asarray(is_viable(cols), dtype=bool).reshape(m, settings.copies)
            fused_robust_viable = np.full(len(p0), np.nan)
            fused_robust_viable[top] = copies_viable.mean(axis=1)
            fused_robust_epsilon = np.full(len(p0), np.nan)
            fused_robust_epsilon[top] = np.quantile(copies_eps, ROBUST_CHECK_QUANTILE, axis=1)
            order = robust_first(order, fused_viable, fused_robust_epsilon[top], m)
            rule += (
                f"; of the first {m}, the widest epsilon that three in four of "
                f"{settings.copies} perturbations there reach"
            )
        timings["predict"] = time.perf_counter() - t0
    else:
        step("predict")
        t0 = time.perf_counter()
        names = np.full(n, obj.name, dtype=object)
        samples = Samples(
            names, names.copy(), np.arange(n), p0, use_dir, np.full(n, np.nan), depth_mm
        )
        order, probability, predicted = model_order(
            classifier, regressor, samples, threshold=threshold
        )
        timings["predict"] = time.perf_counter() - t0
        rule = rule_of(classifier, regressor, threshold)

    step("simulate")
    t0 = time.perf_counter()
    table = evaluate_inputs(obj, p0, use_dir, hand=hand, seed=seed, volume=False).table
    true_score = task_obj.evaluate(table, mode)
    viable = is_viable(table)
    timings["simulate"] = time.perf_counter() - t0

    # percentiles and the random choice among the drawn candidates (all, without refining)
    best = oracle_order(true_score, viable)
    measures = {
        "model": decision_measures(order, true_score, viable, among=n),
        "random": random_measures(true_score[:n], viable[:n]),
        "oracle": decision_measures(best, true_score, viable, among=n),
    }
    chosen = int(order[0])
    outcome = None
    if physics:
        step("physics")
        t0 = time.perf_counter()
        outcome = replay(obj, hand, table.slice(chosen, 1))
        timings["physics"] = time.perf_counter() - t0
    return Plan(
        object=obj.name,
        task=task_obj.name,
        chosen=chosen,
        order=order,
        p0=p0,
        use_dir=use_dir,
        probability=probability,
        predicted=predicted,
        true_score=true_score,
        viable=viable,
        percentile=measures["model"]["top1_percentile"],
        measures=measures,
        rule=rule,
        table=table,
        physics=outcome,
        timings=timings,
        offset_range=offset_range,
        fused_score=fused_score,
        fused_viable=fused_viable,
        fused_epsilon=fused_epsilon,
        fused_robust_viable=fused_robust_viable,
        fused_robust_epsilon=fused_robust_epsilon,
        drawn=n if len(p0) > n else None,
    )


def is_views_spec(spec: Any) -> bool:
    """Whether a model option names the fused views: ``"views"``, ``"views:RANKER"`` or a
    views model file (``.json``, :mod:`affordgrasp.learning.views_model`).

    Parameters
    ----------
    spec : object

    Returns
    -------
    bool
    """
    if isinstance(spec, str) and (spec == VIEWS or spec.startswith(VIEWS + ":")):
        return True
    return isinstance(spec, str | os.PathLike) and str(spec).endswith(".json")


def fuse_candidate_views(depth_mm, poses, camera, name: str, *, sensed: bool = False):
    """The surface ``plan`` decides on: candidates' depth images fused with its settings.

    Parameters
    ----------
    depth_mm : (k, size, size) uint16 ndarray
        The images in millimetres, as a dataset stores them and the models see them.
    poses : (k, 4, 4) float ndarray
        Their camera → object transforms, m.
    camera : DepthCamera
        Their camera.
    name : str
        The fused object's name.
    sensed : bool
        False (the default): exact images, fused with the nearest of four pixels and the
        seen voxels kept. True: a sensor model's images: lost returns next to a return are
        unknown and three votes carve (:data:`SENSOR_UNKNOWN_PX`, :data:`SENSOR_VOTES`),
        with the 3 × 3 filter alone (docs/learning.md).

    Returns
    -------
    GraspObject
        :func:`affordgrasp.vision.fusion.fused_object` of the views.
    """
    from ..vision.depth import depth_from_mm
    from ..vision.fusion import VOTES as FUSION_VOTES
    from ..vision.fusion import fused_object

    k = len(depth_mm)
    return fused_object(
        depth_from_mm(depth_mm),
        poses,
        camera,
        name=name,
        # one view: what it saw, solid behind
        votes=min(SENSOR_VOTES if sensed else FUSION_VOTES, k),
        unknown_px=SENSOR_UNKNOWN_PX if sensed else 0,
        # a sensor's noise makes the nearest of four pixels and the voxels of single
        # returns no better (and a noisy wall's seen voxels not always closed)
        subpixel=not sensed,
        keep_seen=not sensed,
    )


def load_models(models) -> list[tuple[Any, dict]]:
    """Models named or given, loaded (see :func:`plan`'s ``models``).

    Parameters
    ----------
    models : str, path or sequence

    Returns
    -------
    list of (torch.nn.Module, dict)
    """
    from .api import resolve_models
    from .io import load_model

    if isinstance(models, str) or hasattr(models, "__fspath__"):
        models = [models]
    loaded = []
    for m in models:
        if isinstance(m, tuple):
            loaded.append(m)
        else:
            loaded += [load_model(p) for p in resolve_models(m)]
    return loaded


def replay(obj, hand, row: pa.Table) -> dict:
    """The physics replay of one simulated grasp (the physics extra).

    Parameters
    ----------
    obj : GraspObject
    hand : Hand or str
    row : pyarrow.Table
        One row of an evaluation table (its ``hand_pose``, ``joints``, ``use_point`` and
        ``use_normal``).

    Returns
    -------
    dict
        ``GraspOutcome.to_row()``: ``hold_ok``, ``settled``, ``impact_ok``, ...; with
        ``status`` set when the grasp has no pose to replay.
    """
    from ..physics.scene import build_scene
    from ..physics.trials import validate_grasp

    pose = row.column("hand_pose")[0].as_py()
    joints = row.column("joints")[0].as_py()
    if pose is None or joints is None:
        return {"hold_ok": False, "settled": False, "status": "no grasp to replay"}
    up = row.column("use_point")[0].as_py()
    un = row.column("use_normal")[0].as_py()
    scene = build_scene(hand, obj)
    outcome = validate_grasp(
        scene,
        np.asarray(pose, dtype=np.float64).reshape(4, 4),
        np.asarray(joints, dtype=np.float64),
        None if up is None else np.asarray(up, dtype=np.float64),
        None if un is None else np.asarray(un, dtype=np.float64),
    )
    return outcome.to_row()
