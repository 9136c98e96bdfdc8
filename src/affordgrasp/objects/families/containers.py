"""Hollow containers of revolution: bottle, wine glass, tumbler, mug, ice-cream cone.

Frame (before the bounding-box centring done by the caller): the axis is +z, the base at
z = 0 and the opening at the top; the mug's handle points towards +x.  Every container is a
wall of revolution (walls 1.5-4 mm, measured along the surface normal) open at the top, so a
ray cast down the axis from above enters the cavity.
"""

from __future__ import annotations

import manifold3d
import numpy as np

from affordgrasp.objects.families.geometry import hollow_lathe, section, silhouette
from affordgrasp.objects.families.handles import curved_bar
from affordgrasp.objects.families.parameters import ParameterDraw
from affordgrasp.objects.families.parts import tag

__all__ = ["bottle", "wine_glass", "tumbler", "mug", "ice_cream_cone"]

_SEGMENTS = 64


def _smoothstep(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def bottle(p: ParameterDraw) -> manifold3d.Manifold:
    """Glass bottle (wine to beer shapes) with a punt and a lip bead; 0.20-0.32 m tall.

    Parameters
    ----------
    p : ParameterDraw
        The instance's parameter draws (seed 0: the typical instance).

    Returns
    -------
    manifold3d.Manifold
        The solid, metres, in the family frame (module docstring of
        :mod:`affordgrasp.objects.families`).
    """
    height = p.uniform("height_m", 0.20, 0.32, 0.29)
    radius = p.uniform("body_radius_m", 0.030, 0.042, 0.037)
    body = p.uniform("body_fraction", 0.45, 0.65, 0.58)
    shoulder = p.uniform("shoulder_fraction", 0.10, 0.25, 0.15)
    neck_r = p.uniform("neck_radius_m", 0.012, 0.016, 0.0145)
    wall = p.uniform("wall_m", 0.0025, 0.0035, 0.003)
    punt = p.uniform("punt_depth_m", 0.0, 0.02, 0.012)
    bead_h = p.uniform("lip_height_m", 0.006, 0.012, 0.009)
    bead = p.uniform("lip_bead_m", 0.001, 0.0025, 0.0018)

    z_body = body * height
    z_neck = min(z_body + shoulder * height, height - bead_h - 0.02)
    z = np.concatenate(
        [
            np.linspace(0.0, z_body, 4),
            np.linspace(z_body, z_neck, 14)[1:],
            np.linspace(z_neck, height - bead_h, 4)[1:],
        ]
    )
    t = (z - z_body) / (z_neck - z_body)
    neck_taper = 1.0 - 0.04 * np.clip((z - z_neck) / (height - z_neck), 0.0, 1.0)
    r = neck_r * neck_taper + (radius - neck_r) * (1.0 - _smoothstep(t))
    # The bore continues straight through the bead: the cavity is the neck, extended up.
    z_cav = np.concatenate([z, [height + 0.05]])
    r_cav = np.concatenate([r, [r[-1]]])
    r_top = r[-1] + bead
    z_out = np.concatenate([z, [height - bead_h + 0.0015, height]])
    r_out = np.concatenate([r, [r_top, r_top]])
    outer = section(silhouette(r_out, z_out))
    cavity_from = section(silhouette(r_cav, z_cav))
    if punt > 0.0:
        # The punt (push-up) in the base: a dome cut out of outer solid and cavity alike.
        rp = 0.7 * radius
        rr = np.linspace(-rp, rp, 25)
        dome = np.stack([rr, punt * (1.0 - (rr / rp) ** 2)], axis=1)
        cut = section(np.concatenate([dome, [[rp, -0.01], [-rp, -0.01]]], axis=0))
        outer = outer - cut
        cavity_from = cavity_from - cut
    return hollow_lathe(outer, cavity_from, wall, lip_round=0.45 * wall, segments=_SEGMENTS)


def wine_glass(p: ParameterDraw) -> manifold3d.Manifold:
    """Stemmed wine glass: foot, stem, tulip bowl; 0.15-0.22 m tall.

    Parameters
    ----------
    p : ParameterDraw
        The instance's parameter draws (seed 0: the typical instance).

    Returns
    -------
    manifold3d.Manifold
        The solid, metres, in the family frame (module docstring of
        :mod:`affordgrasp.objects.families`).
    """
    height = p.uniform("height_m", 0.15, 0.22, 0.20)
    foot_r = p.uniform("foot_radius_m", 0.032, 0.040, 0.036)
    foot_t = p.uniform("foot_thickness_m", 0.003, 0.005, 0.004)
    foot_rise = p.uniform("foot_rise_m", 0.003, 0.007, 0.005)
    stem_r = p.uniform("stem_radius_m", 0.0035, 0.005, 0.004)
    stem_frac = p.uniform("stem_fraction", 0.3, 0.45, 0.38)
    bowl_r = p.uniform("bowl_radius_m", 0.035, 0.048, 0.042)
    rim_r = p.uniform("rim_radius_m", 0.028, 0.038, 0.032)
    belly = p.uniform("belly_fraction", 0.25, 0.45, 0.35)
    wall = p.uniform("wall_m", 0.0015, 0.0025, 0.002)
    rim_r = min(rim_r, bowl_r - 0.002)

    z_stem0 = foot_t + foot_rise
    z_bowl0 = z_stem0 + stem_frac * (height - z_stem0)
    z_belly = z_bowl0 + belly * (height - z_bowl0)
    # Bowl outer radius: an elliptic bottom up to the belly, then a taper to the rim.
    phi = np.linspace(0.0, np.pi / 2, 16)
    z_low = z_belly - (z_belly - z_bowl0) * np.cos(phi)
    r_low = bowl_r * np.sin(phi)
    s = np.linspace(0.0, 1.0, 18)[1:]
    z_up = z_belly + (height - z_belly) * s
    r_up = rim_r + (bowl_r - rim_r) * np.cos(0.5 * np.pi * s) ** 1.3
    z_bowl = np.concatenate([z_low, z_up])
    r_bowl = np.concatenate([r_low, r_up])
    cavity_from = section(
        silhouette(np.concatenate([r_bowl, [rim_r]]), np.concatenate([z_bowl, [height + 0.05]]))
    )
    # Foot (a disc with a conical top) and a gently swelling stem, united with the bowl.
    rr = np.linspace(foot_r, stem_r, 10)
    z_foot = foot_t + foot_rise * ((foot_r - rr) / (foot_r - stem_r)) ** 1.5
    z_st = np.linspace(z_stem0 + 0.004, z_bowl0 + 0.25 * (z_belly - z_bowl0), 12)
    r_st = stem_r * (1.0 + 0.15 * np.sin(np.pi * (z_st - z_st[0]) / (z_st[-1] - z_st[0])) ** 2)
    r_out = np.concatenate([[foot_r], rr, r_st])
    z_out = np.concatenate([[0.0], z_foot, z_st])
    outer = section(silhouette(r_out, z_out)) + section(silhouette(r_bowl, z_bowl))
    return hollow_lathe(outer, cavity_from, wall, lip_round=0.45 * wall, segments=_SEGMENTS)


def tumbler(p: ParameterDraw) -> manifold3d.Manifold:
    """Straight-sided drinking glass with a thick base; 0.08-0.15 m tall.

    Parameters
    ----------
    p : ParameterDraw
        The instance's parameter draws (seed 0: the typical instance).

    Returns
    -------
    manifold3d.Manifold
        The solid, metres, in the family frame (module docstring of
        :mod:`affordgrasp.objects.families`).
    """
    height = p.uniform("height_m", 0.08, 0.15, 0.11)
    top_r = p.uniform("rim_radius_m", 0.033, 0.043, 0.038)
    taper = p.uniform("base_to_rim_ratio", 0.78, 1.0, 0.88)
    wall = p.uniform("wall_m", 0.002, 0.0035, 0.0025)
    base = p.uniform("base_thickness_m", 0.005, 0.012, 0.008)
    z = np.linspace(0.0, height, 6)
    r = top_r * (taper + (1.0 - taper) * z / height)
    outer = section(silhouette(r, z))
    z_cav = np.concatenate([z, [height + 0.05]])
    r_cav = top_r * (taper + (1.0 - taper) * z_cav / height)
    cavity_from = section(silhouette(r_cav, z_cav))
    return hollow_lathe(
        outer, cavity_from, wall, floor_z=base, lip_round=0.45 * wall, segments=_SEGMENTS
    )


def mug(p: ParameterDraw) -> manifold3d.Manifold:
    """Coffee mug with a loop handle (a finger fits through it); 90-110 mm tall.

    Parameters
    ----------
    p : ParameterDraw
        The instance's parameter draws (seed 0: the typical instance).

    Returns
    -------
    manifold3d.Manifold
        The solid, metres, in the family frame (module docstring of
        :mod:`affordgrasp.objects.families`).
    """
    height = p.uniform("height_m", 0.09, 0.11, 0.097)
    radius = p.uniform("radius_m", 0.0375, 0.0435, 0.041)
    wall = p.uniform("wall_m", 0.003, 0.004, 0.0035)
    base = p.uniform("base_thickness_m", 0.005, 0.007, 0.006)
    barrel = p.uniform("barrel_m", 0.0, 0.0015, 0.0008)
    reach = p.uniform("handle_reach_m", 0.025, 0.035, 0.029)
    top_gap = p.uniform("handle_top_gap_m", 0.012, 0.02, 0.015)
    bottom_gap = p.uniform("handle_bottom_gap_m", 0.015, 0.025, 0.02)
    handle_t = p.uniform("handle_half_thickness_m", 0.0045, 0.006, 0.005)
    handle_w = p.uniform("handle_half_width_m", 0.006, 0.009, 0.0075)
    squareness = p.uniform("handle_squareness", 2.0, 3.5, 2.6)

    z = np.linspace(0.0, height, 12)
    r = radius + barrel * np.sin(np.pi * z / height)
    outer = section(silhouette(r, z))
    z_cav = np.concatenate([z, [height + 0.05]])
    r_cav = np.concatenate([r, [r[-1]]])
    cavity_from = section(silhouette(r_cav, z_cav))
    body = hollow_lathe(
        outer, cavity_from, wall, floor_z=base, lip_round=0.45 * wall, segments=_SEGMENTS
    )

    # Handle: a superelliptic half-loop in the x-z plane.  Its ends meet the body at right
    # angles and stop inside the wall, so nothing shows in the cavity.
    z_top, z_bot = height - top_gap, bottom_gap
    zc, half_h = 0.5 * (z_top + z_bot), 0.5 * (z_top - z_bot)
    x0 = min(np.interp(z_top, z, r), np.interp(z_bot, z, r)) - 0.5 * wall
    phi = np.linspace(-np.pi / 2, np.pi / 2, 48)
    c, s = np.cos(phi), np.sin(phi)
    power = 2.0 / squareness
    x = x0 + (reach + radius - x0) * np.abs(c) ** power
    zz = zc + half_h * np.sign(s) * np.abs(s) ** power
    path = np.stack([x, np.zeros_like(x), zz], axis=1)
    n = path.shape[0]
    handle = curved_bar(
        path, np.array([0.0, 1.0, 0.0]), np.full(n, handle_t), np.full(n, handle_w), 2.4, 24
    )
    return tag(body, "body") + tag(handle, "handle")


def ice_cream_cone(p: ParameterDraw) -> manifold3d.Manifold:
    """Hollow wafer cone with a rim band; 0.10-0.15 m tall.

    Parameters
    ----------
    p : ParameterDraw
        The instance's parameter draws (seed 0: the typical instance).

    Returns
    -------
    manifold3d.Manifold
        The solid, metres, in the family frame (module docstring of
        :mod:`affordgrasp.objects.families`).
    """
    height = p.uniform("height_m", 0.102, 0.15, 0.125)
    top_r = p.uniform("rim_radius_m", 0.022, 0.030, 0.026)
    band = p.uniform("rim_band_height_m", 0.008, 0.016, 0.012)
    band_out = p.uniform("rim_band_step_m", 0.001, 0.002, 0.0015)
    wall = p.uniform("wall_m", 0.002, 0.003, 0.0025)
    z_band = height - band
    # Rounding the section blunts the apex by lip / sin(half-angle) - lip: start the cone
    # that much lower so the finished cone keeps its height.
    lip = 0.45 * wall
    retract = lip / np.sin(np.arctan2(top_r, z_band)) - lip
    z = np.array([-retract, z_band, z_band + 2.0 * band_out, height])
    r = np.array([0.0, top_r, top_r + band_out, top_r + band_out])
    outer = section(silhouette(r, z))
    cavity_from = section(
        silhouette(np.concatenate([r, [r[-1]]]), np.concatenate([z, [height + 0.05]]))
    )
    return hollow_lathe(outer, cavity_from, wall, lip_round=lip, segments=_SEGMENTS)
