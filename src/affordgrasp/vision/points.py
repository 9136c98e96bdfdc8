"""Point clouds equivalent to the depth images (conventions: Vision, paper §III-B).

Each valid pixel (depth > 0) back-projects to the camera-frame point ``depth · ray`` (see
``camera.DepthCamera.ray_directions``: ray z = 1, so the point's z is the depth). Background is
removed; a cloud is brought to a fixed number of points N by a seeded random subsample
without replacement (more than N points) or by padding with points at the origin (fewer).

Canonicalisations (optional):

* ``crop_radius`` (m): keep only points within this distance of the optical axis (the
  approach line), the part of the view the fingers will meet;
* ``centre_depth``: subtract the smallest depth of the cloud from z, so that z = 0 is the
  first surface along the approach (removes the object-length-dependent camera distance).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .camera import DepthCamera


def depth_to_points(depth: np.ndarray, camera: DepthCamera | None = None) -> np.ndarray:
    """All valid pixels of one depth image as camera-frame points, in row-major pixel order.

    Parameters
    ----------
    depth : (h, w) float ndarray
        m (0 = no return).
    camera : DepthCamera, optional

    Returns
    -------
    (k, 3) float32 ndarray
        m.
    """
    depth = np.asarray(depth)
    camera = camera or DepthCamera(size=depth.shape[-1])
    if depth.shape != (camera.size, camera.size):
        raise InputError(f"depth image of shape {depth.shape}; the camera is {camera.size}²")
    rays = camera.ray_directions()
    hit = depth > 0
    return (rays[hit] * depth[hit][:, None]).astype(np.float32)


def point_clouds(
    depth: np.ndarray,
    n_points: int = 1024,
    *,
    seed: int = 0,
    camera: DepthCamera | None = None,
    crop_radius: float | None = None,
    centre_depth: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Fixed-size point clouds of depth images.

    Parameters
    ----------
    depth : (b, h, w) or (h, w) float ndarray
        m (0 = no return).
    n_points : int
        N, points per cloud.
    seed : int
        Image i is subsampled with ``default_rng(SeedSequence([seed, i]))``.
    camera : DepthCamera, optional
    crop_radius : float, optional
        Keep only points within this distance of the optical axis, m.
    centre_depth : bool
        Subtract the smallest depth of each cloud from z.

    Returns
    -------
    points : (b, N, 3) float32 ndarray
        Camera frame, m; padding at the origin.
    counts : (b,) int64 ndarray
        The number of real points before subsampling/padding.
    """
    depth = np.asarray(depth)
    if depth.ndim == 2:
        depth = depth[None]
    if n_points < 1:
        raise InputError(f"n_points must be >= 1, got {n_points}")
    camera = camera or DepthCamera(size=depth.shape[-1])
    out = np.zeros((len(depth), n_points, 3), dtype=np.float32)
    counts = np.zeros(len(depth), dtype=np.int64)
    for i, image in enumerate(depth):
        pts = depth_to_points(image, camera)
        if crop_radius is not None and len(pts):
            pts = pts[np.hypot(pts[:, 0], pts[:, 1]) <= crop_radius]
        if centre_depth and len(pts):
            pts[:, 2] -= pts[:, 2].min()
        counts[i] = len(pts)
        if len(pts) > n_points:
            rng = np.random.default_rng(np.random.SeedSequence([seed, i]))
            pts = pts[np.sort(rng.choice(len(pts), n_points, replace=False))]
        out[i, : len(pts)] = pts
    return out, counts
