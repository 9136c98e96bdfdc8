"""A parallel-jaw gripper in the same form as the Barrett: the design is not Barrett-only.

Hand frame as for every hand: palm face at z = 0, approach along +z. Two jaws (60 mm long,
20 x 20 mm section, rubber pads) slide towards each other along x from an 85 mm opening;
each jaw closes independently until it touches or meets the centre. The gripper has no
pregrasp DOF: the pregrasp's spread parameter is ignored.
"""

from __future__ import annotations

import numpy as np

from .model import Dof, Finger, Hand, Joint, Link, Shape, transform

OPENING = 0.085
JAW = (0.020, 0.020, 0.060)  # x (thickness), y (width), z (length) in m
RADIUS = 0.004


def parallel_jaw() -> Hand:
    """The parallel-jaw gripper of this module's docstring.

    Returns
    -------
    Hand
        A new, validated description: a palm and two jaws on prismatic DOFs (m), no
        pregrasp DOF.
    """
    palm = Link(
        "palm",
        None,
        None,
        (
            Shape(
                "box",
                (0.060 - RADIUS, 0.020 - RADIUS, 0.030 - RADIUS),
                RADIUS,
                transform(None, (0, 0, -0.030)),
            ),
        ),
        "plastic",
    )
    half = np.asarray(JAW) / 2 - RADIUS
    links = [palm]
    fingers = []
    dofs = []
    travel = OPENING / 2
    for name, side in (("jaw_l", 1.0), ("jaw_r", -1.0)):
        origin = transform(None, (side * (OPENING / 2 + JAW[0] / 2), 0.0, 0.0))
        links.append(
            Link(
                name,
                "palm",
                Joint("prismatic", origin, np.array([-side, 0.0, 0.0]), name),
                (Shape("box", tuple(half), RADIUS, transform(None, (0, 0, JAW[2] / 2))),),
                "rubber",
            )
        )
        dofs.append(Dof(name, 0.0, travel, "close"))
        fingers.append(Finger(name, (name,), (1.0,)))
    return Hand(
        "parallel_jaw",
        tuple(links),
        tuple(dofs),
        tuple(fingers),
        None,
        "parallel-jaw gripper: 85 mm opening, two independent rubber-padded jaws",
    )
