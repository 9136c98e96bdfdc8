"""The hand view: a camera-in-hand depth image resampled at a fixed metric scale, with the
Barrett hand's fingers drawn in (conventions: Vision, docs/learning.md *The hand view*).

Why: the camera in the hand stands an object-length before the object, so the same hand
covers a few pixels of a sword's image and most of a tumbler's, and a network had to learn
where the fingers are from the spread alone, as one number fused after the image. The hand
view gives every object the same pixel scale around the approach line and draws, in extra
channels, which visible surface each finger's closing plane sweeps and which lies under
the palm, so that the convolutions see the fingers and the object together.

Channels of a (b, 6, size, size) view, in the hand frame (the camera frame: x along the
columns, y along the rows, the approach line through the centre):

0. the depth relative to the image's nearest point, m × 10 (0 where there is no return);
1. the hit mask;
2–4. for fingers F1, F2, F3: exp(-(e / w)²) at each hit pixel, where e is the distance of
   the pixel's surface point from the finger's closing plane (the vertical plane through
   its proximal joint along its arm, which turns with the spread) and w = 12 mm, about
   half a finger's width;
5. 1 where the surface point lies within the palm's radius (44.5 mm) of the approach line.

The view's pixel (i, j) is the metric point ((j + 0.5 − size/2)·pixel, (i + 0.5 −
size/2)·pixel) on the plane of the nearest depth, looked up in the camera image by the
nearest pixel (outside the camera's field of view: no return); each pixel's surface point
is its depth times its camera ray, so the finger and palm channels use the true depths.
"""

from __future__ import annotations

import numpy as np

from ..hands.barrett import SPREAD_ARM, SPREAD_AXIS_X
from ..vision.camera import DepthCamera

# The view's defaults: 64 x 64 pixels of 6 mm (0.384 m across: the open fingers' reach,
# proximal joint 50 mm from the spread axis plus a 175 mm finger, is about 0.2 m from the
# approach line).
VIEW_SIZE = 64
VIEW_PIXEL_M = 0.006
VIEW_CHANNELS = 6
FINGER_HALF_WIDTH_M = 0.012
PALM_RADIUS_M = 0.0445


def finger_planes(spread: np.ndarray) -> list[tuple[np.ndarray, ...]]:
    """The closing planes of the Barrett hand's three fingers at given spreads.

    Parameters
    ----------
    spread : (b,) float ndarray
        The spread angle, rad (0: F1 and F2 side by side opposite F3; π/2: they face each
        other).

    Returns
    -------
    list of 3 (bx, by, ax, ay) tuples of (b,) float ndarrays
        For F1, F2, F3: the proximal joint (bx, by), m, and the arm's unit direction (ax,
        ay) in the palm plane; the closing plane contains the joint, the arm and the
        approach axis.
    """
    s, c = np.sin(spread), np.cos(spread)
    zero, one = np.zeros_like(s), np.ones_like(s)
    return [
        (SPREAD_AXIS_X + SPREAD_ARM * s, SPREAD_ARM * c, s, c),
        (-SPREAD_AXIS_X - SPREAD_ARM * s, SPREAD_ARM * c, -s, c),
        (zero, -SPREAD_ARM * one, zero, -one),
    ]


def hand_view(depth_mm: np.ndarray, spread: np.ndarray, *, fov_deg: float = 60.0) -> np.ndarray:
    """The hand views of camera-in-hand depth images.

    Parameters
    ----------
    depth_mm : (b, h, h) uint16 ndarray
        Depth images, mm, 0 for no return (square, ``fov_deg`` across).
    spread : (b,) float ndarray
        Each pregrasp's spread, rad (π·p0[5]).
    fov_deg : float
        The depth camera's field of view.

    Returns
    -------
    (b, 6, VIEW_SIZE, VIEW_SIZE) float32 ndarray
        The channels of the module's docstring (pixels of ``VIEW_PIXEL_M`` on the plane of
        the nearest depth).
    """
    z = np.asarray(depth_mm, dtype=np.float32) / 1000.0
    b, h = len(z), z.shape[-1]
    camera = DepthCamera(h, float(fov_deg))
    k, centre = camera.pixel_scale, camera.principal_point[0]
    hit = z > 0
    near = np.where(hit, z, np.inf).reshape(b, -1).min(axis=1) if b else np.zeros(0)
    near = np.where(np.isfinite(near), near, 1.0).astype(np.float32)
    size = VIEW_SIZE
    grid = (np.arange(size) + 0.5 - size / 2.0) * VIEW_PIXEL_M
    src = grid[None, :] / (near[:, None] * k) + centre  # (b, size) source index
    inside = (src >= -0.5) & (src <= h - 0.5)
    idx = np.clip(np.rint(src), 0, h - 1).astype(np.intp)
    zi = z[np.arange(b)[:, None, None], idx[:, :, None], idx[:, None, :]]
    zi = np.where(inside[:, :, None] & inside[:, None, :], zi, np.float32(0.0))
    hit = zi > 0
    ray = ((idx - centre) * k).astype(np.float32)
    x = zi * ray[:, None, :]
    y = zi * ray[:, :, None]
    out = np.empty((b, VIEW_CHANNELS, size, size), dtype=np.float32)
    out[:, 0] = np.where(hit, zi - near[:, None, None], 0.0) * 10.0
    out[:, 1] = hit
    planes = finger_planes(np.asarray(spread, dtype=np.float32))
    for f, (bx, by, ax, ay) in enumerate(planes):
        e = (x - bx[:, None, None]) * -ay[:, None, None] + (y - by[:, None, None]) * ax[
            :, None, None
        ]
        out[:, 2 + f] = np.where(hit, np.exp(-((e / FINGER_HALF_WIDTH_M) ** 2)), 0.0)
    out[:, 5] = hit & (x * x + y * y < PALM_RADIUS_M**2)
    return out
