"""Damaged shards are detected and named; a full or unwritable disk is a clear exit 2 that
leaves nothing half-written behind."""

from __future__ import annotations

import errno
import json
import os
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from dataset_support import SEED

from affordgrasp.cli import main
from affordgrasp.dataset.checksums import (
    CHECKSUM_ALGORITHM,
    CHECKSUMS_NAME,
    file_checksum,
    read_checksums,
    shard_damage,
)
from affordgrasp.dataset.generate import generate
from affordgrasp.dataset.manifest import FORMAT_VERSION
from affordgrasp.dataset.reading import iter_batches, read_dataset
from affordgrasp.dataset.shards import ADDED_COLUMNS, shard_paths
from affordgrasp.errors import DatasetError
from affordgrasp.runtime import writing

SAMPLES, SHARD = 24, 8


@pytest.fixture(scope="module")
def pristine(tmp_path_factory, box_mesh):
    out = tmp_path_factory.mktemp("integrity") / "ds"
    generate([str(box_mesh)], SAMPLES, out, seed=SEED, workers=1, shard_size=SHARD)
    return out


@pytest.fixture
def dataset(pristine, tmp_path):
    out = tmp_path / "ds"
    shutil.copytree(pristine, out)
    return out


def _generate(box_mesh, out) -> int:
    argv = ["generate", str(box_mesh), "--samples", str(SAMPLES), "--out", str(out)]
    return main([*argv, "--seed", str(SEED), "--shard-size", str(SHARD), "--workers", "1"])


def _overwrite_mid_file(path: Path) -> None:
    """Change bytes in the middle of the column data; the footer stays intact."""
    data = bytearray(path.read_bytes())
    middle = len(data) // 3
    data[middle : middle + 64] = bytes((b ^ 0x5A) for b in data[middle : middle + 64])
    path.write_bytes(bytes(data))
    pq.read_metadata(path)  # still a valid footer: only the checksum can tell


def test_every_shard_has_a_recorded_checksum(pristine):
    records = read_checksums(pristine)
    shards = shard_paths(pristine)
    assert sorted(records) == [p.name for p in shards]
    for p in shards:
        assert records[p.name]["bytes"] == p.stat().st_size
        assert shard_damage(p, records[p.name]) is None


def test_shard_overwritten_mid_file_is_refused_by_readers(dataset, capsys):
    damaged = shard_paths(dataset)[1]
    _overwrite_mid_file(damaged)
    with pytest.raises(DatasetError, match=rf"{damaged.name}: its content differs"):
        read_dataset(dataset)
    with pytest.raises(DatasetError, match=damaged.name):
        next(iter_batches(dataset, columns=["sample"]))
    assert main(["best", str(dataset), "--task", "pick"]) == 2
    err = capsys.readouterr().err
    assert damaged.name in err and "affordgrasp generate" in err and err.count("\n") == 1
    out = dataset.parent / "plots"
    assert main(["plots", str(dataset), "-o", str(out), "--no-tasks"]) == 2
    assert damaged.name in capsys.readouterr().err


def test_shard_overwritten_mid_file_is_rewritten_on_resume(dataset, box_mesh, pristine):
    damaged = shard_paths(dataset)[1]
    _overwrite_mid_file(damaged)
    assert _generate(box_mesh, dataset) == 0
    assert damaged.read_bytes() == (pristine / damaged.name).read_bytes()
    assert read_dataset(dataset).equals(read_dataset(pristine))


def test_best_on_a_truncated_shard_names_the_file(dataset, capsys):
    damaged = shard_paths(dataset)[2]
    damaged.write_bytes(damaged.read_bytes()[: damaged.stat().st_size // 2])
    assert main(["best", str(dataset), "--task", "pick"]) == 2
    err = capsys.readouterr().err
    assert damaged.name in err and "bytes long" in err, err
    assert "ArrowInvalid" not in err and "Traceback" not in err


def test_truncated_file_in_a_plain_parquet_folder_is_named(pristine, tmp_path, capsys):
    # Not a dataset (no manifest, no checksums): the footers are checked, the file named.
    folder = tmp_path / "loose"
    folder.mkdir()
    for p in shard_paths(pristine):
        shutil.copy(p, folder / p.name)
    bad = folder / shard_paths(pristine)[0].name
    bad.write_bytes(bad.read_bytes()[:500])
    assert main(["plots", str(folder), "-o", str(tmp_path / "p"), "--no-tasks"]) == 2
    err = capsys.readouterr().err
    assert bad.name in err and err.count("\n") == 1, err


def test_shard_without_a_checksum_is_refused(dataset):
    records = (dataset / CHECKSUMS_NAME).read_text().splitlines()
    (dataset / CHECKSUMS_NAME).write_text("\n".join(records[1:]) + "\n")
    with pytest.raises(DatasetError, match="no checksum was recorded"):
        read_dataset(dataset)


def test_disk_full_exits_2_naming_the_file_and_leaves_no_partial_file(
    tmp_path, box_mesh, pristine, monkeypatch, capsys
):
    out = tmp_path / "ds"
    real_write = writing.write_file
    shards_written = []

    def full_disk(path, data, fsync=True):
        if ".part-" in path.name and len(shards_written) == 1:
            with open(path, "wb") as f:
                f.write(data[: len(data) // 2])  # what a full disk leaves
            raise OSError(errno.ENOSPC, "No space left on device")
        real_write(path, data)
        if ".part-" in path.name:
            shards_written.append(path)

    monkeypatch.setattr(writing, "write_file", full_disk)
    assert _generate(box_mesh, out) == 2
    err = capsys.readouterr().err
    err = _one_line(err)
    assert "No space left on device" in err and "part-00000-000000000008.parquet" in err, err
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []
    assert [p.name for p in shard_paths(out)] == ["part-00000-000000000000.parquet"]
    read_dataset(out)  # what is there is whole and verified

    monkeypatch.setattr(writing, "write_file", real_write)
    assert _generate(box_mesh, out) == 0
    assert read_dataset(out).equals(read_dataset(pristine))


def test_output_that_is_not_a_directory_exits_2(tmp_path, box_mesh, capsys):
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    assert _generate(box_mesh, blocker / "ds") == 2
    assert "a-file" in _one_line(capsys.readouterr().err)


def test_read_only_output_directory_exits_2_before_any_work(
    tmp_path, box_mesh, monkeypatch, capsys
):
    readonly = tmp_path / "readonly"
    readonly.mkdir()
    readonly.chmod(0o555)
    if os.access(readonly, os.W_OK):
        # root writes anywhere: answer as the kernel does for everyone else.
        real_mkdir, real_write = Path.mkdir, writing.write_file

        def denied(path):
            if Path(path).is_relative_to(readonly):
                raise PermissionError(errno.EACCES, "Permission denied", str(path))

        def mkdir(self, *args, **kwargs):
            denied(self)
            return real_mkdir(self, *args, **kwargs)

        def write_file(path, data, fsync=True):
            denied(path)
            return real_write(path, data)

        monkeypatch.setattr(Path, "mkdir", mkdir)
        monkeypatch.setattr(writing, "write_file", write_file)
    for out in (readonly / "ds", readonly):
        assert _generate(box_mesh, out) == 2
        err = _one_line(capsys.readouterr().err)
        assert repr(str(out)) in err and "Permission denied" in err, err
    assert list(readonly.iterdir()) == []


def _one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


def test_manifest_records_the_format_with_checksums(pristine):
    manifest = json.loads((pristine / "_manifest.json").read_text())
    assert manifest["format_version"] == FORMAT_VERSION >= 2


def test_full_disk_while_writing_best_or_an_export_leaves_no_file(
    pristine, tmp_path, monkeypatch, capsys
):
    real_write = writing.write_file

    def full_disk(path, data, fsync=True):
        if not Path(path).is_relative_to(tmp_path):  # the object cache: a disk with room
            return real_write(path, data, fsync=fsync)
        with open(path, "wb") as f:
            f.write(data[: len(data) // 2])
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(writing, "write_file", full_disk)
    top = tmp_path / "top.parquet"
    assert main(["best", str(pristine), "--task", "pick", "--out", str(top)]) == 2
    assert "top.parquet" in _one_line(capsys.readouterr().err)
    mesh = tmp_path / "knife.stl"
    assert main(["objects", "export", "knife", "-o", str(mesh)]) == 2
    assert "No space left on device" in _one_line(capsys.readouterr().err)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------ the plan's shards: missing, extra, foreign


@pytest.fixture(scope="module")
def other_seed(tmp_path_factory, box_mesh):
    """The same object and plan under another seed: its shards are not the pristine's."""
    out = tmp_path_factory.mktemp("integrity-other") / "ds"
    generate([str(box_mesh)], SAMPLES, out, seed=SEED + 1, workers=1, shard_size=SHARD)
    return out


def _forge(dataset: Path, name: str, data: bytes) -> None:
    """Put ``data`` under the shard name ``name`` with its checksum line updated to match."""
    (dataset / name).write_bytes(data)
    records = [r for r in read_checksums(dataset).values() if r["name"] != name]
    records.append({"name": name, "bytes": len(data), CHECKSUM_ALGORITHM: file_checksum(data)})
    (dataset / CHECKSUMS_NAME).write_text("".join(json.dumps(r) + "\n" for r in records))


def _damage(kind: str, dataset: Path, other: Path) -> str:
    """Damage ``dataset`` one way; the name of the shard in question."""
    shards = shard_paths(dataset)
    if kind == "missing":
        shards[1].unlink()
        return shards[1].name
    if kind == "extra":
        extra = dataset / "part-00001-000000000000.parquet"
        shutil.copy(shards[0], extra)
        return extra.name
    _forge(dataset, shards[1].name, (other / shards[1].name).read_bytes())
    return shards[1].name


COMMANDS = {
    "best": lambda d, o: ["best", d, "--task", "pick"],
    "plots": lambda d, o: ["plots", d, "-o", o / "plots", "--no-tasks"],
    "show": lambda d, o: ["show", d, "--task", "pick", "-o", o / "show"],
    "physics": lambda d, o: ["physics", d, "--out", o / "physics", "--workers", "1"],
    "predict": lambda d, o: ["predict", "default", d, "--out", o / "p.parquet"],
    "model-eval": lambda d, o: ["model-eval", "default", d],
    "train": lambda d, o: ["train", d, "--epochs", "1", "-o", o / "m.safetensors"],
}


@pytest.mark.parametrize("kind", ["missing", "extra", "foreign"])
@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_reader_refuses_a_shard_list_that_is_not_the_plan(
    kind, command, dataset, other_seed, tmp_path, capsys
):
    if command in ("predict", "model-eval", "train"):
        pytest.importorskip("torch")
    name = _damage(kind, dataset, other_seed)
    results = tmp_path / "results"
    results.mkdir()
    assert main([str(a) for a in COMMANDS[command](dataset, results)]) == 2
    err = _one_line(capsys.readouterr().err)
    assert name in err and "Traceback" not in err, err
    fix = {
        "missing": "resume the generation with",
        "extra": "remove the file",
        "foreign": "seed",
    }[kind]
    assert fix in err, err
    assert list(results.iterdir()) == []


def test_foreign_shards_of_every_kind_are_named(dataset, other_seed, tmp_path, box_mesh):
    name = shard_paths(dataset)[1].name
    table = pq.read_table(dataset / name)

    def forged(table) -> bytes:
        path = tmp_path / "forged.parquet"
        pq.write_table(table, path)
        return path.read_bytes()

    no_metrics = table.select(table.schema.names[: table.schema.get_field_index("epsilon")])
    other_mesh = tmp_path / "other-mesh"
    generate(["knife"], SAMPLES, other_mesh, seed=SEED, workers=1, shard_size=SHARD)
    resized = tmp_path / "resized"
    generate([str(box_mesh)], SAMPLES, resized, seed=SEED, workers=1, shard_size=SHARD // 2)
    for data, why in (
        (forged(no_metrics), "missing: epsilon"),
        (forged(table.replace_schema_metadata({})), "no shard facts"),
        (forged(table.slice(0, 4)), "rows"),
        ((other_mesh / name).read_bytes(), "footer says it holds 'knife:0'"),
        ((resized / name).read_bytes(), "samples 8 to 12"),
        ((other_seed / name).read_bytes(), "seed"),
    ):
        _forge(dataset, name, data)
        with pytest.raises(DatasetError, match=rf"{name}: .*{why}"):
            read_dataset(dataset)
    # Resuming the generation puts the planned shard back.
    assert _generate(box_mesh, dataset) == 0
    read_dataset(dataset)


def test_a_lost_shard_is_refused_and_resuming_writes_it_again(dataset, pristine, box_mesh):
    shard_paths(dataset)[0].unlink()
    with pytest.raises(DatasetError, match="lost the shard part-00000-000000000000"):
        read_dataset(dataset)
    assert _generate(box_mesh, dataset) == 0
    assert read_dataset(dataset).equals(read_dataset(pristine))


def test_an_unfinished_dataset_reads_with_a_warning_naming_what_is_missing(dataset, caplog, capsys):
    # As a run stopped before its last shard leaves it: no file, no checksum, card incomplete.
    last = shard_paths(dataset)[-1]
    last.unlink()
    records = [r for r in read_checksums(dataset).values() if r["name"] != last.name]
    (dataset / CHECKSUMS_NAME).write_text("".join(json.dumps(r) + "\n" for r in records))
    card = json.loads((dataset / "_card.json").read_text())
    (dataset / "_card.json").write_text(json.dumps({**card, "complete": False}))
    with caplog.at_level("WARNING", logger="affordgrasp"):
        assert read_dataset(dataset).num_rows == SAMPLES - SHARD
    assert "unfinished: 1 of its 3 shards (8 of 24 rows)" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="affordgrasp"):
        assert main(["best", str(dataset), "--task", "pick"]) == 0
    assert "scanned 16 samples" in capsys.readouterr().out
    assert "resume the generation" in caplog.text


def test_a_dataset_of_the_previous_release_still_opens(box_mesh, tmp_path, caplog):
    # The previous release: format version 1 (no checksums, no object seeds: every object
    # drew the run's samples), shards without the columns added since.
    old = tmp_path / "old"
    generate([str(box_mesh)], SAMPLES, old, seed=SEED, workers=1, shard_size=SHARD,
             streams="shared")  # fmt: skip
    manifest = json.loads((old / "_manifest.json").read_text())
    for key in ("hand_spec", "materials", "volume", "sample_streams"):
        manifest.pop(key)
    for entry in manifest["objects"]:
        entry.pop("seed")
    (old / "_manifest.json").write_text(json.dumps({**manifest, "format_version": 1}))
    (old / CHECKSUMS_NAME).unlink()
    for p in shard_paths(old):
        table = pq.read_table(p)
        pq.write_table(table.drop_columns(sorted(ADDED_COLUMNS)), p)
    with caplog.at_level("WARNING", logger="affordgrasp"):
        table = read_dataset(old)
    assert table.num_rows == SAMPLES and "earlier version" in caplog.text
    shard_paths(old)[1].unlink()  # the card says the run completed: a lost shard
    with pytest.raises(DatasetError, match="lost the shard part-00000-000000000008"):
        read_dataset(old)


def test_a_shard_checked_before_is_not_read_again_until_it_changes(dataset, monkeypatch):
    """Between processes, a shard whose size, modification time, inode and checksum are
    those it had when it was checked is trusted; one written since is checked again."""
    from affordgrasp.dataset import checksums, shards

    read_dataset(dataset)  # checks every shard and records them (the user cache)
    # a new process: nothing verified in memory
    monkeypatch.setattr(checksums, "_VERIFIED", set())
    monkeypatch.setattr(shards, "_AS_PLANNED", set())
    calls = []
    real = shards.shard_damage
    monkeypatch.setattr(shards, "shard_damage", lambda p, r: calls.append(p) or real(p, r))
    read_dataset(dataset)
    assert calls == []
    damaged = shard_paths(dataset)[1]
    _overwrite_mid_file(damaged)  # same size, a new modification time
    with pytest.raises(DatasetError, match=rf"{damaged.name}: its content differs"):
        read_dataset(dataset)
    assert calls == [damaged]


def test_scanning_file_by_file_reads_the_rows_the_dataset_holds(dataset):
    """scan_files: the dataset's rows in its file order, a filter applied, a column a file
    lacks read as null (as the dataset reads it)."""
    import pyarrow as pa
    import pyarrow.dataset as pads

    from affordgrasp.dataset.handle import Dataset, scan_files

    arrow = Dataset.open(dataset).arrow()
    whole = arrow.to_table(columns=["sample", "epsilon"])
    got = pa.Table.from_batches(list(scan_files(arrow, ["sample", "epsilon"], batch_size=5)))
    assert got.equals(whole)
    assert max(b.num_rows for b in scan_files(arrow, ["sample"], batch_size=5)) == 5
    flt = pads.field("sample") >= 20
    kept = pa.Table.from_batches(list(scan_files(arrow, ["sample"], flt)))
    assert kept.column("sample").to_pylist() == list(range(20, SAMPLES))
    # a loose file without a column the dataset schema has
    loose = dataset.parent / "loose"
    loose.mkdir()
    first = shard_paths(dataset)[0]
    pq.write_table(pq.read_table(first).drop_columns(["epsilon"]), loose / "a.parquet")
    ds = pads.dataset([str(loose / "a.parquet")], schema=arrow.schema, format="parquet")
    t = pa.Table.from_batches(list(scan_files(ds, ["sample", "epsilon"])))
    assert t.column("epsilon").null_count == t.num_rows == SHARD
