"""The learning commands end to end on a tiny dataset: train, predict, model-eval, depth."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from affordgrasp.cli import main

pytest.importorskip("torch")


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    from affordgrasp.dataset.generate import generate

    out = tmp_path_factory.mktemp("learn") / "ds"
    generate(["knife:0", "knife:1", "knife:2"], 24, out, seed=0, workers=1, depth=True)
    return out


def test_train_predict_evaluate(tiny_dataset, tmp_path, capsys):
    model = tmp_path / "m.safetensors"
    rc = main(
        [
            "train",
            str(tiny_dataset),
            "--model",
            "cnn",
            "--target",
            "n_contacts",
            "--epochs",
            "2",
            "-o",
            str(model),
            "--json",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    split = doc["config"]["training"]["split"]
    assert len(split["test"]) == 1 and split["test"][0] not in split["train"]
    preds = tmp_path / "p.parquet"
    assert main(["predict", str(model), str(tiny_dataset), "--out", str(preds)]) == 0
    table = pq.read_table(preds)
    assert table.column_names == ["object", "sample", "pred_n_contacts"]
    assert table.num_rows == 72 and np.isfinite(table.column(2).to_numpy()).all()
    capsys.readouterr()
    plots = tmp_path / "plots"
    rc = main(["model-eval", str(model), str(tiny_dataset), "--plots", str(plots), "--json"])
    assert rc == 0, capsys.readouterr().err
    rep = json.loads(capsys.readouterr().out)["reports"]["model"]
    assert 0 <= rep["comparison_accuracy"] <= 1 and rep["n"] == 24
    assert (plots / "gms_cdf.png").stat().st_size > 1000


def test_bad_inputs_exit_2(tiny_dataset, tmp_path, capsys):
    assert main(["train", str(tmp_path / "none"), "-o", str(tmp_path / "m.safetensors")]) == 2
    assert "does not exist" in capsys.readouterr().err
    rc = main(
        ["train", str(tiny_dataset), "--target", "nope", "-o", str(tmp_path / "m.safetensors")]
    )
    assert rc == 2 and "nope" in capsys.readouterr().err
    rc = main(["train", str(tiny_dataset), "--members", "0", "-o", str(tmp_path / "m.safetensors")])
    assert rc == 2 and "--members" in capsys.readouterr().err
    assert (
        main(
            [
                "predict",
                str(tmp_path / "x.safetensors"),
                str(tiny_dataset),
                "--out",
                str(tmp_path / "p.parquet"),
            ]
        )
        == 2
    )


def test_depth_command_png_and_npy(tmp_path, capsys):
    npy = tmp_path / "d.npy"
    assert main(["depth", "knife", "--p0", "0.1,0.2,0.3,0,0,0.5", "-o", str(npy), "--json"]) == 0
    facts = json.loads(capsys.readouterr().out)
    depth = np.load(npy)
    assert depth.shape == (128, 128) and depth.dtype == np.float32
    assert facts["pixels_hit"] == int((depth > 0).sum()) > 0
    png = tmp_path / "d.png"
    assert main(["depth", "knife", "--sample", "3", "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert main(["depth", "knife", "--p0", "1,2,3"]) == 2


def test_predict_with_the_shipped_models(tiny_dataset, tmp_path):
    from affordgrasp.learning.api import pretrained_path
    from affordgrasp.learning.io import read_config

    for kind, target in (("classifier", "viable"), ("regressor", "hold_effort_sum")):
        path = pretrained_path(kind)
        assert path.stat().st_size < 10_000_000
        assert read_config(path)["target"]["name"] == target
    out = tmp_path / "p.parquet"
    assert main(["predict", "default", str(tiny_dataset), "--out", str(out)]) == 0
    table = pq.read_table(out)
    assert table.column_names == ["object", "sample", "viable_prob", "pred_hold_effort_sum"]
    p = table.column("viable_prob").to_numpy()
    assert table.num_rows == 72 and np.all((p >= 0) & (p <= 1))


def _without_times(value):
    if isinstance(value, dict):
        return {k: _without_times(v) for k, v in value.items() if k != "seconds"}
    if isinstance(value, list):
        return [_without_times(v) for v in value]
    return value


def test_training_from_a_dataset_is_deterministic_to_the_bit(tiny_dataset, tmp_path):
    # What the shipped models' recipe uses (canonical depth, ranking loss, an ensemble)
    # trained twice from the same dataset and seed: the same tensors, the same config but
    # for the times.
    from safetensors.numpy import load_file

    from affordgrasp.learning.api import train_on_dataset
    from affordgrasp.learning.io import read_config
    from affordgrasp.learning.training import TrainSettings

    paths = [tmp_path / "a.safetensors", tmp_path / "b.safetensors"]
    for path in paths:
        train_on_dataset(
            tiny_dataset,
            arch="cnn",
            target="n_contacts",
            out=path,
            settings=TrainSettings(epochs=2, seed=0, rank_weight=1.0),
            canonical=True,
            members=2,
        )
    a, b = (load_file(p) for p in paths)
    assert a.keys() == b.keys() and len(a) > 0
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name
    config_a, config_b = (read_config(p) for p in paths)
    assert len(config_a["training"]["members"]) == 2
    assert _without_times(config_a) == _without_times(config_b)


def test_model_eval_decisions_and_calibration(tiny_dataset, tmp_path, capsys):
    plots = tmp_path / "plots"
    rc = main(
        [
            "model-eval",
            "classifier",
            str(tiny_dataset),
            "--objects",
            "all",
            "--candidates",
            "8",
            "--draws",
            "3",
            "--threshold",
            "0.7",
            "--plots",
            str(plots),
            "--json",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    dec = doc["decisions"]
    assert dec["objects"] == 3 and dec["rule"] == "highest viability probability"
    for entry in dec["per_object"].values():
        assert entry["draws"] == 3 and entry["candidates"] == 8
        assert entry["oracle"]["top1_percentile"] >= entry["model"]["top1_percentile"]
        assert entry["random"]["top1_percentile"] == pytest.approx(50.0)
    assert 0 <= doc["reports"]["model"]["expected_calibration_error"] <= 1
    assert (plots / "reliability.png").stat().st_size > 1000


def test_model_eval_without_test_objects_and_subsample_say_so(tiny_dataset, capsys):
    # the shipped classifier's test objects are not in this dataset: every object, said
    rc = main(
        [
            "model-eval",
            "classifier",
            str(tiny_dataset),
            "--max-rows",
            "10",
            "--no-decisions",
            "--json",
        ]
    )
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    sel = json.loads(captured.out)["reports"]["model"]["selection"]
    assert sel["objects"].startswith("every object") and "training" in sel["objects"]
    assert sel["subsampled"] and sel["rows_evaluated"] == 10 and sel["rows_available"] == 72
    assert "subsample of 10 of 72 rows" in captured.err


def test_streamed_training_reads_each_epochs_rows_once_within_its_buffer(tiny_dataset):
    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.learning.api import prepare_split, train_on_dataset
    from affordgrasp.learning.streaming import StreamedEpochs
    from affordgrasp.learning.training import TrainSettings, default_config

    train, val, test, target, _ = prepare_split(
        tiny_dataset, "n_contacts", max_train=None, train_depth=False
    )
    assert train.depth_mm is None and val.depth_mm is not None
    config = default_config("cnn", target, width=4)
    epochs = StreamedEpochs(Dataset.open(tiny_dataset), config, train, batch_size=4, buffer_rows=10)
    batches, n = epochs(1, 0)
    seen = []
    for inputs, idx, y in batches:
        assert inputs.depth_mm.shape[0] <= 10 and len(idx) <= 4
        seen += [float(v) for v in y]
    sizes = [10] * (len(train) // 10) + ([len(train) % 10] if len(train) % 10 else [])
    assert len(seen) == len(train) and n == sum(-(-k // 4) for k in sizes)
    # the targets streamed are the training rows' targets
    assert sorted(seen) == pytest.approx(sorted(target.normalise(train.y)))
    settings = TrainSettings(epochs=2, batch_size=4, seed=0)
    kwargs = dict(arch="cnn", target="n_contacts", settings=settings, stream=True, buffer_rows=10)
    m1, c1 = train_on_dataset(tiny_dataset, **kwargs)
    m2, c2 = train_on_dataset(tiny_dataset, **kwargs)
    assert c1["training"]["streamed"]["max_buffered"] <= 10
    a, b = m1.state_dict(), m2.state_dict()
    assert all(np.array_equal(a[k].numpy(), b[k].numpy()) for k in a)  # seeded


def test_model_eval_decides_beside_a_pose_only_baseline(tiny_dataset, tmp_path, capsys):
    pose = tmp_path / "pose.safetensors"
    args = ["train", str(tiny_dataset), "--model", "pose", "--target", "n_contacts"]
    assert main([*args, "--epochs", "1", "-o", str(pose)]) == 0, capsys.readouterr().err
    capsys.readouterr()
    rc = main(
        [
            "model-eval",
            "classifier",
            str(tiny_dataset),
            "--objects",
            "knife:0",
            "--baseline",
            str(pose),
            "--candidates",
            "6",
            "--draws",
            "2",
            "--json",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    dec = json.loads(capsys.readouterr().out)["decisions"]
    assert dec["baseline_rule"] == "largest predicted n_contacts"
    entry = dec["per_object"]["knife:0"]
    assert set(entry) >= {"model", "baseline", "random", "oracle"}
    assert entry["baseline"]["top1_percentile"] <= entry["oracle"]["top1_percentile"]

    # A baseline's subsample is said too, on stderr and in the JSON, never silently.
    rc = main(
        ["model-eval", str(pose), str(tiny_dataset), "--baseline", str(pose), "--max-rows", "10"]
        + ["--objects", "all", "--no-decisions", "--json"]
    )
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    base = json.loads(captured.out)["models"][0]["baseline"]
    assert base["selection"]["subsampled"] and base["selection"]["rows_evaluated"] == 10
    assert "baseline pose on n_contacts: evaluating a uniform subsample of 10" in captured.err


def test_decisions_replay_the_choice_in_physics(tiny_dataset):
    pytest.importorskip("mujoco")
    pytest.importorskip("coacd")
    from affordgrasp.learning.decision_eval import evaluate_decisions
    from affordgrasp.learning.plan import load_models

    res = evaluate_decisions(
        load_models("classifier"), tiny_dataset, ["knife:0"], candidates=3, draws=1, physics=True
    )
    outcome = res["per_object"]["knife:0"]["physics"]
    assert isinstance(outcome["hold_ok"], bool)
    assert res["physics_hold_rate"] == float(outcome["hold_ok"])


def test_thresholded_target_and_robust_decisions(tiny_dataset, tmp_path, capsys):
    # a thresholded column is a classifier target (here a plain column, for speed)
    model = tmp_path / "c.safetensors"
    args = ["train", str(tiny_dataset), "--target", "n_contacts>=3", "--epochs", "1"]
    rc = main([*args, "-o", str(model), "--json"])
    assert rc == 0, capsys.readouterr().err
    target = json.loads(capsys.readouterr().out)["config"]["target"]
    assert target["kind"] == "classification" and target["name"] == "n_contacts>=3"
    # a dataset with robust labels: the decisions report the chosen grasp's robust rate
    from affordgrasp.dataset.generate import generate

    robust = tmp_path / "robust"
    generate(["knife:0"], 12, robust, seed=0, workers=1, depth=True, robust=2)
    rc = main(
        ["model-eval", str(model), str(robust), "--objects", "all", "--candidates", "64", "--json"]
    )
    assert rc == 0, capsys.readouterr().err
    entry = json.loads(capsys.readouterr().out)["decisions"]["per_object"]["knife:0"]
    rate = pq.read_table(robust).column("robust_viable").to_numpy()
    # every row is a candidate: random's expectation is the object's mean rate
    assert entry["random"]["top1_robust_viable"] == pytest.approx(rate.mean())
    assert entry["model"]["top1_robust_viable"] in set(rate.tolist())
