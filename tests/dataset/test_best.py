"""Brute-force argmax over a dataset agrees with a plain pandas computation."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from affordgrasp import tasks
from affordgrasp.cli import main
from affordgrasp.dataset.generate import generate
from affordgrasp.errors import DatasetError
from affordgrasp.search.best import best_grasps

HOLD = [f"hold_effort_{s}" for s in ("px", "nx", "py", "ny", "pz", "nz")]


def pandas_values(df: pd.DataFrame, task: str, mode: str) -> np.ndarray:
    """The paper's formulas written out over the DataFrame (conventions: Tasks)."""
    tau_eps = {
        "default": tasks.TAU_EPS_DEFAULT,
        "no-robustness": -np.inf,
        "extra-robustness": tasks.TAU_EPS_EXTRA,
    }[mode]
    hold = df[HOLD].sum(axis=1)
    if task == "pick-paper":
        return -hold.to_numpy()
    if task == "cut-rules":
        t = tasks.get_task("cut-rules").thresholds
        ok = (
            (df.epsilon_hand >= tau_eps)
            & (df.use_wedge_angle <= t["tau_wedge"])
            & (df.use_wedge_angle_fine <= t["tau_wedge_fine"])
            & (df.use_edge_span >= t["tau_span"])
            & (df.use_edge_thickness <= t["tau_edge_thickness"])
            & (df.use_clearance >= t["tau_clear"])
            & (df.contact_thickness >= t["tau_thick"])
            & (df.contact_width >= t["tau_width"])
            & (df.contact_reach <= t["tau_reach"])
        )
        return np.where(ok, df.use_force, -np.inf)
    if task == "reach":
        return (df.inertia * 1e6 - df.use_edge_angle).to_numpy()
    raise AssertionError(task)


def pandas_top(directory, task: str, mode: str, top: int, objects=None) -> pd.DataFrame:
    df = pd.read_parquet(directory)
    if objects:
        df = df[df.object.isin(objects)]
    df = df.assign(value=pandas_values(df, task, mode))
    df = df[np.isfinite(df.value)]
    order = {"knife:0": 0, "box.stl": 1}
    df = df.assign(obj_rank=df.object.map(order))
    df = df.sort_values(["value", "obj_rank", "sample"], ascending=[False, True, True])
    return df.head(top)


@pytest.fixture(scope="module")
def reach_task():
    # A task finite on every row, so that the ranking has many candidates to merge.
    tasks.register_task(
        "reach",
        lambda m, t: m["inertia"] * 1e6 - m["use_edge_angle"],
        requires=("inertia", "use_edge_angle"),
        replace=True,
    )
    yield "reach"
    tasks.unregister_task("reach")


@pytest.mark.parametrize(
    "task, mode, objects",
    [
        ("pick-paper", "default", None),
        ("cut-rules", "no-robustness", None),
        ("reach", "default", None),
        ("reach", "default", ["box.stl"]),
    ],
)
def test_argmax_agrees_with_pandas(reference_dataset, reach_task, task, mode, objects):
    # Small batches: the running top-k is merged across many of them.
    got = best_grasps(reference_dataset, task, mode=mode, top=7, objects=objects, batch_size=10)
    want = pandas_top(reference_dataset, task, mode, 7, objects)
    assert got.finite == int(
        np.isfinite(
            pandas_values(
                pd.read_parquet(reference_dataset).query("object in @objects")
                if objects
                else pd.read_parquet(reference_dataset),
                task,
                mode,
            )
        ).sum()
    )
    assert got.table["object"].to_pylist() == want.object.tolist()
    assert got.table["sample"].to_pylist() == want["sample"].tolist()
    np.testing.assert_allclose(got.table["affordance"].to_numpy(), want.value.to_numpy())
    assert got.table["rank"].to_pylist() == list(range(1, len(want) + 1))
    # The full rows come along.
    assert got.table["p0"].to_pylist() == [list(v) for v in want.p0]


def test_best_cli_prints_json_and_writes_the_rows(reference_dataset, reach_task, tmp_path, capsys):
    out = tmp_path / "top.parquet"
    code = main(
        ["best", str(reference_dataset), "--task", "reach", "--top", "3", "--json"]
        + ["--object", "knife", "--out", str(out)]
    )
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["task"] == "reach" and len(doc["best"]) == 3
    assert all(r["object"] == "knife:0" for r in doc["best"])
    table = pq.read_table(out)
    assert table["sample"].to_pylist() == [r["sample"] for r in doc["best"]]
    assert json.loads(table.schema.metadata[b"affordgrasp_best"])["task"] == "reach"


def test_best_rejects_bad_input(reference_dataset, tmp_path, box_mesh, capsys):
    assert main(["best", str(reference_dataset), "--task", "pick", "--object", "mug"]) == 2
    assert "holds: knife:0, box.stl" in capsys.readouterr().err
    assert main(["best", str(reference_dataset), "--task", "nope"]) == 2
    assert main(["best", str(reference_dataset), "--task", "cut", "--mode", "weird"]) == 2
    assert main(["best", str(tmp_path), "--task", "pick"]) == 2
    generate([str(box_mesh)], 4, tmp_path / "sim", workers=1, metrics=False)
    with pytest.raises(DatasetError, match="no-metrics"):
        best_grasps(tmp_path / "sim", "pick")


@pytest.mark.parametrize("task", ["pick", "cut", "beat"])
def test_best_reads_the_stored_probabilities_of_the_models_in_use(
    reference_dataset, task, tmp_path, monkeypatch
):
    """A dataset records the digests of the task models it stored p_T with: while they are
    the models in use, best reads the p_T columns instead of walking the trees, and ranks
    exactly as the computed values do."""
    import shutil

    from affordgrasp.dataset.handle import Dataset
    from affordgrasp.search import best as best_module
    from affordgrasp.tasks.probability import model_digests

    ds = Dataset.open(reference_dataset)
    assert ds.manifest["probability_models"] == model_digests()
    assert best_module.stored_probabilities(ds, [tasks.get_task(task)], False) == [task]
    assert best_module.stored_probabilities(ds, [tasks.get_task("pick-paper")], False) == []
    stored = best_grasps(reference_dataset, task, top=9, batch_size=10)
    # the same ranking computed from the metric columns (a dataset of other models)
    other = tmp_path / "ds"
    shutil.copytree(reference_dataset, other)
    manifest = json.loads((other / "_manifest.json").read_text())
    manifest["probability_models"] = {k: "0" * 16 for k in manifest["probability_models"]}
    (other / "_manifest.json").write_text(json.dumps(manifest))
    assert (
        best_module.stored_probabilities(Dataset.open(other), [tasks.get_task(task)], False) == []
    )
    computed = best_grasps(other, task, top=9, batch_size=10)
    assert stored.table["sample"].to_pylist() == computed.table["sample"].to_pylist()
    assert stored.table["object"].to_pylist() == computed.table["object"].to_pylist()
    np.testing.assert_allclose(
        stored.table["affordance"].to_numpy(), computed.table["affordance"].to_numpy(), rtol=1e-12
    )
    # a resume with other models is refused in words
    from affordgrasp.dataset.manifest import manifest_differences

    diffs = manifest_differences(manifest, ds.manifest)
    assert any("task probability models" in d for d in diffs)
    older = {k: v for k, v in ds.manifest.items() if k != "probability_models"}
    assert manifest_differences(older, ds.manifest) == []
    # recorded before the code's version was: version 1, the same models
    models = {k: v for k, v in ds.manifest["probability_models"].items() if k != "code"}
    assert manifest_differences({**ds.manifest, "probability_models": models}, ds.manifest) == []
