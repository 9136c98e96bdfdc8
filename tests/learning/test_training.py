"""Tiny seeded training runs: the loss falls, runs are deterministic, files round-trip
without pickle."""

import pickle

import numpy as np
import pytest

pytest.importorskip("torch")
pytest.importorskip("safetensors")

from affordgrasp.learning.data import Samples  # noqa: E402
from affordgrasp.learning.io import load_model, read_config, save_model  # noqa: E402
from affordgrasp.learning.targets import make_target  # noqa: E402
from affordgrasp.learning.training import (  # noqa: E402
    Inputs,
    TrainSettings,
    default_config,
    predict_scores,
    train_model,
)


def _samples(n: int, seed: int) -> Samples:
    """64x64 depth images (small, for speed) of a square; viable when it is near (0.2 m)."""
    rng = np.random.default_rng(seed)
    near = rng.random(n) < 0.5
    depth = np.zeros((n, 64, 64), dtype=np.uint16)
    for i in range(n):
        r, c = rng.integers(10, 40, 2)
        depth[i, r : r + 20, c : c + 20] = 200 if near[i] else 500
    p0 = np.c_[rng.uniform(-1, 1, (n, 5)), rng.random(n)]
    return Samples(
        object=np.array(["box:0"] * n, dtype=object),
        family=np.array(["box"] * n, dtype=object),
        sample=np.arange(n),
        p0=p0,
        use_dir=rng.uniform(-1, 1, (n, 2)),
        y=near.astype(np.float64),
        depth_mm=depth,
    )


SETTINGS = TrainSettings(epochs=4, batch_size=16, patience=5, seed=1)


@pytest.mark.parametrize("arch", ["cnn", "pointnet", "pointnet-slim"])
def test_tiny_classifier_learns_and_is_deterministic(arch):
    train, val = _samples(64, 0), _samples(32, 1)
    config = default_config(arch, make_target("viable"), n_points=64, width=8)
    model, summary = train_model(config, train, val, SETTINGS)
    losses = [h["train_loss"] for h in summary["history"]]
    assert losses[-1] < losses[0]
    assert [h["lr"] for h in summary["history"]][:3] == pytest.approx([1e-3, 5e-4, 1e-3 / 3])
    model2, summary2 = train_model(config, train, val, SETTINGS)
    assert [h["train_loss"] for h in summary2["history"]] == losses
    a = model.state_dict()
    b = model2.state_dict()
    assert all(np.array_equal(a[k].numpy(), b[k].numpy()) for k in a)
    scores = predict_scores(model, config, Inputs(config, val))
    assert scores.shape == (32,) and np.all((scores >= 0) & (scores <= 1))


def test_regressor_and_early_stopping(tmp_path):
    # Validation targets are the opposite of the training ones: once the model learns the
    # training rule the validation loss rises, and training stops `patience` epochs later.
    train, val = _samples(128, 2), _samples(32, 3)
    train.y = np.where(train.p0[:, 0] > 0, 250.0, 0.0)
    val.y = np.where(val.p0[:, 0] > 0, 0.0, 250.0)
    target = make_target("hold_effort_sum")
    assert target.normalise(np.array([0.0, 250.0])).tolist() == [0.0, 1.0]
    config = default_config("pose", target)
    settings = TrainSettings(epochs=30, batch_size=16, patience=2, seed=0)
    model, summary = train_model(config, train, val, settings)
    assert len(summary["history"]) < 30  # stopped early
    best = min(h["val_loss"] for h in summary["history"])
    assert summary["best_val_loss"] == pytest.approx(best)


def test_save_load_round_trip_without_pickle(tmp_path, monkeypatch):
    train, val = _samples(32, 4), _samples(16, 5)
    config = default_config("pointnet", make_target("viable"), n_points=32, width=8)
    model, _ = train_model(config, train, val, TrainSettings(epochs=1, batch_size=16))
    path = save_model(tmp_path / "m.safetensors", model, config)

    def no_pickle(*args, **kwargs):
        raise AssertionError("pickle used")

    import torch

    monkeypatch.setattr(pickle, "loads", no_pickle)
    monkeypatch.setattr(pickle, "load", no_pickle)
    monkeypatch.setattr(torch, "load", no_pickle)
    loaded, cfg = load_model(path)
    assert cfg["arch"] == "pointnet" and cfg["n_points"] == 32
    assert read_config(path)["target"]["name"] == "viable"
    x = Inputs(config, val)
    np.testing.assert_array_equal(predict_scores(model, config, x), predict_scores(loaded, cfg, x))
    with open(path, "rb") as f:
        assert b"pickle" not in f.read(64)


def test_pose_only_baseline_needs_no_images():
    train, val = _samples(32, 6), _samples(16, 7)
    train.depth_mm = val.depth_mm = None
    config = default_config("pose", make_target("viable"))
    model, summary = train_model(config, train, val, TrainSettings(epochs=2, batch_size=16))
    assert len(summary["history"]) == 2


def test_ensemble_is_the_mean_of_its_members_and_round_trips(tmp_path):
    train, val = _samples(48, 8), _samples(16, 9)
    target = make_target("hold_effort_sum")
    train.y, val.y = 250.0 * train.y, 250.0 * val.y
    settings = TrainSettings(epochs=2, batch_size=16, seed=3)
    config = default_config("cnn", target, width=8, members=2)
    ensemble, summary = train_model(config, train, val, settings)
    assert len(summary["members"]) == 2 and len(ensemble.members) == 2
    x = Inputs(config, val)
    single = dict(config, members=1)
    one, _ = train_model(single, train, val, settings)  # member 0: seed 3
    two, _ = train_model(single, train, val, TrainSettings(epochs=2, batch_size=16, seed=4))
    mean = (predict_scores(one, single, x) + predict_scores(two, single, x)) / 2
    np.testing.assert_allclose(predict_scores(ensemble, config, x), mean, rtol=1e-5, atol=1e-6)
    path = save_model(tmp_path / "e.safetensors", ensemble, config)
    loaded, cfg = load_model(path)
    assert cfg["members"] == 2
    np.testing.assert_array_equal(
        predict_scores(loaded, cfg, x), predict_scores(ensemble, config, x)
    )


def test_decision_threshold_chosen_on_validation_and_round_trips(tmp_path):
    from affordgrasp.learning.api import choose_threshold
    from affordgrasp.learning.decisions import decision_threshold
    from affordgrasp.learning.evaluation import best_f1_threshold

    train, val = _samples(64, 0), _samples(32, 1)
    config = default_config("cnn", make_target("viable"), width=8)
    model, _ = train_model(config, train, val, SETTINGS)
    val.meta.update(positive_weight=1.0, negative_weight=5.0)
    chosen = choose_threshold(model, config, val)
    prob = predict_scores(model, config, Inputs(config, val))
    weights = np.where(val.y > 0.5, 1.0, 5.0)
    assert chosen["value"] == best_f1_threshold(val.y, prob, weights=weights)[0]
    from affordgrasp.learning.api import _natural_rate

    # 1 row per positive, 5 per negative: the objects' rate is P / (P + 5 N)
    p = int((val.y > 0.5).sum())
    assert _natural_rate(val) == pytest.approx(p / (p + 5 * (len(val) - p)))
    config["decision_threshold"] = chosen
    path = save_model(tmp_path / "c.safetensors", model, config)
    assert decision_threshold(read_config(path)) == chosen["value"]


def test_prior_shift_calibration_moves_the_odds():
    from affordgrasp.errors import InputError
    from affordgrasp.learning.training import prior_shift

    train, val = _samples(32, 0), _samples(16, 1)
    config = default_config("pose", make_target("viable"), width=4)
    model, _ = train_model(config, train, val, TrainSettings(epochs=1, batch_size=16, seed=0))
    raw = predict_scores(model, config, Inputs(config, val))
    config["calibration"] = {"kind": "prior_shift", "from_rate": 0.5, "to_rate": 0.05}
    shifted = predict_scores(model, config, Inputs(config, val))
    odds = raw / (1 - raw) * 0.05 / 0.95  # the odds times pi / (1 - pi)
    np.testing.assert_allclose(shifted, odds / (1 + odds), rtol=1e-6)
    assert prior_shift({}) == 0.0
    with pytest.raises(InputError, match="prior shift"):
        prior_shift({"calibration": {"kind": "prior_shift", "from_rate": 0.5, "to_rate": 1.0}})


def test_a_model_reads_the_hand_view_and_round_trips(tmp_path):
    from affordgrasp.errors import InputError
    from affordgrasp.learning.io import check_config
    from affordgrasp.learning.views import VIEW_SIZE

    train, val = _samples(48, 10), _samples(16, 11)
    config = default_config("cnn", make_target("viable"), width=8, view="hand")
    assert config["view"] == "hand" and config["canonical"] is True
    x = Inputs(config, val)
    image, pose = x.batch(np.arange(4))
    assert tuple(image.shape) == (4, 6, VIEW_SIZE, VIEW_SIZE) and pose.shape[1] == 15
    model, summary = train_model(config, train, val, TrainSettings(epochs=2, batch_size=16))
    assert len(summary["history"]) == 2
    path = save_model(tmp_path / "h.safetensors", model, config)
    loaded, cfg = load_model(path)
    assert cfg["view"] == "hand"
    np.testing.assert_array_equal(predict_scores(loaded, cfg, x), predict_scores(model, config, x))
    # a view the package does not know, or on an architecture without images, is refused
    for bad in ({"view": "side"}, {"view": "hand", "arch": "pointnet"}):
        with pytest.raises(InputError, match="view"):
            check_config(dict(cfg, **bad), path)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"rank_weight": float("nan")}, "rank_weight must be a finite number >= 0, got nan"),
        ({"rank_weight": float("inf")}, "rank_weight must be a finite number >= 0, got inf"),
        ({"rank_weight": -1.0}, "rank_weight must be a finite number >= 0, got -1.0"),
        ({"max_seconds": 0.0}, "max_seconds must be a finite number > 0, got 0.0"),
        ({"max_seconds": float("nan")}, "max_seconds must be a finite number > 0, got nan"),
    ],
)
def test_settings_that_would_train_nonsense_are_refused(options, message):
    from affordgrasp.errors import InputError

    with pytest.raises(InputError, match=message):
        TrainSettings(**options)
