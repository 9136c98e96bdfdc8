"""The physical trials on analytic cases: an antipodal jaw grasp of a box holds, one finger
does not, the press test tells them apart, and the outcomes are deterministic."""

from __future__ import annotations

import numpy as np
import pytest
from physics_support import jaw_grasp

from affordgrasp.physics import PhysicsSettings
from affordgrasp.physics.scene import build_scene
from affordgrasp.physics.trials import HOLD_DIRECTIONS, validate_grasp

TOUCH = 0.0225 - 5e-5  # jaw travel that leaves a 0.05 mm gap to the box face (as the policy)


@pytest.fixture(scope="module")
def jaw_scene(box_object):
    return build_scene("parallel_jaw", box_object)


@pytest.fixture(scope="module")
def one_jaw_scene(box_object):
    """The parallel-jaw gripper without its right jaw: a hand with one finger.

    (With both jaws, a box pushed by one jaw drifts into the other and ends up held: the
    squeeze makes any one-jaw touch an antipodal grasp.)
    """
    from affordgrasp.hands import Hand, get_hand

    two = get_hand("parallel_jaw")
    one = Hand("one_jaw", two.links[:2], two.dofs[:1], two.fingers[:1], None)
    return build_scene(one, box_object)


def test_box_held_by_antipodal_jaws(jaw_scene):
    pose, joints = jaw_grasp(TOUCH, TOUCH)
    out = validate_grasp(jaw_scene, pose, joints)
    assert out.contacts >= 2
    assert out.settled and out.hold_ok and out.hold_directions_ok == 6
    s = jaw_scene.settings
    assert np.all(out.hold_shift_m < s.max_shift_m)
    assert out.squeeze_shift_m < 1e-3  # balanced jaws do not push the box away
    assert out.impact_ok is None and np.isnan(out.press_force_n)  # no use point given


def test_box_touched_by_one_finger_falls(one_jaw_scene):
    pose, joints = jaw_grasp(TOUCH, 0.0)
    out = validate_grasp(one_jaw_scene, pose, joints[:1])
    assert not out.hold_ok
    # The squeeze pushes the box off the jaw: it drifts away, and only a load that pushes
    # it back towards the jaw (+x) can leave it in place.
    assert not out.settled and out.contacts == 0
    assert out.hold_directions_ok <= 2
    assert np.sum(out.hold_shift_m > one_jaw_scene.settings.max_shift_m) >= 4


def test_press_on_held_box_reaches_more_force_than_on_loose_box(jaw_scene, one_jaw_scene):
    # Press down on the top face (use point at its centre, outward normal +z of the object).
    use_point, use_normal = np.array([0.0, 0.0, 0.03]), np.array([0.0, 0.0, 1.0])
    held = validate_grasp(jaw_scene, *jaw_grasp(TOUCH, TOUCH), use_point, use_normal)
    pose, joints = jaw_grasp(TOUCH, 0.0)
    loose = validate_grasp(one_jaw_scene, pose, joints[:1], use_point, use_normal)
    # Two rubber jaws (μ = 1) at 20 N resist about 40 N of press: the test stops at 30 N.
    assert held.press_held and held.press_force_n == pytest.approx(30.0)
    assert not loose.press_held and loose.press_force_n == 0.0  # the box left the hand
    assert held.impact_ok is not None and loose.impact_ok is False


def test_outcomes_are_deterministic(box_object):
    pose, joints = jaw_grasp(TOUCH, TOUCH * 0.999)
    use = (np.array([0.0, 0.02, 0.01]), np.array([0.0, 1.0, 0.0]))
    rows = []
    for _ in range(2):
        scene = build_scene("parallel_jaw", box_object, PhysicsSettings(seed=3))
        rows.append(validate_grasp(scene, pose, joints, *use).to_row())
    assert rows[0] == rows[1]
    assert set(f"hold_shift_{d}" for d in HOLD_DIRECTIONS) <= set(rows[0])


def test_barrett_model_matches_the_hand_kinematics(box_object):
    import mujoco

    from affordgrasp.hands import get_hand
    from affordgrasp.physics.trials import set_grasp

    hand = get_hand("barrett")
    # The box sits inside the hand here: no back-off, the joints stay where they are put.
    scene = build_scene(hand, box_object, PhysicsSettings(backoff=False))
    rng = np.random.default_rng(0)
    q = np.array([rng.uniform(d.lower, d.upper) for d in hand.dofs])
    set_grasp(scene, np.eye(4), q)
    fk = hand.forward_kinematics(q)
    for i in range(len(hand.links)):
        b = mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_BODY, f"link_{i}")
        np.testing.assert_allclose(scene.data.xpos[b], fk[i][:3, 3], atol=1e-9)
        np.testing.assert_allclose(scene.data.xmat[b].reshape(3, 3), fk[i][:3, :3], atol=1e-6)
    # The distal joints follow the proximal ones at the hand's closing ratio (1/3).
    assert scene.model.neq == 3


def test_non_backdrivable_jaws_do_not_open_under_load(box_object):
    # A 40 N push along -x of the box, twice a jaw's 20 N: a backdrivable jaw gives way, a
    # non-backdrivable one (lead screw, worm drive) does not.
    load = 40.0 / (box_object.mass.mass * PhysicsSettings().density * 9.81)
    pose, joints = jaw_grasp(TOUCH, TOUCH)
    nx = HOLD_DIRECTIONS.index("nx")
    shifts = {}
    for backdrivable in (False, True):
        settings = PhysicsSettings(load_factor=load, backdrivable=backdrivable)
        out = validate_grasp(build_scene("parallel_jaw", box_object, settings), pose, joints)
        shifts[backdrivable] = out.hold_shift_m[nx]
    assert shifts[False] < 1e-3
    assert shifts[True] > PhysicsSettings().max_shift_m


def test_barrett_distal_follows_the_proximal_at_one_third(box_object):
    from affordgrasp.hands import get_hand
    from affordgrasp.physics.trials import _squeeze, set_grasp

    hand = get_hand("barrett")
    scene = build_scene(hand, box_object)
    q = hand.open_dofs(0.5)
    q[hand.dof_index("f1_dist")] = 0.2  # a breakaway state: the distal ahead of 1/3
    far = np.eye(4)
    far[2, 3] = -1.0  # the box 1 m away: the fingers close on nothing
    set_grasp(scene, far, q)
    _squeeze(scene)
    m, d = scene.model, scene.data
    for k in ("f1", "f2", "f3"):
        prox = d.qpos[m.jnt_qposadr[m.joint(f"j_{hand.link_names.index(k + '_prox')}").id]]
        dist = d.qpos[m.jnt_qposadr[m.joint(f"j_{hand.link_names.index(k + '_dist')}").id]]
        moved = prox - q[hand.dof_index(f"{k}_prox")]
        assert moved > 0.2  # the servo closed the finger
        expected = q[hand.dof_index(f"{k}_dist")] + moved / 3.0
        assert dist == pytest.approx(expected, abs=2e-3)


def test_link_meshes_follow_the_rounded_shapes():
    from affordgrasp.physics.scene import rounded_shape_points

    # Support function of the hull of the points against the exact one of the rounded box.
    half, radius = np.array([0.0045, 0.0025, 0.038]), 0.008
    points = rounded_shape_points("box", half, radius)
    u = np.random.default_rng(0).normal(size=(20000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    exact = np.abs(u) @ half + radius
    hull = (u @ points.T).max(axis=1)
    assert np.all(hull <= exact + 1e-12)  # inscribed: never bigger than the link
    assert np.max(exact - hull) < 0.015 * radius


def test_tools_touch_the_use_point_from_outside(jaw_scene):
    import mujoco

    from affordgrasp.physics.trials import _squeeze, place_anvil, place_plate, set_grasp

    # U on the +y face of the box; the tools must sit beyond it, not inside the box.
    use_point, use_normal = np.array([0.015, 0.02, 0.0]), np.array([0.0, 1.0, 0.0])
    m, d = jaw_scene.model, jaw_scene.data
    for place, body in (
        (place_anvil, m.body("anvil").id),
        (place_plate, m.body("plate").id),
    ):
        set_grasp(jaw_scene, *jaw_grasp(TOUCH, TOUCH))
        _squeeze(jaw_scene)
        place(jaw_scene, use_point, use_normal)
        mujoco.mj_forward(m, d)
        tool = [
            d.contact[k].dist
            for k in range(d.ncon)
            if body in (m.geom_bodyid[d.contact[k].geom[0]], m.geom_bodyid[d.contact[k].geom[1]])
        ]
        assert all(dist > -1e-4 for dist in tool), f"a tool starts {min(tool):.4f} m inside"
        centre = d.xipos[body]  # the cube's centre of mass lies outside, along +y
        assert centre[1] > d.xipos[jaw_scene.object_body][1] + 0.02


def test_impact_torque_turns_the_object_in_the_swing_direction(box_object):
    from affordgrasp.physics.trials import _impact, _Snapshot, _squeeze, set_grasp

    # A pulse far above what the jaws hold (factor 100), with U where the anvil does not
    # block the swing: the box turns about +z of the hand, the approach axis.
    scene = build_scene("parallel_jaw", box_object, PhysicsSettings(impact_factor=100.0))
    set_grasp(scene, *jaw_grasp(TOUCH, TOUCH))
    _squeeze(scene)
    r0 = scene.data.xmat[scene.object_body].reshape(3, 3).copy()
    angle, _ = _impact(
        scene, _Snapshot(scene.data), np.array([-0.015, 0.02, 0.0]), np.array([0.0, 1.0, 0.0])
    )
    r = r0.T @ scene.data.xmat[scene.object_body].reshape(3, 3)
    assert angle > np.radians(0.5)
    assert r[1, 0] - r[0, 1] > 0  # positive rotation about z
