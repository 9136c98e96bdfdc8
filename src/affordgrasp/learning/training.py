"""Training (conventions: Vision; paper §IV-D): Adam 1e-3 decaying ∝ 1/epoch, dropout, early
stopping with patience 5 on the validation loss, seeded and deterministic.

* Classifier: binary cross-entropy; every epoch sees all positives and as many negatives,
  redrawn each epoch (balanced training data, as the paper; the redraw uses more of the
  negatives than one fixed subsample). Validation: a fixed balanced subset.
* Regressor: mean squared error on the [0, 1] target scale; optionally plus a pairwise
  ranking loss (``rank_weight``), which trains the order of predictions — what comparison
  accuracy and GMS measure — directly.

Same seed, same data, same thread count → the same weights, bit for bit
(``torch.use_deterministic_algorithms``).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from .._version import __version__
from ..errors import InputError
from .data import Samples, balanced_indices
from .models import build_model, count_parameters, depth_input, nearest_depth, pose_features
from .targets import Target
from .torch_support import require_torch
from .views import hand_view

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TrainSettings:
    """Optimisation settings (the paper's where it states them).

    Attributes
    ----------
    epochs : int
        Most epochs.
    batch_size : int
        Samples per batch.
    lr : float
        Adam's learning rate of the first epoch; epoch k uses lr / k.
    patience : int
        Stop after this many epochs without a lower validation loss.
    seed : int
        Seeds the weights, the batch order and the balanced draws.
    rank_weight : float
        Weight of the pairwise ranking loss added to a regressor's MSE (0: none).
    max_seconds : float or None
        Stop after the epoch that passes this wall time, s.
    threads : int
        torch threads.
    """

    epochs: int = 40
    batch_size: int = 64
    lr: float = 1e-3
    patience: int = 5
    seed: int = 0
    rank_weight: float = 0.0
    max_seconds: float | None = None
    threads: int = 1

    def __post_init__(self) -> None:
        # a NaN or infinite weight trains non-finite weights; a time limit <= 0 stops at once
        if not 0 <= self.rank_weight < math.inf:
            raise InputError(f"rank_weight must be a finite number >= 0, got {self.rank_weight}")
        if self.max_seconds is not None and not 0 < self.max_seconds < math.inf:
            raise InputError(f"max_seconds must be a finite number > 0, got {self.max_seconds}")


def default_config(arch: str, target: Target, **options) -> dict:
    """A model config: architecture, sizes, inputs and target.

    Parameters
    ----------
    arch : str
        One of :data:`~affordgrasp.learning.models.ARCHITECTURES`.
    target : Target
        What the model learns.
    **options
        Overrides of the defaults (``dropout`` 0.3, ``width`` 16, ``n_points`` 256,
        ``canonical`` False, ``camera`` 128 px at 60°; ``view`` ``"hand"`` for the hand
        view of :mod:`~affordgrasp.learning.views`, which implies ``canonical``, absent
        for the camera image); None values are ignored.

    Returns
    -------
    dict
        JSON-ready; saved with the weights so that a model rebuilds itself exactly.
    """
    config = {
        "arch": arch,
        "target": target.to_dict(),
        "dropout": 0.3,
        "width": 16,
        "n_points": 256,
        "canonical": False,
        "members": 1,
        "camera": {"size": 128, "fov_deg": 60.0},
        "affordgrasp_version": __version__,
    }
    config.update({k: v for k, v in options.items() if v is not None})
    if config.get("view") == "hand":
        config["canonical"] = True
    return config


class Inputs:
    """The network inputs of a set of samples, built once (images are made per batch).

    Parameters
    ----------
    config : dict
        The model config (:func:`default_config`).
    samples : Samples
        With depth images unless the architecture is ``"pose"``.

    Attributes
    ----------
    arch : str
    canonical : bool
    pose : (n, 14) or (n, 15) float32 ndarray
        Pose features; the 15th is the nearest depth of canonical image models.
    depth_mm : (n, h, w) uint16 ndarray or None
        Depth images, mm (the CNN only).
    points : (n, n_points, 3) float32 ndarray or None
        Point clouds in the camera frame, m (PointNet only).

    Raises
    ------
    InputError
        When an image model gets samples without depth images.
    """

    def __init__(self, config: dict, samples: Samples):
        from ..vision.points import point_clouds

        self.arch = config["arch"]
        self.canonical = bool(config.get("canonical"))
        self.view = config.get("view")
        self.fov_deg = float(config.get("camera", {}).get("fov_deg", 60.0))
        # the hand view draws the fingers at each pregrasp's spread (π·p0[5], rad)
        self.spread = np.pi * np.asarray(samples.p0)[:, 5] if self.view == "hand" else None
        pose = pose_features(samples.p0, samples.use_dir)
        if self.arch != "pose" and samples.depth_mm is None:
            raise InputError("samples need their depth images (learning.data.load_depth)")
        if self.canonical and self.arch != "pose":
            pose = np.concatenate([pose, nearest_depth(samples.depth_mm)], axis=1)
        self.pose = pose
        self.depth_mm = samples.depth_mm if self.arch == "cnn" else None
        self.points = None
        if self.arch.startswith("pointnet"):
            depth = samples.depth_mm.astype(np.float32) / 1000.0
            self.points, _ = point_clouds(
                depth,
                int(config.get("n_points", 256)),
                seed=0,
                crop_radius=None,
                centre_depth=self.canonical,
            )

    def __len__(self) -> int:
        return len(self.pose)

    def batch(self, idx: np.ndarray):
        """The model's input tensors for some samples.

        Parameters
        ----------
        idx : (b,) int ndarray
            Sample indices.

        Returns
        -------
        tuple of torch.Tensor
            (image (b, c, h, w), pose) for the CNN, (points (b, n, 3), pose) for PointNet,
            (pose,) for the pose-only model.
        """
        torch = require_torch()
        pose = torch.from_numpy(self.pose[idx])
        if self.arch == "cnn" and self.view == "hand":
            image = hand_view(self.depth_mm[idx], self.spread[idx], fov_deg=self.fov_deg)
            return torch.from_numpy(image), pose
        if self.arch == "cnn":
            return torch.from_numpy(depth_input(self.depth_mm[idx], self.canonical)), pose
        if self.points is not None:
            return torch.from_numpy(self.points[idx]), pose
        return (pose,)


def _forward(model, inputs: Inputs, idx: np.ndarray):
    return model(*inputs.batch(idx))


def predict_scores(model, config: dict, inputs: Inputs, batch_size: int = 256) -> np.ndarray:
    """Model outputs for every sample, in batches, without gradients.

    Parameters
    ----------
    model : torch.nn.Module
        From :func:`~affordgrasp.learning.models.build_model`.
    config : dict
        Its config.
    inputs : Inputs
        The samples' inputs.
    batch_size : int
        Samples per forward pass.

    Returns
    -------
    (n,) float64 ndarray
        Probabilities (classifier; corrected to the prior its config's ``calibration``
        names, :func:`prior_shift`) or values on the target's [0, 1] scale (regressor).
    """
    torch = require_torch()
    classification = config["target"]["kind"] == "classification"
    shift = prior_shift(config) if classification else 0.0
    model.eval()
    out = np.zeros(len(inputs), dtype=np.float64)
    with torch.no_grad():
        for lo in range(0, len(inputs), batch_size):
            idx = np.arange(lo, min(len(inputs), lo + batch_size))
            y = _forward(model, inputs, idx)
            out[idx] = (torch.sigmoid(y + shift) if classification else y).double().numpy()
    return out


def prior_shift(config: dict) -> float:
    """The logit offset that moves a classifier's probabilities to another class prior.

    A classifier trained on balanced batches learns odds at a 50 % prior; at a natural
    positive rate π its calibrated odds are those odds × π / (1 − π) (Saerens et al. 2002).
    A config's ``calibration`` = ``{"kind": "prior_shift", "from_rate": 0.5, "to_rate": π}``
    asks for it; without one (the shipped files) the offset is 0.

    Parameters
    ----------
    config : dict
        A classifier's config.

    Returns
    -------
    float
        logit(to_rate) − logit(from_rate).

    Raises
    ------
    InputError
        For a calibration that is not a prior shift between rates in (0, 1).
    """
    cal = config.get("calibration")
    if not cal:
        return 0.0
    rates = (cal.get("from_rate"), cal.get("to_rate")) if isinstance(cal, dict) else (None,)
    if (
        not isinstance(cal, dict)
        or cal.get("kind") != "prior_shift"
        or not all(isinstance(r, int | float) and 0 < r < 1 for r in rates)
    ):
        raise InputError(
            f"the model's calibration {cal!r} is not a prior shift between two rates in (0, 1)"
        )
    a, b = float(rates[0]), float(rates[1])
    return math.log(b / (1 - b)) - math.log(a / (1 - a))


def _pairwise_rank_loss(torch, pred, y):
    """Logistic loss on every ordered pair of the batch with different targets."""
    diff_y = y[:, None] - y[None, :]
    diff_p = (pred[:, None] - pred[None, :]) * 10.0
    mask = diff_y > 1e-6
    if not bool(mask.any()):
        return pred.sum() * 0.0
    return torch.nn.functional.softplus(-diff_p[mask]).mean()


def train_model(
    config: dict,
    train: Samples,
    val: Samples,
    settings: TrainSettings | None = None,
    progress: Callable[[dict], None] | None = None,
    epoch_batches: Callable | None = None,
):
    """Train the network a config describes (see the module docstring).

    Parameters
    ----------
    config : dict
        The model config (:func:`default_config`).
    train, val : Samples
        ``y`` in target units, with depth images unless the architecture is ``"pose"``.
    settings : TrainSettings, optional
        The defaults when None.
    progress : callable, optional
        Called after every batch with a dict: ``epoch``, ``epochs``, ``batch``, ``batches``,
        ``loss`` (running mean of the epoch) and ``eta_s``.
    epoch_batches : callable, optional
        ``epoch_batches(epoch, seed)`` → (iterable of (Inputs, idx, y), number of batches):
        the training batches of one epoch, made elsewhere (e.g. streamed from a dataset by
        :class:`~affordgrasp.learning.streaming.StreamedEpochs`, ``train`` then needs no
        images); None: batches of ``train`` in memory.

    Returns
    -------
    model : torch.nn.Module
        With the weights of the epoch of lowest validation loss, in eval mode.
    summary : dict
        ``settings``, ``history`` (per epoch: ``train_loss``, ``val_loss``, ``lr``),
        ``best_epoch``, ``best_val_loss``, ``seconds``, ``train_samples``, ``parameters``.
    """
    settings = settings or TrainSettings()
    members = int(config.get("members", 1))
    if members > 1:
        return _train_ensemble(config, train, val, settings, progress, members, epoch_batches)
    torch = require_torch()
    # One thread by default: small batches gain little from more, and on a shared machine
    # torch's spinning worker threads cost far more than they give (measured: 5x slower).
    torch.set_num_threads(max(1, int(settings.threads)))
    torch.manual_seed(settings.seed)
    torch.use_deterministic_algorithms(True)
    target = Target.from_dict(config["target"])
    classification = target.kind == "classification"
    model = build_model(config)
    train_in = Inputs(config, train) if epoch_batches is None else None
    val_in = Inputs(config, val)
    y_train = torch.from_numpy(target.normalise(train.y))
    y_val = torch.from_numpy(target.normalise(val.y))
    if classification:
        val_idx = balanced_indices(val.y, seed=settings.seed + 10_007)
        loss_fn = torch.nn.BCEWithLogitsLoss()
    else:
        val_idx = np.arange(len(val))
        loss_fn = torch.nn.MSELoss()
    optimiser = torch.optim.Adam(model.parameters(), lr=settings.lr)
    # lr of epoch k (1-based) = lr / k: "decaying with inverse proportionality with the epochs"
    schedule = torch.optim.lr_scheduler.LambdaLR(optimiser, lambda e: 1.0 / (e + 1))
    full = config["arch"] == "pointnet"
    history: list[dict] = []
    best = (math.inf, None, 0)
    started = time.perf_counter()
    stale = 0
    for epoch in range(1, settings.epochs + 1):
        rng = np.random.default_rng(np.random.SeedSequence([settings.seed, epoch]))
        if epoch_batches is not None:
            batches, n_batches = epoch_batches(epoch, settings.seed)
        else:
            if classification:
                order = balanced_indices(train.y, seed=int(rng.integers(2**31)))
                order = rng.permutation(order)
            else:
                order = rng.permutation(len(train))
            batches = [
                (train_in, order[i : i + settings.batch_size], None)
                for i in range(0, len(order), settings.batch_size)
            ]
            n_batches = len(batches)
        model.train()
        lr_used = optimiser.param_groups[0]["lr"]
        total, seen = 0.0, 0
        for b, (inputs, idx, y_given) in enumerate(batches, 1):
            if len(idx) < 2:
                continue
            y_batch = y_train[idx] if y_given is None else y_given
            pred = _forward(model, inputs, idx)
            loss = loss_fn(pred, y_batch)
            if settings.rank_weight and not classification:
                loss = loss + settings.rank_weight * _pairwise_rank_loss(torch, pred, y_batch)
            if full and model.last_feature_transform is not None:
                t = model.last_feature_transform
                eye = torch.eye(t.shape[1])
                loss = (
                    loss + 1e-3 * ((torch.bmm(t, t.transpose(1, 2)) - eye) ** 2).sum((1, 2)).mean()
                )
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += float(loss.detach()) * len(idx)
            seen += len(idx)
            if progress is not None:
                elapsed = time.perf_counter() - started
                done = (epoch - 1) + min(b / max(n_batches, 1), 1.0)
                progress(
                    {
                        "epoch": epoch,
                        "epochs": settings.epochs,
                        "batch": b,
                        "batches": n_batches,
                        "loss": total / max(seen, 1),
                        "eta_s": elapsed / done * (settings.epochs - done),
                    }
                )
        schedule.step()
        scores = _validation_outputs(model, val_in, val_idx)
        val_loss = float(loss_fn(scores, y_val[val_idx])) if len(val_idx) else total / max(seen, 1)
        history.append(
            {
                "epoch": epoch,
                "train_loss": total / max(seen, 1),
                "val_loss": val_loss,
                "lr": lr_used,
            }
        )
        log.info("epoch %d train %.5f val %.5f", epoch, history[-1]["train_loss"], val_loss)
        if val_loss < best[0] - 1e-7:
            best = (val_loss, {k: v.clone() for k, v in model.state_dict().items()}, epoch)
            stale = 0
        else:
            stale += 1
            if stale >= settings.patience:
                break
        if settings.max_seconds and time.perf_counter() - started > settings.max_seconds:
            log.info("stopping after %d epochs: time budget reached", epoch)
            break
    if best[1] is not None:
        model.load_state_dict(best[1])
    model.eval()
    summary = {
        "settings": asdict(settings),
        "history": history,
        "best_epoch": best[2],
        "best_val_loss": best[0],
        "seconds": time.perf_counter() - started,
        "train_samples": len(train),
        "parameters": count_parameters(model),
    }
    return model, summary


def _train_ensemble(config, train, val, settings, progress, members: int, epoch_batches=None):
    """Train ``members`` networks with seeds seed, seed + 1, ... and assemble them."""
    from dataclasses import replace

    single = dict(config, members=1)
    trained, summaries = [], []
    for k in range(members):
        model, summary = train_model(
            single, train, val, replace(settings, seed=settings.seed + k), progress, epoch_batches
        )
        trained.append(model)
        summaries.append(summary)
    ensemble = build_model(config)
    for slot, model in zip(ensemble.members, trained, strict=True):
        slot.load_state_dict(model.state_dict())
    ensemble.eval()
    first = summaries[0]
    summary = {
        "settings": asdict(settings),
        "history": first["history"],
        "best_epoch": first["best_epoch"],
        "best_val_loss": first["best_val_loss"],
        "members": [
            {k: s[k] for k in ("best_epoch", "best_val_loss", "seconds")}
            | {"epochs": len(s["history"])}
            for s in summaries
        ],
        "seconds": sum(s["seconds"] for s in summaries),
        "train_samples": len(train),
        "parameters": count_parameters(ensemble),
    }
    return ensemble, summary


def _validation_outputs(model, inputs: Inputs, idx: np.ndarray):
    torch = require_torch()
    model.eval()
    outs = []
    with torch.no_grad():
        for lo in range(0, len(idx), 256):
            outs.append(_forward(model, inputs, idx[lo : lo + 256]))
    return torch.cat(outs) if outs else torch.zeros(0)
