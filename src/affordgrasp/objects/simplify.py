"""Large scans made small: quadric decimation checked against a stated geometric tolerance.

A scan of 0.1-2 M triangles is far finer than what grasp simulation resolves (surface samples
1.4 mm apart, see ``objects.surface``), and its preparation (repair, surface samples, caches)
grows with its size. :func:`simplify_to_tolerance` decimates it with ``fast-simplification``
(Fast-Quadric-Mesh-Simplification) and then *measures* how far the original surface lies from
the simplified one, so the result comes with a number, not a hope:

* the distance is one-sided, from the original's vertices (a seeded sample of at most
  ``DISTANCE_SAMPLES`` of them) to the simplified surface;
* each point's distance is first bounded by the ``NEIGHBOURS`` simplified triangles whose
  centroids are nearest (an upper bound of the true point-to-surface distance); the points
  whose bound exceeds the tolerance (at most ``REFINED``) get their exact distance. The
  reported maximum is exact when no more than ``REFINED`` points needed refining, and can
  otherwise only overstate the error.

One costly pass takes the mesh to ``FIRST_FACES`` triangles (a second one, from the original,
to ``MAX_FACES`` only when that misses the tolerance); cheaper passes then halve it while the
measured distance stays within the tolerance. A mesh that misses the tolerance even at
``MAX_FACES`` is kept at that size and the warning says so, with the distance. Going to
``FIRST_FACES`` in one pass rather than through ``MAX_FACES`` saves a pass and a distance
check on the common scan (2 M triangles: 10.0 -> see benchmarks/RESULTS.md). Validated
(tests) against trimesh's exact closest points and on a sphere and a torus, whose volumes
are known.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

log = logging.getLogger(__name__)

__all__ = [
    "LARGE_MESH_FACES",
    "SIMPLIFY_TOLERANCE_M",
    "Simplification",
    "simplify_to_tolerance",
    "surface_distance_bound",
]

# Meshes with more triangles than this are simplified on load (objects.loading.prepare_mesh).
LARGE_MESH_FACES = 200_000
# The geometric tolerance of that simplification, m (one-sided distance, see above).
SIMPLIFY_TOLERANCE_M = 1e-4
# The first pass decimates to FIRST_FACES triangles (or half the mesh); if that misses the
# tolerance, one pass from the original to MAX_FACES; then halves while the tolerance holds,
# down to MIN_FACES (still finer than 1.4 mm samples on a hand-held tool).
FIRST_FACES = 200_000
MAX_FACES = 400_000
MIN_FACES = 25_000
DISTANCE_SAMPLES = 20_000
NEIGHBOURS = 8
REFINED = 4096  # points whose distance is computed exactly (those with the largest bounds)


@dataclass(frozen=True)
class Simplification:
    """What a simplification did, for the load warning and the dataset card.

    Attributes
    ----------
    faces_before, faces_after : int
        Triangle counts.
    tolerance : float
        The stated tolerance, in the mesh's units.
    distance : float
        The measured one-sided distance (maximum over the sampled vertices), same units.
    sampled : int
        How many original vertices the distance was measured at.
    """

    faces_before: int
    faces_after: int
    tolerance: float
    distance: float
    sampled: int

    @property
    def within_tolerance(self) -> bool:
        """Whether the measured distance is within the stated tolerance."""
        return bool(self.distance <= self.tolerance)


def surface_distance_bound(
    points: np.ndarray,
    vertices: np.ndarray,
    faces: np.ndarray,
    neighbours: int = NEIGHBOURS,
    exact_above: float | None = None,
) -> np.ndarray:
    """An upper bound of each point's distance to a triangle mesh's surface; exact where large.

    First the smallest exact point-triangle distance over the ``neighbours`` triangles whose
    centroids are nearest the point (scipy k-d tree, then trimesh's vectorised closest point
    on triangles): a bound u >= the true distance. Then, for the points whose bound exceeds
    ``exact_above`` (at most ``REFINED`` of them, the largest first), the exact distance:
    the triangle holding the closest point has its centroid within u + R of the point, R
    the largest centroid-to-corner distance, so every such triangle is tried.

    Parameters
    ----------
    points : (n, 3) float ndarray
    vertices : (v, 3) float ndarray
    faces : (f, 3) int ndarray
    neighbours : int
        Candidate triangles per point for the bound.
    exact_above : float, optional
        Refine the points whose bound is above this (None: none).

    Returns
    -------
    (n,) float64 ndarray
        Same units as the inputs; >= the true distance, equal to it where refined.
    """
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=np.float64)
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    centroids = tri.mean(axis=1)
    tree = cKDTree(centroids)
    k = int(min(neighbours, len(tri)))
    _, nearest = tree.query(points, k=k)
    nearest = nearest.reshape(len(points), k)
    best = np.full(len(points), np.inf)
    for j in range(k):
        best = np.minimum(best, _distance_to_triangles(tri[nearest[:, j]], points))
    if exact_above is None:
        return best
    flagged = np.flatnonzero(best > exact_above)
    flagged = flagged[np.argsort(-best[flagged], kind="stable")][:REFINED]
    if not len(flagged):
        return best
    reach = float(np.max(np.linalg.norm(tri - centroids[:, None, :], axis=2)))
    for chunk in np.array_split(flagged, max(1, len(flagged) // 256)):
        lists = tree.query_ball_point(points[chunk], best[chunk] + reach)
        counts = np.array([len(c) for c in lists])
        owner = np.repeat(np.arange(len(chunk)), counts)
        cand = np.concatenate([np.asarray(c, dtype=np.int64) for c in lists])
        d = _distance_to_triangles(tri[cand], points[chunk][owner])
        exact = np.full(len(chunk), np.inf)
        np.minimum.at(exact, owner, d)
        best[chunk] = np.minimum(best[chunk], exact)
    return best


def _distance_to_triangles(tri: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance of each point to its triangle, (n, 3, 3) and (n, 3) -> (n,), scale-free.

    trimesh's ``closest_point`` compares squared lengths with an absolute epsilon (1e-12),
    so on sub-millimetre triangles in metres it takes regular triangles for degenerate ones
    and answers distances hundreds of times too large. Each pair is therefore moved to its
    triangle's first corner and scaled by its longest side before the call.
    """
    from trimesh.triangles import closest_point

    origin = tri[:, 0]
    size = np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2).max(axis=1)
    size = np.where(size > 0, size, 1.0)
    unit = (tri - origin[:, None, :]) / size[:, None, None]
    local = (points - origin) / size[:, None]
    on = closest_point(unit, local)
    return np.linalg.norm(on - local, axis=1) * size


def simplify_to_tolerance(
    vertices: np.ndarray,
    faces: np.ndarray,
    tolerance: float,
    *,
    max_faces: int | None = None,
    min_faces: int = MIN_FACES,
) -> tuple[np.ndarray, np.ndarray, Simplification]:
    """Decimate a mesh to the fewest triangles tried whose measured distance is within tolerance.

    The mesh is decimated once to ``FIRST_FACES`` triangles (the costly pass over the full
    mesh; ``max_faces`` if fewer) and, only if that misses the tolerance, once more from the
    original to ``max_faces``; then halved again and again (each pass cheaper than the one
    before) while the distance, always measured from the original's vertices, stays within
    ``tolerance`` and the count above ``min_faces``.

    Parameters
    ----------
    vertices : (v, 3) float ndarray
        Any units.
    faces : (f, 3) int ndarray
        An indexed mesh (shared vertices; a triangle soup cannot be decimated).
    tolerance : float
        Largest accepted one-sided distance, in the units of ``vertices``.
    max_faces : int, optional
        The most triangles kept; default ``MAX_FACES`` or half the mesh's, if fewer.
    min_faces : int
        No pass goes below this.

    Returns
    -------
    vertices : (v', 3) float64 ndarray
    faces : (f', 3) int64 ndarray
    report : Simplification
        ``report.within_tolerance`` is False when even ``max_faces`` triangles missed it
        (that result is returned, with the distance measured).
    """
    import fast_simplification

    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    cap = int(max_faces or min(MAX_FACES, len(faces) // 2))
    if cap >= len(faces) or cap < 4:
        return vertices, faces, Simplification(len(faces), len(faces), float(tolerance), 0.0, 0)
    rng = np.random.default_rng(0)
    mask = np.zeros(len(vertices), dtype=bool)
    mask[faces.ravel()] = True  # np.unique would sort: seconds on a scan
    used = np.flatnonzero(mask)
    sample = used if len(used) <= DISTANCE_SAMPLES else rng.choice(used, DISTANCE_SAMPLES, False)
    points = vertices[np.sort(sample)]

    def attempt(v, f, target):
        v, f = fast_simplification.simplify(v, f, target_count=target)
        v = np.ascontiguousarray(v, dtype=np.float64)
        f = np.ascontiguousarray(f, dtype=np.int64)
        distance = float(surface_distance_bound(points, v, f, exact_above=tolerance).max())
        log.debug("simplified %d -> %d triangles: distance %.3g", len(faces), len(f), distance)
        return v, f, Simplification(len(faces), len(f), float(tolerance), distance, len(points))

    best = attempt(vertices, faces, min(FIRST_FACES, cap))
    if not best[2].within_tolerance and len(best[1]) < cap:
        return attempt(vertices, faces, cap)
    while best[2].within_tolerance and len(best[1]) // 2 >= min_faces:
        smaller = attempt(best[0], best[1], len(best[1]) // 2)
        if not smaller[2].within_tolerance:
            break
        best = smaller
    return best
