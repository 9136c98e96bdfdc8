"""The solid in a ball at U, from rays: wedge angle, edge span, edge thickness, for real tools.

The measures a cutting edge is told by, at a physical scale and independent of the
triangles (conventions: Metrics): rays from U over a sphere of directions give the part of
a 3 mm (and a 2 mm) ball inside the solid, its opening angle (:func:`use_wedge_angle`), how
the inside directions spread along an edge (:func:`use_edge_span`), and chords behind U its
thickness there (:func:`use_edge_thickness`); :func:`use_wedge_shape` gives all of them from
one cast. Validated in ``tests/metrics/test_wedge.py`` (prisms of known opening, a tip, a
plate's corner and end, each also after a scanner); calibrated with
``studies/calibrate_wedge_angle.py``. The sharpest mesh edge near U: :mod:`.edges`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import InputError
from ..rays.mesh import MeshCaster, mesh_caster
from ..runtime.kernel_cache import install_package_stamp
from .validation import points_n3, positive_length, use_normals_n3

install_package_stamp()  # before the first @njit (see kernel_cache)

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
    mesh, use_point, use_normal, radius, directions
        As for :func:`use_wedge_shape`.

    Returns
    -------
    float or (n,) float64 ndarray
        rad, in [0, 2π]; a float for a single point.
    """
    return _one_measure("angle", mesh, use_point, use_normal, radius=radius, directions=directions)


def _one_measure(field: str, mesh, use_point, use_normal, **kwargs) -> float | np.ndarray:
    """One field of :func:`use_wedge_shape`'s result; a float for a single point."""
    values = getattr(use_wedge_shape(mesh, use_point, use_normal, **kwargs), field)
    return float(values[0]) if np.ndim(use_point) == 1 else values


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
    radius = positive_length(radius, "radius")
    inner_radius = positive_length(inner_radius, "inner_radius")
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
    return _one_measure("span", mesh, use_point, use_normal, **kwargs)


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
    return _one_measure("edge_thickness", mesh, use_point, use_normal, **kwargs)


EDGE_FRAME_DIRECTIONS = 2048  # rays per point of use_edge_frame (256: directions off by 4°)


def use_edge_frame(
    mesh,
    use_point,
    use_normal,
    *,
    radius: float = WEDGE_RADIUS_M,
    directions: int = EDGE_FRAME_DIRECTIONS,
) -> tuple[np.ndarray, np.ndarray]:
    """The direction an edge at U presses along and the edge's direction, at a physical scale.

    From the rays of :func:`use_wedge_shape`: ``outward`` is minus the inside-weighted mean
    ray direction in the ball (the bisector of a wedge's flanks, out of the solid; the
    face normal on a flat face, where a mesh edge's triangle gives only its flank's
    normal), and ``along`` is square to it and to the direction of least inside weight
    (across a blade): the edge line's direction on a wedge, any direction square to
    ``outward`` on a flat face. Where no ray is inside, ``outward`` is ``use_normal`` and
    ``along`` any direction square to it. Signs: ``along`` is arbitrary. On a 20° wedge
    (``tests/metrics/test_wedge.py``) both are within a degree or two of the bisector
    and the apex line with 2048 rays; 256 rays, enough for the wedge angle, leave the
    directions 4–5° off.

    Parameters
    ----------
    mesh, use_point, use_normal, radius
        As for :func:`use_wedge_shape`.
    directions : int
        Rays per point (default :data:`EDGE_FRAME_DIRECTIONS`).

    Returns
    -------
    outward : (n, 3) float64 ndarray
        Unit vectors.
    along : (n, 3) float64 ndarray
        Unit vectors square to ``outward``.
    """
    P = points_n3(use_point, "use_point")
    N = use_normals_n3(use_normal, P)
    rays = mesh_caster(mesh)
    k = int(directions)
    S = _fibonacci_sphere(k)
    outer = np.einsum("ki,kj->kij", S, S).reshape(k, 9)
    outward, along = N.copy(), np.empty_like(N)
    chunk = max(1, 65536 // k)
    for first in range(0, len(P), chunk):
        sl = slice(first, first + chunk)
        m = len(P[sl])
        origins = np.repeat(P[sl] - _WEDGE_START_M * N[sl], k, axis=0)
        ray, t, leaving = _near_crossing_distances(rays, origins, np.tile(S, (m, 1)), radius)
        w = _ball_weights(ray, t, radius, radius, leaving)[0].reshape(m, k)
        into = np.einsum("mk,kq->mq", w, S)
        norm = np.linalg.norm(into, axis=1)
        ok = norm > 1e-3 * np.maximum(w.sum(axis=1), np.finfo(float).tiny)
        outward[sl][ok] = -into[ok] / norm[ok, None]
        moment = np.einsum("mk,kq->mq", w, outer).reshape(m, 3, 3)
        across = np.linalg.eigh(moment)[1][:, :, 0]
        along[sl] = np.cross(across, outward[sl])
    # across parallel to outward (a flat face's degenerate moment): any square direction
    norm = np.linalg.norm(along, axis=1)
    bad = norm < 1e-6
    if bad.any():
        helper = np.where(np.abs(outward[bad, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        along[bad] = np.cross(outward[bad], helper)
        norm[bad] = np.linalg.norm(along[bad], axis=1)
    return outward, along / norm[:, None]


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
