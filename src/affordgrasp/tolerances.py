"""The numerical tolerances of affordgrasp, in one table.

Every comparison with a tolerance outside the compiled solvers reads its value here, so a
reader can see them side by side and a change applies everywhere. Lengths are in metres,
angles in radians; "relative" values are fractions of the scale named in the comment.

================================  ========  ==================================================
name                              value     meaning
================================  ========  ==================================================
``ZERO_LENGTH``                   1e-12     a vector shorter than this (same units as the
                                            vector) is zero: no direction can be taken from it
``UNIT_NORMAL``                   1e-12     a normal whose length is off 1 by more than this
                                            is renormalised before it enters a cone
``CONE_AXIS_SWITCH``              1e-12     GraspIt!'s switch from the x axis to the z axis
                                            for the first tangent of a friction cone
``ZERO_MOMENT``                   1e-12     a moment below this fraction of its lever is zero
``FLAT_DIHEDRAL``                 1e-9      dihedral angles (rad) below this are flat
``ORTHONORMAL``                   1e-9      a hand joint axis / rotation off unit or
                                            orthonormal by more than this is refused
``CONTACT_DISTANCE_M``            2e-4      hand links within 0.2 mm of the object touch
``STOP_DISTANCE_M``               5e-5      a moving link stops within 0.05 mm of the surface
``JOINT_AT_LIMIT``                1e-12     a closing DOF this close to its upper limit (rad
                                            or m) has reached it and stops
``ZERO_AREA``                     1e-12     a mesh whose area is below this fraction of its
                                            longest extent squared has no area
``MIN_RELATIVE_VOLUME``           1e-9      a solid whose volume is below this fraction of its
                                            bounding cube encloses nothing (a flat sheet
                                            closed onto itself; a knife blade is ~1e-4)
``UNION_RTOL``                    1e-9      relative volume mismatch below which a union of
                                            bodies equals their sum (no overlap)
``STRAIGHT_TURN``                 1e-12     a polygon corner turning the wrong way by less
                                            than this fraction of the product of its edge
                                            lengths is straight (OFF faces)
``FULL_TURN_RAD``                 1e-6      a polygon whose corners turn by 2π within this
                                            goes round once (OFF faces)
================================  ========  ==================================================

The compiled hull and LP solvers keep their own pivot and facet tolerances next to the code
that uses them (``metrics/hull.py``, ``metrics/lp.py``, ``metrics/epsilon.py``).
"""

from __future__ import annotations

ZERO_LENGTH = 1e-12
UNIT_NORMAL = 1e-12
CONE_AXIS_SWITCH = 1e-12
ZERO_MOMENT = 1e-12
FLAT_DIHEDRAL = 1e-9
ORTHONORMAL = 1e-9
CONTACT_DISTANCE_M = 2e-4
STOP_DISTANCE_M = 5e-5
JOINT_AT_LIMIT = 1e-12
ZERO_AREA = 1e-12
MIN_RELATIVE_VOLUME = 1e-9
UNION_RTOL = 1e-9
STRAIGHT_TURN = 1e-12
FULL_TURN_RAD = 1e-6
