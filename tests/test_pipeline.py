"""The GWS volume on request (SPEC §2.10): ε alone by default, the volume when asked."""

from __future__ import annotations

import json

import numpy as np
import pytest

from affordgrasp.cli import main
from affordgrasp.pipeline import evaluate, evaluate_samples
from affordgrasp.schema import metric_arrays

SAMPLES = 48


@pytest.fixture(scope="module")
def mug_both():
    """The same 48 mug grasps without (default) and with the volume."""
    return (
        evaluate_samples("mug", SAMPLES, seed=4).table,
        evaluate_samples("mug", SAMPLES, seed=4, volume=True).table,
    )


def test_the_volume_is_null_unless_asked_for_and_nothing_else_changes(mug_both):
    plain, full = mug_both
    assert plain.schema == full.schema  # the column stays in the schema
    assert plain.column("gws_volume").null_count == SAMPLES
    assert full.column("gws_volume").null_count == 0
    for name in plain.column_names:
        if name in ("gws_volume", "epsilon", "epsilon_hand"):  # epsilon_hand is ε on a mug
            continue
        # repr: bit-exact floats, and NaN (no use point) equal to NaN
        assert repr(plain.column(name).to_pylist()) == repr(full.column(name).to_pylist()), name
    # ε from the best-first hull and from the full hull: the same facets, summed apart
    for name in ("epsilon", "epsilon_hand"):
        np.testing.assert_allclose(
            plain.column(name).to_numpy(), full.column(name).to_numpy(), rtol=1e-12
        )
    assert np.all(np.isnan(metric_arrays(plain)["gws_volume"]))


def test_a_computed_volume_is_positive_exactly_on_force_closure(mug_both):
    _, full = mug_both
    eps = full.column("epsilon").to_numpy()
    vol = full.column("gws_volume").to_numpy()
    closure = eps > 0
    assert closure.any() and (~closure).any()
    assert np.all(vol[closure] > 0) and np.all(vol[~closure] == 0)


def test_evaluate_passes_the_request_on():
    rows = evaluate("knife", samples=8, seed=1, volume=True).table
    assert rows.column("gws_volume").null_count == 0
    assert evaluate("knife", samples=8, seed=1).table.column("gws_volume").null_count == 8


def test_cli_metrics_plus_volume(tmp_path, capsys):
    out = tmp_path / "e.parquet"
    argv = ["evaluate", "knife", "--samples", "8", "--metrics", "+volume", "--out", str(out)]
    assert main([*argv, "--json"]) == 0
    capsys.readouterr()
    import pyarrow.parquet as pq

    assert pq.read_table(out).column("gws_volume").null_count == 0
    sim = tmp_path / "s.parquet"
    assert main(["simulate", "knife", "--samples", "8", "--out", str(sim), "--json"]) == 0
    assert "gws_volume" not in pq.read_table(sim).column_names
    assert (
        main(["simulate", "knife", "--samples", "8", "--metrics", "+volume", "--out", str(sim)])
        == 0
    )
    assert pq.read_table(sim).column("gws_volume").null_count == 0
    capsys.readouterr()
    assert main(["evaluate", "knife", "--samples", "8", "--metrics", "+vol"]) == 2
    err = capsys.readouterr().err
    assert "'+vol'" in err and "+volume" in err


def test_generate_records_the_volume_request(tmp_path, capsys):
    out = tmp_path / "d"
    gen = ["generate", "knife", "--samples", "2", "--workers", "1", "--out", str(out)]
    assert main([*gen, "--metrics", "+volume", "--json"]) == 0
    manifest = json.loads((out / "_manifest.json").read_text())
    assert manifest["volume"] is True
    assert "+volume" in manifest["command"]
    capsys.readouterr()
    assert main([*gen, "--no-metrics", "--metrics", "+volume"]) == 2
    assert "drop --no-metrics" in capsys.readouterr().err
