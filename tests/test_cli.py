"""The command line: tables, one JSON document with --json, exit codes 0 / 2, Parquet rows."""

import json
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from affordgrasp.cli import main
from affordgrasp.columns import METRIC_COLUMNS

EXPECTED_COLUMNS = [
    "object", "object_hash", "sample", "seed", "p0", "use_dir", "status", "hand_pose", "joints",
    "contact_points", "contact_normals", "contact_mu", "contact_link", "use_point", "use_normal",
    "wrist_point", "wrist_axis",
]  # fmt: skip


def run_json(capsys, *argv):
    code = main([*argv, "--json"])
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_objects_lists_every_family(capsys):
    code, doc = run_json(capsys, "objects")
    assert code == 0
    names = {f["name"] for f in doc["families"]}
    assert {
        "hammer",
        "knife",
        "meat_cleaver",
        "axe",
        "screwdriver",
        "spatula",
        "sword",
        "dagger",
        "bottle",
        "wine_glass",
        "tumbler",
        "mug",
        "ice_cream_cone",
    } <= names


def test_objects_export_writes_a_mesh(tmp_path, capsys):
    path = tmp_path / "knife.obj"
    assert main(["objects", "export", "knife", "--seed", "3", "-o", str(path)]) == 0
    assert path.stat().st_size > 1000
    assert "knife:3" in capsys.readouterr().out


def test_simulate_summarises_and_writes_the_spec_columns(tmp_path, capsys):
    out = tmp_path / "sims.parquet"
    code, doc = run_json(capsys, "simulate", "hammer", "--samples", "40", "--out", str(out))
    assert code == 0
    assert sum(v["count"] for v in doc["status"].values()) == 40
    assert doc["grasps_per_second_per_core"] > 0
    table = pq.read_table(out)
    assert table.num_rows == 40
    assert set(EXPECTED_COLUMNS) <= set(table.column_names)
    assert table.column("sample").to_pylist() == list(range(40))


def test_evaluate_reports_tasks_and_metrics(tmp_path, capsys):
    out = tmp_path / "phi.parquet"
    code, doc = run_json(
        capsys, "evaluate", "knife", "--samples", "40", "--task", "pick", "--out", str(out)
    )
    assert code == 0
    assert set(doc["best"]) == {"pick"}
    assert 0 <= doc["force_closure_fraction"] <= 1
    table = pq.read_table(out)
    assert set(EXPECTED_COLUMNS) | set(METRIC_COLUMNS) <= set(table.column_names)
    # the rate leaves out the one-time costs, and says what they were
    assert set(doc["one_time_seconds"]) == {"kernels", "prepare"}


def test_summary_line_names_the_one_time_costs(capsys):
    assert main(["evaluate", "knife", "--samples", "10", "--task", "pick"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "grasps/s on one core" in text
    assert "one-time costs, not counted: kernels" in text and "object preparation" in text


def test_same_seed_same_rows(tmp_path):
    paths = [tmp_path / "a.parquet", tmp_path / "b.parquet"]
    for p in paths:
        assert main(["evaluate", "mug", "--samples", "25", "--seed", "4", "--out", str(p)]) == 0
    # Same seed, same bytes (NaN use metrics included, which Table.equals would call unequal).
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_tasks_lists_thresholds(capsys):
    code, doc = run_json(capsys, "tasks")
    assert code == 0
    beat = doc["tasks"]["beat-rules"]["thresholds"]
    assert beat["default"]["tau_eps"] == 0.014 and beat["extra-robustness"]["tau_eps"] == 0.024
    assert beat["paper"]["tau_eps"] == 0.3 and beat["paper-extra-robustness"]["tau_eps"] == 0.5


@pytest.mark.parametrize(
    "argv, message",
    [
        (["simulate", "no_such_thing"], "unknown object"),
        (["simulate", "knife:x"], "seed"),
        (["simulate", "knife", "--samples", "0"], "--samples"),
        (["evaluate", "knife", "--task", "juggle"], "unknown task"),
        (["evaluate", "knife", "--mode", "reckless"], "mode"),
        (["simulate", "knife", "--hand", "shadow"], "unknown hand"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_console_script_runs():
    result = subprocess.run(
        [sys.executable, "-m", "affordgrasp.cli", "objects", "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert result.returncode == 0
    json.loads(result.stdout)


def test_unwritable_output_is_refused_before_the_work(tmp_path, capsys):
    assert main(["simulate", "knife", "--samples", "5", "--out", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
    missing = tmp_path / "no" / "such" / "x.parquet"
    assert main(["evaluate", "knife", "--samples", "5", "--out", str(missing)]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_hand_option_takes_a_hand_file(tmp_path, capsys):
    import dataclasses

    from affordgrasp.hands import get_hand, save_hand

    jaw = dataclasses.replace(get_hand("parallel_jaw"), name="my_jaw")
    path = save_hand(jaw, tmp_path / "my_jaw.toml")
    out = tmp_path / "sims.parquet"
    code, doc = run_json(
        capsys, "simulate", "mug", "--samples", "8", "--hand", str(path), "--out", str(out)
    )
    assert code == 0, doc
    table = pq.read_table(out)
    assert set(table.column("hand").to_pylist()) == {"my_jaw"}
    assert {len(j) for j in table.column("joints").to_pylist()} == {len(jaw.dofs)}
    assert main(["simulate", "mug", "--samples", "2", "--hand", str(tmp_path / "no.toml")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_resuming_with_another_hand_of_the_same_name_is_refused(tmp_path, capsys):
    import dataclasses

    from affordgrasp.hands import get_hand, save_hand

    custom = save_hand(
        dataclasses.replace(get_hand("parallel_jaw"), name="barrett"), tmp_path / "hand.json"
    )
    out = tmp_path / "data"
    argv = ["generate", "mug", "--samples", "4", "--workers", "1", "--out", str(out)]
    assert main([*argv, "--hand", str(custom)]) == 0
    capsys.readouterr()
    assert main([*argv, "--hand", "barrett"]) == 2
    err = capsys.readouterr().err
    assert "--hand 'barrett' is not the hand the dataset" in err
    assert "same name, different" in err and "_manifest.json" in err
    assert main([*argv, "--hand", str(out / "_manifest.json")]) == 0


def test_materials_flag_gives_the_families_their_materials_mass(tmp_path, capsys):
    # default: uniform unit density, as in the paper; --materials: per-part materials
    paths = {}
    for flag in ((), ("--materials",)):
        out = tmp_path / f"rows{len(flag)}.parquet"
        argv = ["evaluate", "hammer", "--samples", "12", "--seed", "1", "--out", str(out)]
        assert main([*argv, *flag]) == 0
        paths[flag] = pq.read_table(out).to_pandas()
    capsys.readouterr()
    uniform, materials = paths[()], paths[("--materials",)]
    assert (uniform["status"] == materials["status"]).all()
    both = uniform["inertia"].notna() & materials["inertia"].notna()
    assert both.any()
    # steel and wood against 1 kg/m³: the same grasps, far heavier
    assert (materials["inertia"][both] > 300 * uniform["inertia"][both]).all()


def test_materials_flag_refused_for_a_mesh_file(tmp_path, capsys):
    mesh = tmp_path / "box.stl"
    import trimesh

    trimesh.creation.box((0.05, 0.03, 0.02)).export(mesh)
    code = main(["evaluate", str(mesh), "--samples", "4", "--materials"])
    err = capsys.readouterr().err
    assert code == 2
    assert "mesh file" in err and "Drop the option" in err


def test_a_scan_file_open_at_its_base_is_evaluated(tmp_path, capsys, caplog):
    # A scan whose base was never seen: the rim left by cutting the foot off a wine glass
    # was refused before its jagged edge was capped with a fan.
    import trimesh

    from affordgrasp.objects import load_object

    glass = load_object("wine_glass:0")
    mesh = trimesh.Trimesh(glass.vertices, glass.faces, process=False)
    keep = mesh.triangles_center[:, 2] > mesh.bounds[0, 2] + 0.002
    cut = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    cut.remove_unreferenced_vertices()
    path = tmp_path / "glass_open.ply"
    cut.export(path)
    with caplog.at_level("WARNING"):
        assert main(["evaluate", str(path), "--samples", "8", "--task", "pick"]) == 0
    assert capsys.readouterr().out.startswith("glass_open.ply: 8 grasps")
    assert "glass_open.ply was repaired: capped 1 hole" in caplog.text


def test_tables_to_a_pipe_keep_whole_cells(capsys, monkeypatch):
    from affordgrasp.commands.output import Output

    monkeypatch.delenv("COLUMNS", raising=False)
    out = Output()  # stdout is captured: not a terminal
    out.table("wide", ["name", "value", "seed"], [["beat-paper" * 12, 8.702e-05, 2**62]])
    text = capsys.readouterr().out
    assert "beat-paper" * 12 in text and "8.702e-05" in text and str(2**62) in text
