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
