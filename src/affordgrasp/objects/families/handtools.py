"""Hand tools with a working tip: screwdriver and spatula (kitchen turner).

Frame (before the bounding-box centring done by the caller): the tool lies along +x, the
handle's butt at x = 0 and the working tip at the largest x.  The screwdriver is symmetric
about its axis (y = z = 0); its slotted tip is flattened in z (blade in the x-y plane).  The
spatula's blade is a thin plate in the x-y plane (thickness along z) whose front edge, at +x,
is chisel-ground on the +z side to a real edge; an offset spatula's blade sits below the
handle (towards -z).
"""

from __future__ import annotations

import manifold3d
import numpy as np

from affordgrasp.objects.families.geometry import (
    rounded_stations,
    superellipse,
    sweep,
    sweep_along_x,
    union,
)
from affordgrasp.objects.families.handles import curved_bar, straight_grip
from affordgrasp.objects.families.parameters import ParameterDraw
from affordgrasp.objects.families.parts import tag

__all__ = ["screwdriver", "spatula"]


def screwdriver(p: ParameterDraw) -> manifold3d.Manifold:
    """Slotted or Phillips screwdriver with a fluted handle; 0.15-0.30 m long.

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
    tip_style = p.choice("tip", ("slotted", "phillips"), "slotted")
    handle_len = p.uniform("handle_length_m", 0.085, 0.12, 0.10)
    handle_r = p.uniform("handle_radius_m", 0.013, 0.018, 0.0155)
    flutes = p.choice("flutes", ("0", "4", "6", "8"), "6")
    flute_depth = p.uniform("flute_depth", 0.05, 0.12, 0.08)
    shaft_len = p.uniform("shaft_length_m", 0.06, 0.16, 0.10)
    shaft_len = float(np.clip(shaft_len, 0.15 - handle_len, 0.29 - handle_len))
    p.values["shaft_length_m"] = shaft_len
    shaft_r = p.uniform("shaft_radius_m", 0.0025, 0.004, 0.003)
    tip_len = p.uniform("tip_length_m", 0.008, 0.014, 0.011)
    tip_t = p.uniform("tip_thickness_m", 0.0005, 0.001, 0.0007)

    n_flutes = int(flutes)
    x_ferrule = handle_len + 0.012
    xs, dome = rounded_stations(0.0, x_ferrule, 0.6 * handle_r, 0.0, middle=24)
    u = xs / handle_len
    radius = handle_r * (1.0 + 0.06 * np.sin(np.pi * np.clip(u, 0.0, 1.0)) ** 2) * dome
    # The front of the handle necks down into a ferrule around the shaft.
    neck = np.clip((xs - 0.85 * handle_len) / (x_ferrule - 0.85 * handle_len), 0.0, 1.0)
    ferrule_r = 1.8 * shaft_r
    radius = radius + (ferrule_r - radius) * (3.0 * neck**2 - 2.0 * neck**3)
    points = 48
    theta = 2.0 * np.pi * np.arange(points) / points
    groove = (0.5 + 0.5 * np.cos(n_flutes * theta)) ** 3 if n_flutes else np.zeros(points)
    depth = flute_depth * (1.0 - neck)
    rel = 1.0 - depth[:, None] * groove[None, :]
    sections = (
        np.stack([np.cos(theta)[None, :] * rel, np.sin(theta)[None, :] * rel], axis=-1)
        * radius[:, None, None]
    )
    handle = sweep_along_x(xs, sections)

    x0 = handle_len - 0.03  # the shaft is seated deep in the handle
    x_tip = x_ferrule + shaft_len
    x_taper = x_tip - tip_len
    s = np.linspace(0.0, 1.0, 10)
    xs_tip = x_taper + tip_len * s
    if tip_style == "slotted":
        half_y = shaft_r * (1.0 + 0.08 * s)
        half_z = shaft_r + (tip_t / 2.0 - shaft_r) * s**0.8
        exps = 2.0 + 4.0 * s
    else:
        half_y = shaft_r * (1.0 - 0.75 * s**1.5)
        half_z = half_y
        exps = np.full_like(s, 2.0)
    stations = np.concatenate([[x0, x_ferrule - 0.002], xs_tip])
    hy = np.concatenate([[shaft_r, shaft_r], half_y])
    hz = np.concatenate([[shaft_r, shaft_r], half_z])
    ex = np.concatenate([[2.0, 2.0], exps])
    sec = np.stack([superellipse(a, b, n, 32) for a, b, n in zip(hy, hz, ex, strict=True)])
    shaft = sweep_along_x(stations, sec)
    return union([tag(handle, "handle"), tag(shaft, "shaft")])


def spatula(p: ParameterDraw) -> manifold3d.Manifold:
    """Kitchen turner with a slotted, front-bevelled blade; 0.25-0.35 m long.

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
    handle_len = p.uniform("handle_length_m", 0.11, 0.15, 0.13)
    grip_hy = p.uniform("handle_half_width_m", 0.011, 0.014, 0.0125)
    grip_hz = p.uniform("handle_half_thickness_m", 0.008, 0.011, 0.0095)
    grip_exp = p.uniform("handle_squareness", 2.2, 3.0, 2.6)
    shank_len = p.uniform("shank_length_m", 0.04, 0.08, 0.06)
    shank_w = p.uniform("shank_width_m", 0.010, 0.014, 0.012)
    shank_t = p.uniform("shank_thickness_m", 0.0025, 0.004, 0.003)
    offset = p.uniform("blade_offset_m", 0.0, 0.03, 0.018)
    blade_len = p.uniform("blade_length_m", 0.09, 0.13, 0.11)
    back_w = p.uniform("blade_back_width_m", 0.045, 0.06, 0.052)
    front_w = p.uniform("blade_front_width_m", 0.065, 0.09, 0.078)
    thick = p.uniform("blade_thickness_m", 0.0012, 0.002, 0.0015)
    corner_r = p.uniform("front_corner_radius_m", 0.006, 0.015, 0.01)
    bevel_angle = np.radians(p.uniform("edge_angle_deg", 14.0, 22.0, 18.0))
    n_slots = p.integer("slots", 0, 4, 3)
    total = handle_len + shank_len + blade_len
    if not 0.25 <= total <= 0.35:
        blade_len = float(np.clip(blade_len + (0.30 - total), 0.08, 0.14))
        p.values["blade_length_m"] = blade_len

    handle = straight_grip(
        0.0, handle_len, grip_hy, grip_hz, exponent=grip_exp, bulge=0.05, front_round=0.004
    )
    x_blade = handle_len + shank_len
    x_front = x_blade + blade_len
    z_blade = -offset

    xs_shank = np.linspace(handle_len - 0.02, x_blade + 0.014, 32)
    v = np.clip((xs_shank - (handle_len + 0.008)) / (shank_len - 0.016), 0.0, 1.0)
    zs = z_blade * (3.0 * v**2 - 2.0 * v**3)
    path = np.stack([xs_shank, np.zeros_like(xs_shank), zs], axis=1)
    w = shank_w * (1.0 + 0.6 * np.clip((xs_shank - x_blade + 0.01) / 0.024, 0.0, 1.0))
    shank = curved_bar(
        path,
        np.array([0.0, 1.0, 0.0]),
        np.full_like(xs_shank, shank_t / 2),
        w / 2,
        exponent=4.0,
        points=24,
    )

    bevel_len = thick / np.tan(bevel_angle)
    back_r = 0.006
    xs = np.concatenate(
        [
            x_blade + back_r * (1.0 - np.cos(np.linspace(0.3, np.pi / 2, 5))),
            np.linspace(x_blade + back_r, x_front - corner_r, 8)[1:],
            x_front - corner_r + corner_r * np.sin(np.linspace(0.0, np.pi / 2, 14))[1:],
            [x_front - bevel_len],
        ]
    )
    xs = np.unique(xs)
    u = (xs - x_blade) / blade_len
    width = back_w + (front_w - back_w) * u
    c = np.clip((xs - (x_front - corner_r)) / corner_r, 0.0, 1.0)
    width -= 2.0 * corner_r * (1.0 - np.sqrt(1.0 - c**2))
    b = np.clip((x_blade + back_r - xs) / back_r, 0.0, 1.0)
    width -= 2.0 * back_r * (1.0 - np.sqrt(1.0 - b**2))
    z_bot = z_blade - thick / 2
    z_top = np.minimum(z_blade + thick / 2, z_bot + (x_front - xs) * np.tan(bevel_angle))
    z_top[-1] = z_bot  # the front station is the edge line itself
    half = width / 2
    n = xs.shape[0]
    sec = np.stack(
        [
            np.stack([-half, np.full(n, z_bot)], axis=1),
            np.stack([half, np.full(n, z_bot)], axis=1),
            np.stack([half, z_top], axis=1),
            np.stack([-half, z_top], axis=1),
        ],
        axis=1,
    )
    rings = np.empty((n, 4, 3))
    rings[..., 0] = xs[:, None]
    rings[..., 1:] = sec
    blade = sweep(rings)

    solid = union([tag(handle, "handle"), tag(shank, "shaft"), tag(blade, "blade")])
    if n_slots:
        slot_w = 0.005
        slot_len = 0.5 * blade_len
        x_mid = x_blade + 0.5 * blade_len
        spacing = 0.6 * back_w / max(n_slots, 1)
        ys = (np.arange(n_slots) - (n_slots - 1) / 2.0) * spacing
        slots = []
        for y in ys:  # at most four slots
            outline = manifold3d.CrossSection.batch_hull(
                [
                    manifold3d.CrossSection.circle(slot_w / 2, 24).translate(
                        (x_mid - slot_len / 2, y)
                    ),
                    manifold3d.CrossSection.circle(slot_w / 2, 24).translate(
                        (x_mid + slot_len / 2, y)
                    ),
                ]
            )
            slots.append(outline.extrude(0.02).translate((0.0, 0.0, z_blade - 0.01)))
        solid = solid - tag(union(slots), "blade")
    return solid
