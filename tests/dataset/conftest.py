"""Shared fixtures: one small dataset, generated once, that other tests compare against."""

from __future__ import annotations

import pytest
from dataset_support import SAMPLES, SEED, SHARD_SIZE


@pytest.fixture(scope="session")
def object_specs(box_mesh):
    return ["knife", str(box_mesh)]


@pytest.fixture(scope="session")
def reference_dataset(tmp_path_factory, object_specs):
    """The uninterrupted, single-process run every other run must reproduce."""
    from affordgrasp.dataset.generate import generate

    out = tmp_path_factory.mktemp("reference") / "ds"
    generate(object_specs, SAMPLES, out, seed=SEED, workers=1, shard_size=SHARD_SIZE)
    return out


@pytest.fixture(scope="session")
def reference_table(reference_dataset):
    from affordgrasp.dataset.reading import read_dataset

    return read_dataset(reference_dataset)
