"""Families with a head on a handle: hammer and axe.

Frame (before the bounding-box centring done by the caller): the handle lies along +x with
its butt at x = 0; the head sits at the +x end and extends along y, its working side towards
-y (the hammer's striking face, the axe's cutting edge) and its back towards +y (the claw or
ball peen, the axe's poll).  Both are symmetric about z = 0; the axe's edge line runs along x
in the plane z = 0 and the head's flat cheeks face +/-z.
"""

from __future__ import annotations

import manifold3d
import numpy as np

from affordgrasp.objects.families.geometry import rounded_stations, superellipse, sweep, union
from affordgrasp.objects.families.handles import curved_bar, straight_grip
from affordgrasp.objects.families.parameters import ParameterDraw
from affordgrasp.objects.families.parts import tag

__all__ = ["hammer", "axe"]

_Z = np.array([0.0, 0.0, 1.0])


def _head_along_y(x_center: float, stations: np.ndarray, points: int = 40) -> manifold3d.Manifold:
    """Sweep superellipse sections along y.

    stations : (n, 4) float, rows (y, half_x, half_z, exponent), y increasing, m.
    """
    rings = np.empty((stations.shape[0], points, 3))
    for i, (y, hx, hz, n) in enumerate(stations):  # a dozen stations
        sec = superellipse(hx, hz, n, points, half_step=True)
        rings[i, :, 0] = x_center + sec[:, 0]
        rings[i, :, 1] = y
        rings[i, :, 2] = sec[:, 1]
    return sweep(rings)


def _arc(start: np.ndarray, length: float, bend: float, n: int) -> np.ndarray:
    """Circular arc in the x-y plane leaving ``start`` along +y and bending towards -x.

    length : arc length, m; bend : total turning angle, rad.  Returns (n, 3) float.
    """
    s = np.linspace(0.0, 1.0, n)
    radius = length / bend
    psi = s * bend
    x = start[0] - radius * (1.0 - np.cos(psi))
    y = start[1] + radius * np.sin(psi)
    return np.stack([x, y, np.full(n, start[2])], axis=1)


def hammer(p: ParameterDraw) -> manifold3d.Manifold:
    """Claw or ball-peen hammer; 0.26-0.34 m long, head 0.09-0.13 m across.

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
    style = p.choice("style", ("claw", "ball_peen"), "claw")
    length = p.uniform("handle_length_m", 0.26, 0.335, 0.31)
    face_r = p.uniform("face_radius_m", 0.012, 0.016, 0.0145)
    face_reach = p.uniform("face_reach_m", 0.045, 0.06, 0.052)
    cheek_hx = p.uniform("head_half_height_m", 0.012, 0.016, 0.014)
    cheek_hz = p.uniform("head_half_width_m", 0.011, 0.014, 0.0125)
    neck = p.uniform("neck_fraction", 0.7, 0.85, 0.78)
    grip_hy = p.uniform("grip_half_height_m", 0.0135, 0.0165, 0.015)
    grip_hz = p.uniform("grip_half_width_m", 0.0095, 0.012, 0.011)
    grip_flare = p.uniform("grip_butt_flare", 0.05, 0.3, 0.15)
    grip_exp = p.uniform("grip_squareness", 2.0, 2.8, 2.3)
    cheek_hy = 0.02

    # The head's top is at x = length; the handle's end stands 3 mm proud of it (wedged).
    x_head = length - cheek_hx
    stations = [
        (-face_reach, 0.9 * face_r, 0.9 * face_r, 2.0),  # chamfered striking face
        (-face_reach + 0.0015, face_r, face_r, 2.0),
        (-face_reach + 0.009, face_r, face_r, 2.0),
        (-face_reach + 0.017, neck * face_r, neck * face_r, 2.0),
        (-cheek_hy - 0.004, 0.95 * cheek_hx, 0.95 * cheek_hz, 3.0),
        (-cheek_hy, cheek_hx, cheek_hz, 4.0),
        (cheek_hy, cheek_hx, cheek_hz, 4.0),
    ]
    parts: list[manifold3d.Manifold] = []
    if style == "claw":
        claw_len = p.uniform("claw_length_m", 0.045, 0.065, 0.055)
        bend = np.radians(p.uniform("claw_bend_deg", 35.0, 65.0, 50.0))
        stations.append((cheek_hy + 0.004, 0.95 * cheek_hx, 0.95 * cheek_hz, 3.5))
        path = _arc(np.array([x_head, cheek_hy - 0.002, 0.0]), claw_len, bend, 24)
        s = np.linspace(0.0, 1.0, path.shape[0])
        half_u = cheek_hx * (1.0 - 0.8 * s**1.2)
        half_v = cheek_hz * (0.95 - 0.15 * s)
        claw = curved_bar(path, _Z, half_u, half_v, exponent=3.0, points=32)
        # The V slot between the two tines, which pulls nails.
        slot_path = _arc(np.array([x_head, cheek_hy - 0.002, 0.0]), 1.3 * claw_len, 1.3 * bend, 30)
        t = np.linspace(0.0, 1.3, slot_path.shape[0])
        start = 0.45
        keep = t >= start
        slot_half = 0.0004 + 0.0032 * (t[keep] - start) / (1.0 - start)
        slot = curved_bar(
            slot_path[keep], _Z, np.full(keep.sum(), 0.03), slot_half, exponent=8.0, points=16
        )
        parts.append(tag(claw - slot, "claw"))
    else:
        peen_r = p.uniform("peen_radius_m", 0.011, 0.015, 0.013)
        peen_reach = p.uniform("peen_reach_m", 0.035, 0.05, 0.042)
        stations += [
            (cheek_hy + 0.005, 0.8 * cheek_hx, 0.8 * cheek_hz, 2.5),
            (peen_reach - 0.3 * peen_r, 0.7 * peen_r, 0.7 * peen_r, 2.0),
        ]
        ball = manifold3d.Manifold.sphere(peen_r, circular_segments=40)
        parts.append(tag(ball.translate((x_head, peen_reach - 0.2 * peen_r, 0.0)), "peen"))
    parts.append(tag(_head_along_y(x_head, np.array(stations)), "head"))
    handle = straight_grip(
        0.0,
        length + 0.003,
        min(grip_hy, 0.8 * cheek_hy),
        min(grip_hz, 0.8 * cheek_hz),
        exponent=grip_exp,
        bulge=0.05,
        butt_flare=grip_flare,
        front_round=0.0015,
    )
    parts.append(tag(handle, "handle"))
    return union(parts)


def axe(p: ParameterDraw) -> manifold3d.Manifold:
    """Hatchet to camp axe with a bearded, curved bit; 0.36-0.70 m long.

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
    length = p.uniform("haft_length_m", 0.36, 0.68, 0.48)
    edge_len = p.uniform("edge_length_m", 0.075, 0.12, 0.095)
    bit_reach = p.uniform("bit_reach_m", 0.085, 0.13, 0.10)
    eye_h = p.uniform("eye_height_m", 0.045, 0.06, 0.052)
    edge_curve = p.uniform("edge_curvature_m", 0.003, 0.012, 0.007)
    edge_angle = np.radians(p.uniform("edge_angle_deg", 20.0, 26.0, 23.0))
    shoulder_t = p.uniform("shoulder_thickness_m", 0.003, 0.005, 0.004)
    thickness = p.uniform("head_thickness_m", 0.022, 0.030, 0.026)
    beard_power = p.uniform("beard_power", 1.3, 2.2, 1.7)
    haft_hy = p.uniform("haft_half_height_m", 0.015, 0.018, 0.0165)
    haft_hz = p.uniform("haft_half_width_m", 0.011, 0.013, 0.012)
    knob = p.uniform("knob_flare", 0.15, 0.35, 0.25)
    kick = p.uniform("haft_curve_m", 0.0, 0.02, 0.01)
    poll = p.uniform("poll_reach_m", 0.022, 0.035, 0.027)

    tan_half = np.tan(edge_angle / 2.0)
    bevel = shoulder_t / 2.0 / tan_half
    eye_front = -haft_hy - 0.004
    poll = max(poll, haft_hy + 0.008)
    run = eye_front - (-bit_reach + bevel)
    # The cheeks must flare less than the edge bevel, or the section would not be convex.
    thickness = min(thickness, shoulder_t + 2.0 * 0.85 * tan_half * run)
    p.values["head_thickness_m"] = thickness
    cheek_slope = (thickness / 2.0 - shoulder_t / 2.0) / run
    edge_len = max(edge_len, eye_h + 0.012)
    p.values["edge_length_m"] = edge_len

    x_top = length
    x_bot = x_top - edge_len
    x_eye = x_top - eye_h
    xs = np.concatenate([np.linspace(x_bot, x_eye - 0.0015, 18), np.linspace(x_eye, x_top, 10)])
    xm = 0.5 * (x_bot + x_top)
    y_edge = -bit_reach + edge_curve * (2.0 * (xs - xm) / edge_len) ** 2
    slope = np.gradient(y_edge, xs)
    cos_t = 1.0 / np.sqrt(1.0 + slope**2)
    back_min = y_edge[0] + bevel / cos_t[0] + 0.008
    v = np.clip((xs - x_bot) / (x_eye - 0.0015 - x_bot), 0.0, 1.0)
    y_back = np.where(xs < x_eye, back_min + (eye_front - back_min) * v**beard_power, poll)

    # Thickness as a function of the distance d from the edge (perpendicular to it): the
    # edge bevel, then cheeks ground parallel to the edge, then the flat eye/poll region.
    # It is concave in d, so every section is convex.
    y_sh = y_edge + bevel / cos_t
    y_crease = y_edge + (bevel + (thickness - shoulder_t) / (2.0 * cheek_slope)) / cos_t
    n_chain = 10
    rings = np.empty((xs.shape[0], 1 + 2 * n_chain, 3))
    for i in range(xs.shape[0]):  # ~30 stations, each vectorised
        ys = y_sh[i] + (y_back[i] - y_sh[i]) * np.linspace(0.0, 1.0, n_chain)
        if y_sh[i] < y_crease[i] < y_back[i]:
            j = 1 + int(np.argmin(np.abs(ys[1:-1] - y_crease[i])))
            ys[j] = y_crease[i]  # keep the crease where the cheek meets the eye
        d = (ys - y_edge[i]) * cos_t[i]
        half = 0.5 * np.minimum(
            np.minimum(2.0 * tan_half * d, shoulder_t + 2.0 * cheek_slope * (d - bevel)), thickness
        )
        rings[i, 0] = (xs[i], y_edge[i], 0.0)
        rings[i, 1 : 1 + n_chain] = np.stack([np.full(n_chain, xs[i]), ys, half], axis=1)
        rings[i, 1 + n_chain :] = np.stack([np.full(n_chain, xs[i]), ys[::-1], -half[::-1]], axis=1)
    head = sweep(rings)

    xs_h, dome = rounded_stations(0.0, x_top + 0.003, 0.012, 0.0015, middle=30)
    u = xs_h / (x_top + 0.003)
    bend_to = 0.6
    y_path = -kick * np.maximum(0.0, 1.0 - u / bend_to) ** 2
    path = np.stack([xs_h, y_path, np.zeros_like(xs_h)], axis=1)
    knob_zone = np.maximum(0.0, 1.0 - u / 0.12) ** 2
    top_zone = np.clip((u - 0.8) / 0.2, 0.0, 1.0)
    hz_top = min(haft_hz, 0.38 * thickness)
    half_u = haft_hy * (1.0 + knob * knob_zone) * (1.0 - 0.08 * np.sin(np.pi * u)) * dome
    half_v = (haft_hz + (hz_top - haft_hz) * top_zone) * (1.0 + 0.5 * knob * knob_zone) * dome
    haft = curved_bar(path, _Z, half_u, half_v, exponent=2.2, points=36)
    return union([tag(haft, "handle"), tag(head, "head")])
