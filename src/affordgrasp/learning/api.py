"""Train, predict, evaluate: the learning pipeline over generated datasets (conventions: Vision).

``train_on_dataset`` splits a dataset by object instance (or family), trains a classifier or
regressor and records the split, the settings, the test metrics and the predict-the-mean
baseline in the model's config. ``predict_dataset`` streams a dataset and returns one row
per sample. ``evaluate_on_dataset`` computes the metrics of ``evaluation`` for a model on a
dataset's rows (by default its own held-out test objects).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from dataclasses import asdict
from importlib import resources
from pathlib import Path

import numpy as np

from ..dataset.handle import Dataset, DatasetLike
from ..dataset.splits import split_by_family, split_by_object
from ..errors import InputError
from .data import Samples, load_depth, read_rows, reads_depth, sensed_depth_mm
from .evaluation import classification_report, expected_calibration_error, regression_report
from .targets import Target
from .training import Inputs, TrainSettings, default_config, predict_scores, train_model

log = logging.getLogger(__name__)

PRETRAINED = {
    "classifier": "default_classifier.safetensors",
    "regressor": "default_regressor.safetensors",
}


def pretrained_path(kind: str) -> Path:
    """Path of a shipped model.

    Parameters
    ----------
    kind : str
        ``"classifier"`` (viable) or ``"regressor"`` (ΣE_h).

    Returns
    -------
    pathlib.Path
        The ``.safetensors`` file inside the package.

    Raises
    ------
    InputError
        For another kind, or when the file is missing (the message names the script that
        rebuilds it).
    """
    if kind not in PRETRAINED:
        raise InputError(f"unknown pretrained model {kind!r}; choose classifier or regressor")
    path = Path(str(resources.files("affordgrasp.learning") / "pretrained" / PRETRAINED[kind]))
    if not path.is_file():
        raise InputError(
            f"the shipped {kind} is missing ({path}); rebuild it with "
            "'python tools/train_default_models.py'"
        )
    return path


def resolve_models(spec: str | os.PathLike) -> list[Path]:
    """The model files a model option names.

    Parameters
    ----------
    spec : str or path
        ``"default"`` (the shipped classifier and regressor), ``"classifier"``,
        ``"regressor"``, or a model file.

    Returns
    -------
    list of pathlib.Path
    """
    if str(spec) == "default":
        return [pretrained_path("classifier"), pretrained_path("regressor")]
    if str(spec) in PRETRAINED:
        return [pretrained_path(str(spec))]
    return [Path(spec)]


def _subsample(idx: np.ndarray, k: int | None, seed: int) -> np.ndarray:
    if k is None or len(idx) <= k:
        return idx
    rng = np.random.default_rng(seed)
    return np.sort(rng.choice(idx, k, replace=False))


def prepare_split(
    dataset: DatasetLike,
    target: str | Target,
    *,
    split: str = "object",
    test_families: Sequence[str] | None = None,
    seed: int = 0,
    max_train: int | None = 20000,
    max_eval: int | None = 4000,
    sensor=None,
    train_depth: bool = True,
):
    """Rows of each part of the split, with depth images loaded (memory-capped).

    Classification keeps every training/validation positive (at most ``max_train // 2`` or
    ``max_eval // 2``) and at most three times as many negatives (each epoch then
    draws a balanced subset); the test rows keep the natural class balance (a uniform
    subsample of at most ``max_eval`` rows). Regression rows are subsampled uniformly.

    Parameters
    ----------
    dataset : path or Dataset
        A dataset generated with metrics (opened once: :class:`~affordgrasp.dataset.Dataset`).
    target : str or Target
        What to learn (:func:`~affordgrasp.learning.data.read_rows`).
    split : str
        ``"object"`` (instances held out, families shared) or ``"family"``.
    test_families : sequence of str, optional
        The held-out families of a split by family.
    seed : int
        Seeds the split and the subsamples.
    max_train, max_eval : int or None
        Caps on the training rows and on each of validation and test (None: no cap).
    sensor : SensorModel, optional
        A depth sensor's noise and lost returns applied to every image
        (:func:`~affordgrasp.vision.sensor.apply_sensor`; keyed by object and sample, so a
        row's noisy image does not depend on the split); None: the exact images.
    train_depth : bool
        Load the training rows' images (False: streamed later, see
        :class:`~affordgrasp.learning.streaming.StreamedEpochs`).

    Returns
    -------
    train, val, test : Samples
        With depth images.
    target : Target
    split : Split
    """
    dataset = Dataset.open(dataset)
    samples, target = read_rows(dataset, target)
    if len(samples) == 0:
        raise InputError(f"dataset {str(dataset)!r} has no rows for target {target.name!r}")
    if split == "object":
        sp = split_by_object(samples.object, samples.family, seed=seed)
    elif split == "family":
        if not test_families:
            raise InputError(
                "split 'family' needs test_families, the families to hold out (e.g. axe,mug)",
                parameter="test_families",
            )
        sp = split_by_family(samples.object, samples.family, test_families, seed=seed)
    else:
        raise InputError(f"unknown split {split!r}; choose object or family")
    parts = []
    for k, part in enumerate(("train", "val", "test")):
        idx = np.flatnonzero(sp.part_of(samples.object, part))
        cap = max_train if part == "train" else max_eval
        weights = {}
        if target.kind == "classification" and part != "test":
            y = samples.y[idx]
            pos, neg = idx[y > 0.5], idx[y <= 0.5]
            kept_pos = _subsample(pos, None if cap is None else cap // 2, seed + k)
            n_neg = int(round(3.0 * max(len(kept_pos), 1)))
            kept_neg = _subsample(neg, n_neg, seed + 10 + k)
            idx = np.sort(np.r_[kept_pos, kept_neg])
            # what each kept row stands for: restores the natural balance of the part
            weights = {
                "positive_weight": len(pos) / max(len(kept_pos), 1),
                "negative_weight": len(neg) / max(len(kept_neg), 1),
            }
        else:  # regression rows, and the classifier's test rows at their natural balance
            idx = _subsample(idx, cap, seed + k)
        taken = samples.take(idx)
        taken.meta.update(weights)
        parts.append(taken)
    for k, p in enumerate(parts):
        if len(p) and (k > 0 or train_depth):
            load_depth(p, dataset)
            if sensor is not None:
                p.depth_mm = sensed_depth_mm(p, sensor)
    return parts[0], parts[1], parts[2], target, sp


def train_on_dataset(
    dataset: DatasetLike,
    *,
    arch: str = "cnn",
    target: str = "viable",
    out: str | os.PathLike | None = None,
    split: str = "object",
    test_families: Sequence[str] | None = None,
    settings: TrainSettings | None = None,
    log_target: bool = False,
    canonical: bool = False,
    max_train: int | None = 20000,
    progress: Callable[[dict], None] | None = None,
    prepared=None,
    members: int = 1,
    sensor=None,
    stream: bool = False,
    buffer_rows: int = 4096,
    calibrate: bool = False,
    view: str | None = None,
):
    """Train a model on a dataset, evaluate it on the held-out objects, save it if asked.

    Parameters
    ----------
    dataset : path or Dataset
        A dataset generated with metrics (opened once: :class:`~affordgrasp.dataset.Dataset`).
    arch : str
        One of :data:`~affordgrasp.learning.models.ARCHITECTURES`.
    target : str
        What to learn (:func:`~affordgrasp.learning.data.read_rows`).
    out : path, optional
        Where to save the model (a ``.safetensors`` file; the config in its metadata).
    split : str
        ``"object"`` or ``"family"`` (:func:`prepare_split`).
    test_families : sequence of str, optional
        The held-out families of a split by family.
    settings : TrainSettings, optional
        Optimisation settings; the defaults when None.
    log_target : bool
        Learn a regression target on a log scale.
    canonical : bool
        Depth relative to the nearest point (:func:`~affordgrasp.learning.models.depth_input`).
    max_train : int or None
        Cap on the training rows.
    progress : callable, optional
        Called after every batch (:func:`~affordgrasp.learning.training.train_model`).
    prepared : tuple, optional
        The result of :func:`prepare_split`, to train several models on the same rows.
    members : int
        More than 1: an ensemble of that many networks (seeds seed, seed + 1, ...) whose
        outputs are averaged, saved as one model.
    sensor : SensorModel, optional
        Train (and validate and test) on the images a depth sensor would return
        (:func:`prepare_split`); recorded in the config's ``training``.
    stream : bool
        Read the training images shard by shard every epoch instead of holding them
        (:class:`~affordgrasp.learning.streaming.StreamedEpochs`): every training row is
        used (``max_train`` is ignored) and memory is that of ``buffer_rows`` images.
    buffer_rows : int
        With ``stream``: rows shuffled together before batches are cut.
    calibrate : bool
        A classifier's probabilities corrected from its balanced training to the positive
        rate of its training objects (config ``calibration``,
        :func:`~affordgrasp.learning.training.prior_shift`); its threshold and test report
        are then those of the corrected probabilities.
    view : str, optional
        ``"hand"``: the CNN reads the hand view (:func:`~affordgrasp.learning.views.hand_view`:
        the depth at a fixed metric scale around the approach line, with the fingers'
        closing planes and the palm drawn in; implies ``canonical``); None: the camera image.

    Returns
    -------
    model : torch.nn.Module
    config : dict
        The model config with ``training`` (dataset, split, rows, history, ...) and, when
        there are test rows, ``test`` (:func:`report`).

    Raises
    ------
    InputError
        When there are too few rows or positives to train on.
    """
    from .io import save_model

    settings = settings or TrainSettings()
    dataset = Dataset.open(dataset)
    if prepared is None:
        prepared = prepare_split(
            dataset,
            target,
            split=split,
            test_families=test_families,
            seed=settings.seed,
            max_train=None if stream else max_train,
            sensor=sensor,
            train_depth=not stream,
        )
    train, val, test, tgt, sp = prepared
    if log_target and tgt.kind == "regression":
        tgt = Target(**dict(tgt.to_dict(), log=True))
    if tgt.kind == "classification" and (train.y > 0.5).sum() < 2:
        raise InputError(
            f"the training objects of {str(dataset)!r} have {int((train.y > 0.5).sum())} viable "
            "grasps; generate more samples or objects"
        )
    if len(train) < 2 or len(val) == 0:
        raise InputError(
            f"too few rows to train on ({len(train)} train, {len(val)} validation); generate "
            "more samples, or objects with at least 3 instances per family"
        )
    if not isinstance(members, int) or isinstance(members, bool) or members < 1:
        raise InputError(f"members must be an integer >= 1, got {members!r}")
    if view not in (None, "hand"):
        raise InputError(f"view must be None (the camera image) or 'hand', got {view!r}")
    if view == "hand" and arch != "cnn":
        raise InputError(f"the hand view is an image input of the cnn, not of {arch!r}")
    config = default_config(arch, tgt, canonical=canonical, members=members, view=view)
    epochs = None
    if stream:
        from .streaming import StreamedEpochs

        epochs = StreamedEpochs(
            dataset,
            config,
            train,
            batch_size=settings.batch_size,
            buffer_rows=buffer_rows,
            sensor=sensor,
        )
    model, summary = train_model(
        config, train, val, settings, progress=progress, epoch_batches=epochs
    )
    if epochs is not None:
        summary["streamed"] = {"buffer_rows": buffer_rows, "max_buffered": epochs.max_buffered}
    config["training"] = {
        "dataset": str(dataset),
        "split": sp.to_dict(),
        "rows": {"train": len(train), "val": len(val), "test": len(test)},
        "train_mean": float(np.mean(tgt.normalise(train.y))),
        "sensor": None if sensor is None else asdict(sensor),
        "positive_rate": _natural_rate(train) if tgt.kind == "classification" else None,
        **{k: v for k, v in summary.items() if k != "history"},
        "history": summary["history"],
    }
    if tgt.kind == "classification":
        if calibrate:
            config["calibration"] = {
                "kind": "prior_shift",
                "from_rate": 0.5,
                "to_rate": config["training"]["positive_rate"],
            }
        config["decision_threshold"] = choose_threshold(model, config, val)
    if len(test):
        config["test"] = report(model, config, test)
    if out is not None:
        save_model(out, model, config)
    return model, config


def _natural_rate(samples: Samples) -> float:
    """The positive rate of the objects some (subsampled) rows came from."""
    y = samples.y > 0.5
    pos = y.sum() * samples.meta.get("positive_weight", 1.0)
    neg = (~y).sum() * samples.meta.get("negative_weight", 1.0)
    return float(pos / max(pos + neg, 1e-300))


def choose_threshold(model, config: dict, val: Samples) -> dict:
    """A classifier's decision threshold, chosen on its validation objects.

    The threshold of largest F1 over the validation rows, each weighted by how many rows of
    its class it stands for (the training subsample of negatives is undone, so F1 is that
    of the objects' natural class balance).

    Parameters
    ----------
    model : torch.nn.Module
    config : dict
        The classifier's config.
    val : Samples
        The validation rows, with depth images (``meta`` may hold ``positive_weight`` and
        ``negative_weight``).

    Returns
    -------
    dict
        ``value`` (a probability), ``rule``, ``f1``, ``rows`` and ``expected_calibration_error``
        (at the natural balance), stored in the model's config as ``decision_threshold``.
    """
    from .evaluation import best_f1_threshold, expected_calibration_error

    rule = "largest F1 on the validation objects at their natural class balance"
    if len(val) == 0:
        return {"value": 0.5, "rule": "no validation rows: 0.5", "f1": None, "rows": 0}
    prob = predict_scores(model, config, Inputs(config, val))
    positive = val.y > 0.5
    weights = np.where(
        positive, val.meta.get("positive_weight", 1.0), val.meta.get("negative_weight", 1.0)
    )
    value, f1 = best_f1_threshold(val.y, prob, weights=weights)
    return {
        "value": value,
        "rule": rule,
        "f1": f1,
        "rows": len(val),
        "expected_calibration_error": expected_calibration_error(val.y, prob, weights=weights),
    }


def report(model, config: dict, samples: Samples, *, seed: int = 0, scores=None) -> dict:
    """The metrics of a model on samples (with depth), beside predict-the-mean.

    Parameters
    ----------
    model : torch.nn.Module
    config : dict
        The model's config.
    samples : Samples
        With depth images unless the model is ``"pose"``.
    seed : int
        Seeds the random pairs, subsets and balanced draws of the metrics.
    scores : (n,) ndarray, optional
        The model's outputs on the samples when already computed.

    Returns
    -------
    dict
        :func:`~affordgrasp.learning.evaluation.classification_report` plus
        ``baseline_average_precision`` (the positive rate), or
        :func:`~affordgrasp.learning.evaluation.regression_report` on the [0, 1] scale plus
        ``baseline_mean_mse`` (predicting the training mean).
    """
    tgt = Target.from_dict(config["target"])
    if scores is None:
        scores = model_scores(model, config, samples)
    if tgt.kind == "classification":
        out = classification_report(samples.y, scores, seed=seed)
        out["baseline_average_precision"] = out["positive_rate"]
        out["expected_calibration_error"] = expected_calibration_error(samples.y, scores)
        return out
    truth = tgt.normalise(samples.y)
    out = regression_report(truth, scores, lower_is_better=tgt.lower_is_better, seed=seed)
    mean = config.get("training", {}).get("train_mean", float(np.mean(truth)))
    out["baseline_mean_mse"] = float(np.mean((truth - mean) ** 2))
    return out


def predictions_of(model, config: dict, samples: Samples) -> np.ndarray:
    """Predictions of a model for samples, in target units.

    Parameters
    ----------
    model, config, samples
        As for :func:`report`.

    Returns
    -------
    (n,) float64 ndarray
        A probability for a classifier, the target's units for a regressor.
    """
    tgt = Target.from_dict(config["target"])
    return tgt.denormalise(model_scores(model, config, samples))


def model_scores(model, config: dict, samples: Samples) -> np.ndarray:
    """A model's outputs for samples on the [0, 1] scale (a network's, or the fused views').

    Parameters
    ----------
    model : torch.nn.Module or FusedViews
    config : dict
        The model's config (``arch`` ``"views"``: :mod:`affordgrasp.learning.views_model`).
    samples : Samples
        With depth images for a network that reads them; the rows of a dataset for the
        views.

    Returns
    -------
    (n,) float64 ndarray
        Probabilities (classifier) or values on the target's [0, 1] scale (regressor).
    """
    if config.get("arch") == "views":
        return model.predict(config, samples)
    return predict_scores(model, config, Inputs(config, samples))


def prediction_column(config: dict) -> str:
    """The name of a model's prediction column in :func:`predict_dataset`'s table.

    Parameters
    ----------
    config : dict
        The model's config.

    Returns
    -------
    str
        ``"viable_prob"`` for a classifier, ``"pred_<target>"`` for a regressor.
    """
    tgt = config["target"]
    return "viable_prob" if tgt["kind"] == "classification" else f"pred_{tgt['name']}"


def predict_dataset(models, dataset: DatasetLike, *, objects=None, progress=None):
    """One row per sample of a dataset: object, sample and each model's prediction.

    The dataset is streamed in batches (memory-bounded); depth images are read when stored,
    else rendered.

    Parameters
    ----------
    models : list of (torch.nn.Module, dict)
        Models and their configs.
    dataset : path or Dataset
        A generated dataset.
    objects : sequence of str, optional
        Predict only these objects.
    progress : callable, optional
        Called with the number of rows after each batch (of 2048 rows).

    Returns
    -------
    pyarrow.Table
        ``object``, ``sample`` and one column per model (:func:`prediction_column`).

    Raises
    ------
    InputError
        When there is no row to predict.
    """
    import pyarrow as pa

    from ..vision.depth import decode_depth_column, depth_to_mm
    from .data import render_samples_depth

    dataset = Dataset.open(dataset)
    families = dataset.families
    stored = dataset.depth
    needs_depth = any(reads_depth(c) for _, c in models)
    columns = ["object", "sample", "p0", "use_dir"] + (
        ["depth_mm"] if stored and needs_depth else []
    )
    parts = []
    for batch in dataset.batches(columns=columns, objects=objects, batch_size=2048):
        tab = pa.Table.from_batches([batch])
        obj = np.asarray(tab.column("object").to_pylist(), dtype=object)
        s = Samples(
            object=obj,
            family=np.asarray([families.get(o, o) for o in obj], dtype=object),
            sample=tab.column("sample").to_numpy().astype(np.int64),
            p0=np.asarray(tab.column("p0").combine_chunks().flatten()).reshape(-1, 6),
            use_dir=np.asarray(tab.column("use_dir").combine_chunks().flatten()).reshape(-1, 2),
            y=np.full(len(obj), np.nan),
            meta={"dataset": dataset},
        )
        if needs_depth:
            if stored:
                s.depth_mm = depth_to_mm(decode_depth_column(tab.column("depth_mm")))
            else:
                s.depth_mm = render_samples_depth(s, dataset)
        cols = {"object": pa.array(list(obj), pa.string()), "sample": pa.array(s.sample)}
        for model, config in models:
            cols[prediction_column(config)] = pa.array(predictions_of(model, config, s))
        parts.append(pa.table(cols))
        if progress is not None:
            progress(len(obj))
    if not parts:
        raise InputError(f"no rows to predict in {str(dataset)!r}")
    return pa.concat_tables(parts)


def evaluate_on_dataset(
    model, config: dict, dataset: DatasetLike, *, objects="test", seed=0, max_rows=None
):
    """Metrics of a model on a dataset's rows of its target.

    Parameters
    ----------
    model : torch.nn.Module
    config : dict
        The model's config.
    dataset : path or Dataset
        A dataset generated with metrics.
    objects : "test", "all" or sequence of str
        The model's held-out test objects, every object, or the objects named. When none of
        the model's test objects is in the dataset, ``"test"`` evaluates every object and
        says so in the report's ``selection``.
    seed : int
        Seeds the subsample and the metrics.
    max_rows : int, optional
        Evaluate a uniform subsample of at most this many rows (the report's ``selection``
        says when it did).

    Returns
    -------
    report : dict
        :func:`report`, plus ``selection``: ``objects`` (how they were chosen, in words),
        ``rows_available``, ``rows_evaluated`` and ``subsampled``.
    samples : Samples
        The rows evaluated.
    scores : (n,) float64 ndarray
        The model's outputs on them, on the [0, 1] scale.

    Raises
    ------
    InputError
        When none of the named objects is in the dataset, or they hold no row to evaluate.
    """
    tgt = Target.from_dict(config["target"])
    dataset = Dataset.open(dataset)
    samples, _ = read_rows(dataset, tgt)
    if objects == "test":
        split = config.get("training", {}).get("split", {})
        held = split.get("test", [])
        mask = np.isin(samples.object, held)
        how = "the model's held-out test objects"
        if not mask.any():
            mask = np.ones(len(samples), dtype=bool)
            earlier = set(split.get("train", [])) | set(split.get("val", []))
            seen = sorted(set(samples.object) & earlier)
            how = "every object: none of the model's test objects is in the dataset" + (
                f" ({len(seen)} of its objects were in the model's training or "
                f"validation split: {', '.join(seen[:5])}{', ...' if len(seen) > 5 else ''})"
                if seen
                else " (and none of its objects was in the model's training split)"
            )
    elif objects == "all":
        mask = np.ones(len(samples), dtype=bool)
        how = "every object"
    else:
        mask = np.isin(samples.object, list(objects))
        how = "the objects named"
        if not mask.any():
            raise InputError(f"none of the objects {list(objects)} is in {str(dataset)!r}")
    available = int(mask.sum())
    if available == 0:
        raise InputError(
            f"{str(dataset.directory)!r} holds no row to evaluate a {tgt.name} model on "
            f"({tgt.rows} rows of {how}); generate more samples"
        )
    idx = _subsample(np.flatnonzero(mask), max_rows, seed)
    samples = samples.take(idx)
    if reads_depth(config):
        load_depth(samples, dataset)
    scores = model_scores(model, config, samples)
    rep = report(model, config, samples, seed=seed, scores=scores)
    rep["selection"] = {
        "objects": how,
        "rows_available": available,
        "rows_evaluated": len(samples),
        "subsampled": len(samples) < available,
    }
    return rep, samples, scores
