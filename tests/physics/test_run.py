"""The physics run's orchestration: the dataset's objects, mass properties included."""

from __future__ import annotations

import dataclasses

import numpy as np
import pyarrow as pa
import pytest

from affordgrasp.physics.settings import PhysicsSettings


def test_a_materials_dataset_is_replayed_with_its_materials(tmp_path, monkeypatch):
    import affordgrasp.physics.run as run
    from affordgrasp.dataset import Dataset
    from affordgrasp.dataset.generate import generate
    from affordgrasp.objects import load_object

    out = tmp_path / "ds"
    generate(["hammer"], 6, out, seed=0, workers=1, materials=True)
    statuses = sorted(set(Dataset.open(out).read(columns=["status"])["status"].to_pylist()))
    shipped = {}

    def fake_validate_rows(rows, hand, objects, settings, *args, **kwargs):
        shipped.update(objects)
        n = rows.num_rows
        return (
            rows.select(["object"])
            .append_column("hold_ok", pa.array([True] * n))
            .append_column("steps", pa.array([0] * n, pa.int64()))
        )

    # The orchestration only: no decomposition, no MuJoCo.
    monkeypatch.setattr(run, "convex_parts_of", lambda obj, settings: [])
    monkeypatch.setattr(run, "validate_rows", fake_validate_rows)
    summary = run.run_physics(out, tmp_path / "phys", statuses=statuses, workers=1)
    assert summary.rows_written == summary.rows and sum(summary.hold_ok["hammer:0"]) > 0
    payload = shipped["hammer:0"]
    steel = load_object("hammer", materials=True).mass
    assert payload.materials and payload.mass.mass == pytest.approx(steel.mass)
    assert not np.isclose(payload.mass.mass, load_object("hammer").mass.mass)
    np.testing.assert_allclose(payload.mass.center_of_mass, steel.center_of_mass)


def test_the_scene_weighs_an_object_by_its_materials(box_object):
    from affordgrasp.objects import mass_properties
    from affordgrasp.physics.scene import build_scene

    settings = PhysicsSettings()
    uniform = build_scene("parallel_jaw", box_object, settings)
    assert uniform.object_mass == pytest.approx(settings.density * box_object.mass.volume)
    steel = dataclasses.replace(
        box_object, mass=mass_properties(box_object.mesh, density=7850.0), materials=True
    )
    scene = build_scene("parallel_jaw", steel, settings)
    assert scene.object_mass == pytest.approx(7850.0 * box_object.mass.volume)
    # The fixed mass of the DexGraspBench protocol still wins.
    fixed = build_scene("parallel_jaw", steel, dataclasses.replace(settings, object_mass_kg=0.2))
    assert fixed.object_mass == pytest.approx(0.2)


def test_the_local_pool_writes_the_rows_of_one_process(tmp_path):
    import trimesh

    from affordgrasp.dataset.generate import generate
    from affordgrasp.physics.run import read_outcomes, run_physics

    mesh = tmp_path / "block.stl"
    trimesh.creation.box([0.05, 0.03, 0.04]).export(mesh)
    data = tmp_path / "ds"
    generate([str(mesh)], 24, data, seed=2, workers=1, shard_size=12, hand="parallel_jaw")
    options = dict(max_per_object=4, shard_size=2, settings=PhysicsSettings())
    one = run_physics(data, tmp_path / "one", workers=1, **options)
    two = run_physics(data, tmp_path / "two", workers=2, **options)
    assert (one.workers, two.workers) == (1, 2) and two.shards_written == 2
    a, b = read_outcomes(tmp_path / "one"), read_outcomes(tmp_path / "two")
    assert a.to_pandas().equals(b.to_pandas())


def test_engine_options_are_checked_before_any_work(tmp_path):
    from affordgrasp.errors import InputError
    from affordgrasp.physics.run import run_physics

    with pytest.raises(InputError, match="unknown engine"):
        run_physics(tmp_path / "nothing", tmp_path / "o", engine="slurm")
    with pytest.raises(InputError, match="engine='ray'"):
        run_physics(tmp_path / "nothing", tmp_path / "o", address="auto")
    assert not (tmp_path / "o").exists()
