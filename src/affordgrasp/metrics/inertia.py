"""Rotational inertia I of the object about the wrist axis (conventions: Metrics).

The hand is rigidly attached to the object and rotates about the wrist axis: the line
through the wrist point ``w`` along the unit approach direction ``a``. By the
parallel-axis theorem::

    I = aᵀ I_com a + m d²,   d = distance from the centre of mass to the line,

with ``I_com`` the inertia tensor about the centre of mass and ``m`` the mass, both from
the object's mass properties (uniform unit density by default, as in the paper; a built-in
family's per-part materials with ``load_object(spec, materials=True)``).
Units: kg m². Scales as s⁵ under a uniform scaling at constant density. Validated
against the closed forms of a box and a rod in ``tests/metrics/test_inertia.py``.
"""

from __future__ import annotations

import numpy as np

from .validation import points_n3, units_n3


def rotational_inertia(mass, wrist_point, wrist_axis) -> float | np.ndarray:
    """Rotational inertia about the wrist axis (conventions: Metrics), kg m².

    Parameters
    ----------
    mass : MassProperties
        The object's mass (kg), centre of mass (3,) m and inertia (3, 3) kg m² about it.
    wrist_point : (3,) or (n, 3) float
        A point of the axis, m.
    wrist_axis : (3,) or (n, 3) float
        Direction of the axis (normalised here).

    Returns
    -------
    float or (n,) float64 ndarray
        A float for single inputs.
    """
    single = np.ndim(wrist_point) == 1 and np.ndim(wrist_axis) == 1
    w = points_n3(wrist_point, "wrist_point")
    a = units_n3(wrist_axis, "wrist_axis")
    w, a = np.broadcast_arrays(w, a)
    c = np.asarray(mass.center_of_mass, dtype=np.float64).reshape(3)
    I_com = np.asarray(mass.inertia, dtype=np.float64).reshape(3, 3)
    r = c - w
    # squared distance from c to the line: |r|² - (r·a)²; the cross-product form is
    # exact where the subtraction would cancel
    d2 = np.sum(np.cross(r, a) ** 2, axis=1)
    value = np.einsum("ij,jk,ik->i", a, I_com, a) + float(mass.mass) * d2
    return float(value[0]) if single else value
