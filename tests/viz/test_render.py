"""The PNG renderer (viz/camera, viz/raycast, viz/overlays): geometry checked in pixels."""

import io

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import binary_dilation

from affordgrasp.errors import InputError
from affordgrasp.viz import (
    Camera,
    GraspScene,
    OverlayStyle,
    auto_camera,
    grasp_image,
    grasp_scene,
    render_image,
    save_grasp_png,
)
from affordgrasp.viz.raycast import HAND_PART, OBJECT_PART


def top_camera(size=128, height=0.5):
    """Looking straight down at the origin, image x along object +x, image up along +y."""
    return Camera(
        eye=[0, 0, height], target=[0, 0, 0], up=[0, 1, 0], fov_deg=40, width=size, height=size
    )


def test_projection_and_rays_agree():
    cam = Camera(
        eye=[0.3, -0.4, 0.2],
        target=[0.01, 0.02, 0.0],
        up=[0, 0, 1],
        fov_deg=35,
        width=64,
        height=48,
    )
    uv, dist = cam.project(cam.target[None])
    np.testing.assert_allclose(uv[0], [32, 24], atol=1e-9)
    assert dist[0] == pytest.approx(np.linalg.norm(cam.eye - cam.target))
    origins, dirs = cam.rays()
    # A point along the ray through pixel (i, j) projects to that pixel's centre.
    k = 5 * 64 + 17
    uv, _ = cam.project(origins[k] + 0.3 * dirs[k])
    np.testing.assert_allclose(uv[0], [17.5, 5.5], atol=1e-9)
    # Points behind the camera do not project.
    uv, _ = cam.project((2 * cam.eye - cam.target)[None])
    assert np.all(np.isnan(uv))


def test_camera_rejects_bad_values():
    with pytest.raises(InputError, match="fov_deg"):
        Camera([0, 0, 1], [0, 0, 0], [0, 1, 0], fov_deg=0.0)
    with pytest.raises(InputError, match="eye and target"):
        Camera([0, 0, 0], [0, 0, 0], [0, 1, 0])


def test_box_is_drawn_where_the_camera_says(box_object):
    cam = top_camera()
    render = render_image(GraspScene(box_object.mesh, None), cam, supersample=2)
    assert render.rgb.shape == (128, 128, 3) and render.rgb.dtype == np.uint8
    obj = render.part == OBJECT_PART
    # The top face (z = 0.015) of the 20 x 4 cm box, projected: its pixel extent must match.
    lo, hi = box_object.mesh.bounds
    corners = np.array([[x, y, hi[2]] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    uv, _ = cam.project(corners)
    rows, cols = np.nonzero(obj)
    assert cols.min() == pytest.approx(uv[:, 0].min(), abs=1.0)
    assert cols.max() + 1 == pytest.approx(uv[:, 0].max(), abs=1.0)
    assert rows.min() == pytest.approx(uv[:, 1].min(), abs=1.0)
    assert rows.max() + 1 == pytest.approx(uv[:, 1].max(), abs=1.0)
    # Wider than tall: x of the object is the image's x.
    assert cols.max() - cols.min() > 4 * (rows.max() - rows.min())
    # Background white, object grey and shaded (not white, not coloured).
    near = binary_dilation(obj, iterations=2)  # edges are anti-aliased
    assert np.all(render.rgb[~near] == 255)
    inner = (
        render.rgb[rows.min() + 3 : rows.max() - 3, cols.min() + 3 : cols.max() - 3]
        .reshape(-1, 3)
        .astype(int)
    )
    assert np.all(inner.max(axis=1) < 245)
    assert np.all(np.ptp(inner, axis=1) < 12)
    # Depth is the distance along the ray: the eye is 0.5 m above z = 0, the top face at hi z.
    assert render.depth[64, 64] == pytest.approx(0.5 - hi[2], abs=1e-4)
    assert np.all(np.isinf(render.depth[render.part == 0]))


def test_hand_is_blue_and_above_the_box(box_object, box_row):
    scene = grasp_scene(box_object, box_row)
    cam = top_camera(160, height=0.6)
    render = render_image(scene, cam)
    hand = render.part == HAND_PART
    assert hand.sum() > 500 and (render.part == OBJECT_PART).sum() > 100
    rgb = render.rgb[hand].astype(int)
    assert np.median(rgb[:, 2] - rgb[:, 0]) > 40  # blue-ish
    # Seen from above, the hand (palm 6 cm above the box) is nearer than the box.
    assert np.median(render.depth[hand]) < np.median(render.depth[render.part == OBJECT_PART])


def test_auto_camera_frames_object_and_hand(box_object, box_row):
    scene = grasp_scene(box_object, box_row)
    cam = auto_camera(scene, width=200, height=150)
    pts = np.concatenate([box_object.mesh.vertices, scene.hand.mesh.vertices])
    uv, _ = cam.project(pts)
    assert np.all(uv[:, 0] >= 0) and np.all(uv[:, 0] <= 200)
    assert np.all(uv[:, 1] >= 0) and np.all(uv[:, 1] <= 150)
    # Tight: the scene spans most of one image side.
    span = (uv.max(axis=0) - uv.min(axis=0)) / [200, 150]
    assert span.max() > 0.8
    # The hand came from +z (wrist axis -z): it is drawn above the object.
    r = render_image(scene, cam, supersample=1)
    hand_rows = np.nonzero(r.part == HAND_PART)[0]
    obj_rows = np.nonzero(r.part == OBJECT_PART)[0]
    assert np.median(hand_rows) < np.median(obj_rows)


def test_overlays_mark_contacts_and_use_point(box_object, box_row):
    scene = grasp_scene(box_object, box_row)
    cam = top_camera(256, height=0.6)
    style = OverlayStyle(contacts=True, normals=False, wrist_axis=False, center_of_mass=False)
    image, used = grasp_image(scene, size_px=256, camera=cam, style=style, caption="")
    assert used == cam
    orange = (
        (image[..., 0] > 200)
        & (np.abs(image[..., 1].astype(int) - 140) < 40)
        & (image[..., 2] < 80)
    )
    red = (image[..., 0] > 170) & (image[..., 1] < 80) & (image[..., 2] < 80)
    uv, _ = cam.project(np.asarray(box_row["contact_points"]))
    for u, v in uv:
        r0, c0 = int(v), int(u)
        assert orange[r0 - 4 : r0 + 5, c0 - 4 : c0 + 5].any(), (u, v)
    uv, _ = cam.project(np.asarray([box_row["use_point"]]))
    r0, c0 = int(uv[0, 1]), int(uv[0, 0])
    assert red[r0 - 5 : r0 + 6, c0 - 5 : c0 + 6].any()
    # Nothing orange far from the contacts.
    far = np.ones_like(orange)
    for u, v in cam.project(np.asarray(box_row["contact_points"]))[0]:
        far[int(v) - 10 : int(v) + 11, int(u) - 10 : int(u) + 11] = False
    assert not orange[far].any()


def test_png_is_deterministic_and_readable(tmp_path, box_object, box_row):
    scene = grasp_scene(box_object, box_row, title="bar #0")
    a = tmp_path / "a.png"
    b = tmp_path / "b.png"
    save_grasp_png(scene, a, size_px=200, style=OverlayStyle(cones=True))
    save_grasp_png(scene, b, size_px=200, style=OverlayStyle(cones=True))
    assert a.read_bytes() == b.read_bytes()
    image = np.asarray(Image.open(io.BytesIO(a.read_bytes())).convert("RGB"))
    assert image.shape == (200, 200, 3)
    assert (image < 250).any(axis=2).mean() > 0.1  # something drawn


def test_rows_with_the_wrong_hand_are_refused(box_object, box_row):
    row = dict(box_row, joints=[0.0, 0.1])
    with pytest.raises(InputError, match="DOFs"):
        grasp_scene(box_object, row)
    with pytest.raises(InputError, match="hand_pose"):
        grasp_scene(box_object, {k: v for k, v in box_row.items() if k != "hand_pose"})


def test_rows_from_arrow_and_pandas_give_the_same_scene(tmp_path, box_object, box_row):
    import pyarrow as pa

    pytest.importorskip("pandas")

    table = pa.Table.from_pylist([box_row])
    from_arrow = grasp_scene(box_object, table.to_pylist()[0])
    from_pandas = grasp_scene(box_object, table.to_pandas().iloc[0].to_dict())
    np.testing.assert_array_equal(from_arrow.hand.mesh.vertices, from_pandas.hand.mesh.vertices)
    np.testing.assert_array_equal(from_arrow.contact_points, from_pandas.contact_points)
    np.testing.assert_array_equal(from_arrow.contact_mu, from_pandas.contact_mu)
    assert list(from_pandas.contact_link) == box_row["contact_link"]
