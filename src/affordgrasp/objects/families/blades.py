"""Bladed families: knife, meat cleaver, dagger, sword.

Frame (before the bounding-box centring done by the caller): the tool lies along +x, the
butt of the handle at x = 0 and the blade tip at the largest x; the blade lies in the x-y
plane, thickness along z, symmetric about z = 0.  Single-edged blades have their cutting
edge towards -y and the spine towards +y; double-edged blades are symmetric about y = 0.

A blade is a sweep of a convex cross-section along x whose edge vertex is a single mesh
vertex, so the cutting edge is a true polyline of mesh edges.  Its inclusive edge angle
``edge_angle`` is held constant measured perpendicular to the edge (the bevel is widened in
y where the edge curves), so the dihedral angle across the edge stays near that value all
along, up to the belly of the tip.
"""

from __future__ import annotations

import manifold3d
import numpy as np

from affordgrasp.objects.families.geometry import rounded_stations, sweep, sweep_along_x, union
from affordgrasp.objects.families.handles import curved_bar, straight_grip
from affordgrasp.objects.families.parameters import ParameterDraw
from affordgrasp.objects.families.parts import tag

__all__ = ["knife", "meat_cleaver", "dagger", "sword", "single_edge_blade", "double_edge_blade"]


def single_edge_blade(
    xs: np.ndarray,
    y_edge: np.ndarray,
    y_spine: np.ndarray,
    bevel: float,
    edge_angle: float,
    spine_thickness: np.ndarray,
    pointed: bool,
) -> manifold3d.Manifold:
    """Single-edged blade swept along x with a flat-ground, secondary-bevelled section.

    Section (y, z), five vertices: edge (z = 0), two bevel shoulders, two spine corners.

    Parameters
    ----------
    xs, y_edge, y_spine, spine_thickness : (n,) float ndarray
        Per station, m.
    bevel : float
        Width of the edge bevel perpendicular to the edge, m.
    edge_angle : float
        Inclusive angle of the cutting edge, rad.
    pointed : bool
        Close the last station in a point (its y_edge must equal its y_spine).

    Returns
    -------
    manifold3d.Manifold
        Metres.
    """
    slope = np.gradient(y_edge, xs)
    cos_t = 1.0 / np.sqrt(1.0 + slope**2)
    height = y_spine - y_edge
    bevel_y_full = bevel / cos_t
    # Near the tip the blade is lower than the bevel: shrink the section self-similarly,
    # which keeps the edge angle and keeps the section convex.
    scale = np.minimum(1.0, 0.5 * height / bevel_y_full)
    bevel_y = bevel_y_full * scale
    shoulder = 2.0 * bevel * np.tan(edge_angle / 2.0) * scale
    with np.errstate(divide="ignore", invalid="ignore"):
        spine_max = shoulder + 0.9 * shoulder * (height - bevel_y) / bevel_y
    spine = np.clip(spine_thickness, shoulder, np.nan_to_num(spine_max))
    n = xs.shape[0]
    sec = np.zeros((n, 5, 2))
    sec[:, 0] = np.stack([y_edge, np.zeros(n)], axis=1)
    sec[:, 1] = np.stack([y_edge + bevel_y, shoulder / 2], axis=1)
    sec[:, 2] = np.stack([y_spine, spine / 2], axis=1)
    sec[:, 3] = np.stack([y_spine, -spine / 2], axis=1)
    sec[:, 4] = np.stack([y_edge + bevel_y, -shoulder / 2], axis=1)
    rings = np.empty((n, 5, 3))
    rings[..., 0] = xs[:, None]
    rings[..., 1:] = sec
    if pointed:
        rings[-1] = np.array([xs[-1], y_edge[-1], 0.0])
    return sweep(rings)


def double_edge_blade(
    xs: np.ndarray, half_width: np.ndarray, flat_fraction: float, edge_angle: float
) -> manifold3d.Manifold:
    """Double-edged blade, symmetric about y = 0 and z = 0, swept along x, closed in a point.

    Section: a flattened hexagon whose edge bevels run from the flat to the edges, so the
    thickness follows from the edge angle.

    Parameters
    ----------
    xs, half_width : (n,) float ndarray
        Stations and half-widths, m.
    flat_fraction : float
        Half-width of the central flat (ridge) over the blade's half-width.
    edge_angle : float
        Inclusive angle of the edges, rad.

    Returns
    -------
    manifold3d.Manifold
        Metres.
    """
    slope = np.gradient(half_width, xs)
    cos_t = 1.0 / np.sqrt(1.0 + slope**2)
    flat = flat_fraction * half_width
    half_t = (half_width - flat) * cos_t * np.tan(edge_angle / 2.0)
    n = xs.shape[0]
    zeros = np.zeros(n)
    sec = np.stack(
        [
            np.stack([-half_width, zeros], axis=1),
            np.stack([-flat, half_t], axis=1),
            np.stack([flat, half_t], axis=1),
            np.stack([half_width, zeros], axis=1),
            np.stack([flat, -half_t], axis=1),
            np.stack([-flat, -half_t], axis=1),
        ],
        axis=1,
    )
    rings = np.empty((n, 6, 3))
    rings[..., 0] = xs[:, None]
    rings[..., 1:] = sec
    rings[-1] = np.array([xs[-1], 0.0, 0.0])
    return sweep(rings)


def _tang(x_heel: float, y_low: float, y_high: float, thickness: float) -> manifold3d.Manifold:
    """Flat bar joining a blade to its handle: 25 mm into the handle, 3 mm into the blade.

    It is as thin as the blade's edge shoulder, so where it overlaps the blade it stays
    inside it; the blade itself starts with a square heel at ``x_heel``.
    """
    half_t = 0.4 * thickness
    ring = np.array(
        [[y_low, -half_t], [y_high, -half_t], [y_high, half_t], [y_low, half_t]], dtype=float
    )
    xs = np.array([x_heel - 0.025, x_heel + 0.003])
    return sweep_along_x(xs, np.stack([ring, ring]))


def _tip_stations(x0: float, x1: float, n: int, power: float = 1.6) -> np.ndarray:
    """Stations on [x0, x1], denser towards x1 where a tip curves."""
    s = np.linspace(0.0, 1.0, n)
    return x0 + (x1 - x0) * (1.0 - (1.0 - s) ** power)


def knife(p: ParameterDraw) -> manifold3d.Manifold:
    """Kitchen knife: chef's, utility, santoku-like variants; 0.20-0.33 m long.

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
    handle_len = p.uniform("handle_length_m", 0.095, 0.135, 0.115)
    blade_len = p.uniform("blade_length_m", 0.10, 0.21, 0.165)
    blade_len = float(np.clip(blade_len, 0.205 - handle_len, 0.325 - handle_len))
    p.values["blade_length_m"] = blade_len
    heel = p.uniform("heel_height_m", 0.16, 0.27, 0.24) * blade_len
    heel = float(np.clip(heel, 0.018, 0.05))
    p.values["heel_height_m"] = heel
    spine_t = p.uniform("spine_thickness_m", 0.0015, 0.0025, 0.002)
    edge_angle = np.radians(p.uniform("edge_angle_deg", 14.0, 20.0, 17.0))
    bevel = p.uniform("bevel_width_m", 0.0015, 0.0035, 0.0025)
    drop = p.uniform("tip_drop", 0.0, 0.7, 0.35)
    belly_start = p.uniform("belly_start", 0.45, 0.75, 0.6)
    belly_power = p.uniform("belly_power", 1.6, 2.6, 2.0)
    spine_start = p.uniform("spine_drop_start", 0.5, 0.8, 0.65)
    tip_taper = p.uniform("distal_taper", 0.35, 0.7, 0.5)
    grip_h = p.uniform("handle_height_m", 0.020, 0.027, 0.024)
    grip_t = p.uniform("handle_thickness_m", 0.014, 0.020, 0.017)
    grip_exp = p.uniform("handle_squareness", 2.2, 3.5, 2.8)
    grip_bulge = p.uniform("handle_bulge", 0.0, 0.12, 0.06)
    grip_flare = p.uniform("handle_butt_flare", 0.0, 0.2, 0.1)
    grip_drop = p.uniform("handle_butt_drop_m", 0.0, 0.006, 0.003)

    grip_center = 0.002 - grip_h / 2.0
    grip = straight_grip(
        0.0,
        handle_len,
        grip_h / 2,
        grip_t / 2,
        exponent=grip_exp,
        bulge=grip_bulge,
        butt_flare=grip_flare,
        butt_drop=grip_drop,
        y_center=grip_center,
        front_round=0.002,
    )

    # The heel sits 1 mm inside the handle's rounded front, so no two faces are coplanar.
    x_heel = handle_len - 0.001
    xs = _tip_stations(x_heel, x_heel + blade_len, 48, power=1.25)
    u = (xs - x_heel) / blade_len
    f = np.maximum(0.0, (u - belly_start) / (1.0 - belly_start)) ** belly_power
    g = np.maximum(0.0, (u - spine_start) / (1.0 - spine_start)) ** 1.8
    y_spine = -drop * heel * g
    y_edge = -heel + (1.0 - drop) * heel * f
    y_edge[-1] = y_spine[-1]
    thickness = spine_t * (1.0 - (1.0 - tip_taper) * u)
    blade = single_edge_blade(xs, y_edge, y_spine, bevel, edge_angle, thickness, pointed=True)
    tang = _tang(
        x_heel,
        y_low=max(grip_center - grip_h / 2 + 0.003, -heel + 2.0 * bevel),
        y_high=-0.001,
        thickness=2.0 * bevel * np.tan(edge_angle / 2.0),
    )
    return union([tag(grip, "handle"), tag(tang, "blade"), tag(blade, "blade")])


def meat_cleaver(p: ParameterDraw) -> manifold3d.Manifold:
    """Meat cleaver: tall rectangular blade with a hanging hole; 0.27-0.35 m long.

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
    handle_len = p.uniform("handle_length_m", 0.11, 0.14, 0.125)
    blade_len = p.uniform("blade_length_m", 0.15, 0.20, 0.175)
    blade_len = float(np.clip(blade_len, 0.275 - handle_len, 0.345 - handle_len))
    p.values["blade_length_m"] = blade_len
    height = p.uniform("blade_height_m", 0.075, 0.11, 0.09)
    spine_t = p.uniform("spine_thickness_m", 0.003, 0.005, 0.004)
    edge_angle = np.radians(p.uniform("edge_angle_deg", 18.0, 26.0, 22.0))
    bevel = p.uniform("bevel_width_m", 0.004, 0.007, 0.0055)
    belly = p.uniform("edge_rise_front_m", 0.0, 0.012, 0.005)
    front_drop = p.uniform("spine_drop_front_m", 0.0, 0.01, 0.003)
    hole_r = p.uniform("hole_radius_m", 0.005, 0.008, 0.0065)
    grip_h = p.uniform("handle_height_m", 0.022, 0.028, 0.025)
    grip_t = p.uniform("handle_thickness_m", 0.016, 0.022, 0.019)
    grip_exp = p.uniform("handle_squareness", 2.0, 3.2, 2.5)
    grip_flare = p.uniform("handle_butt_flare", 0.0, 0.25, 0.12)

    grip = straight_grip(
        0.0,
        handle_len,
        grip_h / 2,
        grip_t / 2,
        exponent=grip_exp,
        bulge=0.04,
        butt_flare=grip_flare,
        y_center=-grip_h / 2 - 0.004,
        front_round=0.002,
    )
    x_heel = handle_len - 0.001
    xs = np.linspace(x_heel, x_heel + blade_len, 32)
    u = (xs - x_heel) / blade_len
    y_spine = -front_drop * u**2
    y_edge = -height + belly * u**3
    # Cleavers keep their thickness to the front: the weight does the chopping.
    thickness = spine_t * (1.0 - 0.25 * u)
    blade = single_edge_blade(xs, y_edge, y_spine, bevel, edge_angle, thickness, pointed=False)
    tang = _tang(
        x_heel,
        y_low=-grip_h - 0.001,
        y_high=-0.007,
        thickness=2.0 * bevel * np.tan(edge_angle / 2.0),
    )
    hole = manifold3d.Manifold.cylinder(0.05, hole_r, circular_segments=32, center=True)
    hole = hole.translate((x_heel + blade_len - 2.6 * hole_r, -2.6 * hole_r - front_drop, 0.0))
    parts = [tag(grip, "handle"), tag(tang, "blade"), tag(blade, "blade")]
    return union(parts) - tag(hole, "blade")


def _hilt(
    p: ParameterDraw,
    grip_len: float,
    grip_half: tuple[float, float],
    guard_span: float,
    guard_thick: float,
    guard_depth: float,
    guard_curve: float,
    pommel_r: float,
) -> tuple[manifold3d.Manifold, float]:
    """Pommel + grip + cross-guard along x from 0; returns the solid and the guard's front x.

    Parts overlap generously and cross each other's surfaces at clear angles: grazing
    intersections would leave sliver triangles.
    """
    pommel_squash = 0.8
    half_y = min(grip_half[0], 0.8 * pommel_r)
    half_z = min(grip_half[1], 0.8 * pommel_squash * pommel_r)
    guard_depth = max(guard_depth, 2.0 * half_z + 0.004)
    p.values["guard_depth_m"] = guard_depth
    x_guard = 1.6 * pommel_r + grip_len
    grip = straight_grip(
        pommel_r,
        x_guard + 0.4 * guard_thick,
        half_y,
        half_z,
        exponent=2.0,
        bulge=p.uniform("grip_bulge", 0.0, 0.15, 0.08),
        butt_round=0.0,
    )
    pommel = manifold3d.Manifold.sphere(pommel_r, circular_segments=32)
    pommel = pommel.scale((1.0, 1.0, pommel_squash)).translate((pommel_r, 0.0, 0.0))
    ys, dome = rounded_stations(
        -guard_span / 2, guard_span / 2, 0.4 * guard_depth, 0.4 * guard_depth
    )
    yn = 2.0 * ys / guard_span
    path = np.stack(
        [x_guard + guard_thick / 2 + guard_curve * yn**2, ys, np.zeros_like(ys)], axis=1
    )
    taper = 1.0 - 0.25 * yn**2
    guard = curved_bar(
        path,
        np.array([0.0, 0.0, 1.0]),
        guard_thick / 2 * taper * dome,
        guard_depth / 2 * taper * dome,
        exponent=2.6,
        points=24,
    )
    hilt = union([tag(pommel, "pommel"), tag(grip, "handle"), tag(guard, "guard")])
    return hilt, x_guard + guard_thick


def _pointed_half_width(u: np.ndarray, base: float, taper: float, point_len: float) -> np.ndarray:
    """Half-width of a straight-tapered blade ending in an ogive point (u in [0, 1])."""
    u_p = 1.0 - point_len
    straight = base * (1.0 - (1.0 - taper) * np.minimum(u, u_p))
    w_p = base * (1.0 - (1.0 - taper) * u_p)
    v = np.clip((u - u_p) / point_len, 0.0, 1.0)
    return np.where(u <= u_p, straight, w_p * np.sqrt(np.maximum(0.0, 1.0 - v**2)))


def _blade_stations(x0: float, length: float, point_len: float, n_body: int, n_point: int):
    u_p = 1.0 - point_len
    body = np.linspace(0.0, u_p, n_body, endpoint=False)
    point = u_p + point_len * (1.0 - (1.0 - np.linspace(0.0, 1.0, n_point)) ** 1.6)
    u = np.concatenate([body, point])
    return x0 + length * u, u


def _hilted_double_edge(p: ParameterDraw, r: dict) -> manifold3d.Manifold:
    """A double-edged blade with cross-guard and pommel: the dagger and the sword, which
    differ only in their ranges (``r``: parameter name -> (low, high, typical), plus the
    overall length range, grip thickness, station count and tang overlap)."""
    blade_len = p.uniform("blade_length_m", *r["blade_length_m"])
    grip_len = p.uniform("grip_length_m", *r["grip_length_m"])
    base_w = p.uniform("blade_width_m", *r["blade_width_m"])
    taper = p.uniform("width_taper", *r["width_taper"])
    point_len = p.uniform("point_fraction", *r["point_fraction"])
    flat = p.uniform("flat_fraction", *r["flat_fraction"])
    edge_angle = np.radians(p.uniform("edge_angle_deg", 15.0, 22.0, 19.0))
    hilt, x0 = _hilt(
        p,
        grip_len,
        (p.uniform("grip_half_height_m", *r["grip_half_height_m"]), r["grip_half_width_m"]),
        guard_span=p.uniform("guard_span_m", *r["guard_span_m"]),
        guard_thick=p.uniform("guard_thickness_m", *r["guard_thickness_m"]),
        guard_depth=p.uniform("guard_depth_m", *r["guard_depth_m"]),
        guard_curve=p.uniform("guard_curve_m", *r["guard_curve_m"]),
        pommel_r=p.uniform("pommel_radius_m", *r["pommel_radius_m"]),
    )
    low, high = r["length_m"]
    blade_len = float(np.clip(blade_len, low - x0, high - x0))
    p.values["blade_length_m"] = blade_len
    xs, u = _blade_stations(x0, blade_len, point_len, r["stations"], 28)
    half_w = _pointed_half_width(u, base_w / 2, taper, point_len)
    xs = np.concatenate([[x0 - r["tang_overlap_m"]], xs])
    half_w = np.concatenate([[half_w[0]], half_w])
    blade = double_edge_blade(xs, half_w, flat, edge_angle)
    return union([hilt, tag(blade, "blade")])


def dagger(p: ParameterDraw) -> manifold3d.Manifold:
    """Double-edged dagger with cross-guard and pommel; 0.22-0.35 m long.

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
    return _hilted_double_edge(
        p,
        {
            "blade_length_m": (0.12, 0.22, 0.17),
            "grip_length_m": (0.08, 0.11, 0.095),
            "blade_width_m": (0.025, 0.040, 0.032),
            "width_taper": (0.25, 0.6, 0.45),
            "point_fraction": (0.15, 0.35, 0.25),
            "flat_fraction": (0.08, 0.3, 0.15),
            "grip_half_height_m": (0.011, 0.014, 0.0125),
            "grip_half_width_m": 0.0095,
            "guard_span_m": (0.06, 0.10, 0.075),
            "guard_thickness_m": (0.007, 0.011, 0.009),
            "guard_depth_m": (0.014, 0.02, 0.017),
            "guard_curve_m": (0.0, 0.008, 0.003),
            "pommel_radius_m": (0.013, 0.018, 0.015),
            "length_m": (0.225, 0.345),
            "stations": 16,
            "tang_overlap_m": 0.006,
        },
    )


def sword(p: ParameterDraw) -> manifold3d.Manifold:
    """Double-edged straight sword (arming sword); 0.70-1.00 m long.

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
    return _hilted_double_edge(
        p,
        {
            "blade_length_m": (0.55, 0.80, 0.70),
            "grip_length_m": (0.10, 0.17, 0.12),
            "blade_width_m": (0.035, 0.055, 0.045),
            "width_taper": (0.35, 0.75, 0.55),
            "point_fraction": (0.06, 0.15, 0.09),
            "flat_fraction": (0.1, 0.35, 0.2),
            "grip_half_height_m": (0.013, 0.016, 0.0145),
            "grip_half_width_m": 0.012,
            "guard_span_m": (0.16, 0.24, 0.20),
            "guard_thickness_m": (0.010, 0.016, 0.013),
            "guard_depth_m": (0.016, 0.024, 0.02),
            "guard_curve_m": (0.0, 0.02, 0.008),
            "pommel_radius_m": (0.018, 0.026, 0.022),
            "length_m": (0.71, 0.99),
            "stations": 24,
            "tang_overlap_m": 0.008,
        },
    )
