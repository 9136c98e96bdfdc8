"""The hand view: a fixed metric scale whatever the camera's distance, the fingers' closing
planes and the palm where the hand model puts them, and models that read it."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from affordgrasp.learning.views import (
    FINGER_HALF_WIDTH_M,
    PALM_RADIUS_M,
    VIEW_PIXEL_M,
    VIEW_SIZE,
    finger_planes,
    hand_view,
)

FOV = 60.0
SIZE = 128
K = math.tan(math.radians(FOV) / 2) / (SIZE / 2)
RAY = (np.arange(SIZE) + 0.5 - SIZE / 2) * K  # camera ray per column (and per row)
GRID = (np.arange(VIEW_SIZE) + 0.5 - VIEW_SIZE / 2) * VIEW_PIXEL_M  # the view's metric grid


def _plane(z_m: float) -> np.ndarray:
    """A plane facing the camera at depth z, filling the image."""
    return np.full((1, SIZE, SIZE), round(z_m * 1000), dtype=np.uint16)


def _disc(z_m: float, radius_m: float, cx_m: float = 0.0, cy_m: float = 0.0) -> np.ndarray:
    """A disc facing the camera at depth z (its pixels: those whose ray hits it)."""
    x, y = RAY[None, :] * z_m, RAY[:, None] * z_m
    inside = (x - cx_m) ** 2 + (y - cy_m) ** 2 < radius_m**2
    return np.where(inside, round(z_m * 1000), 0).astype(np.uint16)[None]


def test_a_plane_fills_the_view_with_its_metric_scale():
    z = 0.4  # the view (0.384 m) is inside the field of view (0.46 m across at 0.4 m)
    v = hand_view(_plane(z), np.array([0.0]), fov_deg=FOV)
    assert v.shape == (1, 6, VIEW_SIZE, VIEW_SIZE) and v.dtype == np.float32
    assert np.all(v[0, 1] == 1) and np.all(v[0, 0] == 0)  # every pixel a hit at the nearest depth
    # F3's closing plane is x = 0: its channel is exp(-(x/w)^2) of the column's x, which is the
    # metric grid to within half a camera pixel at this depth.
    x_true = np.sqrt(-np.log(np.clip(v[0, 4, 0], 1e-30, 1))) * FINGER_HALF_WIDTH_M
    near = v[0, 4, 0] > 1e-6
    np.testing.assert_allclose(x_true[near], np.abs(GRID)[near], atol=0.5 * K * z + 1e-6)
    # the palm: the pixels within its radius of the approach line
    r = np.hypot(GRID[None, :], GRID[:, None])
    assert np.all(v[0, 5][r < PALM_RADIUS_M - K * z] == 1)
    assert np.all(v[0, 5][r > PALM_RADIUS_M + K * z] == 0)


def test_beyond_the_field_of_view_is_no_return():
    z = 0.15  # the field of view is 0.17 m across: the view's rim lies outside it
    v = hand_view(_plane(z), np.array([0.0]), fov_deg=FOV)
    half_fov = math.tan(math.radians(FOV) / 2) * z
    outside = np.abs(GRID) > half_fov + K * z
    assert np.all(v[0, 1][:, outside] == 0) and np.all(v[0, 1][outside, :] == 0)
    assert np.all(v[0, 2:][:, :, outside] == 0)


@settings(max_examples=25, deadline=None)
@given(
    z1=st.floats(0.2, 0.5),
    scale=st.floats(1.3, 2.0),
    radius=st.floats(0.02, 0.08),
    cx=st.floats(-0.05, 0.05),
)
def test_the_view_does_not_depend_on_the_cameras_distance(z1, scale, radius, cx):
    # The same disc seen from two distances covers different pixels of the camera image and
    # the same area of the view (to within the coarser camera pixel along the outline).
    z2 = z1 * scale
    a = hand_view(_disc(z1, radius, cx), np.array([1.0]), fov_deg=FOV)[0, 1]
    b = hand_view(_disc(z2, radius, cx), np.array([1.0]), fov_deg=FOV)[0, 1]
    camera_a = (_disc(z1, radius, cx) > 0).sum()
    camera_b = (_disc(z2, radius, cx) > 0).sum()
    assert camera_a > 1.5 * camera_b  # the camera image shrinks with the distance
    outline = 2 * math.pi * radius / VIEW_PIXEL_M  # view pixels along the outline
    slack = outline * (1 + K * z2 / VIEW_PIXEL_M)
    assert abs(float(a.sum()) - float(b.sum())) <= slack
    area = math.pi * radius**2 / VIEW_PIXEL_M**2
    assert abs(float(a.sum()) - area) <= slack


def test_finger_planes_follow_the_hand_model():
    # Through each finger's proximal joint, along its arm, as the hand's kinematics place
    # them (the open hand: closing joints at zero).
    from affordgrasp.hands import get_hand

    hand = get_hand("barrett")
    for spread in (0.0, 0.7, math.pi / 2, math.pi):
        planes = finger_planes(np.array([spread]))
        frames = hand.forward_kinematics(hand.open_dofs(spread / math.pi))
        names = hand.link_names
        for f, (bx, by, ax, ay) in zip(("f1", "f2", "f3"), planes, strict=True):
            origin = frames[names.index(f"{f}_prox")][:3, 3]
            np.testing.assert_allclose(origin[:2], [bx[0], by[0]], atol=1e-12)
            tip = frames[names.index(f"{f}_dist")][:3, 3]  # the open finger points outward
            arm = (tip - origin)[:2]
            np.testing.assert_allclose(arm / np.linalg.norm(arm), [ax[0], ay[0]], atol=1e-9)


def test_spread_moves_f1_and_f2_planes():
    plate = _plane(0.4)
    v0 = hand_view(plate, np.array([0.0]), fov_deg=FOV)[0]
    v90 = hand_view(plate, np.array([math.pi / 2]), fov_deg=FOV)[0]
    row, col = np.unravel_index(np.argmax(v90[2]), v90[2].shape)
    # at 90° F1's arm lies along +x through y = 0: its plane is the central row
    assert abs(GRID[row]) < VIEW_PIXEL_M
    # at 0° F1 and F2 stand side by side at x = ±25 mm, arms along +y
    cols1 = np.flatnonzero(v0[2, 0] > 0.99)
    cols2 = np.flatnonzero(v0[3, 0] > 0.99)
    assert np.all(np.abs(GRID[cols1] - 0.025) < VIEW_PIXEL_M)
    assert np.all(np.abs(GRID[cols2] + 0.025) < VIEW_PIXEL_M)
