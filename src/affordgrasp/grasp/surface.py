"""Dense surface samples of an object, the object's side of hand–object collision.

Every vertex, points along every edge and a barycentric lattice inside every triangle, no
two neighbours farther apart than ``spacing``. Sharp features (edges whose faces meet at
more than ``SHARP_ANGLE``, and their vertices) are flagged: the object's normal is not
defined there, so a contact on them takes the link's normal instead (see ``policy``).

Because every hand link is rounded by a radius r, a link touching the surface between
samples can sink into the true mesh by at most about spacing**2 / (8 r): 0.06 mm for the
default 1.4 mm spacing and the Barrett palm rim (r = 5 mm). Beyond ``MAX_POINTS`` samples
(a surface of several m²) the spacing grows and a warning says the tolerance is not met.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import trimesh

log = logging.getLogger(__name__)

SHARP_ANGLE = np.deg2rad(20.0)
DEFAULT_SPACING = 1.4e-3
MAX_POINTS = 1_000_000


CELL_SIZE = 8e-3


@dataclass(frozen=True)
class SurfaceSample:
    """Surface samples grouped into cells of a uniform grid.

    points (n, 3) m, normals (n, 3) outward unit, sharp (n,) bool, spacing m;
    cell_start (c + 1,) offsets of each cell's points, cell_center (c, 3) and
    cell_radius (c,) a bounding sphere of each cell's points.
    """

    points: np.ndarray
    normals: np.ndarray
    sharp: np.ndarray
    spacing: float
    cell_start: np.ndarray
    cell_center: np.ndarray
    cell_radius: np.ndarray


def group_into_cells(points: np.ndarray, size: float = CELL_SIZE):
    """Order (n,) that groups points by grid cell, with cell offsets, centres and radii."""
    key = np.floor((points - points.min(axis=0)) / size).astype(np.int64)
    order = np.lexsort((key[:, 2], key[:, 1], key[:, 0]))
    k = key[order]
    new = np.ones(len(k), dtype=bool)
    new[1:] = np.any(k[1:] != k[:-1], axis=1)
    start = np.append(np.nonzero(new)[0], len(k))
    p = points[order]
    counts = np.diff(start)
    cell_of = np.repeat(np.arange(len(counts)), counts)
    center = np.add.reduceat(p, start[:-1], axis=0) / counts[:, None]
    dist = np.linalg.norm(p - center[cell_of], axis=1)
    radius = np.maximum.reduceat(dist, start[:-1]) + 1e-9
    return order, start.astype(np.int64), center, radius


def _lattice(n: int) -> np.ndarray:
    """Barycentric (i/n, j/n) strictly inside a triangle, as (k, 2)."""
    ij = [(i, j) for i in range(1, n) for j in range(1, n - i)]
    return np.array(ij, dtype=np.float64).reshape(-1, 2) / n


def sample_surface(
    mesh: trimesh.Trimesh, spacing: float = DEFAULT_SPACING, max_points: int = MAX_POINTS
) -> SurfaceSample:
    """Deterministic dense sample of the surface; the spacing grows if ``max_points`` is hit."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    face_normals = np.asarray(mesh.face_normals, dtype=np.float64)
    edges = np.asarray(mesh.edges_unique, dtype=np.int64)
    edge_len = np.linalg.norm(vertices[edges[:, 1]] - vertices[edges[:, 0]], axis=1)
    tri = vertices[faces]
    longest = np.max(
        np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1
    )  # (m,) longest side of each face

    # Edge normal and sharpness from the two faces sharing it.
    adj_edges = np.asarray(mesh.face_adjacency_edges, dtype=np.int64)
    adj_faces = np.asarray(mesh.face_adjacency, dtype=np.int64)
    adj_angle = np.asarray(mesh.face_adjacency_angles, dtype=np.float64)
    edge_key = {tuple(e): k for k, e in enumerate(np.sort(edges, axis=1).tolist())}
    edge_normal = np.zeros((len(edges), 3))
    edge_sharp = np.zeros(len(edges), dtype=bool)
    for (a, b), (f0, f1), ang in zip(
        np.sort(adj_edges, axis=1).tolist(), adj_faces.tolist(), adj_angle.tolist(), strict=True
    ):
        k = edge_key[(a, b)]
        edge_normal[k] = face_normals[f0] + face_normals[f1]
        edge_sharp[k] = ang > SHARP_ANGLE

    vertex_sharp = np.zeros(len(vertices), dtype=bool)
    vertex_sharp[edges[edge_sharp].ravel()] = True
    vertex_normals = np.asarray(mesh.vertex_normals, dtype=np.float64)

    while True:
        seg = np.maximum(np.ceil(edge_len / spacing).astype(np.int64), 1)
        per_face = np.maximum(np.ceil(longest / spacing).astype(np.int64), 1)
        n_edge = int((seg - 1).sum())
        n_face = int(((per_face - 1) * (per_face - 2) // 2).sum())
        if len(vertices) + n_edge + n_face <= max_points:
            break
        spacing *= 1.25
        log.warning(
            "surface of %.3g m² needs more than %d samples: spacing raised to %.2f mm, so a "
            "link may sink up to about %.2f mm into the mesh",
            mesh.area,
            max_points,
            spacing * 1e3,
            spacing**2 / 8 / 5e-3 * 1e3,
        )

    pts = [vertices]
    nrm = [vertex_normals]
    shp = [vertex_sharp]
    # Edge interiors, grouped by their number of segments so each group is one array op.
    for n in np.unique(seg[seg > 1]):
        sel = np.nonzero(seg == n)[0]
        frac = np.arange(1, n) / n
        a = vertices[edges[sel, 0]]
        b = vertices[edges[sel, 1]]
        p = a[:, None, :] + frac[None, :, None] * (b - a)[:, None, :]
        pts.append(p.reshape(-1, 3))
        nrm.append(np.repeat(edge_normal[sel], n - 1, axis=0))
        shp.append(np.repeat(edge_sharp[sel], n - 1))
    # Triangle interiors.
    for n in np.unique(per_face[per_face > 2]):
        sel = np.nonzero(per_face == n)[0]
        bary = _lattice(int(n))
        t = tri[sel]
        p = (
            t[:, None, 0, :]
            + bary[None, :, 0, None] * (t[:, None, 1, :] - t[:, None, 0, :])
            + bary[None, :, 1, None] * (t[:, None, 2, :] - t[:, None, 0, :])
        )
        pts.append(p.reshape(-1, 3))
        nrm.append(np.repeat(face_normals[sel], len(bary), axis=0))
        shp.append(np.zeros(len(sel) * len(bary), dtype=bool))
    points = np.concatenate(pts)
    normals = np.concatenate(nrm)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = normals / np.where(length > 0, length, 1.0)
    order, start, center, radius = group_into_cells(points)
    return SurfaceSample(
        np.ascontiguousarray(points[order]),
        np.ascontiguousarray(normals[order]),
        np.concatenate(shp)[order],
        spacing,
        start,
        center,
        radius,
    )
