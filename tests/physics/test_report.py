"""ROC-AUC and Spearman against brute-force definitions and scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import spearmanr

from affordgrasp.physics.report import roc_auc, roc_curve, spearman


def _auc_by_pairs(score, label):
    pos, neg = score[label], score[~label]
    wins = (pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()
    return wins / (len(pos) * len(neg))


def test_auc_analytic_cases():
    label = np.array([False, False, True, True])
    assert roc_auc(np.array([0.0, 1.0, 2.0, 3.0]), label) == 1.0
    assert roc_auc(np.array([3.0, 2.0, 1.0, 0.0]), label) == 0.0
    assert roc_auc(np.full(4, -np.inf), label) == 0.5  # all tied: no credit
    assert math.isnan(roc_auc(np.arange(4.0), np.ones(4, dtype=bool)))


def test_auc_equals_pair_count_with_ties_and_infinities():
    rng = np.random.default_rng(0)
    score = rng.integers(0, 5, 200).astype(float)
    score[rng.random(200) < 0.3] = -np.inf
    label = rng.random(200) < 0.4
    assert roc_auc(score, label) == pytest.approx(_auc_by_pairs(score, label), abs=1e-12)
    fpr, tpr = roc_curve(score, label)
    assert np.trapezoid(tpr, fpr) == pytest.approx(roc_auc(score, label), abs=1e-12)


def test_spearman_matches_scipy_and_drops_nan():
    rng = np.random.default_rng(1)
    x, y = rng.normal(size=100), rng.normal(size=100)
    y += x
    assert spearman(x, y) == pytest.approx(spearmanr(x, y).statistic, abs=1e-12)
    x2 = np.r_[x, np.nan]
    y2 = np.r_[y, 5.0]
    assert spearman(x2, y2) == pytest.approx(spearman(x, y), abs=1e-12)


def _synthetic_outcomes(n=60, seed=0):
    import pyarrow as pa

    from affordgrasp.columns import HOLD_EFFORT_COLUMNS

    rng = np.random.default_rng(seed)
    held = rng.random(n) < 0.4
    eps = np.where(rng.random(n) < 0.5, rng.random(n) * 0.1, 0.0)
    cols = {
        "object": [("mug:0", "knife:0")[i % 2] for i in range(n)],
        "epsilon": eps,
        "impact_effort": rng.random(n),
        "use_force": rng.random(n),
        "discharge": rng.random(n),
        "hold_ok": held,
        "settled": held | (rng.random(n) < 0.2),
        "impact_ok": held,
        "press_held": held,
        "hold_directions_ok": np.where(held, 6, rng.integers(0, 6, n)),
        "impact_angle_rad": rng.random(n),
        "press_force_n": rng.random(n),
        "initial_penetration_m": rng.random(n) * 3e-3,
        "start_penetration_m": rng.random(n) * 5e-5,
        "ejected": ~held & (rng.random(n) < 0.5),
        "distal_at_limit": rng.integers(0, 4, n),
        "settled_epsilon": rng.random(n),
        "settled_hold_effort_sum": rng.random(n),
        "settled_hold_dirs": rng.integers(0, 7, n),
        "robust_hold_dirs": held * 3.0 + rng.random(n),  # separates perfectly
        "protocol": ["dgb"] * n,
    }
    for k, c in enumerate(HOLD_EFFORT_COLUMNS):
        cols[c] = np.where(rng.random(n) < 0.3 + 0.1 * k, np.inf, rng.random(n))
    return pa.table(cols)


def test_report_headline_start_tables_and_plots(tmp_path):
    import matplotlib
    import pyarrow as pa

    from affordgrasp.columns import HOLD_EFFORT_COLUMNS
    from affordgrasp.physics.report import physics_report

    table = _synthetic_outcomes()
    backend = matplotlib.get_backend()
    report = physics_report(table, tmp_path, n_boot=50, seed=1)
    assert matplotlib.get_backend() == backend  # the caller's backend is left alone
    h = report["headline"]
    assert report["protocol"] == ["dgb"]
    assert h["all"]["auc"]["robust_hold_dirs"] == [1.0, 1.0, 1.0]
    assert set(h["families"]) == {"mug", "knife"}
    # hold_dirs = the number of finite hold-effort columns of each row.
    finite = np.isfinite(np.stack([table.column(c).to_numpy() for c in HOLD_EFFORT_COLUMNS]))
    held = table.column("hold_ok").to_numpy(zero_copy_only=False)
    assert h["all"]["auc"]["hold_dirs"][0] == pytest.approx(roc_auc(finite.sum(axis=0), held))
    assert h["force_closure"]["n"] == int(np.sum(table.column("epsilon").to_numpy() > 0))
    start = report["start"]
    assert sum(b["n"] for b in start["by_initial_penetration"]) == table.num_rows
    assert sum(b["n"] for b in start["by_distal_at_limit"]) == table.num_rows
    assert start["start_under_0.5mm"] == 1.0
    other = table.set_column(
        table.schema.get_field_index("protocol"), "protocol", pa.array(["affordgrasp"] * 60)
    )
    both = physics_report(table, n_boot=20, compare=[other])
    assert list(both["by_run"]) == ["dgb", "affordgrasp"]
    assert both["by_run"]["dgb"]["n"] == table.num_rows
    for name in ("report.md", "roc_hold_headline.png", "report.json"):
        assert (tmp_path / name).is_file()
    assert "bootstrap 95 % interval" in (tmp_path / "report.md").read_text()


def test_outcomes_without_a_protocol_column_take_the_runs(tmp_path):
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from affordgrasp.physics.run import MANIFEST, read_outcomes, shard_path

    (tmp_path / MANIFEST).write_text(json.dumps({"settings": {"protocol": "dgb"}}))
    pq.write_table(pa.table({"object": ["mug:0", "mug:0"]}), shard_path(tmp_path, 0))
    assert read_outcomes(tmp_path).column("protocol").to_pylist() == ["dgb", "dgb"]


def test_an_undefined_statistic_says_why():
    from affordgrasp.physics.report import _stats
    from affordgrasp.physics.report import _why_undefined as why_undefined

    force = np.array([1.0, 2.0, 3.0, 4.0])
    assert "every task_cut is -inf" in why_undefined("task_cut", np.full(4, -np.inf), "f", force)
    assert "epsilon is the same" in why_undefined("epsilon", np.ones(4), "f", force)
    assert "f is the same" in why_undefined("epsilon", force, "f", np.ones(4))
    assert "2 rows with both" in why_undefined("e", np.array([1.0, 2, np.nan, np.nan]), "f", force)
    outs = {o: np.array([1.0, 0.0, 1.0, 0.0]) for o in ("hold_ok", "settled", "impact_ok")}
    outs |= {o: force for o in ("press_held", "hold_directions_ok", "impact_steadiness")}
    outs["press_force_n"] = force
    preds = {"task_cut": np.full(4, -np.inf), "use_force": force}
    stats = _stats(preds, outs, np.ones(4, dtype=bool))
    assert math.isnan(stats["spearman"]["press_force_n"]["task_cut"])
    assert "-inf" in stats["undefined"]["press_force_n"]["task_cut"]
    assert "use_force" not in stats["undefined"].get("press_force_n", {})
