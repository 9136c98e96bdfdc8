"""The physics run's orchestration: the dataset's objects, mass properties included."""

from __future__ import annotations

import dataclasses

import numpy as np
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

    def fake_validate_shard(out_dir, k, rows, hand, objects, settings):
        shipped.update(objects)
        return {"rows": rows.num_rows, "steps": 0, "seconds": 0.0, "cpu_seconds": 0.0}

    # The orchestration only: no decomposition, no MuJoCo.
    monkeypatch.setattr(run, "convex_parts_of", lambda obj, settings: [])
    monkeypatch.setattr(run, "validate_shard", fake_validate_shard)
    run.run_physics(out, tmp_path / "phys", statuses=statuses, workers=1)
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
