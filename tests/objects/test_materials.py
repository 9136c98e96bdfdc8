"""Per-part materials of the built-in families: regions, densities, mass properties."""

from __future__ import annotations

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.objects import list_families, load_object, mass_properties
from affordgrasp.objects.families import make_family
from affordgrasp.objects.families.materials import DENSITY_KG_M3, FAMILY_MATERIALS


@pytest.mark.parametrize("name", list_families())
def test_material_regions_split_the_object_exactly(name):
    mesh = make_family(name, 1, materials=True)
    regions = mesh.metadata["materials"]
    assert regions, "every family has at least one material region"
    volumes = []
    for material, density, region in regions:
        assert density == DENSITY_KG_M3[material]
        assert region.is_watertight and region.volume > 0
        # regions lie inside the object (same frame, origin at the bounding-box centre)
        assert np.all(region.bounds[0] >= mesh.bounds[0] - 1e-9)
        assert np.all(region.bounds[1] <= mesh.bounds[1] + 1e-9)
        volumes.append(region.volume)
    # disjoint and covering: the volumes add up to the object's
    assert sum(volumes) == pytest.approx(mesh.volume, rel=1e-6)
    expected = set(FAMILY_MATERIALS[name].values())
    assert {m for m, _, _ in regions} <= expected


def test_mass_is_the_sum_over_materials_and_the_centre_of_mass_their_lever_rule():
    obj = load_object("hammer:2", materials=True)
    assert obj.materials
    regions = make_family("hammer", 2, materials=True).metadata["materials"]
    masses = np.array([rho * r.volume for _, rho, r in regions])
    centres = np.array([r.center_mass for _, _, r in regions])
    assert obj.mass.mass == pytest.approx(masses.sum(), rel=1e-9)
    np.testing.assert_allclose(
        obj.mass.center_of_mass, masses @ centres / masses.sum(), rtol=0, atol=1e-9
    )
    assert obj.mass.density == pytest.approx(obj.mass.mass / obj.mass.volume)
    # a steel head on a wooden handle: the head holds most of the mass, so the centre of
    # mass lies far closer to the head than the homogeneous object's
    by = dict(zip([m for m, _, _ in regions], masses, strict=True))
    assert by["steel"] > 3 * by["wood"]
    uniform = load_object("hammer:2", density=1.0)
    head = centres[[m == "steel" for m, _, _ in regions]][0]
    assert np.linalg.norm(obj.mass.center_of_mass - head) < 0.5 * np.linalg.norm(
        uniform.mass.center_of_mass - head
    )
    # the inertia tensor stays a valid one: symmetric, positive, triangle inequalities
    eig = np.linalg.eigvalsh(obj.mass.inertia)
    assert np.all(eig > 0) and eig[2] <= eig[0] + eig[1] + 1e-12
    np.testing.assert_array_equal(obj.mass.inertia, obj.mass.inertia.T)


@pytest.mark.parametrize("name", ["bottle", "mug"])
def test_one_material_scales_the_homogeneous_object(name):
    obj = load_object(name, materials=True)
    uniform = load_object(name)
    rho = DENSITY_KG_M3[FAMILY_MATERIALS[name]["*"]]
    assert obj.mass.mass == pytest.approx(rho * uniform.mass.volume, rel=1e-9)
    np.testing.assert_allclose(obj.mass.center_of_mass, uniform.mass.center_of_mass, atol=1e-9)
    np.testing.assert_allclose(obj.mass.inertia, rho * uniform.mass.inertia, rtol=1e-9, atol=0)
    assert obj.mass.r_max == pytest.approx(uniform.mass.r_max)


@pytest.mark.parametrize("name", ["knife:3", "hammer:2", "mug"])
def test_default_is_uniform_unit_density(name):
    obj = load_object(name)
    assert not obj.materials
    assert obj.mass.density == 1.0
    assert obj.mass.mass == pytest.approx(mass_properties(obj.mesh).volume * 1.0, rel=1e-12)
    np.testing.assert_array_equal(obj.mass.inertia, mass_properties(obj.mesh).inertia)
    assert load_object(name, density=1.0).mass.mass == obj.mass.mass


def test_materials_are_an_explicit_option():
    uniform = load_object("knife:3")
    materials = load_object("knife:3", materials=True)
    assert materials.materials and materials.mesh_hash == uniform.mesh_hash
    assert materials.mass.mass > 1000 * uniform.mass.mass  # steel and plastic, not 1 kg/m³
    # the option is part of the cache key: asking again gives the same objects back
    assert load_object("knife:3") is uniform
    assert load_object("knife:3", materials=True) is materials
    # a resolved object: materials=True resolves the family's materials, a density undoes it
    assert load_object(uniform, materials=True) is materials
    again = load_object(materials, density=1.0)
    assert again.mass.density == 1.0 and not again.materials
    assert load_object(materials) is materials


def test_materials_refused_with_a_density_or_a_mesh_file(tmp_path):
    with pytest.raises(InputError, match="pass one of the two"):
        load_object("knife", materials=True, density=1000.0)
    path = tmp_path / "knife.stl"
    load_object("knife").mesh.export(path)
    with pytest.raises(InputError, match="mesh file.*Drop the option"):
        load_object(str(path), materials=True)
    with pytest.raises(InputError, match="mesh file"):
        load_object(path, materials=True)
    with pytest.raises(InputError, match="mesh file"):
        load_object(load_object(str(path)), materials=True)
    assert load_object(str(path)).mass.density == 1.0


def test_workers_rebuild_the_material_mass_properties():
    from affordgrasp.dataset.jobs import ObjectPayload

    obj = load_object("axe:1", materials=True)
    rebuilt = ObjectPayload.from_object(obj).build()
    assert rebuilt.materials
    np.testing.assert_array_equal(rebuilt.mass.center_of_mass, obj.mass.center_of_mass)
    np.testing.assert_array_equal(rebuilt.mass.inertia, obj.mass.inertia)
