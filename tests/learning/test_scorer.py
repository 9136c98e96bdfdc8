"""The learned scorer: its inputs in the hand's frame, its shipped network, plan --model learned."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("skimage")  # the fusion's marching cubes

import affordgrasp as ag  # noqa: E402
from affordgrasp.cli import main  # noqa: E402
from affordgrasp.errors import InputError  # noqa: E402
from affordgrasp.learning.scorer import (  # noqa: E402
    DEPTH_M,
    FEATURES,
    GRID,
    LATERAL_M,
    N_FEATURES,
    POINT_SCALE,
    POINTS,
    hand_frame_inputs,
)


def _pose(rotation: np.ndarray, origin) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = origin
    return t


def _rotation(seed: int) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.random(random_state=seed).as_matrix()


def test_inputs_of_a_known_cloud():
    """A hand at the origin looking along +z at a plate of points 0.2 m away: the points
    it sees, counted in the grid's first layer, shifted to the plate, and the features."""
    xs = np.linspace(-0.195, 0.195, 40)  # none on the box's edge
    plate = np.array([[x, y, 0.2] for x in xs for y in xs])
    behind = np.array([[0.0, 0.0, -0.1], [0.0, 0.0, 0.5], [0.3, 0.0, 0.2]])
    cloud = np.concatenate([plate, behind])
    grid, features, points = hand_frame_inputs(
        cloud, np.eye(4)[None], np.array([0.25]), with_points=True
    )
    assert grid.shape == (1, int(np.prod(GRID))) and features.shape == (1, N_FEATURES)
    seen = np.all(np.abs(plate[:, :2]) <= LATERAL_M, axis=1)
    # every point seen lies in the first layer of depth, in the cell of its x and y
    cells = grid[0].reshape(GRID)
    assert cells[:, :, 1:].sum() == 0
    gx, gy, _ = GRID
    ix = ((plate[seen, 0] + LATERAL_M) / (2 * LATERAL_M) * gx).astype(int)
    iy = ((plate[seen, 1] + LATERAL_M) / (2 * LATERAL_M) * gy).astype(int)
    expected = np.zeros((gx, gy))
    np.add.at(expected, (ix, iy), 1.0 / len(cloud))
    np.testing.assert_allclose(cells[:, :, 0], expected, atol=1e-7)
    assert (
        dict(zip(FEATURES, features[0].tolist(), strict=True))
        == pytest.approx(
            {
                "spread": 0.25,
                "first_dm": 2.0,  # 0.2 m
                "share": seen.sum() / len(cloud),
                "palm_share": np.sum(np.hypot(*plate[seen, :2].T) <= 0.04) / seen.sum(),
                "empty": 0.0,
            },
            rel=1e-5,
        )
    )
    # the points: the first POINTS of the cloud's order in the volume, at z = 0
    p = points[0] / POINT_SCALE
    np.testing.assert_allclose(p[:, 2], 0.0, atol=1e-6)
    keep = np.flatnonzero(
        np.all(np.abs(cloud[:, :2]) <= LATERAL_M, axis=1)
        & (cloud[:, 2] > 0)
        & (cloud[:, 2] - 0.2 <= DEPTH_M)
    )[:POINTS]
    np.testing.assert_allclose(p[:, :2], cloud[keep, :2], atol=1e-6)


def test_an_empty_volume_gives_zero_inputs_and_says_so():
    cloud = np.array([[1.0, 1.0, 1.0], [0.0, 0.0, -0.5]])
    grid, features, points = hand_frame_inputs(
        cloud, np.eye(4)[None], np.array([0.5]), with_points=True
    )
    assert not grid.any() and not points.any()
    assert features[0, FEATURES.index("empty")] == 1.0
    assert features[0, FEATURES.index("share")] == 0.0


def test_fewer_points_than_the_input_holds_are_cycled():
    cloud = np.array([[0.0, 0.0, 0.1], [0.01, 0.0, 0.12], [0.0, 0.02, 0.15]])
    _, _, points = hand_frame_inputs(cloud, np.eye(4)[None], np.array([0.0]), with_points=True)
    p = points[0] / POINT_SCALE
    np.testing.assert_allclose(p[:3, 2], [0.0, 0.02, 0.05], atol=1e-6)
    np.testing.assert_allclose(p[3:6], p[:3])


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5))
def test_moving_the_cloud_and_the_hands_together_changes_no_input(seed, dx, dz):
    """The inputs live in the hand's frame: one rigid motion of the cloud and of every start
    pose changes nothing."""
    rng = np.random.default_rng(seed)
    cloud = rng.normal(scale=0.06, size=(500, 3))
    starts = np.stack(
        [_pose(_rotation(seed + i), -0.2 * _rotation(seed + i)[:, 2]) for i in range(4)]
    )
    spread = rng.uniform(size=4)
    motion = _pose(_rotation(seed + 99), [dx, 0.1, dz])
    moved_cloud = cloud @ motion[:3, :3].T + motion[:3, 3]
    moved_starts = motion[None] @ starts
    a = hand_frame_inputs(cloud, starts, spread, with_points=True)
    b = hand_frame_inputs(moved_cloud, moved_starts, spread, with_points=True)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_allclose(x, y, atol=2e-5)


def test_the_shipped_scorer_reads_its_card_and_scores_in_milliseconds():
    import time

    from affordgrasp.grasp.pregrasp import sample_inputs
    from affordgrasp.learning.plan import OFFSET_RANGE, candidate_views
    from affordgrasp.learning.scorer import COLUMNS, load_scorer, score_candidates

    model = load_scorer()
    card = model.card
    assert card["input"] == "hand-cloud" and tuple(model.columns) == COLUMNS
    assert len(card["fit_objects"]) >= 1000
    assert not set(card["fit_objects"]) & set(card["validation_objects"])
    assert not set(card["fit_objects"]) & set(card["test_objects"])
    obj = ag.load_object("tumbler:2")
    p0, _ = sample_inputs(0, 0, 64)
    p0[:, 3:5] *= OFFSET_RANGE
    fused = candidate_views(obj, p0).fuse()
    prob = score_candidates(model, fused, p0)
    assert prob.shape == (64,) and np.all((prob >= 0) & (prob <= 1)) and prob.std() > 0
    t0 = time.process_time()
    again = score_candidates(model, fused, p0)
    assert time.process_time() - t0 < 0.5  # about 10 ms; generous for a loaded machine
    np.testing.assert_array_equal(prob, again)


def test_plan_with_the_learned_scorer_reads_only_the_fused_views(monkeypatch, capsys):
    import affordgrasp.grasp.policy as policy
    import affordgrasp.pipeline as pipeline

    obj = ag.load_object("mug:2")
    step = {"now": None}
    seen = []
    for module, name in ((pipeline, "evaluate_inputs"), (policy, "simulate")):
        real = getattr(module, name)

        def spy(o, *a, _real=real, **k):
            seen.append((step["now"], o is obj or k.get("frame") is obj, len(a[0])))
            return _real(o, *a, **k)

        monkeypatch.setattr(module, name, spy)
    p = ag.plan(obj, "pick", candidates=32, seed=2, models="learned", verify=0,
                progress=lambda s: step.update(now=s))  # fmt: skip
    # nothing is simulated before the check: the scorer reads the fused cloud
    assert seen and {s for s, _, _ in seen} == {"simulate"}
    assert p.chosen == int(np.argmax(p.probability)) and "learned scorer" in p.rule
    assert p.summary()["rule"] == p.rule
    # verified: its first 5 simulated on the fused surface (never the object), the viable
    # one with the widest ε there first, the rest in the scorer's order
    seen.clear()
    q = ag.plan(obj, "pick", candidates=32, seed=2, models="learned", verify=5,
                progress=lambda s: step.update(now=s))  # fmt: skip
    assert [(s, true) for s, true, _ in seen if s == "predict"] == [("predict", False)] * len(
        [s for s, _, _ in seen if s == "predict"]
    )
    assert 5 in [n for s, _, n in seen if s == "predict"]
    np.testing.assert_array_equal(q.probability, p.probability)
    assert set(q.order[:5]) == set(p.order[:5]) and q.order[5:].tolist() == p.order[5:].tolist()
    assert "of its first 5" in q.rule
    rc = main(["plan", "mug:2", "--candidates", "16", "--model", "learned", "--json"])
    assert rc == 0, capsys.readouterr().err
    assert json.loads(capsys.readouterr().out)["candidates"] == 16


def test_the_learned_scorer_refuses_tasks_with_a_use_point(capsys, tmp_path):
    with pytest.raises(InputError, match="use point"):
        ag.plan("hammer:2", "beat", candidates=4, models="learned")
    assert main(["plan", "mug:2", "--model", "learned", "--refine", "2"]) == 2
    assert "--model views" in capsys.readouterr().err
    assert main(["plan", "mug:2", "--verify", "2"]) == 2
    assert "--model learned" in capsys.readouterr().err
    with pytest.raises(InputError, match="verify"):
        ag.plan("mug:2", "pick", candidates=4, models="learned", verify=-1)
    # a file that is not a scorer: a network's, a task probability's
    from affordgrasp.learning.api import pretrained_path
    from affordgrasp.learning.scorer import load_scorer
    from affordgrasp.tasks.probability import task_model

    with pytest.raises(InputError, match="not a scorer"):
        load_scorer(pretrained_path("classifier"))
    path = tmp_path / "pick.json"
    path.write_text(json.dumps(task_model("pick").to_dict()))
    with pytest.raises(InputError, match="not a scorer of this version"):
        load_scorer(path)
