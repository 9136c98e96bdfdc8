"""The written dataset: schema round trip, card, and pandas / polars / DuckDB reading it."""

from __future__ import annotations

import json
import math

import numpy as np
import pyarrow.parquet as pq
import pytest
from dataset_support import SAMPLES, SEED, SHARD_SIZE

from affordgrasp import __version__, tasks
from affordgrasp.dataset.handle import open_dataset
from affordgrasp.dataset.reading import read_dataset, select_objects
from affordgrasp.dataset.shards import shard_paths
from affordgrasp.errors import DatasetError
from affordgrasp.schema import dataset_schema

SCHEMA = dataset_schema()  # the documented shard schema: metrics, then the task probabilities


def test_every_shard_has_the_documented_schema(reference_dataset):
    paths = shard_paths(reference_dataset)
    assert len(paths) == 2 * SAMPLES // SHARD_SIZE
    for p in paths:
        schema = pq.read_schema(p)
        assert schema.remove_metadata() == SCHEMA.remove_metadata()
        assert schema.metadata[b"affordgrasp_version"] == __version__.encode()
        info = json.loads(schema.metadata[b"affordgrasp_shard"])
        assert sum(info["status_counts"].values()) == pq.read_metadata(p).num_rows


def test_schema_round_trip_keeps_values(reference_table):
    t = reference_table
    assert t.schema.remove_metadata() == SCHEMA.remove_metadata()
    rows = t.to_pylist()
    again = type(t).from_pylist(rows, schema=SCHEMA)
    assert again.equals(t.replace_schema_metadata(SCHEMA.metadata))
    for r in rows:
        k = r["n_contacts"]
        assert len(r["contact_points"]) == len(r["contact_normals"]) == len(r["contact_mu"]) == k
        assert len(r["contact_link"]) == k
        assert len(r["hand_pose"]) == 16 and len(r["p0"]) == 6 and len(r["use_dir"]) == 2
        assert all(-1 <= u <= 1 for u in r["p0"][:5]) and 0 <= r["p0"][5] <= 1
        assert math.isclose(np.linalg.norm(r["wrist_axis"]), 1.0, rel_tol=1e-9)
        assert (r["epsilon_reason"] == "") == (r["epsilon"] > 0)
    # +inf is stored as IEEE inf, not a sentinel.
    assert np.isinf(t["impact_effort"].to_numpy()).any()


def test_card_describes_the_dataset(reference_dataset, reference_table):
    card = json.loads((reference_dataset / "_card.json").read_text())
    assert card["complete"] and card["rows"] == reference_table.num_rows
    assert card["affordgrasp_version"] == __version__
    assert card["seed"] == SEED and card["samples_per_object"] == SAMPLES
    assert card["hand"]["name"] == "barrett"
    assert card["friction_table"]["plastic-wood"] == 0.4
    assert card["task_thresholds"]["cut-rules"]["default"]["tau_eps"] == tasks.TAU_EPS_DEFAULT
    assert card["task_thresholds"]["cut-rules"]["paper"]["tau_eps"] == 0.3
    assert [o["name"] for o in card["objects"]] == ["knife:0", "box.stl"]
    for o in card["objects"]:
        assert len(o["mesh_hash"]) == 64 and o["mass_kg"] > 0 and len(o["inertia_kg_m2"]) == 3
    statuses = reference_table["status"].to_pylist()
    assert card["status_counts"] == {s: statuses.count(s) for s in sorted(set(statuses))}
    assert card["force_closure_per_object"]["knife:0"] == int(
        np.sum(read_dataset(reference_dataset, objects=["knife"])["epsilon"].to_numpy() > 0)
    )
    md = (reference_dataset / "_card.md").read_text()
    assert "knife:0" in md and "box.stl" in md and "state: complete" in md


def test_pandas_reads_the_directory(reference_dataset, reference_table):
    pd = pytest.importorskip("pandas")
    df = pd.read_parquet(reference_dataset)
    assert len(df) == reference_table.num_rows
    assert list(df.columns) == SCHEMA.names
    assert df.groupby("object")["sample"].max().to_dict() == {
        "knife:0": SAMPLES - 1,
        "box.stl": SAMPLES - 1,
    }


def test_polars_reads_the_directory(reference_dataset, reference_table):
    pl = pytest.importorskip("polars")
    df = pl.scan_parquet(f"{reference_dataset}/*.parquet").collect()
    assert df.height == reference_table.num_rows
    assert df["epsilon"].to_list() == reference_table["epsilon"].to_pylist()


def test_duckdb_reads_the_directory(reference_dataset, reference_table):
    duckdb = pytest.importorskip("duckdb")
    rows = duckdb.sql(
        f"SELECT status, count(*) FROM '{reference_dataset}/*.parquet' GROUP BY status"
    ).fetchall()
    statuses = reference_table["status"].to_pylist()
    assert dict(rows) == {s: statuses.count(s) for s in set(statuses)}


def test_object_selection_and_errors(reference_dataset, tmp_path):
    assert select_objects(reference_dataset, ["knife"]) == ["knife:0"]
    assert select_objects(reference_dataset, ["knife:0", "box.stl"]) == ["knife:0", "box.stl"]
    with pytest.raises(DatasetError, match="holds: knife:0, box.stl"):
        select_objects(reference_dataset, ["mug"])
    with pytest.raises(DatasetError, match="not an affordgrasp dataset"):
        open_dataset(tmp_path)
    with pytest.raises(DatasetError, match="does not exist"):
        open_dataset(tmp_path / "nowhere")


def test_a_dataset_of_an_earlier_version_says_which_columns_it_lacks(
    reference_dataset, tmp_path, caplog
):
    import shutil

    copy = tmp_path / "old"
    shutil.copytree(reference_dataset, copy)
    for p in shard_paths(copy):  # as an earlier version wrote them: no edge thickness
        pq.write_table(pq.read_table(p).drop_columns(["use_edge_thickness"]), p)
    with caplog.at_level("WARNING", logger="affordgrasp"):
        table = open_dataset(copy, verify=False).to_table()
    assert "use_edge_thickness" in caplog.text and "earlier version" in caplog.text
    assert table.column("use_edge_thickness").null_count == table.num_rows
    caplog.clear()
    with caplog.at_level("WARNING", logger="affordgrasp"):
        open_dataset(reference_dataset)
    assert "earlier version" not in caplog.text
