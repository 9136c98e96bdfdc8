"""Options every command shares: --size-m / --units on each command that takes an object,
-v after the subcommand, and did-you-mean for family, task and mode names."""

from __future__ import annotations

import json

import pytest
import trimesh

from affordgrasp.cli import main


@pytest.fixture(scope="module")
def cube_mm(tmp_path_factory):
    """A 100 x 40 x 30 mm box written in millimetres, as CAD tools export."""
    path = tmp_path_factory.mktemp("mm") / "cube_mm.stl"
    trimesh.creation.box((100.0, 40.0, 30.0)).export(path)
    return path


def _err(capsys) -> str:
    return capsys.readouterr().err


def test_millimetre_mesh_is_refused_with_the_fix_by_every_command(cube_mm, tmp_path, capsys):
    for argv in (
        ["evaluate", str(cube_mm), "--samples", "4"],
        ["simulate", str(cube_mm), "--samples", "4"],
        ["generate", str(cube_mm), "--samples", "4", "--out", str(tmp_path / "d")],
        ["optimize", str(cube_mm), "--task", "pick", "--budget", "8"],
        ["show", str(cube_mm), "--task", "pick", "--samples", "4", "-o", str(tmp_path / "s")],
        ["plots", str(cube_mm), "--samples", "4", "-o", str(tmp_path / "p")],
        ["objects", "export", str(cube_mm), "-o", str(tmp_path / "x.obj")],
    ):
        assert main(argv) == 2, argv
        err = _err(capsys)
        assert err.count("\n") == 1, err
        assert "100 m long" in err and "--units mm" in err, err
    assert not (tmp_path / "d").exists()


def test_units_and_size_m_are_accepted_by_every_command_that_takes_an_object(
    cube_mm, tmp_path, capsys
):
    out = tmp_path / "box.obj"
    assert main(["objects", "export", str(cube_mm), "--units", "mm", "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["extent_m"] == pytest.approx([0.1, 0.04, 0.03])
    assert main(["objects", "export", str(cube_mm), "--size-m", "0.2", "-o", str(out)]) == 0
    assert trimesh.load(out).extents.max() == pytest.approx(0.2)

    data = tmp_path / "data"
    gen = ["generate", str(cube_mm), "knife", "--samples", "6", "--units", "mm"]
    gen += ["--out", str(data), "--workers", "1", "--no-metrics"]
    assert main(gen) == 0
    manifest = json.loads((data / "_manifest.json").read_text())
    # The resume command recorded in the manifest keeps the unit.
    assert manifest["command"][manifest["command"].index("--units") + 1] == "mm"
    # Resuming with another unit is another dataset.
    gen_cm = [a if a != "mm" else "cm" for a in gen]
    assert main(gen_cm) == 2
    assert "different meshes" in _err(capsys)

    opt = ["optimize", str(cube_mm), "--task", "pick", "--budget", "8", "--population", "4"]
    assert main([*opt, "--units", "mm", "--no-baseline", "--workers", "1"]) == 0
    show = ["show", str(cube_mm), "--size-m", "0.1", "--task", "pick", "--samples", "8"]
    assert main([*show, "--top", "1", "--cell", "64", "--no-html", "-o", str(tmp_path / "s")]) == 0
    assert (tmp_path / "s" / "best_grasps.png").exists()
    plots = ["plots", str(data), "--mesh", str(cube_mm), "--units", "mm", "--no-tasks"]
    assert main([*plots, "-o", str(tmp_path / "p")]) == 0
    capsys.readouterr()


def test_units_on_families_only_is_refused(capsys):
    assert main(["objects", "export", "knife", "--units", "mm", "-o", "k.obj"]) == 2
    assert "built-in family" in _err(capsys)
    assert main(["generate", "knife", "mug", "--size-m", "0.1", "--samples", "2", "--out", "x"])
    assert "built-in families" in _err(capsys)


@pytest.mark.parametrize(
    "argv, hint",
    [
        (["evaluate", "hamer", "--samples", "2"], "did you mean 'hammer'?"),
        (["evaluate", "scredriver:3", "--samples", "2"], "did you mean 'screwdriver'?"),
        (["evaluate", "knife", "--samples", "2", "--task", "pik"], "did you mean 'pick'?"),
        (["evaluate", "knife", "--samples", "2", "--mode", "no-robust"], "'no-robustness'"),
        (["show", "knife", "--task", "beat,cutt", "-o", "x"], "did you mean 'cut'"),
        (["objects", "export", "knfe", "-o", "k.obj"], "did you mean 'knife'?"),
    ],
)
def test_did_you_mean(argv, hint, capsys):
    code = main(argv)
    err = _err(capsys)
    assert code == 2
    assert hint in err, err
    assert err.count("\n") == 1


def test_no_suggestion_for_a_far_name(capsys):
    assert main(["evaluate", "zzzzqqq", "--samples", "2"]) == 2
    assert "did you mean" not in _err(capsys)


def test_verbose_is_accepted_after_the_subcommand(capsys):
    assert main(["tasks", "-v", "--json"]) == 0
    json.loads(capsys.readouterr().out)
    assert main(["objects", "list", "--verbose", "--json"]) == 0
    json.loads(capsys.readouterr().out)
    assert main(["-v", "tasks"]) == 0


def test_tables_print_units_and_the_edge_angle_in_degrees(capsys):
    import math
    import re

    from affordgrasp.commands.best import METRICS_SHOWN, metric_cells, metric_headings

    argv = ["evaluate", "knife", "--samples", "300", "--mode", "no-robustness", "--task", "pick"]
    assert main(argv) == 0
    table = capsys.readouterr().out
    assert "use_edge_angle (°)" in table and "use_force (N)" in table
    assert "inertia (kg·m²)" in table and "hold_effort_sum (N)" in table
    shown = float(re.search(r"use_edge_angle \(°\)\s*│\s*([-\d.e+]+)", table).group(1))
    assert main([*argv, "--json"]) == 0
    radians = json.loads(capsys.readouterr().out)["best"]["pick"]["metrics"]["use_edge_angle"]
    assert shown == pytest.approx(math.degrees(radians), rel=1e-3)  # JSON stays in SI

    headings = metric_headings(METRICS_SHOWN)
    assert "edge angle (°)" in headings and "ΣE_h (N)" in headings and "ε" in headings
    cells = metric_cells({"use_edge_angle": math.pi / 4}, [("edge angle", "use_edge_angle")])
    assert cells == [pytest.approx(45.0)]


def test_evaluate_shows_progress_as_it_goes(monkeypatch, capsys):
    from contextlib import contextmanager

    from affordgrasp.commands.output import Output

    steps = []

    @contextmanager
    def progress(self, description, total):
        steps.append(("start", total))
        yield lambda n=1: steps.append(("advance", n))

    monkeypatch.setattr(Output, "progress", progress)
    assert main(["evaluate", "knife", "--samples", "600", "--task", "pick"]) == 0
    capsys.readouterr()
    advances = [n for kind, n in steps if kind == "advance"]
    assert steps[0] == ("start", 600)
    assert len(advances) >= 3 and sum(advances) == 600


def test_tasks_table_prints_thresholds_in_their_units(capsys):
    assert main(["tasks"]) == 0
    table = capsys.readouterr().out
    assert "tau_angle=45°" in table  # stored as 0.785398 rad
    assert "tau_clear=35 mm" in table
    assert "0.785398" not in table
    assert "tau_ug=3e+04 m⁻²" in table
    assert "hold_max=250 N" in table
    assert main(["tasks", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    cut = doc["tasks"]["cut-dihedral"]["thresholds"]["default"]
    assert cut["tau_angle"] == pytest.approx(0.785398)
