"""Brute force over grasps × use points (search/pairs.py): exact, and the default mode finds
beat, cut and pick grasps on small seeded samples."""

from dataclasses import replace

import numpy as np
import pytest

from affordgrasp.grasp.pregrasp import sample_inputs
from affordgrasp.objects import load_object
from affordgrasp.pipeline import evaluate_inputs, evaluate_samples
from affordgrasp.search.pairs import (
    PairSearchSettings,
    best_pairs,
    best_use_per_grasp,
    optimize_pairs,
    pair_scores,
)
from affordgrasp.search.use_points import UsePoints

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
    scores = pair_scores("hammer", table, uses, "beat-rules", "no-robustness", screen=False)
    rng = np.random.default_rng(0)
    pick = rng.choice(len(scores["grasp"]), size=40, replace=False)
    p0 = np.asarray(table.column("p0").to_pylist())[scores["grasp"][pick]]
    rows = evaluate_inputs("hammer", p0, d[scores["use"][pick]]).table
    for name in CHECKED:
        np.testing.assert_allclose(
            scores[name][pick], rows.column(name).to_numpy(), rtol=1e-9, atol=1e-12, err_msg=name
        )


@pytest.mark.parametrize(
    "obj, task, seed",
    [
        ("hammer", "beat-rules", 2),
        ("axe:1", "beat-rules", 0),
        ("knife", "cut-rules", 0),
        ("dagger", "cut-rules", 0),
        ("mug", "pick", 0),
    ],
)
def test_default_mode_finds_the_task_grasps(obj, task, seed):
    # 400 grasps x 3000 use points: a few robust grasps, a few use points on the spot. Beat's
    # striking face is a smaller spot than this search reaches (no candidate on the hammer
    # in 12 seeds), so its three striking-surface tests are off here (tests/tasks checks
    # them); every other default threshold applies.
    off = (
        {"tau_depth": 0.0, "tau_relief": np.inf, "tau_swing": -np.inf}
        if task == "beat-rules"
        else {}
    )
    settings = PairSearchSettings(task, thresholds=off, grasps=400, uses=3000, seed=seed, top=3)
    result = best_pairs(obj, settings)
    values = result.table.column("value").to_numpy()
    assert result.candidates >= 1 and len(values) >= 1
    assert np.all(np.isfinite(values)) and np.all(np.diff(values) <= 1e-12)
    eps = result.table.column("epsilon_hand" if task != "pick" else "epsilon").to_numpy()
    if task != "pick":
        assert np.all(eps >= 0.014)
    if task == "cut-rules":
        assert np.all(result.table.column("use_wedge_angle").to_numpy() <= np.radians(55))
        assert np.all(result.table.column("use_clearance").to_numpy() >= 0.035)


def test_optimizer_over_grasps_with_their_best_use_point():
    settings = PairSearchSettings(
        "cut-rules",
        thresholds={"tau_thick": 0.0, "tau_width": 0.0, "tau_reach": np.inf},
        budget=200,
        uses=1500,
        seed=0,
        top=5,
        population=50,
    )  # the search, not the thresholds: a 200-grasp search rarely holds the handle only
    found = optimize_pairs("meat_cleaver", settings)
    values = found.table.column("value").to_numpy()
    assert found.grasps == 200 and found.candidates >= 1
    assert 1 <= len(values) <= 5 and np.all(np.isfinite(values))
    assert np.all(np.diff(values) <= 1e-12)
    # rows are distinct (grasp, use point) pairs
    keys = {
        (tuple(p), tuple(d))
        for p, d in zip(
            found.table.column("p0").to_pylist(),
            found.table.column("use_dir").to_pylist(),
            strict=True,
        )
    }
    assert len(keys) == len(values)


def test_best_pairs_per_grasp_ranks_each_grasp_once_with_its_best_use():
    # with the materials (the steel blade's centre of mass) this small search finds several
    # cut pairs; at unit density it finds none
    cleaver = load_object("meat_cleaver", materials=True)
    table = evaluate_samples(cleaver, 120, seed=0).table
    settings = PairSearchSettings(
        "cut-rules",
        thresholds={"tau_thick": 0.0, "tau_width": 0.0, "tau_reach": np.inf},
        grasps=120,
        uses=400,
        top=4,
    )
    pairs = best_pairs(cleaver, settings, grasp_table=table)
    grasps = best_pairs(cleaver, replace(settings, per_grasp=True), grasp_table=table)
    assert grasps.candidates == pairs.candidates >= 4
    p0 = [tuple(p) for p in grasps.table.column("p0").to_pylist()]
    assert len(set(p0)) == len(p0) >= 2
    values = grasps.table.column("value").to_numpy()
    assert np.all(np.diff(values) <= 1e-12)
    assert values[0] == pytest.approx(pairs.table.column("value").to_numpy()[0], rel=1e-9)
    # the best pair of each listed grasp: no other use point of it scores higher
    scores = pair_scores(
        cleaver,
        table,
        UsePoints.sample(cleaver, 400, 1),
        "cut-rules",
        tau_thick=0.0,
        tau_width=0.0,
        tau_reach=np.inf,
    )
    best, _ = best_use_per_grasp(scores, 120)
    np.testing.assert_allclose(np.sort(best[np.isfinite(best)])[::-1][: len(values)], values)


def test_best_use_per_grasp():
    scores = {
        "grasp": np.array([0, 0, 1, 2, 2]),
        "use": np.array([3, 1, 0, 5, 4]),
        "value": np.array([1.0, 2.0, -np.inf, 0.5, 0.5]),
    }
    best, use = best_use_per_grasp(scores, 4)
    np.testing.assert_array_equal(best, [2.0, -np.inf, 0.5, -np.inf])
    np.testing.assert_array_equal(use, [1, -1, 4, -1])  # ties: the lowest use index


def test_optimize_command_finds_a_default_mode_cut_with_use_points(capsys):
    import json

    from affordgrasp.cli import main

    argv = [
        "optimize",
        "meat_cleaver",
        "--task",
        "cut-rules",
        "--budget",
        "100",
        "--population",
        "50",
    ]
    argv += ["--threshold", "tau_thick=0", "--threshold", "tau_width=0"]
    argv += ["--threshold", "tau_reach=inf"]  # a 100-sample
    # search rarely holds the handle only
    code = main([*argv, "--uses", "1000", "--workers", "1", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0
    found = [doc[m] for m in ("cem", "random") if doc[m] is not None]
    assert found, "neither search found a default-mode cut"
    for f in found:
        assert np.isfinite(f["value"]) and f["row"]["epsilon"] >= 0.014
        assert f["row"]["use_wedge_angle"] <= np.radians(55)
        assert f["row"]["use_clearance"] >= 0.035


def test_searches_without_the_volume_score_the_same_grasps(hammer_grasps):
    # the ε-only path (volume=False) changes gws_volume only: every score of the search is
    # the same, so best_pairs and optimize_pairs may skip the 6-D hull
    p0 = np.asarray(hammer_grasps.table.column("p0").to_pylist())[:60]
    d = np.asarray(hammer_grasps.table.column("use_dir").to_pylist())[:60]
    full = evaluate_inputs("hammer", p0, d, volume=True).table
    fast = evaluate_inputs("hammer", p0, d, volume=False).table
    closure = full.column("epsilon").to_numpy() > 0
    assert closure.any()
    assert np.all(full.column("gws_volume").to_numpy()[closure] > 0)
    assert fast.column("gws_volume").null_count == fast.num_rows  # not computed: null
    for name in CHECKED:
        np.testing.assert_allclose(  # ε: the same facets, summed in another order
            fast.column(name).to_numpy(),
            full.column(name).to_numpy(),
            rtol=1e-12,
            atol=1e-15,
            err_msg=name,
        )
    again = evaluate_samples("hammer", 60, seed=3, volume=False).table
    assert again.column("epsilon").to_pylist() == fast.column("epsilon").to_pylist()


def test_pair_scores_in_blocks_equal_one_block(hammer_grasps, monkeypatch):
    import affordgrasp.search.pairs as pairs

    _, d = sample_inputs(5, 0, 400)
    uses = UsePoints.of("hammer", d)
    whole = pair_scores("hammer", hammer_grasps.table, uses, "beat-paper", "no-robustness")
    monkeypatch.setattr(pairs, "_BLOCK_PAIRS", 1000)  # 2 grasps x 400 uses per block
    blocks = pair_scores("hammer", hammer_grasps.table, uses, "beat-paper", "no-robustness")
    assert len(whole["grasp"]) > 0 and whole.keys() == blocks.keys()
    for key in whole:
        np.testing.assert_array_equal(blocks[key], whole[key], err_msg=key)


def test_optimizer_restarts_share_the_budget_and_repeat():
    settings = PairSearchSettings(
        "pick", budget=96, uses=50, seed=0, top=5, population=16, restarts=3
    )
    found = optimize_pairs("hammer", settings)
    again = optimize_pairs("hammer", settings)
    values = found.table.column("value").to_numpy()
    assert found.grasps == 96 and found.candidates >= 1
    assert 1 <= len(values) <= 5 and np.all(np.isfinite(values))
    assert np.all(np.diff(values) <= 1e-12)
    assert again.table.column("p0").to_pylist() == found.table.column("p0").to_pylist()


@pytest.mark.parametrize("budget, restarts", [(96, 0), (96, 2.5), (2, 3), (96, True)])
def test_optimizer_refuses_bad_restarts(budget, restarts):
    from affordgrasp.errors import InputError

    with pytest.raises(InputError, match="restarts|budget"):
        optimize_pairs(
            "hammer", PairSearchSettings("pick", budget=budget, uses=10, restarts=restarts)
        )


def test_refine_continues_the_best_restart_within_the_budget(monkeypatch):
    import affordgrasp.search.cem as optimize_module

    calls = []
    real = optimize_module.cem_maximize

    def spy(objective, **kwargs):
        trace = real(objective, **kwargs)
        calls.append((kwargs, trace))
        return trace

    monkeypatch.setattr(optimize_module, "cem_maximize", spy)
    settings = PairSearchSettings(
        "pick", budget=96, uses=50, seed=0, top=5, population=16, restarts=3, refine=0.25
    )
    found = optimize_pairs("hammer", settings)
    assert found.grasps == 96
    runs, last = calls[:3], calls[3]
    assert [c[0]["budget"] for c in calls] == [24, 24, 24, 24]
    assert len(calls) == 4 and runs[0][0].get("state") is None
    # the continued run is the restart with the largest F_T (ties: the first)
    bests = [trace.state.best for _, trace in runs]
    chosen = runs[int(np.argmax(bests))][1].state
    given = last[0]["state"]
    # ... its elites carried on, its distribution centred on its best point, narrow
    np.testing.assert_array_equal(given.elite_v, chosen.elite_v)
    np.testing.assert_array_equal(given.mean, chosen.elite_x[0])
    np.testing.assert_allclose(given.std, 0.01 * (optimize_module.HIGH - optimize_module.LOW))
    again = optimize_pairs("hammer", settings)
    assert again.table.column("p0").to_pylist() == found.table.column("p0").to_pylist()


@pytest.mark.parametrize("refine", [-0.1, 1.0, True, "half"])
def test_optimizer_refuses_bad_refine(refine):
    from affordgrasp.errors import InputError

    with pytest.raises(InputError, match="refine"):
        optimize_pairs(
            "hammer", PairSearchSettings("pick", budget=96, uses=10, restarts=2, refine=refine)
        )


def test_optimizer_refuses_a_refine_share_that_rounds_to_nothing():
    from affordgrasp.errors import InputError

    with pytest.raises(InputError, match="rounds to no simulation"):
        optimize_pairs(
            "hammer", PairSearchSettings("pick", budget=96, uses=10, restarts=2, refine=0.001)
        )


def test_pair_searches_simulate_the_hand_they_are_given():
    from affordgrasp import tasks
    from affordgrasp.hands import get_hand

    # finite on every grasp: the searches rank rows whatever the hand
    tasks.register_task("inertia-only", lambda m, t: m["inertia"], requires=("inertia",))
    jaw = get_hand("parallel_jaw")
    try:
        searches = (
            best_pairs(
                "hammer",
                PairSearchSettings("inertia-only", grasps=40, uses=20, top=2, hand="parallel_jaw"),
            ),
            optimize_pairs(
                "hammer",
                PairSearchSettings(
                    "inertia-only", budget=32, uses=20, top=2, population=16, hand=jaw
                ),
            ),
        )
    finally:
        tasks.unregister_task("inertia-only")
    for found in searches:
        assert found.table.num_rows == 2
        assert set(found.table.column("hand").to_pylist()) == {"parallel_jaw"}
        joints = found.table.column("joints").to_pylist()
        assert {len(j) for j in joints} == {len(jaw.dofs)} != {len(get_hand("barrett").dofs)}
        # the re-simulated rows score what the search scored
        np.testing.assert_allclose(
            found.table.column("value").to_numpy(), found.table.column("inertia").to_numpy()
        )
