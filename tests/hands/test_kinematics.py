"""Forward kinematics of the built-in hands against poses computed by hand from their dimensions."""

import numpy as np
import pytest

from affordgrasp.errors import HandError
from affordgrasp.hands import Hand, Link, Shape, get_hand, list_hands
from affordgrasp.hands.kinematics import joint_poses, kinematic_tree
from affordgrasp.hands.model import axis_angle

MM = 1e-3


def pose_of(hand, dofs, name):
    return hand.forward_kinematics(dofs)[hand.link_names.index(name)]


def barrett_dofs(spread=0.0, **joints):
    hand = get_hand("barrett")
    q = np.zeros(len(hand.dofs))
    q[hand.dof_index("spread")] = spread
    for k, v in joints.items():
        q[hand.dof_index(k)] = v
    return hand, q


@pytest.mark.parametrize(
    "spread, f1, f2",
    [
        (0.0, (25, 50), (-25, 50)),  # side by side, opposite F3
        (np.pi / 2, (75, 0), (-75, 0)),  # facing each other
        (np.pi, (25, -50), (-25, -50)),  # all on the F3 side
        (np.pi / 3, (25 + 50 * np.sin(np.pi / 3), 25), (-25 - 50 * np.sin(np.pi / 3), 25)),
    ],
)
def test_barrett_spread_places_the_proximal_joints(spread, f1, f2):
    hand, q = barrett_dofs(spread)
    for name, xy in (("f1_prox", f1), ("f2_prox", f2), ("f3_prox", (0, -50))):
        np.testing.assert_allclose(
            pose_of(hand, q, name)[:3, 3], [*np.array(xy) * MM, 15 * MM], atol=1e-12
        )


def test_barrett_open_fingers_lie_flat_and_point_outward():
    hand, q = barrett_dofs(0.0)
    out = {"f1": [0, 1, 0], "f2": [0, 1, 0], "f3": [0, -1, 0]}
    for f, e in out.items():
        np.testing.assert_allclose(pose_of(hand, q, f"{f}_prox")[:3, 2], e, atol=1e-12)
        # Distal joint 70 mm further out, at knuckle height.
        np.testing.assert_allclose(
            pose_of(hand, q, f"{f}_dist")[:3, 3] - pose_of(hand, q, f"{f}_prox")[:3, 3],
            np.array(e) * 70 * MM,
            atol=1e-12,
        )
    # The fixed 42° bend turns the distal links up, towards the approach.
    c, s = np.cos(np.deg2rad(42)), np.sin(np.deg2rad(42))
    np.testing.assert_allclose(pose_of(hand, q, "f3_dist")[:3, 2], [0, -c, s], atol=1e-12)
    np.testing.assert_allclose(pose_of(hand, q, "f1_dist")[:3, 2], [0, c, s], atol=1e-12)


def test_barrett_closing_f3():
    # Proximal at 90°: the proximal link points along the approach, its distal joint 70 mm
    # above the knuckle; at 140° it leans 50° past that towards the palm axis.
    hand, q = barrett_dofs(0.0, f3_prox=np.pi / 2, f3_dist=np.deg2rad(30))
    np.testing.assert_allclose(pose_of(hand, q, "f3_prox")[:3, 2], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(
        pose_of(hand, q, "f3_dist")[:3, 3], [0, -50 * MM, 85 * MM], atol=1e-12
    )
    total = np.pi / 2 + np.deg2rad(42 + 30)  # from the outward direction towards +y
    np.testing.assert_allclose(
        pose_of(hand, q, "f3_dist")[:3, 2], [0, -np.cos(total), np.sin(total)], atol=1e-12
    )
    hand, q = barrett_dofs(0.0, f3_prox=np.deg2rad(140))
    d = pose_of(hand, q, "f3_prox")[:3, 2]
    np.testing.assert_allclose(d, [0, np.sin(np.deg2rad(50)), np.cos(np.deg2rad(50))], atol=1e-12)


def test_barrett_limits_and_couplings_follow_the_spec():
    hand = get_hand("barrett")
    lim = {d.name: (d.lower, d.upper) for d in hand.dofs}
    assert lim["spread"] == (0.0, np.pi)
    assert np.isclose(lim["f1_prox"][1], np.deg2rad(140))
    assert np.isclose(lim["f1_dist"][1], np.deg2rad(48))
    for f in hand.fingers:
        assert f.speeds == (1.0, 1.0 / 3.0)
    materials = {link.name: link.material for link in hand.links if link.shapes}
    assert materials["palm"] == "plastic"
    assert all(m == "wood" for n, m in materials.items() if n != "palm")


def test_gripper_jaws_close_towards_each_other():
    hand = get_hand("parallel_jaw")
    q = np.zeros(len(hand.dofs))
    left = pose_of(hand, q, "jaw_l")[:3, 3]
    right = pose_of(hand, q, "jaw_r")[:3, 3]
    assert left[0] - right[0] == pytest.approx(0.085 + 0.020)
    q[:] = 0.01
    assert pose_of(hand, q, "jaw_l")[0, 3] == pytest.approx(left[0] - 0.01)
    assert pose_of(hand, q, "jaw_r")[0, 3] == pytest.approx(right[0] + 0.01)
    assert hand.pregrasp_dof is None


def test_forward_kinematics_checks_the_dof_count():
    with pytest.raises(HandError, match="DOF values"):
        get_hand("barrett").forward_kinematics(np.zeros(3))


def test_hand_validation_names_the_problem():
    palm = Link("palm", None, None, (Shape("box", (0.01, 0.01, 0.01), 0.001),), "plastic")
    with pytest.raises(HandError, match="unknown material"):
        Hand("h", (Link("palm", None, None, palm.shapes, "cheese"),), (), (), None)
    with pytest.raises(HandError, match="unknown hand"):
        get_hand("shadow")
    assert set(list_hands()) == {"barrett", "parallel_jaw"}


def test_axis_angle_is_a_right_handed_rotation():
    r = axis_angle([0, 0, 1], np.pi / 2)
    np.testing.assert_allclose(r @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


def _jaw_hand(**changes):
    from affordgrasp.hands import Dof, Finger, Joint
    from affordgrasp.hands.model import transform

    shape = (Shape("box", (0.01, 0.01, 0.01), 0.002),)
    axis = changes.get("axis", np.array([1.0, 0, 0]))
    links = [
        Link("palm", None, None, shape, "plastic"),
        Link("a", "palm", Joint("prismatic", transform(), axis, "close_a"), shape, "rubber"),
        Link(
            "b",
            "palm",
            Joint("prismatic", transform(), -np.array(axis), changes.get("b_dof", "close_b")),
            shape,
            "rubber",
        ),
    ]
    dofs = (Dof("close_a", 0, 0.04, "close"), Dof("close_b", 0, 0.04, "close"))
    fingers = (Finger("a", ("close_a",), (1.0,)), Finger("b", ("close_b",), (1.0,)))
    return Hand("jaws", tuple(links), dofs, fingers, None)


def test_hand_validation_refuses_what_the_closing_search_cannot_sweep():
    assert _jaw_hand().name == "jaws"
    with pytest.raises(HandError, match="unit vector"):
        _jaw_hand(axis=np.array([2.0, 0, 0]))
    with pytest.raises(HandError, match="exactly one link"):
        _jaw_hand(b_dof="close_a")  # one DOF mirrored onto both jaws


@pytest.mark.parametrize("name", ["barrett", "parallel_jaw"])
def test_joint_poses_compose_to_the_link_poses(name):
    hand = get_hand(name)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = np.array([rng.uniform(d.lower, d.upper) for d in hand.dofs])
        links = hand.forward_kinematics(q)
        local = joint_poses(q, kinematic_tree(hand))
        np.testing.assert_array_equal(local[0], np.eye(4))
        for i, link in enumerate(hand.links[1:], start=1):
            parent = links[hand.link_names.index(link.parent)]
            np.testing.assert_allclose(parent @ local[i], links[i], atol=1e-15)
            j = link.joint
            value = j.ratio * q[hand.dof_index(j.dof)]
            if j.kind == "revolute":
                motion = np.eye(4)
                motion[:3, :3] = axis_angle(j.axis, value)
            else:
                motion = np.eye(4)
                motion[:3, 3] = np.asarray(j.axis) / np.linalg.norm(j.axis) * value
            np.testing.assert_allclose(local[i], j.origin @ motion, atol=1e-15)
