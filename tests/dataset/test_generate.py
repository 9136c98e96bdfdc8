"""Generation: determinism, resume after Ctrl-C and kill -9, refusal of foreign directories."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from dataset_support import SAMPLES, SEED, SHARD_SIZE
from terminal import as_in_a_terminal

from affordgrasp.dataset.generate import generate
from affordgrasp.dataset.reading import read_dataset
from affordgrasp.dataset.shards import plan_shards, shard_paths
from affordgrasp.errors import DatasetError, HandError, InputError
from affordgrasp.grasp.pregrasp import object_stream_seed


def rows_of(table: pa.Table, obj: str, start: int, stop: int) -> pa.Table:
    mask = pc.and_(
        pc.equal(table["object"], obj),
        pc.and_(pc.greater_equal(table["sample"], start), pc.less(table["sample"], stop)),
    )
    return table.filter(mask).replace_schema_metadata(None)


def _bits(column) -> bytes:
    """A column's values as bytes, nested lists flattened: floats compared bit for bit."""
    values = column.combine_chunks()
    while pa.types.is_list(values.type) or pa.types.is_fixed_size_list(values.type):
        values = values.flatten()
    if values.null_count == len(values):  # a metric not computed (gws_volume by default)
        return f"{len(values)} nulls".encode()
    if pa.types.is_floating(values.type):
        assert values.null_count == 0
        return np.ascontiguousarray(values.to_numpy(zero_copy_only=False)).tobytes()
    return repr(values.to_pylist()).encode()


def same_rows(a: pa.Table, b: pa.Table) -> None:
    a = a.replace_schema_metadata(None)
    b = b.replace_schema_metadata(None)
    assert a.schema == b.schema
    assert a.num_rows == b.num_rows
    for name in a.column_names:
        # bit for bit (NaN rows too, which ChunkedArray.equals calls unequal)
        assert _bits(a[name]) == _bits(b[name]), f"column {name} differs"


def test_plan_is_a_pure_function_of_the_command():
    plan = plan_shards(2, 10, 4)
    assert [(s.object_index, s.start, s.stop) for s in plan] == [
        (0, 0, 4),
        (0, 4, 8),
        (0, 8, 10),
        (1, 0, 4),
        (1, 4, 8),
        (1, 8, 10),
    ]
    assert plan == plan_shards(2, 10, 4)
    assert plan[2].name == "part-00000-000000000008.parquet"


def test_reference_rows_are_every_sample_in_order(reference_table):
    assert reference_table.num_rows == 2 * SAMPLES
    for name in ("knife:0", "box.stl"):
        rows = rows_of(reference_table, name, 0, SAMPLES)
        assert rows["sample"].to_pylist() == list(range(SAMPLES))
        # each object draws from its own stream, recorded in its rows
        assert set(rows["seed"].to_pylist()) == {object_stream_seed(SEED, name)}
    # Unstable samples are written too.
    assert {"missed", "touched", "grasped"} & set(reference_table["status"].to_pylist())
    assert len(set(reference_table["status"].to_pylist())) >= 2


def test_rows_equal_a_direct_evaluation(reference_table):
    from affordgrasp.pipeline import evaluate_samples

    # the row's seed column is the seed to evaluate it again with
    direct = evaluate_samples("knife", 12, seed=object_stream_seed(SEED, "knife:0"), start=40).table
    same_rows(rows_of(reference_table, "knife:0", 40, 52), direct)


def test_objects_draw_different_samples_unless_streams_are_shared(tmp_path, object_specs):
    # per-object streams (the default): no pregrasp is repeated across objects, the
    # learning datasets' need; shared: sample i is the same pregrasp on every object
    def inputs(table, name):
        rows = rows_of(table, name, 0, 6)
        return np.asarray(rows["p0"].to_pylist()), set(rows["seed"].to_pylist())

    per = read_dataset(generate(object_specs, 6, tmp_path / "per", seed=SEED, workers=1).directory)
    (a, sa), (b, sb) = inputs(per, "knife:0"), inputs(per, "box.stl")
    assert sa != sb and not np.any(np.all(np.isclose(a[:, None], b[None]), axis=2))
    shared = generate(object_specs, 6, tmp_path / "shared", seed=SEED, workers=1, streams="shared")
    table = read_dataset(shared.directory)
    (a, sa), (b, sb) = inputs(table, "knife:0"), inputs(table, "box.stl")
    assert sa == sb == {SEED} and np.array_equal(a, b)
    same_rows(rows_of(table, "knife:0", 0, 6), evaluate_samples_of("knife", 6, SEED))
    with pytest.raises(DatasetError, match="shared streams there vs per-object here"):
        generate(object_specs, 6, tmp_path / "shared", seed=SEED, streams="per-object")
    # a resume without --streams keeps the dataset's own
    again = generate(object_specs, 6, tmp_path / "shared", seed=SEED, workers=1)
    assert again.complete and again.samples_written == 0
    with pytest.raises(InputError, match="streams"):
        generate(object_specs, 6, tmp_path / "bad", seed=SEED, streams="each")


def test_a_manifest_without_streams_resumes_as_shared(tmp_path, object_specs):
    out = tmp_path / "old"
    generate(object_specs, 4, out, seed=SEED, workers=1, streams="shared")
    path = out / "_manifest.json"
    manifest = json.loads(path.read_text())
    del manifest["sample_streams"]  # as written before streams were recorded
    path.write_text(json.dumps(manifest))
    summary = generate(object_specs, 4, out, seed=SEED, workers=1)
    assert summary.complete and summary.samples_written == 0


def evaluate_samples_of(name: str, n: int, seed: int) -> pa.Table:
    from affordgrasp.pipeline import evaluate_samples

    return evaluate_samples(name, n, seed=seed).table


def test_rows_do_not_depend_on_workers_or_shard_boundaries(tmp_path, object_specs, reference_table):
    n = 32
    summary = generate(
        object_specs, n, tmp_path / "w2", seed=SEED, workers=2, shard_size=20, chunk_size=8
    )
    assert summary.complete and summary.workers == 2
    got = read_dataset(tmp_path / "w2")
    for name in ("knife:0", "box.stl"):
        same_rows(rows_of(got, name, 0, n), rows_of(reference_table, name, 0, n))


@pytest.mark.parametrize("batch_size", [1, 7])
def test_rows_do_not_depend_on_the_batch_they_are_evaluated_in(batch_size):
    # Workers, chunks and shards only change which samples share a batch: every column of a
    # sample (the mug's, where start poses and U_g once depended on the batch) must be the
    # same bits whether its batch holds 40 samples, 7 or itself alone.
    from affordgrasp.pipeline import evaluate_samples

    whole = evaluate_samples("mug", 40, seed=SEED, start=3).table
    pieces = evaluate_samples("mug", 40, seed=SEED, start=3, batch_size=batch_size).table
    same_rows(pieces, whole)


def test_refuses_a_directory_made_by_another_command(reference_dataset, object_specs):
    before = sorted(p.name for p in reference_dataset.iterdir())
    with pytest.raises(DatasetError, match="seed 5 there vs 6 here"):
        generate(object_specs, SAMPLES, reference_dataset, seed=6, shard_size=SHARD_SIZE)
    with pytest.raises(DatasetError, match="samples"):
        generate(object_specs, 10, reference_dataset, seed=SEED, shard_size=SHARD_SIZE)
    assert sorted(p.name for p in reference_dataset.iterdir()) == before


def test_refuses_a_foreign_directory(tmp_path, box_mesh):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(DatasetError, match="not empty"):
        generate([str(box_mesh)], 4, tmp_path, workers=1)


def test_damaged_shard_and_stale_temporary_are_redone(tmp_path, box_mesh, reference_table):
    out = tmp_path / "ds"
    generate([str(box_mesh)], 24, out, seed=SEED, workers=1, shard_size=8)
    shards = shard_paths(out)
    assert len(shards) == 3
    shards[1].write_bytes(b"PAR1 not really")  # damaged after it was written
    stale = out / f".{shards[2].name}.tmp-12345"
    stale.write_bytes(b"half a shard")
    summary = generate([str(box_mesh)], 24, out, seed=SEED, workers=1, shard_size=8)
    assert (summary.shards_written, summary.shards_skipped) == (1, 2)
    assert not stale.exists()
    same_rows(read_dataset(out), rows_of(reference_table, "box.stl", 0, 24))


def _cli(args: list[str]) -> list[str]:
    return [sys.executable, "-m", "affordgrasp.cli", *args]


def _start(cmd: list[str]) -> subprocess.Popen:
    # Its own process group, like a shell job: signals reach the workers too.
    return subprocess.Popen(
        as_in_a_terminal(cmd),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _wait_for_shards(out, at_least: int, proc: subprocess.Popen, timeout: float = 60) -> int:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        n = len(shard_paths(out)) if out.exists() else 0
        if n >= at_least:
            return n
        if proc.poll() is not None:
            raise AssertionError(f"generation ended early: {proc.communicate()}")
        time.sleep(0.005)
    raise AssertionError("no shard appeared in time")


def test_ctrl_c_then_kill_9_then_resume_equals_an_uninterrupted_run(
    tmp_path, object_specs, reference_dataset, reference_table
):
    out = tmp_path / "ds"
    cmd = _cli(
        ["generate", *object_specs, "--samples", str(SAMPLES), "--out", str(out)]
        + ["--seed", str(SEED), "--shard-size", str(SHARD_SIZE), "--workers", "2"]
        + ["--chunk-size", "8"]
    )
    total = len(plan_shards(2, SAMPLES, SHARD_SIZE))

    # Ctrl-C (SIGINT to the process group, as a terminal sends it): a clean stop.
    proc = _start(cmd)
    _wait_for_shards(out, 1, proc)
    # Frozen first, so that the interrupt lands mid-run however fast the machine finishes
    # the remaining shards.
    os.killpg(proc.pid, signal.SIGSTOP)
    assert len(shard_paths(out)) < total
    os.killpg(proc.pid, signal.SIGINT)
    os.killpg(proc.pid, signal.SIGCONT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Run the same command to finish" in err
    first = len(shard_paths(out))
    assert 1 <= first < total
    card = json.loads((out / "_card.json").read_text())
    assert card["complete"] is False and card["shards"] == first

    # kill -9 of the driver and its workers, mid-run.
    proc = _start(cmd)
    _wait_for_shards(out, first + 1, proc)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    assert len(shard_paths(out)) < total

    # The same command again finishes the job.
    proc = _start(cmd + ["--json"])
    stdout, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    summary = json.loads(stdout)
    assert summary["complete"] and summary["shards_skipped"] >= first + 1
    assert summary["shards_skipped"] + summary["shards_written"] == total

    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == []
    same_rows(read_dataset(out), reference_table)
    card = json.loads((out / "_card.json").read_text())
    ref_card = json.loads((reference_dataset / "_card.json").read_text())
    assert card["complete"] and card["status_counts"] == ref_card["status_counts"]
    assert [r["complete"] for r in card["runs"]] == [False, True]  # kill -9 leaves no record


def test_generate_uses_the_hand_object_it_is_given(tmp_path, box_mesh):
    # Regression: the hand travelled to the jobs by name, so a custom hand named "barrett"
    # was silently replaced by the built-in Barrett.
    import dataclasses

    from affordgrasp.hands import get_hand
    from affordgrasp.pipeline import evaluate_samples

    custom = dataclasses.replace(get_hand("parallel_jaw"), name="barrett")
    generate([str(box_mesh)], 6, tmp_path / "custom", seed=3, workers=1, hand=custom)
    got = read_dataset(tmp_path / "custom")
    assert {len(j) for j in got["joints"].to_pylist()} == {len(custom.dofs)}
    seed = got["seed"][0].as_py()
    expected = evaluate_samples(str(box_mesh), 6, seed=seed, hand=custom).table
    assert got["joints"].to_pylist() == expected["joints"].to_pylist()
    assert got["epsilon"].to_pylist() == expected["epsilon"].to_pylist()


def test_the_manifest_records_the_whole_hand(tmp_path, box_mesh):
    # A custom hand named like a built-in one: the name alone cannot tell them apart.
    import dataclasses

    from affordgrasp.dataset.reading import dataset_hand
    from affordgrasp.hands import get_hand, hand_to_dict

    custom = dataclasses.replace(get_hand("parallel_jaw"), name="barrett")
    out = tmp_path / "custom"
    generate([str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand=custom)
    manifest = json.loads((out / "_manifest.json").read_text())
    assert manifest["hand"] == "barrett"
    assert manifest["hand_spec"] == json.loads(json.dumps(hand_to_dict(custom)))
    assert hand_to_dict(dataset_hand(out)) == hand_to_dict(custom)
    from affordgrasp.viz.sources import DatasetSource

    assert hand_to_dict(DatasetSource(out).hand) == hand_to_dict(custom)  # show draws it

    with pytest.raises(DatasetError) as refused:
        generate([str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand="barrett")
    message = str(refused.value)
    assert refused.value.parameter == "hand"
    assert "hand 'barrett' is not the hand the dataset" in message
    assert "same name, different dofs, fingers, links, pregrasp_dof" in message
    assert "_manifest.json" in message and "new output directory" in message

    # The fix the message names: the manifest reads as a hand file.
    again = generate(
        [str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand=out / "_manifest.json"
    )
    assert again.shards_skipped == 2 and again.samples_written == 0


def test_a_manifest_without_the_hand_spec_still_reads_and_resumes(tmp_path, box_mesh):
    from affordgrasp.dataset.reading import dataset_hand
    from affordgrasp.hands import get_hand, hand_to_dict

    out = tmp_path / "old"
    generate([str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand="parallel_jaw")
    path = out / "_manifest.json"
    manifest = json.loads(path.read_text())
    del manifest["hand_spec"]  # as written before hands were recorded whole
    path.write_text(json.dumps(manifest))
    assert hand_to_dict(dataset_hand(out)) == hand_to_dict(get_hand("parallel_jaw"))
    assert read_dataset(out).num_rows == 4
    again = generate([str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand="parallel_jaw")
    assert again.shards_skipped == 2
    with pytest.raises(DatasetError, match="hand 'parallel_jaw' there vs 'barrett' here"):
        generate([str(box_mesh)], 4, out, seed=3, workers=1, shard_size=2, hand="barrett")
    with pytest.raises(HandError, match="records its hand by name only .'parallel_jaw'"):
        get_hand(path)


def test_the_manifest_records_the_materials_and_a_resume_must_match(tmp_path):
    from affordgrasp.dataset.card import read_card

    out = tmp_path / "materials"
    generate(["knife"], 2, out, seed=3, workers=1, shard_size=2, metrics=False, materials=True)
    manifest = json.loads((out / "_manifest.json").read_text())
    assert manifest["materials"] is True
    card = read_card(out)
    assert card["materials"] is True and card["objects"][0]["materials"] is True
    assert card["objects"][0]["density_kg_m3"] > 1000  # steel and plastic
    with pytest.raises(DatasetError, match="per-part materials .--materials. there vs unit"):
        generate(["knife"], 2, out, seed=3, workers=1, shard_size=2, metrics=False)
    again = generate(
        ["knife"], 2, out, seed=3, workers=1, shard_size=2, metrics=False, materials=True
    )
    assert again.shards_skipped == 1

    # the default is unit density; a manifest from before the key reads as unit density
    plain = tmp_path / "plain"
    generate(["knife"], 2, plain, seed=3, workers=1, shard_size=2, metrics=False)
    path = plain / "_manifest.json"
    manifest = json.loads(path.read_text())
    assert manifest["materials"] is False
    assert read_card(plain)["objects"][0]["density_kg_m3"] == 1.0
    del manifest["materials"]
    path.write_text(json.dumps(manifest))
    assert (
        generate(["knife"], 2, plain, seed=3, workers=1, shard_size=2, metrics=False).shards_skipped
        == 1
    )
    with pytest.raises(DatasetError, match="unit density there vs per-part materials"):
        generate(
            ["knife"], 2, plain, seed=3, workers=1, shard_size=2, metrics=False, materials=True
        )


def test_the_gws_volume_is_computed_on_request_recorded_and_resumed(tmp_path):
    from affordgrasp.dataset.card import read_card
    from affordgrasp.dataset.reading import dataset_volume

    plain, full = tmp_path / "plain", tmp_path / "full"
    generate(["knife"], 6, plain, seed=3, workers=1, shard_size=3)
    generate(["knife"], 6, full, seed=3, workers=1, shard_size=3, volume=True)
    assert json.loads((plain / "_manifest.json").read_text())["volume"] is False
    assert json.loads((full / "_manifest.json").read_text())["volume"] is True
    assert read_card(plain)["gws_volume"] is False and read_card(full)["gws_volume"] is True
    assert "GWS volume: not computed" in (plain / "_card.md").read_text()
    a, b = read_dataset(plain), read_dataset(full)
    assert a.schema == b.schema and a["gws_volume"].null_count == 6
    assert b["gws_volume"].null_count == 0
    assert np.all((b["gws_volume"].to_numpy() > 0) == (b["epsilon"].to_numpy() > 0))
    assert not dataset_volume(plain) and dataset_volume(full)
    with pytest.raises(DatasetError, match="GWS volume not computed there vs computed"):
        generate(["knife"], 6, plain, seed=3, workers=1, shard_size=3, volume=True)

    # a dataset from before the volume was optional computed it: it resumes with it only
    path = full / "_manifest.json"
    manifest = json.loads(path.read_text())
    del manifest["volume"]
    path.write_text(json.dumps(manifest))
    assert dataset_volume(full)
    again = generate(["knife"], 6, full, seed=3, workers=1, shard_size=3, volume=True)
    assert again.shards_skipped == 2
    with pytest.raises(DatasetError, match="GWS volume computed .--metrics .volume. there vs not"):
        generate(["knife"], 6, full, seed=3, workers=1, shard_size=3)


def test_a_worker_keeps_a_few_objects_and_rebuilds_one_that_left(monkeypatch):
    # a run of many objects must not keep every prepared object alive in a worker
    from affordgrasp.dataset import jobs
    from affordgrasp.objects import load_object
    from affordgrasp.pipeline import evaluate_samples
    from affordgrasp.runtime.engines import run_job

    monkeypatch.setattr(jobs, "_KEEP_OBJECTS", 2)
    objects = [load_object(f"knife:{v}") for v in range(4)]
    context = jobs.RunContext(
        objects=tuple(jobs.ObjectPayload.from_object(o) for o in objects),
        hand="barrett",
        seed=SEED,
    )
    first = run_job(jobs.Job(0, 0, 3), context)
    for index in (1, 2, 3):
        run_job(jobs.Job(index, 0, 3), context)
        assert len(jobs._OBJECTS) <= 2
    assert list(jobs._OBJECTS) == [2, 3]
    again = run_job(jobs.Job(0, 0, 3), context)  # rebuilt: the same rows
    same_rows(again, first)
    same_rows(first, evaluate_samples("knife:0", 3, seed=SEED).table)
