"""The self-contained HTML viewer: its content, and a real headless Chromium drawing it."""

import json
import re

import numpy as np
import pytest

from affordgrasp.viz import auto_camera, grasp_scene
from affordgrasp.viz.html import ViewerEntry, viewer_document, write_viewer

from .conftest import grasp_row_on_box


@pytest.fixture(scope="module")
def page(tmp_path_factory, box_object):
    entries = []
    for i, spread in enumerate((0.0, 0.5)):
        scene = grasp_scene(box_object, grasp_row_on_box(box_object, spread=spread, sample=i))
        entries.append(
            ViewerEntry(
                scene,
                auto_camera(scene, width=96, height=96, candidates=16),
                title=f"grasp {i} </script><!-- tricky",
                group="bar · pick",
                facts=[("sample", str(i)), ("note", "<b>not html</b>")],
            )
        )
    return write_viewer(tmp_path_factory.mktemp("html") / "view.html", entries, title="viewer test")


def embedded_document(text: str) -> dict:
    m = re.search(
        r'<script id="affordgrasp-data" type="application/json">(.*?)</script>', text, re.S
    )
    assert m, "the data script is missing"
    return json.loads(m.group(1))


def test_page_is_self_contained(page):
    text = page.read_text()
    # Nothing is loaded from elsewhere: no src/href attributes at all, scripts inline.
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)=", text, re.I)
    assert "import(" not in text.split("<script>", 1)[0]
    assert text.count("<script") == 3 and text.count("</script>") == 3
    doc = embedded_document(text)
    assert len(doc["grasps"]) == 2 and len(doc["objects"]) == 1  # the object is sent once
    assert doc["grasps"][0]["title"].startswith("grasp 0 </script>")  # escaped, intact
    assert list(doc["hands"]) == ["barrett"]
    assert len(doc["grasps"][0]["link_poses"]) == len(doc["hands"]["barrett"]["links"])


def test_document_meshes_round_trip(box_object):
    import base64

    scene = grasp_scene(box_object, grasp_row_on_box(box_object))
    doc = viewer_document(
        [ViewerEntry(scene, auto_camera(scene, width=64, height=64, candidates=8))]
    )
    mesh = doc["objects"][0]["mesh"]
    positions = np.frombuffer(base64.b64decode(mesh["positions"]), "<f4").reshape(-1, 3)
    index = np.frombuffer(base64.b64decode(mesh["index"]), "<u2").reshape(-1, 3)
    normals = np.frombuffer(base64.b64decode(mesh["normals"]), np.int8).reshape(-1, 3) / 127.0
    np.testing.assert_allclose(positions[index], box_object.mesh.triangles, atol=1e-7)
    # A box keeps its sharp edges: every corner's normal is its face's normal.
    np.testing.assert_allclose(
        normals[index], np.repeat(box_object.mesh.face_normals[:, None, :], 3, axis=1), atol=0.01
    )
    # Link poses are the row-major link -> object transforms.
    pose = np.asarray(doc["grasps"][0]["link_poses"][0]).reshape(4, 4)
    np.testing.assert_allclose(pose, scene.link_poses[0])


def test_chromium_draws_the_page_without_errors(chromium, page):
    chromium.console_errors.clear()
    chromium.navigate(page.as_uri())
    status = chromium.wait_for(
        "(s => s !== 'loading' && s)(document.documentElement.dataset.status)"
    )
    chromium.collect_events()
    assert chromium.console_errors == []
    assert status == "ready", f"viewer status {status!r} (WebGL unavailable?)"
    drawn = int(chromium.evaluate("document.documentElement.dataset.drawn"))
    assert drawn > 2000, "the canvas is (nearly) empty"

    # The screenshot shows the object (grey) and the hand (blue) inside the canvas.
    rect = json.loads(
        chromium.evaluate("JSON.stringify(document.getElementById('view').getBoundingClientRect())")
    )
    shot = chromium.screenshot().astype(int)
    x0, y0 = int(rect["left"]), int(rect["top"])
    canvas = shot[y0 : y0 + int(rect["height"]), x0 : x0 + int(rect["width"])]
    not_white = (canvas < 245).any(axis=2)
    assert not_white.mean() > 0.02
    blue = (canvas[..., 2] - canvas[..., 0] > 60) & not_white
    grey = (np.ptp(canvas, axis=2) < 12) & (canvas.mean(axis=2) > 90) & (canvas.mean(axis=2) < 235)
    assert blue.sum() > 500 and grey.sum() > 200

    # Toggles act on the drawing; the other grasp can be selected.
    with_hand = chromium.evaluate("affordgraspViewer.drawnPixels()")
    chromium.evaluate("affordgraspViewer.setLayer('hand', false)")
    without_hand = chromium.evaluate("affordgraspViewer.drawnPixels()")
    assert without_hand < with_hand
    chromium.evaluate("affordgraspViewer.setLayer('hand', true); affordgraspViewer.select(1)")
    assert chromium.evaluate(
        "document.querySelector('.card.selected span').textContent"
    ).startswith("grasp 1")
    assert chromium.evaluate("document.querySelector('#grasp-info').textContent").count("<b>") == 1
    chromium.evaluate(
        "affordgraspViewer.setLayer('cones', true); affordgraspViewer.setLayer('xray', true)"
    )
    chromium.collect_events()
    assert chromium.console_errors == []
