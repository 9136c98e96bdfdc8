"""Where the hand holds relative to the working part (hand_placement.py, conventions: Metrics)."""

import numpy as np
import pytest
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.objects import load_object


def test_use_clearance_is_the_nearest_contact():
    from affordgrasp.metrics.hand_placement import use_clearance

    contacts = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.0, 0.2, 0]])
    offsets = np.array([0, 2, 2, 3])  # grasp 1 has no contact
    U = np.array([[0.03, 0, 0], [0.0, 0, 0], [0.0, 0.25, 0]])
    np.testing.assert_allclose(use_clearance(contacts, offsets, U), [0.03, np.inf, 0.05])
    np.testing.assert_allclose(
        use_clearance(contacts, offsets, U[[0, 0]], group=[2, 0]), [np.hypot(0.03, 0.2), 0.03]
    )
    assert np.isnan(use_clearance(contacts, offsets, [[np.nan] * 3], group=[0]))[0]


def test_contact_thickness_is_the_chord_under_the_thinnest_contact():
    import trimesh

    from affordgrasp.metrics.hand_placement import contact_thickness

    plate = trimesh.creation.box(extents=(0.1, 0.05, 0.004))
    C = np.array([[0.0, 0.0, 0.002], [0.05, 0.0, 0.0], [0.0, 0.025, 0.0]])
    N = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0]])
    got = contact_thickness(plate, C, N, [0, 1, 1, 3])  # grasp 1 has no contact
    np.testing.assert_allclose(got, [0.004, np.inf, 0.05], rtol=1e-6)


def test_contact_width_measures_across_the_part():
    from affordgrasp.metrics.hand_placement import contact_thickness, contact_width

    # a cleaver's blade: 100 x 60 x 3 mm; a finger on its spine (normal +y) has a 60 mm chord
    # along the normal, but the part is 3 mm wide across
    plate = trimesh.creation.box(extents=(0.1, 0.06, 0.003))
    C = np.array([[0.0, 0.03, 0.0], [0.01, 0.0, 0.0015]])
    N = np.array([[0, 1.0, 0], [0, 0, 1.0]])
    np.testing.assert_allclose(contact_thickness(plate, C, N, [0, 1, 2]), [0.06, 0.003], rtol=1e-6)
    np.testing.assert_allclose(contact_width(plate, C, N, [0, 1, 2]), [0.003, 0.003], rtol=1e-6)
    # a round handle, 16 mm across: the same along the normal and across
    handle = trimesh.creation.cylinder(radius=0.008, height=0.1, sections=256)
    got = contact_width(
        handle, [[0.008, 0, 0.01], [0, -0.008, 0.0]], [[1.0, 0, 0], [0, -1.0, 0]], [0, 2]
    )
    assert got[0] == pytest.approx(0.016, rel=1e-3)
    # the grasp's narrowest contact decides; no contact: +inf
    both = contact_width(plate, C, N, [0, 2, 2])
    assert both[0] == pytest.approx(0.003) and both[1] == np.inf
    with pytest.raises(InputError, match="directions"):
        contact_width(plate, C, N, [0, 2], directions=0)


def test_contact_width_in_one_cast_is_each_direction_cast_alone():
    """The chords across the part, cast together, are the chords cast one direction (and
    one half) at a time, bit for bit, on a mug's contacts."""
    from affordgrasp.metrics.cones import plane_axes
    from affordgrasp.metrics.hand_placement import (
        _THICKNESS_START_M,
        _first_exit,
        contact_thickness_and_width,
    )

    mesh = load_object("mug").mesh_data
    rng = np.random.default_rng(4)
    faces = rng.choice(len(mesh.faces), 300, replace=False)
    C = mesh.vertices[mesh.faces[faces]].mean(axis=1)
    N = mesh.face_normals[faces]
    offsets = np.arange(0, 301, 3)
    thickness, width = contact_thickness_and_width(mesh, C, N, offsets, directions=6)
    origins = C - _THICKNESS_START_M * N
    along = _first_exit(mesh, origins, -N)
    want = np.where(np.isfinite(along), along + _THICKNESS_START_M, 0.0)
    assert np.array_equal(thickness, want.reshape(-1, 3).min(axis=1))
    inside = np.isfinite(along)
    centre = origins[inside] - 0.5 * along[inside, None] * N[inside]
    e1, e2 = plane_axes(N[inside])
    for angle in np.arange(6) * np.pi / 6:
        d = np.cos(angle) * e1 + np.sin(angle) * e2
        chord = _first_exit(mesh, centre, d) + _first_exit(mesh, centre, -d)
        want[inside] = np.minimum(want[inside], chord)
    assert np.array_equal(width, want.reshape(-1, 3).min(axis=1))
    assert np.all(width <= thickness) and np.any(width < thickness)


def test_contact_reach_is_the_farthest_contact_towards_the_use_end():
    from affordgrasp.metrics.hand_placement import contact_reach, long_axis

    # a rod along x: the long axis is x (either sign)
    rod = trimesh.creation.box(extents=(0.3, 0.02, 0.02))
    axis = long_axis(rod.moment_inertia)
    assert abs(axis[0]) == pytest.approx(1.0)
    c = np.zeros(3)
    contacts = np.array([[-0.10, 0.01, 0], [-0.05, -0.01, 0], [0.02, 0.01, 0], [0.1, 0, 0.01]])
    offsets = [0, 2, 4, 4]  # grasp 0 behind the mass, grasp 1 past it, grasp 2 no contact
    U = np.array([[0.14, 0, 0], [0.14, 0, 0], [0.14, 0, 0]])
    expected = np.array([-0.05, 0.1, -np.inf]) / 0.14  # a fraction of U's own offset
    np.testing.assert_allclose(contact_reach(contacts, offsets, U, c, axis), expected)
    # the sign of the axis does not matter; U on the other end mirrors the reach
    np.testing.assert_allclose(contact_reach(contacts, offsets, U, c, -axis), expected)
    got = contact_reach(contacts, offsets, [[-0.14, 0, 0]] * 2, c, axis, group=[0, 1])
    np.testing.assert_allclose(got, [0.10 / 0.14, -0.02 / 0.14])
    assert np.isnan(contact_reach(contacts, offsets, [[np.nan] * 3], c, axis, group=[0]))[0]
    with pytest.raises(InputError, match="axis"):
        contact_reach(contacts, offsets, U, c, [0, 0, 0])
    with pytest.raises(InputError, match="offsets"):
        contact_reach(contacts, [0, 2, 3], U[:2], c, axis)
