"""Edges at U on the mesh's triangles: U_g and the sharpest-edge angle.

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


Validated on known geometries (``tests/metrics/test_edges.py``): plane (U_g = 0),
finely meshed cylinder (U_g = 1/R²), sphere (U_g ≈ 0), wedges of known opening angle.
Per-mesh data (vertex-face incidence, convex edge segments and their search tree) are
computed once and cached for as long as the mesh object lives unmodified. The same angle
at a physical scale, independent of the triangles: :mod:`.wedge`.
"""

from __future__ import annotations

import numpy as np

from ..caching import IdentityCache
from ..errors import InputError
from ..tolerances import FLAT_DIHEDRAL
from .cones import plane_axes
from .validation import points_n3, positive_length, use_normals_n3

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
    e1, e2 = plane_axes(normal)
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
    radius = positive_length(radius, "radius")
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
