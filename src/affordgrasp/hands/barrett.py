"""The Barrett BH8-282, built from its published dimensions (conventions: Hands).

Hand frame: palm face at z = 0, approach along +z. F1 and F2 turn on spread axes at
x = ±25 mm (F1 at +x); F3 is fixed with its proximal joint at (0, -50 mm). At spread 0 the
arms of F1/F2 point along +y (side by side, opposite F3); F1 turns towards +x and F2 towards
-x as the spread grows (90°: F1 and F2 face each other; 180°: all fingers on the -y side).

Joint values (rad): ``spread``; per finger ``fK_prox`` and ``fK_dist``. At ``fK_prox`` = 0 the
proximal link points radially outward, parallel to the palm (the fully open, flat hand, as
GraspIt!'s model); 90° points it along the approach (+z) and 140° (closed) bends it 50° past
that towards the palm axis. ``fK_dist`` is the distal joint *beyond* its fixed 42° bend
(towards the closing side), limited to 48°. While closing
the distal turns at 1/3 of the proximal speed; after a proximal contact it keeps closing alone
(TorqueSwitch breakaway). No third-party mesh is used: the links are rounded boxes and the
palm a rounded cylinder with the dimensions below.
"""

from __future__ import annotations

import numpy as np

from .model import Dof, Finger, Hand, Joint, Link, Shape, axis_angle, transform

MM = 1e-3
SPREAD_ARM = 50 * MM  # spread axis to proximal joint
SPREAD_AXIS_X = 25 * MM  # F1's spread axis at +x, F2's at -x
PROXIMAL_LENGTH = 70 * MM  # proximal joint to distal joint
DISTAL_BEND = np.deg2rad(42.0)
PROXIMAL_LIMIT = np.deg2rad(140.0)
DISTAL_LIMIT = np.deg2rad(48.0)
KNUCKLE_HEIGHT = 15 * MM  # proximal joint axes above the palm face
ROUNDING = 8 * MM

# -x in a finger's joint frame: positive joint angles bend the finger towards the palm centre.
_CLOSE_AXIS = np.array([-1.0, 0.0, 0.0])


def _rounded_box(size_mm, center_mm, radius=ROUNDING) -> Shape:
    size = np.asarray(size_mm) * MM
    return Shape(
        "box", tuple(size / 2 - radius), radius, transform(None, np.asarray(center_mm) * MM)
    )


def _finger(prefix: str, parent: str, origin: np.ndarray) -> tuple[Link, Link]:
    # Proximal link about 92 x 25 x 21 mm (length x width x thickness), centred between joints.
    proximal = Link(
        f"{prefix}_prox",
        parent,
        Joint("revolute", origin, _CLOSE_AXIS, f"{prefix}_prox"),
        (_rounded_box((25, 21, 92), (0, 0, 35)),),
        "wood",
    )
    # Distal link about 68 x 19 x 23 mm, tip about 57 mm beyond the distal joint.
    bend = transform(axis_angle(_CLOSE_AXIS, DISTAL_BEND), (0.0, 0.0, PROXIMAL_LENGTH))
    distal = Link(
        f"{prefix}_dist",
        f"{prefix}_prox",
        Joint("revolute", bend, _CLOSE_AXIS, f"{prefix}_dist"),
        (_rounded_box((19, 23, 68), (0, 0, 23)),),
        "wood",
    )
    return proximal, distal


def barrett_bh8_282() -> Hand:
    """The Barrett BH8-282 three-finger hand.

    Returns
    -------
    Hand
        A new, validated description: palm and three fingers of two links each, the
        spread DOF as pregrasp DOF (rad), three closing DOFs (rad); lengths in m.
    """
    palm = Link(
        "palm",
        None,
        None,
        # Cylinder of diameter 89 mm, 70 mm deep behind the palm face, rim rounded by 5 mm.
        (Shape("cylinder", (0.0395, 0.0395, 0.030), 0.005, transform(None, (0, 0, -0.035))),),
        "plastic",
    )
    links = [palm]
    # Proximal link frame: z along the link, y its inner (closing) face, x the joint axis
    # reversed. Open, F3's link points along -y with its inner face up (+z).
    up = axis_angle([1.0, 0.0, 0.0], np.pi / 2)
    # F1/F2 arms point along +y of their base frame at spread 0: turned half a turn.
    flip = axis_angle([0.0, 0.0, 1.0], np.pi) @ up
    for prefix, x, ratio in (("f1", SPREAD_AXIS_X, -1.0), ("f2", -SPREAD_AXIS_X, 1.0)):
        base = Link(
            f"{prefix}_base",
            "palm",
            Joint("revolute", transform(None, (x, 0, 0)), np.array([0.0, 0, 1]), "spread", ratio),
            (),
            "plastic",
        )
        links.append(base)
        links.extend(_finger(prefix, base.name, transform(flip, (0, SPREAD_ARM, KNUCKLE_HEIGHT))))
    links.extend(_finger("f3", "palm", transform(up, (0, -SPREAD_ARM, KNUCKLE_HEIGHT))))
    dofs = [Dof("spread", 0.0, np.pi, "pregrasp")]
    fingers = []
    for prefix in ("f1", "f2", "f3"):
        dofs.append(Dof(f"{prefix}_prox", 0.0, PROXIMAL_LIMIT, "close"))
        dofs.append(Dof(f"{prefix}_dist", 0.0, DISTAL_LIMIT, "close"))
        fingers.append(Finger(prefix, (f"{prefix}_prox", f"{prefix}_dist"), (1.0, 1.0 / 3.0)))
    return Hand(
        "barrett",
        tuple(links),
        tuple(dofs),
        tuple(fingers),
        "spread",
        "Barrett BH8-282: three fingers, spread 0-180 deg, TorqueSwitch breakaway",
    )
