"""Helpers the physics tests share (a module of its own: two directories have a conftest)."""

from __future__ import annotations

import numpy as np


def jaw_grasp(q_left: float, q_right: float, height: float = 0.035):
    """Parallel-jaw grasp of the box: hand → object pose and joint values.

    The box sits on the approach axis, its centre ``height`` above the palm face; the jaw
    travel 0.0225 m brings a jaw's pad to the box face (x = ±0.02).
    """
    pose = np.eye(4)
    pose[2, 3] = -height
    return pose, np.array([q_left, q_right])
