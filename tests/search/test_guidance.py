"""Guidance of searches over grasps (search/guidance.py): the swing's alignment with use points."""

import numpy as np
import pytest

from affordgrasp import tasks
from affordgrasp.search.guidance import swing_alignment
from affordgrasp.search.use_points import UsePoints


def _uses(points, normals, depth=0.09, relief=1e-4, wedge=np.pi):
    n = len(points)
    return UsePoints(
        use_dir=np.zeros((n, 2)),
        point=np.asarray(points, float),
        normal=np.asarray(normals, float),
        triangle=np.arange(n),
        use_edge=np.zeros(n),
        use_edge_angle=np.full(n, np.pi),
        use_wedge_angle=np.full(n, wedge),
        use_wedge_angle_fine=np.full(n, wedge),
        use_edge_span=np.full(n, 1.0 / 3.0),
        use_edge_thickness=np.zeros(n),
        use_depth=np.full(n, depth),
        use_relief=np.full(n, relief),
    )


def test_a_swing_that_meets_a_striking_face_square_scores_one():
    beat = tasks.get_task("beat-rules")
    # a face at x = 0.3 m looking along +y; the hand at the origin
    uses = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    wrist = np.zeros((3, 3))
    # +z swings the face along +y (square); -z swings it backwards; +x does not move it
    axes = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    got = swing_alignment(beat, "default", {}, uses, wrist, axes)
    np.testing.assert_allclose(got, [1.0, 0.0, 0.0], atol=1e-12)
    tilted = np.array([[0.0, np.sin(0.5), np.cos(0.5)]])  # the axis tilted by 0.5 rad
    assert 0.0 < swing_alignment(beat, "default", {}, uses, wrist[:1], tilted)[0] < 1.0


def test_only_candidates_of_the_task_count_and_tasks_without_delta_score_zero():
    beat = tasks.get_task("beat-rules")
    wrist, axis = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    side_face = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]], depth=0.025)  # too shallow
    assert swing_alignment(beat, "default", {}, side_face, wrist, axis)[0] == 0.0
    relaxed = swing_alignment(beat, "default", {"tau_depth": 0.0}, side_face, wrist, axis)
    assert relaxed[0] == 1.0
    face = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    assert swing_alignment(tasks.get_task("cut-rules"), "default", {}, face, wrist, axis)[0] == 0.0
    assert (
        swing_alignment(tasks.get_task("beat-paper"), "default", {}, side_face, wrist, axis)[0]
        == 1.0
    )  # the paper's beat has no test of the use point


def test_task_tests_read_the_task_thresholds_and_leave_out_infinite_ones():
    from affordgrasp.search.guidance import task_tests

    cut = tasks.get_task("cut-rules")
    got = {t.threshold: (t.column, t.sense) for t in task_tests(cut)}
    assert got["tau_eps"] == ("epsilon_hand", 1)  # the ε cut gates on
    assert got["tau_wedge"] == ("use_wedge_angle", -1)
    assert got["tau_reach"] == ("contact_reach", -1)
    assert set(got) == set(cut.thresholds)
    loose = task_tests(cut, "no-robustness")
    assert "tau_eps" not in {t.threshold for t in loose}  # τ_ε = -inf: always passes
    assert task_tests(tasks.get_task("cut-rules"), overrides={"tau_wedge": 0.5})[1].tau == 0.5
    assert task_tests(tasks.get_task("pick")) == []


def test_closeness_is_a_hinge_at_the_threshold():
    from affordgrasp.search.guidance import ThresholdTest, threshold_closeness

    at_least = ThresholdTest("tau_eps", "epsilon", +1, 0.02)
    at_most = ThresholdTest("tau_wedge", "use_wedge_angle", -1, 1.0)
    got = threshold_closeness(
        [at_least, at_most],
        {
            "epsilon": np.array([0.03, 0.02, 0.01, 0.0, np.nan]),
            "use_wedge_angle": np.array([0.5, 1.0, 1.5, 3.0, 1.0]),
        },
    )
    np.testing.assert_allclose(got[:, 0], [1.0, 1.0, 0.5, 0.0, 0.0])
    np.testing.assert_allclose(got[:, 1], [1.0, 1.0, 0.5, 0.0, 1.0])


@pytest.fixture(scope="module")
def hammer_rows():
    from affordgrasp.pipeline import evaluate_samples

    return evaluate_samples("hammer", 40, seed=3, volume=False).table


def test_threshold_guidance_ranks_a_grasp_closer_to_passing_higher(hammer_rows):
    import pyarrow as pa

    from affordgrasp.objects import load_object
    from affordgrasp.search.guidance import threshold_guidance

    obj = load_object("hammer")
    cut = tasks.get_task("cut-rules")
    tau = cut.thresholds_for("default")
    touched = np.flatnonzero(hammer_rows.column("n_contacts").to_numpy() > 0)
    untouched = np.flatnonzero(hammer_rows.column("n_contacts").to_numpy() == 0)
    i = int(touched[0])
    rows = hammer_rows.take([i] * 4 + [int(untouched[0])] * (len(untouched) > 0))

    def put(table, name, values):
        j = table.schema.get_field_index(name)
        return table.set_column(j, name, pa.array(np.asarray(values, dtype=np.float64)))

    e = tau["tau_eps"]
    w = tau["tau_width"]
    k = rows.num_rows
    rows = put(rows, "epsilon_hand", [e, e / 2, e, 0.0, *[e] * (k - 4)][:k])
    rows = put(rows, "contact_width", [w, w, w / 4, w, *[w] * (k - 4)][:k])
    rows = put(rows, "contact_thickness", np.full(k, 1.0))
    # an edge point 0.3 m from the contacts: the use tests and the clearance pass
    uses = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]], wedge=0.5)
    g = threshold_guidance(obj, rows, cut, "default", {}, uses)
    assert g[0] > g[1] > g[3]  # ε at τ, at τ/2, at 0
    assert g[0] > g[2]  # a finger on a part a quarter as wide as the test asks
    np.testing.assert_allclose(g[0] - g[1], 0.5)  # half of the ε hinge
    if k > 4:
        assert g[4] == 0.0  # no contact, no guidance
    user = tasks.make_task("plain", lambda m, t: m["epsilon"], requires=("epsilon",))
    assert threshold_guidance(obj, rows, user, "default", {}, uses) is None


def test_use_only_passes_keeps_the_edge_points_of_cut():
    from affordgrasp.search.guidance import use_only_passes

    cut = tasks.get_task("cut-rules")
    edge = _uses([[0.1, 0.0, 0.0]], [[0.0, 1.0, 0.0]], wedge=0.5)
    flat = _uses([[0.1, 0.0, 0.0]], [[0.0, 1.0, 0.0]], wedge=np.pi)
    assert use_only_passes(cut, "default", {}, edge).tolist() == [True]
    assert use_only_passes(cut, "default", {}, flat).tolist() == [False]
    assert use_only_passes(cut, "default", {"tau_wedge": 4.0, "tau_wedge_fine": 4.0}, flat)[0]
