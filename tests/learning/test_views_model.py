"""The fused views judged as a model: the calibration map, the model file, predictions that
are the simulation on the fused surface, and model-eval / predict end to end."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest
from hypothesis import given
from hypothesis import strategies as st

from affordgrasp.cli import main
from affordgrasp.errors import InputError
from affordgrasp.learning.views_model import (
    FORMAT,
    calibrated,
    fit_calibration,
    load_views_models,
    read_views_config,
    share_score,
    views_config_path,
    write_views_config,
)


def test_calibration_map_is_the_rate_of_each_share():
    cal = fit_calibration(np.array([0, 0, 0.5, 0.5, 1, 1.0]), np.array([0, 0, 0, 1, 1, 1]))
    assert cal == {"share": [0.0, 0.5, 1.0], "rate": [0.0, 0.5, 1.0]}
    # a rate that falls with the share is pooled with its neighbour (isotonic)
    cal = fit_calibration(np.array([0, 0, 0.5, 0.5]), np.array([0, 1, 0, 0]))
    assert cal["share"] == [0.0, 0.5] and cal["rate"] == pytest.approx([0.25, 0.25])
    assert fit_calibration(np.array([0.5, np.nan]), [1, 0])["share"] == [0.0, 0.5]


@given(
    st.lists(st.floats(0, 1), min_size=1, max_size=8),
    st.lists(st.integers(0, 10**9), min_size=2, max_size=40, unique=True),
)
def test_calibrated_probabilities_keep_every_ranking(rates, scores):
    rates = sorted(rates)
    cal = {"share": list(np.linspace(0, 1, len(rates))), "rate": rates}
    s = np.sort(np.array(scores)) / 1e9  # scores apart by 1e-9 or more (ε tie-breaks: 1e-5)
    p = calibrated(s, cal)
    assert np.all((p >= 0) & (p <= 1))
    assert np.all(np.diff(p) > 0)  # strictly increasing: the map makes no ties
    assert np.array_equal(calibrated(s, None), s)


def test_share_score_breaks_ties_by_epsilon_and_never_across_shares():
    s = share_score(np.array([0.48, 0.48, 0.52, np.nan]), np.array([0.5, 0.01, 0.0, 0.3]))
    assert s[0] > s[1] and s[2] > s[0] and s[3] < s[1]


def test_views_model_files_are_checked(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        read_views_config(tmp_path / "none.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(InputError, match="not readable JSON"):
        read_views_config(bad)
    bad.write_text(json.dumps({"arch": "cnn"}))
    with pytest.raises(InputError, match="not a views model file"):
        read_views_config(bad)
    bad.write_text(json.dumps({"format": FORMAT, "format_version": 99}))
    with pytest.raises(InputError, match="upgrade affordgrasp"):
        read_views_config(bad)
    bad.write_text(json.dumps({"format": FORMAT, "views": 64, "seed": 0}))
    with pytest.raises(InputError, match="'copies' must be an integer >= 1, got None"):
        read_views_config(bad)
    good = {"format": FORMAT, "views": 8, "copies": 2, "seed": 0}
    bad.write_text(json.dumps({**good, "calibration": {"share": [0.5, 0.1], "rate": [0, 1]}}))
    with pytest.raises(InputError, match="knots"):
        read_views_config(bad)


def test_the_shipped_views_model_was_fitted_on_validation_objects():
    config = read_views_config(views_config_path())
    cal = config["calibration"]
    assert cal["rows"] > 1000 and np.all(np.diff(cal["rate"]) >= 0)
    assert 0 < config["decision_threshold"]["value"] < 1
    fitted = config["training"]["split"]["val"]
    assert len(fitted) == 13 and all(name.endswith(":7") for name in fitted)
    (clf, c1), (reg, c2) = load_views_models("views")
    assert clf is reg and c1["target"]["name"] == "viable" and c2["target"]["name"] == "robust_hold"
    assert "decision_threshold" not in c2
    (_, c1), (_, c2) = load_views_models("views:raw")
    with pytest.raises(InputError, match="views:raw"):
        load_views_models("views:hold")
    assert c2["target"]["name"] == "hold_effort_sum" and c2["target"]["lower_is_better"]


@pytest.fixture(scope="module")
def robust_dataset(tmp_path_factory):
    from affordgrasp.dataset.generate import generate

    out = tmp_path_factory.mktemp("views") / "ds"
    generate(["knife:5", "hammer:5"], 12, out, seed=3, workers=1, robust=2)
    return out


@pytest.fixture(scope="module")
def small_views(tmp_path_factory):
    """A views model of 8 views and 2 copies (cheap), with the shipped calibration."""
    config = read_views_config(views_config_path())
    config.update(views=8, copies=2)
    return write_views_config(tmp_path_factory.mktemp("vm") / "views8.json", config)


def test_predictions_are_the_simulation_on_the_fused_surface(robust_dataset, small_views):
    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.learning.data import read_rows
    from affordgrasp.learning.views_model import fused_surface, perturbation_seed
    from affordgrasp.pipeline import evaluate_inputs
    from affordgrasp.robust import RobustSettings

    lines = []
    (views, c1), (_, c2) = load_views_models(small_views, log=lines.append)
    samples, _ = read_rows(Dataset.open(robust_dataset), "viable")
    prob = views.predict(c1, samples)
    hold = views.predict(c2, samples)
    assert len(lines) == 2  # one simulation per object, kept for the ranker
    assert np.all((prob >= 0) & (prob <= 1)) and np.all((hold > -0.1) & (hold <= 1))
    ds = Dataset.open(robust_dataset)
    knife = samples.object == "knife:5"
    obj = ds.object("knife:5")
    table = evaluate_inputs(
        fused_surface(obj, views=8),
        samples.p0[knife],
        samples.use_dir[knife],
        # the predictor's own perturbations, not the labels' (seed 0)
        robust=RobustSettings(copies=2, seed=perturbation_seed(c1)),
        frame=obj,
    ).table
    share = table.column("robust_viable").to_numpy(zero_copy_only=False)
    eps = table.column("epsilon").to_numpy(zero_copy_only=False)
    assert np.array_equal(prob[knife], calibrated(share_score(share, eps), c1["calibration"]))
    fused_hold = table.column("robust_hold").to_numpy(zero_copy_only=False)
    assert np.allclose(hold[knife] * 6, fused_hold) and fused_hold.max() > 1
    # the raw ranker: the fused ΣE_h, the viability bound where the grasp does not hold
    from affordgrasp.columns import HOLD_EFFORT_COLUMNS, hold_effort_sum

    effort = views.predict(load_views_models("views:raw")[1][1], samples)[knife] * 250
    fused_effort = hold_effort_sum(
        {c: table.column(c).to_numpy(zero_copy_only=False) for c in HOLD_EFFORT_COLUMNS}
    )
    assert np.allclose(effort, np.where(np.isfinite(fused_effort), fused_effort, 250.0))
    assert len(lines) == 2
    # a subset in another order: the same predictions, nothing simulated again
    idx = np.flatnonzero(knife)[::-1]
    assert np.array_equal(views.predict(c1, samples.take(idx)), prob[idx]) and len(lines) == 2


def test_views_outside_a_dataset_are_refused(small_views):
    from affordgrasp.learning.data import Samples

    (views, c1), _ = load_views_models(small_views)
    rows = Samples(
        np.array(["knife"], dtype=object),
        np.array(["knife"], dtype=object),
        np.zeros(1, dtype=np.int64),
        np.full((1, 6), 0.5),
        np.full((1, 2), 0.5),
        np.full(1, np.nan),
    )
    with pytest.raises(InputError, match="dataset's rows"):
        views.predict(c1, rows)


def test_model_eval_and_predict_with_the_views(robust_dataset, small_views, tmp_path, capsys):
    pytest.importorskip("skimage")
    rc = main(
        [
            "model-eval",
            str(small_views),
            str(robust_dataset),
            "--candidates",
            "8",
            "--draws",
            "2",
            "--json",
        ]
    )
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    doc = json.loads(captured.out)
    assert [m["arch"] for m in doc["models"]] == ["views", "views"]
    assert [m["target"]["name"] for m in doc["models"]] == ["viable", "robust_hold"]
    clf, reg = (m["report"] for m in doc["models"])
    assert 0 <= clf["expected_calibration_error"] <= 1 and reg["n"] == 24
    assert "largest predicted robust_hold" in doc["decisions"]["rule"]
    assert "every object" in clf["selection"]["objects"]  # views hold out no objects
    assert captured.err.count("views: ") == 2  # one simulation per object
    out = tmp_path / "p.parquet"
    assert main(["predict", str(small_views), str(robust_dataset), "--out", str(out)]) == 0
    table = pq.read_table(out)
    assert table.column_names == ["object", "sample", "viable_prob", "pred_robust_hold"]
    assert table.num_rows == 24


def test_model_eval_views_without_robust_labels_judges_the_classifier(
    small_views, tmp_path, capsys
):
    pytest.importorskip("skimage")
    from affordgrasp.dataset.generate import generate

    plain = tmp_path / "plain"
    generate(["knife:5"], 10, plain, seed=3, workers=1)
    capsys.readouterr()
    rc = main(["model-eval", str(small_views), str(plain), "--no-decisions", "--json"])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    assert [m["target"]["name"] for m in json.loads(captured.out)["models"]] == ["viable"]
    assert "ranker of robust_hold is not judged" in captured.err + captured.out


def test_plan_decides_with_views_not_a_views_model_file(tmp_path):
    from affordgrasp.learning.plan import plan

    for spec in ("views:raw", str(tmp_path / "v.json")):
        with pytest.raises(InputError, match="model-eval and predict"):
            plan("knife", models=spec)


def test_bad_views_options_exit_2(robust_dataset, tmp_path, capsys):
    assert main(["model-eval", "views:hold", str(robust_dataset)]) == 2
    assert "unknown views ranker 'hold'" in capsys.readouterr().err
    missing = tmp_path / "none.json"
    rc = main(["predict", str(missing), str(robust_dataset), "--out", str(tmp_path / "p.parquet")])
    assert rc == 2 and "does not exist" in capsys.readouterr().err


def test_objects_simulated_in_worker_processes_match_in_process(robust_dataset, small_views):
    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.learning.data import read_rows
    from affordgrasp.learning.views_model import FusedViews

    samples, _ = read_rows(Dataset.open(robust_dataset), "viable")
    config = read_views_config(small_views)
    lines = []
    apart = FusedViews(config, workers=2, log=lines.append).raw(samples)
    assert len(lines) == 2 and np.array_equal(apart, FusedViews(config).raw(samples))
    with pytest.raises(InputError, match="workers"):
        FusedViews(config, workers=0)


def test_model_eval_refuses_no_workers(robust_dataset, capsys):
    assert main(["model-eval", "views", str(robust_dataset), "--workers", "0"]) == 2
    assert "--workers must be >= 1" in capsys.readouterr().err
