"""The decision loop: candidates, views, predictions, choice, simulated truth."""

import json

import numpy as np
import pytest

pytest.importorskip("torch")

import affordgrasp as ag  # noqa: E402
from affordgrasp.cli import main  # noqa: E402
from affordgrasp.errors import InputError  # noqa: E402
from affordgrasp.learning.decisions import decision_order, true_percentiles  # noqa: E402


def test_plan_chooses_by_the_rule_and_reports_the_truth(box_mesh):
    from affordgrasp.learning.api import resolve_models
    from affordgrasp.learning.decisions import decision_threshold
    from affordgrasp.learning.io import read_config

    p = ag.plan(str(box_mesh), "pick-paper", candidates=6, seed=3, models="default")
    assert isinstance(p, ag.Plan)
    assert p.chosen == p.order[0] and sorted(p.order.tolist()) == list(range(6))
    # the order is the rule's on the predictions, at the shipped classifier's stored threshold
    (clf,) = resolve_models("classifier")
    t = decision_threshold(read_config(clf))
    assert 0.0 < t < 0.5  # chosen on validation objects, after the calibration
    again = decision_order(p.probability, p.predicted, threshold=t)
    assert again.tolist() == p.order.tolist()
    # the truth: -ΣE_h of the simulated candidates, the percentile among them
    from affordgrasp.columns import HOLD_EFFORT_COLUMNS

    effort = sum(p.table.column(c).to_numpy() for c in HOLD_EFFORT_COLUMNS)
    np.testing.assert_allclose(p.true_score, -effort)
    assert p.percentile == true_percentiles(p.true_score)[p.chosen]
    assert p.measures["oracle"]["top1_percentile"] >= p.percentile
    assert p.measures["random"]["top1_percentile"] == pytest.approx(50.0)
    doc = p.summary()
    assert doc["chosen"]["index"] == p.chosen and doc["candidates"] == 6
    json.dumps(doc)  # JSON-ready
    # same seed, same candidates and choice
    q = ag.plan(str(box_mesh), "pick-paper", candidates=6, seed=3, models="default")
    assert q.chosen == p.chosen and np.array_equal(q.p0, p.p0)


def test_plan_with_a_classifier_alone_takes_the_most_probable(box_mesh):
    p = ag.plan(str(box_mesh), "pick", candidates=5, models="classifier", seed=1)
    assert p.predicted is None and p.chosen == int(np.argmax(p.probability))
    assert p.rule == "highest viability probability"


def test_plan_command_json_and_bad_input(box_mesh, capsys):
    rc = main(["plan", str(box_mesh), "--candidates", "4", "--task", "pick", "--json"])
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["candidates"] == 4 and 0 <= doc["chosen"]["percentile"] <= 100
    assert main(["plan", str(box_mesh), "--candidates", "0"]) == 2
    assert "candidates" in capsys.readouterr().err
    assert main(["plan", str(box_mesh), "--task", "nope"]) == 2
    assert main(["plan", str(box_mesh), "--threshold", "2"]) == 2
    capsys.readouterr()
    assert main(["plan", str(box_mesh), "--candidates", "1000000000"]) == 2
    assert "GB in memory" in capsys.readouterr().err


def test_plan_physics_replays_the_chosen_grasp(box_mesh):
    pytest.importorskip("mujoco")
    pytest.importorskip("coacd")
    p = ag.plan(str(box_mesh), "pick", candidates=3, seed=0, physics=True)
    assert isinstance(p.physics["hold_ok"], bool)
    assert "physics" in p.timings


def test_plan_with_a_sensor_sees_other_images_of_the_same_candidates(box_mesh):
    from affordgrasp.vision.sensor import SensorModel

    exact = ag.plan(str(box_mesh), "pick", candidates=4, seed=2, models="classifier")
    sensed = ag.plan(
        str(box_mesh), "pick", candidates=4, seed=2, models="classifier", sensor=SensorModel()
    )
    assert np.array_equal(exact.p0, sensed.p0)
    np.testing.assert_array_equal(exact.true_score, sensed.true_score)
    assert not np.array_equal(exact.probability, sensed.probability)


def test_plan_offset_range_scales_the_candidates_offsets_only(box_mesh, capsys):
    from affordgrasp.grasp.pregrasp import PLAN_OFFSET_RANGE as OFFSET_RANGE_HELP
    from affordgrasp.grasp.pregrasp import sample_inputs
    from affordgrasp.learning.plan import OFFSET_RANGE

    assert OFFSET_RANGE_HELP == OFFSET_RANGE
    uniform = ag.plan(str(box_mesh), "pick", candidates=5, seed=4, offset_range=1.0)
    near = ag.plan(str(box_mesh), "pick", candidates=5, seed=4)
    p0, d = sample_inputs(4, 0, 5)
    assert uniform.drawn == near.drawn == 5  # then the refined ones
    np.testing.assert_array_equal(uniform.p0[:5], p0)
    np.testing.assert_array_equal(uniform.use_dir[:5], d)
    # the default: the same draws, the offsets (u4, u5) scaled into [-R, R]²
    np.testing.assert_array_equal(near.p0[:5, [0, 1, 2, 5]], p0[:, [0, 1, 2, 5]])
    np.testing.assert_array_equal(near.p0[:5, 3:5], OFFSET_RANGE * p0[:, 3:5])
    np.testing.assert_array_equal(near.use_dir[:5], d)
    assert near.offset_range == OFFSET_RANGE and near.summary()["offset_range"] == OFFSET_RANGE
    for bad in (0.0, -0.5, 1.5, float("nan"), "wide"):
        with pytest.raises(InputError, match="offset_range"):
            ag.plan(str(box_mesh), "pick", candidates=2, offset_range=bad)
    rc = main(["plan", str(box_mesh), "--candidates", "3", "--offset-range", "1", "--json"])
    assert rc == 0, capsys.readouterr().err
    assert json.loads(capsys.readouterr().out)["offset_range"] == 1.0
    assert main(["plan", str(box_mesh), "--offset-range", "2"]) == 2
    assert "offset_range" in capsys.readouterr().err


def test_plan_with_the_views_decides_on_the_surface_they_fuse_into(box_mesh, capsys):
    p = ag.plan(
        str(box_mesh), "pick", candidates=12, seed=2, models="views", robust_check=0, refine=0
    )
    assert p.probability is None and p.predicted is None and p.fused_robust_viable is None
    assert p.fused_score.shape == (12,) and p.fused_viable.dtype == bool
    # viable on the fused surface first, then feasible there, then by its ε there
    key = [
        (not p.fused_viable[i], not np.isfinite(p.fused_score[i]), -p.fused_epsilon[i], i)
        for i in range(12)
    ]
    assert p.order.tolist() == [k[3] for k in sorted(key)]
    assert "fused from 12 views" in p.rule
    doc = p.summary()
    json.dumps(doc)
    assert doc["chosen"]["fused_viable"] == bool(p.fused_viable[p.chosen])
    # a box seen from 12 views: the fused surface's simulation mostly agrees with the truth
    assert (p.fused_viable == p.viable).mean() >= 0.75
    with pytest.raises(InputError, match="threshold"):
        ag.plan(str(box_mesh), candidates=2, models="views", threshold=0.3)
    rc = main(["plan", str(box_mesh), "--candidates", "6", "--model", "views", "--json"])
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["chosen"]["fused_viable"] is not None and "fuse" in doc["timings"]
    assert main(["plan", str(box_mesh), "--model", "views", "--threshold", "0.2"]) == 2


def test_plan_with_the_views_fuses_what_a_sensor_returns(box_mesh, monkeypatch):
    from affordgrasp.learning.plan import SENSOR_UNKNOWN_PX, SENSOR_VOTES
    from affordgrasp.vision import fusion
    from affordgrasp.vision.sensor import SensorModel

    options = []
    fused_object = fusion.fused_object

    def recorded(*args, **kwargs):
        options.append(kwargs)
        return fused_object(*args, **kwargs)

    monkeypatch.setattr(fusion, "fused_object", recorded)
    exact = ag.plan(str(box_mesh), "pick", candidates=8, seed=1, refine=0)
    sensed = ag.plan(
        str(box_mesh), "pick", candidates=8, seed=1, sensor=SensorModel(seed=1), refine=0
    )
    # exact images: the four pixels and the seen voxels; a sensor's: the filter alone, with
    # lost returns unknown and three votes (docs/learning.md)
    assert options[0]["subpixel"] and options[0]["keep_seen"] and options[0]["unknown_px"] == 0
    assert not options[1]["subpixel"] and not options[1]["keep_seen"]
    assert options[1]["unknown_px"] == SENSOR_UNKNOWN_PX and options[1]["votes"] == SENSOR_VOTES
    # the same candidates, each placed on the hull of the surface its views fused into
    np.testing.assert_array_equal(exact.p0, sensed.p0)
    assert sensed.fused_score.shape == (8,)
    # the fused surfaces differ, so their simulations do
    assert not np.array_equal(exact.fused_epsilon, sensed.fused_epsilon)


def test_plan_with_the_views_checks_its_first_candidates_under_perturbation(
    box_mesh, capsys, monkeypatch
):
    from affordgrasp.learning import plan as planning
    from affordgrasp.learning.decisions import margin_order

    p = ag.plan(str(box_mesh), "pick", candidates=12, seed=2, refine=0)  # the default checks 8
    margin = margin_order(p.fused_viable, p.fused_score, p.fused_epsilon)
    checked = margin[:8]
    r, q = p.fused_robust_viable, p.fused_robust_epsilon
    for values in (r, q):
        assert np.isfinite(values[checked]).all() and np.isnan(np.delete(values, checked)).all()
    assert ((r[checked] >= 0) & (r[checked] <= 1)).all() and (q[checked] >= 0).all()
    # the widest lower-quartile ε of the first eight (of those viable on the fused surface),
    # the others in the margin's order
    pool = checked[p.fused_viable[checked]] if p.fused_viable[checked].any() else checked
    assert p.chosen in pool and q[p.chosen] == q[pool].max()
    assert p.order[1:].tolist() == [i for i in margin if i != p.chosen]
    assert "the first 8" in p.rule
    doc = p.summary()
    assert doc["chosen"]["fused_robust_viable"] == r[p.chosen]
    assert doc["chosen"]["fused_robust_epsilon"] == q[p.chosen]
    # unperturbed copies are the grasps themselves: robust viability is the fused viability,
    # the quantile of ε is ε, and the widest ε stays first
    still = planning.RobustSettings(
        copies=3, translation_m=0.0, rotation_rad=0.0, friction_sd=0.0, com_m=0.0, tasks=()
    )
    monkeypatch.setattr(planning, "ROBUST_CHECK_SETTINGS", still)
    same = ag.plan(str(box_mesh), "pick", candidates=12, seed=2, robust_check=6, refine=0)
    np.testing.assert_array_equal(
        same.fused_robust_viable[margin[:6]], p.fused_viable[margin[:6]].astype(float)
    )
    np.testing.assert_array_equal(
        same.fused_robust_epsilon[margin[:6]], p.fused_epsilon[margin[:6]]
    )
    assert same.order.tolist() == margin.tolist()
    for bad in (-1, 1.5, True):
        with pytest.raises(InputError, match="robust_check"):
            ag.plan(str(box_mesh), candidates=2, robust_check=bad)
    rc = main(["plan", str(box_mesh), "--candidates", "6", "--robust-check", "0", "--json"])
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["chosen"]["fused_robust_viable"] is None and "perturbations" not in doc["rule"]
    assert doc["chosen"]["fused_robust_epsilon"] is None
    # learned models have no fused surface to check on
    assert main(["plan", str(box_mesh), "--model", "classifier", "--robust-check", "2"]) == 2
    assert "--model views" in capsys.readouterr().err


def test_plan_with_the_views_refines_its_first_candidates(box_mesh, capsys):
    from affordgrasp.grasp.pregrasp import PLAN_REFINE_NEIGHBOURS as J
    from affordgrasp.grasp.pregrasp import PLAN_REFINE_SIGMA
    from affordgrasp.learning.decisions import margin_order, percentile_among, random_measures
    from affordgrasp.learning.plan import REFINE_STREAM
    from affordgrasp.search.cem import nearby_inputs

    p = ag.plan(str(box_mesh), "pick", candidates=12, seed=2, robust_check=0, refine=3)
    n = 12 + 3 * J
    assert p.drawn == 12 and len(p.p0) == len(p.use_dir) == len(p.table) == n
    assert p.fused_score.shape == p.true_score.shape == p.viable.shape == (n,)
    # the refined candidates: drawn near the first three of the drawn ones' margin order,
    # their use directions kept
    first = margin_order(p.fused_viable[:12], p.fused_score[:12], p.fused_epsilon[:12])[:3]
    x = nearby_inputs(
        np.concatenate([p.p0[first], p.use_dir[first]], axis=1),
        np.r_[np.full(6, PLAN_REFINE_SIGMA), 0.0, 0.0],
        J,
        np.random.default_rng(np.random.SeedSequence([2, REFINE_STREAM])),
    )
    np.testing.assert_array_equal(p.p0[12:], x[:, :6])
    np.testing.assert_array_equal(p.use_dir[12:], np.repeat(p.use_dir[first], J, axis=0))
    # all ranked together; the truth of every one simulated; the chosen placed among the
    # drawn ones, a random choice among the drawn ones
    assert p.order.tolist() == margin_order(p.fused_viable, p.fused_score, p.fused_epsilon).tolist()
    assert p.percentile == percentile_among(p.true_score[[p.chosen]], p.true_score[:12])[0]
    assert p.measures["random"] == random_measures(
        p.true_score[:12], p.viable[:12], feasible=p.feasible[:12]
    )
    assert p.measures["model"]["top1_percentile"] == p.percentile
    assert "drawn near each of the first 3" in p.rule
    doc = p.summary()
    assert doc["candidates"] == 12 and doc["refined"] == 3 * J
    # refine=0: the drawn candidates alone, the same as before refining existed
    plain = ag.plan(str(box_mesh), "pick", candidates=12, seed=2, robust_check=0, refine=0)
    assert plain.drawn is None and len(plain.p0) == 12 and plain.summary()["refined"] == 0
    np.testing.assert_array_equal(plain.fused_epsilon, p.fused_epsilon[:12])
    np.testing.assert_array_equal(plain.true_score, p.true_score[:12])
    for bad in (-1, 2.5, True, "3"):
        with pytest.raises(InputError, match="refine"):
            ag.plan(str(box_mesh), candidates=2, refine=bad)
    rc = main(["plan", str(box_mesh), "--candidates", "4", "--refine", "1", "--json"])
    assert rc == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["candidates"] == 4 and doc["refined"] == J
    assert main(["plan", str(box_mesh), "--candidates", "4", "--refine", "1"]) == 0
    assert f"of 4 and {J} refined" in capsys.readouterr().out
    assert main(["plan", str(box_mesh), "--model", "classifier", "--refine", "2"]) == 2
    err = capsys.readouterr().err
    assert "--refine" in err and "--model views" in err


def test_plan_says_when_no_candidate_is_viable_on_the_fused_surface(box_mesh, capsys):
    # one candidate, one view: seed 1's is not viable on the surface that view fuses into,
    # seed 3's is
    for seed, warned in ((1, True), (3, False)):
        p = ag.plan(str(box_mesh), "pick", candidates=1, seed=seed)
        assert bool(p.fused_viable[0]) is not warned
        assert main(["plan", str(box_mesh), "--candidates", "1", "--seed", str(seed)]) == 0
        err = capsys.readouterr().err
        assert ("no candidate is viable on the fused surface" in err) is warned


def test_the_true_object_never_reaches_the_decision(monkeypatch):
    """Everything the decision simulates is the fused surface, placed on its own hull; the
    true object is simulated only by the check that follows (step "simulate")."""
    import affordgrasp.grasp.policy as policy
    import affordgrasp.pipeline as pipeline

    obj = ag.load_object("hammer:3")
    step = {"now": None}
    seen = []
    for module, name in ((pipeline, "evaluate_inputs"), (policy, "simulate")):
        real = getattr(module, name)

        def spy(o, *a, _real=real, **k):
            seen.append((step["now"], o is obj or k.get("frame") is obj))
            return _real(o, *a, **k)

        monkeypatch.setattr(module, name, spy)
    p = ag.plan(
        obj,
        "beat",
        candidates=16,
        seed=1,
        refine=1,
        robust_check=2,
        uses=60,
        progress=lambda s: step.update(now=s),
    )
    assert {s for s, _ in seen} >= {"predict", "simulate"}
    assert not [s for s, true in seen if true and s != "simulate"]
    assert [s for s, true in seen if true] == ["simulate"]
    # a task that reads the use point: each grasp took its best use point on the surface
    assert p.use_point is not None and np.isfinite(p.use_point).all()
    assert "each grasp with its best of" in p.rule and "beat probability" in p.rule
    # ranked by the task probability on the surface, the robust check moved one of the
    # first two to the front
    ranked = np.lexsort((-np.nan_to_num(p.fused_epsilon), -p.fused_score, ~p.fused_viable))
    assert set(p.order[:2]) == set(ranked[:2])
    assert p.order[2:].tolist() == [i for i in ranked if i not in p.order[:2]]
    assert np.isfinite(p.fused_robust_score[p.order[:2]]).all()
    # the truth: the task probability on the true object, feasible when p >= 0.5
    np.testing.assert_array_equal(p.feasible, p.true_score >= 0.5)
    doc = p.summary()
    json.dumps(doc)
    assert doc["pose_error"] == [0.01, 5.0]
    assert doc["chosen"]["use_part"] is not None and doc["chosen"]["contact_parts"] is not None
    assert doc["chosen"]["feasible"] == bool(p.true_score[p.chosen] >= 0.5)
    # the true use point: the true surface's closest to the fused one (a few mm away)
    true_u = np.asarray(doc["chosen"]["use_point"])
    assert np.linalg.norm(true_u - p.use_point[p.chosen]) < 0.01


def test_plan_aims_its_views_from_a_pose_estimate(box_mesh):
    from affordgrasp.vision.camera import pose_error_transform

    exact = ag.plan(str(box_mesh), "pick", candidates=6, seed=5, pose_error=None, refine=0)
    off = ag.plan(str(box_mesh), "pick", candidates=6, seed=5, refine=0)
    assert exact.pose_error is None and off.pose_error == (0.01, 5.0)
    assert exact.summary()["pose_error"] is None
    np.testing.assert_array_equal(exact.p0, off.p0)  # the same candidates, other views
    assert not np.array_equal(exact.fused_epsilon, off.fused_epsilon)
    for bad in ((-0.01, 5.0), (0.01,), "near", "15", 3, (float("nan"), 1.0)):
        with pytest.raises(InputError, match="pose_error"):
            ag.plan(str(box_mesh), "pick", candidates=2, pose_error=bad)
    # the error's sizes are exact, its directions drawn from the seed
    c = np.array([0.1, -0.2, 0.3])
    t = pose_error_transform(c, 0.01, 5.0, seed=7)
    angle = np.degrees(np.arccos((np.trace(t[:3, :3]) - 1) / 2))
    assert angle == pytest.approx(5.0)
    np.testing.assert_allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.linalg.norm(t[:3, :3] @ c + t[:3, 3] - c) == pytest.approx(0.01)
    np.testing.assert_array_equal(t, pose_error_transform(c, 0.01, 5.0, seed=7))
    assert not np.allclose(t, pose_error_transform(c, 0.01, 5.0, seed=8))
    np.testing.assert_allclose(pose_error_transform(c, 0.0, 0.0, seed=7), np.eye(4), atol=1e-15)
