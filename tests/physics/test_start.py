"""The start of the replay: back-off to first contact, couplings at their limit, settled
contacts and the DexGraspBench protocol, on analytic cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from physics_support import jaw_grasp

from affordgrasp.errors import InputError
from affordgrasp.physics import PhysicsSettings
from affordgrasp.physics.scene import build_scene
from affordgrasp.physics.settings import protocol_settings
from affordgrasp.physics.trials import penetration_depth, set_grasp, validate_grasp

TOUCH = 0.0225  # jaw travel that brings a pad to the box face (x = ±0.02)


@pytest.fixture(scope="module")
def jaw_scene(box_object):
    return build_scene("parallel_jaw", box_object)


def test_jaws_inside_the_box_are_opened_to_first_contact(jaw_scene, box_object):
    pose, joints = jaw_grasp(TOUCH + 0.002, TOUCH + 0.001)  # 2 and 1 mm deep
    start = set_grasp(jaw_scene, pose, joints)
    assert start.initial_penetration_m == pytest.approx(0.002, abs=1e-4)
    tol = jaw_scene.settings.backoff_depth_m
    assert start.start_penetration_m <= tol
    assert penetration_depth(jaw_scene) == start.start_penetration_m
    assert start.backoff_open == pytest.approx(0.002, abs=2 * tol)
    assert start.backoff_shift_m == 0.0  # nothing touched the palm

    raw = build_scene("parallel_jaw", box_object, PhysicsSettings(backoff=False))
    as_placed = set_grasp(raw, pose, joints)
    assert as_placed.start_penetration_m == as_placed.initial_penetration_m > 1.9e-3


def test_object_in_the_palm_is_pushed_off(jaw_scene):
    # The box's bottom face 1 mm into the palm, jaws wide open.
    palm = jaw_scene.hand.links[0].shapes[0]
    assert palm.kind == "box" and np.allclose(palm.pose[:3, :3], np.eye(3))
    top = palm.pose[2, 3] + palm.half_extents[2] + palm.radius  # the palm's face, z
    pose, joints = jaw_grasp(0.0, 0.0, height=top + 0.03 - 0.001)
    start = set_grasp(jaw_scene, pose, joints)
    assert start.initial_penetration_m == pytest.approx(0.001, abs=2e-4)
    assert start.start_penetration_m <= jaw_scene.settings.backoff_depth_m
    assert start.backoff_shift_m == pytest.approx(0.001, abs=2e-4)
    body = jaw_scene.object_body
    assert jaw_scene.data.xpos[body][2] > top + 0.03 - 1e-4  # moved along +z, off the palm


def test_a_finger_with_its_distal_at_the_limit_still_closes(box_object):
    from affordgrasp.hands import get_hand

    hand = get_hand("barrett")
    scene = build_scene(hand, box_object)
    names = [d.name for d in hand.dofs]
    q = np.array([d.lower for d in hand.dofs])
    prox, dist = names.index("f1_prox"), names.index("f1_dist")
    q[prox], q[dist] = 0.5, hand.dofs[dist].upper  # the distal at its closing limit
    far = np.eye(4)
    far[:3, 3] = [1.0, 1.0, 1.0]  # the object out of reach: the fingers close freely
    start = set_grasp(scene, far, q)
    assert start.distal_at_limit >= 1
    from affordgrasp.physics.trials import _squeeze

    jid = scene.fingers[0].joint
    adr = scene.model.jnt_qposadr[jid]
    before = float(scene.data.qpos[adr])
    _squeeze(scene)
    # The servo target ends overshoot_rad past the start: the proximal closes most of it.
    assert scene.data.qpos[adr] - before > 0.5 * scene.settings.overshoot_rad


def test_settled_contacts_lie_on_the_jaw_faces(jaw_scene):
    pose, joints = jaw_grasp(TOUCH - 5e-5, TOUCH - 5e-5)
    out = validate_grasp(jaw_scene, pose, joints)
    assert out.settled and not out.ejected
    k = len(out.settled_mu)
    assert k >= 2
    # Box faces at x = ±0.02 of the object frame, outward normals ±x.
    assert np.allclose(np.abs(out.settled_points[:, 0]), 0.02, atol=1e-3)
    assert np.allclose(np.abs(out.settled_normals[:, 0]), 1.0, atol=1e-3)
    assert np.all(np.sign(out.settled_points[:, 0]) == np.sign(out.settled_normals[:, 0]))
    row = out.to_row()
    assert row["settled_contacts"] == k and len(row["settled_points"]) == 3 * k
    assert 0 <= row["settled_hold_dirs"] <= 6
    assert row["settled_epsilon"] >= 0.0


def test_dgb_protocol_constants_and_bad_names():
    s = protocol_settings("dgb")
    assert s.protocol == "dgb" and s.displacement_from == "placed"
    assert (s.hold_time, s.max_shift_m, s.friction, s.condim) == (2.0, 0.05, 0.6, 4)
    assert s.max_angle_rad == pytest.approx(math.radians(15.0))
    assert (s.load_factor, s.object_mass_kg, s.timestep) == (10.0, 0.1, 0.004)
    assert protocol_settings("dgb", load_factor=5.0).load_factor == 5.0
    assert protocol_settings() == PhysicsSettings()
    assert s.digest() != PhysicsSettings().digest()
    with pytest.raises(InputError, match="bogus"):
        protocol_settings("bogus")
    with pytest.raises(InputError, match="displacement_from"):
        PhysicsSettings(displacement_from="nowhere")


def test_dgb_scene_has_the_protocol_mass_and_friction(box_object):
    scene = build_scene("parallel_jaw", box_object, protocol_settings("dgb"))
    assert scene.object_mass == pytest.approx(0.1)
    m = scene.model
    hand = np.concatenate([*scene.finger_geoms, scene.palm_geoms])
    assert np.allclose(m.geom_friction[hand, 0], 0.6)
    assert np.all(m.geom_condim[hand] == 4)
    assert m.opt.noslip_iterations == 2


def test_friction_margin_widens_the_cones_and_settled_metrics_keep_the_table_mu(box_object):
    """μ' = tan(atan μ + δ) on every hand geom; the settled contacts report the table's μ."""
    from affordgrasp.materials import friction_coefficient
    from affordgrasp.physics.scene import engine_friction, table_friction

    s = PhysicsSettings(friction_margin_deg=10.0)
    # Analytic: a 0.4 cone (21.80°) widened by 10° is 31.80°: tan = 0.6200.
    assert engine_friction(s, 0.4) == pytest.approx(math.tan(math.atan(0.4) + math.radians(10)))
    assert engine_friction(s, 0.4) == pytest.approx(0.62, abs=1e-3)
    assert table_friction(s, np.array([engine_friction(s, 0.3)]))[0] == pytest.approx(0.3)
    assert engine_friction(PhysicsSettings(friction_margin_deg=0.0), 0.4) == 0.4
    assert engine_friction(protocol_settings("dgb", friction_margin_deg=10.0), 0.4) == 0.6
    scene = build_scene("parallel_jaw", box_object, s)
    mu = friction_coefficient(scene.hand.links[1].material, "plastic")  # rubber jaws: 1.0
    mu_palm = friction_coefficient(scene.hand.links[0].material, "plastic")
    friction = scene.model.geom_friction[:, 0]
    assert np.allclose(friction[scene.finger_geoms[0]], engine_friction(s, mu))
    assert np.allclose(friction[scene.palm_geoms], engine_friction(s, mu_palm))
    pose, joints = jaw_grasp(TOUCH - 5e-5, TOUCH - 5e-5)
    out = validate_grasp(scene, pose, joints)
    assert len(out.settled_mu) >= 2 and np.allclose(out.settled_mu, mu)
    with pytest.raises(InputError, match="friction_margin_deg"):
        PhysicsSettings(friction_margin_deg=45.0)
