"""The validation study and ``affordgrasp validate`` on tiny searches (docs/validation.md §5)."""

import json

import pyarrow.parquet as pq
import pytest

from affordgrasp import validation as vt
from affordgrasp.cli import main
from affordgrasp.errors import InputError
from affordgrasp.objects import load_object

TINY = ["--tasks", "pick", "--families", "hammer", "--grasps", "150", "--uses", "200"]


@pytest.fixture(scope="module")
def command_run(tmp_path_factory):
    """``affordgrasp validate --json`` on one hammer, tiny searches: (report, folder)."""
    out = tmp_path_factory.mktemp("validate") / "out"
    code = main(["validate", "-o", str(out), *TINY, "--budget", "100", "--json"])
    assert code == 0
    return out


def test_command_writes_the_report_it_prints(command_run, capsys):
    report = json.loads((command_run / "validation.json").read_text())
    assert list(report["tasks"]) == ["pick"]
    entry = report["tasks"]["pick"]["families"]["hammer"]
    assert entry["seeds"] == [0] and set(report["tasks"]["pick"]["families"]) == {"hammer"}
    hits, judged = entry["brute_force"][0]
    assert 0 <= hits <= judged <= 10 and judged >= 1  # the searches found grasps
    summary = report["tasks"]["pick"]["summary"]["brute_force"]
    assert (summary["hits"], summary["top_grasps"]) == (hits, judged)
    assert report["settings"]["grasps"] == 150 and report["settings"]["figures"] is False


def test_command_judges_the_rows_of_the_searches(command_run):
    # the report's verdicts are the judges' verdicts on the top rows the searches kept, and
    # the brute force's rows are those of the package's brute force on the same grasps
    report = json.loads((command_run / "validation.json").read_text())
    entry = report["tasks"]["pick"]["families"]["hammer"]
    hammer = load_object("hammer:0")
    com = hammer.mass.center_of_mass
    cache = command_run / "cache"
    for method, suffix in (("brute_force", "bf"), ("optimizer", "opt")):
        top = pq.read_table(cache / f"top_pick_hammer_0_{suffix}.parquet")
        ok = vt.judge("pick", "hammer", top, com)
        assert entry[method] == [[sum(ok), len(ok)]]
        assert entry["top1"][method] == [ok[0] if ok else None]
    table = vt.grasp_table(cache, "hammer", 0, 150)
    assert table.num_rows == 150
    found = vt.brute_force(hammer, "pick", table, uses=200, top=10)
    top = pq.read_table(cache / "top_pick_hammer_0_bf.parquet")
    assert found.table.column("p0").to_pylist() == top.column("p0").to_pylist()
    assert entry["candidates"] == [found.candidates]


def test_same_settings_same_numbers(command_run, tmp_path):
    # a fresh cache: every grasp simulated again, every search run again
    settings = vt.ValidationSettings(
        seeds=1,
        grasps=150,
        uses=200,
        budget=100,
        tasks=("pick",),
        families=("hammer",),
        figures=False,
    )
    seen = []
    report = vt.validate_tasks(
        settings, tmp_path / "o", cache=tmp_path / "c", on_object=lambda *a: seen.append(a[:3])
    )
    assert seen == [("pick", "hammer", 0)] and settings.steps == 1
    first = json.loads((command_run / "validation.json").read_text())
    assert report["tasks"] == first["tasks"]
    assert json.loads((tmp_path / "o" / "validation.json").read_text())["tasks"] == first["tasks"]


def test_quick_default_and_full_presets(capsys):
    from affordgrasp.cli import build_parser
    from affordgrasp.commands.validate import settings_of

    parser = build_parser()
    quick = settings_of(parser.parse_args(["validate", "-o", "x"]))
    assert (quick.seeds, quick.grasps, quick.families, quick.figures) == (
        1,
        100,
        ("hammer", "knife"),
        False,
    )
    assert quick.steps == 4  # cut: knife; beat: hammer; pick: hammer, knife
    full = settings_of(parser.parse_args(["validate", "-o", "x", "--full", "--grasps", "16000"]))
    assert (full.seeds, full.grasps, full.uses, full.families, full.figures) == (
        5,
        16000,
        4000,
        (),
        True,
    )
    assert full.steps == 5 * sum(len(f) for f in vt.TASK_FAMILIES.values())


@pytest.mark.parametrize(
    "changes, fragment",
    [
        ({"seeds": 0}, "seeds must be a positive integer, got 0"),
        ({"top": True}, "top must be a positive integer, got True"),
        ({"grasps": 50, "also_grasps": 50}, "also_grasps must lie in [0, grasps) = [0, 50)"),
        ({"refine": -0.1}, "refine must lie in [0, 1), got -0.1"),
        ({"tasks": ()}, "tasks names no task"),
        ({"tasks": ("pick",), "families": ("hammer", "anvil")}, "has 'anvil'"),
        ({"optimizer": False, "brute_force": False}, "nothing to run"),
    ],
)
def test_settings_refused_before_any_work(changes, fragment, tmp_path):
    settings = vt.ValidationSettings(**changes)
    with pytest.raises(InputError, match=None) as err:
        vt.validate_tasks(settings, tmp_path / "out")
    assert fragment in str(err.value)
    assert not (tmp_path / "out").exists()


def test_figures_are_the_modes_of_each_task_and_of_the_knife(tmp_path):
    settings = vt.ValidationSettings(
        seeds=1,
        grasps=30,
        uses=30,
        tasks=("beat",),
        families=("hammer",),
        optimizer=False,
        cell_px=48,
    )
    vt.validate_tasks(settings, tmp_path / "o", cache=tmp_path / "c")
    names = sorted(p.name for p in (tmp_path / "o").iterdir())
    assert names == [
        "modes_knife.json",
        "validation.json",
        "validation_beat.png",
        "validation_modes_knife.png",
    ]
    for png in ("validation_beat.png", "validation_modes_knife.png"):
        assert (tmp_path / "o" / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    modes = json.loads((tmp_path / "o" / "modes_knife.json").read_text())
    assert sorted(modes) == sorted(f"{t}/{m}" for t in ("beat", "cut") for m in vt.MODES)
    # the figures drew the first families of the task from the same cached grasp tables
    cached = sorted(p.name for p in (tmp_path / "c").glob("*_0_30_unit.parquet"))
    assert cached == [f"{f}_0_30_unit.parquet" for f in ("axe", "hammer", "knife", "meat_cleaver")]


def test_command_prints_a_table_per_family_and_task(tmp_path, capsys):
    argv = ["validate", "-o", str(tmp_path / "o"), "--tasks", "beat", "--families", "hammer"]
    assert main([*argv, "--grasps", "20", "--uses", "20", "--no-optimizer"]) == 0
    out = capsys.readouterr().out
    assert "top-10 grasps judged right" in out and "brute force" in out
    header = next(line for line in out.splitlines() if "┃" in line and "family" in line)
    assert "brute force" in header and "optimizer" not in header  # --no-optimizer
    assert f"report: {tmp_path / 'o'}/validation.json" in out.replace("\n", "")
    rows = [line for line in out.splitlines() if "beat" in line and "│" in line]
    assert len(rows) == 2  # hammer, then all
