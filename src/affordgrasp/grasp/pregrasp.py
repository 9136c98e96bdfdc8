"""Decoding the pregrasp p0 and the use direction d (conventions: Pregrasp, paper §IV-B).

Spherical coding shared by p0 and d: azimuth = π·u1, cos(polar) = u2, so uniform (u1, u2) in
[-1, 1]^2 gives directions uniform on the sphere::

    direction = (sin θ cos φ, sin θ sin φ, cos θ),  φ = π u1,  cos θ = u2

Hand frame from p0 = (u1, u2, u3, u4, u5, s):

* z (approach) = direction(u1, u2);
* reference x0 = normalise(e × z) with e = +Z of the object frame, or +X when |z·Z| > 0.99;
  y0 = z × x0; then x, y = x0, y0 turned by the roll π·u3 about z (right-hand rule);
* the approach line passes through the point whose x/y coordinates are the centre of the
  object's extent seen along z (its vertices projected on x and y) plus (u4, u5) times the
  half-extents of that projection;
* the palm starts on that line so that the whole open hand lies behind the plane tangent to
  the object's bounding sphere (centre: bounding-box centre), i.e. outside the object;
* s ∈ [0, 1] sets the hand's pregrasp DOF (Barrett: spread = 180°·s).

The use point U = DM(d, O) is the farthest intersection of the ray from the centre of mass
along direction(d) with the surface, with the outward normal of the triangle hit. Where that
ray meets no surface (from a hollow object's cavity out through its opening), U is the
first hit of the same line coming back from outside along -d, on the far side of the centre
of mass: every line through the centre of mass of a container meets its wall or its base,
so every d has a use point. (Equivalently, in both cases: the hit of the line through the
centre of mass along d that lies farthest along +d.)

Use directions for searches (:func:`surface_use_directions`) are drawn so that the use
points cover the surface by area: a uniform d reaches a knife's blade, a thin part seen
edge-on from the centre of mass in the handle, in a few per mille of draws.
"""

from __future__ import annotations

import hashlib
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..rays.mesh import mesh_caster

if TYPE_CHECKING:
    import trimesh


def spherical_direction(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """Unit directions from normalised spherical coordinates.

    Parameters
    ----------
    u1, u2 : (n,) float ndarray
        Coordinates in [-1, 1].

    Returns
    -------
    (n, 3) float64 ndarray
        Unit vectors.
    """
    phi = np.pi * np.asarray(u1, dtype=np.float64)
    cos_t = np.clip(np.asarray(u2, dtype=np.float64), -1.0, 1.0)
    sin_t = np.sqrt(1.0 - cos_t**2)
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=-1)


def validate_pregrasps(p0) -> np.ndarray:
    """p0 as an (n, 6) float64 array inside [-1, 1]^5 × [0, 1], or a clear InputError.

    Parameters
    ----------
    p0 : array_like
        One (6,) pregrasp or (n, 6).

    Returns
    -------
    (n, 6) float64 ndarray
    """
    p0 = np.atleast_2d(np.asarray(p0, dtype=np.float64))
    if p0.ndim != 2 or p0.shape[1] != 6:
        raise InputError(f"pregrasps must have shape (n, 6), got {p0.shape}")
    bad = ~np.isfinite(p0)
    bad[:, :5] |= np.abs(np.nan_to_num(p0[:, :5])) > 1.0
    bad[:, 5] |= (p0[:, 5] < 0) | (p0[:, 5] > 1)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(
            f"pregrasp row {row}, parameter {col} is {float(p0[row, col])}: pregrasps must "
            "be finite and lie in [-1, 1]^5 x [0, 1]"
        )
    return p0


def validate_use_directions(d) -> np.ndarray:
    """Use directions as an (n, 2) float64 array inside [-1, 1]^2, or a clear InputError.

    Parameters
    ----------
    d : array_like
        One (2,) use direction or (n, 2).

    Returns
    -------
    (n, 2) float64 ndarray
    """
    d = np.atleast_2d(np.asarray(d, dtype=np.float64))
    if d.ndim != 2 or d.shape[1] != 2:
        raise InputError(f"use directions must have shape (n, 2), got {d.shape}")
    bad = ~np.isfinite(d) | (np.abs(np.nan_to_num(d)) > 1.0)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(
            f"use direction row {row}, parameter {col} is {float(d[row, col])}: use "
            "directions must be finite and lie in [-1, 1]^2"
        )
    return d


def hand_rotations(p0: np.ndarray) -> np.ndarray:
    """Hand orientations in the object frame.

    Parameters
    ----------
    p0 : (n, 6) float64 ndarray
        Pregrasps.

    Returns
    -------
    (n, 3, 3) float64 ndarray
        Columns x, y, z (approach) of the hand frame.
    """
    z = spherical_direction(p0[:, 0], p0[:, 1])
    ref = np.where(np.abs(z[:, 2:3]) > 0.99, [[1.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]])
    x0 = np.cross(ref, z)
    x0 /= np.linalg.norm(x0, axis=1, keepdims=True)
    y0 = np.cross(z, x0)
    roll = np.pi * p0[:, 2:3]
    x = np.cos(roll) * x0 + np.sin(roll) * y0
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products over the last axis (length 3), broadcast, term by term in a fixed order.

    ``a @ b`` goes through BLAS, whose blocking depends on the number of rows, so a row's last
    bit would depend on the batch it is evaluated in; this does not.

    Parameters
    ----------
    a, b : (..., 3) float ndarray
        Broadcast against each other.

    Returns
    -------
    (...) float64 ndarray
    """
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def start_poses(
    p0: np.ndarray, hull_vertices: np.ndarray, hand_reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """Start poses of the hand and the approach length to try.

    Parameters
    ----------
    p0 : (n, 6) float64 ndarray
        Pregrasps.
    hull_vertices : (v, 3) float64 ndarray
        The object's convex-hull vertices, m (the extent seen along any direction is that of
        its hull).
    hand_reach : float
        How far the open hand extends in front of the palm face, m.

    Returns
    -------
    poses : (n, 4, 4) float64 ndarray
        Hand → object, m.
    lengths : (n,) float64 ndarray
        Approach length, m.
    """
    rot = hand_rotations(p0)
    lo = hull_vertices.min(axis=0)
    hi = hull_vertices.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.max(np.linalg.norm(hull_vertices - centre, axis=1)))
    # The object's extent along each hand's x and y axes: every hull vertex projected, in a
    # compiled loop (kernels.hull_extents: the same bits as numpy's term-by-term sum, which
    # a matrix product would not give: a sample's start pose must not depend on the batch
    # it is simulated in).
    from .kernels import hull_extents

    ext = hull_extents(
        *(np.ascontiguousarray(hull_vertices[:, k], dtype=np.float64) for k in range(3)),
        np.ascontiguousarray(rot, dtype=np.float64),
    )
    xlo, xhi, ylo, yhi = ext[:, 0], ext[:, 1], ext[:, 2], ext[:, 3]
    x = (xlo + xhi) / 2 + p0[:, 3] * (xhi - xlo) / 2
    y = (ylo + yhi) / 2 + p0[:, 4] * (yhi - ylo) / 2
    z = dot3(rot[:, :, 2], centre) - radius - hand_reach
    origin = rot[:, :, 0] * x[:, None] + rot[:, :, 1] * y[:, None] + rot[:, :, 2] * z[:, None]
    poses = np.zeros((len(p0), 4, 4))
    poses[:, :3, :3] = rot
    poses[:, :3, 3] = origin
    poses[:, 3, 3] = 1.0
    travel = np.full(len(p0), 2 * radius + hand_reach + 1e-3)
    return poses, travel


def use_points(
    mesh: trimesh.Trimesh, center: np.ndarray, use_dir: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """DM(d, O): farthest surface hit along each use direction from the centre of mass.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    center : (3,) float64 ndarray
        Centre of mass, m.
    use_dir : (n, 2) float64 ndarray
        Use directions in [-1, 1]^2.

    Returns
    -------
    points : (n, 3) float64 ndarray
        m.
    normals : (n, 3) float64 ndarray
        Outward unit normals.
    triangles : (n,) int64 ndarray
        Face indices. Rows whose ray leaves the object without a hit (possible from a hollow
        object's cavity) are NaN with triangle -1.
    """
    d = spherical_direction(use_dir[:, 0], use_dir[:, 1])
    n = len(d)
    points = np.full((n, 3), np.nan)
    normals = np.full((n, 3), np.nan)
    tris = np.full(n, -1, dtype=np.int64)
    if n == 0:
        return points, normals, tris
    origins = np.repeat(np.asarray(center, dtype=np.float64)[None], n, axis=0)
    rays = mesh_caster(mesh)
    _, ray_idx, tri_idx = rays.intersects_location(origins, d, multiple_hits=True)
    o, dirs = origins[ray_idx], d[ray_idx]
    t = _plane_hits(mesh, tri_idx, o, dirs, -np.inf)
    keep = _first_per_ray(ray_idx, -t)  # per ray, the farthest
    r = ray_idx[keep]
    ahead = t[keep] > 0
    r, keep = r[ahead], keep[ahead]
    points[r] = o[keep] + t[keep, None] * dirs[keep]
    normals[r] = np.asarray(mesh.face_normals)[tri_idx[keep]]
    tris[r] = tri_idx[keep]
    missed = np.flatnonzero(tris < 0)
    if missed.size:
        # back from outside along -d: the line's hit farthest along +d, behind the centre
        V = np.asarray(mesh.vertices, dtype=np.float64)
        reach = float(np.linalg.norm(V - origins[0], axis=1).max()) * 1.5 + 1e-3
        o2 = origins[missed] + reach * d[missed]
        _, ray2, tri2 = rays.intersects_location(o2, -d[missed], multiple_hits=True)
        if len(tri2):
            back = -d[missed][ray2]
            t2 = _plane_hits(mesh, tri2, o2[ray2], back, np.inf)
            pick = _first_per_ray(ray2, t2)  # per ray, the nearest
            rows = missed[ray2[pick]]
            points[rows] = o2[ray2[pick]] + t2[pick, None] * back[pick]
            normals[rows] = np.asarray(mesh.face_normals)[tri2[pick]]
            tris[rows] = tri2[pick]
    return points, normals, tris


def _plane_hits(mesh, tri_idx: np.ndarray, o: np.ndarray, d: np.ndarray, miss: float) -> np.ndarray:
    """Ray parameter of each hit, in float64 on the plane of the triangle the (float32) ray
    engine reported; ``miss`` for a ray parallel to it."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)[tri_idx]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    denom = np.einsum("ij,ij->i", nrm, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("ij,ij->i", nrm, tri[:, 0] - o) / denom
    return np.where(np.isfinite(t), t, miss)


def _first_per_ray(ray: np.ndarray, key: np.ndarray) -> np.ndarray:
    """Index of the hit of least ``key`` on each ray that has one."""
    order = np.lexsort((key, ray))
    first = np.ones(len(order), dtype=bool)
    first[1:] = ray[order][1:] != ray[order][:-1]
    return order[first]


def surface_use_directions(
    mesh: trimesh.Trimesh, center: np.ndarray, n: int, seed: int
) -> np.ndarray:
    """Use directions d towards points drawn uniformly by area on the surface.

    DM(d, O) of such a d is the drawn point or a point farther along the same line, so the
    use points reach every part of the surface in proportion to its area (a knife's blade,
    a hammer's striking face) instead of in proportion to the solid angle it subtends from
    the centre of mass. The learning input stays d.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (``vertices``, ``faces``).
    center : (3,) float64 ndarray
        Centre of mass, m.
    n : int
        How many directions.
    seed : int
        Same seed, same directions.

    Returns
    -------
    (n, 2) float64 ndarray
        Use directions in [-1, 1]^2 (the spherical coding of the module docstring).
    """
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x5EED]))
    tri = V[F]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    face = rng.choice(len(F), size=int(n), p=area / area.sum())
    a, b = rng.random((2, int(n)))
    flip = a + b > 1
    a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
    T = tri[face]
    P = T[:, 0] + a[:, None] * (T[:, 1] - T[:, 0]) + b[:, None] * (T[:, 2] - T[:, 0])
    return directions_towards(center, P)


def directions_towards(center, points) -> np.ndarray:
    """The use directions d whose use rays from ``center`` pass through ``points``.

    DM(d, O) is then the point or the surface's last hit farther along the same line (the
    inverse of :func:`spherical_direction`).

    Parameters
    ----------
    center : (3,) array_like of float
        Centre of mass, m.
    points : (n, 3) array_like of float
        m.

    Returns
    -------
    (n, 2) float64 ndarray
        Use directions in [-1, 1]^2.
    """
    d = np.asarray(points, dtype=np.float64).reshape(-1, 3) - np.asarray(
        center, dtype=np.float64
    ).reshape(3)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return np.stack([np.arctan2(d[:, 1], d[:, 0]) / np.pi, np.clip(d[:, 2], -1, 1)], axis=1)


# A planner's candidates (``plan``) draw the approach line's offsets (u4, u5) in
# [-PLAN_OFFSET_RANGE, PLAN_OFFSET_RANGE]² rather than the dataset's [-1, 1]²: uniform offsets
# put most approach lines near or past the object's outline (on 26 objects the models never
# saw, 11 % of uniform grasps with |(u4, u5)| < 0.4 are viable, 3 % of those beyond 0.8).
# Chosen on validation objects (variants 7 and 8 of the families, 6 seeds of 64 candidates
# each; docs/learning.md) among 0.25, 0.35, 0.5, 0.7 and 1. Here, beside the draw it scales,
# so that the command line's help reads it without importing the learning modules.
PLAN_OFFSET_RANGE = 0.25
# Candidates ``plan`` draws by default: with the fused views, the choice among 256 was viable
# on 0.88 of unseen objects' decisions (six seeds; 0.932 of nine with the refined candidates
# and the robust check below), among 64 on 0.73 (three seeds, before either); more than 256
# did not help on the validation objects. Each candidate past the 64th costs a simulation on
# the fused surface and one on the object, about 2 ms (docs/learning.md).
PLAN_CANDIDATES = 256
# With the fused views, ``plan`` simulates its first PLAN_ROBUST_CHECK candidates on the fused
# surface again under small perturbations and chooses the one whose copies keep the widest ε
# (its lower quartile): the widest ε there is sometimes a contact that only grazes the fused
# surface (a distal link touching a surface a millimetre outside the true one), or a margin
# too thin to survive the surface's errors. Chosen on validation objects (variants 7-10, 195
# decisions, with the neighbours below) among 2, 4 and 8 checked candidates, 12 or 24 copies,
# and the share of copies viable, the lower quartile or the median of their ε
# (docs/learning.md).
PLAN_ROBUST_CHECK = 8

# With the fused views, ``plan`` then draws PLAN_REFINE_NEIGHBOURS pregrasps near each of its
# first PLAN_REFINE candidates (``search.cem.nearby_inputs``, σ = PLAN_REFINE_SIGMA) and
# simulates them on the fused surface too: a grasp that is viable by a thin margin has
# neighbours with a wider one. Chosen on validation objects (variants 7-10, 195 decisions;
# docs/learning.md).
PLAN_REFINE = 8
PLAN_REFINE_NEIGHBOURS = 16
PLAN_REFINE_SIGMA = 0.04
# A task that reads the use point: ``plan`` pairs every candidate's grasp with PLAN_USES use
# points drawn by area on the fused surface and keeps its best (search.pairs).
PLAN_USES = 1000
# With the learned scorer (``plan --model learned``), its first PLAN_VERIFY candidates are
# simulated on the fused surface and the viable one with the widest ε there goes first:
# chosen on validation objects among 0, 4, 8 and 16 (docs/learning.md).
PLAN_VERIFY = 16
# ``plan`` aims its views from a pose estimate this far off (vision.camera.pose_error_transform):
# the robot believes the object is 1 cm and 5° away from where it is, a typical estimate from
# a fixed camera or a model registration (docs/learning.md).
POSE_ERROR_M = 0.01
POSE_ERROR_DEG = 5.0

SAMPLE_BLOCK = 1024

# How a multi-object run draws its samples (``generate --streams``): "per-object", each
# object its own stream (:func:`object_stream_seed`), or "shared", every object the run's
# stream (sample i is the same pregrasp on every object; the only choice before streams were
# recorded in the manifest).
SAMPLE_STREAMS = ("per-object", "shared")


def object_stream_seed(seed: int, name: str) -> int:
    """The seed of an object's own sample stream in a run of seed ``seed``.

    A learning dataset needs it: with one stream shared by every object, sample i is the
    same pregrasp and use direction on every object, so a run of 390 objects × 200 samples
    holds 200 distinct inputs. A model then learns those 200 poses' labels, and objects held
    out of the same run (the same 200 poses) score it far above objects of another run
    (docs/learning.md). Keyed by the object's name, not its place in the run: the same object
    gets the same samples in any run of that seed.

    Parameters
    ----------
    seed : int
        The run's seed (>= 0).
    name : str
        The object's name (``knife:3``, ``knife:3~scan``, a mesh's name).

    Returns
    -------
    int
        In [0, 2**63): the seed :func:`sample_inputs` draws the object's samples from (and
        the rows' ``seed`` column).
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    digest = hashlib.sha256(f"affordgrasp-samples:{int(seed)}:{name}".encode()).digest()
    return int.from_bytes(digest[:8], "little") & ((1 << 63) - 1)


def sample_inputs(seed: int, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    """Uniform pregrasps and use directions for samples start..stop-1.

    Sample i depends only on (seed, i): draws come in fixed blocks of SAMPLE_BLOCK samples,
    each block from its own ``SeedSequence([seed, block])``, so any split of a run into
    shards or workers produces the same samples. A dataset's objects each draw from their
    own seed (:func:`object_stream_seed`) unless it was generated with shared streams.

    Parameters
    ----------
    seed : int
        The run's seed.
    start, stop : int
        Sample range.

    Returns
    -------
    p0 : (n, 6) float64 ndarray
    use_dir : (n, 2) float64 ndarray
    """
    if seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed}")
    if not 0 <= start <= stop:
        raise InputError(f"bad sample range [{start}, {stop})")
    p0 = np.empty((stop - start, 6))
    d = np.empty((stop - start, 2))
    first, last = start // SAMPLE_BLOCK, (stop - 1) // SAMPLE_BLOCK if stop > start else -1
    for block in range(first, last + 1):
        rng = np.random.default_rng(np.random.SeedSequence([seed, block]))
        u = rng.random((SAMPLE_BLOCK, 8))
        lo = max(start, block * SAMPLE_BLOCK)
        hi = min(stop, (block + 1) * SAMPLE_BLOCK)
        rows = u[lo - block * SAMPLE_BLOCK : hi - block * SAMPLE_BLOCK]
        p0[lo - start : hi - start, :5] = 2.0 * rows[:, :5] - 1.0
        p0[lo - start : hi - start, 5] = rows[:, 5]
        d[lo - start : hi - start] = 2.0 * rows[:, 6:8] - 1.0
    return p0, d
