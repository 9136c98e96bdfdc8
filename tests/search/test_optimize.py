"""The cross-entropy optimiser: respects −∞, and beats random sampling where it should."""

from __future__ import annotations

import json

import numpy as np
import pytest

from affordgrasp import tasks
from affordgrasp.cli import main
from affordgrasp.errors import InputError
from affordgrasp.search.cem import HIGH, LOW, PERIODIC, cem_maximize, uniform_inputs
from affordgrasp.search.optimize import optimize

TARGET = np.array([0.97, 0.3, -0.98, 0.1, -0.2, 0.7, 0.5, -0.4])


def narrow_peak(x: np.ndarray) -> np.ndarray:
    """A peak near the azimuth seam, −inf outside a small ball (a failed threshold)."""
    d = x - TARGET
    d[:, PERIODIC] = (d[:, PERIODIC] + 1) % 2 - 1
    r2 = (d**2).sum(axis=1)
    return np.where(r2 < 0.8, -r2, -np.inf)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cem_beats_random_sampling_on_a_narrow_peak(seed):
    trace = cem_maximize(narrow_peak, budget=1500, seed=seed)
    random = narrow_peak(uniform_inputs(np.random.default_rng(seed), 1500))
    assert trace.values.max() > random.max()
    assert trace.values.max() > -0.1  # near the optimum 0; random sampling gets about -0.2
    assert np.all((trace.x >= LOW) & (trace.x <= HIGH))
    assert len(trace.x) == 1500


def test_minus_infinity_everywhere_is_not_an_error():
    trace = cem_maximize(lambda x: np.full(len(x), -np.inf), budget=100, seed=0)
    assert trace.best_index is None and len(trace.values) == 100
    nan = cem_maximize(lambda x: np.full(len(x), np.nan), budget=50, seed=0)
    assert nan.best_index is None and np.all(nan.values == -np.inf)


def test_guidance_leads_to_the_feasible_region():
    # Feasible only near TARGET; guidance says how close an infeasible point came.
    def needle(x):
        v = narrow_peak(x)
        return np.where(v > -0.15, v, -np.inf)  # about 1 in 10^7 of the box

    def objective(x):
        return needle(x), -np.abs(x - TARGET).sum(axis=1)

    guided = cem_maximize(objective, budget=600, seed=3, population=60)
    blind = cem_maximize(needle, budget=600, seed=3, population=60)
    assert np.sum(guided.values > -np.inf) > 10
    assert blind.best_index is None


@pytest.fixture(scope="module")
def wrist_inertia_task():
    # Smooth in the approach direction, finite for every grasp: a case for CEM.
    tasks.register_task(
        "wrist-inertia", lambda m, t: m["inertia"], requires=("inertia",), replace=True
    )
    yield "wrist-inertia"
    tasks.unregister_task("wrist-inertia")


def test_optimizer_beats_random_sampling_in_simulation(wrist_inertia_task, box_mesh):
    result = optimize(str(box_mesh), wrist_inertia_task, budget=240, seed=0, workers=1)
    assert result.cem is not None and result.random is not None
    assert result.cem.value > result.random.value
    assert result.cem_evaluations_to_match_random < 240
    # The winner's row is a real simulation of its inputs.
    from affordgrasp.pipeline import evaluate_inputs

    again = evaluate_inputs(str(box_mesh), result.cem.p0[None], result.cem.use_dir[None]).table
    assert again["inertia"][0].as_py() == pytest.approx(result.cem.value, rel=1e-12)


def test_optimize_cli_json(wrist_inertia_task, box_mesh, capsys):
    code = main(
        ["optimize", str(box_mesh), "--task", wrist_inertia_task, "--budget", "64", "--json"]
        + ["--workers", "1", "--seed", "1"]
    )
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["budget"] == 64 and doc["cem"]["value"] >= doc["random"]["value"]
    assert len(doc["cem"]["p0"]) == 6 and len(doc["cem"]["use_dir"]) == 2
    assert main(["optimize", str(box_mesh), "--task", "cut-rules", "--budget", "0"]) == 2


def test_optimize_uses_the_hand_object_it_is_given(wrist_inertia_task, box_mesh):
    # A custom hand that happens to be named like a built-in one: the optimiser must simulate
    # it, not look the name up again (it used to run the built-in Barrett instead).
    import dataclasses

    from affordgrasp.hands import get_hand

    custom = dataclasses.replace(get_hand("parallel_jaw"), name="barrett")
    result = optimize(str(box_mesh), wrist_inertia_task, budget=40, seed=0, workers=1, hand=custom)
    joints = result.cem.row["joints"] if result.cem is not None else result.random.row["joints"]
    assert len(joints) == len(custom.dofs) != len(get_hand("barrett").dofs)


def test_a_continued_run_keeps_its_elites_and_samples_its_distribution():
    first = cem_maximize(narrow_peak, budget=300, seed=0, population=30)
    state = first.state
    assert state is not None and state.mean is not None
    assert state.best == pytest.approx(first.values.max())
    more = cem_maximize(narrow_peak, budget=120, seed=5, population=30, state=state)
    # elites are kept until better points replace them: never worse than where it stood
    assert more.state.best >= state.best
    # the first generation is drawn around the run's mean (10 % of it uniform), not afresh
    d = more.x[:30] - state.mean
    d[:, PERIODIC] = (d[:, PERIODIC] + 1) % 2 - 1
    near = np.all(np.abs(d) <= 4 * state.std + 1e-12, axis=1)
    assert near.sum() >= 24
    fresh = cem_maximize(narrow_peak, budget=120, seed=5, population=30)
    assert more.values.max() >= fresh.values.max()


def test_a_carried_elite_stays_until_beaten():
    from affordgrasp.search.cem import CEMState

    x0 = np.full((2, 8), 0.5)
    state = CEMState(
        mean=np.zeros(8),
        std=np.full(8, 0.1),
        elite_x=x0,
        elite_v=np.array([10.0, 9.0]),  # better than anything the objective gives
        elite_g=np.full(2, np.nan),
    )
    trace = cem_maximize(narrow_peak, budget=60, seed=0, population=20, state=state)
    assert trace.state.best == 10.0 and len(trace.values) == 60
    with pytest.raises(InputError, match="initial|state"):
        cem_maximize(narrow_peak, budget=60, seed=0, initial=x0, state=state)


@pytest.mark.parametrize("uses", [0, 8])
def test_optimize_reports_rows_of_the_hand_it_searched_with(wrist_inertia_task, box_mesh, uses):
    # With use points the winner is simulated once more with its best use point: that
    # simulation used to fall back to the Barrett hand, so `optimize --hand parallel_jaw`
    # reported a Barrett row.
    from affordgrasp.hands import get_hand

    jaw = get_hand("parallel_jaw")
    result = optimize(
        str(box_mesh), wrist_inertia_task, budget=40, seed=0, workers=1, hand=jaw, uses=uses
    )
    for found in (result.cem, result.random):
        assert found is not None
        assert found.row["hand"] == "parallel_jaw"
        assert len(found.row["joints"]) == len(jaw.dofs) != len(get_hand("barrett").dofs)
        assert found.row["inertia"] == pytest.approx(found.value, rel=1e-12)


def test_optimize_cli_reports_a_parallel_jaw_row(wrist_inertia_task, box_mesh, capsys):
    args = ["optimize", str(box_mesh), "--task", wrist_inertia_task, "--hand", "parallel_jaw"]
    code = main(args + ["--budget", "40", "--uses", "8", "--workers", "1", "--json"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["cem"]["row"]["hand"] == "parallel_jaw"
    assert doc["random"]["row"]["hand"] == "parallel_jaw"
    # the task reads no column of the use point: the plain sample, and the JSON says so
    assert doc["use_points"]["kept"] == 8 and not doc["use_points"]["tested"]
    code = main(args + ["--budget", "40", "--uses", "8", "--passing-uses", "--workers", "1"])
    assert code == 0 and "use points: 8 drawn by area" in capsys.readouterr().out


def test_optimize_with_restarts_keeps_the_budget_and_the_baseline(wrist_inertia_task, box_mesh):
    from affordgrasp.pipeline import evaluate_samples

    result = optimize(
        str(box_mesh), wrist_inertia_task, budget=64, seed=2, workers=1, restarts=2, refine=0.25
    )
    assert len(result.cem_trace.values) == 64
    assert {g["run"] for g in result.cem_trace.generations} == {0, 1, 2}
    assert result.cem.value == pytest.approx(result.cem_trace.values.max(), rel=1e-12)
    assert result.cem.row["inertia"] == pytest.approx(result.cem.value, rel=1e-12)
    # the baseline is samples 0..63 of the seed, the runs' first generations reused in it
    plain = evaluate_samples(str(box_mesh), 64, seed=2).table["inertia"].to_numpy()
    np.testing.assert_allclose(result.random_values, plain, rtol=1e-12)
    with pytest.raises(InputError, match="restarts"):
        optimize(str(box_mesh), wrist_inertia_task, budget=64, restarts=0)


def test_optimize_simulates_the_object_with_its_materials(wrist_inertia_task):
    # A steel blade on a wooden handle: another centre of mass (so other use points) and
    # another inertia than at uniform density. The winner's row is the materials object's.
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_inputs

    steel = load_object("meat_cleaver", materials=True)
    result = optimize(steel, wrist_inertia_task, budget=40, seed=0, workers=1, uses=8)
    p0, d = result.cem.p0[None], result.cem.use_dir[None]
    again = evaluate_inputs(steel, p0, d).table.to_pylist()[0]
    uniform = evaluate_inputs(load_object("meat_cleaver"), p0, d).table.to_pylist()[0]
    for name in ("inertia", "use_edge_angle"):
        assert result.cem.row[name] == pytest.approx(again[name], rel=1e-12)
        assert result.cem.row[name] != pytest.approx(uniform[name], rel=1e-6)


def test_passing_use_points_pass_the_use_only_tests_and_repeat_per_seed():
    from affordgrasp.search.guidance import use_only_passes
    from affordgrasp.search.use_points import UsePoints, passing_use_points

    cut = tasks.get_task("cut-rules")
    uses, sampling = passing_use_points("knife", cut, 12, seed=5, max_draws=600)
    assert not sampling.fallback and sampling.tested
    assert len(uses.triangle) == sampling.kept == min(12, sampling.passing) > 0
    assert use_only_passes(cut, "default", {}, uses).all()
    # the same points, cast with every column: the edge tests pass on them too
    full = UsePoints.of("knife", uses.use_dir)
    np.testing.assert_array_equal(full.point, uses.point)
    assert np.all(full.use_wedge_angle <= cut.thresholds["tau_wedge"])
    again, _ = passing_use_points("knife", cut, 12, seed=5, max_draws=600)
    assert again.use_dir.tobytes() == uses.use_dir.tobytes()
    other, _ = passing_use_points("knife", cut, 12, seed=6, max_draws=600)
    assert other.use_dir.tobytes() != uses.use_dir.tobytes()
    # a plain sample by area holds fewer edge points than it draws
    plain = UsePoints.sample("knife", 12, 5)
    assert use_only_passes(cut, "default", {}, plain).sum() < 12


def test_passing_use_points_fall_back_to_the_plain_sample_and_say_so():
    from affordgrasp.search.use_points import UsePoints, passing_use_points

    cut = tasks.get_task("cut-rules")
    # no point of a knife is a 0.01 rad wedge: nothing passes
    uses, sampling = passing_use_points(
        "knife", cut, 10, seed=2, thresholds={"tau_wedge": 0.01}, max_draws=30
    )
    assert sampling.fallback and sampling.passing == 0 and sampling.drawn == 30
    assert "none of 30" in sampling.describe()
    np.testing.assert_array_equal(uses.use_dir, UsePoints.sample("knife", 10, 2).use_dir)
    # pick reads no column of the use point: the plain sample, as before
    _, pick = passing_use_points("knife", tasks.get_task("pick"), 10, seed=2)
    assert not pick.tested and pick.kept == 10
    with pytest.raises(InputError, match="uses"):
        passing_use_points("knife", cut, 0, seed=2)
