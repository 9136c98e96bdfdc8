"""The metric vector Φ(O, G, U), assembled in one place (conventions: Metrics, Sample columns).

Each entry comes from its own metric function; this module only gathers inputs, runs the
contact-based metrics of a whole batch in one compiled loop (no Python work per grasp on
the hot path) and returns columns:

========================  =====  ==========================================================
column                    unit   metric
========================  =====  ==========================================================
epsilon                   --     ε, GraspIt!'s L1 epsilon (:mod:`.epsilon`)
gws_volume                --     GWS 6-volume, force-closure grasps only, else 0
epsilon_reason            str    "" when ε > 0, else why ε = 0
inertia                   kg m²  I about the wrist axis (:mod:`.inertia`)
hold_effort_{px..nz}      N      E_h for gravity along ±x, ±y, ±z (:mod:`.effort`)
impact_effort             N/N·m  E_i (:mod:`.effort`)
discharge                 --     δ (:mod:`.discharge`)
use_force                 N      U_τ (:mod:`.transmission`)
use_edge                  m⁻²    U_g (:mod:`.edges`)
use_edge_angle            rad    sharpest convex dihedral angle near U (:mod:`.edges`)
use_wedge_angle           rad    2π × the part of a 3 mm ball at U inside the solid
use_wedge_angle_fine      rad    the same in a 2 mm ball (same rays)
use_edge_span             --     λ2 of the inside directions' second moment (same rays)
use_edge_thickness        m      the part's thickness at U, from chords 1 and 3 mm behind it
use_clearance             m      smallest contact-to-U distance
use_lever_ratio           --     U's distance to the wrist axis / the centre of mass's
contact_thickness         m      thinnest chord through the solid under a contact
contact_width             m      narrowest part under a contact, across the part
contact_reach             --     farthest contact past the centre of mass towards U, over U's offset
use_depth                 m      the solid's depth behind U along -n (:mod:`.striking`)
use_relief                m      U's and a 5 mm ring's largest distance from their plane
use_swing_cosine          --     cosine between U's normal and its swing velocity
epsilon_hand              --     ε with torques / min(r_max, 0.25 m) (:mod:`.epsilon_hand`)
========================  =====  ==========================================================

Infeasible efforts are +inf (IEEE), never a sentinel.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numba import njit

from ..columns import HOLD_EFFORT_COLUMNS, METRIC_COLUMNS
from ..errors import InputError
from ..runtime.kernel_cache import install_package_stamp
from .cones import wrench_matrix_kernel
from .discharge import discharge
from .edges import EDGE_RADIUS_M, use_edge, use_edge_angle
from .effort import hold_effort, hold_effort_kernel, impact_effort, impact_effort_kernel, use_wrench
from .epsilon import HULL_FALLBACK, LP_FALLBACK, REASONS, epsilon, epsilon_volume_store
from .epsilon_hand import epsilon_hand
from .hand_placement import contact_reach, contact_thickness_and_width, long_axis, use_clearance
from .hull import hull_workspace
from .inertia import rotational_inertia
from .lp import OPTIMAL
from .striking import use_depth, use_lever_ratio, use_relief, use_swing_cosine
from .transmission import use_force, use_force_kernel
from .validation import points_n3, stacked_contact_arrays, units_n3
from .wedge import use_wedge_shape

install_package_stamp()  # before the first @njit (see kernel_cache)

log = logging.getLogger(__name__)


@njit(cache=True)
def contact_metrics_batch(
    points, normals, mu, offsets, center, r_max, use_point, use_normal, wrist_axis, soft, volume
):
    """ε, GWS volume, E_h, E_i and U_τ of many grasps on one object, compiled.

    Parameters
    ----------
    points, normals : (K, 3) float64 ndarray
        All contacts (m; outward unit normals), grasp i owning rows
        ``offsets[i]:offsets[i + 1]``.
    mu : (K,) float64 ndarray
        Friction coefficients.
    offsets : (n + 1,) int64 ndarray
        Row ranges of the grasps.
    center : (3,) float64 ndarray
        The object's centre of mass, m.
    r_max : float
        The object's torque normalisation length, m.
    use_point, use_normal, wrist_axis : (n, 3) float64 ndarray
        Use points (m), their outward unit normals, unit wrist axes.
    soft : bool
        Soft-finger cones.
    volume : bool
        Compute the GWS volume (the full hull; else NaN for force-closure grasps).

    Returns
    -------
    code : (n,) int64 ndarray
        ε's reason code.
    eps, volume : (n,) float64 ndarray
    hold : (n, 6) float64 ndarray
        E_h, N.
    impact : (n,) float64 ndarray
        E_i, N per N·m.
    force : (n,) float64 ndarray
        U_τ, N.
    redo : (n,) bool ndarray
        Grasps on which a compiled solver gave up (the caller recomputes them).
    """
    n = offsets.shape[0] - 1
    code = np.empty(n, dtype=np.int64)
    eps = np.empty(n)
    vol = np.empty(n)
    hold = np.empty((n, 6))
    impact = np.empty(n)
    force = np.empty(n)
    redo = np.zeros(n, dtype=np.bool_)
    inv_r = 1.0 / r_max
    store = hull_workspace()  # one facet store for every hull of the batch
    for i in range(n):
        s = offsets[i]
        e = offsets[i + 1]
        P = np.ascontiguousarray(points[s:e])
        N = np.ascontiguousarray(normals[s:e])
        M = np.ascontiguousarray(mu[s:e])
        Wn = wrench_matrix_kernel(P, N, M, center, inv_r, soft)
        c, eps[i], vol[i], store = epsilon_volume_store(Wn, volume, store)
        code[i] = c
        W = wrench_matrix_kernel(P, N, M, center, 1.0, soft)
        ok_hold = hold_effort_kernel(W, hold[i])
        w_use = use_wrench(use_point[i], use_normal[i], center)
        ok_impact, impact[i] = impact_effort_kernel(W, w_use, wrist_axis[i])
        status, force[i] = use_force_kernel(W, w_use, e - s)
        redo[i] = (
            (not ok_hold)
            or (not ok_impact)
            or status != OPTIMAL
            or c == HULL_FALLBACK
            or c == LP_FALLBACK
        )
    return code, eps, vol, hold, impact, force, redo


def _stack_contacts(contacts: Sequence) -> tuple[np.ndarray, ...]:
    """All contacts of all grasps, checked and concatenated, and each grasp's row offsets."""
    return stacked_contact_arrays(contacts)


def compute_phi_batch(
    mass,
    mesh,
    contacts: Sequence,
    use_point,
    use_normal,
    use_triangle,
    wrist_point,
    wrist_axis,
    *,
    soft: bool = False,
    edge_radius: float = EDGE_RADIUS_M,
    volume: bool = True,
) -> dict[str, np.ndarray]:
    """Φ for n grasps of one object (conventions: Metrics), columns :data:`METRIC_COLUMNS`.

    Parameters
    ----------
    mass : MassProperties
        The object's (centre of mass, r_max, inertia).
    mesh : trimesh.Trimesh
        The object, m (for U_g and the edge angle).
    contacts : sequence of n ContactSet
        Each grasp's contacts, object frame.
    use_point, use_normal : (n, 3) float
        Use points (m) and their outward normals.
    use_triangle : (n,) int
        Face index of each use point.
    wrist_point, wrist_axis : (n, 3) float
        Palm centre (m) and approach direction (normalised here).
    soft : bool
        Soft-finger cones for every contact metric.
    edge_radius : float
        Search radius of ``use_edge_angle``, m.
    volume : bool
        Compute ``gws_volume`` (the full 6-D hull of every force-closure grasp, most of the
        metric cost on enveloping grasps). False: ε from the facets nearest the origin only
        (the same ε) and ``gws_volume`` NaN for force-closure grasps (0 otherwise).

    Returns
    -------
    dict of str to (n,) ndarray
        float64 columns (+inf where infeasible) and ``epsilon_reason`` as an object array
        of str.
    """
    n = len(contacts)
    use_point = points_n3(use_point, "use_point") if n else np.zeros((0, 3))
    use_normal = units_n3(use_normal, "use_normal") if n else np.zeros((0, 3))
    wrist_point = points_n3(wrist_point, "wrist_point") if n else np.zeros((0, 3))
    wrist_axis = units_n3(wrist_axis, "wrist_axis") if n else np.zeros((0, 3))
    use_triangle = np.asarray(use_triangle).reshape(-1)
    for name, arr in (
        ("use_point", use_point),
        ("use_normal", use_normal),
        ("wrist_point", wrist_point),
        ("wrist_axis", wrist_axis),
        ("use_triangle", use_triangle),
    ):
        if arr.shape[0] != n:
            raise InputError(f"{name} has {arr.shape[0]} rows, expected one per grasp ({n})")
    if n == 0:
        return {
            name: np.zeros(0, object if name == "epsilon_reason" else None)
            for name in METRIC_COLUMNS
        }
    # A copy: the cached object's arrays are read-only, a worker's unpickled ones are not,
    # and numba compiles a kernel once per read-only flag (a worker would compile
    # the metric kernels on a first run that loads the shipped ones in process).
    center = np.array(mass.center_of_mass, dtype=np.float64).reshape(3)
    r_max = float(mass.r_max)
    points, normals, mu, offsets = _stack_contacts(contacts)

    code, eps, vol, hold, impact, force, redo = contact_metrics_batch(
        points,
        normals,
        mu,
        offsets,
        center,
        r_max,
        use_point,
        use_normal,
        wrist_axis,
        bool(soft),
        bool(volume),
    )
    reason_of_code = np.array([REASONS[c] for c in sorted(REASONS)], dtype=object)
    reason = reason_of_code[np.clip(code, 0, len(reason_of_code) - 1)]
    for i in np.flatnonzero(redo):
        # rare: a compiled solver could not certify its answer; the per-metric
        # functions retry with HiGHS / qhull
        log.debug("grasp %d: recomputing contact metrics with the reference solvers", i)
        cs = contacts[i]
        res = epsilon(cs, center, r_max, soft=soft, volume=volume)
        eps[i], vol[i] = res.epsilon, res.volume
        reason[i] = res.reason
        hold[i] = hold_effort(cs, center, soft=soft, backend="highs")
        impact[i] = impact_effort(
            cs, center, use_point[i], use_normal[i], wrist_axis[i], soft=soft, backend="highs"
        )
        force[i] = use_force(cs, center, use_point[i], use_normal[i], soft=soft, backend="highs")

    out: dict[str, np.ndarray] = {
        "epsilon": eps,
        "gws_volume": vol,
        "epsilon_reason": reason,
        "inertia": np.asarray(rotational_inertia(mass, wrist_point, wrist_axis), dtype=float),
    }
    for j, name in enumerate(HOLD_EFFORT_COLUMNS):
        out[name] = np.ascontiguousarray(hold[:, j])
    out["impact_effort"] = impact
    out["discharge"] = np.asarray(
        discharge(use_point, use_normal, wrist_point, wrist_axis), dtype=float
    )
    out["use_force"] = force
    out["use_edge"] = np.asarray(use_edge(mesh, use_triangle, use_point), dtype=float)
    out["use_edge_angle"] = np.asarray(
        use_edge_angle(mesh, use_point, radius=edge_radius, use_normal=use_normal), dtype=float
    )
    wedge = use_wedge_shape(mesh, use_point, use_normal)
    out["use_wedge_angle"] = wedge.angle
    out["use_wedge_angle_fine"] = wedge.inner_angle
    out["use_edge_span"] = wedge.span
    out["use_edge_thickness"] = wedge.edge_thickness
    out["use_clearance"] = use_clearance(points, offsets, use_point)
    out["use_depth"] = np.asarray(use_depth(mesh, use_point, use_normal), dtype=float)
    out["use_relief"] = np.asarray(use_relief(mesh, use_point, use_normal), dtype=float)
    out["use_swing_cosine"] = use_swing_cosine(use_point, use_normal, wrist_point, wrist_axis)
    out["use_lever_ratio"] = use_lever_ratio(use_point, center, wrist_point, wrist_axis)
    out["contact_reach"] = contact_reach(
        points, offsets, use_point, center, long_axis(mass.inertia)
    )
    out["contact_thickness"], out["contact_width"] = contact_thickness_and_width(
        mesh, points, normals, offsets
    )
    out["epsilon_hand"] = epsilon_hand(
        points, normals, mu, offsets, center, r_max, eps, soft=bool(soft)
    )
    return {name: out[name] for name in METRIC_COLUMNS}


def compute_phi(
    mass,
    mesh,
    contacts,
    use_point,
    use_normal,
    use_triangle: int,
    wrist_point,
    wrist_axis,
    *,
    soft: bool = False,
    edge_radius: float = EDGE_RADIUS_M,
) -> dict[str, float | str]:
    """Φ of one grasp (conventions: Metrics); see :func:`compute_phi_batch`.

    Parameters
    ----------
    mass, mesh, contacts
        The object's mass properties and mesh, the grasp's ContactSet.
    use_point, use_normal, wrist_point, wrist_axis : (3,) float
        As for :func:`compute_phi_batch`, one grasp.
    use_triangle : int
        Face index of the use point.
    soft, edge_radius
        As for :func:`compute_phi_batch`.

    Returns
    -------
    dict of str to float or str
        One value per column of :data:`METRIC_COLUMNS`.
    """
    cols = compute_phi_batch(
        mass,
        mesh,
        [contacts],
        np.reshape(use_point, (1, 3)),
        np.reshape(use_normal, (1, 3)),
        np.reshape(use_triangle, (1,)),
        np.reshape(wrist_point, (1, 3)),
        np.reshape(wrist_axis, (1, 3)),
        soft=soft,
        edge_radius=edge_radius,
    )
    return {k: (str(v[0]) if k == "epsilon_reason" else float(v[0])) for k, v in cols.items()}
