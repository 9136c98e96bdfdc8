"""Dense surface samples of an object, the object's side of hand–object collision.

Every vertex, points along every edge and a barycentric lattice inside every triangle, no
two neighbours farther apart than ``spacing``. Sharp features (edges whose faces meet at
more than ``SHARP_ANGLE``, and their vertices) are flagged: the object's normal is not
defined there, so a contact on them takes the link's normal instead (see
:mod:`affordgrasp.grasp.policy`, which hands them to the kernels as a
:class:`~affordgrasp.grasp.kernels.SampleCloud`).

Because every hand link is rounded by a radius r, a link touching the surface between
samples can sink into the true mesh by at most about spacing**2 / (4 r): 0.1 mm for the
default 1.4 mm spacing and the Barrett palm rim (r = 5 mm). Beyond ``MAX_POINTS`` samples
(a surface of several m²) the spacing grows and a warning says the tolerance is not met.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import trimesh

log = logging.getLogger(__name__)

SHARP_ANGLE = np.deg2rad(20.0)
DEFAULT_SPACING = 1.4e-3
MAX_POINTS = 1_000_000


CELL_SIZE = 6e-3  # fine cells; coarse cells are 3 x 3 x 3 of them
SUB_CELLS = 2  # the contact search splits each fine cell 2 x 2 x 2 (3 mm sub-cells)


@dataclass(frozen=True)
class SurfaceSample:
    """Surface samples grouped into a two-level grid of cells.

    Attributes
    ----------
    points : (n, 3) float64 ndarray
        m.
    normals : (n, 3) float64 ndarray
        Outward unit normals.
    sharp : (n,) bool ndarray
        Samples on sharp edges or corners.
    spacing : float
        m.
    cell_start : (c + 1,) int ndarray
        Offsets of each fine cell's points.
    cell_center, cell_radius : (c, 3), (c,) float64 ndarray
        A bounding sphere of each fine cell's points, m.
    cell_normal, cell_slab : (c, 3), (c, 2) float64 ndarray
        Each fine cell's best-fit plane through its centre (unit normal) and the largest
        distances of its points from that plane and from the normal line, m (see
        :func:`group_into_cells`).
    coarse_start : (k + 1,) int ndarray
        Offsets of each coarse cell's (3 x 3 x 3) fine cells.
    coarse_center, coarse_radius : (k, 3), (k,) float64 ndarray
        A bounding sphere of each coarse cell, m.
    cell_sub_start : (c + 1,) int ndarray
        Offsets of each fine cell's sub-cells (its points split 2 x 2 x 2).
    sub_start : (s + 1,) int ndarray
        Offsets of each sub-cell's points in ``sub_points``.
    sub_points : (n,) int ndarray
        Point indices, grouped by sub-cell (the points keep their order: a sub-cell's are
        listed, not moved).
    sub_center, sub_radius, sub_normal, sub_slab : (s, 3), (s,), (s, 3), (s, 2) ndarray
        As ``cell_*``, per sub-cell.
    """

    points: np.ndarray
    normals: np.ndarray
    sharp: np.ndarray
    spacing: float
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


def _runs(keys: np.ndarray) -> np.ndarray:
    """Start offsets (+ the end) of the runs of equal rows in sorted keys (n, d)."""
    new = np.ones(len(keys), dtype=bool)
    new[1:] = np.any(keys[1:] != keys[:-1], axis=1)
    return np.append(np.nonzero(new)[0], len(keys)).astype(np.int64)


def _spheres(p: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    counts = np.diff(start)
    owner = np.repeat(np.arange(len(counts)), counts)
    center = np.add.reduceat(p, start[:-1], axis=0) / counts[:, None]
    dist = np.linalg.norm(p - center[owner], axis=1)
    return center, np.maximum.reduceat(dist, start[:-1]) + 1e-9


def _slabs(p: np.ndarray, start: np.ndarray, center: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's best-fit plane through ``center`` (the normal: the covariance's
    eigenvector of the smallest eigenvalue) and the largest distances of its points from
    the plane and from the normal line (plus 1 nm, as the spheres), (c, 3) and (c, 2)."""
    counts = np.diff(start)
    owner = np.repeat(np.arange(len(counts)), counts)
    q = p - center[owner]
    cov = np.add.reduceat(q[:, :, None] * q[:, None, :], start[:-1], axis=0)
    normal = np.ascontiguousarray(np.linalg.eigh(cov)[1][:, :, 0])
    along = np.sum(q * normal[owner], axis=1)
    across = np.linalg.norm(q - along[:, None] * normal[owner], axis=1)
    slab = np.stack(
        [np.maximum.reduceat(np.abs(along), start[:-1]), np.maximum.reduceat(across, start[:-1])],
        axis=1,
    )
    return normal, slab + 1e-9


def group_into_cells(points: np.ndarray, size: float = CELL_SIZE):
    """Order of the points by coarse then fine cell, and both levels' offsets and spheres.

    Parameters
    ----------
    points : (n, 3) float64 ndarray
        m.
    size : float
        Fine cell edge, m.

    Returns
    -------
    order : (n,) int ndarray
    fine : tuple
        (start, center, radius, normal, slab) of the fine cells: a bounding sphere, and a
        flat cylinder around the same centre (the best-fit plane's unit normal, the points'
        largest distances from the plane and from the normal line). A fine cell of a
        surface is nearly flat: the contact search bounds its points' distance to a link
        through the cylinder, several times tighter than through the sphere.
    coarse : tuple
        (start into the fine cells, center, radius) of the coarse cells.
    sub : tuple
        (start into the sub-cells per fine cell, start into ``points`` per sub-cell,
        points, center, radius, normal, slab) of the sub-cells: each fine cell's points
        split 2 x 2 x 2 (by the halves of its edges), listed by index in the sorted order
        (they are not reordered), with a sphere and a flat cylinder as the fine cells'.
    """
    fine = np.floor((points - points.min(axis=0)) / size).astype(np.int64)
    coarse = fine // 3
    order = np.lexsort((fine[:, 2], fine[:, 1], fine[:, 0], coarse[:, 2], coarse[:, 1],
                        coarse[:, 0]))  # fmt: skip
    p = points[order]
    fine_start = _runs(np.concatenate([coarse[order], fine[order]], axis=1))
    fine_center, fine_radius = _spheres(p, fine_start)
    fine_normal, fine_slab = _slabs(p, fine_start, fine_center)
    coarse_of_fine = coarse[order][fine_start[:-1]]
    coarse_runs = _runs(coarse_of_fine)
    coarse_center, coarse_radius = _spheres(p, fine_start[coarse_runs])
    # sub-cells: the half of each fine cell's edge a point lies in, per axis (a point
    # rounded into its neighbour's half only makes that sub-cell's sphere larger)
    half = np.floor((p - points.min(axis=0)) / (size / SUB_CELLS)).astype(np.int64) % SUB_CELLS
    bits = (half[:, 0] * SUB_CELLS + half[:, 1]) * SUB_CELLS + half[:, 2]
    owner = np.repeat(np.arange(len(fine_start) - 1), np.diff(fine_start))
    listed = np.lexsort((bits, owner))  # stable: by index within a sub-cell
    listed_owner = owner[listed]
    sub_start = _runs(np.stack([listed_owner, bits[listed]], axis=1))
    q = p[listed]
    sub_center, sub_radius = _spheres(q, sub_start)
    sub_normal, sub_slab = _slabs(q, sub_start, sub_center)
    cell_sub_start = np.searchsorted(
        listed_owner[sub_start[:-1]], np.arange(len(fine_start))
    ).astype(np.int64)
    return (
        order,
        (fine_start, fine_center, fine_radius, fine_normal, fine_slab),
        (coarse_runs, coarse_center, coarse_radius),
        (
            cell_sub_start,
            sub_start,
            listed.astype(np.int64),
            sub_center,
            sub_radius,
            sub_normal,
            sub_slab,
        ),
    )


def _face_lattice(tri: np.ndarray, spacing: float):
    """Points strictly inside each triangle on a grid along its two shorter edges.

    tri : (m, 3, 3). From the corner opposite the longest edge, steps of at most
    ``spacing`` along each of the two other edges, so a long thin triangle gets as many points
    as its area needs, not as many as its longest side squared.
    returns : points (k, 3), face index of each (k,)
    """
    side = np.linalg.norm(tri[:, [2, 0, 1]] - tri[:, [1, 2, 0]], axis=2)  # side opposite corner
    corner = np.argmax(side, axis=1)
    m = len(tri)
    rows = np.arange(m)
    v0 = tri[rows, corner]
    e1 = tri[rows, (corner + 1) % 3] - v0
    e2 = tri[rows, (corner + 2) % 3] - v0
    n1 = np.maximum(np.ceil(np.linalg.norm(e1, axis=1) / spacing).astype(np.int64), 1)
    n2 = np.maximum(np.ceil(np.linalg.norm(e2, axis=1) / spacing).astype(np.int64), 1)
    # Pairs (face, i) for i = 1..n1-1, then j = 1..J(i) with i/n1 + j/n2 < 1.
    fi = np.repeat(rows, n1 - 1)
    start = np.cumsum(n1 - 1) - (n1 - 1)
    i = np.arange(len(fi)) - np.repeat(start, n1 - 1) + 1
    jmax = np.ceil(n2[fi] * (1.0 - i / n1[fi])).astype(np.int64) - 1
    jmax = np.maximum(jmax, 0)
    f = np.repeat(fi, jmax)
    ii = np.repeat(i, jmax)
    jstart = np.cumsum(jmax) - jmax
    j = np.arange(len(f)) - np.repeat(jstart, jmax) + 1
    pts = v0[f] + (ii / n1[f])[:, None] * e1[f] + (j / n2[f])[:, None] * e2[f]
    return pts, f


def sample_count_bound(
    tri: np.ndarray, edge_len: np.ndarray, n_vertices: int, spacing: float
) -> float:
    """An upper bound on the number of samples at ``spacing``, computed without building them.

    Floats, O(triangles): vertices + edge interiors + n1 n2 / 2 per triangle, n1 and n2 its
    lattice steps along its two shorter sides (see ``_face_lattice``).

    Parameters
    ----------
    tri : (m, 3, 3) float64 ndarray
        Triangle corners, m.
    edge_len : (e,) float64 ndarray
        Lengths of the mesh's unique edges, m.
    n_vertices : int
        Mesh vertices.
    spacing : float
        m.

    Returns
    -------
    float
    """
    side = np.sort(np.linalg.norm(tri[:, [2, 0, 1]] - tri[:, [1, 2, 0]], axis=2), axis=1)
    n1 = np.maximum(np.ceil(side[:, 0] / spacing), 1.0)
    n2 = np.maximum(np.ceil(side[:, 1] / spacing), 1.0)
    edges = float(np.sum(np.maximum(np.ceil(edge_len / spacing), 1.0) - 1.0))
    return float(n_vertices) + edges + float(np.sum(n1 * n2 / 2.0))


def capped_spacing(
    tri: np.ndarray, edge_len: np.ndarray, n_vertices: int, spacing: float, max_points: int
) -> float:
    """The requested spacing, or the smallest one tried at which the sample count fits.

    Tried in steps of 1.25x, from a first jump by the square root of the excess, until
    :func:`sample_count_bound` is <= max_points. Memory is bounded by construction: no sample
    array is built before the count fits, so a mesh in the wrong units (a 100 mm cube read as
    100 m) costs seconds, not 228 GiB. A mesh with more than ``max_points`` vertices keeps
    only its vertices and edges' ends. The result is finite and at most the longest side of
    a triangle (where the count is smallest); it may then still exceed ``max_points``.

    Parameters
    ----------
    tri, edge_len, n_vertices, spacing
        As for :func:`sample_count_bound`.
    max_points : int
        The cap.

    Returns
    -------
    float
        Spacing, m.
    """
    count = sample_count_bound(tri, edge_len, n_vertices, spacing)
    if count <= max_points:
        return spacing
    # Beyond the longest side nothing changes (one segment per edge, the coarsest lattice),
    # so the search stops there: the spacing stays finite and no larger than the mesh's own
    # triangles, which then bound how far a link can sink (the mesh has more vertices and
    # triangles than the cap allows samples; simplify it, see objects.loading).
    longest = float(np.max(edge_len)) if len(edge_len) else spacing
    if len(tri):
        longest = max(longest, float(np.max(np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2))))
    if n_vertices >= max_points or spacing >= longest:
        return max(spacing, longest)
    # Area terms scale as 1 / spacing², so this jump lands near the cap; then step up.
    spacing = min(spacing * max(np.sqrt(count / max_points) / 1.25**2, 1.0), longest)
    while spacing < longest:
        if sample_count_bound(tri, edge_len, n_vertices, spacing) <= max_points:
            return spacing
        spacing = min(spacing * 1.25, longest)
    return longest


def sample_surface(
    mesh: trimesh.Trimesh, spacing: float = DEFAULT_SPACING, max_points: int = MAX_POINTS
) -> SurfaceSample:
    """Deterministic dense sample of the surface; the spacing grows if ``max_points`` is hit.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object, m.
    spacing : float
        Requested spacing, m.
    max_points : int
        Cap on the number of samples (memory bound).

    Returns
    -------
    SurfaceSample
    """
    requested = spacing
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    face_normals = np.asarray(mesh.face_normals, dtype=np.float64)
    edges = np.asarray(mesh.edges_unique, dtype=np.int64)
    edge_len = np.linalg.norm(vertices[edges[:, 1]] - vertices[edges[:, 0]], axis=1)
    tri = vertices[faces]

    # Edge normal and sharpness from the two faces sharing it.
    adj_edges = np.asarray(mesh.face_adjacency_edges, dtype=np.int64)
    adj_faces = np.asarray(mesh.face_adjacency, dtype=np.int64)
    adj_angle = np.asarray(mesh.face_adjacency_angles, dtype=np.float64)
    # Each adjacency's unique edge, by its sorted vertex pair as one integer (vectorised:
    # a dictionary of pairs costs seconds on a scan). The last adjacency of an edge wins,
    # as it did when they were assigned in turn.
    n_v = np.int64(max(len(vertices), 1))
    sorted_edges = np.sort(edges, axis=1)
    key = sorted_edges[:, 0] * n_v + sorted_edges[:, 1]
    order = np.argsort(key, kind="stable")
    adj_sorted = np.sort(adj_edges, axis=1).reshape(-1, 2)
    adj_key = adj_sorted[:, 0] * n_v + adj_sorted[:, 1]
    k = order[np.searchsorted(key[order], adj_key)] if len(adj_key) else adj_key
    edge_normal = np.zeros((len(edges), 3))
    edge_sharp = np.zeros(len(edges), dtype=bool)
    edge_normal[k] = face_normals[adj_faces[:, 0]] + face_normals[adj_faces[:, 1]]
    edge_sharp[k] = adj_angle > SHARP_ANGLE

    vertex_sharp = np.zeros(len(vertices), dtype=bool)
    vertex_sharp[edges[edge_sharp].ravel()] = True
    vertex_normals = np.asarray(mesh.vertex_normals, dtype=np.float64)

    spacing = capped_spacing(tri, edge_len, len(vertices), spacing, max_points)
    if spacing > requested:
        log.warning(
            "surface of %.3g m² needs more than %d samples at %.2f mm: spacing raised to "
            "%.3g mm (samples capped for memory), so a link may sink up to about %.3g mm into "
            "the mesh",
            mesh.area,
            max_points,
            requested * 1e3,
            spacing * 1e3,
            spacing**2 / 4 / 5e-3 * 1e3,
        )
    seg = np.maximum(np.ceil(edge_len / spacing).astype(np.int64), 1)
    face_pts, face_of = _face_lattice(tri, spacing)

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
    pts.append(face_pts)
    nrm.append(face_normals[face_of])
    shp.append(np.zeros(len(face_pts), dtype=bool))
    points = np.concatenate(pts)
    normals = np.concatenate(nrm)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = normals / np.where(length > 0, length, 1.0)
    order, fine, coarse, sub = group_into_cells(points)
    return SurfaceSample(
        np.ascontiguousarray(points[order]),
        np.ascontiguousarray(normals[order]),
        np.concatenate(shp)[order],
        spacing,
        *fine,
        *coarse,
        *sub,
    )
