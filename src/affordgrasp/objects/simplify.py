"""Large scans made small: quadric decimation checked against a stated geometric tolerance.

A scan of 0.1-2 M triangles is far finer than what grasp simulation resolves (surface samples
1.4 mm apart, see ``grasp.surface``), and its preparation (repair, surface samples, caches)
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

If the measured distance exceeds the tolerance, the decimation is redone with twice as many
triangles (at most ``ATTEMPTS`` times). Validated on analytic shapes (tests): a sphere and a
torus of 0.3 M+ triangles, whose true distance to the simplified mesh is known from the radii.
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
# The first target: half the threshold, far above what 1.4 mm surface samples resolve.
TARGET_FACES = 100_000
DISTANCE_SAMPLES = 50_000
NEIGHBOURS = 8
REFINED = 4096  # points whose distance is computed exactly (those with the largest bounds)
ATTEMPTS = 3


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
    from trimesh.triangles import closest_point

    points = np.asarray(points, dtype=np.float64)
    tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    centroids = tri.mean(axis=1)
    tree = cKDTree(centroids)
    k = int(min(neighbours, len(tri)))
    _, nearest = tree.query(points, k=k)
    nearest = nearest.reshape(len(points), k)
    best = np.full(len(points), np.inf)
    for j in range(k):
        on = closest_point(tri[nearest[:, j]], points)
        best = np.minimum(best, np.linalg.norm(on - points, axis=1))
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
        on = closest_point(tri[cand], points[chunk][owner])
        d = np.linalg.norm(on - points[chunk][owner], axis=1)
        exact = np.full(len(chunk), np.inf)
        np.minimum.at(exact, owner, d)
        best[chunk] = np.minimum(best[chunk], exact)
    return best


def simplify_to_tolerance(
    vertices: np.ndarray,
    faces: np.ndarray,
    tolerance: float,
    *,
    target_faces: int | None = None,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, Simplification]:
    """Decimate a mesh until the measured distance is within ``tolerance`` (or tries run out).

    Parameters
    ----------
    vertices : (v, 3) float ndarray
        Any units.
    faces : (f, 3) int ndarray
        An indexed mesh (shared vertices; a triangle soup cannot be decimated).
    tolerance : float
        Largest accepted one-sided distance, in the units of ``vertices``.
    target_faces : int, optional
        Triangles of the first attempt, doubled on each retry; default ``TARGET_FACES``,
        or a quarter of the mesh's when that is fewer.
    seed : int
        Chooses the sampled vertices (same seed, same result).

    Returns
    -------
    vertices : (v', 3) float64 ndarray
    faces : (f', 3) int64 ndarray
    report : Simplification
        ``report.within_tolerance`` is False when the last attempt still missed it.
    """
    import fast_simplification

    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    rng = np.random.default_rng(seed)
    used = np.unique(faces)
    sample = used if len(used) <= DISTANCE_SAMPLES else rng.choice(used, DISTANCE_SAMPLES, False)
    points = vertices[np.sort(sample)]
    target = int(target_faces or min(TARGET_FACES, len(faces) // 4))
    best = None
    for _ in range(ATTEMPTS):
        if target >= len(faces):
            break
        v, f = fast_simplification.simplify(vertices, faces, target_count=target)
        v = np.asarray(v, dtype=np.float64)
        f = np.asarray(f, dtype=np.int64)
        distance = float(surface_distance_bound(points, v, f, exact_above=tolerance).max())
        report = Simplification(len(faces), len(f), float(tolerance), distance, len(points))
        log.debug("simplified %d -> %d triangles: distance %.3g", len(faces), len(f), distance)
        best = (v, f, report)
        if report.within_tolerance:
            break
        target *= 2
    if best is None:  # already as small as the target: nothing to do
        report = Simplification(len(faces), len(faces), float(tolerance), 0.0, 0)
        return vertices, faces, report
    return best
