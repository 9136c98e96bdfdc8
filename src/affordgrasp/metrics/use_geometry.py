"""Geometry at the use point: U_g (edge-ness) and the sharpest-edge angle (conventions: Metrics).

**U_g** (the paper's definition). Take the triangle hit at U and every triangle that
shares at least one vertex with it; express all their vertices in a frame whose origin is
U and whose z axis is the hit triangle's normal; least-squares fit the height function
``z = a x² + b x y + c y² + d x + e y + f``; the Hessian ``[[2a, b], [b, 2c]]`` has
eigenvalues λ1, λ2 and ``U_g = (λ1 - λ2)² = 4 ((a - c)² + b²)``, in m⁻².

Well-posed fits do not depend on the in-plane origin or orientation of the frame (a
translation only changes the linear terms). Degenerate fits (fewer than six independent
points, e.g. a tetrahedron's corner) use the minimum-norm least-squares solution, made
frame independent by fitting in coordinates divided by the neighbourhood's RMS radius and
in the orthonormal monomial basis ``(x², √2 x y, y², x, y, 1)``, so U_g stays invariant
to rigid motions and scales as s⁻² under a uniform scaling. Singular values of the
design matrix below 1e-10 of the largest count as zero.

Flaws, measured rather than hidden: U_g scales as 1/h² with the size h of the fitted
neighbourhood (a finely meshed edge has a large curvature, a coarsely meshed one a small
one), and over one flank of an acute wedge the opposite flank folds back under the
fitting plane, so sharp edges score lower than blunt creases. On the built-in blades it
does not separate cutting edges from other points (``studies/calibrate_use_edge.py``,
numbers in :data:`affordgrasp.tasks.TAU_UG_DEFAULT`); the edge angle below does.

**Sharpest-edge angle** (resolution independent): the smallest interior dihedral angle
(the opening angle of the solid: π on a flat face, small on a sharp convex edge) among
the convex mesh edges within ``radius`` (default 3 mm) of U; π when there is none.
Concave edges are ignored (they cannot cut). Units: rad.

Given the use normal n (outward), an edge counts only when it *faces* the use direction:
n lies within ``facing_tol`` (default 5°) of the edge's normal fan, the arc of outward
normals between its two flank normals. A point on either flank of the edge has n on the
fan's end; a face that merely ends next to the edge does not: a dagger guard's front face
beside the blade root (n along the edge, 90° off the fan) or a blade's flat beside a
narrow bevel (n half the edge angle, 7-13°, off the fan). Without a normal every edge
within ``radius`` counts, as before.

Validated on known geometries (``tests/metrics/test_use_geometry.py``): plane (U_g = 0),
finely meshed cylinder (U_g = 1/R²), sphere (U_g ≈ 0), wedges of known opening angle.
Per-mesh data (vertex-face incidence, convex edge segments and their search tree) are
computed once and cached for as long as the mesh object lives unmodified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..caching import IdentityCache
from ..errors import InputError
from ..grasp.pregrasp import dot3
from ..rays.mesh import MeshCaster, mesh_caster
from ..runtime.kernel_cache import install_package_stamp
from ..tolerances import FLAT_DIHEDRAL
from .validation import points_n3, use_normals_n3

install_package_stamp()  # before the first @njit (see kernel_cache)

EDGE_RADIUS_M = 0.003  # default search radius of the sharpest-edge angle
EDGE_FACING_TOL_RAD = float(np.radians(5.0))  # use normal off an edge's normal fan, at most
_FLAT_ANGLE = FLAT_DIHEDRAL  # dihedral angles below this (rad) are flat, not edges
_FIT_RCOND = 1e-10  # relative singular-value cutoff of the quadratic fit
_CHUNK = 2048  # use points per batched fit

# per-mesh derived data, validated by trimesh's content hash (see affordgrasp.caching)
_MESH_DATA: IdentityCache[dict] = IdentityCache()


def _mesh_cache(mesh) -> dict:
    return _MESH_DATA.get(mesh, dict, version=hash(mesh))


def _vertex_faces_csr(mesh) -> tuple[np.ndarray, np.ndarray]:
    data = _mesh_cache(mesh)
    if "vf" not in data:
        faces = np.asarray(mesh.faces, dtype=np.int64)
        flat = faces.ravel()
        order = np.argsort(flat, kind="stable")
        ptr = np.zeros(len(mesh.vertices) + 1, dtype=np.int64)
        np.add.at(ptr, flat + 1, 1)
        data["vf"] = (np.cumsum(ptr), order // 3)
    return data["vf"]


def _check_triangles(mesh, use_triangle) -> np.ndarray:
    T = np.asarray(use_triangle).reshape(-1)
    if T.size and not np.issubdtype(T.dtype, np.integer):
        if not np.all(np.equal(np.mod(T, 1), 0)):
            raise InputError(f"use_triangle must hold integer face indices, got {T[:5]}")
    T = T.astype(np.int64)
    n_faces = len(mesh.faces)
    if np.any(T < 0) or np.any(T >= n_faces):
        raise InputError(
            f"use_triangle indices must lie in [0, {n_faces}), got min {T.min()} max {T.max()}"
        )
    return T


def _frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal in-plane axes (e1, e2) of unit normals (n, 3)."""
    helper = np.zeros_like(normals)
    use_x = np.abs(normals[:, 0]) < 0.9
    helper[use_x, 0] = 1.0
    helper[~use_x, 1] = 1.0
    e1 = np.cross(normals, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(normals, e1)
    return e1, e2


def _triangle_normals(mesh, T: np.ndarray) -> np.ndarray:
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)[T]
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    norm = np.linalg.norm(n, axis=1)
    bad = norm <= 1e-300
    if np.any(bad):
        # a zero-area hit triangle has no normal: use the mesh's (area-weighted) one
        n[bad] = np.asarray(mesh.face_normals)[T[bad]]
        norm[bad] = np.maximum(np.linalg.norm(n[bad], axis=1), 1e-300)
    return n / norm[:, None]


def use_edge(mesh, use_triangle, use_point=None) -> float | np.ndarray:
    """U_g, the paper's edge-ness of the surface at the use point (conventions: Metrics), m⁻².

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object, m.
    use_triangle : int or (n,) int
        Index of the face hit at the use point.
    use_point : (3,) or (n, 3) float, optional
        Origin of the fitting frame, m; the hit triangle's centroid when omitted (the same
        result for well-posed fits).

    Returns
    -------
    float or (n,) float64 ndarray
        A float for a single query.
    """
    single = np.ndim(use_triangle) == 0
    T = _check_triangles(mesh, use_triangle)
    n = T.shape[0]
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    if use_point is None:
        origin = V[F[T]].mean(axis=1)
    else:
        origin = np.broadcast_to(points_n3(use_point, "use_point"), (n, 3))
    if n == 0:
        return np.zeros(0)
    # chunks bound the memory of the padded design matrices (a vertex of high valence,
    # e.g. the centre of a fan, pads every query of its chunk to its row count)
    value = np.concatenate(
        [
            _use_edge_chunk(mesh, T[i : i + _CHUNK], np.ascontiguousarray(origin[i : i + _CHUNK]))
            for i in range(0, n, _CHUNK)
        ]
    )
    return float(value[0]) if single else value


def _use_edge_chunk(mesh, T: np.ndarray, origin: np.ndarray) -> np.ndarray:
    n = T.shape[0]
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    ptr, face_of = _vertex_faces_csr(mesh)

    # vertices of every face incident to a vertex of the hit triangle, per query
    corner = F[T].ravel()  # (3n,)
    counts = ptr[corner + 1] - ptr[corner]
    total = int(counts.sum())
    query_of_corner = np.repeat(np.arange(n), 3)
    query = np.repeat(query_of_corner, counts)
    within = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    faces_near = face_of[np.repeat(ptr[corner], counts) + within]
    key = np.repeat(query, 3) * len(V) + F[faces_near].ravel()
    key = np.unique(key)
    q = key // len(V)
    vert = key % len(V)

    normal = _triangle_normals(mesh, T)
    e1, e2 = _frames(normal)
    d = V[vert] - origin[q]
    x = np.einsum("ij,ij->i", d, e1[q])
    y = np.einsum("ij,ij->i", d, e2[q])
    z = np.einsum("ij,ij->i", d, normal[q])
    per_query = np.bincount(q, minlength=n).astype(np.float64)
    h = np.sqrt(np.bincount(q, weights=x * x + y * y, minlength=n) / np.maximum(per_query, 1))
    h = np.where(h > 0, h, 1.0)
    x, y, z = x / h[q], y / h[q], z / h[q]
    M = np.stack([x * x, np.sqrt(2.0) * x * y, y * y, x, y, np.ones_like(x)], axis=1)

    # The fits are batched by row count, never padded: a query's SVD sees exactly its own
    # rows (LAPACK's path and blocking depend on the row count, so zero padding to the
    # batch's largest fit would change the last bits with the batch's composition), and the
    # contractions below run in a fixed order per query, so every value depends only on its
    # own query, whatever else is evaluated with it.
    order = np.argsort(q, kind="stable")
    start = np.searchsorted(q[order], np.arange(n))
    pos = np.empty_like(q)
    pos[order] = np.arange(q.size) - start[q[order]]
    rows_of = per_query.astype(np.int64)
    coef = np.zeros((n, 6))
    for rows in np.unique(rows_of[rows_of > 0]):
        members = np.nonzero(rows_of == rows)[0]
        slot = np.full(n, -1, dtype=np.int64)
        slot[members] = np.arange(members.size)
        sel = slot[q] >= 0
        Mg = np.zeros((members.size, int(rows), 6))
        zg = np.zeros((members.size, int(rows)))
        Mg[slot[q[sel]], pos[sel]] = M[sel]
        zg[slot[q[sel]], pos[sel]] = z[sel]
        U, S, Vt = np.linalg.svd(Mg, full_matrices=False)
        cutoff = S[:, :1] * _FIT_RCOND
        inv_s = np.divide(1.0, S, out=np.zeros_like(S), where=S > cutoff)
        # minimum-norm pseudo-inverse, Vt.T @ (inv_s * (U.T @ z)), summed term by term
        utz = np.zeros((members.size, S.shape[1]))
        for r in range(int(rows)):
            utz += U[:, r, :] * zg[:, r, None]
        w = inv_s * utz
        cg = np.zeros((members.size, 6))
        for j in range(S.shape[1]):
            cg += Vt[:, j, :] * w[:, j, None]
        coef[members] = cg
    a = coef[:, 0]
    b = np.sqrt(2.0) * coef[:, 1]
    c = coef[:, 2]
    return 4.0 * ((a - c) ** 2 + b**2) / h**2


# ------------------------------------------------------------------------------------
# sharpest convex edge near the use point
# ------------------------------------------------------------------------------------


MAX_EDGE_SAMPLES = 1_000_000


def _edge_index(mesh, radius: float):
    data = _mesh_cache(mesh)
    key = ("edges", radius)
    if key in data:
        return data[key]
    angles = np.asarray(mesh.face_adjacency_angles, dtype=np.float64)
    convex = np.asarray(mesh.face_adjacency_convex, dtype=bool)
    keep = convex & (angles > _FLAT_ANGLE)
    edges = np.asarray(mesh.face_adjacency_edges, dtype=np.int64)[keep]
    V = np.asarray(mesh.vertices, dtype=np.float64)
    A = V[edges[:, 0]] if len(edges) else np.zeros((0, 3))
    B = V[edges[:, 1]] if len(edges) else np.zeros((0, 3))
    interior = np.pi - angles[keep]
    # the two flank normals of each edge (for the facing test)
    pairs = np.asarray(mesh.face_adjacency, dtype=np.int64)[keep]
    FN = np.asarray(mesh.face_normals, dtype=np.float64)
    N1 = FN[pairs[:, 0]] if len(pairs) else np.zeros((0, 3))
    N2 = FN[pairs[:, 1]] if len(pairs) else np.zeros((0, 3))
    # sample every edge at a spacing <= radius: a point within `radius` of a segment is
    # then within radius + spacing / 2 of one of its samples, and long edges (a blade's
    # edge can be one segment) still sit in a compact tree
    # The spacing grows past the radius only when the edges would need more than
    # MAX_EDGE_SAMPLES samples (a mesh in the wrong units): the query radius grows with it and
    # the exact segment distance still decides, so memory stays bounded and results exact.
    length = np.linalg.norm(B - A, axis=1)
    spacing = max(radius, float(length.sum()) / MAX_EDGE_SAMPLES)
    n_samples = np.ceil(length / spacing).astype(np.int64) + 1
    owner = np.repeat(np.arange(len(edges)), n_samples)
    start = np.repeat(np.cumsum(n_samples) - n_samples, n_samples)
    t = (np.arange(owner.size) - start) / np.maximum(n_samples[owner] - 1, 1)
    samples = A[owner] + t[:, None] * (B - A)[owner]
    data[key] = (samples, owner, A, B, interior, spacing, N1, N2)
    return data[key]


def _sample_grid(mesh, radius: float, samples: np.ndarray, cell: float):
    """The edge samples bucketed in a uniform grid of cubes of side ``cell``, built once.

    Returns
    -------
    origin : (3,) int64 ndarray
        Smallest cell coordinate, less one (so that every neighbour of a sample's cell has
        non-negative coordinates).
    shape : (3,) int64 ndarray
        Cells along x, y, z, with one cell of margin on each side.
    keys : (u,) int64 ndarray
        Sorted flat indices of the cells that hold samples.
    starts : (u + 1,) int64 ndarray
        Offsets of each cell's samples in ``order``.
    order : (s,) int64 ndarray
        Sample indices, grouped by cell.
    """
    data = _mesh_cache(mesh)
    key = ("edge grid", radius, cell)
    if key not in data:
        coords = np.floor(samples / cell).astype(np.int64)
        origin = coords.min(axis=0) - 1
        shape = coords.max(axis=0) - origin + 2
        flat = np.ravel_multi_index((coords - origin).T, tuple(shape))
        order = np.argsort(flat, kind="stable")
        keys, counts = np.unique(flat[order], return_counts=True)
        starts = np.concatenate([[0], np.cumsum(counts)])
        data[key] = (origin, shape, keys, starts, order)
    return data[key]


_NEIGHBOURS = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), -1)
_NEIGHBOURS = _NEIGHBOURS.reshape(-1, 3)


def _candidate_pairs(mesh, radius, P, samples, owner, n_edges, spacing):
    """(use point, edge) pairs that may be within ``radius``, sorted, without repeats.

    Every edge with a point within ``radius`` of a use point has a sample within
    ``radius + spacing / 2`` of it (see :func:`_edge_index`), so in the use point's grid cell
    or one of its 26 neighbours when the cells are that large: the candidates include every
    edge the exact segment distance then keeps (a superset, so the result is exact). A grid
    in numpy, not a k-d tree: importing scipy.spatial costs a command ~0.4 s of CPU.
    """
    if P.shape[0] * n_edges <= _ALL_PAIRS_MAX:
        return np.repeat(np.arange(P.shape[0]), n_edges), np.tile(np.arange(n_edges), P.shape[0])
    cell = radius + 0.5 * spacing
    extent = (samples.max(axis=0) - samples.min(axis=0)) / cell + 3
    if float(np.prod(extent)) > 2.0**62:  # no flat cell index (absurd units): every edge
        return np.repeat(np.arange(P.shape[0]), n_edges), np.tile(np.arange(n_edges), P.shape[0])
    origin, shape, keys, starts, order = _sample_grid(mesh, radius, samples, cell)
    around = np.floor(P / cell).astype(np.int64)[:, None, :] + _NEIGHBOURS  # (n, 27, 3)
    rel = (around - origin).reshape(-1, 3)
    inside = np.all((rel >= 0) & (rel < shape), axis=1)
    query = np.repeat(np.arange(P.shape[0]), len(_NEIGHBOURS))[inside]
    flat = np.ravel_multi_index(rel[inside].T, tuple(shape))
    slot = np.minimum(np.searchsorted(keys, flat), len(keys) - 1)
    held = keys[slot] == flat
    query, slot = query[held], slot[held]
    lengths = starts[slot + 1] - starts[slot]
    if not lengths.sum():
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    first = np.repeat(starts[slot] - np.cumsum(lengths) + lengths, lengths)
    members = order[first + np.arange(int(lengths.sum()))]
    edge = owner[members]
    pair = np.unique(np.repeat(query, lengths) * n_edges + edge)
    return pair // n_edges, pair % n_edges


# Below this many (use point, edge) pairs the candidate edges are all edges: the exact
# segment distance decides either way, so the result is the same as through the grid
# (whose candidates include every edge within the radius), and a short run spares building
# it.
_ALL_PAIRS_MAX = 20_000


def _segment_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    AB = B - A
    denom = np.maximum(np.einsum("ij,ij->i", AB, AB), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", P - A, AB) / denom, 0.0, 1.0)
    return np.linalg.norm(P - (A + t[:, None] * AB), axis=1)


def _off_fan(n: np.ndarray, A, B, N1, N2) -> np.ndarray:
    """Angle (rad) from unit normals ``n`` to the normal fan of edges (A, B; flanks N1, N2)."""
    e = B - A
    e /= np.maximum(np.linalg.norm(e, axis=1, keepdims=True), 1e-300)
    along = np.einsum("ij,ij->i", n, e)
    perp = n - along[:, None] * e
    # within the fan's wedge (between the flank normals, seen along the edge): the angle
    # is the tilt along the edge; outside it, the angle to the nearer flank normal
    bis = N1 + N2
    half = 0.5 * np.arccos(np.clip(np.einsum("ij,ij->i", N1, N2), -1.0, 1.0))
    bis /= np.maximum(np.linalg.norm(bis, axis=1, keepdims=True), 1e-300)
    perp_len = np.linalg.norm(perp, axis=1)
    cos_perp = np.einsum("ij,ij->i", perp, bis) / np.maximum(perp_len, 1e-300)
    inside = (perp_len > 1e-12) & (cos_perp >= np.cos(half) - 1e-12)
    tilt = np.arcsin(np.clip(np.abs(along), 0.0, 1.0))
    to_flank = np.arccos(
        np.clip(np.maximum(np.einsum("ij,ij->i", n, N1), np.einsum("ij,ij->i", n, N2)), -1.0, 1.0)
    )
    return np.where(inside, tilt, to_flank)


def use_edge_angle(
    mesh,
    use_point,
    *,
    radius: float = EDGE_RADIUS_M,
    use_normal=None,
    facing_tol: float = EDGE_FACING_TOL_RAD,
) -> float | np.ndarray:
    """Smallest interior dihedral angle of a convex edge within ``radius`` of U, rad.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object, m.
    use_point : (3,) or (n, 3) float
        The use point(s), m.
    radius : float
        Search radius, m (default :data:`EDGE_RADIUS_M`).
    use_normal : (3,) or (n, 3) float, optional
        Outward unit normal(s) at U. When given, only edges that face the use direction
        count (the normal within ``facing_tol`` of the edge's normal fan; module docstring).
    facing_tol : float
        rad (default :data:`EDGE_FACING_TOL_RAD`, 5°).

    Returns
    -------
    float or (n,) float64 ndarray
        π where no (facing) convex edge is that close; a float for a single point.
    """
    single = np.ndim(use_point) == 1
    P = points_n3(use_point, "use_point")
    radius = float(radius)
    if not (np.isfinite(radius) and radius > 0):
        raise InputError(f"radius must be a positive length in metres, got {radius}")
    normals = None if use_normal is None else use_normals_n3(use_normal, P)
    out = np.full(P.shape[0], np.pi)
    samples, owner, A, B, interior, spacing, N1, N2 = _edge_index(mesh, radius)
    if owner.size and P.shape[0]:
        query, edge = _candidate_pairs(mesh, radius, P, samples, owner, len(A), spacing)
        close = np.nonzero(_segment_distance(P[query], A[edge], B[edge]) <= radius)[0]
        query, edge = query[close], edge[close]
        if normals is not None:
            facing = _off_fan(normals[query], A[edge], B[edge], N1[edge], N2[edge]) <= facing_tol
            query, edge = query[facing], edge[facing]
        np.minimum.at(out, query, interior[edge])
    return float(out[0]) if single else out


# ------------------------------------------------------------------------------------
# wedge angle at a physical scale
# ------------------------------------------------------------------------------------

WEDGE_RADIUS_M = 0.003  # default radius of the ball of the wedge angle
WEDGE_DIRECTIONS = 256  # rays per use point
WEDGE_INNER_RADIUS_M = 0.002  # radius of the inner ball (use_wedge_angle_fine)
_WEDGE_START_M = 2e-5  # rays start this far inside the surface, along -n
_WEDGE_SAME_HIT_M = 1e-7  # hits closer than this along one ray are one crossing
# use_edge_thickness: chords across the part at these depths behind U, at these offsets
# along the edge (the median of the offsets' chords: 0.15 mm of scanner noise on either
# flank moves one chord by about 0.2 mm)
EDGE_CHORD_DEPTHS_M = (0.001, 0.003)
EDGE_CHORD_OFFSETS_M = (-0.0015, 0.0, 0.0015)


def _fibonacci_sphere(k: int) -> np.ndarray:
    """(k, 3) unit vectors spread evenly over the sphere (golden-angle spiral)."""
    i = np.arange(k, dtype=np.float64) + 0.5
    z = 1.0 - 2.0 * i / k
    phi = np.pi * (1.0 + np.sqrt(5.0)) * i
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def use_wedge_angle(
    mesh,
    use_point,
    use_normal,
    *,
    radius: float = WEDGE_RADIUS_M,
    directions: int = WEDGE_DIRECTIONS,
) -> float | np.ndarray:
    """Wedge angle of the solid at U at a physical scale: 2π × the part of the ball inside.

    The ball of radius ``radius`` centred at U is split by the surface; the fraction f of its
    volume inside the solid, times 2π, is the opening angle of the solid there: π on a flat
    face, α on the apex line of a wedge of opening α (a blade's edge), less at a tip, more
    than π in a concave corner. Computed exactly along ``directions`` rays from U (a
    golden-angle spiral; each ray's inside length weighted by ρ² dρ, from its crossings
    of the surface), so it depends on the ball, not on the triangles: a rounded or noisy
    edge (0.5 mm round, 0.3 mm noise) still measures its flanks' angle, and a blade's 2 mm
    spine, whose flanks are parallel, measures about 3π T / (4 r) (67° at T = 1.5 mm, r =
    3 mm), not an edge. Needs a closed mesh. :func:`use_wedge_shape` gives the same angle
    with the shape measures of the same rays.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    use_point : (3,) or (n, 3) float
        Use points on the surface, m.
    use_normal : (3,) or (n, 3) float
        Outward unit normals there (the rays start 20 µm inside, along -n).
    radius : float
        Radius of the ball, m (default :data:`WEDGE_RADIUS_M`, 3 mm).
    directions : int
        Rays per use point (default :data:`WEDGE_DIRECTIONS`).

    Returns
    -------
    float or (n,) float64 ndarray
        rad, in [0, 2π]; a float for a single point.
    """
    shape = use_wedge_shape(mesh, use_point, use_normal, radius=radius, directions=directions)
    return float(shape.angle[0]) if np.ndim(use_point) == 1 else shape.angle


@dataclass(frozen=True)
class WedgeShape:
    """The solid in a ball at U, from one set of rays (:func:`use_wedge_shape`).

    Attributes
    ----------
    angle : (n,) float64 ndarray
        ``use_wedge_angle``: 2π × the part of the ball of radius r inside, rad.
    inner_angle : (n,) float64 ndarray
        The same in the concentric ball of radius ``inner_radius``, rad
        (``use_wedge_angle_fine``).
    span : (n,) float64 ndarray
        ``use_edge_span``: the middle eigenvalue of the inside-weighted second moment of the
        ray directions in the ball of radius r, in [0, 1/2]; dimensionless.
    edge_thickness : (n,) float64 ndarray
        ``use_edge_thickness``: the part's thickness at U extrapolated from its chords 1 and
        3 mm behind U, m (about 0 on a cutting edge, the plate's thickness at a spine; below
        0 where the part thickens faster than a wedge); NaN where no chord at a depth lies
        inside the solid, no ray is inside the ball, or the inside rays have no mean
        direction.
    """

    angle: np.ndarray
    inner_angle: np.ndarray
    span: np.ndarray
    edge_thickness: np.ndarray


def use_wedge_shape(
    mesh,
    use_point,
    use_normal,
    *,
    radius: float = WEDGE_RADIUS_M,
    inner_radius: float = WEDGE_INNER_RADIUS_M,
    directions: int = WEDGE_DIRECTIONS,
) -> WedgeShape:
    """Wedge angle at two scales, edge span and edge thickness at U, from one ray cast and
    a few chords.

    The rays of :func:`use_wedge_angle` also say *where* the solid lies around U. With w_k
    the volume-weighted inside part of ray k (direction s_k) in the ball of radius r, the
    second moment ``M = Σ w_k s_k s_kᵀ / Σ w_k`` has eigenvalues λ1 ≥ λ2 ≥ λ3 (sum 1), and
    the **edge span** is λ2. Along a wedge of any opening the inside directions fill its
    sector of azimuth and every inclination to the edge line, so the component along the
    edge is uniform on [-1, 1] and λ2 = 1/3 (λ1 ≈ 2/3 along the bisector, λ3 ≈ 0 across
    the blade); at a sharp tip (a cone, a blade's point) they lie in a narrow cone and λ2
    ≈ 0; at a thin plate's 90° corner (a cleaver's heel) in a quarter disc,
    λ2 = 1/2 - 1/π ≈ 0.18; a thin plate's straight edge (a half disc) gives 1/2 and a flat
    face 1/3. So a small wedge angle with a small span is a tip or a thin part's corner,
    not an edge to cut with. The **inner angle** is the wedge angle of the ball of radius
    ``inner_radius`` on the same rays (their crossings within it): a blade thinner than the
    3 mm ball reads as an edge over its whole flat (3π T / (4 r)), while in a 2 mm ball its
    flat reads 1.5 × larger and the crest of its cutting edge does not change.

    The **edge thickness** tells a cutting edge from the end of a thin plate (a knife's
    spine), which the balls cannot when the plate is as thin as they are wide and a scanner
    has rounded both: the flanks of an edge converge on U, a spine's stay parallel up to its
    rounded end. With e3 the direction of least inside weight (across the blade) and b the
    inside-weighted mean direction square to it (into the part), the chord of the solid
    along e3 through U + d b is measured at d = 1 and 3 mm (each the median of three
    chords, 1.5 mm apart along the edge) and extrapolated to U: t(0) = 1.5 t(1) - 0.5 t(3).
    On a wedge of opening α it is 0 (2 tan(α/2) d is linear in d), on a plate's end its
    thickness T, whatever the rounding within 1 mm of the end and whatever the triangles.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    use_point : (3,) or (n, 3) float
        Use points on the surface, m.
    use_normal : (3,) or (n, 3) float
        Outward unit normals there (the rays start 20 µm inside, along -n).
    radius : float
        Radius of the ball, m (default :data:`WEDGE_RADIUS_M`, 3 mm).
    inner_radius : float
        Radius of the inner ball, m (default :data:`WEDGE_INNER_RADIUS_M`, 2 mm).
    directions : int
        Rays per use point (default :data:`WEDGE_DIRECTIONS`).

    Returns
    -------
    WedgeShape
        (n,) arrays, also for a single point; a span of 1/3 where no ray is inside (and an
        edge thickness of NaN). The edge thickness casts 12 more rays per point (2 per
        chord).
    """
    P = points_n3(use_point, "use_point")
    N = use_normals_n3(use_normal, P)
    radius = float(radius)
    if not (np.isfinite(radius) and radius > 0):
        raise InputError(f"radius must be a positive length in metres, got {radius}")
    inner_radius = float(inner_radius)
    if not (np.isfinite(inner_radius) and inner_radius > 0):
        raise InputError(f"inner_radius must be a positive length in metres, got {inner_radius}")
    k = int(directions)
    if k < 8:
        raise InputError(f"directions must be an integer >= 8, got {directions}")
    n = P.shape[0]
    rays = mesh_caster(mesh)
    S = _fibonacci_sphere(k)
    angle, inner, span, thickness = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    outer = np.einsum("ki,kj->kij", S, S).reshape(k, 9)
    chunk = max(1, 65536 // k)
    for first in range(0, n, chunk):
        p = P[first : first + chunk]
        m = len(p)
        origins = np.repeat(p - _WEDGE_START_M * N[first : first + chunk], k, axis=0)
        dirs = np.tile(S, (m, 1))
        ray, t, leaving = _near_crossing_distances(rays, origins, dirs, max(radius, inner_radius))
        w, w_in = _ball_weights(ray, t, radius, inner_radius, leaving)
        w, w_in = w.reshape(m, k), w_in.reshape(m, k)
        angle[first : first + m] = 2.0 * np.pi * w.mean(axis=1)
        inner[first : first + m] = 2.0 * np.pi * w_in.mean(axis=1)
        total = w.sum(axis=1)
        # einsum's own loop, not a BLAS product: each point's sum runs in the same order
        # whatever else is in the batch, so the span does not depend on the batch's size
        moment = np.einsum("mk,kq->mq", w, outer).reshape(m, 3, 3)
        moment /= np.where(total > 0, total, 1.0)[:, None, None]
        moment[total <= 0] = np.eye(3) / 3.0
        span[first : first + m] = np.linalg.eigvalsh(moment)[:, 1]
        thickness[first : first + m] = _edge_thickness(rays, p, w, S, moment, total)
    return WedgeShape(angle, inner, span, thickness)


def _edge_thickness(
    rays: MeshCaster,
    P: np.ndarray,
    w: np.ndarray,
    S: np.ndarray,
    moment: np.ndarray,
    total: np.ndarray,
) -> np.ndarray:
    """(m,) ``use_edge_thickness`` of the points P from their rays' inside weights w (m, k)
    over the directions S and the weights' second moment (:func:`use_wedge_shape`), m."""
    m = len(P)
    # least inside weight: across the blade (eigh's eigenvalues are not eigvalsh's bits, so
    # the span keeps its own call)
    across = np.linalg.eigh(moment)[1][:, :, 0]
    into = np.einsum("mk,kq->mq", w, S)  # not BLAS: the same sums whatever the batch
    into -= np.einsum("ij,ij->i", into, across)[:, None] * across
    norm = np.linalg.norm(into, axis=1)
    # no direction into the part: every ray (nearly) inside, or none
    ok = (total > 0) & (norm > 1e-3 * total)
    into = np.where(ok[:, None], into / np.where(norm > 0, norm, 1.0)[:, None], 0.0)
    along = np.cross(across, into)
    depths, offsets = np.asarray(EDGE_CHORD_DEPTHS_M), np.asarray(EDGE_CHORD_OFFSETS_M)
    # chord centres (m, depth, offset, 3) and their direction, one row per chord
    centre = (
        P[:, None, None, :]
        + depths[None, :, None, None] * into[:, None, None, :]
        + offsets[None, None, :, None] * along[:, None, None, :]
    ).reshape(-1, 3)
    d = np.repeat(across, len(depths) * len(offsets), axis=0)
    n_chords = len(centre)
    # both halves of every chord in one cast: rays along +e3, then along -e3
    origins = np.concatenate([centre, centre])
    dirs = np.concatenate([d, -d])
    _, ray, locations = rays.crossings(origins, dirs)
    _, ray, t = _distinct(ray, locations, origins, dirs)
    first = np.full(2 * n_chords, np.inf)
    np.minimum.at(first, ray, t)
    # inside the solid when the ray leaves it an odd number of times
    odd = np.bincount(ray, minlength=2 * n_chords) % 2 == 1
    inside = odd[:n_chords] & odd[n_chords:]
    chord = np.where(inside, first[:n_chords] + first[n_chords:], np.inf)
    # per depth, the median of the chords inside (np.sort puts +inf last); NaN if none is
    chord = np.sort(chord.reshape(m, len(depths), len(offsets)), axis=2)
    count = np.isfinite(chord).sum(axis=2)
    low = np.take_along_axis(chord, np.maximum(count - 1, 0)[..., None] // 2, axis=2)[..., 0]
    high = np.take_along_axis(chord, (count // 2)[..., None], axis=2)[..., 0]
    t_depth = np.where(count > 0, 0.5 * (low + high), np.nan)
    d1, d3 = depths
    out = t_depth[:, 0] + (t_depth[:, 0] - t_depth[:, 1]) * d1 / (d3 - d1)
    return np.where(ok, out, np.nan)


def use_edge_span(mesh, use_point, use_normal, **kwargs) -> float | np.ndarray:
    """``use_edge_span``: λ2 of the directions inside a 3 mm ball at U (:func:`use_wedge_shape`).

    About 1/3 along an edge or a flat, 1/2 along a thin plate's straight edge, 0.18 at a
    thin plate's 90° corner, near 0 at a sharp tip.

    Parameters
    ----------
    mesh, use_point, use_normal
        As for :func:`use_wedge_shape`.
    **kwargs
        ``radius``, ``directions``.

    Returns
    -------
    float or (n,) float64 ndarray
        Dimensionless, in [0, 1/2]; a float for a single point.
    """
    shape = use_wedge_shape(mesh, use_point, use_normal, **kwargs)
    return float(shape.span[0]) if np.ndim(use_point) == 1 else shape.span


def use_edge_thickness(mesh, use_point, use_normal, **kwargs) -> float | np.ndarray:
    """``use_edge_thickness``: the part's thickness at U from chords 1 and 3 mm behind it.

    About 0 on a cutting edge (its flanks converge on U), the plate's thickness at a thin
    plate's end such as a knife's spine (its flanks parallel), rounded or not
    (:func:`use_wedge_shape`).

    Parameters
    ----------
    mesh, use_point, use_normal
        As for :func:`use_wedge_shape`.
    **kwargs
        ``radius``, ``inner_radius``, ``directions`` of :func:`use_wedge_shape` (the radius
        sets the rays that give the chords' frame, not the chords' depths, 1 and 3 mm).

    Returns
    -------
    float or (n,) float64 ndarray
        m, below 0 where the part thickens faster than a wedge behind U; NaN where no
        chord at a depth lies inside the solid, no ray is inside the ball, or the inside
        rays have no mean direction; a float for a single point.
    """
    shape = use_wedge_shape(mesh, use_point, use_normal, **kwargs)
    return float(shape.edge_thickness[0]) if np.ndim(use_point) == 1 else shape.edge_thickness


def _distinct(
    ray: np.ndarray, locations: np.ndarray, origins: np.ndarray, dirs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The crossings (ray, point) as distances along their rays ((m,) int64 index of each
    kept crossing in the input, (m,) int64 ray, (m,) float64 distance), by ray then
    distance, one per surface: a ray through an edge reports both of its faces, kept once."""
    t = np.einsum("ij,ij->i", locations - origins[ray], dirs[ray])
    order = _order_by_ray(ray, t)
    ray, t = ray[order], t[order]
    keep = np.ones(len(t), dtype=bool)
    keep[1:] = ~((ray[1:] == ray[:-1]) & (t[1:] - t[:-1] < _WEDGE_SAME_HIT_M))
    return order[keep], ray[keep], t[keep]


def _near_crossing_distances(
    rays: MeshCaster, origins: np.ndarray, dirs: np.ndarray, reach: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ray and distance (:func:`_distinct`) of at least the crossings within ``reach``, and
    whether each ray starts inside the solid ((n,) bool).

    A ray starts inside when its first crossing leaves the solid (the face's outward normal
    along the ray), as long as its crossings within ``reach`` alternate, leaving and
    entering; where they do not (a scan's surface folded on itself next to U), when it
    crosses the surface an odd number of times in all. Where every crossing alternates
    the two rules agree, and a crossing missed next to the start (a ray through an edge)
    makes the ray start outside by both; the first needs no crossing beyond the ball, so the
    rays may be followed no farther (``rays.crossings`` with a reach; a container's rays
    cross its far wall). Where crossings beyond the ball do not alternate (a missed
    crossing, or a fold, far from U), the parity can turn a ray inside out that the first
    crossing does not.
    """
    tri, ray, locations = rays.crossings(origins, dirs, reach)
    kept, ray, t = _distinct(ray, locations, origins, dirs)
    leaves = np.einsum("ij,ij->i", rays.normals[tri[kept]], dirs[ray]) > 0
    starts_inside = np.zeros(len(origins), dtype=bool)
    first = np.ones(len(ray), dtype=bool)
    first[1:] = ray[1:] != ray[:-1]
    starts_inside[ray[first]] = leaves[first]
    # two crossings in a row within reach both leaving, or both entering
    folded = (~first[1:]) & (leaves[1:] == leaves[:-1]) & (t[1:] < reach)
    odd = np.unique(ray[1:][folded])
    if len(odd):
        _, sub, sub_locations = rays.crossings(origins[odd], dirs[odd])
        _, sub, _ = _distinct(sub, sub_locations, origins[odd], dirs[odd])
        starts_inside[odd] = np.bincount(sub, minlength=len(odd)) % 2 == 1
    return ray, t, starts_inside


def _order_by_ray(ray: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The order of the crossings by ray, then by distance (``np.lexsort((t, ray))``).

    The hits of one ray come in the order the ray met them, so a stable sort by ray alone
    is nearly always that order already (a few times faster than the two-key sort); if
    some ray's distances do not increase, the two-key sort decides.
    """
    order = np.argsort(ray, kind="stable")
    ray_sorted, t_sorted = ray[order], t[order]
    if np.isnan(t).any() or np.any(
        (ray_sorted[1:] == ray_sorted[:-1]) & (t_sorted[1:] < t_sorted[:-1])
    ):
        return np.lexsort((t, ray))
    return order


def _ball_weights(
    ray: np.ndarray, t: np.ndarray, radius: float, inner_radius: float, starts_inside: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Volume-weighted inside part of [0, radius] and of [0, inner_radius] of each ray.

    ``ray`` sorted, ``t`` sorted within each ray (crossing distances, m, at least every one
    within the radius); ``starts_inside`` (n_rays,) bool: the ray's first crossing leaves
    the solid (so a crossing missed next to the start does not turn the ray inside out:
    the next one, entering, says it starts outside). From inside, with crossings
    t1 < t2 < ... within the radius (c = (t / r)³), the inside segments are [0, t1],
    [t2, t3], ...: Σ_k (-1)^k c_(k+1), + 1 after an even number of crossings; from outside,
    the complement. Summed by a compiled pass over the crossings.
    """
    return _ball_weights_kernel(
        ray, t, (t / radius) ** 3, (t / inner_radius) ** 3, radius, inner_radius, starts_inside
    )


@njit(cache=True)
def _ball_weights_kernel(ray, t, cube_out, cube_in, radius, inner_radius, starts_inside):
    """:func:`_ball_weights`' sums, in the order ``np.bincount`` would add them (tests compare
    the two, bit for bit); ``cube_out``, ``cube_in``: ``(t / radius) ** 3`` and
    ``(t / inner_radius) ** 3`` (numpy's power)."""
    n = starts_inside.shape[0]
    acc_out = np.zeros(n)
    acc_in = np.zeros(n)
    k_out = np.zeros(n, dtype=np.int64)
    k_in = np.zeros(n, dtype=np.int64)
    for a in range(ray.shape[0]):
        r = ray[a]
        if t[a] < radius:
            acc_out[r] += cube_out[a] if k_out[r] % 2 == 0 else -cube_out[a]
            k_out[r] += 1
        if t[a] < inner_radius:
            acc_in[r] += cube_in[a] if k_in[r] % 2 == 0 else -cube_in[a]
            k_in[r] += 1
    w = np.empty(n)
    w_in = np.empty(n)
    for r in range(n):
        v = acc_out[r] + (1.0 if k_out[r] % 2 == 0 else 0.0)
        w[r] = v if starts_inside[r] else 1.0 - v
        v = acc_in[r] + (1.0 if k_in[r] % 2 == 0 else 0.0)
        w_in[r] = v if starts_inside[r] else 1.0 - v
    return w, w_in


def _use_point_groups(group, n_uses: int, n_grasps: int) -> np.ndarray:
    """(n,) int64: the grasp of each use point (default: use point i is grasp i), checked."""
    group = np.arange(n_uses) if group is None else np.asarray(group, dtype=np.int64).reshape(-1)
    if group.shape[0] != n_uses:
        raise InputError(f"group has {group.shape[0]} rows, expected one per use point ({n_uses})")
    if n_uses and (group.min() < 0 or group.max() >= n_grasps):
        raise InputError(
            f"group indices must lie in [0, {n_grasps}), got {group.min()}..{group.max()}"
        )
    return group


def use_clearance(contact_points, offsets, use_point, group=None) -> np.ndarray:
    """Smallest distance from a grasp's contacts to its use point (``use_clearance``), m.

    A hand that touches the working part near U (fingers on a blade) has a small clearance;
    tasks whose use point is a working part ask for at least a hand's width.

    Parameters
    ----------
    contact_points : (k, 3) float
        Contacts of all grasps, stacked, m.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.
    use_point : (n, 3) float
        Use points, m.
    group : (n,) int, optional
        The grasp of each use point (default: use point i belongs to grasp i, n = g).

    Returns
    -------
    (n,) float64 ndarray
        m; +inf for a grasp without contacts, NaN for a NaN use point.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    g = len(offsets) - 1
    group = _use_point_groups(group, len(U), g)
    counts = np.diff(offsets)
    kmax = int(counts.max()) if g else 0
    out = np.full(len(U), np.inf)
    if kmax == 0 or len(U) == 0:
        return np.where(np.isnan(U).any(axis=1), np.nan, out)
    padded = np.full((g, kmax, 3), np.nan)
    owner = np.repeat(np.arange(g), counts)
    padded[owner, np.arange(len(C)) - offsets[owner]] = C
    for first in range(0, len(U), 65536):
        sl = slice(first, first + 65536)
        d = np.linalg.norm(padded[group[sl]] - U[sl, None, :], axis=2)
        has = ~np.isnan(d)
        out[sl] = np.where(has.any(axis=1), np.min(np.where(has, d, np.inf), axis=1), np.inf)
    return np.where(np.isnan(U).any(axis=1), np.nan, out)


def long_axis(inertia) -> np.ndarray:
    """The object's long axis: the principal axis of least moment of inertia.

    Parameters
    ----------
    inertia : (3, 3) float
        Inertia tensor about the centre of mass, kg·m² (any density scale).

    Returns
    -------
    (3,) float64 ndarray
        Unit vector (its sign is arbitrary; :func:`contact_reach` does not depend on it).
    """
    inertia = np.asarray(inertia, dtype=np.float64).reshape(3, 3)
    _, vectors = np.linalg.eigh(0.5 * (inertia + inertia.T))
    return vectors[:, 0]


def contact_reach(
    contact_points, offsets, use_point, center_of_mass, axis, group=None
) -> np.ndarray:
    """How far the hand reaches past the centre of mass towards U (``contact_reach``).

    Along the object's long axis e (:func:`long_axis`), with u = (U - c) · e the use point's
    offset from the centre of mass c, the largest (p - c) · e · sign(u) over a grasp's
    contacts p, divided by |u|: 0 when no contact lies past the centre of mass on U's side,
    1 when one reaches as far as U does, negative when every contact lies behind the centre
    of mass. A knife held by its handle and cutting with its blade, or a hammer with a steel
    head held by its handle and striking with its head, reads small or negative; a finger on
    an axe's head or a knife's blade reads near 1. It needs no part labels, so it holds on a
    scanned mesh.

    Parameters
    ----------
    contact_points : (k, 3) float
        Contacts of all grasps, stacked, m.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.
    use_point : (n, 3) float
        Use points, m.
    center_of_mass : (3,) float
        m.
    axis : (3,) float
        The long axis (any sign).
    group : (n,) int, optional
        The grasp of each use point (default: use point i belongs to grasp i, n = g).

    Returns
    -------
    (n,) float64 ndarray
        Dimensionless; -inf for a grasp without contacts, ±inf when U lies level with the
        centre of mass (u = 0) and a contact lies past it (+) or none does (-), NaN for a
        NaN use point.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(center_of_mass, dtype=np.float64).reshape(3)
    e = np.asarray(axis, dtype=np.float64).reshape(3)
    norm = float(np.linalg.norm(e))
    if not (np.isfinite(norm) and norm > 0):
        raise InputError(f"axis must be a non-zero finite vector, got {e.tolist()}")
    e = e / norm
    g = len(offsets) - 1
    if g < 0 or offsets[-1] != len(C):
        raise InputError(
            f"offsets must end at the number of contacts ({len(C)}), got {offsets.tolist()}"
        )
    group = _use_point_groups(group, len(U), g)
    counts = np.diff(offsets)
    hi = np.full(g, -np.inf)
    lo = np.full(g, np.inf)
    if len(C):
        owner = np.repeat(np.arange(g), counts)
        along = dot3(C - c, e)
        np.maximum.at(hi, owner, along)
        np.minimum.at(lo, owner, along)
    u = dot3(U - c, e)
    reach = np.where(u >= 0, hi[group], -lo[group])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(u != 0, reach / np.abs(u), np.where(reach > 0, np.inf, -np.inf))
    return np.where(np.isnan(U).any(axis=1), np.nan, out)


_THICKNESS_START_M = 1e-4  # the rays start this far inside, along -n


def contact_thickness(mesh, contact_points, contact_normals, offsets) -> np.ndarray:
    """Thinnest part a grasp touches (``contact_thickness``), m.

    At each contact, the length of the chord through the solid along the inward normal (the
    first exit of a ray from just inside, along -n); per grasp the smallest. A blade, 1-5 mm
    thick, is thin everywhere; a handle or a hammer's head is not: tasks whose working part
    is a blade keep the hand off it with a minimum thickness.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    contact_points, contact_normals : (k, 3) float
        Contacts of all grasps, stacked, m; the object's outward unit normals.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.

    Returns
    -------
    (g,) float64 ndarray
        m; +inf for a grasp without contacts; a contact whose ray finds no exit (grazing an
        edge) counts as 0.
    """
    return contact_thickness_and_width(
        mesh, contact_points, contact_normals, offsets, directions=0
    )[0]


WIDTH_DIRECTIONS = 6  # directions across the part, per contact, of contact_width


def _first_exit(mesh, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(k,) distance from each origin to the first surface along its direction, m; inf if none."""
    out = np.full(len(origins), np.inf)
    if len(origins) == 0:
        return out
    locations, ray, _ = mesh_caster(mesh).intersects_location(origins, dirs, multiple_hits=False)
    ray = np.asarray(ray, dtype=np.int64)
    if len(ray):
        out[ray] = np.linalg.norm(np.asarray(locations, dtype=np.float64) - origins[ray], axis=1)
    return out


def contact_width(
    mesh, contact_points, contact_normals, offsets, directions: int = WIDTH_DIRECTIONS
) -> np.ndarray:
    """Narrowest part a grasp touches, measured across the part (``contact_width``), m.

    At each contact, the chord through the solid along the inward normal (as
    :func:`contact_thickness`), then from that chord's midpoint, the chords across the part
    along ``directions`` directions perpendicular to the normal (half-turn evenly spaced);
    the contact's width is the smallest of them, and a grasp's the smallest over its
    contacts. A finger on a handle reads the handle's section (12 mm and more); a finger on
    a blade's spine reads the blade's thickness (2-5 mm), though its chord along the normal
    runs down the blade's height: the thickness test alone lets a hand hold a cleaver by its
    spine.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`); closed.
    contact_points, contact_normals : (k, 3) float
        Contacts of all grasps, stacked, m; the object's outward unit normals.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.
    directions : int
        Directions across the part per contact (default :data:`WIDTH_DIRECTIONS`).

    Returns
    -------
    (g,) float64 ndarray
        m; +inf for a grasp without contacts; a contact whose normal ray finds no exit
        (grazing an edge) counts as 0.
    """
    if int(directions) < 1:
        raise InputError(f"directions must be a positive integer, got {directions}")
    return contact_thickness_and_width(
        mesh, contact_points, contact_normals, offsets, directions=directions
    )[1]


def contact_thickness_and_width(
    mesh, contact_points, contact_normals, offsets, directions: int = WIDTH_DIRECTIONS
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`contact_thickness` and :func:`contact_width` from one set of rays.

    The chord along the inward normal is both the thickness and the width's first chord;
    the chords across the part, both halves of every direction for every contact, are cast
    in one call.

    Parameters
    ----------
    mesh, contact_points, contact_normals, offsets
        As for :func:`contact_width`.
    directions : int
        Directions across the part per contact (0: the thickness alone; the width is then
        the chord along the normal).

    Returns
    -------
    thickness, width : (g,) float64 ndarray
        m.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    N = np.asarray(contact_normals, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    k = int(directions)
    if k < 0:
        raise InputError(f"directions must be a non-negative integer, got {directions}")
    g = len(offsets) - 1
    thickness = np.full(g, np.inf)
    out = np.full(g, np.inf)
    if len(C) == 0:
        return thickness, out
    origins = C - _THICKNESS_START_M * N
    along = _first_exit(mesh, origins, -N)
    chord_n = np.where(np.isfinite(along), along + _THICKNESS_START_M, 0.0)
    width = chord_n.copy()
    inside = np.isfinite(along)
    m = int(inside.sum())
    if m and k:
        centre = origins[inside] - 0.5 * along[inside, None] * N[inside]
        e1, e2 = _frames(N[inside])
        # rows: direction a's + half, then its - half, each over the m contacts
        d = np.stack(
            [np.cos(angle) * e1 + np.sin(angle) * e2 for angle in np.arange(k) * np.pi / k]
        )
        dirs = np.stack([d, -d], axis=1).reshape(-1, 3)
        exits = _first_exit(mesh, np.tile(centre, (2 * k, 1)), dirs).reshape(k, 2, m)
        for a in range(k):
            width[inside] = np.minimum(width[inside], exits[a, 0] + exits[a, 1])
    counts = np.diff(offsets)
    owner = np.repeat(np.arange(g), counts)
    np.minimum.at(thickness, owner, chord_n)
    np.minimum.at(out, owner, width)
    return thickness, out


def use_lever_ratio(use_point, center_of_mass, wrist_point, wrist_axis) -> np.ndarray:
    """How far U is from the wrist axis, relative to the centre of mass (``use_lever_ratio``).

    With r_U and r_C the offsets of U and of the centre of mass from the wrist axis (the line
    through the palm centre along the approach direction; the parts perpendicular to it), the
    ratio is |r_U|² / (r_C · r_U): U's lever over the centre of mass's lever projected on U's
    side. A swing about that axis strikes with its massive end when the ratio is at least 1
    (the mass lies between the axis and U) and small (the mass near U: at most 2 puts it in
    the outer half of the lever). A hammer held by its handle, whose steel head holds the
    centre of mass, strikes with the head (ratio a little over 1); striking with the handle's
    end beyond the hand puts the mass on the other side of the axis (negative), and holding
    the head to strike with the handle puts the mass near the axis (large).

    Parameters
    ----------
    use_point : (n, 3) float
        m.
    center_of_mass : (3,) float
        m.
    wrist_point : (n, 3) float
        Palm centres, m.
    wrist_axis : (n, 3) float
        Unit approach directions.

    Returns
    -------
    (n,) float64 ndarray
        Dimensionless; -inf when the centre of mass is on the axis or on the other side of it
        from U (r_C · r_U <= 0); NaN where U is NaN (no use point).
    """
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    W = np.asarray(wrist_point, dtype=np.float64).reshape(-1, 3)
    A = np.asarray(wrist_axis, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(center_of_mass, dtype=np.float64).reshape(1, 3)

    def off_axis(P: np.ndarray) -> np.ndarray:
        d = P - W
        return d - np.einsum("ij,ij->i", d, A)[:, None] * A

    r_u = off_axis(U)
    r_c = off_axis(np.broadcast_to(c, U.shape))
    along = np.einsum("ij,ij->i", r_c, r_u)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.einsum("ij,ij->i", r_u, r_u) / along
    return np.where(along > 0, ratio, np.where(np.isnan(along), np.nan, -np.inf))
