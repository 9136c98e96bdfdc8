"""The Dataset handle: opened once, one rule for its objects, old manifests still open."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from affordgrasp.dataset import Dataset
from affordgrasp.dataset.handle import find_object, object_specs
from affordgrasp.errors import DatasetError


def test_generate_returns_the_opened_dataset(reference_dataset, reference_table):
    ds = Dataset.open(reference_dataset)
    assert ds.objects == ["knife:0", "box.stl"]
    assert ds.families["knife:0"] == "knife" and ds.families["box.stl"] == "mesh"
    assert ds.hand.name == "barrett" and not ds.materials and ds.metrics
    assert ds.read().equals(reference_table)
    assert ds.select(["knife"]) == ["knife:0"]
    assert ds.count_rows(["knife"]) == reference_table.num_rows // 2
    assert Dataset.open(ds) is ds and str(ds) == str(reference_dataset)
    with pytest.raises(DatasetError, match="box.stl"):
        ds.select(["axe"])


def test_summary_of_generate_carries_the_dataset(tmp_path, box_mesh):
    from affordgrasp.dataset.generate import generate

    summary = generate([str(box_mesh)], 4, tmp_path / "d", seed=1, workers=1, shard_size=4)
    assert isinstance(summary.dataset, Dataset)
    assert summary.dataset.objects == ["box.stl"] and summary.dataset.read().num_rows == 4
    assert "dataset" not in summary.to_dict()  # the JSON document is unchanged


def test_objects_resolve_by_one_rule_and_check_the_mesh(reference_dataset, box_mesh):
    ds = Dataset.open(reference_dataset)
    knife = ds.object("knife")
    assert knife.name == "knife:0" and knife.mesh_hash == ds.mesh_hash("knife:0")
    box = ds.object("box.stl")
    assert box.mesh_hash == ds.mesh_hash("box.stl") and box.source == str(box_mesh.resolve())
    assert ds.object("box.stl") is box  # resolved once per handle


def test_a_moved_mesh_is_found_in_meshes_or_refused_with_the_fix(reference_dataset, tmp_path):
    copy = tmp_path / "ds"
    shutil.copytree(reference_dataset, copy)
    manifest = json.loads((copy / "_manifest.json").read_text())
    moved = tmp_path / "elsewhere" / "box.stl"
    moved.parent.mkdir()
    shutil.copy(manifest["objects"][1]["source"], moved)
    manifest["objects"][1]["source"] = str(tmp_path / "gone" / "box.stl")
    (copy / "_manifest.json").write_text(json.dumps(manifest))
    ds = Dataset.open(copy)
    with pytest.raises(DatasetError, match="--mesh PATH"):
        ds.object("box.stl")
    assert ds.object("box.stl", meshes=[str(moved)]).mesh_hash == ds.mesh_hash("box.stl")
    # Another mesh of the same name is not the dataset's: refused, not used.
    import trimesh

    other = tmp_path / "other" / "box.stl"
    other.parent.mkdir()
    trimesh.creation.box([0.1, 0.1, 0.1]).export(other)
    with pytest.raises(DatasetError, match="another mesh"):
        ds.object("box.stl", meshes=[str(other)])


def test_a_manifest_of_the_first_format_still_opens(reference_dataset, tmp_path):
    copy = tmp_path / "old"
    shutil.copytree(reference_dataset, copy)
    manifest = json.loads((copy / "_manifest.json").read_text())
    for key in ("hand_spec", "materials", "volume", "robust", "depth"):
        manifest.pop(key, None)
    manifest["format_version"] = 1
    (copy / "_manifest.json").write_text(json.dumps(manifest))
    ds = Dataset.open(copy)
    assert ds.hand.name == "barrett" and not ds.materials and ds.volume == ds.metrics
    assert ds.robust is None and not ds.depth
    assert ds.read(columns=["object"]).num_rows == 2 * ds.samples
    assert ds.object("knife").mesh_hash == ds.mesh_hash("knife:0")


def test_materials_reach_the_dataset_objects(tmp_path):
    from affordgrasp.dataset.generate import generate
    from affordgrasp.objects import load_object

    out = tmp_path / "m"
    generate(["hammer"], 2, out, seed=0, workers=1, materials=True)
    obj = Dataset.open(out).object("hammer")
    assert obj.materials
    expected = load_object("hammer", materials=True).mass
    uniform = load_object("hammer").mass
    assert obj.mass.mass == pytest.approx(expected.mass)
    assert not np.isclose(obj.mass.mass, uniform.mass)


def test_scan_variants_of_mesh_files_are_degraded_again():
    specs = object_specs("part.stl~scan:3", "/data/part.stl", meshes=["/m/part.stl", "/m/x.stl"])
    assert specs == ["/m/part.stl~scan:3", "/data/part.stl~scan:3"]
    assert object_specs("knife:2~scan", "family") == ["knife:2~scan"]
    # Rows without a manifest: the offered files, then the name itself.
    assert object_specs("a.off", None, meshes=["/m/a.off"]) == ["/m/a.off", "a.off"]


def test_resolve_object_of_loose_rows_and_bad_options(box_mesh):
    obj = find_object("box.stl", source=None, meshes=[str(box_mesh)])
    assert obj.name == "box.stl"
    with pytest.raises(DatasetError, match="generated on"):
        find_object("box.stl", source=None)
    with pytest.raises(ValueError, match="changed_family"):
        find_object("knife", changed_family="maybe")


def test_the_dataset_splits_its_objects_as_training_does(tmp_path):
    from affordgrasp.dataset.generate import generate
    from affordgrasp.dataset.splits import split_by_object as learning_split
    from affordgrasp.errors import InputError

    out = tmp_path / "k"
    generate(["knife:0", "knife:1", "knife:2", "mug:0"], 1, out, seed=0, workers=1)
    ds = Dataset.open(out)
    split = ds.split(seed=3)
    assert set(split.train) | set(split.val) | set(split.test) == set(ds.objects)
    assert split == learning_split(ds.objects, [ds.families[o] for o in ds.objects], seed=3)
    assert len(split.test) == 1 and split.test[0].startswith("knife")
    assert ds.split("family", test_families=[ds.families["mug:0"]]).test == ("mug:0",)
    with pytest.raises(InputError, match="test_families"):
        ds.split("family")


def test_a_mesh_file_named_like_a_scan_variant_is_that_file_to_every_reader(tmp_path, capsys):
    import trimesh

    from affordgrasp.cli import main
    from affordgrasp.dataset.generate import generate

    mesh = tmp_path / "knife~scan.stl"
    trimesh.creation.box((0.12, 0.04, 0.03)).export(mesh)
    out = tmp_path / "ds"
    generate([str(mesh)], 16, out, seed=0, workers=1)
    assert object_specs("knife~scan.stl", str(mesh)) == [str(mesh)]
    assert object_specs("knife~scan.stl", None) == ["knife~scan.stl"]
    ds = Dataset.open(out)
    assert ds.object("knife~scan.stl").mesh_hash == ds.mesh_hash("knife~scan.stl")
    rc = main(["show", str(out), "--task", "pick", "--top", "1", "-o", str(tmp_path / "s")])
    assert rc == 0, capsys.readouterr().err
