"""Embree scenes: many alive in one process (a long generate run keeps one per object)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from affordgrasp.objects.rays import EmbreeScene, embree_available, embree_device

pytestmark = pytest.mark.skipif(not embree_available(), reason="embreex is not installed")

# Builds 1500 scenes of 20 triangles each, keeps them alive and casts a ray into each. With a
# device per scene (embreex's default) the process segfaults after about a thousand: run in
# a child process, so that a crash fails this test rather than the suite.
SCRIPT = textwrap.dedent(
    """
    import numpy as np
    from affordgrasp.objects.rays import EmbreeScene

    rng = np.random.default_rng(0)
    scenes = []
    for i in range(1500):
        tri = rng.random((20, 3, 3))
        tri[0] = [[-1.0, -1.0, 0.5], [1.0, -1.0, 0.5], [0.0, 1.0, 0.5]]
        scene = EmbreeScene(tri)
        scenes.append(scene)
        hits = scene.cast(np.array([[0.0, 0.0, -1.0]]), np.array([[0.0, 0.0, 1.0]]))
        assert hits.hit[0] and abs(hits.distance[0] - 1.5) < 1e-5, (i, hits)
    print("ok", len(scenes))
    """
)


def test_a_thousand_scenes_alive_in_one_process():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=240
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert done.stdout.strip() == "ok 1500"


def test_scenes_share_one_device_and_stay_independent():
    a = EmbreeScene(np.array([[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]]))
    b = EmbreeScene(np.array([[[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]]]))
    assert embree_device() is embree_device()
    origin, direction = np.array([[0.2, 0.2, 0.0]]), np.array([[0.0, 0.0, 1.0]])
    assert a.cast(origin, direction).distance[0] == pytest.approx(1.0, abs=1e-6)
    assert b.cast(origin, direction).distance[0] == pytest.approx(2.0, abs=1e-6)
    del a  # releasing one scene leaves the other (and the device) working
    assert b.cast(origin, direction).distance[0] == pytest.approx(2.0, abs=1e-6)
    assert not b.cast(np.array([[5.0, 5.0, 0.0]]), direction).hit[0]
