"""Hostile command-line options, every command: each is refused with exit 2 and one line.

A sweep of option values a user can type by mistake (zero, negative, NaN, huge, wrong type,
unknown names, files where folders belong and the reverse, foreign files). Each case must
end with exit 2 and a single line ``affordgrasp COMMAND: error: ...`` containing the given
fragment, before any work: no traceback, no "internal error", and none of the outputs it
names created. The mesh-file corpus and the costlier cases live in
``test_hostile_inputs.py``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from affordgrasp.cli import main

# (argv, fragment of the message); {ds} a small dataset, {d} a scratch folder, {txt} a text
# file, {empty} an empty folder, {bad} random bytes named .safetensors.
CASES = [
    (["evaluate", "knife", "--samples", "0"], "--samples must be a positive integer, got 0"),
    (["evaluate", "knife", "--samples", "-3"], "--samples must be a positive integer, got -3"),
    (["evaluate", "knife", "--samples", "abc"], "argument --samples: invalid int value"),
    (["evaluate", "knife", "--samples", "1e3"], "argument --samples: invalid int value"),
    (
        ["evaluate", "knife", "--samples", "3", "--seed", "-1"],
        "--seed must be an integer in [0, 2**63 - 1], got -1",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--seed", "1180591620717411303424"],
        "--seed must be an integer in [0, 2**63 - 1]",
    ),
    (
        ["evaluate", "knfie", "--samples", "3"],
        "?): it is not a built-in family and no file exists at that p",
    ),
    (["evaluate", "knife:abc", "--samples", "3"], "must be a non-negative integer (e.g"),
    (["evaluate", "knife:-1", "--samples", "3"], "must be a non-negative integer (e.g"),
    (["evaluate", "knife:3~scan:xyz", "--samples", "3"], "with a non-negative integer seed"),
    (
        ["evaluate", "knife~foo", "--samples", "3"],
        "?): it is not a built-in family and no file exists at that p",
    ),
    (["evaluate", "knife~scan:-5", "--samples", "3"], "with a non-negative integer seed"),
    (["evaluate", "", "--samples", "3"], "the object spec is empty; give a family name (e.g"),
    (
        ["evaluate", "knife", "--samples", "3", "--task", "nosuch"],
        "available tasks: beat, beat-paper, cut, cut-dihedral, cut-ug",
    ),
    (["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/missing.toml"], "does not exist"),
    (
        ["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/bad.toml"],
        "at the end of a table declaration (at line 1, column 7",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/empty.toml"],
        "has no [tasks.<name>] tables",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/weird.toml"],
        "] (allowed: value, requires, thresholds, modes, description",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--hand", "robotiq"],
        "hands: barrett, parallel_jaw (or a .json/.toml hand file",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--units", "parsec"],
        "is a built-in family, made at its real size in metres; size ",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--size-m", "-1"],
        "is a built-in family, made at its real size in metres; size ",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--size-m", "nan"],
        "is a built-in family, made at its real size in metres; size ",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--size-m", "inf"],
        "is a built-in family, made at its real size in metres; size ",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--size-m", "0.2", "--units", "mm"],
        "is a built-in family, made at its real size in metres; size ",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--robust", "-1"],
        "--robust must be an integer >= 0 (copies per grasp), got -1",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--robust", "abc"],
        "argument --robust: invalid int value",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--metrics", "+foo"],
        "is not one of +volume (the paper's metric vector is always c",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--metrics", "volume"],
        "is not one of +volume (the paper's metric vector is always c",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--mode", "nosuch"],
        "modes: default, no-robustness, extra-robustness, paper, pape",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--out", "{txt}/x.parquet"],
        "is a file, not a folder",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--out", "{d}"],
        "is a directory; give a file name inside it",
    ),
    (
        ["evaluate", "{txt}", "--samples", "3"],
        "supported formats: .glb, .gltf, .obj, .off, .ply, .stl",
    ),
    (["evaluate", "{empty}", "--samples", "3"], "is not a file; pass a mesh file"),
    (
        ["evaluate", "{bad}", "--samples", "3"],
        "supported formats: .glb, .gltf, .obj, .off, .ply, .stl",
    ),
    (["simulate", "knife", "--samples", "0"], "--samples must be a positive integer, got 0"),
    (
        ["generate", "knife", "--samples", "0", "--out", "{d}/g0"],
        "--samples must be an integer >= 1, got 0",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g1", "--shard-size", "0"],
        "--shard-size must be an integer >= 1, got 0",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g2", "--workers", "0"],
        "--workers must be at least 1, got 0",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g3", "--workers", "-1"],
        "--workers must be at least 1, got -1",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g4", "--chunk-size", "0"],
        "--chunk-size must be an integer >= 1, got 0",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{txt}"],
        "is a file, not a directory; give a directory",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{ds}"],
        "holds a dataset made by a different command (samples 48 ther",
    ),
    (
        ["generate", "knife:1", "--samples", "48", "--out", "{ds}", "--seed", "9"],
        "holds a dataset made by a different command (seed 0 there vs",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g5", "--address", "x:1"],
        "--address is for the Ray engine; set engine=",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g7", "--no-metrics", "--robust", "3"],
        "--robust needs the metric columns; drop --no-metrics or --ro",
    ),
    (
        ["best", "{empty}", "--task", "pick"],
        "is not an affordgrasp dataset (no _manifest.json); give the ",
    ),
    (["best", "{txt}", "--task", "pick"], "does not exist; create one with"),
    (
        ["best", "{ds}", "--task", "nosuch"],
        "available tasks: beat, beat-paper, cut, cut-dihedral, cut-ug",
    ),
    (["best", "{ds}", "--task", "pick", "--top", "0"], "--top must be a positive integer, got 0"),
    (["best", "{ds}", "--task", "pick", "--top", "-2"], "--top must be a positive integer, got -2"),
    (["best", "{ds}", "--task", "pick", "--object", "mug"], "is not in dataset"),
    (["best", "{ds}", "--task", "pick", "--threshold", "foo=1"], "has no threshold"),
    (
        ["best", "{ds}", "--task", "pick", "--threshold", "epsilon=abc"],
        "must be NAME=VALUE with a number, e.g. tau_eps=0.1",
    ),
    (
        ["best", "{ds}", "--task", "pick", "--threshold", "epsilon=nan"],
        "must be NAME=VALUE with a number, e.g. tau_eps=0.1",
    ),
    (
        ["best", "{ds}", "--task", "pick", "--robust", "3"],
        "has no robust columns; generate it with --robust K",
    ),
    (["best", "{d}/nonexist", "--task", "pick"], "does not exist; create one with"),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "0"],
        "--budget must be a positive integer, got 0",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "-1"],
        "--budget must be a positive integer, got -1",
    ),
    (
        ["optimize", "knife", "--task", "nosuch", "--budget", "20"],
        "available tasks: beat, beat-paper, cut, cut-dihedral, cut-ug",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--restarts", "0"],
        "--restarts must be a positive integer, got 0",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--refine", "2"],
        "--refine must be a share in [0, 1), got 2.0",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--refine", "-0.5"],
        "--refine must be a share in [0, 1), got -0.5",
    ),
    (
        ["show", "{ds}", "--task", "nosuch", "-o", "{d}/s2"],
        "available tasks: beat, beat-paper, cut, cut-dihedral, cut-ug",
    ),
    (
        ["show", "{ds}", "--task", "pick", "-o", "{txt}"],
        "is a file, not a directory; give a directory",
    ),
    (
        ["show", "{ds}", "--task", "pick", "--top", "0", "-o", "{d}/s3"],
        "--top must be at least 1, got 0",
    ),
    (
        ["show", "{ds}", "--task", "pick", "--cell", "0", "-o", "{d}/s4"],
        "--cell must be between 64 and 2048 pixels, got 0",
    ),
    (
        ["show", "{ds}", "--task", "pick", "--grasp-size", "-1", "-o", "{d}/s5"],
        "--grasp-size must be between 64 and 2048 pixels, got -1",
    ),
    (["plots", "{empty}", "-o", "{d}/p1"], "give a dataset directory written by"),
    (["plots", "{ds}", "-o", "{d}/p2", "--bins", "0"], "--bins must be between 5 and 500, got 0"),
    (["plots", "{ds}", "-o", "{d}/p3", "--bins", "-4"], "--bins must be between 5 and 500, got -4"),
    (
        ["physics", "{ds}", "--out", "{d}/ph2", "--timestep", "nan"],
        "physics setting timestep must be a finite number, got nan",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph4", "--load-factor", "-1"],
        "physics setting load_factor must be > 0, got -1.0",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph5", "--density", "0"],
        "physics setting density must be > 0, got 0.0",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph6", "--grip-torque", "inf"],
        "physics setting grip_torque must be a finite number, got inf",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph7", "--coacd-threshold", "0"],
        "physics setting coacd_threshold must be > 0, got 0.0",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph8", "--coacd-max-hulls", "-1"],
        "physics setting coacd_max_hulls must be > 0, got -1",
    ),
    (
        ["physics", "{empty}", "--out", "{d}/ph9"],
        "is not an affordgrasp dataset (no _manifest.json); give the ",
    ),
    (["physics", "{ds}", "--out", "{txt}"], "is a file, not a directory; give a directory"),
    (["physics", "{ds}", "--out", "{d}/ph10", "--object", "mug"], "is not in dataset"),
    (
        ["physics", "{ds}", "--out", "{d}/ph11", "--shard-size", "0"],
        "--shard-size must be a positive integer, got 0",
    ),
    (["depth", "knife", "--sample", "-1", "-o", "{d}/d1.png"], "--sample must be >= 0, got -1"),
    (
        ["depth", "knife", "--size", "0", "-o", "{d}/d3.png"],
        "camera size must be an integer >= 2, got 0",
    ),
    (
        ["depth", "knife", "--fov", "0", "-o", "{d}/d5.png"],
        "camera field of view must be in (0, 180) degrees, got 0.0",
    ),
    (
        ["depth", "knife", "--fov", "200", "-o", "{d}/d6.png"],
        "camera field of view must be in (0, 180) degrees, got 200.0",
    ),
    (
        ["depth", "knife", "--p0", "1,2,3", "-o", "{d}/d7.png"],
        "--p0 needs six numbers (u1,u2,u3,u4,u5,s), got 3",
    ),
    (
        ["depth", "knife", "--p0", "nan,0,0,0,0,0", "-o", "{d}/d8.png"],
        "pregrasp row 0, parameter 0 is nan: pregrasps must be finite",
    ),
    (
        ["depth", "knife", "--p0", "9,9,9,9,9,9", "-o", "{d}/d9.png"],
        "pregrasp row 0, parameter 0 is 9.0: pregrasps must be finite",
    ),
    (["depth", "knife", "--sample", "1", "-o", "{d}/d10.xyz"], "must end in .png or .npy"),
    (
        ["depth", "knife", "--sample", "1", "--scale", "0", "-o", "{d}/d11.png"],
        "--scale must be >= 1, got 0",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m1.safetensors", "--epochs", "0"],
        "--epochs must be >= 1, got 0",
    ),
    (
        ["train", "{empty}", "-o", "{d}/m3.safetensors"],
        "is not an affordgrasp dataset (no _manifest.json); give the ",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m4.safetensors", "--batch-size", "0"],
        "--batch-size must be >= 1, got 0",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m5.safetensors", "--test-families", "nosuch"],
        "a split by object needs at least 2 instances of some family ",
    ),
    (["train", "{ds}", "-o", "{d}/m6.txt"], "must end in .safetensors"),
    (
        ["train", "{ds}", "-o", "{d}/m7.safetensors", "--members", "0"],
        "--members must be >= 1, got 0",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m8.safetensors", "--max-minutes", "-1"],
        "--max-minutes must be a finite number in [0.01, 10080], got -1.0",
    ),
    (
        ["predict", "{d}/nonexist.safetensors", "{ds}", "--out", "{d}/pr1.parquet"],
        "does not exist; train one with",
    ),
    (
        ["predict", "{bad}", "{ds}", "--out", "{d}/pr2.parquet"],
        "is not a safetensors model file: Error while deserializing h",
    ),
    (
        ["predict", "{txt}", "{ds}", "--out", "{d}/pr3.parquet"],
        "is not a safetensors model file: Error while deserializing h",
    ),
    (
        ["model-eval", "{bad}", "{ds}"],
        "is not a safetensors model file: Error while deserializing h",
    ),
    (["model-eval", "shipped", "{ds}", "--max-rows", "0"], "does not exist; train one with"),
    (["model-eval", "shipped", "{empty}"], "does not exist; train one with"),
    (["plan", "knife", "--candidates", "0"], "candidates must be >= 1, got 0"),
    (["plan", "knife", "--candidates", "-1"], "candidates must be >= 1, got -1"),
    (["plan", "knife", "--candidates", "1000000000"], "would hold about"),
    (["plan", "knife", "--model", "{d}/nonexist.safetensors"], "does not exist; train one with"),
    (
        ["plan", "knife", "--model", "{bad}"],
        "is not a safetensors model file: Error while deserializing h",
    ),
    (
        ["plan", "knife", "--task", "nosuch"],
        "available tasks: beat, beat-paper, cut, cut-dihedral, cut-ug",
    ),
    (["plan", "knife", "--threshold", "2"], "threshold must be a probability in [0, 1], got 2.0"),
    (["plan", "knfie"], "?): it is not a built-in family and no file exists at that p"),
    (
        ["objects", "export", "knife", "{d}/o1.xyz"],
        "the following arguments are required: -o/--out",
    ),
    (
        ["objects", "export", "nosuch", "{d}/o2.stl"],
        "the following arguments are required: -o/--out",
    ),
    (["objects", "nosuchaction"], "argument ACTION: invalid choice"),
    (
        ["tasks", "--tasks-file", "{d}/bad.toml"],
        "at the end of a table declaration (at line 1, column 7",
    ),
    (
        ["tasks", "--tasks-file", "{d}/weird.toml"],
        "] (allowed: value, requires, thresholds, modes, description",
    ),
    (["nosuchcommand"], "argument COMMAND: invalid choice"),
    (
        ["model-eval", "default", "{ds}", "--draws", "0"],
        "--candidates and --draws must be >= 1, got 64 and 0",
    ),
    (
        ["model-eval", "default", "{ds}", "--candidates", "0"],
        "--candidates and --draws must be >= 1, got 0 and 20",
    ),
    (
        ["model-eval", "default", "{ds}", "--threshold", "-1"],
        "--threshold must be a probability in [0, 1], got -1.0",
    ),
    (
        ["model-eval", "default", "{ds}", "--plots", "{txt}"],
        "is a file, not a directory; give a directory",
    ),
    (
        ["model-eval", "default", "{ds}", "--max-rows", "-5"],
        "--max-rows must be 0 (every row) or >= 2, got -5",
    ),
    (["predict", "default", "{ds}", "--out", "{d}/pr.csv"], "must end in .parquet"),
    (["physics", "{ds}", "--out", "{d}/ph19", "--workers", "0"], "--workers must be a positive"),
    (
        ["physics", "{ds}", "--out", "{d}/ph13", "--report", "{txt}"],
        "is a file, not a directory; give a directory",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph15", "--seed", "-1"],
        "physics setting seed must be > 0, got -1",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph16", "--friction-margin", "45"],
        "physics setting friction_margin_deg = 45.0 ° is outside its physical range [0, 30]",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph17", "--friction-margin", "nan"],
        "physics setting friction_margin_deg must be a finite number, got nan",
    ),
    (
        ["physics", "{ds}", "--out", "{d}/ph18", "--robust", "-1"],
        "--robust must be an integer >= 0 (copies per grasp), got -1",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m9.safetensors", "--split", "family"],
        "needs --test-families, the families to hold out (e.g. axe,mu",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m10.safetensors", "--rank-weight", "-1"],
        "--rank-weight must be a finite number in [0, 100], got -1.0",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m11.safetensors", "--buffer-rows", "0", "--stream"],
        "--buffer-rows must be >= 1, got 0",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m12.safetensors", "--patience", "-1"],
        "--patience must be >= 1, got -1",
    ),
    (["depth", "knife", "--sample", "1", "-o", "{d}/dd"], "must end in .png or .npy"),
    (
        ["depth", "knife", "--p0", "0,0,0,0,0,0.5", "--sample", "1", "-o", "{d}/d12.png"],
        "argument --sample: not allowed with argument --p0",
    ),
    (
        ["depth", "knife", "--p0", "a,b,c,d,e,f", "-o", "{d}/d13.png"],
        "is not six comma-separated numbers",
    ),
    (
        ["depth", "{txt}", "--sample", "1", "-o", "{d}/d14.png"],
        "supported formats: .glb, .gltf, .obj, .off, .ply, .stl",
    ),
    (["plan", "{txt}"], "supported formats: .glb, .gltf, .obj, .off, .ply, .stl"),
    (["plan", "knife", "--candidates", "2", "--seed", "-3"], "--seed must be >= 0, got -3"),
    (["objects", "export", "knife", "-o", "{d}/o1.xyz"], "use .obj, .stl, .ply, .glb or .off"),
    (
        ["objects", "export", "nosuch", "-o", "{d}/o2.stl"],
        "it is not a built-in family and no file exists at that path.",
    ),
    (["objects", "export", "knife", "-o", "{d}"], "is a directory; give a file name inside it"),
    (
        ["best", "{ds}", "--task", "pick", "--mode", "nosuch"],
        "modes: default, no-robustness, extra-robustness, paper, pape",
    ),
    (["tasks", "--tasks-file", "{d}"], "is a directory; give a .toml file"),
    (
        ["show", "knife", "--task", "pick", "-o", "{d}/s7", "--samples", "0"],
        "--samples must be a positive integer, got 0",
    ),
    (
        ["plots", "knife", "-o", "{d}/p4", "--samples", "-1"],
        "--samples must be a positive integer, got -1",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--workers", "0"],
        "--workers must be at least 1, got 0",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--uses", "-5"],
        "--uses must be a non-negative integer, got -5",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--robust", "-2"],
        "--robust must be an integer >= 0 (copies per grasp), got -2",
    ),
    (["validate", "-o", "{d}/v1", "--seeds", "0"], "--seeds must be a positive integer, got 0"),
    (["validate", "-o", "{d}/v2", "--uses", "-4"], "--uses must be a positive integer, got -4"),
    (
        ["validate", "-o", "{d}/v3", "--grasps", "100", "--also-grasps", "100"],
        "--also-grasps must lie in [0, grasps) = [0, 100), got 100",
    ),
    (
        ["validate", "-o", "{d}/v4", "--also-grasps", "-1"],
        "--also-grasps must lie in [0, grasps) = [0, 100), got -1",
    ),
    (["validate", "-o", "{d}/v5", "--refine", "1"], "--refine must lie in [0, 1), got 1.0"),
    (
        ["validate", "-o", "{d}/v6", "--tasks", "cutt"],
        "which the validation does not judge (did you mean 'cut'?)",
    ),
    (
        ["validate", "-o", "{d}/v7", "--tasks", "cut", "--families", "mug"],
        "has 'mug', which no task of cut judges; choose among axe, dagger",
    ),
    (
        ["validate", "-o", "{d}/v8", "--no-optimizer", "--no-brute-force"],
        "--no-optimizer and --no-brute-force leave nothing to run; drop one",
    ),
    (["validate", "-o", "{txt}"], "is a file, not a directory; give a directory"),
    (["validate", "-o", "{d}/v9", "--seeds", "two"], "argument --seeds: invalid int value"),
]


@pytest.fixture(scope="module")
def place(tmp_path_factory) -> dict[str, str]:
    d = tmp_path_factory.mktemp("hostile")
    ds = d / "ds"
    assert main(["generate", "knife:1", "--samples", "48", "--out", str(ds), "--workers", "1"]) == 0
    (d / "text.txt").write_text("hello")
    (d / "bad.toml").write_text("[tasks\nx=")
    (d / "empty.toml").write_text("")
    (d / "weird.toml").write_text('[tasks.t]\nexpr = "epsilon >"\n')
    (d / "model.safetensors").write_bytes(os.urandom(200))
    (d / "emptydir").mkdir()
    return {
        "ds": str(ds),
        "d": str(d),
        "txt": str(d / "text.txt"),
        "empty": str(d / "emptydir"),
        "bad": str(d / "model.safetensors"),
    }


@pytest.mark.parametrize("argv, fragment", CASES, ids=[" ".join(a)[:70] for a, _ in CASES])
def test_hostile_option_is_refused_in_one_line(argv, fragment, place, capsys):
    args = [a.format(**place) for a in argv]
    scratch = Path(place["d"])
    before = {p.name for p in scratch.iterdir()}
    try:
        code = main(args)
    except SystemExit as exc:  # argparse's own refusals
        code = exc.code
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err, err
    assert code == 2, f"exit {code}: {err}"
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    # "affordgrasp CMD: error:", "affordgrasp objects export: error:" or, for an unknown
    # command, "affordgrasp: error:"
    assert re.match(rf"affordgrasp( {re.escape(args[0])}( [a-z]+)?)?: error: ", lines[0]), lines[0]
    assert fragment in lines[0], lines[0]
    assert {p.name for p in scratch.iterdir()} == before  # refused before any work
