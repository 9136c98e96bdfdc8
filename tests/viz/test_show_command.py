"""``affordgrasp show`` end to end on a small dataset directory."""

import json
import shutil

import numpy as np
import pyarrow.dataset as pads
import pytest
from PIL import Image

from affordgrasp.cli import main
from affordgrasp.pipeline import Evaluation
from affordgrasp.viz.grid import LABEL_PX, TITLE_PX

from .conftest import write_dataset


@pytest.fixture(scope="module")
def dataset(tmp_path_factory, box_object, block_object):
    directory = write_dataset(tmp_path_factory.mktemp("ds") / "data", [box_object, block_object])
    # The bar's mesh travels with the dataset; the block's is given with --mesh.
    shutil.copy(box_object.source, directory / "bar.stl")
    return directory


def run_json(capsys, argv):
    rc = main(argv + ["--json"])
    captured = capsys.readouterr()
    return rc, captured.out, captured.err


def test_show_writes_grid_page_and_best_rows(tmp_path, capsys, dataset, block_object):
    out = tmp_path / "out"
    rc, stdout, stderr = run_json(
        capsys,
        [
            "show",
            str(dataset),
            "--task",
            "beat-rules,pick-paper",
            "--top",
            "2",
            "--cell",
            "96",
            "--mesh",
            block_object.source,
            "-o",
            str(out),
        ],
    )
    assert rc == 0, stderr
    doc = json.loads(stdout)
    assert doc["files"]["grid"] == str(out / "best_grasps.png")
    assert doc["files"]["html"] == str(out / "best_grasps.html")
    assert doc["tasks"] == ["beat-rules", "pick-paper"]
    assert len(doc["best"]) == 2 * 2 * 2  # objects x tasks x top
    # The best pick is the row with the least total hold effort, found independently.
    shards = [str(p) for p in sorted(dataset.glob("*.parquet"))]
    table = pads.dataset(shards, format="parquet").to_table().to_pylist()
    for name in ("bar.stl", "block.stl"):
        rows = [r for r in table if r["object"] == name]
        effort = [
            sum(r[f"hold_effort_{s}"] for s in ("px", "nx", "py", "ny", "pz", "nz")) for r in rows
        ]
        best = rows[int(np.argmin(effort))]
        got = [
            b
            for b in doc["best"]
            if b["object"] == name and b["task"] == "pick-paper" and b["rank"] == 1
        ]
        assert got[0]["sample"] == best["sample"]
        assert got[0]["score"] == pytest.approx(-min(effort))
        ranks = [
            b["score"] for b in doc["best"] if b["object"] == name and b["task"] == "pick-paper"
        ]
        assert ranks == sorted(ranks, reverse=True)
    # Grid: one row per (object, task), one column per rank.
    image = Image.open(out / "best_grasps.png")
    assert image.size[0] == LABEL_PX + 2 * 96
    assert image.size[1] > TITLE_PX + LABEL_PX + 4 * 96
    html = (out / "best_grasps.html").read_text()
    assert html.count('"link_poses"') == 8


def test_one_grasp_per_task_puts_tasks_in_columns(tmp_path, capsys, dataset, block_object):
    out = tmp_path / "out"
    rc, stdout, stderr = run_json(
        capsys,
        [
            "show",
            str(dataset),
            "--task",
            "beat",
            "--task",
            "cut,pick",
            "--top",
            "1",
            "--cell",
            "80",
            "--mesh",
            block_object.source,
            "--no-html",
            "--each",
            "--grasp-size",
            "96",
            "-o",
            str(out),
        ],
    )
    assert rc == 0, stderr
    doc = json.loads(stdout)
    assert doc["files"]["html"] is None
    assert len(doc["files"]["grasps"]) == 6
    assert all(p.endswith(".png") for p in doc["files"]["grasps"])
    assert Image.open(out / "grasps" / "bar.stl_cut_1.png").size == (96, 96)
    image = Image.open(out / "best_grasps.png")
    assert image.size[0] == LABEL_PX + 3 * 80  # beat, cut, pick


def test_bad_inputs_exit_2_with_a_reason(tmp_path, capsys, dataset):
    rc = main(["show", str(dataset), "--task", "juggle", "-o", str(tmp_path)])
    assert rc == 2 and "juggle" in capsys.readouterr().err
    rc = main(["show", str(dataset), "--task", "cut", "--mode", "sloppy", "-o", str(tmp_path)])
    assert rc == 2 and "sloppy" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.mkdir()
    rc = main(["show", str(empty), "--task", "cut", "-o", str(tmp_path)])
    assert rc == 2 and "no Parquet files" in capsys.readouterr().err
    # block.stl is not in the dataset directory and not given with --mesh.
    rc = main(["show", str(dataset), "--task", "pick", "--top", "1", "-o", str(tmp_path)])
    err = capsys.readouterr().err
    assert rc == 2 and "block.stl" in err and "--mesh" in err
    rc = main(
        ["show", str(dataset), "--task", "cut", "--threshold", "tau_x=1", "-o", str(tmp_path)]
    )
    assert rc == 2 and "tau_x" in capsys.readouterr().err


def test_an_object_source_is_evaluated_then_shown(tmp_path, capsys, monkeypatch, box_object):
    """An object SOURCE is sampled with --samples/--seed (the simulation itself is replaced
    here by rows from a small dataset, to keep the test fast)."""
    import pyarrow.parquet as pq

    import affordgrasp.pipeline

    data = write_dataset(tmp_path / "data", [box_object], rows_per_object=6)
    table = pq.read_table(next(data.glob("*.parquet")))
    calls = []

    def fake_evaluate_samples(obj, n, *, seed=0, start=0, hand="barrett", **kwargs):
        calls.append((obj.name, n, seed, start, hand))
        return Evaluation(table.slice(start, n), {})

    monkeypatch.setattr(affordgrasp.pipeline, "evaluate_samples", fake_evaluate_samples)
    rc, stdout, stderr = run_json(
        capsys,
        [
            "show",
            box_object.source,
            "--task",
            "pick-paper",
            "--top",
            "3",
            "--samples",
            "6",
            "--seed",
            "4",
            "--cell",
            "64",
            "-o",
            str(tmp_path / "out"),
        ],
    )
    assert rc == 0, stderr
    assert calls == [("bar.stl", 6, 4, 0, "barrett")]
    doc = json.loads(stdout)
    assert [b["rank"] for b in doc["best"]] == [1, 2, 3]
    assert doc["rankings"] == [
        {"object": "bar.stl", "task": "pick-paper", "scored": 6, "accepted": 4}
    ]


def test_show_falls_back_when_its_brute_force_finds_no_pair(monkeypatch):
    """No pair by area: a search aimed at the task's tests, said, its rows appended (the
    searches are replaced here by stand-ins that record their calls)."""
    import types

    import pyarrow as pa

    import affordgrasp.search.pairs
    from affordgrasp.commands.show import with_best_pairs
    from affordgrasp.pipeline import evaluate_samples
    from affordgrasp.tasks import get_task

    table = evaluate_samples("hammer", 6, seed=1, volume=False).table
    found = table.slice(0, 2).append_column("value", pa.array([2.0, 1.0]))
    none = found.slice(0, 0)
    calls = []

    def fake(name, rows):
        def search(obj, settings, **kwargs):
            calls.append((name, settings.task, settings.budget, settings.restarts))
            return types.SimpleNamespace(table=rows)

        return search

    said = []
    out = types.SimpleNamespace(text=said.append)
    args = types.SimpleNamespace(
        uses=50, samples=300, mode="default", seed=0, top=2, hand="barrett"
    )
    cut = get_task("cut")
    # the brute force finds pairs: nothing else runs, nothing is said
    monkeypatch.setattr(affordgrasp.search.pairs, "best_pairs", fake("brute force", found))
    monkeypatch.setattr(affordgrasp.search.pairs, "optimize_pairs", fake("search", found))
    grown = with_best_pairs("hammer", table, [cut], {}, args, out)
    assert [c[0] for c in calls] == ["brute force"] and not said
    assert grown.num_rows == table.num_rows + 2
    # nothing by area: the search, 4 x --samples simulations in 2 restarts
    calls.clear()
    monkeypatch.setattr(affordgrasp.search.pairs, "best_pairs", fake("brute force", none))
    grown = with_best_pairs("hammer", table, [cut], {}, args, out)
    assert [c[0] for c in calls] == ["brute force", "search"]
    assert calls[-1][2:] == (1200, 2)
    assert "no pair of the 6 grasps with 50 use points" in said[-1]
    assert "1,200 more simulations in 2 restarts: 2 grasps found" in said[-1]
    assert grown.column("sample").to_pylist()[-2:] == [6, 7]
    # nothing found at all: the samples alone, and it says so
    monkeypatch.setattr(affordgrasp.search.pairs, "optimize_pairs", fake("search", none))
    assert with_best_pairs("hammer", table, [cut], {}, args, out) is table
    assert said[-1].endswith("0 grasps found")
    # pick reads no use point: no pair search at all
    calls.clear()
    assert with_best_pairs("hammer", table, [get_task("pick")], {}, args, out) is table
    assert not calls
