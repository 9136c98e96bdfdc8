"""Grasp and task metrics: the metric vector Φ(O, G, U) (conventions: docs/conventions.md).

Every metric works on raw contacts, without any simulator: build a :class:`ContactSet` from
arrays (GraspIt! output, a real robot's tactile contacts...) with
``ContactSet.from_arrays(points, normals, mu)`` and call the function. Frames and units: the
object's mesh frame, SI units, outward normals.

==========================  ==============================================================
function                    metric
==========================  ==============================================================
:func:`epsilon`             ε and the GWS volume (GraspIt!'s L1 epsilon)
:func:`rotational_inertia`  I about the wrist axis
:func:`hold_effort`         E_h (six gravity directions)
:func:`impact_effort`       E_i
:func:`discharge`           δ
:func:`use_force`           U_τ
:func:`use_edge`            U_g (paper's edge-ness)
:func:`use_edge_angle`      sharpest convex dihedral angle near U
:func:`use_wedge_angle`     opening angle of the solid in a 3 mm ball at U
:func:`use_wedge_shape`     the same, in a 2 mm ball, edge span and thickness (shared rays)
:func:`use_clearance`       smallest contact-to-U distance
:func:`contact_thickness`   thinnest chord through the solid under a contact
:func:`contact_width`       narrowest part under a contact, across the part
:func:`compute_phi`         all of them, one grasp; :func:`compute_phi_batch` for many
==========================  ==============================================================
"""

from ..columns import HOLD_EFFORT_COLUMNS, HOLD_EFFORT_SUFFIXES, METRIC_COLUMNS, hold_effort_sum
from .cones import contact_wrenches, edges_per_contact, friction_cone_edges, tangent_frames
from .contacts import ContactSet
from .discharge import discharge
from .edges import EDGE_RADIUS_M, use_edge, use_edge_angle
from .effort import GRAVITY_DIRECTIONS, hold_effort, impact_effort
from .epsilon import EpsilonResult, epsilon, gws_volume
from .hand_placement import (
    contact_reach,
    contact_thickness,
    contact_width,
    long_axis,
    use_clearance,
)
from .inertia import rotational_inertia
from .lp import LPResult, LPStatus, solve_standard_lp
from .phi import compute_phi, compute_phi_batch
from .striking import use_lever_ratio
from .transmission import use_force
from .wedge import WedgeShape, use_edge_span, use_edge_thickness, use_wedge_angle, use_wedge_shape

__all__ = [
    "EDGE_RADIUS_M",
    "GRAVITY_DIRECTIONS",
    "HOLD_EFFORT_COLUMNS",
    "HOLD_EFFORT_SUFFIXES",
    "METRIC_COLUMNS",
    "ContactSet",
    "EpsilonResult",
    "LPResult",
    "LPStatus",
    "compute_phi",
    "compute_phi_batch",
    "contact_reach",
    "contact_thickness",
    "contact_width",
    "contact_wrenches",
    "discharge",
    "edges_per_contact",
    "epsilon",
    "friction_cone_edges",
    "gws_volume",
    "hold_effort",
    "hold_effort_sum",
    "impact_effort",
    "rotational_inertia",
    "solve_standard_lp",
    "tangent_frames",
    "use_edge",
    "use_clearance",
    "use_edge_angle",
    "use_force",
    "long_axis",
    "use_lever_ratio",
    "use_wedge_angle",
    "use_wedge_shape",
    "use_edge_span",
    "use_edge_thickness",
    "WedgeShape",
]
