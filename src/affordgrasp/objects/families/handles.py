"""Grips, handles and hafts shared by the tool families (all along +x)."""

from __future__ import annotations

import manifold3d
import numpy as np

from affordgrasp.objects.families.geometry import (
    planar_frames,
    rounded_stations,
    superellipse,
    sweep,
    sweep_along_x,
)

__all__ = ["straight_grip", "curved_bar"]


def straight_grip(
    x0: float,
    x1: float,
    half_y: float,
    half_z: float,
    exponent: float = 2.0,
    bulge: float = 0.0,
    butt_flare: float = 0.0,
    butt_drop: float = 0.0,
    y_center: float = 0.0,
    butt_round: float | None = None,
    front_round: float = 0.0,
) -> manifold3d.Manifold:
    """A grip from x0 (butt) to x1 (front) with a superellipse section (40 vertices) at 18
    stations between the end zones.

    Parameters
    ----------
    x0, x1 : float
        Butt and front, m.
    half_y, half_z : float
        Section semi-axes, m.
    exponent : float
        2 oval, ~3-4 rounded rectangle.
    bulge : float
        Relative swell in the middle of the grip (palm swell).
    butt_flare : float
        Relative widening of the last 20 % before the butt (stops the hand sliding).
    butt_drop : float
        How far the butt hooks towards -y, m (a pistol-grip curve).
    y_center : float
        Offset of the grip's axis along y, m.
    butt_round, front_round : float
        Length of the domed end zones, m (butt_round None: 60 % of the smaller semi-axis).

    Returns
    -------
    manifold3d.Manifold
        Metres.
    """
    if butt_round is None:
        butt_round = 0.6 * min(half_y, half_z)
    xs, dome = rounded_stations(x0, x1, butt_round, front_round, middle=18)
    u = (xs - x0) / (x1 - x0)
    swell = 1.0 + bulge * np.sin(np.pi * np.clip(u, 0.0, 1.0)) ** 2
    flare = np.maximum(0.0, 1.0 - u / 0.2) ** 2
    sy = half_y * swell * (1.0 + butt_flare * flare) * dome
    sz = half_z * swell * (1.0 + 0.5 * butt_flare * flare) * dome
    yc = y_center - butt_drop * np.maximum(0.0, 1.0 - u / 0.35) ** 2
    unit = superellipse(1.0, 1.0, exponent, 40, half_step=True)
    sections = unit[None, :, :] * np.stack([sy, sz], axis=1)[:, None, :]
    return sweep_along_x(xs, sections, y_center=yc)


def curved_bar(
    path: np.ndarray,
    plane_normal: np.ndarray,
    half_u: np.ndarray,
    half_v: np.ndarray,
    exponent: float | np.ndarray = 2.0,
    points: int = 32,
) -> manifold3d.Manifold:
    """A bar swept along a planar path.

    Parameters
    ----------
    path : (n, 3) float ndarray
        m.
    plane_normal : (3,) float ndarray
        Normal of the path's plane.
    half_u : (n,) float ndarray
        Semi-axis in the plane, perpendicular to the path, m.
    half_v : (n,) float ndarray
        Semi-axis along the plane normal, m.
    exponent : float or (n,) float ndarray
        Superellipse exponent per station.
    points : int
        Vertices per section.

    Returns
    -------
    manifold3d.Manifold
        Metres.
    """
    normal, binormal = planar_frames(path, plane_normal)
    n = path.shape[0]
    exps = np.broadcast_to(np.asarray(exponent, dtype=float), (n,))
    rings = np.empty((n, points, 3))
    for i in range(n):  # n is a few dozen stations; each ring is vectorised
        sec = superellipse(half_u[i], half_v[i], exps[i], points, half_step=True)
        rings[i] = path[i] + sec[:, :1] * normal[i] + sec[:, 1:] * binormal[i]
    return sweep(rings)
