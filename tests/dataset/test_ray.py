"""The Ray engine writes the same rows as the local one (a small run on a local Ray)."""

from __future__ import annotations

import pyarrow.compute as pc
import pytest
from dataset_support import SEED

from affordgrasp.dataset.generate import generate
from affordgrasp.dataset.reading import read_dataset


def test_a_small_run_on_a_local_ray_equals_the_local_engine(
    tmp_path, object_specs, reference_table
):
    pytest.importorskip("ray")
    n = 24
    summary = generate(
        object_specs, n, tmp_path / "ray", seed=SEED, engine="ray", workers=2, shard_size=10
    )
    assert summary.complete and summary.engine == "ray"
    got = read_dataset(tmp_path / "ray").replace_schema_metadata(None)
    want = reference_table.filter(pc.less(reference_table["sample"], n)).replace_schema_metadata(
        None
    )
    assert got.equals(want)
