"""Dataset plots (affordgrasp.viz.plots) and the ``affordgrasp plots`` command."""

import json

import numpy as np
import pyarrow as pa
import pytest
from PIL import Image

from affordgrasp.cli import main
from affordgrasp.viz.plots import Summary, summarize

from .conftest import write_dataset


def summary_of(values, chunks=2):
    s = Summary()
    parts = np.array_split(np.asarray(values, dtype=np.float64), chunks)
    for p in parts:
        s.see(p)
    s.fix_bins(20)
    for p in parts:
        s.add(p)
    return s


def test_summary_counts_what_it_cannot_bin():
    values = np.concatenate([np.linspace(0.0, 1.0, 50), [np.inf, np.inf, -np.inf, np.nan]])
    s = summary_of(values)
    assert (s.n, s.pos_inf, s.neg_inf, s.nan, s.finite) == (54, 2, 1, 1, 50)
    assert s.counts.sum() == 50  # the extremes fall in the end bins
    assert s.scale == "linear" and s.edges[0] == 0.0 and s.edges[-1] == 1.0
    assert "+∞ 4%" in s.note() and "NaN 2%" in s.note()


@pytest.mark.parametrize(
    ("values", "scale"),
    [
        (np.geomspace(1e-2, 1e4, 30), "log"),
        (np.concatenate([[0.0], np.geomspace(1e-3, 1e5, 30)]), "symlog"),
        (-np.geomspace(1e-2, 1e5, 30), "symlog"),
        (np.linspace(-3, 7, 30), "linear"),
        (np.full(5, 2.5), "linear"),
    ],
)
def test_summary_picks_a_readable_scale(values, scale):
    s = summary_of(values)
    assert s.scale == scale
    assert s.counts.sum() == len(values)
    assert np.all(np.diff(s.edges) > 0)


def test_summarize_streams_batches_and_scores_tasks():
    from affordgrasp.tasks import get_task

    rng = np.random.default_rng(1)
    n = 40
    eff = {f"hold_effort_{s}": rng.uniform(1, 10, n) for s in ("px", "nx", "py", "ny", "pz", "nz")}
    eff["hold_effort_px"][:5] = np.inf  # pick -> -inf for these
    table = pa.table(
        {
            "object": ["a"] * 30 + ["b"] * 10,
            "status": ["grasped"] * 25 + ["missed"] * 15,
            **eff,
        }
    )
    batches = [table.slice(0, 17), table.slice(17)]
    s = summarize(
        lambda cols: (b.select(cols) for b in batches), table.schema, [get_task("pick-paper")]
    )
    assert s.rows == 40
    assert s.status == {"a": {"grasped": 25, "missed": 5}, "b": {"missed": 10}}
    pick = s.affordances["pick-paper"]
    assert pick["a"].n == 30 and pick["a"].neg_inf == 5 and pick["b"].finite == 10
    assert pick["a"].counts.sum() == 25
    assert pick["a"].hi == pytest.approx(-np.min(sum(eff.values())[:30]))


def test_plots_command_writes_three_pngs(tmp_path, capsys, box_object):
    data = write_dataset(tmp_path / "data", [box_object], rows_per_object=9)
    out = tmp_path / "plots"
    rc = main(["plots", str(data), "--task", "beat-rules,pick-paper", "-o", str(out), "--json"])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    doc = json.loads(captured.out)
    assert set(doc["files"]) == {"metrics", "status", "affordances"}
    for path in doc["files"].values():
        image = np.asarray(Image.open(path).convert("RGB"))
        assert image.shape[0] > 200 and image.shape[1] > 600
        assert (image < 200).any(axis=2).mean() > 0.01  # axes, bars and text were drawn
    assert doc["rows"] == 9
    assert doc["status"] == {"bar.stl": {"grasped": 6, "touched": 3}}
    assert doc["tasks"]["pick-paper"]["bar.stl"] == {"rows": 9, "accepted": 6}
    assert doc["metrics"]["impact_effort"]["pos_inf"] == 3


def test_a_task_probability_accepts_its_probable_rows_and_reads_stored_columns(monkeypatch):
    """p_T is never -inf: the rows a task probability accepts are those with p_T >= 0.5;
    with ``stored`` the p_T column is read (the models are not run) and gives the same."""
    import affordgrasp.tasks.probability as probability
    from affordgrasp.tasks import get_task

    rng = np.random.default_rng(2)
    n = 30
    eff = {f"hold_effort_{s}": rng.uniform(1, 10, n) for s in ("px", "nx", "py", "ny", "pz", "nz")}
    cols = {"object": ["a"] * 20 + ["b"] * 10, "status": ["grasped"] * n, **eff}
    for c in probability.task_model("pick").columns:
        cols.setdefault(c, rng.uniform(0, 1, n))
    table = pa.table(cols)
    p = probability.task_probability("pick", table_metrics(table))
    table = table.append_column("p_pick", pa.array(p))
    pick = get_task("pick")

    def run(stored):
        return summarize(lambda c: [table.select(c)], table.schema, [pick], stored=stored)

    computed = run(())
    assert computed.probable["pick"] == {
        "a": int((p[:20] >= 0.5).sum()),
        "b": int((p[20:] >= 0.5).sum()),
    }
    assert computed.accepted("pick", "a") == computed.probable["pick"]["a"]
    import affordgrasp.tasks.builtins as builtins

    monkeypatch.setattr(builtins, "task_probability", lambda *a: 1 / 0)  # not run
    with pytest.raises(ZeroDivisionError):
        run(())
    stored = run(["pick"])
    assert stored.probable == computed.probable
    assert stored.affordances["pick"]["a"].hi == computed.affordances["pick"]["a"].hi


def table_metrics(table):
    from affordgrasp.tasks import MetricColumns

    return MetricColumns(table)
