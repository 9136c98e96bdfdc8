"""Construction primitives shared by the procedural families: sections, sweeps, lathes.

Everything here works in metres on float64 numpy arrays and returns ``manifold3d.Manifold``
solids, which are closed and consistently oriented by construction, so the families can
combine them with exact booleans and convert the result once, at the end, with
:func:`to_trimesh`.

Validated against known geometries in ``tests/objects/test_families.py`` (volumes of swept
boxes and lathed cylinders agree with the closed forms).
"""

from __future__ import annotations

import manifold3d
import numpy as np
import trimesh

from affordgrasp.errors import AffordgraspError

__all__ = [
    "superellipse",
    "sweep",
    "sweep_along_x",
    "planar_frames",
    "hollow_lathe",
    "silhouette",
    "section",
    "cavity_section",
    "rounded_stations",
    "to_trimesh",
    "union",
]

_ARC_SEGMENTS = 32  # segments per full turn on the rounded corners of an offset section


def superellipse(
    half_u: float, half_v: float, exponent: float = 2.0, points: int = 32, half_step: bool = False
) -> np.ndarray:
    """Closed superellipse |u/a|^n + |v/b|^n = 1, counter-clockwise from +u.

    Parameters
    ----------
    half_u, half_v : float
        Semi-axes along u and v, m.
    exponent : float
        n: 2 is an ellipse, 4 a rounded rectangle.
    points : int
        Number of vertices, even and >= 4.
    half_step : bool
        Start half a step after +u, so that no vertex lies on the u axis (v = 0). Parts united
        with others symmetric about the same plane use it: vertices exactly on a shared
        symmetry plane make booleans leave zero-height slivers.

    Returns
    -------
    (points, 2) float64 ndarray
        The (u, v) vertices, m, exactly symmetric about the u axis.

    Raises
    ------
    ValueError
        When ``points`` is odd or below 4.
    """
    if points < 4 or points % 2:
        raise ValueError(f"superellipse needs an even number of points >= 4, got {points}")
    # Build the upper half and mirror it, so the section is exactly symmetric about u: a
    # section squashed to v = 0 then collapses to a ridge with coincident vertices.
    half = points // 2
    power = 2.0 / exponent
    if half_step:
        theta = np.pi * (np.arange(half) + 0.5) / half
        c, s = np.cos(theta), np.sin(theta)
        u = half_u * np.sign(c) * np.abs(c) ** power
        v = half_v * np.abs(s) ** power
        u = np.concatenate([u, u[::-1]])
        v = np.concatenate([v, -v[::-1]])
        return np.stack([u, v], axis=1)
    theta = np.pi * np.arange(half + 1) / half
    c, s = np.cos(theta), np.sin(theta)
    s[[0, -1]] = 0.0
    u = half_u * np.sign(c) * np.abs(c) ** power
    v = half_v * np.abs(s) ** power
    u = np.concatenate([u, u[-2:0:-1]])
    v = np.concatenate([v, -v[-2:0:-1]])
    return np.stack([u, v], axis=1)


def planar_frames(path: np.ndarray, plane_normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Section frames for a path that lies in a plane.

    A planar path needs no parallel transport, and these frames never twist.

    Parameters
    ----------
    path : (n, 3) float ndarray
        Points of the path, m.
    plane_normal : (3,) float ndarray
        Normal of the path's plane.

    Returns
    -------
    normals : (n, 3) float64 ndarray
        Unit vectors in the plane, perpendicular to the path.
    binormals : (n, 3) float64 ndarray
        The plane normal at every point.
    """
    tangent = np.gradient(path, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    binormal = np.broadcast_to(np.asarray(plane_normal, dtype=float), path.shape).copy()
    normal = np.cross(binormal, tangent)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return normal, binormal


def rounded_stations(
    x0: float, x1: float, radius0: float, radius1: float, middle: int = 16
) -> tuple[np.ndarray, np.ndarray]:
    """Stations along [x0, x1] for a bar whose ends are rounded like a dome.

    The factor follows a quarter circle from 0.3 at the tips to 1 in the middle (7 stations
    in each rounded zone), so a handle gets a domed butt with a small flat cap instead of a
    pinched apex.

    Parameters
    ----------
    x0, x1 : float
        Ends of the bar along x, m.
    radius0, radius1 : float
        Length of the rounded zone at each end, m (0 for a square end).
    middle : int
        Stations in the straight middle part.

    Returns
    -------
    xs : (k,) float64 ndarray
        Increasing stations, m.
    factor : (k,) float64 ndarray
        Scale the section by ``factor`` at ``xs``.
    """
    arc, phi_min = 7, np.arcsin(0.3)
    xs_parts, f_parts = [], []
    if radius0 > 0:
        phi = np.linspace(phi_min, np.pi / 2, arc, endpoint=False)
        xs_parts.append(x0 + radius0 * (1.0 - np.cos(phi)))
        f_parts.append(np.sin(phi))
    mid = np.linspace(x0 + radius0, x1 - radius1, middle)
    xs_parts.append(mid)
    f_parts.append(np.ones_like(mid))
    if radius1 > 0:
        phi = np.linspace(np.pi / 2, phi_min, arc + 1)[1:]
        xs_parts.append(x1 - radius1 * (1.0 - np.cos(phi)))
        f_parts.append(np.sin(phi))
    return np.concatenate(xs_parts), np.concatenate(f_parts)


def _ring_area(ring: np.ndarray) -> float:
    """Area of a closed 3-D polygon (Newell's method); 0 for a point or a segment."""
    return 0.5 * float(np.linalg.norm(np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0)))


def sweep(rings: np.ndarray) -> manifold3d.Manifold:
    """Closed solid through a sequence of cross-section rings.

    Ring i and ring i + 1 are joined vertex k to vertex k; every ring must run the same way
    round. Ends with area are closed by a fan from their centroid. A ring whose vertices
    coincide (exactly, same floats) collapses: to a point it closes the solid in an apex, to a
    segment it closes it in a ridge, which is how blades get a true edge line rather than a
    blunt cap.

    Parameters
    ----------
    rings : (n, m, 3) float ndarray
        n rings of m vertices, m.

    Returns
    -------
    manifold3d.Manifold
        Closed and consistently oriented (outward normals).

    Raises
    ------
    AffordgraspError
        When the rings do not bound a closed manifold.
    """
    rings = np.ascontiguousarray(rings, dtype=np.float64)
    n, m, _ = rings.shape
    vertices = [rings.reshape(-1, 3)]
    idx = np.arange(n * m).reshape(n, m)
    a = idx[:-1, :]
    b = np.roll(idx[:-1, :], -1, axis=1)
    c = np.roll(idx[1:, :], -1, axis=1)
    d = idx[1:, :]
    # Split each quad along its shorter diagonal: mirror-symmetric rings then give
    # mirror-symmetric triangles, so both faces at a blade edge tilt alike.
    flat = rings.reshape(-1, 3)
    ac = np.linalg.norm(flat[a] - flat[c], axis=-1)
    bd = np.linalg.norm(flat[b] - flat[d], axis=-1)
    use_ac = (ac <= bd)[..., None]
    first = np.where(use_ac, np.stack([a, b, c], axis=-1), np.stack([a, b, d], axis=-1))
    second = np.where(use_ac, np.stack([a, c, d], axis=-1), np.stack([b, c, d], axis=-1))
    faces = [first.reshape(-1, 3), second.reshape(-1, 3)]
    next_index = n * m
    for end, flip in ((0, False), (n - 1, True)):
        if _ring_area(rings[end]) <= 1e-16:
            continue
        vertices.append(rings[end].mean(axis=0, keepdims=True))
        ring_idx = idx[end]
        fan = np.stack(
            [np.full(m, next_index), np.roll(ring_idx, -1), ring_idx]
            if not flip
            else [np.full(m, next_index), ring_idx, np.roll(ring_idx, -1)],
            axis=-1,
        )
        faces.append(fan)
        next_index += 1
    # "+ 0.0" turns -0.0 into 0.0 so mirrored zeros merge too.
    verts = np.concatenate(vertices, axis=0) + 0.0
    tris = np.concatenate(faces, axis=0)
    # Merge exactly coincident vertices: collapsed rings become apexes and ridges.
    verts, inverse = np.unique(verts, axis=0, return_inverse=True)
    tris = inverse.reshape(-1)[tris]
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[keep]
    return _manifold_from_arrays(verts, tris)


def sweep_along_x(
    xs: np.ndarray,
    sections: np.ndarray,
    y_center: np.ndarray | float = 0.0,
    z_center: np.ndarray | float = 0.0,
) -> manifold3d.Manifold:
    """Sweep (y, z) sections along the x axis (:func:`sweep`).

    Parameters
    ----------
    xs : (n,) float ndarray
        Increasing stations, m.
    sections : (n, m, 2) float ndarray
        (y, z) offsets of each section's vertices from its origin, m.
    y_center, z_center : float or (n,) float ndarray
        Section origin at each station, m.

    Returns
    -------
    manifold3d.Manifold
    """
    xs = np.asarray(xs, dtype=float)
    n = xs.shape[0]
    yc = np.broadcast_to(np.asarray(y_center, dtype=float), (n,))
    zc = np.broadcast_to(np.asarray(z_center, dtype=float), (n,))
    rings = np.empty(sections.shape[:2] + (3,))
    rings[..., 0] = xs[:, None]
    rings[..., 1] = yc[:, None] + sections[..., 0]
    rings[..., 2] = zc[:, None] + sections[..., 1]
    return sweep(rings)


def _signed_volume(verts: np.ndarray, tris: np.ndarray) -> float:
    v0, v1, v2 = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    return float(np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() / 6.0)


def _manifold_from_arrays(verts: np.ndarray, tris: np.ndarray) -> manifold3d.Manifold:
    if _signed_volume(verts, tris) < 0.0:
        tris = tris[:, ::-1]
    mesh = manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(verts, dtype=np.float64),
        tri_verts=np.ascontiguousarray(tris, dtype=np.uint64),
    )
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        raise AffordgraspError(f"procedural solid is not a closed manifold ({solid.status()})")
    return solid


def section(polygon: np.ndarray) -> manifold3d.CrossSection:
    """Planar region bounded by one closed polygon.

    Parameters
    ----------
    polygon : (k, 2) float ndarray
        Vertices, m.

    Returns
    -------
    manifold3d.CrossSection
    """
    return manifold3d.CrossSection([np.ascontiguousarray(polygon, dtype=np.float64)])


def silhouette(radius: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Closed, axis-symmetric (r, z) polygon of a solid whose outer radius is radius(z).

    Parameters
    ----------
    radius : (k,) float ndarray
        Outer radius at each height, m.
    z : (k,) float ndarray
        Increasing heights, m.

    Returns
    -------
    (2k, 2) float64 ndarray
        Counter-clockwise (r, z) vertices; the first and last z close it with flat ends.
    """
    right = np.stack([radius, z], axis=1)
    left = np.stack([-radius[::-1], z[::-1]], axis=1)
    return np.concatenate([right, left], axis=0)


def cavity_section(
    cavity_from: manifold3d.CrossSection, wall: float, floor_z: float | None = None
) -> manifold3d.CrossSection:
    """The (r, z) cavity of :func:`hollow_lathe`.

    Parameters
    ----------
    cavity_from : manifold3d.CrossSection
        Symmetric (r, z) silhouette, m.
    wall : float
        Inward offset, m (the wall thickness).
    floor_z : float, optional
        Cut the cavity below this height, m (a thick base).

    Returns
    -------
    manifold3d.CrossSection
        ``cavity_from`` offset inwards by ``wall``, cut at ``floor_z`` if given.
    """
    cavity = cavity_from.offset(-wall, manifold3d.JoinType.Round, 2.0, _ARC_SEGMENTS)
    if floor_z is not None:
        big = 10.0
        above = manifold3d.CrossSection.square((2 * big, big)).translate((-big, floor_z))
        cavity = cavity ^ above
    return cavity


def hollow_lathe(
    outer: manifold3d.CrossSection,
    cavity_from: manifold3d.CrossSection,
    wall: float,
    floor_z: float | None = None,
    lip_round: float | None = None,
    segments: int = 64,
) -> manifold3d.Manifold:
    """Container wall of revolution about +z, open at the top.

    Parameters
    ----------
    outer : manifold3d.CrossSection
        Symmetric (r, z) silhouette of the full solid, m.
    cavity_from : manifold3d.CrossSection
        Symmetric (r, z) silhouette whose inward offset by ``wall`` is the cavity. It must
        reach above the rim so that the cavity opens there (it may differ from ``outer``, so
        that the cavity follows a glass's bowl and not its stem).
    wall : float
        Wall thickness, m, measured along the surface normal (an offset, not a radial step,
        so a sloping shoulder is as thick as a vertical side).
    floor_z : float, optional
        The cavity stops at this height, m (a thick base).
    lip_round : float, optional
        Radius with which convex corners of the wall section are rounded, m.
    segments : int
        Segments around the axis.

    Returns
    -------
    manifold3d.Manifold
    """
    cavity = cavity_section(cavity_from, wall, floor_z)
    wall_section = outer - cavity
    if lip_round:
        # A morphological opening rounds the rim and the foot like a finished part.
        wall_section = wall_section.offset(
            -lip_round, manifold3d.JoinType.Round, 2.0, _ARC_SEGMENTS
        ).offset(lip_round, manifold3d.JoinType.Round, 2.0, _ARC_SEGMENTS)
    # Offsets leave many near-collinear vertices; 20 um is far below any feature here.
    return _clear_axis(wall_section.simplify(2e-5)).revolve(circular_segments=segments)


def _clear_axis(region: manifold3d.CrossSection, radius: float = 2e-4) -> manifold3d.CrossSection:
    """The r >= 0 half of an (r, z) region, with vertices closer than ``radius`` to the axis
    moved onto it.

    Revolving a vertex a few micrometres off the axis gives a ring of needle triangles;
    moving it onto the axis changes the surface by less than ``radius``.  Clipping first
    keeps the region on one side, so snapped vertices only extend its edge on the axis.
    """
    big = 10.0
    half = region ^ manifold3d.CrossSection.square((big, 2 * big)).translate((0.0, -big))
    contours = []
    for contour in half.to_polygons():
        snapped = np.array(contour, dtype=np.float64)
        snapped[snapped[:, 0] < radius, 0] = 0.0
        contours.append(snapped)
    return manifold3d.CrossSection(contours)


def union(parts: list[manifold3d.Manifold]) -> manifold3d.Manifold:
    """Boolean union of solids.

    Parameters
    ----------
    parts : list of manifold3d.Manifold

    Returns
    -------
    manifold3d.Manifold
    """
    return manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add)


def to_trimesh(solid: manifold3d.Manifold, center: bool = True) -> trimesh.Trimesh:
    """Convert a solid to a float64 ``trimesh.Trimesh``.

    The conversion goes through manifold's double-precision mesh, so the same solid always
    gives the same bytes; vertices no triangle uses (left on the axis by revolving) are
    dropped.

    Parameters
    ----------
    solid : manifold3d.Manifold
    center : bool
        Move the origin to the bounding-box centre.

    Returns
    -------
    trimesh.Trimesh
        Built with ``process=False``, m.

    Raises
    ------
    AffordgraspError
        When the solid is empty or invalid.
    """
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        raise AffordgraspError(f"procedural solid is empty or invalid ({solid.status()})")
    mesh = solid.to_mesh64()
    vertices = np.array(mesh.vert_properties[:, :3], dtype=np.float64)
    faces = np.array(mesh.tri_verts, dtype=np.int64)
    # Revolving can leave a vertex on the axis that no triangle uses; drop such vertices so
    # every vertex belongs to the surface.
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    if not used.all():
        vertices = vertices[used]
        faces = (np.cumsum(used) - 1)[faces]
    if center:
        vertices -= 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
