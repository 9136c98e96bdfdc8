"""Mass properties against closed forms and the laws of rigid motion."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from affordgrasp.errors import InputError, MeshError
from affordgrasp.objects import MassProperties, mass_properties, mass_properties_parts


def box_inertia(mass: float, a: float, b: float, c: float) -> np.ndarray:
    return mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def test_box_against_closed_form():
    a, b, c = 0.1, 0.2, 0.3
    mesh = trimesh.creation.box(extents=(a, b, c))
    props = mass_properties(mesh, density=700.0)
    assert isinstance(props, MassProperties)
    assert props.density == 700.0
    assert props.volume == pytest.approx(a * b * c, rel=1e-12)
    assert props.mass == pytest.approx(700.0 * a * b * c, rel=1e-12)
    np.testing.assert_allclose(props.center_of_mass, 0.0, atol=1e-15)
    np.testing.assert_allclose(
        props.inertia, box_inertia(props.mass, a, b, c), rtol=1e-12, atol=1e-15
    )
    assert props.r_max == pytest.approx(0.5 * np.sqrt(a * a + b * b + c * c))
    np.testing.assert_allclose(props.bounds, [[-a / 2, -b / 2, -c / 2], [a / 2, b / 2, c / 2]])


def test_default_density_is_one():
    props = mass_properties(trimesh.creation.box(extents=(1, 2, 3)))
    assert props.density == 1.0 and props.mass == pytest.approx(6.0)


def test_regular_prism_cylinder_against_closed_form():
    r, h, n = 0.04, 0.25, 64
    mesh = trimesh.creation.cylinder(radius=r, height=h, sections=n)
    props = mass_properties(mesh)
    alpha = 2 * np.pi / n
    # The tessellated cylinder is a regular n-gon prism: its closed form is exact.
    area = 0.5 * n * r * r * np.sin(alpha)
    mass = area * h
    izz = mass * r * r * (2 + np.cos(alpha)) / 6
    ixx = mass * h * h / 12 + izz / 2
    assert props.volume == pytest.approx(area * h, rel=1e-12)
    np.testing.assert_allclose(props.inertia, np.diag([ixx, ixx, izz]), rtol=1e-10, atol=1e-18)
    # And close to the smooth cylinder.
    assert izz == pytest.approx(0.5 * mass * r * r, rel=2e-3)


def test_sphere_against_closed_form():
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=0.05)
    props = mass_properties(mesh, density=1000.0)
    # The sphere with the polyhedron's volume: tessellation error cancels to first order.
    r_eq = (3 * props.volume / (4 * np.pi)) ** (1 / 3)
    assert r_eq == pytest.approx(0.05, rel=2e-3)
    expected = 0.4 * props.mass * r_eq**2
    np.testing.assert_allclose(np.diag(props.inertia), expected, rtol=1e-3)
    off_diagonal = props.inertia - np.diag(np.diag(props.inertia))
    assert np.abs(off_diagonal).max() < 1e-6 * expected
    np.testing.assert_allclose(props.center_of_mass, 0.0, atol=1e-15)


def test_translation_moves_the_centre_of_mass_only():
    mesh = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    moved = mesh.copy()
    moved.apply_translation([1.0, -2.0, 3.0])
    a, b = mass_properties(mesh), mass_properties(moved)
    np.testing.assert_allclose(b.center_of_mass, [1.0, -2.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(b.inertia, a.inertia, rtol=1e-8, atol=1e-12)
    assert b.r_max == pytest.approx(a.r_max)


def test_density_scales_mass_and_inertia_linearly():
    mesh = trimesh.creation.cylinder(radius=0.02, height=0.1, sections=16)
    a, b = mass_properties(mesh, 1.0), mass_properties(mesh, 2500.0)
    assert b.volume == a.volume
    assert b.mass == pytest.approx(2500.0 * a.mass)
    np.testing.assert_allclose(b.inertia, 2500.0 * a.inertia, rtol=1e-12)
    np.testing.assert_array_equal(b.center_of_mass, a.center_of_mass)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0.01, 1.0), min_size=3, max_size=3),
    st.lists(st.floats(-5.0, 5.0), min_size=3, max_size=3),
    st.integers(0, 2**32 - 1),
)
def test_rigid_motion_of_a_box(extents, translation, seed):
    a, b, c = extents
    transform = trimesh.transformations.random_rotation_matrix(
        np.random.default_rng(seed).random(3)
    )
    transform[:3, 3] = translation
    rotation = transform[:3, :3]
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_transform(transform)
    props = mass_properties(mesh)
    volume = a * b * c
    assert props.volume == pytest.approx(volume, rel=1e-9)
    np.testing.assert_allclose(props.center_of_mass, translation, atol=1e-9)
    expected = rotation @ box_inertia(volume, a, b, c) @ rotation.T
    scale = np.abs(expected).max()
    np.testing.assert_allclose(props.inertia, expected, atol=1e-8 * scale)
    np.testing.assert_array_equal(props.inertia, props.inertia.T)


def test_parts_with_equal_densities_match_the_whole():
    whole = trimesh.creation.box(extents=(0.2, 0.1, 0.05))
    whole.apply_translation([0.3, 0.0, 0.1])
    left = trimesh.creation.box(extents=(0.05, 0.1, 0.05))
    left.apply_translation([0.3 - 0.075, 0.0, 0.1])
    right = trimesh.creation.box(extents=(0.15, 0.1, 0.05))
    right.apply_translation([0.3 + 0.025, 0.0, 0.1])
    single = mass_properties(whole, density=800.0)
    parts = mass_properties_parts([left, right], [800.0, 800.0])
    assert parts.volume == pytest.approx(single.volume, rel=1e-12)
    assert parts.mass == pytest.approx(single.mass, rel=1e-12)
    assert parts.density == pytest.approx(800.0)
    np.testing.assert_allclose(parts.center_of_mass, single.center_of_mass, atol=1e-12)
    np.testing.assert_allclose(parts.inertia, single.inertia, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(parts.bounds, single.bounds)
    assert parts.r_max == pytest.approx(single.r_max)


def test_parts_with_different_densities_use_the_parallel_axis_theorem():
    # A steel head on a wooden handle, both boxes along x.
    handle = trimesh.creation.box(extents=(0.3, 0.03, 0.02))
    head = trimesh.creation.box(extents=(0.04, 0.1, 0.03))
    head.apply_translation([0.17, 0.0, 0.0])
    rho_handle, rho_head = 600.0, 7800.0
    props = mass_properties_parts([handle, head], [rho_handle, rho_head])
    m1, m2 = rho_handle * 0.3 * 0.03 * 0.02, rho_head * 0.04 * 0.1 * 0.03
    com_x = m2 * 0.17 / (m1 + m2)
    expected = box_inertia(m1, 0.3, 0.03, 0.02) + box_inertia(m2, 0.04, 0.1, 0.03)
    for mass, x in ((m1, 0.0), (m2, 0.17)):
        d = x - com_x
        expected += mass * d * d * np.diag([0.0, 1.0, 1.0])
    assert props.mass == pytest.approx(m1 + m2)
    np.testing.assert_allclose(props.center_of_mass, [com_x, 0, 0], atol=1e-12)
    np.testing.assert_allclose(props.inertia, expected, rtol=1e-10, atol=1e-15)
    assert props.density == pytest.approx((m1 + m2) / props.volume)


def test_arrays_are_read_only():
    props = mass_properties(trimesh.creation.box())
    for array in (props.center_of_mass, props.inertia, props.bounds):
        with pytest.raises(ValueError):
            array[0] = 1.0


@pytest.mark.parametrize("density", [0.0, -1.0, float("nan"), float("inf"), "heavy", None])
def test_bad_density_is_refused(density):
    with pytest.raises(InputError, match="density"):
        mass_properties(trimesh.creation.box(), density=density)


def test_open_or_inverted_mesh_is_refused():
    open_box = trimesh.creation.box()
    open_box.update_faces(np.arange(10))
    with pytest.raises(MeshError, match="not watertight.*prepare_mesh"):
        mass_properties(open_box)
    inverted = trimesh.creation.box()
    inverted.invert()
    with pytest.raises(MeshError, match="outward-oriented"):
        mass_properties(inverted)


def test_parts_arguments_are_validated():
    box = trimesh.creation.box()
    with pytest.raises(InputError, match="at least one part"):
        mass_properties_parts([], [])
    with pytest.raises(InputError, match="2 meshes but 1 densities"):
        mass_properties_parts([box, box], [1.0])
    with pytest.raises(InputError, match=r"densities\[1\]"):
        mass_properties_parts([box, box], [1.0, -2.0])


def test_region_densities_beside_a_mesh_file(tmp_path):
    import trimesh

    from affordgrasp.errors import InputError
    from affordgrasp.objects import load_object

    path = tmp_path / "bar.stl"
    trimesh.creation.box(extents=(0.1, 0.02, 0.02)).export(path)
    side = tmp_path / "bar.stl.materials.toml"
    side.write_text(
        'density = 700.0\n[[region]]\nname = "head"\ndensity = 7850.0\n'
        "plane_point = [0.03, 0.0, 0.0]\nplane_normal = [1.0, 0.0, 0.0]\n"
    )
    obj = load_object(path)
    head, rest = 8e-6 * 7850.0, 3.2e-5 * 700.0
    assert obj.materials
    assert obj.mass.mass == pytest.approx(head + rest, rel=1e-6)
    com_x = (head * 0.04 + rest * -0.01) / (head + rest)
    np.testing.assert_allclose(obj.mass.center_of_mass, [com_x, 0, 0], atol=1e-9)
    side.write_text("[[region]]\nname = 'x'\n")
    with pytest.raises(InputError, match="materials.toml"):
        load_object(path)
