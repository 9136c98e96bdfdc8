"""The face of a mesh closest to each point, without trimesh (trimesh's ``closest_point``).

:func:`closest_faces` is ``trimesh.proximity.closest_point`` (trimesh 4) with the same
operations in the same order, so that it picks the same face, ties included: the candidate
faces of a point are those whose bounding box meets the box around the point that reaches
its nearest vertex, in the order trimesh's R-tree of face bounds lists them (the same
``rtree`` index, built the same way); the nearest vertex comes from numpy instead of
scipy's k-d tree (the same distance). Without ``rtree`` (which trimesh needs here) the
candidates come from numpy in face order, which can only change the pick among faces at
exactly the same distance. Validated against trimesh face for face (tests), on points on
sharp edges, vertices and off the surface.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..caching import IdentityCache
from .prepared import MeshData

__all__ = ["closest_faces"]

_TOL_ZERO = float(np.finfo(np.float64).resolution * 100)  # trimesh.tol.zero
_TOL_MERGE = 1e-8  # trimesh.tol.merge
_ONES = [1.0, 1.0, 1.0]
_CHUNK = 1 << 16  # point-vertex pairs per block of the nearest-vertex search (in cache)

_TREES: IdentityCache[Any] = IdentityCache()


def closest_faces(mesh: MeshData, points: np.ndarray) -> np.ndarray:
    """Index of the face closest to each point (trimesh's ``closest_point`` triangle ids).

    Parameters
    ----------
    mesh : MeshData
        With ``face_normals`` (they break ties between faces at the same distance).
    points : (n, 3) float array_like
        m.

    Returns
    -------
    (n,) int64 ndarray
        Face indices.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    if mesh.face_normals is None:
        raise ValueError("closest_faces needs a mesh with face normals")
    triangles = mesh.vertices.view(np.ndarray)[mesh.faces]
    candidates = _nearby_faces(mesh, triangles, points)

    all_candidates = np.concatenate(candidates)
    num_candidates = list(map(len, candidates))
    tile_idxs = np.repeat(np.arange(len(points)), num_candidates)
    query_point = points[tile_idxs, :]
    query_tri = triangles[all_candidates]
    query_close = _closest_on_triangles(query_tri, query_point)
    query_group = np.cumsum(num_candidates)[:-1]
    query_vector = query_point - query_close
    query_distance = np.dot(query_vector * query_vector, _ONES)

    # the best two candidates of each point
    qds = np.array_split(query_distance, query_group)
    idxs = np.int32([qd.argsort()[:2] if len(qd) > 1 else [0, 0] for qd in qds])
    idxs[1:] += query_group.reshape(-1, 1)
    two_dists = query_distance[idxs]
    two_candidates = all_candidates[idxs]
    result = two_candidates[:, 0]

    # the same closest point on two faces: the face that faces the point more
    check_distance = np.ptp(two_dists, axis=1) < _TOL_MERGE
    check_magnitude = np.all(np.abs(two_dists) > _TOL_MERGE, axis=1)
    c_mask = np.bitwise_and(check_distance, check_magnitude)
    normals = mesh.face_normals[two_candidates[c_mask]]
    vectors = query_vector[idxs[c_mask]] / two_dists[c_mask].reshape(-1, 2, 1) ** 0.5
    dots = (normals * vectors).sum(axis=2)
    c_idxs = dots.argmax(axis=1)
    result[c_mask] = two_candidates[c_mask, c_idxs]
    return np.asarray(result, dtype=np.int64)


def _nearby_faces(mesh: MeshData, triangles: np.ndarray, points: np.ndarray) -> list[np.ndarray]:
    """Candidate faces of each point (trimesh's ``proximity.nearby_faces``)."""
    referenced = np.zeros(len(mesh.vertices), dtype=bool)
    referenced[mesh.faces] = True
    distance_vertex = _nearest_distance(mesh.vertices[referenced], points).reshape((-1, 1))
    distance_vertex += _TOL_MERGE
    bounds = np.column_stack((points - distance_vertex, points + distance_vertex))
    tree = _TREES.get(mesh, lambda: _bounds_tree(triangles))
    if tree is None:
        low = triangles.min(axis=1)
        high = triangles.max(axis=1)
        return [np.flatnonzero(((low <= b[3:]) & (high >= b[:3])).all(axis=1)) for b in bounds]
    try:
        hit_ids, hit_counts = tree.intersection_v(bounds[:, :3], bounds[:, 3:])
        return np.array_split(hit_ids, np.cumsum(hit_counts)[:-1])
    except BaseException:  # noqa: BLE001 - trimesh's fallback, for rtree < 1.4.1
        return [np.array(list(tree.intersection(b)), dtype=np.int64) for b in bounds]


def _nearest_distance(vertices: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance from each point to its nearest vertex, m (what scipy's k-d tree gives).

    Brute force by blocks of points: the points that miss a ray are few.
    """
    out = np.empty(len(points))
    x, y, z = (np.ascontiguousarray(vertices[:, k]) for k in range(3))
    step = max(1, _CHUNK // max(1, len(vertices)))
    for start in range(0, len(points), step):
        block = points[start : start + step]
        # the squares summed as scipy sums them: (dx^2 + dy^2) + dz^2
        d = x - block[:, 0:1]
        squared = d * d
        d = y - block[:, 1:2]
        squared += d * d
        d = z - block[:, 2:3]
        squared += d * d
        out[start : start + step] = np.sqrt(squared.min(axis=1))
    return out


def _bounds_tree(triangles: np.ndarray) -> Any:
    """trimesh's R-tree of face bounds (``Trimesh.triangles_tree``), or None without rtree."""
    try:
        import rtree
    except ImportError:
        return None
    bounds = np.column_stack((triangles.min(axis=1), triangles.max(axis=1)))
    bounds = np.array(bounds, dtype=np.float64, copy=True)
    properties = rtree.index.Property(dimension=3)
    return rtree.index.Index(
        zip(np.arange(len(bounds)), bounds, [None] * len(bounds), strict=True),
        properties=properties,
    )


def _closest_on_triangles(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Closest point of each triangle to its point (trimesh's ``triangles.closest_point``).

    "Real Time Collision Detection", ``ClosestPtPointTriangle``, with its names.

    Parameters
    ----------
    triangles : (n, 3, 3) float64 ndarray
        m.
    points : (n, 3) float64 ndarray
        m.

    Returns
    -------
    (n, 3) float64 ndarray
    """
    result = np.zeros_like(points)
    remain = np.ones(len(points), dtype=bool)
    a = triangles[:, 0, :]
    b = triangles[:, 1, :]
    c = triangles[:, 2, :]

    # vertex region outside A
    ab = b - a
    ac = c - a
    ap = points - a
    d1 = np.dot(ab * ap, _ONES)
    d2 = np.dot(ac * ap, _ONES)
    is_a = np.logical_and(d1 < _TOL_ZERO, d2 < _TOL_ZERO)
    if any(is_a):
        result[is_a] = a[is_a]
        remain[is_a] = False

    # A and B coincide: the triangle is the segment AC (or a point)
    collapsed_ab = np.all(ab == 0.0, axis=1)
    if collapsed_ab.any():
        segment = ac[collapsed_ab]
        length_squared = np.sum(segment**2, axis=1)
        factor = np.zeros(len(segment), dtype=np.float64)
        np.divide(
            np.sum(ap[collapsed_ab] * segment, axis=1),
            length_squared,
            out=factor,
            where=length_squared > 0,
        )
        result[collapsed_ab] = a[collapsed_ab] + np.clip(factor, 0, 1)[:, None] * segment
        remain[collapsed_ab] = False

    # vertex region outside B
    bp = points - b
    d3 = np.dot(ab * bp, _ONES)
    d4 = np.dot(ac * bp, _ONES)
    is_b = (d3 > -_TOL_ZERO) & (d4 <= d3) & remain
    if any(is_b):
        result[is_b] = b[is_b]
        remain[is_b] = False

    # edge region of AB
    vc = (d1 * d4) - (d3 * d2)
    is_ab = (vc < _TOL_ZERO) & (d1 > -_TOL_ZERO) & (d3 < _TOL_ZERO) & remain
    if any(is_ab):
        v = (d1[is_ab] / (d1[is_ab] - d3[is_ab])).reshape((-1, 1))
        result[is_ab] = a[is_ab] + (v * ab[is_ab])
        remain[is_ab] = False

    # vertex region outside C
    cp = points - c
    d5 = np.dot(ab * cp, _ONES)
    d6 = np.dot(ac * cp, _ONES)
    is_c = (d6 > -_TOL_ZERO) & (d5 <= d6) & remain
    if any(is_c):
        result[is_c] = c[is_c]
        remain[is_c] = False

    # edge region of AC
    vb = (d5 * d2) - (d1 * d6)
    is_ac = (vb < _TOL_ZERO) & (d2 > -_TOL_ZERO) & (d6 < _TOL_ZERO) & remain
    if any(is_ac):
        w = (d2[is_ac] / (d2[is_ac] - d6[is_ac])).reshape((-1, 1))
        result[is_ac] = a[is_ac] + w * ac[is_ac]
        remain[is_ac] = False

    # edge region of BC
    va = (d3 * d6) - (d5 * d4)
    is_bc = (va < _TOL_ZERO) & ((d4 - d3) > -_TOL_ZERO) & ((d5 - d6) > -_TOL_ZERO) & remain
    if any(is_bc):
        d43 = d4[is_bc] - d3[is_bc]
        w = (d43 / (d43 + (d5[is_bc] - d6[is_bc]))).reshape((-1, 1))
        result[is_bc] = b[is_bc] + w * (c[is_bc] - b[is_bc])
        remain[is_bc] = False

    # inside the face region
    if any(remain):
        denom = 1.0 / (va[remain] + vb[remain] + vc[remain])
        v = (vb[remain] * denom).reshape((-1, 1))
        w = (vc[remain] * denom).reshape((-1, 1))
        result[remain] = a[remain] + (ab[remain] * v) + (ac[remain] * w)
    return result
