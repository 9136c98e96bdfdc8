"""Hostile command-line options, every command: each is refused with exit 2 and one line.

A sweep of option values a user can type by mistake (zero, negative, NaN, huge, wrong type,
unknown names, files where folders belong and the reverse, foreign files). Each case must
end with exit 2 and a single line ``affordgrasp COMMAND: error: ...`` containing the given
fragment, before any work: no traceback, no "internal error", and none of the outputs it
names created. The mesh-file corpus and the costlier cases live in
``test_hostile_inputs.py``.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import re
from pathlib import Path

import pytest

from affordgrasp.cli import build_parser, main
from affordgrasp.hands import get_hand, save_hand

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
        "available tasks: beat, beat-paper, beat-rules, cut, cut-dihedral, cut-rules, cut-ug",
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
        "available tasks: beat, beat-paper, beat-rules, cut, cut-dihedral, cut-rules, cut-ug",
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
        "available tasks: beat, beat-paper, beat-rules, cut, cut-dihedral, cut-rules, cut-ug",
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
        "available tasks: beat, beat-paper, beat-rules, cut, cut-dihedral, cut-rules, cut-ug",
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
        "available tasks: beat, beat-paper, beat-rules, cut, cut-dihedral, cut-rules, cut-ug",
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
    # Hand files: every number finite and in its range (an infinite joint limit hung).
    (
        ["evaluate", "knife", "--samples", "3", "--hand", "{d}/inf_limit.json"],
        "the joint's travel (ratio 1 × the limits of 'f1_prox') must be a finite number in",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--hand", "{d}/nan_palm.json"],
        "a shape's rounding radius must be a finite number in [0, 1] m, got nan",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--hand", "{d}/wide_palm.json"],
        "a shape's half extents must be a finite number in [0, 1] m, got 2e+06",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g10", "--hand", "{d}/slow.json"],
        "a closing speed must be a finite number in [0.001, 1000], got 1e-12",
    ),
    # Task files: thresholds are numbers or ±inf; expressions bounded in size and depth.
    (
        ["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/nan_threshold.toml"],
        "threshold 't' must be a number (inf and -inf switch a test off), got nan",
    ),
    (
        ["evaluate", "knife", "--samples", "3", "--tasks-file", "{d}/minus.toml"],
        "is 100,007 characters long; a task expression may have at most 2,000",
    ),
    (["tasks", "--tasks-file", "{d}/sum.toml"], "a task expression may have at most 2,000"),
    (["tasks", "--tasks-file", "{d}/deep.toml"], "levels deep; a task expression may nest at most"),
    # Numeric options: finite, their sign, a largest value with the reason.
    (
        ["train", "{ds}", "-o", "{d}/m13.safetensors", "--target", "hold_effort_sum"]
        + ["--rank-weight", "nan"],
        "--rank-weight must be a finite number in [0, 100], got nan",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m14.safetensors", "--rank-weight", "inf"],
        "--rank-weight must be a finite number in [0, 100], got inf",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m15.safetensors", "--max-minutes", "0"],
        "--max-minutes must be a finite number in [0.01, 10080], got 0.0 (a week)",
    ),
    (
        ["train", "{ds}", "-o", "{d}/m16.safetensors", "--max-minutes", "nan"],
        "--max-minutes must be a finite number in [0.01, 10080], got nan",
    ),
    (
        ["depth", "knife", "--sample", "1", "--scale", "100000", "-o", "{d}/d15.png"],
        "makes a PNG 12,800,000 pixels wide; at most 4,096: with --size 128, use --scale at most",
    ),
    (
        ["show", "{ds}", "--task", "pick", "--uses", "1000000000", "-o", "{d}/s9"],
        "--uses must be an integer in [0, 50,000], got 1000000000 (each use point is ray cast",
    ),
    (
        ["optimize", "knife", "--task", "pick", "--budget", "20", "--uses", "1000000000"],
        "--uses must be an integer at most 50,000, got 1000000000",
    ),
    (
        ["generate", "knife", "--samples", "5", "--out", "{d}/g8", "--workers", "1000000"],
        "--workers must be an integer at most",
    ),
    (
        ["generate", "knife", "--samples", "1000000000000", "--out", "{d}/g9"],
        "shard files; at most 100,000: use at most 409,600,000 samples per object",
    ),
    # An option that names nothing is refused, not read as absent.
    (["evaluate", "knife", "--samples", "3", "--task", ""], "--task '' names nothing; give a"),
    (["evaluate", "knife", "--samples", "3", "--task", ","], "--task ',' names nothing; give a"),
    (["evaluate", "knife", "--samples", "3", "--metrics", ""], "--metrics '' names nothing"),
    (["show", "{ds}", "--task", " ", "-o", "{d}/s10"], "--task ' ' names nothing"),
    (["validate", "-o", "{d}/v10", "--families", ""], "--families '' names nothing"),
    # Messages that say what to do with what the command has.
    (
        ["generate", "knife:1", "--samples", "48", "--out", "{ds}", "--depth"],
        "(no depth images (--depth) there vs depth images of 128 px at 60.0° (--depth) here)",
    ),
    (["plots", "{txt}", "-o", "{d}/p5"], "is a file but not a mesh file (.txt); give a dataset"),
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
    _hostile_files(d)
    return {
        "ds": str(ds),
        "d": str(d),
        "txt": str(d / "text.txt"),
        "empty": str(d / "emptydir"),
        "bad": str(d / "model.safetensors"),
    }


def _hostile_files(d: Path) -> None:
    """Hand files with a bad number each, and task files past the bounds."""
    save_hand(get_hand("barrett"), d / "barrett.json")
    doc = json.loads((d / "barrett.json").read_text())
    edits = {
        "inf_limit": lambda h: h["dofs"][1].update(upper=math.inf),  # written as Infinity
        "nan_palm": lambda h: h["links"][0]["shapes"][0].update(radius=math.nan),
        "wide_palm": lambda h: h["links"][0]["shapes"][0].update(half_extents=[2e6, 2e6, 0.03]),
        "slow": lambda h: [f.update(speeds=[1.0, 1e-12]) for f in h["fingers"]],
    }
    for name, edit in edits.items():
        hand = copy.deepcopy(doc)
        edit(hand)
        (d / f"{name}.json").write_text(json.dumps(hand))
    task = '[tasks.x]\nvalue = "{}"\n'
    (d / "nan_threshold.toml").write_text(task.format("epsilon") + "thresholds = { t = nan }\n")
    (d / "minus.toml").write_text(task.format("-" * 100_000 + "epsilon"))
    (d / "sum.toml").write_text(task.format("+".join(["epsilon"] * 200_000)))
    (d / "deep.toml").write_text(task.format("+".join(["epsilon"] * 150)))


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


# ----------------------------------------------------------------- every numeric option
# Each command declares the limits of its numeric options (LIMITS in its module, checked by
# cli.main before the command runs): no numeric option without them, and a value past a
# limit is refused before any work, whatever the rest of the command line says.

BASE = {  # the least each command parses; the refusal comes before anything is read
    "objects": ["objects", "export", "knife", "-o", "o.obj"],
    "simulate": ["simulate", "knife"],
    "evaluate": ["evaluate", "knife"],
    "generate": ["generate", "knife", "--samples", "5", "--out", "g"],
    "best": ["best", "ds", "--task", "pick"],
    "optimize": ["optimize", "knife", "--task", "pick"],
    "show": ["show", "ds", "--task", "pick", "-o", "s"],
    "plots": ["plots", "ds", "-o", "p"],
    "physics": ["physics", "ds", "--out", "ph"],
    "depth": ["depth", "knife", "-o", "d.png"],
    "train": ["train", "ds", "-o", "m.safetensors"],
    "model-eval": ["model-eval", "default", "ds"],
    "plan": ["plan", "knife"],
    "validate": ["validate", "-o", "v"],
}


def _numeric_options():
    """(command, option string, dest, type, module) of every int or float option."""
    parser = build_parser()
    (commands,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for name, sub in commands.choices.items():
        module = sub.get_default("_module")
        parsers = [sub]
        while parsers:
            for action in parsers.pop()._actions:
                if isinstance(action, argparse._SubParsersAction):
                    parsers.extend(action.choices.values())
                elif action.type in (int, float):
                    yield name, action.option_strings[-1], action.dest, action.type, module


def test_every_numeric_option_has_limits():
    missing = [
        f"{name} {option}"
        for name, option, dest, _, module in _numeric_options()
        if dest not in getattr(module, "LIMITS", {})
    ]
    assert not missing, missing


def _past_the_limits():
    cases = []
    for name, option, dest, kind, module in _numeric_options():
        low, high, _ = module.LIMITS[dest]
        if callable(high):  # sized by the memory available, which moves: far past it
            high = 2**62
        values = []
        if low is not None:
            values.append(str(kind(low) - 1))
        if high is not None:
            values.append(str(high + 1) if kind is int else repr(2.0 * high + 1.0))
        if kind is float and (low, high) != (None, None):
            values += ["nan", "inf", "-inf"]
        cases += [(name, option, value) for value in values]
    return cases


PAST = _past_the_limits()


@pytest.mark.parametrize("name, option, value", PAST, ids=[" ".join(c) for c in PAST])
def test_a_value_past_the_limits_is_refused_before_any_work(
    name, option, value, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    code = main([*BASE[name], f"{option}={value}"])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith(f"affordgrasp {name}: error: {option} must be "), lines[0]
    assert not list(tmp_path.iterdir())
