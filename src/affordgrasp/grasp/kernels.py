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

import numpy as np
from numba import njit

from ..metrics.kernel_cache import install_package_stamp

install_package_stamp()  # before the first @njit (see kernel_cache)

# Shape kinds (see affordgrasp.hands.model).
BOX = 0
CYLINDER = 1
REVOLUTE = 0
PRISMATIC = 1
BISECTIONS = 48
# Closing parameter (rad for revolute joints, m for prismatic ones) used to tell whether a
# point within the hit level is being pressed (its distance falls) or left behind.
PROBE = 1e-7
# Step of a point inside the hit level that is not pressed: with speed bounds of a few
# tenths of a metre per radian it moves a few micrometres.
SLIDE_STEP = 2e-5


@njit(cache=True, fastmath=False)
def sdf_local(x, y, z, kind, hx, hy, hz, r):
    """Signed distance of a point in a shape's frame to the rounded core (m)."""
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


@njit(cache=True)
def sdf_world(px, py, pz, pose, kind, half, r):
    """Signed distance of a hand-frame point to a shape with hand-frame ``pose`` (4, 4)."""
    dx = px - pose[0, 3]
    dy = py - pose[1, 3]
    dz = pz - pose[2, 3]
    x = pose[0, 0] * dx + pose[1, 0] * dy + pose[2, 0] * dz
    y = pose[0, 1] * dx + pose[1, 1] * dy + pose[2, 1] * dz
    z = pose[0, 2] * dx + pose[1, 2] * dy + pose[2, 2] * dz
    return sdf_local(x, y, z, kind, half[0], half[1], half[2], r)


@njit(cache=True)
def outward_normal_world(px, py, pz, pose, kind, half, r):
    """Unit normal of the shape surface closest to the point, pointing out of the shape."""
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
def _to_hand(p, rot, trans, out):
    """out = (p - trans) @ rot: an object-frame point in the hand frame."""
    dx = p[0] - trans[0]
    dy = p[1] - trans[1]
    dz = p[2] - trans[2]
    out[0] = dx * rot[0, 0] + dy * rot[1, 0] + dz * rot[2, 0]
    out[1] = dx * rot[0, 1] + dy * rot[1, 1] + dz * rot[2, 1]
    out[2] = dx * rot[0, 2] + dy * rot[1, 2] + dz * rot[2, 2]


@njit(cache=True)
def _mul4_into(a, b, out):
    for i in range(4):
        for j in range(4):
            out[i, j] = (
                a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j] + a[i, 3] * b[3, j]
            )


@njit(cache=True)
def _bounding_radius(kind, half, r):
    if kind == BOX:
        return np.sqrt(half[0] ** 2 + half[1] ** 2 + half[2] ** 2) + r
    return np.sqrt(half[0] ** 2 + half[2] ** 2) + r


@njit(cache=True)
def _in_column(c, rr, pose, t_max):
    """Whether a sphere (hand-frame centre c, radius rr grown by a shape's bounding radius)
    meets the shape's bounding sphere while the hand travels 0..t_max along +z."""
    dx = c[0] - pose[0, 3]
    dy = c[1] - pose[1, 3]
    d2 = dx * dx + dy * dy
    if d2 > rr * rr:
        return False
    half_chord = np.sqrt(rr * rr - d2)
    dz = c[2] - pose[2, 3]
    return dz + half_chord >= 0.0 and dz - half_chord <= t_max


@njit(cache=True)
def _joint_motion_into(kind, axis, q, mot):
    """mot (4, 4) = the motion of a joint at value q: rotation about or translation along axis."""
    if kind == REVOLUTE:
        c = np.cos(q)
        sn = np.sin(q)
        C = 1.0 - c
        ax = axis[0]
        ay = axis[1]
        az = axis[2]
        mot[0, 0] = c + ax * ax * C
        mot[0, 1] = ax * ay * C - az * sn
        mot[0, 2] = ax * az * C + ay * sn
        mot[1, 0] = ay * ax * C + az * sn
        mot[1, 1] = c + ay * ay * C
        mot[1, 2] = ay * az * C - ax * sn
        mot[2, 0] = az * ax * C - ay * sn
        mot[2, 1] = az * ay * C + ax * sn
        mot[2, 2] = c + az * az * C
        mot[0, 3] = 0.0
        mot[1, 3] = 0.0
        mot[2, 3] = 0.0
    else:
        for a in range(3):
            for b in range(3):
                mot[a, b] = 1.0 if a == b else 0.0
            mot[a, 3] = axis[a] * q
    mot[3, 0] = 0.0
    mot[3, 1] = 0.0
    mot[3, 2] = 0.0
    mot[3, 3] = 1.0


@njit(cache=True)
def _chain_poses_into(
    s,
    base,
    origins,
    kinds,
    axes,
    q0,
    speeds,
    shape_joint,
    shape_local,
    link_buf,
    shape_buf,
    tmp_a,
    tmp_b,
):
    """Fill link_buf (m, 4, 4) and shape_buf (k, 4, 4) with the chain's poses at ``s``."""
    m = origins.shape[0]
    tmp_a[:, :] = base
    mot = np.empty((4, 4))
    for j in range(m):
        _mul4_into(tmp_a, origins[j], tmp_b)
        _joint_motion_into(kinds[j], axes[j], q0[j] + speeds[j] * s, mot)
        _mul4_into(tmp_b, mot, tmp_a)
        link_buf[j, :, :] = tmp_a
    for q in range(shape_joint.shape[0]):
        _mul4_into(link_buf[shape_joint[q]], shape_local[q], shape_buf[q])


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
def _chain_touch(px, py, pz, s, r, inv_base, inv_origin, kinds, axes, q0, speeds, shape_joint,
                 inv_shape, shape_kinds, halves, radii, chain_len, margin):  # fmt: skip
    """Distance of a hand-frame point to the moving shapes at closing parameter s.

    The point is carried down the chain (joint frame, then undo the joint's motion) instead
    of composing the links' poses: a few dozen operations per joint.
    r is the point's distance from the first joint origin (plus a cell's radius when the
    point is a cell centre); with a margin below the hit level the steps reach the hit level
    in finitely many steps.
    returns : (smallest distance, its shape, a safe step in s: min over shapes of
        (distance - margin) / (the point's speed bound relative to that shape's link))
    """
    x = inv_base[0, 0] * px + inv_base[0, 1] * py + inv_base[0, 2] * pz + inv_base[0, 3]
    y = inv_base[1, 0] * px + inv_base[1, 1] * py + inv_base[1, 2] * pz + inv_base[1, 3]
    z = inv_base[2, 0] * px + inv_base[2, 1] * py + inv_base[2, 2] * pz + inv_base[2, 3]
    d_min = np.inf
    q_min = -1
    step = np.inf
    for j in range(inv_origin.shape[0]):
        o = inv_origin[j]
        x, y, z = (
            o[0, 0] * x + o[0, 1] * y + o[0, 2] * z + o[0, 3],
            o[1, 0] * x + o[1, 1] * y + o[1, 2] * z + o[1, 3],
            o[2, 0] * x + o[2, 1] * y + o[2, 2] * z + o[2, 3],
        )
        q = q0[j] + speeds[j] * s
        ax = axes[j, 0]
        ay = axes[j, 1]
        az = axes[j, 2]
        if kinds[j] == REVOLUTE:
            # Rotate by -q about the axis (Rodrigues): into the moving link's frame.
            c = np.cos(q)
            sn = np.sin(q)
            dot = (ax * x + ay * y + az * z) * (1.0 - c)
            cx = ay * z - az * y
            cy = az * x - ax * z
            cz = ax * y - ay * x
            x, y, z = (x * c - cx * sn + ax * dot, y * c - cy * sn + ay * dot,
                       z * c - cz * sn + az * dot)  # fmt: skip
        else:
            x -= ax * q
            y -= ay * q
            z -= az * q
        for sq in range(shape_joint.shape[0]):
            if shape_joint[sq] != j:
                continue
            t = inv_shape[sq]
            lx = t[0, 0] * x + t[0, 1] * y + t[0, 2] * z + t[0, 3]
            ly = t[1, 0] * x + t[1, 1] * y + t[1, 2] * z + t[1, 3]
            lz = t[2, 0] * x + t[2, 1] * y + t[2, 2] * z + t[2, 3]
            h = halves[sq]
            d = sdf_local(lx, ly, lz, shape_kinds[sq], h[0], h[1], h[2], radii[sq])
            if d < d_min:
                d_min = d
                q_min = sq
            bound = 0.0
            for i in range(j + 1):
                if kinds[i] == REVOLUTE:
                    bound += abs(speeds[i]) * (r + chain_len[i])
                else:
                    bound += abs(speeds[i])
            if bound > 0.0:
                step = min(step, max(d - margin, 0.0) / bound)
    return d_min, q_min, step


@njit(cache=True)
def _heap_push(key, ident, prev, size, k, i, p):
    j = size
    key[j] = k
    ident[j] = i
    prev[j] = p
    while j > 0:
        parent = (j - 1) // 2
        if key[parent] <= key[j]:
            break
        key[parent], key[j] = key[j], key[parent]
        ident[parent], ident[j] = ident[j], ident[parent]
        prev[parent], prev[j] = prev[j], prev[parent]
        j = parent
    return size + 1


@njit(cache=True)
def _heap_pop(key, ident, prev, size):
    k = key[0]
    i = ident[0]
    p = prev[0]
    size -= 1
    key[0] = key[size]
    ident[0] = ident[size]
    prev[0] = prev[size]
    j = 0
    while True:
        left = 2 * j + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and key[left + 1] < key[left]:
            child = left + 1
        if key[j] <= key[child]:
            break
        key[child], key[j] = key[j], key[child]
        ident[child], ident[j] = ident[j], ident[child]
        prev[child], prev[j] = prev[j], prev[child]
        j = child
    return k, i, p, size


@njit(cache=True)
def approach_until_contact(
    points, cell_start, cell_center, cell_radius, coarse_start, coarse_center, coarse_radius,
    rot, trans, poses, kinds, halves, radii, t_max, hit_eps,
):  # fmt: skip
    """Distance the hand can travel along its +z before a link touches a sample point.

    points : (n, 3) object samples in the object frame, grouped by cell
    cell_start : (c + 1,) offsets of each fine cell's points; cell_center (c, 3),
        cell_radius (c,) a bounding sphere per cell; coarse_start (k + 1,) offsets of each
        coarse cell's fine cells, coarse_center (k, 3), coarse_radius (k,)
    rot, trans : the start pose of the hand (object frame = rot @ hand + trans)
    poses : (s, 4, 4) shape poses in the hand frame; kinds (s,), halves (s, 3), radii (s,)
    returns : (t, point index, shape index); (inf, -1, -1) if nothing is touched by t_max.

    Every point moves at unit speed relative to the hand, so a step never exceeds its
    distance to a shape. (cell or point, shape) pairs sit in one priority queue keyed by a
    lower bound on their touching time, as in the closing search: coarse cells whose sphere
    crosses the column a shape sweeps, then, once a cell's sphere touches, its fine cells,
    then their points. The first crossing of the hit level is refined by bisection.
    """
    n = points.shape[0]
    nc = cell_center.shape[0]
    nk = coarse_center.shape[0]
    ns = poses.shape[0]
    rho = np.empty(ns)
    for s in range(ns):
        # Grown by the hit level: a point can come within hit_eps of a rounded corner while
        # still outside the exact bounding sphere.
        rho[s] = _bounding_radius(kinds[s], halves[s], radii[s]) + 2.0 * hit_eps
    # Entity codes: a point i, then fine cell n + c, then coarse cell n + nc + k; an entry's
    # id is entity * ns + shape.
    kc = np.empty((nk, 3))
    cap = 1
    for kk in range(nk):
        _to_hand(coarse_center[kk], rot, trans, kc[kk])
        for s in range(ns):
            if _in_column(kc[kk], coarse_radius[kk] + rho[s], poses[s], t_max):
                cap += 1 + coarse_start[kk + 1] - coarse_start[kk]
                cap += cell_start[coarse_start[kk + 1]] - cell_start[coarse_start[kk]]
    key = np.empty(cap)
    ident = np.empty(cap, dtype=np.int64)
    prev = np.empty(cap)
    size = 0
    for kk in range(nk):
        for s in range(ns):
            rr = coarse_radius[kk] + rho[s]
            if not _in_column(kc[kk], rr, poses[s], t_max):
                continue
            dx = kc[kk, 0] - poses[s, 0, 3]
            dy = kc[kk, 1] - poses[s, 1, 3]
            t_in = max(kc[kk, 2] - poses[s, 2, 3] - np.sqrt(rr * rr - dx * dx - dy * dy), 0.0)
            size = _heap_push(key, ident, prev, size, t_in, (n + nc + kk) * ns + s, t_in)
    best = t_max
    hp = np.empty(16, dtype=np.int64)
    hs = np.empty(16, dtype=np.int64)
    hlo = np.empty(16)
    hhi = np.empty(16)
    nh = 0
    x = np.empty(3)
    margin = 0.5 * hit_eps
    for _ in range(10_000_000):
        if size == 0:
            break
        t, e, t_prev = _heap_pop(key, ident, prev, size)[:3]
        size -= 1
        if t >= best:
            break
        s = e % ns
        ent = e // ns
        if ent >= n:
            coarse = ent >= n + nc
            c = ent - n - nc if coarse else ent - n
            radius = coarse_radius[c] if coarse else cell_radius[c]
            _to_hand(coarse_center[c] if coarse else cell_center[c], rot, trans, x)
            d = sdf_world(x[0], x[1], x[2] - t, poses[s], kinds[s], halves[s], radii[s]) - radius
            if d <= hit_eps:
                # Everything inside is clear at t_prev and goes on from t, one level down.
                if coarse:
                    for f in range(coarse_start[c], coarse_start[c + 1]):
                        size = _heap_push(key, ident, prev, size, t, (n + f) * ns + s, t_prev)
                else:
                    for i in range(cell_start[c], cell_start[c + 1]):
                        size = _heap_push(key, ident, prev, size, t, i * ns + s, t_prev)
            else:
                nxt = t + d - margin
                # Past the shape's bounding sphere the pair can no longer touch.
                if nxt < best and x[2] - poses[s, 2, 3] - nxt > -(rho[s] + radius):
                    size = _heap_push(key, ident, prev, size, nxt, e, t)
            continue
        _to_hand(points[ent], rot, trans, x)
        d = sdf_world(x[0], x[1], x[2] - t, poses[s], kinds[s], halves[s], radii[s])
        if d <= hit_eps:
            if nh == hp.shape[0]:
                hp = np.concatenate((hp, np.empty(nh, dtype=np.int64)))
                hs = np.concatenate((hs, np.empty(nh, dtype=np.int64)))
                hlo = np.concatenate((hlo, np.empty(nh)))
                hhi = np.concatenate((hhi, np.empty(nh)))
            hp[nh] = ent
            hs[nh] = s
            hlo[nh] = t_prev
            hhi[nh] = t
            nh += 1
            best = min(best, t)
        else:
            nxt = t + d - margin  # d > hit_eps = 2 margin: at least margin
            if nxt < best and x[2] - poses[s, 2, 3] - nxt > -rho[s]:
                size = _heap_push(key, ident, prev, size, nxt, e, t)
    # Refine the hits whose bracket starts before the best one by bisection. Steps that
    # jump past the best hit are dropped, so the hand stops with a gap in [hit_eps / 2,
    # hit_eps] to the closest sample, never touching it.
    first = np.inf
    first_p = -1
    first_s = -1
    for h in range(nh):
        if hlo[h] > best:
            continue
        s = hs[h]
        _to_hand(points[hp[h]], rot, trans, x)
        lo = hlo[h]
        hi = hhi[h]
        for _ in range(BISECTIONS):
            if hi - lo <= 1e-13:
                break
            mid = 0.5 * (lo + hi)
            if (
                sdf_world(x[0], x[1], x[2] - mid, poses[s], kinds[s], halves[s], radii[s])
                <= hit_eps
            ):
                hi = mid
            else:
                lo = mid
        if hi < first:
            first = hi
            first_p = hp[h]
            first_s = s
    if first_p < 0:
        return np.inf, -1, -1
    return first, first_p, first_s


@njit(cache=True)
def close_chain_until_contact(
    points, cell_start, cell_center, cell_radius, coarse_start, coarse_center, coarse_radius,
    rot, trans,
    base, origins, kinds, axes, q0, speeds,
    shape_joint, shape_local, shape_kinds, shape_halves, shape_radii,
    s_max, hit_eps,
):  # fmt: skip
    """Closing parameter at which a moving link of a finger first touches a sample point.

    The chain's joints move as q_j = q0_j + speeds_j * s (joint frames: ``origins`` in their
    parent link, the first one's parent at ``base`` in the hand frame). shape_joint (k,) is
    the chain link carrying each moving shape, shape_local (k, 4, 4) its pose in that link.
    A point's speed relative to link j is bounded by sum over joints i <= j of
    |speed_i| * (|p - o_0| + chain length to joint i) for revolute joints and |speed_i| for
    prismatic ones (o_0, the first joint's origin, does not move while the finger closes);
    every step is a distance over that bound, so no point can pass through a link.

    Cells (as bounding spheres) and points sit in one priority queue keyed by a lower bound
    on when they can first touch; the smallest is advanced by one step at a time, a touching
    cell releases its points, and the search stops once no entry can beat the best hit. The
    first crossing of the hit level is then refined by bisection among the hits that can
    still be first.
    returns : (s, point index, shape index); (inf, -1, -1) when nothing is touched by s_max.
    """
    m = origins.shape[0]
    k = shape_joint.shape[0]
    link_buf = np.empty((m, 4, 4))
    shape_buf = np.empty((k, 4, 4))
    tmp_a = np.empty((4, 4))
    tmp_b = np.empty((4, 4))
    _chain_poses_into(0.0, base, origins, kinds, axes, q0, speeds, shape_joint, shape_local,
                      link_buf, shape_buf, tmp_a, tmp_b)  # fmt: skip
    _mul4_into(base, origins[0], tmp_a)
    o0 = tmp_a[:3, 3].copy()
    inv_base = np.empty((3, 4))
    _inverse_rigid(base, inv_base)
    inv_origin = np.empty((m, 3, 4))
    for j in range(m):
        _inverse_rigid(origins[j], inv_origin[j])
    inv_shape = np.empty((k, 3, 4))
    for q in range(k):
        _inverse_rigid(shape_local[q], inv_shape[q])
    # Bound on the distance from the first joint to joint j whatever the joints do: the fixed
    # offsets plus the largest extension of every slide before it.
    slide = np.zeros(m)
    for j in range(m):
        if kinds[j] == PRISMATIC:
            slide[j] = max(abs(q0[j]), abs(q0[j] + speeds[j] * s_max))
    chain_len = np.zeros(m)
    for j in range(1, m):
        chain_len[j] = (
            chain_len[j - 1]
            + slide[j - 1]
            + np.sqrt(origins[j, 0, 3] ** 2 + origins[j, 1, 3] ** 2 + origins[j, 2, 3] ** 2)
        )
    reach = 0.0
    for q in range(k):
        j = shape_joint[q]
        dx = shape_buf[q, 0, 3] - link_buf[j, 0, 3]
        dy = shape_buf[q, 1, 3] - link_buf[j, 1, 3]
        dz = shape_buf[q, 2, 3] - link_buf[j, 2, 3]
        ext = _bounding_radius(shape_kinds[q], shape_halves[q], shape_radii[q])
        reach = max(reach, chain_len[j] + np.sqrt(dx * dx + dy * dy + dz * dz) + ext)
    reach += 2.0 * hit_eps
    # The shapes were placed at s = 0; slides can carry them further out, by at most the
    # slide's travel from where it is now.
    for j in range(m):
        if kinds[j] == PRISMATIC:
            reach += abs(speeds[j]) * s_max + slide[j]
    # When every joint is revolute about parallel axes (a planar finger, like the Barrett's),
    # the links sweep a slab across that axis: nothing outside it can be touched.
    _mul4_into(base, origins[0], tmp_a)
    a0 = _rotate(tmp_a, axes[0])
    planar = True
    for j in range(m):
        if kinds[j] != REVOLUTE:
            planar = False
            break
        if j > 0:
            _mul4_into(link_buf[j - 1], origins[j], tmp_b)
            aj = _rotate(tmp_b, axes[j])
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
            ext = _bounding_radius(shape_kinds[q], shape_halves[q], shape_radii[q])
            slab = max(slab, abs(along) + ext)
        slab += 2.0 * hit_eps
    # Heap entries: id >= 0 a point, -1 - f the fine cell f, -1 - nf - k the coarse cell k;
    # prev is the last key at which the entry was known not to touch (the low end of the
    # bracket of a crossing).
    nf = cell_center.shape[0]
    nk = coarse_center.shape[0]
    kc = np.empty((nk, 3))
    kr = np.empty(nk)
    tmp = np.empty(3)
    cap = nk + 1
    for c in range(nk):
        _to_hand(coarse_center[c], rot, trans, tmp)
        dx = tmp[0] - o0[0]
        dy = tmp[1] - o0[1]
        dz = tmp[2] - o0[2]
        r0 = np.sqrt(dx * dx + dy * dy + dz * dz)
        kc[c, 0] = tmp[0]
        kc[c, 1] = tmp[1]
        kc[c, 2] = tmp[2]
        kr[c] = -1.0
        if r0 - coarse_radius[c] > reach:
            continue
        if abs(dx * a0[0] + dy * a0[1] + dz * a0[2]) - coarse_radius[c] > slab:
            continue
        kr[c] = r0 + coarse_radius[c]
        f0 = coarse_start[c]
        f1 = coarse_start[c + 1]
        cap += f1 - f0 + cell_start[f1] - cell_start[f0]
    key = np.empty(cap)
    ident = np.empty(cap, dtype=np.int64)
    prev = np.empty(cap)
    size = 0
    for c in range(nk):
        if kr[c] < 0.0:
            continue
        d, _, step = _chain_touch(kc[c, 0], kc[c, 1], kc[c, 2], 0.0, kr[c], inv_base,
                                  inv_origin, kinds, axes, q0, speeds, shape_joint, inv_shape,
                                  shape_kinds, shape_halves, shape_radii, chain_len,
                                  0.5 * hit_eps + coarse_radius[c])  # fmt: skip
        if step < s_max:
            size = _heap_push(key, ident, prev, size, step, -1 - nf - c, 0.0)
    best = s_max  # an upper bound on the first crossing, lowered by every hit
    hp = np.empty(64, dtype=np.int64)
    hlo = np.empty(64)
    hhi = np.empty(64)
    nh = 0
    ph = np.empty(3)
    for _ in range(1_000_000):
        if size == 0:
            break
        s, e, s_prev = _heap_pop(key, ident, prev, size)[:3]
        size -= 1
        if s >= best:
            break
        if e < 0:
            coarse = -1 - e >= nf
            c = -1 - e - nf if coarse else -1 - e
            radius = coarse_radius[c] if coarse else cell_radius[c]
            center = coarse_center[c] if coarse else cell_center[c]
            _to_hand(center, rot, trans, ph)
            dx = ph[0] - o0[0]
            dy = ph[1] - o0[1]
            dz = ph[2] - o0[2]
            r = np.sqrt(dx * dx + dy * dy + dz * dz) + radius
            d, _, step = _chain_touch(ph[0], ph[1], ph[2], s, r, inv_base, inv_origin, kinds,
                                      axes, q0, speeds, shape_joint, inv_shape, shape_kinds,
                                      shape_halves, shape_radii, chain_len,
                                      0.5 * hit_eps + radius)  # fmt: skip
            if d - radius <= hit_eps:
                # Everything inside is still clear at s_prev and goes on from s, one level
                # down: fine cells of a coarse cell, points of a fine cell.
                if coarse:
                    for f in range(coarse_start[c], coarse_start[c + 1]):
                        size = _heap_push(key, ident, prev, size, s, -1 - f, s_prev)
                else:
                    for i in range(cell_start[c], cell_start[c + 1]):
                        size = _heap_push(key, ident, prev, size, s, i, s_prev)
            elif s + step < best:
                size = _heap_push(key, ident, prev, size, s + step, e, s)
            continue
        _to_hand(points[e], rot, trans, ph)
        dx = ph[0] - o0[0]
        dy = ph[1] - o0[1]
        dz = ph[2] - o0[2]
        r = np.sqrt(dx * dx + dy * dy + dz * dz)
        d, _, step = _chain_touch(ph[0], ph[1], ph[2], s, r, inv_base, inv_origin, kinds, axes,
                                  q0, speeds, shape_joint, inv_shape, shape_kinds, shape_halves,
                                  shape_radii, chain_len, 0.5 * hit_eps)  # fmt: skip
        pressing = False
        if d <= hit_eps:
            # Within the hit level, a point blocks the finger only if the motion presses into
            # it: a link left touching by the approach (or an earlier phase) that closes away
            # from the object is free to move, as in GraspIt!.
            d_next, _, _ = _chain_touch(ph[0], ph[1], ph[2], s + PROBE, r, inv_base, inv_origin,
                                        kinds, axes, q0, speeds, shape_joint, inv_shape,
                                        shape_kinds, shape_halves, shape_radii, chain_len,
                                        0.5 * hit_eps)  # fmt: skip
            pressing = d_next < d
        if pressing:
            if nh == hp.shape[0]:
                hp = np.concatenate((hp, np.empty(nh, dtype=np.int64)))
                hlo = np.concatenate((hlo, np.empty(nh)))
                hhi = np.concatenate((hhi, np.empty(nh)))
            hp[nh] = e
            hlo[nh] = s_prev
            hhi[nh] = s
            nh += 1
            best = min(best, s)
        else:
            # A point inside the hit level that is not pressed (receding or sliding) has no
            # safe step from its distance; it moves on by a small fixed one (a few µm of
            # motion) until it is clear or pressed.
            nxt = s + (step if d > hit_eps else SLIDE_STEP)
            if nxt < best:
                size = _heap_push(key, ident, prev, size, nxt, e, s)
    # The first crossing among the hits whose bracket starts before the best hit.
    first = np.inf
    first_p = -1
    first_q = -1
    for h in range(nh):
        if hlo[h] > best:
            continue
        i = hp[h]
        _to_hand(points[i], rot, trans, ph)
        lo = hlo[h]
        hi = hhi[h]
        for _ in range(BISECTIONS):
            if hi - lo <= 1e-13:
                break
            mid = 0.5 * (lo + hi)
            dm, _, _ = _chain_touch(ph[0], ph[1], ph[2], mid, 0.0, inv_base, inv_origin, kinds,
                                    axes, q0, speeds, shape_joint, inv_shape, shape_kinds,
                                    shape_halves, shape_radii, chain_len, hit_eps)  # fmt: skip
            if dm <= hit_eps:
                hi = mid
            else:
                lo = mid
        if hi < first:
            _, q_hi, _ = _chain_touch(ph[0], ph[1], ph[2], hi, 0.0, inv_base, inv_origin, kinds,
                                      axes, q0, speeds, shape_joint, inv_shape, shape_kinds,
                                      shape_halves, shape_radii, chain_len, hit_eps)  # fmt: skip
            first = hi
            first_p = i
            first_q = q_hi
    if first_p < 0:
        return np.inf, -1, -1
    return first, first_p, first_q


@njit(cache=True)
def touching_points(
    points, cell_start, cell_center, cell_radius, coarse_start, coarse_center, coarse_radius,
    rot, trans, poses, kinds, halves, radii, tol,
):  # fmt: skip
    """Samples within ``tol`` of any shape at a fixed hand configuration.

    returns : point indices (k,), shape indices (k,), signed distances (k,) and the shape's
        outward unit normal at its closest point (k, 3) in the hand frame (it points from the
        link towards the sample).
    """
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
    for kk in range(coarse_center.shape[0]):
        _to_hand(coarse_center[kk], rot, trans, tmp)
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
            _to_hand(cell_center[c], rot, trans, tmp)
            for s in range(ns):
                dx = tmp[0] - poses[s, 0, 3]
                dy = tmp[1] - poses[s, 1, 3]
                dz = tmp[2] - poses[s, 2, 3]
                rr = rho[s] + cell_radius[c]
                if dx * dx + dy * dy + dz * dz > rr * rr:
                    continue
                dc = sdf_world(tmp[0], tmp[1], tmp[2], poses[s], kinds[s], halves[s], radii[s])
                if dc - cell_radius[c] > tol:
                    continue
                for i in range(cell_start[c], cell_start[c + 1]):
                    _to_hand(points[i], rot, trans, ph)
                    d = sdf_world(ph[0], ph[1], ph[2], poses[s], kinds[s], halves[s], radii[s])
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
def link_poses(q, parent, origin, axis, kind, dof, ratio):
    """Forward kinematics: pose (l, 4, 4) of every link in the hand frame.

    q (n_dofs,); per link: parent (l,) index (-1 for the root), origin (l, 4, 4) joint frame
    in the parent link, axis (l, 3), kind (l,) REVOLUTE/PRISMATIC, dof (l,) index, ratio (l,).
    Links are in topological order.
    """
    n = parent.shape[0]
    out = np.empty((n, 4, 4))
    mot = np.empty((4, 4))
    tmp = np.empty((4, 4))
    for i in range(n):
        if parent[i] < 0:
            for a in range(4):
                for b in range(4):
                    out[i, a, b] = 1.0 if a == b else 0.0
            continue
        _joint_motion_into(kind[i], axis[i], ratio[i] * q[dof[i]], mot)
        _mul4_into(out[parent[i]], origin[i], tmp)
        _mul4_into(tmp, mot, out[i])
    return out


@njit(cache=True)
def shape_poses(links, shape_link, shape_local):
    """Pose (s, 4, 4) of every shape from the link poses (l, 4, 4)."""
    out = np.empty((shape_link.shape[0], 4, 4))
    for s in range(shape_link.shape[0]):
        _mul4_into(links[shape_link[s]], shape_local[s], out[s])
    return out


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
    points (k, 3), normals (k, 3) unit, dist (k,), link (k,) int
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
