"""The quick examples of README.md and docs/ run as written and show what their text says.

Each command is looked up in its markdown file (so the test fails when the text changes without
it), run in a temporary folder, in the documented order, and checked against the claim next to
it. A dataset command runs with fewer samples; the commands that read the dataset then run as
written. The slow examples (minutes) are listed with their measured cost in
docs/conventions.md, "Running the examples"; README.md's Python blocks are
tests/test_readme.py's.
"""

import contextlib
import io
import json
import re
import shlex
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from affordgrasp.cli import main

ROOT = Path(__file__).resolve().parents[1]


def commands(doc: str) -> list[list[str]]:
    """Every command of the ```bash/```sh blocks of one file, as argv lists (comments dropped,
    continued lines joined, ``a && b`` split)."""
    found = []
    text = (ROOT / doc).read_text()
    for block in re.findall(r"```(?:bash|sh)\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            try:
                argv = shlex.split(line, comments=True)
            except ValueError:  # a line of a here-document
                continue
            while "&&" in argv:
                cut = argv.index("&&")
                found.append(argv[:cut])
                argv = argv[cut + 1 :]
            if argv:
                found.append(argv)
    return found


def documented(doc: str, command: str) -> list[str]:
    """``command``'s argv, after checking that ``doc`` shows it in a shell block."""
    argv = shlex.split(command)
    assert argv in commands(doc), f"{doc} no longer shows `{command}`"
    return argv


def python_block(doc: str, marker: str) -> str:
    """The one ```python block of ``doc`` that contains ``marker``."""
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / doc).read_text(), flags=re.S)
    found = [b for b in blocks if marker in b]
    assert len(found) == 1, f"{doc}: {len(found)} Python blocks contain {marker!r}"
    return found[0]


def affordgrasp(argv: list[str]) -> dict:
    """Run ``affordgrasp ...`` in this process with --json (which every command accepts)."""
    assert argv[0] == "affordgrasp"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main([*argv[1:], "--json"])
    assert code == 0, argv
    return json.loads(out.getvalue())


def run_python(code: str, name: str) -> tuple[dict, list[str]]:
    namespace: dict = {"__name__": "__main__"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, name, "exec"), namespace)
    return namespace, out.getvalue().splitlines()


def with_samples(argv: list[str], samples: int) -> list[str]:
    at = argv.index("--samples")
    return [*argv[: at + 1], str(samples), *argv[at + 2 :]]


def test_the_front_door_prints_the_best_grasp_per_task(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    doc = affordgrasp(documented("README.md", "affordgrasp evaluate knife --samples 1000"))
    assert doc["samples"] == 1000
    # every task shows its most likely grasp; "on a knife, 1000 uniform samples rarely put the
    # use point on the edge with the hand on the handle": no cut reaches 0.5, and it says so
    assert all(doc["best"][t] is not None for t in ("beat", "cut", "pick"))
    assert doc["best"]["cut"]["probable"] is False and doc["best"]["cut"]["value"] < 0.5
    assert doc["best"]["beat-rules"] is None and doc["best"]["cut-rules"] is None
    # the throughput of the steady state, the one-time costs apart
    assert doc["grasps_per_second_per_core"] > 0
    assert set(doc["one_time_seconds"]) == {"kernels", "prepare"}


def test_the_readme_command_line_in_order(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    families = affordgrasp(documented("README.md", "affordgrasp objects"))["families"]
    assert len(families) == 13
    affordgrasp(documented("README.md", "affordgrasp objects export knife --seed 3 -o knife.obj"))
    assert Path("knife.obj").read_text().startswith(("#", "v "))
    sims = "affordgrasp simulate hammer --samples 1000 --out sims.parquet"
    affordgrasp(documented("README.md", sims))
    assert pq.read_table("sims.parquet").num_rows == 1000
    phi = (
        "affordgrasp evaluate knife --samples 2000 --task cut --mode no-robustness"
        " --out phi.parquet"
    )
    doc = affordgrasp(documented("README.md", phi))
    assert pq.read_table("phi.parquet").num_rows == 2000 and doc["mode"] == "no-robustness"
    tasks = affordgrasp(documented("README.md", "affordgrasp tasks"))["tasks"]
    assert {"beat", "cut", "pick"} <= set(tasks)
    # the quick validation: one seed of the hammer and the knife (docs/validation.md §5)
    doc = affordgrasp(documented("README.md", "affordgrasp validate -o validation-out"))
    assert doc["settings"]["families"] == ["hammer", "knife"] and doc["settings"]["seeds"] == 1
    summary = {
        task: found["summary"]["brute_force"]["top_grasps"]
        + found["summary"]["optimizer"]["top_grasps"]
        for task, found in doc["tasks"].items()
    }
    # it checks the machinery: the task probabilities rank grasps for every task
    assert summary["pick"] > 0 and summary["cut"] > 0 and summary["beat"] > 0
    assert Path("validation-out/validation.json").is_file()

    # the task of the TOML block, run with the command its first line gives
    toml = re.search(r"```toml\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S).group(1)
    Path("pry.toml").write_text(toml)
    command = re.search(r"use with: (affordgrasp .*)", toml).group(1)
    pry = affordgrasp(shlex.split(command))["best"]["pry"]
    assert pry is not None and pry["value"] > 0

    # docs/viewing.md renders a row of phi.parquet
    code = python_block("docs/viewing.md", "save_grasp_png(")
    ns, _ = run_python(code, "viewing.md")
    from PIL import Image

    assert Image.open("grasp.png").size == (512, 512)
    assert ns["rows"][0]["object"] == "knife:0"


def test_a_small_dataset_reads_as_the_docs_say(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    generate = "affordgrasp generate knife hammer mug --samples 100000 --out data/tools --seed 0"
    for doc in ("README.md", "docs/dataset.md"):
        argv = documented(doc, generate)
    summary = affordgrasp(with_samples(argv, 200))
    assert summary["complete"] and summary["samples_written"] == 600

    best = (
        "affordgrasp best data/tools --task cut --mode no-robustness --top 5 --out best-cut.parquet"
    )
    for doc in ("README.md", "docs/dataset.md"):
        affordgrasp(documented(doc, best))
    assert pq.read_table("best-cut.parquet").num_rows <= 5
    beat = "affordgrasp best data/tools --task beat-paper --object hammer"
    doc = affordgrasp(documented("docs/dataset.md", beat))
    assert doc["rows_scanned"] == 200 and doc["objects"] == ["hammer:0"]

    # README: pandas, polars and DuckDB read the directory
    printed = [
        run_python(argv[2], "README.md")[1]
        for argv in commands("README.md")
        if argv[:2] == ["python", "-c"]
    ]
    assert len(printed) == 3
    pandas, polars, duckdb = ("\n".join(lines) for lines in printed)
    assert "grasped" in pandas and polars.startswith("(600, ") and "hammer:0" in duckdb
    # docs/dataset.md: the readers, then the handle
    ns, _ = run_python(python_block("docs/dataset.md", "pd.read_parquet("), "dataset.md")
    assert len(ns["df"]) == 600 and (ns["closure"]["epsilon"] > 0).all()
    ns, lines = run_python(python_block("docs/dataset.md", "ag.Dataset.open("), "dataset.md")
    assert lines == ["['knife:0', 'hammer:0', 'mug:0'] barrett False"]
    assert ns["knife"].name == "knife:0" and set(ns["table"]["object"].to_pylist()) == {"knife:0"}

    # docs/viewing.md: the best grasps of a dataset directory, and its plots
    show = "affordgrasp show data/tools --task pick -o figures/pick"
    doc = affordgrasp(documented("docs/viewing.md", show))
    assert Path(doc["files"]["grid"]).is_file() and Path(doc["files"]["html"]).is_file()
    assert {r["object"] for r in doc["rankings"]} == {"knife:0", "hammer:0", "mug:0"}
    doc = affordgrasp(
        documented("docs/viewing.md", "affordgrasp plots data/tools -o figures/plots")
    )
    assert sorted(doc["files"]) == ["affordances", "metrics", "status"] and doc["rows"] == 600
    assert all(Path(f).is_file() for f in doc["files"].values())


def test_robust_scores(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    command = "affordgrasp evaluate hammer --samples 1000 --robust 25"
    doc = affordgrasp(documented("docs/robust.md", command))
    assert doc["robust"]["copies"] == 25 and doc["robust"]["quantile"] == 0.2
    # "ranks by the robust score": pick's is robust_hold, load directions held on average
    assert 0 < doc["best"]["pick"]["value"] <= 6
    ns, _ = run_python(python_block("docs/robust.md", "robust=25"), "robust.md")
    hold = ns["result"].table.column("robust_hold").to_numpy()
    # load directions held on average, less under 1/K for the effort
    assert hold.shape == (500,) and hold.min() > -1 / 25 and hold.max() <= 6


def test_a_viewer_page_from_python(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run_python(python_block("docs/viewing.md", "write_viewer("), "viewing.md")
    page = Path("knife.html").read_text()
    assert "my grasp" in page and len(page) > 100_000  # three.js is inlined: offline


def test_depth_images(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    png = "affordgrasp depth knife --p0 0.1,0.2,0.3,0,0,0.5 -o depth.png"
    doc = affordgrasp(documented("docs/vision.md", png))
    assert doc["pixels_hit"] > 0 and Path("depth.png").stat().st_size > 0
    npy = "affordgrasp depth knife:3 --sample 17 --seed 0 -o depth.npy"
    affordgrasp(documented("docs/vision.md", npy))
    depth = np.load("depth.npy")
    assert depth.dtype == np.float32 and depth.shape == (128, 128)
    assert 0.05 < depth.max() < 1.0 and depth.min() == 0  # metres; 0 = no return
    ns, lines = run_python(python_block("docs/vision.md", "render_depth("), "vision.md")
    assert ns["depth"].shape == (2, 128, 128) and ns["points"].shape == (2, 1024, 3)
    assert lines[0].startswith("(2, 128, 128) (2, 1024, 3)")
