"""Brute force over grasps × use points (pairs.py): exact, and the default mode finds
beat, cut and pick grasps on small seeded samples."""

import numpy as np
import pytest

from affordgrasp.evaluate import evaluate, evaluate_samples
from affordgrasp.grasp.pregrasp import sample_inputs
from affordgrasp.pairs import UsePoints, best_pairs, pair_scores

CHECKED = (
    "epsilon",
    "inertia",
    *(f"hold_effort_{s}" for s in ("px", "nx", "py", "ny", "pz", "nz")),
    "impact_effort",
    "discharge",
    "use_force",
    "use_edge",
    "use_edge_angle",
)


@pytest.fixture(scope="module")
def hammer_grasps():
    return evaluate_samples("hammer", 150, seed=3)


def test_pair_metrics_equal_the_rows_they_stand_for(hammer_grasps):
    table = hammer_grasps.table
    _, d = sample_inputs(11, 0, 25)
    uses = UsePoints.of("hammer", d)
    scores = pair_scores("hammer", table, uses, "beat", "no-robustness", screen=False)
    rng = np.random.default_rng(0)
    pick = rng.choice(len(scores["grasp"]), size=40, replace=False)
    p0 = np.asarray(table.column("p0").to_pylist())[scores["grasp"][pick]]
    rows, _ = evaluate("hammer", p0, d[scores["use"][pick]])
    for name in CHECKED:
        np.testing.assert_allclose(
            scores[name][pick], rows.column(name).to_numpy(), rtol=1e-9, atol=1e-12, err_msg=name
        )


@pytest.mark.parametrize(
    "obj, task, seed",
    [
        ("hammer", "beat", 1),
        ("axe", "beat", 0),
        ("knife", "cut", 0),
        ("dagger", "cut", 0),
        ("mug", "pick", 0),
    ],
)
def test_default_mode_finds_the_task_grasps(obj, task, seed):
    # 400 grasps x 3000 use points: a few robust grasps, a few use points on the spot
    result = best_pairs(obj, task, grasps=400, uses=3000, seed=seed, top=3, mode="default")
    values = result.table.column("value").to_numpy()
    assert result.candidates >= 1 and len(values) >= 1
    assert np.all(np.isfinite(values)) and np.all(np.diff(values) <= 1e-12)
    eps = result.table.column("epsilon").to_numpy()
    if task != "pick":
        assert np.all(eps >= 0.014)
    if task == "cut":
        assert np.all(result.table.column("use_edge_angle").to_numpy() <= np.radians(45))
