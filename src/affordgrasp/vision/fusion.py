"""The object as the camera in the hand saw it: depth images fused into a closed surface
(conventions: Vision).

A robot that looks at an object from several pregrasps knows, for every pixel of every
view, that the space between the camera and the first return is empty. Fusing the views
carves that free space out of a voxel grid around what was seen; what no view saw through
is kept as solid (space carving with depth, Kutulakos & Seitz 2000; a free-space field as in
KinectFusion's TSDF, Newcombe et al. 2011). The surface is the field's zero level,
extracted by marching cubes (scikit-image, the ``learn`` extra) as a closed mesh the
simulator can grasp: :mod:`affordgrasp.learning.plan` chooses among candidate grasps by
simulating them on it (``plan --model views``), with no access to the true mesh.

**The field.** For a voxel centre x and a view i whose image x projects into (in front of
the camera), ``f_i(x) = D̃_i(pixel) − z_i(x)``: the observed depth minus x's depth along the
optical axis, clipped to [−τ, τ] (τ = :data:`TRUNCATION_VOXELS` voxels), +τ where the pixel
has no return (the ray met nothing). ``D̃_i`` is the nearest of the four pixels around x's
projection where all four returned (``subpixel``), and elsewhere (a silhouette, a lost
return) the image after a minimum filter over (2r + 1)² pixels around the nearest pixel
(r = ``dilate_px``, no return counted as infinitely far): a voxel is carved only when it
lies in front of every nearby return, so a silhouette or a surface seen at a grazing angle
is not eaten by the rounding of its projection to one pixel. The field is the
``votes``-th largest ``f_i`` over the views that see x (+τ where fewer views see it): a
voxel is free when at least ``votes`` views see past it, so one view's error cannot cut a
thin blade in two. Solid is ``field < 0``; every voxel that holds a return of some view is
kept solid (``keep_seen``: its value at most −:data:`SEEN_SOLID_VOXELS` voxel, after the
smoothing of :func:`field_surface`), so a blade thinner than a voxel, whose voxel centres
may all lie outside it, is not melted away.

**Measured** (64 views at ``plan``'s pregrasps, 1 mm voxels, grown on the largest tools;
docs/learning.md): the 3 × 3 filter everywhere put the fused surface 0.8 mm (median)
outside the true one on knives, daggers, cleavers and spatulas, 1.5-2 mm on an axe and a
sword (larger voxels), and thickened blades by that much on each side; the four pixels and
the seen voxels bring it to 0.1-0.5 mm. With r = 0 or one vote, thin blades break into
pieces.

Validated against known geometry: a box and a sphere seen from many pregrasps are
recovered within a voxel (``tests/vision/test_fusion.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from ..errors import InputError, require
from ..runtime.kernel_cache import install_package_stamp
from .camera import DepthCamera

install_package_stamp()  # before the first @njit (see kernel_cache)

VOXEL_M = 1e-3  # the grid's finest voxel, m (a pixel of the camera is 0.8-5 mm on an object)
MAX_VOXELS = 2_000_000  # the grid grows its voxels beyond this many (memory and time)
VOTES = 2  # views that must see past a voxel to carve it
DILATE_PX = 1  # the minimum filter's radius, pixels
TRUNCATION_VOXELS = 3.0  # the field is clipped to ± this many voxels
SMOOTH_VOXELS = 0.6  # Gaussian σ of the field before marching cubes, voxels
SEEN_SOLID_VOXELS = 0.1  # a voxel holding a return has a field value <= -this, voxels
MARGIN_VOXELS = 3  # empty voxels around the seen points
RETRY_SMOOTH_VOXELS = (1.0, 1.5)  # smoother fields tried when a surface is not closed


@dataclass(frozen=True)
class FreeSpaceField:
    """The fused views on a voxel grid: solid where ``values < 0``.

    Attributes
    ----------
    values : (nx, ny, nz) float64 ndarray
        The field at the voxel centres, m, in [−τ, τ].
    origin : (3,) float64 ndarray
        Centre of voxel (0, 0, 0), object frame, m.
    voxel_m : float
        Voxel edge, m.
    seen : (nx, ny, nz) bool ndarray or None
        Voxels that hold a return of some view: :func:`field_surface` keeps them solid
        (None: nothing is kept).
    """

    values: np.ndarray
    origin: np.ndarray
    voxel_m: float
    seen: np.ndarray | None = None


@njit(cache=True, nogil=True)
def _carve(origin, voxel, dims, raw, depth, rot, trans, focal, cx, cy, trunc, votes, out):
    # One pass over voxels × views: numpy would hold an (voxels × views) array (2e6 × 64
    # doubles, 1 GB); this keeps the `votes` largest values of each voxel only. `depth` is
    # the minimum-filtered image (-1: unknown), `raw` the image itself, or an empty array
    # for the filtered image everywhere (no sub-pixel rule).
    n, h, w = depth.shape
    subpixel = raw.shape[0] == n
    top = np.empty(votes)
    for a in range(dims[0]):
        x = origin[0] + voxel * a
        for b in range(dims[1]):
            y = origin[1] + voxel * b
            for c in range(dims[2]):
                z = origin[2] + voxel * c
                top[:] = -np.inf
                seen = 0
                for i in range(n):
                    px = x - trans[i, 0]
                    py = y - trans[i, 1]
                    pz = z - trans[i, 2]
                    qz = px * rot[i, 0, 2] + py * rot[i, 1, 2] + pz * rot[i, 2, 2]
                    if qz <= 1e-9:
                        continue
                    qx = px * rot[i, 0, 0] + py * rot[i, 1, 0] + pz * rot[i, 2, 0]
                    qy = px * rot[i, 0, 1] + py * rot[i, 1, 1] + pz * rot[i, 2, 1]
                    fu = cx + focal * qx / qz
                    fv = cy + focal * qy / qz
                    u = np.floor(fu + 0.5)
                    v = np.floor(fv + 0.5)
                    if u < 0 or u >= w or v < 0 or v >= h:
                        continue
                    d = depth[i, int(v), int(u)]
                    if d < 0.0:
                        continue  # unknown: a lost return near the surface
                    if subpixel:
                        # the four pixels around the projection: where all returned, the
                        # nearest of them (the filter's 3 x 3 reaches a pixel further)
                        u0 = int(np.floor(fu))
                        v0 = int(np.floor(fv))
                        if u0 >= 0 and v0 >= 0 and u0 + 1 < w and v0 + 1 < h:
                            near = min(
                                min(raw[i, v0, u0], raw[i, v0, u0 + 1]),
                                min(raw[i, v0 + 1, u0], raw[i, v0 + 1, u0 + 1]),
                            )
                            if near > 0.0:
                                d = near
                    seen += 1
                    val = trunc if d == 0.0 else min(d - qz, trunc)
                    if val > top[votes - 1]:
                        j = votes - 1
                        while j > 0 and top[j - 1] < val:
                            top[j] = top[j - 1]
                            j -= 1
                        top[j] = val
                        if top[votes - 1] >= trunc:
                            break  # free whatever the other views say
                best = top[votes - 1] if seen >= votes else trunc
                out[a, b, c] = max(best, -trunc)


def require_marching_cubes():
    """scikit-image's ``marching_cubes``, or a MissingDependencyError naming the extra.

    Returns
    -------
    callable
    """
    return require("skimage.measure", "learn").marching_cubes


def _check_views(depth, poses, camera: DepthCamera) -> tuple[np.ndarray, np.ndarray]:
    depth = np.asarray(depth, dtype=np.float64)
    poses = np.asarray(poses, dtype=np.float64)
    if depth.ndim != 3 or depth.shape[1:] != (camera.size, camera.size):
        raise InputError(
            f"depth images must have shape (n, {camera.size}, {camera.size}) for this camera, "
            f"got {depth.shape}"
        )
    if poses.shape != (len(depth), 4, 4):
        raise InputError(
            f"need one camera pose (4, 4) per depth image ({len(depth)}), got {poses.shape}"
        )
    if not (np.isfinite(depth).all() and np.isfinite(poses).all()):
        raise InputError("depth images and camera poses must be finite (0 = no return)")
    if (depth < 0).any():
        raise InputError("depth must be >= 0 m (0 = no return)")
    return depth, poses


def seen_points(depth, poses, camera: DepthCamera | None = None) -> np.ndarray:
    """Every return of every view as an object-frame point.

    Parameters
    ----------
    depth : (n, size, size) float array_like
        Depth along the optical axis, m; 0 = no return.
    poses : (n, 4, 4) float array_like
        Camera → object transforms, m.
    camera : DepthCamera, optional
        The intrinsics (default: the camera in the hand).

    Returns
    -------
    (k, 3) float64 ndarray
        m.
    """
    camera = camera or DepthCamera()
    depth, poses = _check_views(depth, poses, camera)
    rays = camera.ray_directions()
    points = []
    for image, pose in zip(depth, poses, strict=True):
        hit = image > 0
        local = rays[hit] * image[hit][:, None]
        points.append(local @ pose[:3, :3].T + pose[:3, 3])
    return np.concatenate(points) if points else np.zeros((0, 3))


def free_space_field(
    depth,
    poses,
    camera: DepthCamera | None = None,
    *,
    voxel_m: float = VOXEL_M,
    votes: int = VOTES,
    dilate_px: int = DILATE_PX,
    max_voxels: int = MAX_VOXELS,
    unknown_px: int = 0,
    subpixel: bool = True,
    keep_seen: bool = True,
) -> FreeSpaceField:
    """Fuse depth images into a free-space field (the module docstring defines it).

    Parameters
    ----------
    depth : (n, size, size) float array_like
        Depth along the optical axis, m; 0 = no return.
    poses : (n, 4, 4) float array_like
        Camera → object transforms of the views, m.
    camera : DepthCamera, optional
        The intrinsics (default: the camera in the hand).
    voxel_m : float
        The finest voxel edge, m; grown when the seen points' box would need more than
        ``max_voxels`` voxels.
    votes : int
        Views that must see past a voxel to carve it (>= 1).
    dilate_px : int
        Radius of the minimum filter over each image, pixels (>= 0).
    max_voxels : int
        The most voxels of the grid.
    unknown_px : int
        Pixels without a return within this many pixels of a return say nothing (the
        view is skipped there) instead of "empty all along the ray": a real sensor loses
        returns where the surface is seen at a grazing angle, next to what it saw (0, the
        default: every pixel without a return is empty space, as in an exact image).
    subpixel : bool
        Where the four pixels around a voxel's projection all returned, read the nearest
        of them instead of the minimum filter's (2r + 1)² (True, the default; False: the
        filter everywhere).
    keep_seen : bool
        Mark the voxels that hold a return as seen, which :func:`field_surface` keeps
        solid (True, the default). Meant for exact images: with a sensor's noise, stray
        returns become solid specks and can join sheets that the smoother retries of
        :func:`fused_object` cannot part (``plan`` turns it off with a sensor model).

    Returns
    -------
    FreeSpaceField

    Raises
    ------
    InputError
        For images or poses of the wrong shape, non-finite values, bad options, or views
        that saw nothing.
    """
    from scipy.ndimage import maximum_filter, minimum_filter

    camera = camera or DepthCamera()
    depth, poses = _check_views(depth, poses, camera)
    if isinstance(votes, bool) or not isinstance(votes, int | np.integer) or votes < 1:
        raise InputError(f"votes must be an integer >= 1, got {votes!r}")
    for name, value in (("dilate_px", dilate_px), ("unknown_px", unknown_px)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
            raise InputError(f"{name} must be an integer >= 0, got {value!r}")
    if not (np.isfinite(voxel_m) and voxel_m > 0):
        raise InputError(f"voxel_m must be a positive length in metres, got {voxel_m!r}")
    if isinstance(max_voxels, bool) or not isinstance(max_voxels, int) or max_voxels < 1000:
        raise InputError(f"max_voxels must be an integer >= 1000, got {max_voxels!r}")
    points = seen_points(depth, poses, camera)
    if len(points) == 0:
        raise InputError(
            "no view saw the object (every pixel is 0): nothing to fuse; aim the views at it"
        )
    low, high = points.min(axis=0), points.max(axis=0)

    def grid_dims(edge: float) -> np.ndarray:
        return np.ceil((high - low) / edge).astype(np.int64) + 2 * MARGIN_VOXELS + 1

    voxel = float(voxel_m)
    while np.prod(grid_dims(voxel)) > max_voxels:
        voxel *= 1.1
    origin = low - MARGIN_VOXELS * voxel
    dims = grid_dims(voxel)
    returned = depth > 0
    raw = depth
    if dilate_px > 0:
        far = np.where(returned, depth, np.inf)
        far = minimum_filter(far, size=(1, 2 * dilate_px + 1, 2 * dilate_px + 1), mode="nearest")
        depth = np.where(np.isinf(far), 0.0, far)
    if unknown_px > 0:
        width = 2 * unknown_px + 1
        near = maximum_filter(returned, size=(1, width, width), mode="constant")
        depth = np.where((depth == 0) & near, -1.0, depth)  # the kernel skips -1
    out = np.empty(tuple(int(d) for d in dims), dtype=np.float64)
    cx, cy = camera.principal_point
    _carve(
        origin,
        voxel,
        dims,
        np.ascontiguousarray(raw) if subpixel else np.zeros((0, 1, 1)),
        np.ascontiguousarray(depth),
        np.ascontiguousarray(poses[:, :3, :3]),
        np.ascontiguousarray(poses[:, :3, 3]),
        float(camera.focal_px),
        float(cx),
        float(cy),
        TRUNCATION_VOXELS * voxel,
        int(votes),
        out,
    )
    seen = None
    if keep_seen:
        index = np.floor((points - origin) / voxel + 0.5).astype(np.int64)
        seen = np.zeros(out.shape, dtype=bool)
        seen[index[:, 0], index[:, 1], index[:, 2]] = True
    return FreeSpaceField(out, origin, voxel, seen)


def field_surface(field: FreeSpaceField, *, smooth_voxels: float = SMOOTH_VOXELS):
    """The closed surface of a field's solid (its largest connected piece).

    Parameters
    ----------
    field : FreeSpaceField
    smooth_voxels : float
        Gaussian σ applied to the field first, voxels (0: none). Smoothing removes the
        single-voxel pinches where marching cubes would join two sheets at a vertex. The
        field's seen voxels are then made solid: their value at most
        −:data:`SEEN_SOLID_VOXELS` voxel.

    Returns
    -------
    trimesh.Trimesh
        Closed, outward-oriented, object frame, m.

    Raises
    ------
    InputError
        When the field holds no solid.
    MissingDependencyError
        When scikit-image (the ``learn`` extra) is missing.
    """
    import trimesh
    from scipy.ndimage import gaussian_filter

    marching_cubes = require_marching_cubes()
    values = field.values
    if smooth_voxels > 0:
        values = gaussian_filter(values, float(smooth_voxels), mode="nearest")
    if field.seen is not None:  # after smoothing, which would melt a blade thinner than a voxel
        values = np.where(
            field.seen, np.minimum(values, -SEEN_SOLID_VOXELS * field.voxel_m), values
        )
    if not (values < 0).any():
        raise InputError("the fused views hold no solid: no view saw a surface to keep")
    # A border of free space closes the surface where the solid meets the grid's edge.
    padded = np.pad(-values, 1, constant_values=-float(field.values.max()))
    vertices, faces, _, _ = marching_cubes(padded, level=0.0, spacing=(field.voxel_m,) * 3)
    vertices = vertices + field.origin - field.voxel_m
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    pieces = mesh.split(only_watertight=False)
    if len(pieces) > 1:  # specks carved loose from the solid's edge
        mesh = max(pieces, key=lambda piece: len(piece.faces))
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def fuse_views(
    depth, poses, camera: DepthCamera | None = None, *, smooth_voxels=SMOOTH_VOXELS, **carving
):
    """The surface of an object from depth images of it (:func:`free_space_field`, then
    :func:`field_surface`).

    Parameters
    ----------
    depth, poses, camera
        The views, as for :func:`free_space_field`.
    smooth_voxels : float
        See :func:`field_surface`.
    **carving
        Options of :func:`free_space_field` (``voxel_m``, ``votes``, ``dilate_px``,
        ``max_voxels``, ``unknown_px``, ``subpixel``, ``keep_seen``).

    Returns
    -------
    trimesh.Trimesh
        Closed, outward-oriented, object frame, m.
    """
    field = free_space_field(depth, poses, camera, **carving)
    return field_surface(field, smooth_voxels=smooth_voxels)


def fused_object(
    depth,
    poses,
    camera: DepthCamera | None = None,
    *,
    name: str = "fused views",
    smooth_voxels: float = SMOOTH_VOXELS,
    **carving,
):
    """The object as the views saw it, ready to be grasped in simulation.

    Parameters
    ----------
    depth, poses, camera
        The views, as for :func:`free_space_field`.
    name : str
        The object's name.
    smooth_voxels : float
        See :func:`field_surface` (the first try).
    **carving
        Options of :func:`free_space_field`.

    Returns
    -------
    GraspObject
        In the views' object frame, unit density; its derived geometry is kept in memory
        only (``source`` is :data:`~affordgrasp.objects.prepared.TRANSIENT_SOURCE`). When
        the surface is not a closed volume even after the loader's repairs, the field
        without its seen voxels is tried (smoothing cannot part two sheets they join),
        then smoother fields (σ in :data:`RETRY_SMOOTH_VOXELS`).

    Raises
    ------
    InputError
        When no field gives a closed surface, or for bad views (see
        :func:`free_space_field`).
    """
    from ..errors import MeshError
    from ..objects import object_from_mesh

    field = free_space_field(depth, poses, camera, **carving)
    # Two sheets of a thin, noisy wall can meet along an edge that no repair closes; a
    # smoother field separates them (seen with a sensor model on a mug's wall). Seen voxels
    # can join them too (once in ~450 plans, a tumbler's rim), which no smoothing undoes:
    # after the first try, the field without them.
    bare = replace(field, seen=None)
    attempts = [(field, smooth_voxels)] if field.seen is not None else []
    attempts += [(bare, smooth) for smooth in (smooth_voxels, *RETRY_SMOOTH_VOXELS)]
    problem = None
    for candidate, smooth in attempts:
        try:
            # never simplified: the scans' 0.1 mm simplification cannot hold on a surface
            # of 1 mm voxels and broke a closed one (a tumbler's, 213,000 triangles), whose
            # repair then failed after 10 s
            return object_from_mesh(
                field_surface(candidate, smooth_voxels=smooth), name, simplify_above=None
            )
        except MeshError as exc:
            problem = exc
    raise InputError(
        f"the views of {name} fused into no closed surface ({problem}); give more views or "
        "exact images"
    )
