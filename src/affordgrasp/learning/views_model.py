"""The fused views as a model: what ``plan`` decides with, judged row by row as the
learned models are (``affordgrasp model-eval views DATASET``).

For each object, the first :data:`~affordgrasp.learning.plan.FUSED_VIEWS` of ``plan``'s
candidate views (seed 0, the offsets ``plan`` draws) are rendered and fused into a surface
(:func:`~affordgrasp.learning.plan.fuse_candidate_views`); every row is simulated on that
surface from the pose it has on the object, with K perturbed copies (the robust labels'
default perturbations, :mod:`affordgrasp.robust`). Two predictions come of it:

* the **classifier** of ``viable``: the share of the copies viable on the fused surface
  (ties broken by the fused ε), mapped through a non-decreasing calibration map fitted on
  validation objects (isotonic regression of their true viability on the share); the map
  is strictly increasing, so it changes no ranking;
* the **ranker** of ``robust_hold``: the fused surface's own ``robust_hold``; or, with
  ``views:raw``, of the raw ΣE_h on viable rows: the fused surface's ΣE_h (the viability
  bound, 250 N, where the grasp does not hold there).

Nothing is learned but the calibration map and the decision threshold, stored in
``pretrained/views.json`` (:func:`fit_views_config` writes one; ``tools/fit_views_model.py``
rebuilds the shipped one). The cost is one simulation per row and copy on the fused
surface (about 8 s of CPU per 512 rows with K = 25 on one core) where a network predicts in
a fraction of a millisecond: a model to judge the views by, and the reference the learned
models are measured against (docs/learning.md).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..columns import HOLD_EFFORT_COLUMNS
from ..errors import InputError
from ..runtime.writing import atomic_write
from .plan import FUSED_VIEWS, OFFSET_RANGE, PERTURBATION_SEED, fuse_candidate_views
from .plan import VIEWS as ARCH
from .targets import Target, make_target

FORMAT = "affordgrasp-views"
FORMAT_VERSION = 1
VIEWS_FILE = "views.json"
DEFAULT_COPIES = 25  # K of the copies simulated on the fused surface (the robust labels' K)
# the ε tie-break inside one share of copies: below the step between shares (1/K, K <= 100)
TIE_BREAK = 1e-3
# the calibrated probability's own slope: keeps the map strictly increasing (no ties made),
# moving a probability by at most this much
MAP_SLOPE = 1e-3
CLASSIFIER_TARGET = Target("viable", "classification", "all")
# robust_hold counts the load directions held (one per hold-effort column), less under 1/K
RANKER_TARGET = Target(
    "robust_hold", "regression", "finite", 0.0, float(len(HOLD_EFFORT_COLUMNS)), False, False
)
RAW_RANKER_TARGET = make_target("hold_effort_sum")  # ΣE_h on viable rows, [0, 250] N
RANKERS = {"robust": RANKER_TARGET, "raw": RAW_RANKER_TARGET}


def views_config_path() -> Path:
    """The shipped views model's file (its calibration map and decision threshold).

    Returns
    -------
    pathlib.Path
    """
    return Path(str(resources.files("affordgrasp.learning") / "pretrained" / VIEWS_FILE))


def read_views_config(path: str | os.PathLike | None = None) -> dict:
    """A views model's file: its settings, calibration map and decision threshold.

    Parameters
    ----------
    path : path, optional
        A file written by :func:`fit_views_config` (default: the shipped one).

    Returns
    -------
    dict

    Raises
    ------
    InputError
        When the file is missing, not JSON or not a views model.
    """
    path = Path(path) if path is not None else views_config_path()
    try:
        config = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(
            f"views model file {str(path)!r} does not exist"
            + (
                "; rebuild the shipped one with 'python tools/fit_views_model.py'"
                if path == views_config_path()
                else ""
            )
        ) from None
    except (OSError, ValueError) as exc:
        raise InputError(f"views model file {str(path)!r} is not readable JSON: {exc}") from None
    if not isinstance(config, dict) or config.get("format") != FORMAT:
        raise InputError(
            f"{str(path)!r} is not a views model file (format {FORMAT!r}); model files are "
            ".safetensors, views model files .json written by fit_views_config"
        )
    if config.get("format_version", 0) > FORMAT_VERSION:
        raise InputError(
            f"{str(path)!r} is a views model file of format version "
            f"{config['format_version']}; this affordgrasp reads up to {FORMAT_VERSION}: "
            "upgrade affordgrasp"
        )
    for key, least in (("views", 1), ("copies", 1), ("seed", 0), ("perturbation_seed", 0)):
        value = config.get(key, 0 if key == "perturbation_seed" else None)
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise InputError(f"{str(path)!r}: {key!r} must be an integer >= {least}, got {value!r}")
    calibration = config.get("calibration") or {}
    xs, ys = calibration.get("share", []), calibration.get("rate", [])
    if len(xs) != len(ys) or any(b < a for a, b in zip(xs, xs[1:], strict=False)):
        raise InputError(f"{str(path)!r}: the calibration map's knots are not increasing pairs")
    return config


def load_views_models(spec: str | os.PathLike = ARCH, *, log=None, workers: int = 1):
    """The views classifier and ranker as ``(predictor, config)`` pairs, as models load.

    Parameters
    ----------
    spec : str or path
        ``"views"`` or ``"views:robust"`` (the shipped calibration; the ranker of
        ``robust_hold``, which needs a dataset with robust labels to judge),
        ``"views:raw"`` (the ranker of ΣE_h on viable rows), or a views model file (the
        ranker of ``robust_hold``).
    log : callable, optional
        Called with a line of progress per object predicted.
    workers : int
        Processes simulating objects side by side (:class:`FusedViews`).

    Returns
    -------
    list of (FusedViews, dict)
        The classifier first; both share one predictor (each row is simulated once).
    """
    name, _, which = str(spec).partition(":")
    shipped = name == ARCH
    if shipped and which and which not in RANKERS:
        raise InputError(
            f"unknown views ranker {which!r} in {str(spec)!r}; choose views (robust_hold), "
            "views:robust or views:raw (hold_effort_sum)"
        )
    config = read_views_config(None if shipped else spec)
    predictor = FusedViews(config, log=log, workers=workers)
    ranker = {k: v for k, v in config.items() if k != "decision_threshold"}
    target = RANKERS[which or "robust"] if shipped else RANKER_TARGET
    return [
        (predictor, {**config, "arch": ARCH, "target": CLASSIFIER_TARGET.to_dict()}),
        (predictor, {**ranker, "arch": ARCH, "target": target.to_dict()}),
    ]


def views_candidates(views: int, seed: int = 0) -> np.ndarray:
    """The pregrasps whose views are fused: ``plan``'s first candidates.

    Parameters
    ----------
    views : int
    seed : int
        ``plan``'s seed.

    Returns
    -------
    (views, 6) float64 ndarray
    """
    from ..grasp.pregrasp import sample_inputs

    p0, _ = sample_inputs(seed, 0, views)
    p0[:, 3:5] *= OFFSET_RANGE
    return p0


def perturbation_seed(config: dict) -> int:
    """The seed of a views model's perturbed copies (its card's ``perturbation_seed``).

    Parameters
    ----------
    config : dict
        A views model file's contents.

    Returns
    -------
    int
        :data:`~affordgrasp.learning.plan.PERTURBATION_SEED` for files written before the
        card stated it (they drew the labels' own perturbations, seed 0, which a prediction
        must not share).
    """
    return int(config.get("perturbation_seed", PERTURBATION_SEED))


def fused_surface(obj, *, views: int, seed: int = 0):
    """The surface ``plan`` (seed ``seed``) fuses from an object's first ``views`` views,
    aimed from the true object (``plan(..., pose_error=None)``; plan's default aims them
    from a pose estimate 1 cm and 5° off).

    Parameters
    ----------
    obj : GraspObject
    views : int
    seed : int

    Returns
    -------
    GraspObject
    """
    from ..vision.depth import depth_to_mm, renderer_for

    seen = views_candidates(views, seed)
    renderer = renderer_for(obj)
    return fuse_candidate_views(
        depth_to_mm(renderer.render(seen)), renderer.poses(seen), renderer.camera, obj.name
    )


def simulate_on_fused(
    surface, obj, hand, p0, use_dir, copies: int, perturbation_seed: int = PERTURBATION_SEED
) -> np.ndarray:
    """Rows simulated on a fused surface from the poses they have on the object.

    Parameters
    ----------
    surface : GraspObject
        The fused surface (:func:`fused_surface`).
    obj : GraspObject
        The object (it places the pregrasps and the copies' starts).
    hand : Hand
    p0 : (n, 6) float ndarray
    use_dir : (n, 2) float ndarray
    copies : int
        K perturbed copies per row.
    perturbation_seed : int
        Seed of their perturbations (:class:`affordgrasp.robust.RobustSettings`); default
        :data:`~affordgrasp.learning.plan.PERTURBATION_SEED`, a stream of its own: the
        robust labels' copies (seed 0) are not the predictor's.

    Returns
    -------
    (n, 4) float64 ndarray
        Share of viable copies, ε, ``robust_hold``, ΣE_h (N; 250 where it does not hold).
    """
    from ..columns import hold_effort_sum
    from ..pipeline import evaluate_inputs
    from ..robust import RobustSettings

    settings = RobustSettings(copies=int(copies), seed=int(perturbation_seed))
    table = evaluate_inputs(surface, p0, use_dir, hand=hand, robust=settings, frame=obj).table
    cols = [
        np.nan_to_num(table.column(c).to_numpy(zero_copy_only=False).astype(np.float64))
        for c in ("robust_viable", "epsilon", "robust_hold")
    ]
    effort = hold_effort_sum(
        {c: table.column(c).to_numpy(zero_copy_only=False) for c in HOLD_EFFORT_COLUMNS}
    )
    # no hold on the fused surface: the viability bound (beyond it, nothing is viable)
    cols.append(np.where(np.isfinite(effort), effort, RAW_RANKER_TARGET.high))
    return np.stack(cols, axis=1)


def _object_rows(directory: str, name: str, config: dict, p0, use_dir) -> tuple:
    """A worker's job: one object's rows on its fused surface, and the CPU seconds."""
    import time

    from ..dataset.handle import Dataset

    t0 = time.process_time()
    dataset = Dataset.open(directory)
    obj = dataset.object(name)
    surface = fused_surface(obj, views=int(config["views"]), seed=int(config["seed"]))
    rows = simulate_on_fused(
        surface, obj, dataset.hand, p0, use_dir, int(config["copies"]), perturbation_seed(config)
    )
    return rows, time.process_time() - t0


class FusedViews:
    """Predictions of the fused views for a dataset's rows (see the module's docstring).

    Each (dataset, object, sample) row is simulated once and kept, so the classifier, the
    ranker and the decisions on the same rows cost one simulation.

    Parameters
    ----------
    config : dict
        A views model file's contents (:func:`read_views_config`).
    log : callable, optional
        Called with a line after each object's rows are simulated.
    workers : int
        Processes simulating objects side by side (1: in this process, keeping each fused
        surface for later rows of its object).
    """

    def __init__(
        self, config: dict, *, log: Callable[[str], Any] | None = None, workers: int = 1
    ) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise InputError(f"workers must be an integer >= 1, got {workers!r}")
        self.config = config
        self.log = log
        self.workers = workers
        self._surfaces: dict[tuple[str, str], Any] = {}
        self._rows: dict[tuple[str, str], dict[int, tuple[float, ...]]] = {}

    def _said(self, name: str, n: int, seconds: float) -> None:
        if self.log is not None:
            self.log(
                f"views: {name}: {n} rows x {self.config['copies']} copies on the surface "
                f"fused from {self.config['views']} views, {seconds:.1f} s CPU"
            )

    def _inline(self, dataset, name: str, p0, use_dir) -> np.ndarray:
        import time

        t0 = time.process_time()
        key = (str(dataset.directory), name)
        obj = dataset.object(name)
        if key not in self._surfaces:
            self._surfaces[key] = fused_surface(
                obj, views=int(self.config["views"]), seed=int(self.config["seed"])
            )
        rows = simulate_on_fused(
            self._surfaces[key],
            obj,
            dataset.hand,
            p0,
            use_dir,
            int(self.config["copies"]),
            perturbation_seed(self.config),
        )
        self._said(name, len(rows), time.process_time() - t0)
        return rows

    def _in_workers(self, dataset, jobs: list) -> list[np.ndarray]:
        from ..runtime.engines import process_pool, stop_pool

        pool = process_pool(min(self.workers, len(jobs)))
        try:
            futures = [
                pool.submit(_object_rows, str(dataset.directory), name, self.config, p0, d)
                for name, p0, d in jobs
            ]
            out = []
            for (name, _, _), future in zip(jobs, futures, strict=True):
                rows, seconds = future.result()
                self._said(name, len(rows), seconds)
                out.append(rows)
        except BaseException:
            # Ctrl-C or a failed object: the other objects' work is thrown away now
            stop_pool(pool)
            raise
        pool.shutdown(wait=True)
        return out

    def raw(self, samples) -> np.ndarray:
        """The rows' simulations on the fused surfaces, in the order of ``samples``.

        Parameters
        ----------
        samples : Samples
            Rows of one dataset (``samples.meta["dataset"]``).

        Returns
        -------
        (n, 4) float64 ndarray
            Share of viable copies, fused ε, fused ``robust_hold``, fused ΣE_h (N; 250
            where it does not hold).

        Raises
        ------
        InputError
            For rows that do not come from a dataset (the objects are read from it).
        """
        dataset = samples.meta.get("dataset")
        if dataset is None:
            raise InputError(
                "the views model predicts for a dataset's rows (it renders and fuses each "
                "object's views itself); read the rows with affordgrasp.learning.data.read_rows"
            )
        groups = {
            str(name): np.flatnonzero(samples.object == name)
            for name in dict.fromkeys(samples.object)
        }
        jobs, where = [], []
        for name, rows in groups.items():
            kept = self._rows.setdefault((str(dataset.directory), name), {})
            fresh = [i for i in rows if int(samples.sample[i]) not in kept]
            # a sample listed twice is simulated once
            fresh = list({int(samples.sample[i]): i for i in fresh}.values())
            if fresh:
                jobs.append((name, samples.p0[fresh], samples.use_dir[fresh]))
                where.append((kept, samples.sample[fresh]))
        if self.workers > 1 and len(jobs) > 1:
            results = self._in_workers(dataset, jobs)
        else:
            results = [self._inline(dataset, name, p0, d) for name, p0, d in jobs]
        for (kept, ids), rows in zip(where, results, strict=True):
            for s, row in zip(ids.tolist(), rows.tolist(), strict=True):
                kept[int(s)] = tuple(row)
        out = np.zeros((len(samples), 4))
        for name, rows in groups.items():
            kept = self._rows[(str(dataset.directory), name)]
            out[rows] = [kept[int(s)] for s in samples.sample[rows]]
        return out

    def predict(self, config: dict, samples) -> np.ndarray:
        """A pair's prediction on the [0, 1] scale of its target.

        Parameters
        ----------
        config : dict
            The classifier's or the ranker's config (:func:`load_views_models`).
        samples : Samples

        Returns
        -------
        (n,) float64 ndarray
            The calibrated probability of ``viable``, or the fused ``robust_hold`` or ΣE_h
            on the target's scale (as the truth is normalised: ``robust_hold`` / 6,
            ΣE_h / 250 N).
        """
        raw = self.raw(samples)
        if config["target"]["kind"] == "classification":
            return calibrated(share_score(raw[:, 0], raw[:, 1]), config.get("calibration"))
        tgt = Target.from_dict(config["target"])
        value = raw[:, 3] if tgt.name == RAW_RANKER_TARGET.name else raw[:, 2]
        return (value - tgt.low) / (tgt.high - tgt.low)


def share_score(share: np.ndarray, epsilon: np.ndarray) -> np.ndarray:
    """The uncalibrated probability: the share of viable copies, ties broken by ε.

    Parameters
    ----------
    share, epsilon : (n,) float ndarray

    Returns
    -------
    (n,) float64 ndarray
        In [0, 1 + :data:`TIE_BREAK`).
    """
    eps = np.nan_to_num(np.asarray(epsilon, dtype=np.float64), nan=0.0)
    return np.nan_to_num(np.asarray(share, dtype=np.float64), nan=0.0) + TIE_BREAK * np.tanh(eps)


def calibrated(score: np.ndarray, calibration: dict | None) -> np.ndarray:
    """Map uncalibrated scores through a calibration map (identity without one).

    Parameters
    ----------
    score : (n,) float ndarray
        :func:`share_score`.
    calibration : dict or None
        ``share`` and ``rate`` knots (:func:`fit_calibration`).

    Returns
    -------
    (n,) float64 ndarray
        Probabilities in [0, 1], a strictly increasing function of the score.
    """
    score = np.asarray(score, dtype=np.float64)
    if not calibration or not calibration.get("share"):
        return np.clip(score, 0.0, 1.0)
    rate = np.interp(score, calibration["share"], calibration["rate"])
    return np.clip(rate * (1.0 - MAP_SLOPE) + MAP_SLOPE * np.clip(score, 0.0, 1.0), 0.0, 1.0)


def fit_calibration(share: np.ndarray, label: np.ndarray) -> dict:
    """A non-decreasing map from shares of viable copies to the rate of positives
    (isotonic regression, one knot per share: the ε tie-break is not calibrated).

    Parameters
    ----------
    share : (n,) float ndarray
        Shares of viable copies on validation rows.
    label : (n,) bool or 0/1 ndarray
        Their truth.

    Returns
    -------
    dict
        ``share`` (the distinct shares, increasing) and ``rate`` (the fitted rate at each),
        for :func:`calibrated`.
    """
    from scipy.optimize import isotonic_regression

    share = np.nan_to_num(np.asarray(share, dtype=np.float64), nan=0.0)
    knots, inverse = np.unique(share, return_inverse=True)
    y = np.asarray(label, dtype=np.float64)
    count = np.bincount(inverse, minlength=len(knots)).astype(np.float64)
    mean = np.bincount(inverse, weights=y, minlength=len(knots)) / count
    rate = isotonic_regression(mean, weights=count).x
    return {"share": knots.tolist(), "rate": [float(r) for r in rate]}


def fit_views_config(
    dataset,
    objects,
    *,
    views: int | None = None,
    copies: int = DEFAULT_COPIES,
    seed: int = 0,
    log=None,
    workers: int = 1,
) -> dict:
    """Fit a views model's calibration map and decision threshold on validation objects.

    Parameters
    ----------
    dataset : path or Dataset
        A dataset generated with metrics.
    objects : sequence of str
        The validation objects (never those the views model is judged on).
    views : int, optional
        Views fused per object (default :data:`~affordgrasp.learning.plan.FUSED_VIEWS`).
    copies : int
        K perturbed copies per row on the fused surface.
    seed : int
        ``plan``'s seed whose first candidates' views are fused.
    log : callable, optional
        Progress lines.
    workers : int
        Processes simulating objects side by side.

    Returns
    -------
    dict
        The model file's contents (:func:`write_views_config`).
    """
    from ..dataset.handle import Dataset
    from .data import read_rows
    from .evaluation import best_f1_threshold, expected_calibration_error

    views = FUSED_VIEWS if views is None else int(views)
    if views < 1 or copies < 1:
        raise InputError(f"views and copies must be >= 1, got {views} and {copies}")
    dataset = Dataset.open(dataset)
    samples, _ = read_rows(dataset, CLASSIFIER_TARGET, objects=list(objects))
    if len(samples) == 0:
        raise InputError(f"none of the objects {list(objects)} has rows in {str(dataset)!r}")
    config = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "arch": ARCH,
        "views": views,
        "seed": int(seed),
        "copies": int(copies),
        "perturbation_seed": PERTURBATION_SEED,
    }
    raw = FusedViews(config, log=log, workers=workers).raw(samples)
    score = share_score(raw[:, 0], raw[:, 1])
    config["calibration"] = fit_calibration(raw[:, 0], samples.y > 0.5)
    prob = calibrated(score, config["calibration"])
    # the threshold is one of the shares' calibrated values (a row's ε tie-break only adds)
    value, f1 = best_f1_threshold(samples.y, calibrated(raw[:, 0], config["calibration"]))
    names = sorted(set(samples.object))
    config["decision_threshold"] = {
        "value": value,
        "rule": "largest F1 on the validation objects",
        "f1": f1,
        "rows": len(samples),
        "expected_calibration_error": expected_calibration_error(samples.y, prob),
    }
    config["calibration"].update(
        {
            "rule": "isotonic regression of the true viability on the share of viable copies",
            "rows": len(samples),
            "positive_rate": float(np.mean(samples.y > 0.5)),
            "uncalibrated_expected_calibration_error": expected_calibration_error(
                samples.y, np.clip(score, 0.0, 1.0)
            ),
        }
    )
    # the objects fitted on are the model's validation split: model-eval names them
    config["training"] = {"split": {"train": [], "val": names, "test": []}}
    return config


def write_views_config(path: str | os.PathLike, config: dict) -> Path:
    """Write a views model file (JSON, atomically).

    Parameters
    ----------
    path : path
    config : dict
        :func:`fit_views_config`'s result.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    atomic_write(path, (json.dumps(config, indent=1) + "\n").encode())
    return path
