"""Affordance functions, thresholds, the registry and declarative task files (tasks/)."""

import math

import numpy as np
import pyarrow as pa
import pytest

from affordgrasp import tasks
from affordgrasp.errors import TaskError

INF = np.inf


def table(**overrides):
    """Five grasps; defaults make every task pass, overrides change columns."""
    n = 5
    cols = {
        "epsilon": np.full(n, 0.4),
        "gws_volume": np.full(n, 0.01),
        "inertia": np.array([1.0, 2.0, 3.0, 4.0, 5.0]) * 1e-4,
        "impact_effort": np.array([10.0, 20.0, 30.0, 40.0, INF]),
        "discharge": np.full(n, 0.99),
        "use_force": np.array([0.5, 1.0, 1.5, 2.0, 2.5]),
        "use_edge": np.full(n, 1e6),
        "use_edge_angle": np.full(n, math.radians(20)),
        "use_wedge_angle": np.full(n, math.radians(20)),  # beat's tests make it blunt
        "use_wedge_angle_fine": np.full(n, math.radians(20)),
        "use_edge_span": np.full(n, 1.0 / 3.0),
        "use_edge_thickness": np.full(n, 1e-4),
        "use_clearance": np.full(n, 0.05),
        "contact_thickness": np.full(n, 0.02),
        "contact_width": np.full(n, 0.015),
        "use_lever_ratio": np.full(n, 1.2),
        "contact_reach": np.full(n, -0.2),
        "use_depth": np.full(n, 0.08),  # a hammer's face: the head's length behind it
        "use_relief": np.full(n, 1e-4),  # and flat around it
        "use_swing_cosine": np.full(n, 0.99),  # struck square
    }
    for s in ("px", "nx", "py", "ny", "pz", "nz"):
        cols[f"hold_effort_{s}"] = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    cols.update({k: np.asarray(v, dtype=float) for k, v in overrides.items()})
    cols.setdefault("epsilon_hand", cols["epsilon"])  # an object within 0.25 m
    return cols


@pytest.fixture
def registry():
    """Let a test register tasks; remove them afterwards."""
    before = set(tasks.list_tasks())
    yield
    for name in set(tasks.list_tasks()) - before:
        tasks.unregister_task(name)


def test_builtin_tasks_are_listed():
    names = {
        "beat-rules",
        "beat-paper",
        "cut-rules",
        "cut-wedge",
        "cut-dihedral",
        "cut-ug",
        "pick",
        "pick-paper",
        "viable",
        "beat",
        "cut",
    }
    assert names <= set(tasks.list_tasks())
    with pytest.raises(TaskError, match="available tasks: .*beat"):
        tasks.get_task("juggle")


def test_beat_paper_follows_the_paper():
    beat = tasks.get_task("beat-paper")
    np.testing.assert_allclose(
        beat.evaluate(table()), [1e-5, 1e-5, 1e-5, 1e-5, 0.0]
    )  # I / E_i, and I / inf = 0
    low_eps = table(epsilon=[0.01, 0.4, 0.4, 0.4, 0.4])
    low_delta = table(discharge=[0.99, 0.9, 0.99, 0.99, 0.99])
    no_hold = table(hold_effort_pz=[1.0, 2.0, INF, 4.0, 5.0])
    assert beat.evaluate(low_eps)[0] == -INF
    assert beat.evaluate(low_delta)[1] == -INF
    assert beat.evaluate(no_hold)[2] == -INF
    assert np.isfinite(beat.evaluate(low_eps, mode="no-robustness")[0])
    assert np.all(beat.evaluate(table(epsilon=np.full(5, 0.02)), mode="extra-robustness") == -INF)
    assert np.all(beat.evaluate(table(), mode="paper-extra-robustness") == -INF)  # 0.4 < 0.5
    assert np.isfinite(beat.evaluate(table(), mode="paper")).all()  # 0.4 >= 0.3
    assert np.isfinite(beat.evaluate(low_delta, tau_delta=0.8)[1])


def test_beat_is_the_papers_on_a_blunt_point_with_the_hand_off_it():
    beat, paper = tasks.get_task("beat-rules"), tasks.get_task("beat-paper")
    blunt = table(use_wedge_angle=np.full(5, math.pi))
    np.testing.assert_array_equal(beat.evaluate(blunt), paper.evaluate(blunt))
    sharp = table(use_wedge_angle=[math.pi, math.radians(60), math.pi, math.pi, math.pi])
    near = table(use_wedge_angle=np.full(5, math.pi), use_clearance=[0.05, 0.05, 0.01, 0.05, 0.05])
    assert beat.evaluate(sharp)[1] == -INF and np.isfinite(beat.evaluate(sharp)[0])
    assert beat.evaluate(near)[2] == -INF and np.isfinite(beat.evaluate(near)[3])
    assert beat.thresholds["tau_clear"] == tasks.TAU_CLEARANCE_DEFAULT
    butt = table(use_wedge_angle=np.full(5, math.pi), use_lever_ratio=[0.3, 1.2, 1.2, 1.2, 1.2])
    assert beat.evaluate(butt)[0] == -INF and np.isfinite(beat.evaluate(butt)[1])
    held_by_head = table(use_wedge_angle=np.full(5, math.pi), use_lever_ratio=[6.0, 2.0, 1.2, 1, 1])
    assert beat.evaluate(held_by_head)[0] == -INF
    assert np.isfinite(beat.evaluate(held_by_head)[1:]).all()  # 1 <= ratio <= 2 passes
    beyond_hand = table(use_wedge_angle=np.full(5, math.pi), use_lever_ratio=[-INF, 1, 1, 1, 1])
    assert beat.evaluate(beyond_hand)[0] == -INF
    nan_use = table(use_wedge_angle=[np.nan, math.pi, math.pi, math.pi, math.pi])
    assert beat.evaluate(nan_use)[0] == -INF  # no use point: not usable


def test_beat_strikes_with_a_deep_flat_surface():
    beat, paper = tasks.get_task("beat-rules"), tasks.get_task("beat-paper")
    blunt = dict(use_wedge_angle=np.full(5, math.pi))
    # a side face of the head (25 mm behind it), a claw, a ball peen (1 mm off its plane at
    # 5 mm), a ring that leaves the part (inf), and a face
    cols = table(
        **blunt,
        use_depth=[0.025, 0.008, 0.09, 0.09, 0.09],
        use_relief=[1e-4, 1e-4, 1e-3, INF, 1e-4],
    )
    got = beat.evaluate(cols)
    assert np.all(got[:4] == -INF) and np.isfinite(got[4])
    assert np.isfinite(paper.evaluate(cols)[:4]).all()  # the paper's form reads neither
    assert beat.thresholds["tau_depth"] == tasks.TAU_DEPTH_DEFAULT
    assert beat.thresholds["tau_relief"] == tasks.TAU_RELIEF_DEFAULT
    relaxed = beat.evaluate(cols, tau_depth=0.0, tau_relief=INF)
    assert np.isfinite(relaxed).all()
    nan_depth = table(**blunt, use_depth=[np.nan, 0.09, 0.09, 0.09, 0.09])
    assert beat.evaluate(nan_depth)[0] == -INF


def test_beat_and_cut_gate_epsilon_at_the_hand_length_the_paper_variants_epsilon():
    # a sword: ε (torques / r_max) below τ_ε, the same grasp's ε at 0.25 m above it
    long = table(
        epsilon=np.full(5, 0.01),
        epsilon_hand=[0.01, 0.02, 0.02, 0.02, 0.02],
        use_wedge_angle=np.full(5, math.pi),
    )
    beat = tasks.get_task("beat-rules").evaluate(long)
    assert beat[0] == -INF and np.isfinite(beat[1:]).all()
    assert np.all(tasks.get_task("beat-paper").evaluate(long) == -INF)
    edge = dict(long, use_wedge_angle=np.full(5, 0.3))
    cut = tasks.get_task("cut-rules").evaluate(edge)
    assert cut[0] == -INF and np.isfinite(cut[1:]).all()
    assert np.all(tasks.get_task("cut-dihedral").evaluate(edge) == -INF)
    assert np.all(tasks.get_task("cut-ug").evaluate(edge) == -INF)
    # viability (learning ground truth) stays on ε
    weak = dict(edge, epsilon=np.full(5, 0.005))
    assert np.all(tasks.get_task("viable").evaluate(weak) == 0.0)
    # the modes set τ_ε of the same column
    assert np.all(tasks.get_task("beat-rules").evaluate(long, mode="extra-robustness") == -INF)
    # rows written before the column existed are gated on ε itself
    old = {k: v for k, v in long.items() if k != "epsilon_hand"}
    assert np.all(tasks.get_task("beat-rules").evaluate(old) == -INF)


def test_cut_tests_the_wedge_angle_and_clearance_and_keeps_the_other_tests():
    cut = tasks.get_task("cut-rules")
    np.testing.assert_allclose(cut.evaluate(table()), table()["use_force"])
    blunt = table(use_wedge_angle=[math.pi, 0.3, 0.3, 0.3, 0.3], use_edge_angle=np.full(5, 0.1))
    assert cut.evaluate(blunt)[0] == -INF and cut.evaluate(blunt)[1] == 1.0
    on_blade = table(use_clearance=[0.005, 0.05, 0.05, 0.05, 0.05])
    assert cut.evaluate(on_blade)[0] == -INF and cut.evaluate(on_blade, tau_clear=0.0)[0] == 0.5
    thin = table(contact_thickness=[0.002, 0.02, 0.02, 0.02, 0.02])
    assert cut.evaluate(thin)[0] == -INF and cut.evaluate(thin)[1] == 1.0
    assert cut.thresholds["tau_thick"] == tasks.TAU_THICKNESS_DEFAULT
    reach = table(contact_reach=[0.6, 0.5, -0.05, -INF, 3.0])
    got = cut.evaluate(reach)
    assert got[0] == -INF and got[4] == -INF and np.isfinite(got[1:4]).all()
    assert cut.evaluate(reach, tau_reach=INF)[4] == 2.5
    assert cut.thresholds["tau_wedge"] == pytest.approx(tasks.TAU_WEDGE_DEFAULT)
    dihedral = tasks.get_task("cut-dihedral")
    edge_only = table(use_edge_angle=[math.pi, 0.3, 0.3, 0.3, 0.3], use_wedge_angle=np.full(5, 3.0))
    assert dihedral.evaluate(edge_only)[0] == -INF and dihedral.evaluate(edge_only)[1] == 1.0
    assert dihedral.thresholds["tau_angle"] == pytest.approx(tasks.TAU_EDGE_ANGLE_DEFAULT)
    ug = tasks.get_task("cut-ug")
    flat = table(use_edge=[0.0, 1e6, 1e6, 1e6, 1e6], use_edge_angle=np.full(5, math.pi))
    assert ug.evaluate(flat)[0] == -INF and ug.evaluate(flat, tau_ug=-1.0)[0] == 0.5
    assert ug.evaluate(flat)[1] == 1.0  # U_g alone decides, whatever the angle
    assert ug.thresholds["tau_ug"] == tasks.TAU_UG_DEFAULT


def test_cut_rejects_thin_flats_tips_and_corners_and_cut_wedge_keeps_them():
    cut, plain = tasks.get_task("cut-rules"), tasks.get_task("cut-wedge")
    fine = math.radians(100.0)  # a thin flat: an edge in the 3 mm ball, not in the 2 mm one
    corner = 0.12  # a blade's point or a cleaver's heel: the inside directions in a sector
    cols = table(
        use_wedge_angle_fine=[fine, math.radians(20), 0.3, 0.3, 0.3],
        use_edge_span=[1 / 3, corner, 0.5, 1 / 3, 0.3],
    )
    got = cut.evaluate(cols)
    assert got[0] == -INF and got[1] == -INF and np.isfinite(got[2:]).all()
    np.testing.assert_allclose(plain.evaluate(cols), cols["use_force"])  # the 3 mm test alone
    # each new test is a threshold that can be relaxed; the previous tests still apply
    assert cut.evaluate(cols, tau_wedge_fine=math.pi)[0] == 0.5
    assert cut.evaluate(cols, tau_span=0.0)[1] == 1.0
    blunt = table(use_wedge_angle=np.full(5, math.pi))
    assert np.all(cut.evaluate(blunt) == -INF) and np.all(plain.evaluate(blunt) == -INF)
    assert np.isnan(cut.evaluate(table(use_edge_span=[np.nan, 0.3, 0.3, 0.3, 0.3]))).sum() == 0
    assert cut.evaluate(table(use_edge_span=[np.nan, 0.3, 0.3, 0.3, 0.3]))[0] == -INF
    assert cut.thresholds["tau_wedge_fine"] == pytest.approx(tasks.TAU_WEDGE_FINE_DEFAULT)
    assert cut.thresholds["tau_span"] == pytest.approx(tasks.TAU_SPAN_DEFAULT)
    assert 0.18 < tasks.TAU_SPAN_DEFAULT < 1 / 3  # between a 90° corner and an edge
    # the use point on a spine: a 1 mm plate's end, parallel flanks behind it; a NaN
    # thickness (no chord behind U inside the part) is no edge either
    end = table(use_edge_thickness=[0.001, np.nan, 0.0, 0.0, 0.0])
    got = cut.evaluate(end)
    assert got[0] == -INF and got[1] == -INF and np.isfinite(got[2:]).all()
    assert cut.evaluate(end, tau_edge_thickness=0.002)[0] == 0.5
    np.testing.assert_allclose(plain.evaluate(end), end["use_force"])
    # rows of an earlier version, without the column: named, and what to do
    old_rows = {c: v for c, v in end.items() if c != "use_edge_thickness"}
    with pytest.raises(TaskError, match="use_edge_thickness.*earlier version"):
        cut.evaluate(old_rows)
    assert cut.thresholds["tau_edge_thickness"] == pytest.approx(tasks.TAU_EDGE_THICKNESS_DEFAULT)
    # a finger on a spine: thick along its normal, 3 mm across
    spine = table(contact_width=[0.003, 0.015, 0.015, 0.015, 0.015])
    assert cut.evaluate(spine)[0] == -INF and plain.evaluate(spine)[0] == 0.5
    assert cut.evaluate(spine, tau_width=0.0)[0] == 0.5
    assert cut.thresholds["tau_width"] == tasks.TAU_WIDTH_DEFAULT


def test_pick_and_viable():
    np.testing.assert_allclose(
        tasks.get_task("pick-paper").evaluate(table()), [-6, -12, -18, -24, -30]
    )
    cols = table(epsilon=[0.005, 0.2, 0.2, 0.2, 0.2], impact_effort=[10, 2e5, 10, 10, 10])
    cols["hold_effort_px"] = np.array([1.0, 1.0, 300.0, 1.0, 1.0])
    np.testing.assert_array_equal(tasks.get_task("viable").evaluate(cols), [0, 0, 0, 1, 1])
    np.testing.assert_array_equal(tasks.is_viable(cols), [False, False, False, True, True])
    np.testing.assert_array_equal(
        tasks.is_viable(cols, eps_min=0.001), [True, False, False, True, True]
    )
    # the paper's literal thresholds: ε > 0.15 and E_i < 100
    paper = table(epsilon=[0.1, 0.2, 0.2, 0.2, 0.2], impact_effort=[10, 200, 10, 10, 10])
    np.testing.assert_array_equal(
        tasks.is_viable(paper, mode="paper"), [False, False, True, True, True]
    )
    assert tasks.VIABLE_EPS_MIN == tasks.TAU_EPS_VIABLE


def test_modes_and_overrides_are_checked():
    beat = tasks.get_task("beat-rules")
    assert beat.thresholds_for("no-robustness")["tau_eps"] == -INF
    assert beat.thresholds_for("extra-robustness")["tau_eps"] == tasks.TAU_EPS_EXTRA
    assert beat.thresholds_for("paper")["tau_eps"] == 0.3
    assert beat.thresholds_for("paper-extra-robustness")["tau_eps"] == 0.5
    assert beat.thresholds_for()["tau_delta"] == 0.95
    assert set(beat.thresholds_by_mode()) == set(tasks.MODES)
    # the calibrated values keep the paper's ratios 0.15 : 0.3 : 0.5
    assert tasks.TAU_EPS_DEFAULT == pytest.approx(2 * tasks.TAU_EPS_VIABLE, rel=0.05)
    assert tasks.TAU_EPS_EXTRA == pytest.approx(10 / 3 * tasks.TAU_EPS_VIABLE, rel=0.05)
    with pytest.raises(TaskError, match="no mode"):
        beat.evaluate(table(), mode="reckless")
    with pytest.raises(TaskError, match="no threshold 'tau_x'"):
        beat.evaluate(table(), tau_x=1.0)
    with pytest.raises(TaskError, match="missing.*available"):
        beat.evaluate({"epsilon": np.ones(3)})


def test_arrow_and_pandas_inputs():
    pd = pytest.importorskip("pandas")
    cols = table()
    expected = tasks.get_task("beat-rules").evaluate(cols)
    arrow = pa.table({"object": ["knife:0"] * 5, **cols, "epsilon_reason": [""] * 5})
    np.testing.assert_array_equal(tasks.get_task("beat-rules").evaluate(arrow), expected)
    frame = pd.DataFrame({"object": ["knife:0"] * 5, **cols})
    np.testing.assert_array_equal(tasks.evaluate_task("beat-rules", frame), expected)
    np.testing.assert_array_equal(
        tasks.get_task("pick-paper").evaluate(arrow), -6 * cols["hold_effort_px"]
    )


def test_python_registration(registry):
    def lever(m, t):
        return np.where(m["use_force"] > t["min_force"], m["use_force"] * m["discharge"], -np.inf)

    task = tasks.register_task(
        "lever", lever, thresholds={"min_force": 1.0}, requires=["use_force", "discharge"]
    )
    assert tasks.get_task("lever") is task
    out = task.evaluate(table())
    assert out[0] == -INF and out[4] == pytest.approx(2.5 * 0.99)
    assert task.evaluate(table(), min_force=0.0)[0] == pytest.approx(0.495)
    with pytest.raises(TaskError, match="already registered"):
        tasks.register_task("lever", lever)
    tasks.register_task("lever", lever, replace=True)


TOML = """
[tasks.pry]
description = "lever something open"
value = "use_force / impact_effort"
requires = "epsilon >= tau_eps and discharge >= 0.5"
[tasks.pry.thresholds]
tau_eps = 0.3
[tasks.pry.modes.extra-robustness]
tau_eps = 0.5

[tasks.steady]
value = "-log(hold_effort_sum) + 0 * max(epsilon, 0.1, gws_volume)"
requires = "not (epsilon < 0.1) and isfinite(hold_effort_sum)"
"""


def test_toml_task_file(tmp_path, registry):
    path = tmp_path / "mytasks.toml"
    path.write_text(TOML)
    assert tasks.load_task_file(path) == ["pry", "steady"]
    pry = tasks.get_task("pry")
    assert set(pry.requires) == {"use_force", "impact_effort", "epsilon", "discharge"}
    cols = table(epsilon=[0.2, 0.4, 0.4, 0.4, 0.4], discharge=[0.9, 0.9, 0.1, 0.9, 0.9])
    out = pry.evaluate(cols)
    np.testing.assert_allclose(out, [-INF, 1.0 / 20, -INF, 2.0 / 40, 0.0])
    assert np.all(pry.evaluate(cols, mode="extra-robustness") == -INF)
    assert pry.evaluate(cols, mode="no-robustness")[0] == pytest.approx(0.05)  # τ_ε = -inf
    steady = tasks.get_task("steady").evaluate(table(hold_effort_px=[1, 2, 3, 4, INF]))
    assert steady[0] == pytest.approx(-np.log(6.0)) and steady[4] == -INF


def test_environment_variable(tmp_path, monkeypatch, registry):
    path = tmp_path / "env.toml"
    path.write_text('[tasks.envtask]\nvalue = "2 * use_force"\n')
    monkeypatch.setenv(tasks.ENV_VAR, str(path))
    fresh = tasks.TaskRegistry()  # reads the variable at its first lookup...
    assert "envtask" in fresh.names()
    np.testing.assert_allclose(fresh.get("envtask").evaluate(table()), 2 * table()["use_force"])
    # ...and only then: a later change of the variable is not re-read at every lookup
    path.write_text('[tasks.other]\nvalue = "use_force"\n')
    monkeypatch.setenv(tasks.ENV_VAR, str(path))
    assert "other" not in fresh.names()
    assert fresh.load_environment() == ["other"] and "other" in fresh
    assert "envtask" not in tasks.TaskRegistry(environment=False).names()


@pytest.mark.parametrize(
    "expr, token",
    [
        ("__import__('os')", "__import__"),
        ("epsilon.__class__", "Attribute"),
        ("(lambda: 1)()", "lambda"),
        ("[x for x in epsilon]", "ListComp"),
        ("epsilon[0]", "Subscript"),
        ("'text'", "'text'"),
        ("open('f')", "open"),
        ("_private + 1", "_private"),
        ("abs(epsilon, out=epsilon)", "keyword argument 'out'"),
        ("epsilon if epsilon else 0", "IfExp"),
        ("epsilon @ epsilon", "MatMult"),
        ("epsilon +", "not a valid expression"),
    ],
)
def test_safe_evaluator_rejects_everything_else(expr, token, registry):
    with pytest.raises(TaskError, match=None) as err:
        tasks.task_from_expressions("bad", expr)
    assert token in str(err.value)
    assert "bad" not in tasks.list_tasks()


def test_bad_task_files(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[tasks.x]\nvalue = "1"\ncolour = "red"\n')
    with pytest.raises(TaskError, match="unknown keys"):
        tasks.load_task_file(bad)
    bad.write_text("[tasks.x]\nrequires = 'epsilon > 0'\n")
    with pytest.raises(TaskError, match="needs a 'value'"):
        tasks.load_task_file(bad)
    bad.write_text("not toml [")
    with pytest.raises(TaskError, match="not valid TOML"):
        tasks.load_task_file(bad)
    with pytest.raises(TaskError, match="does not exist"):
        tasks.load_task_file(tmp_path / "missing.toml")
    bad.write_text('[tasks.x]\nvalue = "1"\n[tasks.x.modes.default]\ntau = 1\n')
    with pytest.raises(TaskError, match="unknown thresholds"):
        tasks.load_task_file(bad)


def test_thresholds_are_numbers_or_infinite_never_nan(registry):
    task = tasks.task_from_expressions("bounded", "epsilon", "epsilon > t", {"t": -math.inf})
    assert task.thresholds_for("default", t=math.inf)["t"] == math.inf
    for bad in (math.nan, "abc", None):
        with pytest.raises(TaskError, match="threshold 't' must be a number"):
            task.thresholds_for("default", t=bad)
    with pytest.raises(TaskError, match="threshold 't' must be a number"):
        tasks.task_from_expressions("nan_t", "epsilon", "epsilon > t", {"t": math.nan})
    with pytest.raises(TaskError, match="must be a number"):
        tasks.task_from_expressions("nan_mode", "epsilon", None, {"t": 0}, {"m": {"t": math.nan}})


@pytest.mark.parametrize(
    "expr, message",
    [
        ("-" * 100_000 + "epsilon", "100,007 characters long; .* at most 2,000"),
        ("+".join(["epsilon"] * 200_000), "characters long"),
        ("-" * 1500 + "epsilon", "nests 1503 levels deep; .* at most 100"),
        ("+".join(["epsilon"] * 120), "levels deep"),
        ("(" * 300 + "epsilon" + ")" * 300, "not a valid expression"),
    ],
)
def test_expressions_are_bounded_in_size_and_depth(expr, message, registry):
    with pytest.raises(TaskError, match=message):
        tasks.task_from_expressions("big", expr)
    assert tasks.task_from_expressions("sum", "+".join(["epsilon"] * 90)).name == "sum"
