"""Guidance of searches over grasps (search/guidance.py): the swing's alignment with use points."""

import numpy as np

from affordgrasp import tasks
from affordgrasp.pairs import UsePoints
from affordgrasp.search.guidance import swing_alignment


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
        use_depth=np.full(n, depth),
        use_relief=np.full(n, relief),
    )


def test_a_swing_that_meets_a_striking_face_square_scores_one():
    beat = tasks.get_task("beat")
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
    beat = tasks.get_task("beat")
    wrist, axis = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    side_face = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]], depth=0.025)  # too shallow
    assert swing_alignment(beat, "default", {}, side_face, wrist, axis)[0] == 0.0
    relaxed = swing_alignment(beat, "default", {"tau_depth": 0.0}, side_face, wrist, axis)
    assert relaxed[0] == 1.0
    face = _uses([[0.3, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    assert swing_alignment(tasks.get_task("cut"), "default", {}, face, wrist, axis)[0] == 0.0
    assert (
        swing_alignment(tasks.get_task("beat-paper"), "default", {}, side_face, wrist, axis)[0]
        == 1.0
    )  # the paper's beat has no test of the use point
