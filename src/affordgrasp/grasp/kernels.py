"""Compiled inner loops of the grasp policy: signed distances, approach and finger closing.

Why our own kernels: the approach is a translational sweep and the closing a rotational one;
python-fcl's continuous collision is wrong (it snaps to coarse steps and misses contacts) and
mujoco collides meshes as convex hulls. Instead every hand link is a union of sphere-swept
boxes/cylinders with an exact signed distance, the object is a dense surface sample, and each
sample point is *sphere-traced* along its relative motion: a step never exceeds the distance
to the link divided by the point's largest speed, so no sample can jump over a link, however
thin the object part. Points are traced in order of their lower bound on the hit time and
dropped once that bound passes the best hit found, so typically only the few points near the
first contact are traced to the end.

All positions are in the hand frame (palm face z = 0, approach +z), metres.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..hands.kinematics import (
    PRISMATIC,
    REVOLUTE,
    KinematicTree,
    joint_motion_into,
    link_poses,
    mul4_into,
    shape_poses,
)
from ..runtime.kernel_cache import install_package_stamp

install_package_stamp()  # before the first @njit (see kernel_cache)

# Shape kinds (see affordgrasp.hands.model).
BOX = 0
CYLINDER = 1


class SampleCloud(NamedTuple):
    """Object surface samples grouped into cells, as the compiled kernels take them.

    The arrays of :class:`affordgrasp.objects.surface.SurfaceSample` that the contact search
    reads, the same arrays with the same meaning (``policy.sample_cloud`` hands them over
    without copying): the points ordered by cell, the fine cells (``cell_*``: offsets,
    bounding sphere, flat cylinder), the coarse cells (``coarse_*``: offsets into the fine
    cells, bounding sphere) and the sub-cells (``cell_sub_start``, ``sub_*``: each fine
    cell's points split 2 x 2 x 2 and listed by index, with a sphere and a flat cylinder).

    Attributes
    ----------
    points, cell_start, cell_center, cell_radius, cell_normal, cell_slab, coarse_start,
    coarse_center, coarse_radius, cell_sub_start, sub_start, sub_points, sub_center,
    sub_radius, sub_normal, sub_slab : ndarray
        As in ``SurfaceSample`` (m for lengths).
    """

    points: np.ndarray
    cell_start: np.ndarray
    cell_center: np.ndarray
    cell_radius: np.ndarray
    cell_normal: np.ndarray
    cell_slab: np.ndarray
    coarse_start: np.ndarray
    coarse_center: np.ndarray
    coarse_radius: np.ndarray
    cell_sub_start: np.ndarray
    sub_start: np.ndarray
    sub_points: np.ndarray
    sub_center: np.ndarray
    sub_radius: np.ndarray
    sub_normal: np.ndarray
    sub_slab: np.ndarray


class ShapeSet(NamedTuple):
    """Rounded hand shapes.

    Attributes
    ----------
    local : (k, 4, 4) float64 ndarray
        Pose in the hand frame, or in the chain link that carries each.
    kinds : (k,) int ndarray
        BOX / CYLINDER.
    halves : (k, 3) float64 ndarray
        Half extents of the core, m.
    radii : (k,) float64 ndarray
        Rounding radius, m.
    """

    local: np.ndarray
    kinds: np.ndarray
    halves: np.ndarray
    radii: np.ndarray


class Chain(NamedTuple):
    """A moving kinematic chain: joint j moves as q_j = q0_j + speeds_j * s.

    Attributes
    ----------
    base : (4, 4) float64 ndarray
        Frame of the first joint's parent in the hand frame.
    origins : (m, 4, 4) float64 ndarray
        Joint frames in their parent links.
    kinds : (m,) int ndarray
    axes : (m, 3) float64 ndarray
        Unit joint axes.
    q0 : (m,) float64 ndarray
        Start values, rad / m.
    speeds : (m,) float64 ndarray
    shape_joint : (k,) int ndarray
        The joint whose link carries each of ``shapes``.
    shapes : ShapeSet
    """

    base: np.ndarray
    origins: np.ndarray
    kinds: np.ndarray
    axes: np.ndarray
    q0: np.ndarray
    speeds: np.ndarray
    shape_joint: np.ndarray
    shapes: ShapeSet


class ChainFrames(NamedTuple):
    """Per-search constants of a Chain (see ``_chain_frames``).

    Attributes
    ----------
    inv_base : (3, 4) float64 ndarray
        Inverse of the chain's base frame.
    inv_origin : (m, 3, 4) float64 ndarray
        Inverses of the joint frames.
    inv_shape : (k, 3, 4) float64 ndarray
        Inverses of the shapes' local poses.
    chain_len : (m,) float64 ndarray
        Bound on the distance from the first joint to each joint, m.
    slide : (m,) float64 ndarray
        Largest extension of each prismatic joint over the search, m.
    drift : (m,) float64 ndarray
        Bound on the speed of each joint's origin (the joints before it carry it), m per
        unit of the motion parameter.
    """

    inv_base: np.ndarray
    inv_origin: np.ndarray
    inv_shape: np.ndarray
    chain_len: np.ndarray
    slide: np.ndarray
    drift: np.ndarray


class HandKernel(NamedTuple):
    """A hand flattened for :func:`simulate_batch`: its tree, its shapes and its fingers.

    Finger f owns the joints ``joint_start[f]:joint_start[f + 1]`` (proximal first); chain
    joint j of the whole array has the shape subset ``subset_start[j]:subset_start[j + 1]``:
    the shapes that move when the finger's first active joint is j (those of the links from
    j on), each with its joint's index in the finger (``subset_joint``), posed in its link.

    Attributes
    ----------
    tree : KinematicTree
    shape_link : (s,) int64 ndarray
        Link index of each shape.
    shapes : ShapeSet
        Every shape, posed in its link.
    finger_parent : (f,) int64 ndarray
        Link each finger's chain hangs from (no closing DOF moves it).
    joint_start : (f + 1,) int64 ndarray
        Offsets of each finger's joints.
    origins : (j, 4, 4) float64 ndarray
        Joint frames in their parent links.
    kinds : (j,) int64 ndarray
    axes : (j, 3) float64 ndarray
        Unit joint axes.
    ratios : (j,) float64 ndarray
        Joint value per unit of its DOF.
    speeds : (j,) float64 ndarray
        Closing speed of each joint's DOF.
    upper : (j,) float64 ndarray
        Upper limit of each joint's DOF, rad or m.
    dof_index : (j,) int64 ndarray
        Index of each joint's DOF.
    subset_start : (j + 1,) int64 ndarray
        Offsets of each joint's shape subset.
    subset_joint : (t,) int64 ndarray
        Finger joint index of each subset shape.
    subset_shapes : ShapeSet
        The subsets' shapes, posed in their links.
    """

    tree: KinematicTree
    shape_link: np.ndarray
    shapes: ShapeSet
    finger_parent: np.ndarray
    joint_start: np.ndarray
    origins: np.ndarray
    kinds: np.ndarray
    axes: np.ndarray
    ratios: np.ndarray
    speeds: np.ndarray
    upper: np.ndarray
    dof_index: np.ndarray
    subset_start: np.ndarray
    subset_joint: np.ndarray
    subset_shapes: ShapeSet


BISECTIONS = 48
# Closing parameter (rad for revolute joints, m for prismatic ones) used to tell whether a
# point within the hit level is being pressed (its distance falls) or left behind.
PROBE = 1e-7
# Step of a point inside the hit level that is not pressed: with speed bounds of a few
# tenths of a metre per radian it moves a few micrometres.
SLIDE_STEP = 2e-5
# Counters of one search (see first_contact_counted): heap pops, heap pushes, distance
# queries of the search, distance queries of the first-hit refinement.
POPS = 0
PUSHES = 1
QUERIES = 2
REFINE_QUERIES = 3
N_COUNTS = 4
# A fine cell thinner than this fraction of its radius across its best-fit plane is bounded
# by that plane's flat cylinder (flat_cell_sdf_at), a thicker one (a thin wall's two sides
# in one cell, a sharp bend) by its sphere: there the cylinder is hardly tighter and costs a
# subgradient per query.
FLAT_CELL = 0.4


@njit(cache=True, fastmath=False)
def sdf_local(x, y, z, kind, hx, hy, hz, r):
    """Signed distance of a point in a shape's frame to the rounded core.

    Parameters
    ----------
    x, y, z : float
        The point in the shape frame, m.
    kind : int
        BOX or CYLINDER.
    hx, hy, hz : float
        Core half extents, m.
    r : float
        Rounding radius, m.

    Returns
    -------
    float
        m; negative inside.
    """
    if kind == BOX:
        qx = abs(x) - hx
        qy = abs(y) - hy
        qz = abs(z) - hz
        ox = max(qx, 0.0)
        oy = max(qy, 0.0)
        oz = max(qz, 0.0)
        outside = np.sqrt(ox * ox + oy * oy + oz * oz)
        inside = min(max(qx, max(qy, qz)), 0.0)
        return outside + inside - r
    rho = np.sqrt(x * x + y * y)
    dr = rho - hx
    dz = abs(z) - hz
    ox = max(dr, 0.0)
    oz = max(dz, 0.0)
    return np.sqrt(ox * ox + oz * oz) + min(max(dr, dz), 0.0) - r


@njit(cache=True, inline="always")
def _sdf_subgradient(x, y, z, kind, hx, hy, hz):
    """A unit subgradient of :func:`sdf_local` at a point of the shape frame.

    The signed distance to a convex core (a box, a cylinder) is convex, so for every point
    p: sdf(p) >= sdf(c) + g . (p - c) with g a subgradient at c; outside the core g is the
    direction from the closest core point, inside it the normal of the nearest face.
    """
    if kind == BOX:
        qx = abs(x) - hx
        qy = abs(y) - hy
        qz = abs(z) - hz
        sx = 1.0 if x >= 0.0 else -1.0
        sy = 1.0 if y >= 0.0 else -1.0
        sz = 1.0 if z >= 0.0 else -1.0
        ox = max(qx, 0.0)
        oy = max(qy, 0.0)
        oz = max(qz, 0.0)
        o = np.sqrt(ox * ox + oy * oy + oz * oz)
        if o > 0.0:
            return sx * ox / o, sy * oy / o, sz * oz / o
        if qx >= qy and qx >= qz:
            return sx, 0.0, 0.0
        if qy >= qz:
            return 0.0, sy, 0.0
        return 0.0, 0.0, sz
    rho = np.sqrt(x * x + y * y)
    dr = rho - hx
    dz = abs(z) - hz
    sz = 1.0 if z >= 0.0 else -1.0
    ux = x / rho if rho > 0.0 else 1.0
    uy = y / rho if rho > 0.0 else 0.0
    orr = max(dr, 0.0)
    oz = max(dz, 0.0)
    o = np.sqrt(orr * orr + oz * oz)
    if o > 0.0:
        return ux * orr / o, uy * orr / o, sz * oz / o
    if dr >= dz:
        return ux, uy, 0.0
    return 0.0, 0.0, sz


@njit(cache=True, inline="always")
def _flat_slack(x, y, z, kind, hx, hy, hz, nx, ny, nz, thick, spread, grow):
    """How far below a shape's sdf at a flat cell's centre (x, y, z) any of its points can
    be: |g.n| thick + |g_t| spread (g the subgradient there, n the cell's unit normal, both
    in the shape's frame), at most the sphere's ``grow``."""
    gx, gy, gz = _sdf_subgradient(x, y, z, kind, hx, hy, hz)
    gn = min(abs(gx * nx + gy * ny + gz * nz), 1.0)
    return min(gn * thick + np.sqrt(1.0 - gn * gn) * spread, grow)


@njit(cache=True)
def sdf_at(px, py, pz, poses, s, kinds, halves, radii):
    """Signed distance of a hand-frame point to shape ``s`` of a set of shapes.

    The shape's rows are indexed in place (no views of them: in a compiled loop each view
    costs a reference-count increment and decrement).

    Parameters
    ----------
    px, py, pz : float
        The point, hand frame, m.
    poses : (S, 4, 4) float64 ndarray
        Hand-frame poses.
    s : int
        The shape.
    kinds : (S,) int ndarray
    halves : (S, 3) float64 ndarray
        Core half extents, m.
    radii : (S,) float64 ndarray
        Rounding radii, m.

    Returns
    -------
    float
        m; negative inside.
    """
    dx = px - poses[s, 0, 3]
    dy = py - poses[s, 1, 3]
    dz = pz - poses[s, 2, 3]
    x = poses[s, 0, 0] * dx + poses[s, 1, 0] * dy + poses[s, 2, 0] * dz
    y = poses[s, 0, 1] * dx + poses[s, 1, 1] * dy + poses[s, 2, 1] * dz
    z = poses[s, 0, 2] * dx + poses[s, 1, 2] * dy + poses[s, 2, 2] * dz
    return sdf_local(x, y, z, kinds[s], halves[s, 0], halves[s, 1], halves[s, 2], radii[s])


@njit(cache=True, inline="always")
def flat_cell_sdf_at(px, py, pz, poses, s, kinds, halves, radii, nx, ny, nz, thick, spread,
                     radius):  # fmt: skip
    """A lower bound on the signed distance of every point of a flat cell to shape ``s``.

    The cell's points lie within ``thick`` of the plane through the hand-frame point p with
    unit normal n, within ``spread`` of the normal line and within ``radius`` of p. The
    shape's signed distance is convex (:func:`_sdf_subgradient`), so every point is at
    least sdf(p) - (|g.n| thick + |g_t| spread) from it, g its subgradient at p; never
    below the sphere's sdf(p) - radius.

    Parameters
    ----------
    px, py, pz : float
        The cell's centre, hand frame, m.
    poses, s, kinds, halves, radii
        As for :func:`sdf_at`.
    nx, ny, nz : float
        The cell plane's unit normal, hand frame.
    thick, spread, radius : float
        m.

    Returns
    -------
    float
        m.
    """
    dx = px - poses[s, 0, 3]
    dy = py - poses[s, 1, 3]
    dz = pz - poses[s, 2, 3]
    x = poses[s, 0, 0] * dx + poses[s, 1, 0] * dy + poses[s, 2, 0] * dz
    y = poses[s, 0, 1] * dx + poses[s, 1, 1] * dy + poses[s, 2, 1] * dz
    z = poses[s, 0, 2] * dx + poses[s, 1, 2] * dy + poses[s, 2, 2] * dz
    kind = kinds[s]
    hx = halves[s, 0]
    hy = halves[s, 1]
    hz = halves[s, 2]
    d = sdf_local(x, y, z, kind, hx, hy, hz, radii[s])
    return d - _flat_slack(
        x, y, z, kind, hx, hy, hz,
        poses[s, 0, 0] * nx + poses[s, 1, 0] * ny + poses[s, 2, 0] * nz,
        poses[s, 0, 1] * nx + poses[s, 1, 1] * ny + poses[s, 2, 1] * nz,
        poses[s, 0, 2] * nx + poses[s, 1, 2] * ny + poses[s, 2, 2] * nz,
        thick, spread, radius,
    )  # fmt: skip


@njit(cache=True)
def outward_normal_world(px, py, pz, pose, kind, half, r):
    """Unit normal of the shape surface closest to the point, pointing out of the shape.

    Parameters
    ----------
    px, py, pz : float
        The point, hand frame, m.
    pose : (4, 4) float64 ndarray
        The shape's hand-frame pose.
    kind : int
    half : (3,) float64 ndarray
        Core half extents, m.
    r : float
        Rounding radius, m.

    Returns
    -------
    (3,) float64 ndarray
        Hand frame.
    """
    dx = px - pose[0, 3]
    dy = py - pose[1, 3]
    dz = pz - pose[2, 3]
    x = pose[0, 0] * dx + pose[1, 0] * dy + pose[2, 0] * dz
    y = pose[0, 1] * dx + pose[1, 1] * dy + pose[2, 1] * dz
    z = pose[0, 2] * dx + pose[1, 2] * dy + pose[2, 2] * dz
    if kind == BOX:
        cx = min(max(x, -half[0]), half[0])
        cy = min(max(y, -half[1]), half[1])
        cz = min(max(z, -half[2]), half[2])
    else:
        rho = np.sqrt(x * x + y * y)
        scale = 1.0
        if rho > half[0]:
            scale = half[0] / rho
        cx = x * scale
        cy = y * scale
        cz = min(max(z, -half[2]), half[2])
    nx = x - cx
    ny = y - cy
    nz = z - cz
    n = np.sqrt(nx * nx + ny * ny + nz * nz)
    if n < 1e-12:
        # The point is inside the core (deep penetration, which the policy never produces):
        # any unit vector will do; take the shape's ±z.
        nx, ny, nz = 0.0, 0.0, 1.0 if z >= 0 else -1.0
        n = 1.0
    nx /= n
    ny /= n
    nz /= n
    return (
        pose[0, 0] * nx + pose[0, 1] * ny + pose[0, 2] * nz,
        pose[1, 0] * nx + pose[1, 1] * ny + pose[1, 2] * nz,
        pose[2, 0] * nx + pose[2, 1] * ny + pose[2, 2] * nz,
    )


@njit(cache=True)
def _to_hand(points, i, rot, trans, out):
    """out = (points[i] - trans) @ rot: an object-frame point in the hand frame (the row is
    indexed in place: no view of it)."""
    dx = points[i, 0] - trans[0]
    dy = points[i, 1] - trans[1]
    dz = points[i, 2] - trans[2]
    out[0] = dx * rot[0, 0] + dy * rot[1, 0] + dz * rot[2, 0]
    out[1] = dx * rot[0, 1] + dy * rot[1, 1] + dz * rot[2, 1]
    out[2] = dx * rot[0, 2] + dy * rot[1, 2] + dz * rot[2, 2]


@njit(cache=True)
def _to_hand_direction(vectors, i, rot, out):
    """out = vectors[i] @ rot: an object-frame direction in the hand frame."""
    out[0] = vectors[i, 0] * rot[0, 0] + vectors[i, 1] * rot[1, 0] + vectors[i, 2] * rot[2, 0]
    out[1] = vectors[i, 0] * rot[0, 1] + vectors[i, 1] * rot[1, 1] + vectors[i, 2] * rot[2, 1]
    out[2] = vectors[i, 0] * rot[0, 2] + vectors[i, 1] * rot[1, 2] + vectors[i, 2] * rot[2, 2]


@njit(cache=True)
def _bounding_radius(kind, half, r):
    if kind == BOX:
        return np.sqrt(half[0] ** 2 + half[1] ** 2 + half[2] ** 2) + r
    return np.sqrt(half[0] ** 2 + half[2] ** 2) + r


@njit(cache=True)
def _sweep_entry(cx, cy, cz, rr, poses, q, axis, t_max):
    """For a sphere (hand-frame centre c, radius rr grown by a shape's bounding radius) and
    shape q (start pose ``poses[q]``) translating by 0..t_max along axis: the travel at
    which the sphere enters the shape's swept bounding sphere (0 if it is in already), or
    -1 if it never does."""
    dx = cx - poses[q, 0, 3]
    dy = cy - poses[q, 1, 3]
    dz = cz - poses[q, 2, 3]
    along = dx * axis[0] + dy * axis[1] + dz * axis[2]
    # the part across the axis (for the approach's axis, +z: exactly (dx, dy, 0))
    ex = dx - along * axis[0]
    ey = dy - along * axis[1]
    ez = dz - along * axis[2]
    d2 = ex * ex + ey * ey + ez * ez
    if d2 > rr * rr:
        return -1.0
    half_chord = np.sqrt(rr * rr - d2)
    if along + half_chord < 0.0 or along - half_chord > t_max:
        return -1.0
    return max(along - np.sqrt(rr * rr - ex * ex - ey * ey - ez * ez), 0.0)


@njit(cache=True)
def _chain_poses_into(s, chain, link_buf, shape_buf):
    """Fill link_buf (m, 4, 4) and shape_buf (k, 4, 4) with the chain's poses at ``s``."""
    tmp_a = np.empty((4, 4))
    tmp_b = np.empty((4, 4))
    mot = np.empty((4, 4))
    tmp_a[:, :] = chain.base
    for j in range(chain.origins.shape[0]):
        mul4_into(tmp_a, chain.origins[j], tmp_b)
        joint_motion_into(chain.kinds[j], chain.axes[j], chain.q0[j] + chain.speeds[j] * s, mot)
        mul4_into(tmp_b, mot, tmp_a)
        link_buf[j, :, :] = tmp_a
    for q in range(chain.shape_joint.shape[0]):
        mul4_into(link_buf[chain.shape_joint[q]], chain.shapes.local[q], shape_buf[q])


@njit(cache=True)
def _rotate(t, v):
    """The rotation part of t (4, 4) applied to v (3,)."""
    out = np.empty(3)
    for a in range(3):
        out[a] = t[a, 0] * v[0] + t[a, 1] * v[1] + t[a, 2] * v[2]
    return out


@njit(cache=True)
def _inverse_rigid(t, out):
    """out (3, 4) = the inverse of the rigid transform t (4, 4), as [R^T | -R^T p]."""
    for a in range(3):
        for b in range(3):
            out[a, b] = t[b, a]
        out[a, 3] = -(t[0, a] * t[0, 3] + t[1, a] * t[1, 3] + t[2, a] * t[2, 3])


@njit(cache=True)
def _chain_frames(chain, s_max):
    """What every distance query of a search reuses: the inverse frames and the bound on the
    distance from the first joint to each joint (the fixed offsets plus the largest
    extension of every slide before it)."""
    m = chain.origins.shape[0]
    k = chain.shape_joint.shape[0]
    inv_base = np.empty((3, 4))
    _inverse_rigid(chain.base, inv_base)
    inv_origin = np.empty((m, 3, 4))
    for j in range(m):
        _inverse_rigid(chain.origins[j], inv_origin[j])
    inv_shape = np.empty((k, 3, 4))
    for q in range(k):
        _inverse_rigid(chain.shapes.local[q], inv_shape[q])
    slide = np.zeros(m)
    for j in range(m):
        if chain.kinds[j] == PRISMATIC:
            slide[j] = max(abs(chain.q0[j]), abs(chain.q0[j] + chain.speeds[j] * s_max))
    chain_len = np.zeros(m)
    for j in range(1, m):
        o = chain.origins[j]
        chain_len[j] = (
            chain_len[j - 1] + slide[j - 1] + np.sqrt(o[0, 3] ** 2 + o[1, 3] ** 2 + o[2, 3] ** 2)
        )
    drift = np.zeros(m)
    for j in range(1, m):
        for i in range(j):
            if chain.kinds[i] == PRISMATIC:
                drift[j] += abs(chain.speeds[i])
            else:
                drift[j] += abs(chain.speeds[i]) * (chain_len[j] - chain_len[i])
    return ChainFrames(inv_base, inv_origin, inv_shape, chain_len, slide, drift)


@njit(cache=True, inline="always")
def _unturn(ax, ay, az, c, sn, x, y, z):
    """(x, y, z) rotated by -q about the unit axis (ax, ay, az), c = cos q, sn = sin q
    (Rodrigues)."""
    dot = (ax * x + ay * y + az * z) * (1.0 - c)
    cx = ay * z - az * y
    cy = az * x - ax * z
    cz = ax * y - ay * x
    return x * c - cx * sn + ax * dot, y * c - cy * sn + ay * dot, z * c - cz * sn + az * dot


@njit(cache=True, inline="always", error_model="numpy")
def _chain_touch(px, py, pz, s, r, chain, frames, margin, level, grow, trig, flat, nx, ny, nz,
                 thick, spread):  # fmt: skip
    """Distance of a hand-frame point to the moving shapes at motion parameter s.

    The point is carried down the chain (joint frame, then undo the joint's motion) instead
    of composing the links' poses: a few dozen operations per joint.
    r is the point's distance from the first joint origin and grow a cell's radius when the
    point is a cell centre (r includes it; 0 for a sample point); with a margin below the
    hit level the steps reach the hit level in finitely many steps.

    The safe step h against the shapes of link j is the largest of three bounds, each valid
    over the whole step. Two bound the point's speed: the distance over the speed bound
    sum_i<=j |w_i| (r + chain length to joint i), and the root of lin h + quad h^2 / 2 =
    distance, where lin = sum_i<=j |w_i| (|p - o_i(s)| + grow) is the point's speed bound
    now and quad = sum_i<=j |w_i| drift_i bounds how fast it grows as the joint origins o_i
    move. The second is several times tighter when the first moving joint is not the chain's first
    (a distal link closing alone: its origin does not move at all).

    A third bound follows the point's path instead of its speed. In link j's frame the
    point moves with velocity u, carried down the chain with the point (joint i adds
    -w_i a_i x y, y the point from its origin; a slide -w_i a_i), and its acceleration is at
    most A = sum_i<=j 2 |w_i| V_i-1 + w_i^2 (r + chain length to i), V_i-1 the speed bound
    of the joints before i. The signed distance of a rounded box or cylinder is convex and
    1-Lipschitz, so over a step h, sdf >= d + h g.u - A h^2 / 2 (g its subgradient,
    :func:`_sdf_subgradient`): the step is where that reaches ``level``. A point passing a
    link sideways (g.u near 0) steps by about sqrt(2 (d - level) / A) instead of
    (d - margin) / speed, one moving away further still. That bound keeps the point
    above the hit level (``level``), not above the margin: its steps never carry a point
    into the hit band and out again, so a point that grazes the band is met by the speed
    bounds' short steps, as without it. A query already within ``level`` gets no step
    from it.
    (error_model="numpy": no zero-division branches in the search's innermost arithmetic;
    every division here is guarded.)
    level : float
        The distance the path bound keeps the point above: the hit level, plus the radius
        for a cell (for a flat cell, of its sphere).
    trig : (m, 2) float64 ndarray
        cos and sin of each joint's value at s (:func:`_set_trig`): many queries in a row
        share their s (the children of a cell), so the search computes them once per s.
    flat : bool
        The point is the centre of a fine cell whose points lie within ``thick`` of the
        plane through it with hand-frame unit normal (nx, ny, nz) and within ``spread`` of
        the normal line: the distance returned is then a lower bound on every point's,
        per shape sdf(c) - (|g.n| thick + |g_t| spread) with g the shape's subgradient at c
        (convexity, see :func:`_sdf_subgradient`), never below the sphere's sdf(c) - grow.
        Several times tighter than the sphere where a link faces a flat patch, which then
        opens later or not at all. False (a literal at every call): a point or a sphere,
        and the normal's arithmetic is compiled away.
    returns : (smallest distance, its shape, the safe step in s)
    """
    ib = frames.inv_base
    x = ib[0, 0] * px + ib[0, 1] * py + ib[0, 2] * pz + ib[0, 3]
    y = ib[1, 0] * px + ib[1, 1] * py + ib[1, 2] * pz + ib[1, 3]
    z = ib[2, 0] * px + ib[2, 1] * py + ib[2, 2] * pz + ib[2, 3]
    vx = ib[0, 0] * nx + ib[0, 1] * ny + ib[0, 2] * nz
    vy = ib[1, 0] * nx + ib[1, 1] * ny + ib[1, 2] * nz
    vz = ib[2, 0] * nx + ib[2, 1] * ny + ib[2, 2] * nz
    d_min = np.inf
    q_min = -1
    step = np.inf
    shapes = chain.shapes
    bound = 0.0
    lin = 0.0
    quad = 0.0
    # the point's velocity in the current joint's frame (d/ds), and a bound on its
    # acceleration over every s
    ux = 0.0
    uy = 0.0
    uz = 0.0
    accel = 0.0
    io = frames.inv_origin
    it = frames.inv_shape
    halves = shapes.halves
    for j in range(chain.origins.shape[0]):
        x, y, z = (
            io[j, 0, 0] * x + io[j, 0, 1] * y + io[j, 0, 2] * z + io[j, 0, 3],
            io[j, 1, 0] * x + io[j, 1, 1] * y + io[j, 1, 2] * z + io[j, 1, 3],
            io[j, 2, 0] * x + io[j, 2, 1] * y + io[j, 2, 2] * z + io[j, 2, 3],
        )
        if flat:
            vx, vy, vz = (
                io[j, 0, 0] * vx + io[j, 0, 1] * vy + io[j, 0, 2] * vz,
                io[j, 1, 0] * vx + io[j, 1, 1] * vy + io[j, 1, 2] * vz,
                io[j, 2, 0] * vx + io[j, 2, 1] * vy + io[j, 2, 2] * vz,
            )
        ux, uy, uz = (
            io[j, 0, 0] * ux + io[j, 0, 1] * uy + io[j, 0, 2] * uz,
            io[j, 1, 0] * ux + io[j, 1, 1] * uy + io[j, 1, 2] * uz,
            io[j, 2, 0] * ux + io[j, 2, 1] * uy + io[j, 2, 2] * uz,
        )
        q = chain.q0[j] + chain.speeds[j] * s
        ax = chain.axes[j, 0]
        ay = chain.axes[j, 1]
        az = chain.axes[j, 2]
        w = abs(chain.speeds[j])
        if chain.kinds[j] != REVOLUTE:
            lin += w
        elif w > 0.0:
            # (x, y, z) is the point relative to joint j's origin
            lin += w * (np.sqrt(x * x + y * y + z * z) + grow)
            quad += w * frames.drift[j]
        if chain.kinds[j] == REVOLUTE:
            wj = chain.speeds[j]
            if wj != 0.0:
                # d/ds of Rot(-q) y is Rot(-q) (y' - w a x y); its second derivative adds
                # at most 2 |w| |y'| + w^2 |y|, |y| <= r + chain length
                ux -= wj * (ay * z - az * y)
                uy -= wj * (az * x - ax * z)
                uz -= wj * (ax * y - ay * x)
                accel += 2.0 * w * bound + w * w * (r + frames.chain_len[j])
            # Rotate by -q about the axis: into the moving link's frame.
            c = trig[j, 0]
            sn = trig[j, 1]
            x, y, z = _unturn(ax, ay, az, c, sn, x, y, z)
            ux, uy, uz = _unturn(ax, ay, az, c, sn, ux, uy, uz)
            if flat:
                vx, vy, vz = _unturn(ax, ay, az, c, sn, vx, vy, vz)
            bound += abs(chain.speeds[j]) * (r + frames.chain_len[j])
        else:
            x -= ax * q
            y -= ay * q
            z -= az * q
            ux -= ax * chain.speeds[j]
            uy -= ay * chain.speeds[j]
            uz -= az * chain.speeds[j]
            bound += abs(chain.speeds[j])
        d_joint = np.inf
        h_curved = np.inf
        for sq in range(chain.shape_joint.shape[0]):
            if chain.shape_joint[sq] != j:
                continue
            lx = it[sq, 0, 0] * x + it[sq, 0, 1] * y + it[sq, 0, 2] * z + it[sq, 0, 3]
            ly = it[sq, 1, 0] * x + it[sq, 1, 1] * y + it[sq, 1, 2] * z + it[sq, 1, 3]
            lz = it[sq, 2, 0] * x + it[sq, 2, 1] * y + it[sq, 2, 2] * z + it[sq, 2, 3]
            d = sdf_local(lx, ly, lz, shapes.kinds[sq], halves[sq, 0], halves[sq, 1],
                          halves[sq, 2], shapes.radii[sq])  # fmt: skip
            # d(s + h) >= d(s) + h g.u - accel h^2 / 2: the sdf is convex and 1-Lipschitz
            gx, gy, gz = _sdf_subgradient(lx, ly, lz, shapes.kinds[sq], halves[sq, 0],
                                          halves[sq, 1], halves[sq, 2])  # fmt: skip
            rate = (
                gx * (it[sq, 0, 0] * ux + it[sq, 0, 1] * uy + it[sq, 0, 2] * uz)
                + gy * (it[sq, 1, 0] * ux + it[sq, 1, 1] * uy + it[sq, 1, 2] * uz)
                + gz * (it[sq, 2, 0] * ux + it[sq, 2, 1] * uy + it[sq, 2, 2] * uz)
            )
            room = d - level
            if room <= 0.0:
                h_q = 0.0
            elif accel > 0.0:
                h_q = (rate + np.sqrt(rate * rate + 2.0 * accel * room)) / accel
            elif rate < 0.0:
                h_q = room / -rate
            else:
                h_q = np.inf
            h_curved = min(h_curved, h_q)
            if flat:
                d -= _flat_slack(
                    lx, ly, lz, shapes.kinds[sq], halves[sq, 0], halves[sq, 1], halves[sq, 2],
                    it[sq, 0, 0] * vx + it[sq, 0, 1] * vy + it[sq, 0, 2] * vz,
                    it[sq, 1, 0] * vx + it[sq, 1, 1] * vy + it[sq, 1, 2] * vz,
                    it[sq, 2, 0] * vx + it[sq, 2, 1] * vy + it[sq, 2, 2] * vz,
                    thick, spread, grow,
                )  # fmt: skip
            d_joint = min(d_joint, d)
            if d < d_min:
                d_min = d
                q_min = sq
        if bound > 0.0 and d_joint < np.inf:
            gap = max(d_joint - margin, 0.0)
            h_far = gap / bound
            # lin h + quad h^2 / 2 <= gap at h = gap / (lin + quad (gap / lin) / 2), since
            # gap / lin bounds h from above
            h_near = gap / (lin + 0.5 * quad * gap / lin) if lin > 0.0 else h_far
            step = min(step, max(h_far, h_near, h_curved))
    return d_min, q_min, step


@njit(cache=True)
def hull_extents(hx, hy, hz, rot):
    """The smallest and largest projection of a hull's vertices on each hand's x and y axes.

    The projection of vertex v on axis a of hand i is hx[v] rot[i, 0, a] + hy[v] rot[i, 1, a]
    + hz[v] rot[i, 2, a], multiplied and summed in that order: the same bits as numpy's
    term-by-term sum of the same products (not a matrix product, which BLAS rounds
    differently for a batch and for one row). One pass over the vertices per hand, no
    temporaries: numpy's form built (vertices, grasps) arrays chunk by chunk.

    Parameters
    ----------
    hx, hy, hz : (v,) float64 ndarray
        The vertices' coordinates, m.
    rot : (n, 3, 3) float64 ndarray
        Hand rotations (columns: the hand's axes).

    Returns
    -------
    (n, 4) float64 ndarray
        Per hand: x min, x max, y min, y max, m.
    """
    n = rot.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        x0 = rot[i, 0, 0]
        x1 = rot[i, 1, 0]
        x2 = rot[i, 2, 0]
        y0 = rot[i, 0, 1]
        y1 = rot[i, 1, 1]
        y2 = rot[i, 2, 1]
        xlo = np.inf
        xhi = -np.inf
        ylo = np.inf
        yhi = -np.inf
        for v in range(hx.shape[0]):
            px = hx[v] * x0 + hy[v] * x1 + hz[v] * x2
            py = hx[v] * y0 + hy[v] * y1 + hz[v] * y2
            xlo = min(xlo, px)
            xhi = max(xhi, px)
            ylo = min(ylo, py)
            yhi = max(yhi, py)
        out[i, 0] = xlo
        out[i, 1] = xhi
        out[i, 2] = ylo
        out[i, 3] = yhi
    return out


@njit(cache=True)
def _swept_distance(px, py, pz, u, q, shapes, shape_pose, axis):
    """For a translation: distance of a hand-frame point to shape q (at ``shape_pose`` when
    the motion starts) after it has travelled u along axis. Only the point moves (by -u
    along axis), so for the approach (axis +z) this is exactly sdf(px, py, pz - u)."""
    return sdf_at(px - axis[0] * u, py - axis[1] * u, pz - axis[2] * u, shape_pose, q,
                  shapes.kinds, shapes.halves, shapes.radii)  # fmt: skip


@njit(cache=True, inline="always")
def _set_trig(s, chain, trig):
    """cos and sin of every joint's value at s (rows of trig)."""
    for j in range(chain.q0.shape[0]):
        q = chain.q0[j] + chain.speeds[j] * s
        trig[j, 0] = np.cos(q)
        trig[j, 1] = np.sin(q)


@njit(cache=True)
def _heap_push(key, ident, prev, size, k, i, p):
    """Push (key k, entry i, bracket low p) on the 4-ary heap (key, ident, prev).

    Entry j's children are 4 j + 1 .. 4 j + 4: half the levels of a binary heap, and the
    four keys compared at each level are adjacent in memory. The parents above the new key
    move down one level and the entry is written once where it stops.
    """
    j = size
    while j > 0:
        parent = (j - 1) >> 2
        kp = key[parent]
        if kp <= k:
            break
        key[j] = kp
        ident[j] = ident[parent]
        prev[j] = prev[parent]
        j = parent
    key[j] = k
    ident[j] = i
    prev[j] = p
    return size + 1


@njit(cache=True)
def _heap_pop(key, ident, prev, size):
    """Pop the smallest key: (key, entry, bracket low, new size).

    The last entry sifts down from the root as a hole, each level to the smallest of the
    (up to four) children. Entries with equal keys may leave in another order than from a
    binary heap. Every key is a lower bound on when its entry can touch, so the first
    crossing the search finds does not depend on that order; which points touching at
    exactly that crossing it collects could (on the built-in objects the results equal
    those of a binary heap).
    """
    k0 = key[0]
    i0 = ident[0]
    p0 = prev[0]
    size -= 1
    k = key[size]
    i = ident[size]
    p = prev[size]
    j = 0
    while True:
        first = 4 * j + 1
        if first >= size:
            break
        child = first
        kc = key[first]
        for c in range(first + 1, min(first + 4, size)):
            if key[c] < kc:
                kc = key[c]
                child = c
        if k <= kc:
            break
        key[j] = kc
        ident[j] = ident[child]
        prev[j] = prev[child]
        j = child
    key[j] = k
    ident[j] = i
    prev[j] = p
    return k0, i0, p0, size


@njit(cache=True)
def _refine_first_hit(cloud, rot, trans, chain, frames, swept, axis, hits, n_hits, best, hit_eps,
                      counts):  # fmt: skip
    """The first crossing of the hit level among the hits whose bracket starts before the
    best one, each refined by bisection on its bracket [lo, hi].

    hits : (h, 4) rows (point index, shape slot, bracket low, bracket high) as float; slot
        q + 1 is a (point, shape q) pair of a translation, whose bracket is in travel (m),
        slot 0 a point against every shape of the chain, bracket in the motion parameter.
    swept : (k, 4, 4) the shapes' hand-frame poses when a translation starts.
    returns : (bracket value, point index, shape index); (inf, -1, -1) when there is no hit.
    """
    ph = np.empty(3)
    trig = np.empty((chain.q0.shape[0], 2))
    first = np.inf
    first_p = -1
    first_q = -1
    for h in range(n_hits):
        lo = hits[h, 2]
        if lo > best:
            continue
        i = int(hits[h, 0])
        slot = int(hits[h, 1])
        hi = hits[h, 3]
        _to_hand(cloud.points, i, rot, trans, ph)
        for _ in range(BISECTIONS):
            if hi - lo <= 1e-13:
                break
            mid = 0.5 * (lo + hi)
            counts[REFINE_QUERIES] += 1
            if slot > 0:
                dm = _swept_distance(ph[0], ph[1], ph[2], mid, slot - 1, chain.shapes, swept, axis)
            else:
                _set_trig(mid, chain, trig)
                dm, _, _ = _chain_touch(ph[0], ph[1], ph[2], mid, 0.0, chain, frames, hit_eps,
                                        hit_eps, 0.0, trig, False, 0.0, 0.0, 0.0, 0.0,
                                        0.0)  # fmt: skip
            if dm <= hit_eps:
                hi = mid
            else:
                lo = mid
        if hi < first:
            if slot > 0:
                q_hi = slot - 1
            else:
                counts[REFINE_QUERIES] += 1
                _set_trig(hi, chain, trig)
                _, q_hi, _ = _chain_touch(ph[0], ph[1], ph[2], hi, 0.0, chain, frames, hit_eps,
                                          hit_eps, 0.0, trig, False, 0.0, 0.0, 0.0, 0.0,
                                          0.0)  # fmt: skip
            first = hi
            first_p = i
            first_q = q_hi
    if first_p < 0:
        return np.inf, -1, -1
    return first, first_p, first_q


@njit(cache=True, inline="always")
def _cell_in_hand(center, radius, normal, slab, c, rot, trans, ph, nh_dir):
    """Fine or sub-cell c in the hand frame: its centre into ph and, where its points lie in
    a flat cylinder (see _chain_touch's flat), its normal into nh_dir.

    returns : (radius, slab thickness, slab spread, flat)
    """
    _to_hand(center, c, rot, trans, ph)
    r = radius[c]
    thick = slab[c, 0]
    spread = slab[c, 1]
    flat = thick < FLAT_CELL * r
    if flat:
        _to_hand_direction(normal, c, rot, nh_dir)
    return r, thick, spread, flat


@njit(cache=True)
def _ahead(c, poses, q, axis, u, extent):
    """For a translation: whether a shape (start pose ``pose``, bounding radius grown by the
    hit level and a cell's radius: ``extent``) that has travelled u along axis has not yet
    passed the point or cell centre c."""
    along = (
        (c[0] - poses[q, 0, 3]) * axis[0]
        + (c[1] - poses[q, 1, 3]) * axis[1]
        + (c[2] - poses[q, 2, 3]) * axis[2]
    )
    return along - u > -extent


@njit(cache=True, error_model="numpy")
def first_contact_counted(cloud, rot, trans, chain, s_max, hit_eps, counts):
    """:func:`first_contact`, adding the work it did to ``counts``.

    Parameters
    ----------
    cloud, rot, trans, chain, s_max, hit_eps
        As for :func:`first_contact`.
    counts : (N_COUNTS,) int64 ndarray
        Incremented in place, indexed by ``POPS``, ``PUSHES``, ``QUERIES``,
        ``REFINE_QUERIES`` (queue pops, queue pushes, distance queries of the search and of
        the refinement).

    Returns
    -------
    s : float
        inf when nothing is touched by s_max.
    point : int
        Sample index (-1: none).
    shape : int
        Shape index (-1: none).
    """
    m = chain.origins.shape[0]
    k = chain.shape_joint.shape[0]
    shapes = chain.shapes
    link_buf = np.empty((m, 4, 4))
    shape_buf = np.empty((k, 4, 4))
    _chain_poses_into(0.0, chain, link_buf, shape_buf)
    frames = _chain_frames(chain, s_max)
    tmp_a = np.empty((4, 4))
    tmp_b = np.empty((4, 4))
    mul4_into(chain.base, chain.origins[0], tmp_a)
    o0 = tmp_a[:3, 3].copy()
    a0 = _rotate(tmp_a, chain.axes[0])
    rho = np.empty(k)
    for q in range(k):
        # grown by the hit level: a point can come within hit_eps of a rounded corner while
        # still outside the exact bounding sphere
        rho[q] = (
            _bounding_radius(shapes.kinds[q], shapes.halves[q], shapes.radii[q]) + 2.0 * hit_eps
        )
    # A pure translation (the approach, a sliding jaw) moves every shape along one column:
    # its entries are (cell or point, shape) pairs, keyed and stepped in travel (m), and
    # a pair leaves the queue once the shape has passed it. Otherwise an entry is a cell or
    # point against the whole chain, keyed in the motion parameter.
    translation = m == 1 and chain.kinds[0] == PRISMATIC
    speed = abs(chain.speeds[0])
    # the direction the shapes travel (a slide may close along -axis)
    a_move = a0 * (1.0 if chain.speeds[0] >= 0.0 else -1.0)
    slots = k + 1 if translation else 1
    limit = speed * s_max if translation else s_max
    reach = 0.0
    for q in range(k):
        j = chain.shape_joint[q]
        dx = shape_buf[q, 0, 3] - link_buf[j, 0, 3]
        dy = shape_buf[q, 1, 3] - link_buf[j, 1, 3]
        dz = shape_buf[q, 2, 3] - link_buf[j, 2, 3]
        ext = _bounding_radius(shapes.kinds[q], shapes.halves[q], shapes.radii[q])
        reach = max(reach, frames.chain_len[j] + np.sqrt(dx * dx + dy * dy + dz * dz) + ext)
    reach += 2.0 * hit_eps
    # The shapes were placed at s = 0; slides can carry them further out, by at most the
    # slide's travel from where it is now.
    for j in range(m):
        if chain.kinds[j] == PRISMATIC:
            reach += abs(chain.speeds[j]) * s_max + frames.slide[j]
    # When every joint is revolute about parallel axes (a planar finger, like the Barrett's),
    # the links sweep a slab across that axis: nothing outside it can be touched.
    planar = True
    for j in range(m):
        if chain.kinds[j] != REVOLUTE:
            planar = False
            break
        if j > 0:
            mul4_into(link_buf[j - 1], chain.origins[j], tmp_b)
            aj = _rotate(tmp_b, chain.axes[j])
            if abs(aj[0] * a0[0] + aj[1] * a0[1] + aj[2] * a0[2]) < 1.0 - 1e-9:
                planar = False
                break
    slab = np.inf
    if planar:
        slab = 0.0
        for q in range(k):
            along = (
                (shape_buf[q, 0, 3] - o0[0]) * a0[0]
                + (shape_buf[q, 1, 3] - o0[1]) * a0[1]
                + (shape_buf[q, 2, 3] - o0[2]) * a0[2]
            )
            slab = max(slab, abs(along) + rho[q])
    # Heap entries: entry = code * slots + slot, code a point i (< n), the sub-cell n + b,
    # the fine cell n + ns + f or the coarse cell n + ns + nf + c; slot 0 the whole chain,
    # q + 1 the shape q of a translation. prev is the last key at which the entry was known
    # not to touch (the low end of the bracket of a crossing).
    n = cloud.points.shape[0]
    ns = cloud.sub_center.shape[0]
    nf = cloud.cell_center.shape[0]
    nk = cloud.coarse_center.shape[0]
    kc = np.empty((nk, 3))
    kr = np.empty(nk)
    # a translation's entry travel of each (coarse cell, shape) pair, -1: never enters
    t_enter = np.empty((nk, k) if translation else (0, k))
    tmp = np.empty(3)
    cap = 1
    for c in range(nk):
        _to_hand(cloud.coarse_center, c, rot, trans, tmp)
        kc[c, 0] = tmp[0]
        kc[c, 1] = tmp[1]
        kc[c, 2] = tmp[2]
        kr[c] = -1.0
        radius = cloud.coarse_radius[c]
        f0 = cloud.coarse_start[c]
        f1 = cloud.coarse_start[c + 1]
        below = (
            1
            + f1
            - f0
            + cloud.cell_sub_start[f1]
            - cloud.cell_sub_start[f0]
            + cloud.cell_start[f1]
            - cloud.cell_start[f0]
        )
        if translation:
            for q in range(k):
                rr = radius + rho[q]
                t_in = _sweep_entry(tmp[0], tmp[1], tmp[2], rr, shape_buf, q, a_move, limit)
                t_enter[c, q] = t_in
                if t_in >= 0.0:
                    cap += below
            continue
        dx = tmp[0] - o0[0]
        dy = tmp[1] - o0[1]
        dz = tmp[2] - o0[2]
        r0 = np.sqrt(dx * dx + dy * dy + dz * dz)
        if r0 - radius > reach:
            continue
        if abs(dx * a0[0] + dy * a0[1] + dz * a0[2]) - radius > slab:
            continue
        kr[c] = r0 + radius
        cap += below
    heap_key = np.empty(cap)
    heap_ident = np.empty(cap, dtype=np.int64)
    heap_prev = np.empty(cap)
    # the joints' cos and sin at trig_s (a chain's queries at one s share them)
    trig = np.empty((m, 2))
    trig_s = 0.0
    _set_trig(0.0, chain, trig)
    # the same at a probe's s (trig keeps those of trig_s for the entries that share it)
    trig_probe = np.empty((m, 2))
    # The children a touching cell releases share its key, the smallest of all (every key
    # pushed later is at least that): they wait on a stack, popped before the heap, instead
    # of each sifting through it.
    stack_e = np.empty(cap, dtype=np.int64)
    stack_p = np.empty(cap)
    stack_key = 0.0
    n_stack = 0
    size = 0
    margin = 0.5 * hit_eps
    for c in range(nk):
        code = n + ns + nf + c
        radius = cloud.coarse_radius[c]
        if translation:
            for q in range(k):
                t_in = t_enter[c, q]
                if t_in >= 0.0:
                    counts[PUSHES] += 1
                    e = code * slots + q + 1
                    size = _heap_push(heap_key, heap_ident, heap_prev, size, t_in, e, t_in)
            continue
        if kr[c] < 0.0:
            continue
        counts[QUERIES] += 1
        _, _, step = _chain_touch(kc[c, 0], kc[c, 1], kc[c, 2], 0.0, kr[c], chain, frames,
                                  margin + radius, hit_eps + radius, radius, trig, False, 0.0,
                                  0.0, 0.0, 0.0, 0.0)  # fmt: skip
        if step < s_max:
            counts[PUSHES] += 1
            size = _heap_push(heap_key, heap_ident, heap_prev, size, step, code * slots, 0.0)
    best = limit  # an upper bound on the first crossing, lowered by every hit
    hits = np.empty((64, 4))
    nh = 0
    ph = np.empty(3)
    nh_dir = np.empty(3)
    for _ in range(100_000_000):
        if n_stack > 0:
            n_stack -= 1
            s = stack_key
            e = stack_e[n_stack]
            s_prev = stack_p[n_stack]
        elif size == 0:
            break
        else:
            s, e, s_prev, size = _heap_pop(heap_key, heap_ident, heap_prev, size)
        if s != trig_s and not translation:
            _set_trig(s, chain, trig)
            trig_s = s
        counts[POPS] += 1
        if s >= best:
            break
        code = e // slots
        slot = e - code * slots
        q = slot - 1
        if code >= n:
            coarse = code >= n + ns + nf
            fine = not coarse and code >= n + ns
            flat = False
            thick = 0.0
            spread = 0.0
            if coarse:
                c = code - n - ns - nf
                radius = cloud.coarse_radius[c]
                _to_hand(cloud.coarse_center, c, rot, trans, ph)
            elif fine:
                c = code - n - ns
                radius, thick, spread, flat = _cell_in_hand(
                    cloud.cell_center, cloud.cell_radius, cloud.cell_normal, cloud.cell_slab,
                    c, rot, trans, ph, nh_dir,
                )  # fmt: skip
            else:
                c = code - n
                radius, thick, spread, flat = _cell_in_hand(
                    cloud.sub_center, cloud.sub_radius, cloud.sub_normal, cloud.sub_slab,
                    c, rot, trans, ph, nh_dir,
                )  # fmt: skip
            counts[QUERIES] += 1
            if translation:
                if not flat:
                    d = (
                        _swept_distance(ph[0], ph[1], ph[2], s, q, shapes, shape_buf, a_move)
                        - radius
                    )
                else:
                    # a fine or sub-cell: a flat cylinder (see flat_cell_sdf_at); a
                    # translation moves the point, not the direction
                    d = flat_cell_sdf_at(ph[0] - a_move[0] * s, ph[1] - a_move[1] * s,
                                         ph[2] - a_move[2] * s, shape_buf, q, shapes.kinds,
                                         shapes.halves, shapes.radii, nh_dir[0], nh_dir[1],
                                         nh_dir[2], thick, spread, radius)  # fmt: skip
                touching = d <= hit_eps
                nxt = s + d - margin
            elif not flat:
                dx = ph[0] - o0[0]
                dy = ph[1] - o0[1]
                dz = ph[2] - o0[2]
                r = np.sqrt(dx * dx + dy * dy + dz * dz) + radius
                d, _, step = _chain_touch(ph[0], ph[1], ph[2], s, r, chain, frames,
                                          margin + radius, hit_eps + radius, radius, trig, False,
                                          0.0, 0.0, 0.0, 0.0, 0.0)  # fmt: skip
                touching = d - radius <= hit_eps
                nxt = s + step
            else:
                # its points lie in a flat cylinder (see _chain_touch's flat)
                dx = ph[0] - o0[0]
                dy = ph[1] - o0[1]
                dz = ph[2] - o0[2]
                r = np.sqrt(dx * dx + dy * dy + dz * dz) + radius
                d, _, step = _chain_touch(ph[0], ph[1], ph[2], s, r, chain, frames, margin,
                                          hit_eps + radius, radius, trig, True, nh_dir[0],
                                          nh_dir[1], nh_dir[2], thick, spread)  # fmt: skip
                touching = d <= hit_eps
                nxt = s + step
            if touching:
                # Everything inside is still clear at s_prev and goes on from s, one level
                # down: fine cells of a coarse cell, sub-cells of a fine cell, points of a
                # sub-cell.
                stack_key = s
                if coarse:
                    f0 = cloud.coarse_start[c]
                    f1 = cloud.coarse_start[c + 1]
                    counts[PUSHES] += f1 - f0
                    for f in range(f1 - 1, f0 - 1, -1):
                        stack_e[n_stack] = (n + ns + f) * slots + slot
                        stack_p[n_stack] = s_prev
                        n_stack += 1
                elif fine:
                    b0 = cloud.cell_sub_start[c]
                    b1 = cloud.cell_sub_start[c + 1]
                    counts[PUSHES] += b1 - b0
                    for b in range(b1 - 1, b0 - 1, -1):
                        stack_e[n_stack] = (n + b) * slots + slot
                        stack_p[n_stack] = s_prev
                        n_stack += 1
                else:
                    i0 = cloud.sub_start[c]
                    i1 = cloud.sub_start[c + 1]
                    counts[PUSHES] += i1 - i0
                    for j in range(i1 - 1, i0 - 1, -1):
                        stack_e[n_stack] = cloud.sub_points[j] * slots + slot
                        stack_p[n_stack] = s_prev
                        n_stack += 1
            elif nxt < best:
                # A translation's pair is dropped once the shape has passed the cell.
                if not translation or _ahead(ph, shape_buf, q, a_move, nxt, rho[q] + radius):
                    counts[PUSHES] += 1
                    size = _heap_push(heap_key, heap_ident, heap_prev, size, nxt, e, s)
            continue
        _to_hand(cloud.points, code, rot, trans, ph)
        counts[QUERIES] += 1
        if translation:
            d = _swept_distance(ph[0], ph[1], ph[2], s, q, shapes, shape_buf, a_move)
            pressing = False
            if d <= hit_eps:
                # Within the hit level, a point blocks the motion only if the motion presses
                # into it: a link left touching by an earlier phase that moves away from the
                # object is free to move, as in GraspIt!.
                counts[QUERIES] += 1
                d_next = _swept_distance(
                    ph[0], ph[1], ph[2], s + speed * PROBE, q, shapes, shape_buf, a_move
                )
                pressing = d_next < d
            # d > hit_eps = 2 margin: a step of at least margin
            nxt = s + d - margin if d > hit_eps else s + speed * SLIDE_STEP
            still = _ahead(ph, shape_buf, q, a_move, nxt, rho[q])
        else:
            dx = ph[0] - o0[0]
            dy = ph[1] - o0[1]
            dz = ph[2] - o0[2]
            r = np.sqrt(dx * dx + dy * dy + dz * dz)
            d, _, step = _chain_touch(ph[0], ph[1], ph[2], s, r, chain, frames, margin, hit_eps,
                                      0.0, trig, False, 0.0, 0.0, 0.0, 0.0, 0.0)  # fmt: skip
            pressing = False
            if d <= hit_eps:
                counts[QUERIES] += 1
                s_probe = s + PROBE
                _set_trig(s_probe, chain, trig_probe)
                d_next, _, _ = _chain_touch(ph[0], ph[1], ph[2], s_probe, r, chain, frames,
                                            margin, hit_eps, 0.0, trig_probe, False, 0.0, 0.0,
                                            0.0, 0.0, 0.0)  # fmt: skip
                pressing = d_next < d
            # A point inside the hit level that is not pressed (receding or sliding) has no
            # safe step from its distance; it moves on by a small fixed one (a few µm of
            # motion) until it is clear or pressed.
            nxt = s + (step if d > hit_eps else SLIDE_STEP)
            still = True
        if pressing:
            if nh == hits.shape[0]:
                grown = np.empty((2 * nh, 4))
                grown[:nh] = hits
                hits = grown
            hits[nh, 0] = code
            hits[nh, 1] = slot
            hits[nh, 2] = s_prev
            hits[nh, 3] = s
            nh += 1
            best = min(best, s)
        elif nxt < best and still:
            counts[PUSHES] += 1
            size = _heap_push(heap_key, heap_ident, heap_prev, size, nxt, e, s)
    first, p, q = _refine_first_hit(cloud, rot, trans, chain, frames, shape_buf, a_move, hits,
                                    nh, best, hit_eps, counts)  # fmt: skip
    if translation and p >= 0:
        first = first / speed
    return first, p, q


@njit(cache=True)
def first_contact(cloud, rot, trans, chain, s_max, hit_eps):
    """Motion parameter at which a moving shape of ``chain`` first touches a sample point.

    A point's speed relative to link j is bounded by sum over joints i <= j of
    |speed_i| * |p - o_i| for revolute joints and |speed_i| for prismatic ones, where the
    joint origins o_i move at most as fast as the joints before them carry them; every step
    is at most what that bound allows over the step (see ``_chain_touch``), so no point can
    pass through a link, however thin the object part.

    The approach is the chain of one prismatic joint along +z carrying every shape; a
    finger's closing is its chain of revolute (or prismatic) joints. Cells (as bounding
    spheres) and points sit in one priority queue keyed by a lower bound on when they can
    first touch; the smallest is advanced by one step at a time, a touching cell releases
    its children (coarse -> fine -> sub-cells -> points), and the search stops once no entry can
    beat the best hit. A pure translation (the approach) queues (cell or point, shape) pairs
    instead: each shape sweeps a column, a coarse cell enters the queue for the shapes whose
    column it crosses, keyed by when it enters it, and a pair is dropped once its shape has
    passed it. The first crossing is then refined by bisection (:func:`_refine_first_hit`).

    Parameters
    ----------
    cloud : SampleCloud
        Surface samples, object frame.
    rot : (3, 3) float64 ndarray
    trans : (3,) float64 ndarray
        The hand pose: object frame = rot @ hand + trans (m).
    chain : Chain
        The moving joints and the shapes they carry.
    s_max : float
        Largest motion parameter searched.
    hit_eps : float
        Contact distance, m.

    Returns
    -------
    s : float
        inf when nothing is touched by s_max.
    point : int
        Sample index (-1: none).
    shape : int
        Shape index (-1: none).
    """
    return first_contact_counted(
        cloud, rot, trans, chain, s_max, hit_eps, np.zeros(N_COUNTS, dtype=np.int64)
    )


@njit(cache=True)
def close_finger(cloud, rot, trans, base, hk, f, dofs, hit_eps, at_limit):
    """Close finger f of a hand with breakaway until it touches or reaches its limits.

    Every joint below its upper limit closes at its speed; when a link touches, the joints
    up to it stop and those beyond go on; when a joint reaches its limit, it stops and the
    others go on (GraspIt!'s autograsp).

    Parameters
    ----------
    cloud : SampleCloud
        Surface samples, object frame.
    rot : (3, 3) float64 ndarray
    trans : (3,) float64 ndarray
        The hand pose: object frame = rot @ hand + trans (m).
    base : (4, 4) float64 ndarray
        Pose of the finger's parent link in the hand frame (no closing DOF moves it).
    hk : HandKernel
    f : int
        Finger index.
    dofs : (n_dofs,) float64 ndarray
        DOF values, updated in place.
    hit_eps : float
        Contact distance, m.
    at_limit : float
        A DOF this close below its upper limit has reached it.
    """
    j_a = hk.joint_start[f]
    j_b = hk.joint_start[f + 1]
    m = j_b - j_a
    origins = hk.origins[j_a:j_b]
    kinds = hk.kinds[j_a:j_b]
    axes = hk.axes[j_a:j_b]
    ratios = hk.ratios[j_a:j_b]
    speeds = hk.speeds[j_a:j_b]
    upper = hk.upper[j_a:j_b]
    dof_index = hk.dof_index[j_a:j_b]
    sub = hk.subset_shapes
    active = np.empty(m, dtype=np.bool_)
    for j in range(m):
        active[j] = dofs[dof_index[j]] < upper[j]
    q0 = np.empty(m)
    joint_speeds = np.empty(m)
    while True:
        j0 = -1
        for j in range(m):
            if active[j]:
                j0 = j
                break
        if j0 < 0:
            return
        # Largest s before an active DOF reaches its upper limit.
        s_max = np.inf
        for j in range(m):
            q0[j] = ratios[j] * dofs[dof_index[j]]
            joint_speeds[j] = ratios[j] * speeds[j] if active[j] else 0.0
            if active[j]:
                s_max = min(s_max, (upper[j] - dofs[dof_index[j]]) / speeds[j])
        s_max = max(s_max, 0.0)
        t_a = hk.subset_start[j_a + j0]
        t_b = hk.subset_start[j_a + j0 + 1]
        chain_index = hk.subset_joint[t_a:t_b]
        shapes = ShapeSet(sub.local[t_a:t_b], sub.kinds[t_a:t_b], sub.halves[t_a:t_b],
                          sub.radii[t_a:t_b])  # fmt: skip
        chain = Chain(base, origins, kinds, axes, q0, joint_speeds, chain_index, shapes)
        s_hit, _, q_hit = first_contact(cloud, rot, trans, chain, s_max, hit_eps)
        s = min(s_hit, s_max)
        for j in range(m):
            if active[j]:
                dofs[dof_index[j]] = min(dofs[dof_index[j]] + speeds[j] * s, upper[j])
        if np.isfinite(s_hit) and s_hit <= s_max:
            # Breakaway: the joints up to the blocked link stop, those beyond go on.
            blocked = chain_index[q_hit]
            for j in range(blocked + 1):
                active[j] = False
        else:
            # A joint reached its limit: it stops, the others go on.
            for j in range(m):
                if active[j] and not dofs[dof_index[j]] < upper[j] - at_limit:
                    active[j] = False


@njit(cache=True)
def close_fingers(cloud, rot, trans, hk, dofs, hit_eps, at_limit):
    """Close every finger of a hand, one after the other (see :func:`close_finger`).

    Parameters
    ----------
    cloud, rot, trans, hk, hit_eps, at_limit
        As for :func:`close_finger`.
    dofs : (n_dofs,) float64 ndarray
        DOF values, updated in place.
    """
    # A finger's chain hangs from a link that no closing DOF moves (the palm, or a Barrett
    # knuckle turned by the spread), so its pose is fixed while the fingers close.
    links = link_poses(dofs, hk.tree)
    for f in range(hk.finger_parent.shape[0]):
        close_finger(cloud, rot, trans, links[hk.finger_parent[f]], hk, f, dofs, hit_eps,
                     at_limit)  # fmt: skip


@njit(cache=True)
def _posed(hk, dofs):
    """Every shape of the hand with its hand-frame pose at ``dofs``."""
    sh = hk.shapes
    return ShapeSet(
        shape_poses(link_poses(dofs, hk.tree), hk.shape_link, sh.local),
        sh.kinds,
        sh.halves,
        sh.radii,
    )


@njit(cache=True)
def grasp_contacts(cloud, normals, sharp, rot, trans, hk, dofs, tol, merge_radius, cos_patch):
    """The contacts of a hand at rest: touching samples, facing the link, merged per link.

    Parameters
    ----------
    cloud : SampleCloud
        Surface samples, object frame.
    normals : (n, 3) float64 ndarray
        The samples' outward unit normals.
    sharp : (n,) bool ndarray
        Samples on sharp features (no object normal: the link's is taken).
    rot, trans, hk
        As for :func:`close_finger`.
    dofs : (n_dofs,) float64 ndarray
    tol : float
        Contact distance, m.
    merge_radius, cos_patch : float
        As for :func:`merge_contacts`.

    Returns
    -------
    point : (k,) int64 ndarray
        Sample index of each contact.
    shape : (k,) int64 ndarray
        Shape index of each contact.
    normal : (k, 3) float64 ndarray
        The object's outward unit normal at each contact, object frame.
    """
    pi, si, dist, ln = touching_points(cloud, rot, trans, _posed(hk, dofs), tol)
    m = pi.shape[0]
    n_obj = np.empty((m, 3))
    sel = np.empty(m, dtype=np.int64)
    ns = 0
    for t in range(m):
        # The link's normal in the object frame, reversed (it points into the link).
        lx = -(ln[t, 0] * rot[0, 0] + ln[t, 1] * rot[0, 1] + ln[t, 2] * rot[0, 2])
        ly = -(ln[t, 0] * rot[1, 0] + ln[t, 1] * rot[1, 1] + ln[t, 2] * rot[1, 2])
        lz = -(ln[t, 0] * rot[2, 0] + ln[t, 1] * rot[2, 1] + ln[t, 2] * rot[2, 2])
        # Object outward normal: the surface normal on smooth samples; on sharp features
        # (where the object has no normal) the normal of the touching link surface, reversed.
        if sharp[pi[t]]:
            n_obj[t, 0] = lx
            n_obj[t, 1] = ly
            n_obj[t, 2] = lz
        else:
            n_obj[t, :] = normals[pi[t]]
        # A sample facing away from the link lies on the far side of a part thinner than
        # the tolerance; it is not in contact.
        if n_obj[t, 0] * lx + n_obj[t, 1] * ly + n_obj[t, 2] * lz > 0.0:
            sel[ns] = t
            ns += 1
    sel = sel[:ns]
    pts = np.empty((ns, 3))
    for t in range(ns):
        pts[t, :] = cloud.points[pi[sel[t]]]
    keep = sel[
        merge_contacts(pts, n_obj[sel], dist[sel], hk.shape_link[si[sel]], merge_radius, cos_patch)
    ]
    return pi[keep], si[keep], n_obj[keep]


@njit(cache=True)
def simulate_batch(cloud, normals, sharp, starts, travel, dofs, hk, hit_eps, at_limit, tol,
                   merge_radius, cos_patch):  # fmt: skip
    """The grasp policy for a batch of start poses: approach, close, contacts.

    Parameters
    ----------
    cloud, normals, sharp
        The object's surface samples (see :func:`grasp_contacts`), object frame.
    starts : (n, 4, 4) float64 ndarray
        Hand -> object start poses, m.
    travel : (n,) float64 ndarray
        Approach length to try, m.
    dofs : (n, n_dofs) float64 ndarray
        Open DOF values of each grasp; overwritten with the final ones.
    hk : HandKernel
    hit_eps : float
        A moving link stops within this distance of the surface, m.
    at_limit : float
        A DOF this close below its upper limit has reached it.
    tol, merge_radius, cos_patch : float
        As for :func:`grasp_contacts`.

    Returns
    -------
    poses : (n, 4, 4) float64 ndarray
        Final hand -> object poses.
    touched : (n,) bool ndarray
        False where the approach missed the object.
    offsets : (n + 1,) int64 ndarray
        Contact rows of each grasp in the arrays below.
    point, shape : (k,) int64 ndarray
        Sample and shape index of each contact.
    normal : (k, 3) float64 ndarray
        Object outward unit normal at each contact.
    """
    n = starts.shape[0]
    k = hk.shape_link.shape[0]
    poses = starts.copy()
    touched = np.zeros(n, dtype=np.bool_)
    offsets = np.zeros(n + 1, dtype=np.int64)
    cap = 16 * n + 16
    c_point = np.empty(cap, dtype=np.int64)
    c_shape = np.empty(cap, dtype=np.int64)
    c_normal = np.empty((cap, 3))
    nc = 0
    # the approach: one slide along the hand's +z carrying every shape
    eye = np.eye(4)
    slide_origin = np.eye(4).reshape(1, 4, 4)
    slide_kind = np.array([PRISMATIC])
    slide_axis = np.array([[0.0, 0.0, 1.0]])
    slide_q0 = np.zeros(1)
    slide_speed = np.ones(1)
    slide_joint = np.zeros(k, dtype=np.int64)
    rot = np.empty((3, 3))
    trans = np.empty(3)
    for i in range(n):
        rot[:, :] = poses[i, :3, :3]
        trans[:] = poses[i, :3, 3]
        q = dofs[i]
        chain = Chain(eye, slide_origin, slide_kind, slide_axis, slide_q0, slide_speed,
                      slide_joint, _posed(hk, q))  # fmt: skip
        t, _, _ = first_contact(cloud, rot, trans, chain, travel[i], hit_eps)
        if np.isfinite(t):
            touched[i] = True
            for a in range(3):
                trans[a] += t * rot[a, 2]
            poses[i, :3, 3] = trans
            close_fingers(cloud, rot, trans, hk, q, hit_eps, at_limit)
            p, s, nrm = grasp_contacts(cloud, normals, sharp, rot, trans, hk, q, tol,
                                       merge_radius, cos_patch)  # fmt: skip
            m = p.shape[0]
            if nc + m > cap:
                cap = 2 * (nc + m)
                grown_p = np.empty(cap, dtype=np.int64)
                grown_s = np.empty(cap, dtype=np.int64)
                grown_n = np.empty((cap, 3))
                grown_p[:nc] = c_point[:nc]
                grown_s[:nc] = c_shape[:nc]
                grown_n[:nc] = c_normal[:nc]
                c_point, c_shape, c_normal = grown_p, grown_s, grown_n
            c_point[nc : nc + m] = p
            c_shape[nc : nc + m] = s
            c_normal[nc : nc + m] = nrm
            nc += m
        offsets[i + 1] = nc
    return poses, touched, offsets, c_point[:nc], c_shape[:nc], c_normal[:nc]


@njit(cache=True)
def touching_points(cloud, rot, trans, shapes, tol):
    """Samples of ``cloud`` within ``tol`` of any of ``shapes`` at a fixed hand pose.

    Parameters
    ----------
    cloud : SampleCloud
        Surface samples, object frame.
    rot : (3, 3) float64 ndarray
    trans : (3,) float64 ndarray
        The hand pose: object frame = rot @ hand + trans (m).
    shapes : ShapeSet
        Hand-frame poses.
    tol : float
        m.

    Returns
    -------
    points : (k,) int ndarray
        Sample indices.
    shapes : (k,) int ndarray
        Shape indices.
    dist : (k,) float64 ndarray
        Signed distances, m.
    normals : (k, 3) float64 ndarray
        The shape's outward unit normal at its closest point, hand frame (it points from the
        link towards the sample).
    """
    points = cloud.points
    cell_start = cloud.cell_start
    cell_center = cloud.cell_center
    cell_radius = cloud.cell_radius
    coarse_start = cloud.coarse_start
    coarse_center = cloud.coarse_center
    coarse_radius = cloud.coarse_radius
    poses = shapes.local
    kinds = shapes.kinds
    halves = shapes.halves
    radii = shapes.radii
    ns = poses.shape[0]
    cap = 64
    pi = np.empty(cap, dtype=np.int64)
    si = np.empty(cap, dtype=np.int64)
    dist = np.empty(cap)
    nrm = np.empty((cap, 3))
    m = 0
    rho = np.empty(ns)
    for s in range(ns):
        rho[s] = _bounding_radius(kinds[s], halves[s], radii[s]) + tol
    tmp = np.empty(3)
    ph = np.empty(3)
    normal = np.empty(3)
    for kk in range(coarse_center.shape[0]):
        _to_hand(coarse_center, kk, rot, trans, tmp)
        near = False
        for s in range(ns):
            dx = tmp[0] - poses[s, 0, 3]
            dy = tmp[1] - poses[s, 1, 3]
            dz = tmp[2] - poses[s, 2, 3]
            rr = rho[s] + coarse_radius[kk]
            if dx * dx + dy * dy + dz * dz <= rr * rr:
                near = True
                break
        if not near:
            continue
        for c in range(coarse_start[kk], coarse_start[kk + 1]):
            _to_hand(cell_center, c, rot, trans, tmp)
            _to_hand_direction(cloud.cell_normal, c, rot, normal)
            for s in range(ns):
                dx = tmp[0] - poses[s, 0, 3]
                dy = tmp[1] - poses[s, 1, 3]
                dz = tmp[2] - poses[s, 2, 3]
                rr = rho[s] + cell_radius[c]
                if dx * dx + dy * dy + dz * dz > rr * rr:
                    continue
                if cloud.cell_slab[c, 0] < FLAT_CELL * cell_radius[c]:
                    dc = flat_cell_sdf_at(tmp[0], tmp[1], tmp[2], poses, s, kinds, halves,
                                          radii, normal[0], normal[1], normal[2],
                                          cloud.cell_slab[c, 0], cloud.cell_slab[c, 1],
                                          cell_radius[c])  # fmt: skip
                else:
                    dc = sdf_at(tmp[0], tmp[1], tmp[2], poses, s, kinds, halves, radii)
                    dc -= cell_radius[c]
                if dc > tol:
                    continue
                for i in range(cell_start[c], cell_start[c + 1]):
                    _to_hand(points, i, rot, trans, ph)
                    d = sdf_at(ph[0], ph[1], ph[2], poses, s, kinds, halves, radii)
                    if d > tol:
                        continue
                    if m == cap:
                        cap *= 2
                        pi2 = np.empty(cap, dtype=np.int64)
                        si2 = np.empty(cap, dtype=np.int64)
                        dist2 = np.empty(cap)
                        nrm2 = np.empty((cap, 3))
                        pi2[:m] = pi
                        si2[:m] = si
                        dist2[:m] = dist
                        nrm2[:m] = nrm
                        pi, si, dist, nrm = pi2, si2, dist2, nrm2
                    nx, ny, nz = outward_normal_world(
                        ph[0], ph[1], ph[2], poses[s], kinds[s], halves[s], radii[s]
                    )
                    pi[m] = i
                    si[m] = s
                    dist[m] = d
                    nrm[m, 0] = nx
                    nrm[m, 1] = ny
                    nrm[m, 2] = nz
                    m += 1
    return pi[:m], si[:m], dist[:m], nrm[:m]


@njit(cache=True)
def _hull_2d(u, v, idx):
    """Indices (into idx) of the 2-D convex hull vertices of points (u, v)[idx] (monotone
    chain; collinear points reduce to the two ends)."""
    n = idx.shape[0]
    order = np.argsort(v[idx], kind="mergesort")
    order = order[np.argsort(u[idx][order], kind="mergesort")]
    pts = idx[order]
    hull = np.empty(2 * n + 1, dtype=np.int64)
    k = 0
    for t in range(2):
        start = k
        rng = range(n) if t == 0 else range(n - 1, -1, -1)
        for j in rng:
            p = pts[j]
            while k >= start + 2:
                a = hull[k - 2]
                b = hull[k - 1]
                cross = (u[b] - u[a]) * (v[p] - v[a]) - (v[b] - v[a]) * (u[p] - u[a])
                if cross > 1e-18:
                    break
                k -= 1
            hull[k] = p
            k += 1
        k -= 1  # the last point of each chain starts the other
    out = hull[: max(k, 1)]
    return np.unique(out)


@njit(cache=True)
def merge_contacts(points, normals, dist, link, radius, cos_patch):
    """Reduce touching samples to contacts: indices of the samples kept.

    Per link, samples whose normals agree within the patch angle form a patch; a flat patch
    carries exactly the wrenches of its 2-D convex hull, so only the hull's vertices stay.
    Then, closest first, a sample within ``radius`` of a kept one of the same link is merged
    into it (as GraspIt! merges contacts within 3 mm).

    Parameters
    ----------
    points : (k, 3) float64 ndarray
        m.
    normals : (k, 3) float64 ndarray
        Unit.
    dist : (k,) float64 ndarray
        Signed distances, m.
    link : (k,) int ndarray
    radius : float
        Merge radius, m.
    cos_patch : float
        Cosine of the patch angle.

    Returns
    -------
    (j,) int ndarray
        Indices of the samples kept.
    """
    k = points.shape[0]
    order = np.argsort(dist, kind="mergesort")
    group = np.full(k, -1, dtype=np.int64)
    leader = np.empty(k, dtype=np.int64)
    ng = 0
    for oi in range(k):
        i = order[oi]
        for g in range(ng):
            j = leader[g]
            if (
                link[j] == link[i]
                and (
                    normals[j, 0] * normals[i, 0]
                    + normals[j, 1] * normals[i, 1]
                    + normals[j, 2] * normals[i, 2]
                )
                > cos_patch
            ):
                group[i] = g
                break
        if group[i] < 0:
            leader[ng] = i
            group[i] = ng
            ng += 1
    candidate = np.zeros(k, dtype=np.bool_)
    u = np.empty(k)
    v = np.empty(k)
    for g in range(ng):
        members = np.nonzero(group == g)[0]
        if members.shape[0] < 4:
            candidate[members] = True
            continue
        n = normals[leader[g]]
        # Two tangents of the patch plane.
        if abs(n[0]) < 0.9:
            tx, ty, tz = 0.0, n[2], -n[1]
        else:
            tx, ty, tz = -n[2], 0.0, n[0]
        tn = np.sqrt(tx * tx + ty * ty + tz * tz)
        tx /= tn
        ty /= tn
        tz /= tn
        bx = n[1] * tz - n[2] * ty
        by = n[2] * tx - n[0] * tz
        bz = n[0] * ty - n[1] * tx
        for i in members:
            u[i] = points[i, 0] * tx + points[i, 1] * ty + points[i, 2] * tz
            v[i] = points[i, 0] * bx + points[i, 1] * by + points[i, 2] * bz
        candidate[_hull_2d(u, v, members)] = True
    kept = np.empty(k, dtype=np.int64)
    nk = 0
    r2 = radius * radius
    for oi in range(k):
        i = order[oi]
        if not candidate[i]:
            continue
        close = False
        for t in range(nk):
            j = kept[t]
            if link[j] != link[i]:
                continue
            dx = points[i, 0] - points[j, 0]
            dy = points[i, 1] - points[j, 1]
            dz = points[i, 2] - points[j, 2]
            if dx * dx + dy * dy + dz * dz < r2:
                close = True
                break
        if not close:
            kept[nk] = i
            nk += 1
    return np.sort(kept[:nk])
