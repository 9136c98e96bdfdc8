"""From a camera view to a grasp: sample candidates, look, predict, choose, check
(conventions: Vision).

:func:`plan` (``affordgrasp.plan``) does what a robot with a camera in its hand would do,
then says how good the decision truly was:

1. draw ``candidates`` pregrasps p0 and use directions d (sample i depends only on
   (seed, i), as in a generated dataset), uniform but for the approach line's offsets
   (u4, u5), drawn in [-r, r]² with r = ``offset_range`` (default :data:`OFFSET_RANGE`:
   a planner aims near the object; 1 is the dataset's uniform draw);
2. render the candidates' camera-in-hand depth images D(p0, O) in one batch
   (:func:`candidate_views`; every candidate's for the networks; the first
   :data:`FUSED_VIEWS`, those it fuses, for ``models="views"`` and ``"learned"``);
3. by default (``models="views"``) fuse the first :data:`FUSED_VIEWS` images into a
   surface (:mod:`affordgrasp.vision.fusion`) and simulate every candidate on it, placed
   on the surface's own hull (for a task that reads the use point, each grasp with its
   best use point there); with ``models="learned"`` score every candidate on that
   surface's cloud (:mod:`affordgrasp.learning.scorer`) and simulate its first ``verify``
   there; or predict with networks in one batch;
4. choose (:func:`decide_on_fused`): on the fused surface's simulation, viable there
   first, then by the task probability (beat, cut) or, for other tasks,
   :func:`~affordgrasp.learning.decisions.margin_order` (task-feasible, then the widest
   ε); more candidates drawn near its first ``refine`` ones, simulated there and ranked
   with them; the first ``robust_check`` of all simulated there again under
   perturbations and the one that fares best under them first (the robust task
   probability, or the widest ε the copies keep;
   :func:`~affordgrasp.learning.decisions.robust_first`); with models by
   :func:`~affordgrasp.learning.decisions.decision_order` (a classifier alone: the most
   probably viable; with a regressor as well, the classifier's decision threshold, then
   least predicted effort);
5. simulate every candidate (not only the chosen one), so the chosen grasp's true task
   score, viability and percentile among the candidates' true scores are known; with
   ``physics=True`` replay the chosen grasp in MuJoCo (the physics extra).

The simulation of step 5 is the check, not part of the decision: the deciders see only the
depth images and the poses (the fused surface is made from the images alone), and the
views are aimed from a believed pose of the object (``pose_error``).
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
    PLAN_USES,
    PLAN_VERIFY,
    POSE_ERROR_DEG,
    POSE_ERROR_M,
)
from ..robust import RobustSettings
from .decisions import (
    decision_measures,
    decision_order,
    decision_threshold,
    margin_order,
    oracle_good,
    oracle_order,
    random_measures,
    robust_first,
    task_feasible,
)

OFFSET_RANGE = PLAN_OFFSET_RANGE  # the candidates' offsets (u4, u5) lie in [-R, R]² (pregrasp)
VIEWS = "views"  # the decider that fuses the candidates' views and simulates on the surface
LEARNED = "learned"  # the learned scorer of candidates on the fused cloud (learning.scorer)
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
# A predictor's perturbed copies draw from a stream of their own: the robust labels' copies
# (seed 0) are not the predictor's, or the labels would judge draws they share.
PERTURBATION_SEED = 0x51DE
ROBUST_CHECK_SETTINGS = RobustSettings(
    copies=12,
    translation_m=0.0025,
    rotation_rad=math.radians(1.5),
    com_m=0.00125,
    tasks=(),
    seed=PERTURBATION_SEED,
)
# A task probability's robust check: its robust model reads copies at the robust labels'
# scales (the ones it was fitted on), 12 of them
TASK_CHECK_SETTINGS = RobustSettings(copies=12, tasks=(), seed=PERTURBATION_SEED)

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
    feasible : (n,) bool ndarray or None
        Simulated task feasibility of every candidate
        (:func:`~affordgrasp.learning.decisions.task_feasible`); None: a finite score.
    use_point : (n, 3) float64 ndarray or None
        With ``models="views"`` and a task that reads the use point: each candidate's use
        point on the fused surface (the best of the use points paired with its grasp
        there; NaN where its use ray missed the surface); the true check uses the use ray
        from the true centre of mass through the true surface's point closest to it (its
        last hit: that point, unless the ray meets the surface again beyond it). Else
        None.
    fused_robust_score : (n,) float64 ndarray or None
        With a task probability that reads the use point and ``robust_check``: the task's
        robust probability on the fused surface of the candidates re-simulated (NaN for the
        others); else None.
    pose_error : tuple of float or None
        The pose estimate's error the views were aimed with (m, degrees); None: aimed from
        the true object.
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
    feasible: np.ndarray | None = None
    use_point: np.ndarray | None = None
    fused_robust_score: np.ndarray | None = None
    pose_error: tuple[float, float] | None = None

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
                "fused_robust_score": (
                    None
                    if self.fused_robust_score is None
                    or not np.isfinite(self.fused_robust_score[c])
                    else float(self.fused_robust_score[c])
                ),
                "fused_use_point": (
                    None
                    if self.use_point is None or not np.isfinite(self.use_point[c]).all()
                    else self.use_point[c].tolist()
                ),
                "true_score": float(self.true_score[c]),
                "viable": bool(self.viable[c]),
                "feasible": bool(self._feasible()[c]),
                "percentile": self.percentile,
                **self._parts(c),
            },
            "pose_error": None if self.pose_error is None else list(self.pose_error),
            "candidates_viable": int(self.viable.sum()),
            "candidates_feasible": int(self._feasible().sum()),
            "measures": self.measures,
            "physics": self.physics,
            "timings": dict(self.timings),
        }

    def _feasible(self) -> np.ndarray:
        if self.feasible is None:
            return np.isfinite(self.true_score)
        return self.feasible

    def _parts(self, c: int) -> dict:
        # where the chosen grasp truly touches and uses the object (labelled objects only)
        out = {}
        names = self.table.column_names
        for column in ("use_part", "contact_parts"):
            if column in names:
                out[column] = self.table.column(column)[c].as_py()
        if "use_point" in names:
            out["use_point"] = self.table.column("use_point")[c].as_py()
        return out


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
    pose_error: tuple[float, float] | None = (POSE_ERROR_M, POSE_ERROR_DEG),
    uses: int = PLAN_USES,
    verify: int = PLAN_VERIFY,
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
        it, placed on its hull, and the candidates are ranked on that simulation
        (:func:`decide_on_fused`: viable there first, then the task probability or
        task-feasible by decreasing ε); the first ``refine`` of them get
        neighbours, simulated there as well, and the first ``robust_check`` of all are
        checked under perturbation (needs scikit-image, the ``learn`` extra; the chosen
        grasp's viability on unseen objects: docs/learning.md; the shipped classifier's:
        0.37).
        ``"learned"``: the same fused surface read as a cloud by the shipped scorer
        (:mod:`affordgrasp.learning.scorer`), the most probably viable candidate first
        (tasks that read no use point).
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
    pose_error : (float, float) or None
        The error of the robot's estimate of the object's pose, (metres, degrees): the
        views are aimed from the object moved by that much (a translation of that length
        and a rotation of that angle about the box centre, in directions drawn from
        ``seed``, :func:`affordgrasp.vision.camera.pose_error_transform`). Default 1 cm
        and 5°; None or (0, 0): aimed from the true object. With ``models="views"`` the
        candidates are placed on the fused surface's hull either way, and nothing of the
        decision reads the object but through the images; learned models' candidates are
        placed from the believed object.
    uses : int
        With ``models="views"`` and a task that reads the use point: use points drawn on the
        fused surface and paired with every grasp (default :data:`PLAN_USES`).
    verify : int
        With ``models="learned"``: how many of the scorer's first candidates are simulated
        on the fused surface, the viable one with the widest ε there first (0: the scorer's
        order as it is; default ``grasp.pregrasp.PLAN_VERIFY``).
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
    drawn candidates alone, the uniform draw a planner without a decider would choose
    from (for a task that reads the use point, each with the use point the pairing on the
    fused surface gave it). A task probability's candidate is task-feasible when its value
    reaches 0.5 (p_T to six decimals).
    """
    from ..grasp.pregrasp import directions_towards, sample_inputs, use_points
    from ..objects import load_object
    from ..pipeline import evaluate_inputs
    from ..tasks import get_task, is_viable
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
    if isinstance(uses, bool) or not isinstance(uses, int | np.integer) or uses < 1:
        raise InputError(f"uses must be an integer >= 1, got {uses!r}")
    if isinstance(verify, bool) or not isinstance(verify, int | np.integer) or verify < 0:
        raise InputError(f"verify must be an integer >= 0, got {verify!r}")
    pose_error = _pose_error(pose_error)
    task_obj = get_task(task)
    task_obj.thresholds_for(mode)  # an unknown mode fails before any work
    step = progress or (lambda name: None)
    timings: dict[str, float] = {}
    views = isinstance(models, str) and models == VIEWS
    learned = isinstance(models, str) and models == LEARNED
    on_fused = views or learned  # deciders that read the surface fused from the views
    if not views and is_views_spec(models):
        raise InputError(
            f"plan decides on the fused views with models='views' (its own rule: margin "
            f"order, refined candidates, the robust check); {str(models)!r} is for "
            "model-eval and predict, which judge the views row by row"
        )
    if on_fused and threshold is not None:
        raise InputError(
            f"threshold is a learned classifier's decision threshold; models={models!r} has none"
        )
    classifier, regressor = (None, None) if on_fused else split_models(load_models(models))
    scorer = None
    if learned:
        from ..columns import USE_METRICS
        from .scorer import load_scorer

        if set(USE_METRICS) & set(task_obj.requires):
            raise InputError(
                f"the learned scorer predicts whether the grip is viable; {task_obj.name} "
                "also needs a use point: decide it on the views (--model views)"
            )
        scorer = load_scorer()
    obj = load_object(obj)
    n = int(candidates)
    p0, use_dir = sample_inputs(seed, 0, n)
    p0[:, 3:5] *= offset_range

    step("render")
    t0 = time.perf_counter()
    k = min(n, FUSED_VIEWS) if on_fused else n  # the fusion reads the first ones only
    seen = candidate_views(obj, p0[:k], seed=seed, pose_error=pose_error, sensor=sensor)
    depth_mm, error = seen.depth_mm, seen.error
    timings["render"] = time.perf_counter() - t0

    probability = predicted = None
    fused = None
    if on_fused:
        step("fuse")
        t0 = time.perf_counter()
        fused = seen.fuse()
        timings["fuse"] = time.perf_counter() - t0
    if views:
        step("predict")
        t0 = time.perf_counter()
        decided = decide_on_fused(
            fused,
            task_obj,
            p0,
            use_dir,
            mode=mode,
            hand=hand,
            seed=seed,
            refine=refine,
            robust_check=robust_check,
            uses=uses,
            views=k,
        )
        p0, use_dir, order, rule = decided.p0, decided.use_dir, decided.order, decided.rule
        timings["predict"] = time.perf_counter() - t0
        frame = fused  # the candidates were placed on the fused surface
    elif scorer is not None and fused is not None:  # fused: on_fused
        from .scorer import score_candidates

        decided = None
        step("predict")
        t0 = time.perf_counter()
        probability = score_candidates(scorer, fused, p0, hand)
        order = np.lexsort((np.arange(n), -probability))  # the most probably viable first
        rule = (
            f"the learned scorer on the cloud fused from {k} view{'' if k == 1 else 's'}: "
            "the most probably viable"
        )
        m = min(int(verify), n)
        if m > 0:
            # its first m simulated on the fused surface: viable there, then the widest ε
            top = order[:m]
            t = evaluate_inputs(fused, p0[top], use_dir[top], hand=hand, seed=seed,
                                volume=False, frame=fused).table  # fmt: skip
            eps = np.nan_to_num(t.column("epsilon").to_numpy(zero_copy_only=False))
            order[:m] = top[np.lexsort((-eps, ~np.asarray(is_viable(t), dtype=bool)))]
            rule += f"; of its first {m}, viable on the fused surface, then the widest epsilon"
        timings["predict"] = time.perf_counter() - t0
        frame = fused
    else:
        decided = None
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
        frame = None if error is None else _believed_object(obj, error)

    step("simulate")
    t0 = time.perf_counter()
    true_dir = use_dir
    fused_point = None
    if decided is not None and decided.pairs and fused is not None:
        # the robot uses the point it chose on the fused surface: on the true object, the
        # true surface's point closest to it (the use ray from the true centre of mass
        # through that point; the object's own centre of mass may lie centimetres from the
        # fused surface's, a hammer's steel head)
        import trimesh

        fused_point, _, hit = use_points(fused.mesh, fused.mass.center_of_mass, use_dir)
        true_dir = use_dir.copy()
        if np.any(hit >= 0):
            closest, _, _ = trimesh.proximity.closest_point(obj.mesh, fused_point[hit >= 0])
            true_dir[hit >= 0] = directions_towards(obj.mass.center_of_mass, closest)
    table = evaluate_inputs(obj, p0, true_dir, hand=hand, seed=seed, volume=False, frame=frame)
    table = table.table
    true_score = task_obj.evaluate(table, mode)
    viable = is_viable(table)
    feasible = task_feasible(task_obj, true_score)
    timings["simulate"] = time.perf_counter() - t0

    # percentiles and the random choice among the drawn candidates (all, without refining)
    best = oracle_order(true_score, oracle_good(task_obj, true_score, viable))
    measures = {
        "model": decision_measures(order, true_score, viable, among=n, feasible=feasible),
        "random": random_measures(true_score[:n], viable[:n], feasible=feasible[:n]),
        "oracle": decision_measures(best, true_score, viable, among=n, feasible=feasible),
    }
    chosen = int(order[0])
    outcome = None
    if physics:
        step("physics")
        t0 = time.perf_counter()
        outcome = replay(obj, hand, table.slice(chosen, 1), trials=trial_names(task_obj.name))
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
        fused_score=None if decided is None else decided.score,
        fused_viable=None if decided is None else decided.viable,
        fused_epsilon=None if decided is None else decided.epsilon,
        fused_robust_viable=None if decided is None else decided.robust_viable,
        fused_robust_epsilon=None if decided is None else decided.robust_epsilon,
        drawn=n if len(p0) > n else None,
        feasible=feasible,
        use_point=fused_point,
        fused_robust_score=None if decided is None else decided.robust_score,
        pose_error=pose_error,
    )


def _pose_error(value) -> tuple[float, float] | None:
    """``plan``'s pose error as (m, degrees), or None for none."""
    if value is None or (
        isinstance(value, int | float) and not isinstance(value, bool) and value == 0
    ):
        return None
    if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
        raise InputError(f"pose_error must be (metres, degrees) or None, got {value!r}")
    try:
        m, deg = (float(v) for v in value)
    except (TypeError, ValueError):
        raise InputError(f"pose_error must be (metres, degrees) or None, got {value!r}") from None
    if not (math.isfinite(m) and math.isfinite(deg)) or m < 0 or deg < 0:
        raise InputError(f"pose_error must be a distance >= 0 and an angle >= 0, got {value!r}")
    return None if m == 0 and deg == 0 else (m, deg)


def _believed_object(obj, error: np.ndarray):
    """The object where the robot believes it is (it places a learned model's candidates)."""
    from ..objects import object_from_mesh

    mesh = obj.mesh.copy()
    mesh.apply_transform(error)
    return object_from_mesh(mesh, f"{obj.name} (believed)", simplify_above=None)


def trial_names(task: str) -> tuple[str, ...]:
    """The task trials that judge a task's decision in physics (beside the hold test).

    Parameters
    ----------
    task : str
        A task's name (``beat``, ``beat-rules``, ``cut-ug``, ...).

    Returns
    -------
    tuple of str
        ``("beat",)`` or ``("cut",)`` for the tasks of a hammer or a knife, else ``()``.
    """
    base = task.split("-")[0]
    return (base,) if base in ("beat", "cut") else ()


@dataclass(frozen=True)
class FusedDecision:
    """``plan``'s decision on a fused surface (:func:`decide_on_fused`).

    Attributes
    ----------
    p0 : (n, 6) float64 ndarray
        The candidates, refined ones appended.
    use_dir : (n, 2) float64 ndarray
        Their use directions (with ``pairs``: each grasp's best use point on the surface).
    order : (n,) int64 ndarray
        Best first.
    rule : str
        The decision rule in words.
    score, viable, epsilon : (n,) ndarray
        The task's value, viability and ε simulated on the fused surface.
    robust_viable, robust_epsilon, robust_score : (n,) float64 ndarray or None
        The robust check's share of copies viable, ε quantile and (task probabilities) the
        robust probability, NaN for the candidates not checked; None without a check.
    pairs : bool
        Whether the grasps were paired with use points on the surface.
    """

    p0: np.ndarray
    use_dir: np.ndarray
    order: np.ndarray
    rule: str
    score: np.ndarray
    viable: np.ndarray
    epsilon: np.ndarray
    robust_viable: np.ndarray | None
    robust_epsilon: np.ndarray | None
    robust_score: np.ndarray | None
    pairs: bool


def decide_on_fused(
    fused,
    task,
    p0: np.ndarray,
    use_dir: np.ndarray,
    *,
    mode: str = "default",
    hand="barrett",
    seed: int = 0,
    refine: int = PLAN_REFINE,
    robust_check: int = PLAN_ROBUST_CHECK,
    uses: int = PLAN_USES,
    views: int = FUSED_VIEWS,
) -> FusedDecision:
    """Rank candidates on a surface fused from views: what ``plan`` decides with.

    It reads the fused surface and the candidates, never the object: the candidates are
    placed on the surface's own hull. For a task that reads the use point, every grasp is
    paired with ``uses`` use points drawn by area on the surface and takes its best one
    (:func:`affordgrasp.search.pairs.pair_scores`); a task probability then ranks by its
    value (ε breaks ties), a task of tests by :func:`margin_order`. The first ``refine``
    get neighbours; the first ``robust_check`` are simulated again under perturbations.

    Parameters
    ----------
    fused : GraspObject
        The fused surface.
    task : Task
    p0 : (n, 6) float ndarray
    use_dir : (n, 2) float ndarray
    mode : str
    hand : Hand or str
    seed : int
        The plan's seed (the refined candidates' and the use points' draws).
    refine, robust_check, uses : int
        As for :func:`plan`.
    views : int
        Views fused (for the rule's words).

    Returns
    -------
    FusedDecision
    """
    from ..columns import USE_METRICS
    from ..grasp.policy import simulate
    from ..pipeline import evaluate_inputs
    from ..robust import copy_metrics
    from ..search.cem import nearby_inputs
    from ..search.pairs import PAIR_GRASPS, best_use_per_grasp, pair_scores
    from ..search.use_points import draw_use_points
    from ..tasks import is_viable
    from ..tasks.metric_columns import MetricColumns

    pairs = bool(set(USE_METRICS) & set(task.requires))
    by_value = pairs and task.probability
    points = (
        draw_use_points(fused, task, int(uses), seed + 1, mode, {}, None, False)[0]
        if pairs
        else None
    )
    n_uses = 0 if points is None else len(points.triangle)

    def on_fused(q0, q_dir):
        # the task's value, viability and ε of pregrasps simulated on the fused surface,
        # each grasp with its best use point there
        t = evaluate_inputs(fused, q0, q_dir, hand=hand, seed=seed, volume=False, frame=fused)
        t = t.table
        eps = t.column("epsilon").to_numpy(zero_copy_only=False)
        score = task.evaluate(t, mode)
        if points is not None:
            # pair_scores pairs at most PAIR_GRASPS grasps of a call: every grasp here
            best = np.full(len(q0), -np.inf)
            best_use = np.full(len(q0), -1, dtype=np.int64)
            for first in range(0, len(q0), PAIR_GRASPS):
                part = t.slice(first, PAIR_GRASPS)
                b, u = best_use_per_grasp(
                    pair_scores(fused, part, points, task.name, mode), part.num_rows
                )
                best[first : first + part.num_rows] = b
                best_use[first : first + part.num_rows] = u
            has = best_use >= 0
            q_dir = q_dir.copy()
            q_dir[has] = points.use_dir[best_use[has]]
            score = np.where(has, best, score)
        return score, is_viable(t), eps, q_dir

    def ranked(viable, score, eps):
        if by_value:  # viable first, the most probable first, the widest ε among ties
            e = np.nan_to_num(np.asarray(eps, dtype=np.float64), nan=0.0)
            v = np.asarray(viable, dtype=bool)
            return np.lexsort((-e, -np.nan_to_num(score, nan=-np.inf), ~v))
        return margin_order(viable, score, eps)

    score, viable, epsilon, use_dir = on_fused(p0, use_dir)
    order = ranked(viable, score, epsilon)
    plural = "" if views == 1 else "s"
    if by_value:
        rule = (
            f"on the surface fused from {views} view{plural}, each grasp with its best of "
            f"{n_uses} use points there: viable, then the highest {task.name} probability"
        )
    else:
        rule = (
            f"on the surface fused from {views} view{plural}"
            + (f", each grasp with its best of {n_uses} use points" if pairs else "")
            + f": viable, then {task.name}-feasible, then the widest epsilon"
        )
    n = len(p0)
    r = min(int(refine), n)
    if r > 0:
        # the pregrasp moves, the use direction stays
        drawn_near = nearby_inputs(
            np.concatenate([p0[order[:r]], use_dir[order[:r]]], axis=1),
            np.r_[np.full(6, PLAN_REFINE_SIGMA), 0.0, 0.0],
            PLAN_REFINE_NEIGHBOURS,
            np.random.default_rng(np.random.SeedSequence([int(seed), REFINE_STREAM])),
        )
        near_p0 = drawn_near[:, :6]
        near_dir = use_dir[np.repeat(order[:r], PLAN_REFINE_NEIGHBOURS)]
        near_score, near_viable, near_epsilon, near_dir = on_fused(near_p0, near_dir)
        p0 = np.concatenate([p0, near_p0])
        use_dir = np.concatenate([use_dir, near_dir])
        score = np.concatenate([score, near_score])
        viable = np.concatenate([viable, near_viable])
        epsilon = np.concatenate([epsilon, near_epsilon])
        order = ranked(viable, score, epsilon)
        rule += (
            f"; {PLAN_REFINE_NEIGHBOURS} candidates drawn near each of the first {r} "
            "and ranked with them"
        )
    robust_viable = robust_epsilon = robust_score = None
    m = min(int(robust_check), len(p0))
    if m > 0 and by_value:
        top = order[:m]
        t = evaluate_inputs(
            fused,
            p0[top],
            use_dir[top],
            hand=hand,
            seed=seed,
            volume=False,
            robust=TASK_CHECK_SETTINGS,
            frame=fused,
        ).table
        robust_score = np.full(len(p0), np.nan)
        robust_score[top] = task.evaluate(t, mode)  # the task's robust model
        order = robust_first(order, viable, robust_score[top], m)
        rule += (
            f"; of the first {m}, the highest robust {task.name} probability over "
            f"{TASK_CHECK_SETTINGS.copies} perturbations there"
        )
    elif m > 0:
        top = order[:m]
        settings = ROBUST_CHECK_SETTINGS
        batch = simulate(fused, p0[top], use_dir[top], hand=hand, frame=fused)
        cols = MetricColumns(copy_metrics(fused, batch, settings, hand=hand, frame=fused))
        copies_eps = np.nan_to_num(
            np.asarray(cols["epsilon"], dtype=np.float64).reshape(m, settings.copies)
        )
        copies_viable = np.asarray(is_viable(cols), dtype=bool).reshape(m, settings.copies)
        robust_viable = np.full(len(p0), np.nan)
        robust_viable[top] = copies_viable.mean(axis=1)
        robust_epsilon = np.full(len(p0), np.nan)
        robust_epsilon[top] = np.quantile(copies_eps, ROBUST_CHECK_QUANTILE, axis=1)
        order = robust_first(order, viable, robust_epsilon[top], m)
        rule += (
            f"; of the first {m}, the widest epsilon that three in four of "
            f"{settings.copies} perturbations there reach"
        )
    return FusedDecision(
        p0,
        use_dir,
        order,
        rule,
        score,
        viable,
        epsilon,
        robust_viable,
        robust_epsilon,
        robust_score,
        pairs,
    )


@dataclass
class CandidateViews:
    """The candidates' camera-in-hand views of an object, aimed from a believed pose.

    Attributes
    ----------
    depth_mm : (k, size, size) uint16 ndarray
        The images in millimetres.
    poses : (k, 4, 4) float ndarray
        Their camera → object transforms (the believed object's), m.
    camera : DepthCamera
    error : (4, 4) float ndarray or None
        The pose error: believed pose = ``error`` applied to the true one.
    name : str
        The object's name.
    sensed : bool
        Whether the images went through a sensor model.
    """

    depth_mm: np.ndarray
    poses: np.ndarray
    camera: Any
    error: np.ndarray | None
    name: str
    sensed: bool

    def fuse(self):
        """The surface fused from the views (:func:`fuse_candidate_views`).

        Returns
        -------
        GraspObject
        """
        return fuse_candidate_views(
            self.depth_mm, self.poses, self.camera, self.name, sensed=self.sensed
        )


def candidate_views(
    obj,
    p0: np.ndarray,
    *,
    seed: int = 0,
    pose_error: tuple[float, float] | None = None,
    sensor=None,
) -> CandidateViews:
    """Render the candidates' views as a robot would: aimed from where it believes the
    object is (the true object moved by the pose error; the images are of the true one).

    Parameters
    ----------
    obj : GraspObject
    p0 : (k, 6) float ndarray
        The pregrasps whose views are rendered.
    seed : int
        Draws the pose error's directions.
    pose_error : (float, float) or None
        (metres, degrees), as for :func:`plan`.
    sensor : SensorModel, optional
        Image i's noise keyed by i; None: exact images.

    Returns
    -------
    CandidateViews
    """
    from ..vision.camera import camera_poses, pose_error_transform
    from ..vision.depth import depth_to_mm, renderer_for

    renderer = renderer_for(obj)
    error = (
        None
        if pose_error is None
        else pose_error_transform(renderer.frame.centre, *pose_error, seed)
    )
    aim = renderer.frame if error is None else renderer.frame.moved(error)
    poses = camera_poses(aim, p0)
    depth = renderer.render_poses(poses)
    if sensor is not None:
        from ..vision.sensor import apply_sensor

        depth = apply_sensor(depth, sensor, np.arange(len(p0)))
    return CandidateViews(
        depth_to_mm(depth), poses, renderer.camera, error, obj.name, sensor is not None
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


def replay(obj, hand, row: pa.Table, trials: Sequence[str] = ()) -> dict:
    """The physics replay of one simulated grasp (the physics extra).

    Parameters
    ----------
    obj : GraspObject
    hand : Hand or str
    row : pyarrow.Table
        One row of an evaluation table (its ``hand_pose``, ``joints``, ``use_point`` and
        ``use_normal``).
    trials : sequence of str
        Task trials to run as well (``"beat"``, ``"cut"``;
        :mod:`affordgrasp.physics.task_trials`): their ``beat_ok`` / ``cut_ok`` and
        measured quantities join the outcome.

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
    if trials:
        from ..physics.run import validate_rows
        from ..physics.settings import PhysicsSettings

        out = validate_rows(row, hand, {obj.name: obj}, PhysicsSettings(), trials=tuple(trials))
        # the outcome and the trials' columns (not the row's own metrics again)
        return {k: v[0] for k, v in out.to_pydict().items() if k not in row.column_names}
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
