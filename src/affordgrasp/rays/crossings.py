"""Every crossing of many rays with a mesh: Embree finds the faces, a compiled loop the rest.

trimesh's multiple-hit loop (``RayMeshIntersector.intersects_id``) spends two thirds of its
time outside Embree, in numpy: gathering the live rays, intersecting each hit face's plane,
advancing the rays past their hits. :func:`crossings` makes the same Embree calls on the
same float32 rays and does the rest in one compiled pass per round, with the same
floating-point operations in the same order, so the hits, their points and their order are
the same bits (``tests/rays/test_crossings.py`` compares the two); about twice as fast on
the wedge angle's rays. :class:`~.mesh.EmbreeRays` answers trimesh's hit-point queries
with it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..runtime.kernel_cache import install_package_stamp
from . import _unitize

install_package_stamp()  # before the first @njit (see kernel_cache)

_MAX_HITS = 100  # rounds, as trimesh's intersects_id's max_hits


@njit(cache=True)
def _advance(query, live, last_hit, origins, directions, offsets, base_offset, plane_origins,
             plane_normals, scene_origin, scene_scale):  # fmt: skip
    """One round of the multiple-hit loop, after Embree answered for the live rays.

    Mirrors trimesh's ``intersects_id``: a ray that hits the face it hit last time is a
    duplicate (its offset doubles and it moves on by it); another hit is intersected with the
    face's plane (``_planes_lines``, the same operations: a row's dot product summed left to
    right as ``np.dot`` with ones does) and the ray restarts just past it; a hit whose
    direction is parallel to the plane is dropped.

    Parameters
    ----------
    query : (L,) int ndarray
        Embree's face per live ray, -1: a miss.
    live : (L,) int64 ndarray
        The live rays.
    last_hit : (n,) int64 ndarray
        Last face hit per ray; updated in place.
    origins, directions, offsets : (n, 3) float64 ndarray
        Current origins (updated in place), unit directions, current offsets (updated).
    base_offset : float
        m.
    plane_origins, plane_normals : (f, 3) float64 ndarray
        A vertex and the unit normal of every face.
    scene_origin : (3,) float64 ndarray
    scene_scale : float
        Embree's frame: (x - scene_origin) * scene_scale, in float32.

    Returns
    -------
    rays, faces : (h,) int64 ndarray
        The hits of this round, in the order trimesh's ``intersects_id`` appends them.
    points : (h, 3) float64 ndarray
    next_live : (L',) int64 ndarray
    next_origins, next_directions : (L', 3) float32 ndarray
        The next round's rays in Embree's frame.
    """
    n_live = live.shape[0]
    ok = np.empty(n_live, dtype=np.int64)
    ok_face = np.empty(n_live, dtype=np.int64)
    dupes = np.empty(n_live, dtype=np.int64)
    n_ok = 0
    n_dupe = 0
    for a in range(n_live):
        f = query[a]
        if f == -1:
            continue
        r = live[a]
        if last_hit[r] == f:
            dupes[n_dupe] = r
            n_dupe += 1
        else:
            ok[n_ok] = r
            ok_face[n_ok] = f
            n_ok += 1
        last_hit[r] = f
    rays = np.empty(n_ok, dtype=np.int64)
    faces = np.empty(n_ok, dtype=np.int64)
    points = np.empty((n_ok, 3))
    h = 0
    for b in range(n_ok):
        r = ok[b]
        f = ok_face[b]
        ox = plane_origins[f, 0] - origins[r, 0]
        oy = plane_origins[f, 1] - origins[r, 1]
        oz = plane_origins[f, 2] - origins[r, 2]
        nx = plane_normals[f, 0]
        ny = plane_normals[f, 1]
        nz = plane_normals[f, 2]
        proj_ori = (ox * nx + oy * ny) + oz * nz
        proj_dir = (directions[r, 0] * nx + directions[r, 1] * ny) + directions[r, 2] * nz
        if not abs(proj_dir) > 1e-5:
            continue
        dist = proj_ori / proj_dir
        for c in range(3):
            points[h, c] = directions[r, c] * dist + origins[r, c]
        rays[h] = r
        faces[h] = f
        h += 1
    next_live = np.empty(h + n_dupe, dtype=np.int64)
    for b in range(h):
        r = rays[b]
        for c in range(3):
            origins[r, c] = points[b, c] + offsets[r, c]
            offsets[r, c] = directions[r, c] * base_offset
        next_live[b] = r
    for b in range(n_dupe):
        r = dupes[b]
        for c in range(3):
            offsets[r, c] *= 2.0
            origins[r, c] += offsets[r, c]
        next_live[h + b] = r
    next_origins = np.empty((h + n_dupe, 3), dtype=np.float32)
    next_directions = np.empty((h + n_dupe, 3), dtype=np.float32)
    for b in range(h + n_dupe):
        r = next_live[b]
        for c in range(3):
            next_origins[b, c] = np.float32((origins[r, c] - scene_origin[c]) * scene_scale)
            next_directions[b, c] = np.float32(directions[r, c])
    return rays[:h], faces[:h], points[:h], next_live, next_origins, next_directions


@njit(cache=True)
def _still_near(live, o32, d32, origins, start, directions, reach, slack, scene_scale):
    """The live rays that now start within ``reach`` of where they started, and how far
    Embree is to search along each (to ``reach`` + ``slack``, in the scene's units)."""
    n = live.shape[0]
    keep = np.empty(n, dtype=np.int64)
    gone = np.empty(n)
    k = 0
    for a in range(n):
        r = live[a]
        g = 0.0
        for c in range(3):
            g += (origins[r, c] - start[r, c]) * directions[r, c]
        if g < reach:
            keep[k] = a
            gone[k] = g
            k += 1
    out_live = np.empty(k, dtype=np.int64)
    out_o = np.empty((k, 3), dtype=np.float32)
    out_d = np.empty((k, 3), dtype=np.float32)
    limits = np.empty(k, dtype=np.float32)
    for b in range(k):
        a = keep[b]
        out_live[b] = live[a]
        out_o[b] = o32[a]
        out_d[b] = d32[a]
        limits[b] = np.float32((reach - gone[b] + slack) * scene_scale)
    return out_live, out_o, out_d, limits


def crossings(rays, origins, directions, reach: float | None = None, max_hits: int = _MAX_HITS):
    """Every hit of every ray, as trimesh's ``intersects_id(..., multiple_hits=True,
    return_locations=True)`` returns them (same faces, points and order); with ``reach``,
    those within ``reach`` of each ray's origin and each ray's first wherever it is.

    With ``reach``, a ray is followed past a crossing only while that crossing lies within
    ``reach``, and from then on Embree searches no farther than ``reach`` (plus 0.1 %): the
    crossings within ``reach`` and the first one are the same (faces, points, order) as
    without, in fewer rounds when rays go on far past the ball they are cast for (a mug's
    rays cross its far wall: 1.5 rounds per ray instead of 2.65).

    Parameters
    ----------
    rays : affordgrasp.rays.mesh.EmbreeRays
        The mesh's ray caster.
    origins, directions : (n, 3) float64 array_like
        m; directions need not be unit.
    reach : float, optional
        m, > 0.
    max_hits : int
        Most hits per ray (trimesh's default); 1 gives trimesh's first hits
        (``multiple_hits=False``).

    Returns
    -------
    index_tri, index_ray : (m,) int64 ndarray
        Face and ray of each hit (with ``reach``: every one within it, each ray's first, and
        perhaps a few more within 0.1 % beyond).
    locations : (m, 3) float64 ndarray
        m.
    """
    reach = None if reach is None else float(reach)
    start = np.asarray(origins, dtype=np.float64)
    origins = start.copy()
    directions = np.array(directions, dtype=np.float64)
    if origins.shape != directions.shape:
        raise ValueError("Ray origin and direction don't match!")
    directions = _unitize(directions)  # as trimesh's loop
    base_offset = rays.ray_offset
    offsets = directions * base_offset
    plane_origins, plane_normals = rays.face_planes
    scene_origin, scene_scale = rays.scene_frame
    last_hit = np.full(len(origins), -1, dtype=np.int64)
    live = np.arange(len(origins), dtype=np.int64)
    o32, d32 = rays.to_scene(origins, directions)
    limits = None
    tris = [np.zeros(0, dtype=np.int64)]
    idx = [np.zeros(0, dtype=np.int64)]
    locs = [np.zeros((0, 3), dtype=np.float64)]
    for _depth in range(max_hits):
        query = rays.first_faces_scene(o32, d32, limits)
        if not (query != -1).any():
            break
        hit_rays, hit_tris, points, live, o32, d32 = _advance(
            query, live, last_hit, origins, directions, offsets, base_offset, plane_origins,
            plane_normals, scene_origin, scene_scale,
        )  # fmt: skip
        tris.append(hit_tris)
        idx.append(hit_rays)
        locs.append(points)
        if reach is not None:
            live, o32, d32, limits = _still_near(live, o32, d32, origins, start, directions,
                                                 reach, 1e-3 * reach, scene_scale)  # fmt: skip
            if not len(live):
                break
    return np.concatenate(tris), np.concatenate(idx), np.concatenate(locs)
