"""``affordgrasp physics`` on a tiny dataset: outcomes, report, resume, bad input."""

from __future__ import annotations

import json

import pyarrow.parquet as pq
import pytest

from affordgrasp.cli import main


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    import trimesh

    from affordgrasp.dataset.generate import generate

    root = tmp_path_factory.mktemp("physics-cli")
    mesh = root / "block.stl"
    trimesh.creation.box([0.05, 0.03, 0.04]).export(mesh)
    out = root / "ds"
    generate([str(mesh)], 24, out, seed=2, workers=1, shard_size=12, hand="parallel_jaw")
    return out


def _run(capsys, *argv):
    code = main(["physics", *map(str, argv), "--json"])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_physics_command_writes_outcomes_report_and_resumes(tiny_dataset, tmp_path, capsys):
    out, report = tmp_path / "physics.parquet", tmp_path / "report"
    args = [tiny_dataset, "--out", out, "--max-per-object", 4, "--shard-size", 2, "--workers", 1]
    code, stdout, _ = _run(capsys, *args, "--report", report)
    assert code == 0
    doc = json.loads(stdout)
    assert doc["summary"]["rows"] == 4 and doc["summary"]["shards_written"] == 2
    shards = sorted(out.glob("part-*.parquet"))
    assert len(shards) == 2
    table = pq.read_table(out)
    assert {"hold_ok", "settled", "hold_shift_px", "press_force_n", "epsilon"} <= set(
        table.column_names
    )
    assert set(table.column("status").to_pylist()) == {"grasped"}
    for name in ("report.json", "report.md", "roc_hold_ok.png", "auc_hold_by_family.png"):
        assert (report / name).is_file()
    first = pq.read_table(shards[1])

    # Resume: a lost shard is written again, the other is kept, and the rows are the same.
    shards[1].unlink()
    code, stdout, _ = _run(capsys, *args)
    assert code == 0
    summary = json.loads(stdout)["summary"]
    assert summary["shards_skipped"] == 1 and summary["shards_written"] == 1
    assert pq.read_table(shards[1]).to_pandas().equals(first.to_pandas())  # NaN == NaN

    # An object the dataset does not hold is refused, naming the ones it holds.
    code, _, stderr = _run(capsys, tiny_dataset, "--out", tmp_path / "o2", "--object", "axe")
    assert code == 2 and "block.stl" in stderr

    # Another plan in the same directory is refused, with what differs.
    code, _, stderr = _run(capsys, tiny_dataset, "--out", out, "--load-factor", 2)
    assert code == 2 and "settings_digest" in stderr


def test_physics_command_rejects_a_directory_that_is_not_a_dataset(tmp_path, capsys):
    code, _, stderr = _run(capsys, tmp_path, "--out", tmp_path / "o")
    assert code == 2 and stderr.count("\n") == 1


def test_missing_extra_names_the_install_command(monkeypatch):
    import builtins

    from affordgrasp.errors import MissingDependencyError
    from affordgrasp.physics import deps

    real_import = builtins.__import__

    def no_mujoco(name, *a, **k):
        if name == "mujoco":
            raise ImportError("no mujoco here")
        return real_import(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_mujoco)
    monkeypatch.delitem(__import__("sys").modules, "mujoco", raising=False)
    with pytest.raises(MissingDependencyError, match=r'pip install "affordgrasp\[physics\]"'):
        deps.mujoco()


def test_physics_command_dgb_protocol_and_bad_protocol(tiny_dataset, tmp_path, capsys):
    out = tmp_path / "dgb"
    args = [tiny_dataset, "--out", out, "--max-per-object", 2, "--workers", 1]
    code, stdout, _ = _run(capsys, *args, "--protocol", "dgb")
    assert code == 0
    doc = json.loads(stdout)
    assert doc["settings"]["protocol"] == "dgb" and doc["settings"]["load_factor"] == 10.0
    table = pq.read_table(out)
    assert set(table.column("protocol").to_pylist()) == {"dgb"}
    assert max(table.column("start_penetration_m").to_pylist()) <= 5e-5
    code, _, stderr = _run(capsys, tiny_dataset, "--out", tmp_path / "x", "--protocol", "bogus")
    assert code == 2 and "bogus" in stderr


def test_physics_robust_computes_the_columns_a_robust_dataset_holds(tiny_dataset, tmp_path, capsys):
    """--robust K on a plain dataset computes, for the replayed rows, the very robust columns
    that ``generate --robust K`` writes for them; on a robust dataset it reads them."""
    import numpy as np

    from affordgrasp.dataset.generate import generate
    from affordgrasp.dataset.manifest import read_manifest

    mesh = read_manifest(tiny_dataset)["objects"][0]["source"]
    robust_ds = tmp_path / "robust-ds"
    generate([mesh], 24, robust_ds, seed=2, workers=1, shard_size=12, hand="parallel_jaw", robust=2)
    common = ["--max-per-object", 2, "--workers", 1, "--robust", 2]
    code, stdout, _ = _run(capsys, tiny_dataset, "--out", tmp_path / "computed", *common)
    assert code == 0
    assert json.loads(stdout)["summary"]["robust"] == {"copies": 2, "source": "computed"}
    code, stdout, _ = _run(capsys, robust_ds, "--out", tmp_path / "read", *common)
    assert code == 0
    assert json.loads(stdout)["summary"]["robust"] == {"copies": 2, "source": "dataset"}
    computed, read = pq.read_table(tmp_path / "computed"), pq.read_table(tmp_path / "read")
    names = [c for c in read.column_names if c.startswith("robust_")]
    assert {"robust_hold", "robust_fc", "robust_pick-paper"} <= set(names)
    for c in names:
        a = np.asarray(computed.column(c).to_pylist(), dtype=float)
        b = np.asarray(read.column(c).to_pylist(), dtype=float)
        np.testing.assert_array_equal(a, b, err_msg=c)
    assert np.isfinite(computed.column("robust_fc").to_numpy()).all()
    # A resume with another K is refused (the plan records the computed robust settings).
    again = [*common[:-1], 3]
    code, _, stderr = _run(capsys, tiny_dataset, "--out", tmp_path / "computed", *again)
    assert code == 2 and "robust {" in stderr and "max_per_object" not in stderr
    # Another K than the dataset's is refused, naming the dataset's.
    code, _, stderr = _run(capsys, robust_ds, "--out", tmp_path / "x", "--robust", 3)
    assert code == 2 and "--robust 2" in stderr


def test_robust_of_rows_refuses_rows_that_do_not_simulate_to_their_grasp(tiny_dataset):
    """A stored grasp that its pregrasp no longer gives is refused, not scored as another."""
    import numpy as np
    import pyarrow as pa

    from affordgrasp.dataset import Dataset
    from affordgrasp.errors import DatasetError
    from affordgrasp.physics.run import _plan_rows, robust_of_rows

    dataset = Dataset.open(tiny_dataset)
    rows = _plan_rows(dataset, ("grasped",), None, 2)
    poses = np.asarray(rows.column("hand_pose").to_pylist(), dtype=float)
    poses[0, 3] += 1e-4  # 0.1 mm off along x
    i = rows.column_names.index("hand_pose")
    moved = rows.set_column(i, "hand_pose", pa.array(poses.tolist(), rows.schema.field(i).type))
    with pytest.raises(DatasetError, match="stored grasp"):
        robust_of_rows(moved, "parallel_jaw", {"block.stl": dataset.object("block.stl")}, 2)


def test_physics_trials_write_their_columns_cards_and_resume(tiny_dataset, tmp_path, capsys):
    out = tmp_path / "trials"
    args = [tiny_dataset, "--out", out, "--max-per-object", 2, "--shard-size", 1, "--workers", 1]
    code, stdout, _ = _run(capsys, *args, "--trials", "beat,cut,pick")
    assert code == 0
    doc = json.loads(stdout)
    assert set(doc["summary"]["trials"]) == {"beat", "cut", "pick"}
    table = pq.read_table(out).to_pandas()
    columns = {"strike_offset_m", "strike_nail_advance_m", "beat_ok", "stroke_offset_m"}
    assert columns | {"stroke_edge_thickness_m", "cut_ok", "pick_ok"} <= set(table.columns)
    assert (table["pick_ok"] == table["hold_ok"]).all()
    # rows with a use point get an outcome, the others null
    has_use = table["use_force"].notna()
    assert table.loc[has_use, "beat_ok"].notna().all()
    assert table.loc[~has_use, "beat_ok"].isna().all()
    cards = json.loads((out / "_physics.json").read_text())["trials"]
    assert {k: c["version"] for k, c in cards.items()} == {"beat": 2, "cut": 1, "pick": 1}
    assert cards["beat"]["settings"]["nail_force_n"] == 150.0
    # resumed with the same trials: nothing to do; with others: refused, naming them
    code, stdout, _ = _run(capsys, *args, "--trials", "beat,cut,pick")
    assert code == 0 and json.loads(stdout)["summary"]["shards_written"] == 0
    code, _, stderr = _run(capsys, *args, "--trials", "pick")
    assert code == 2 and "trials" in stderr
    code, _, stderr = _run(capsys, *args, "--trials", "chop")
    assert code == 2 and "chop" in stderr
    # the report judges p_T, the threshold task and the paper's formula against each trial
    report = tmp_path / "report"
    code, _, _ = _run(capsys, *args, "--trials", "beat,cut,pick", "--report", report)
    assert code == 0
    trials = json.loads((report / "report.json").read_text())["task_trials"]
    assert set(trials) == {"beat", "cut", "pick"}
    assert set(trials["beat"]["groups"]["all"]["auc"]) == {"beat", "beat-rules", "beat-paper"}
    assert trials["pick"]["groups"]["all"]["n"] == len(table)
    assert "Task trial `cut_ok`" in (report / "report.md").read_text()
    assert (report / "calibration_tasks.png").stat().st_size > 0
