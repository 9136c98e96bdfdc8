"""Embree through ``embreex``, one ray per call: scenes of triangles that cast any rays.

:class:`EmbreeScene`: triangles in a robust (watertight) ``embreex`` scene, a
:class:`~affordgrasp.rays.RayCaster`; a mesh's (:class:`~.mesh.EmbreeRays`) also answers
trimesh's ray queries.
"""

from __future__ import annotations

import numpy as np

from . import RayHits, SceneFrame, ray_hits

_EMBREE_MISS = 1e30  # Embree reports a miss as tfar = 1e37


_DEVICE = None


def embree_device():
    """The process's one Embree device, shared by every :class:`EmbreeScene`.

    ``embreex`` makes a new device for each scene it is not given one for, and does not
    check that the device was made: with about a thousand scenes alive in one process (a
    ``generate`` run of 500 objects keeps two per object) Embree's device creation fails
    and the next scene segfaults inside Embree. Scenes of one device are independent, and
    tracing them from several threads is safe; one device makes the number of scenes
    limited by memory only (``tests/rays/test_embree.py`` builds 1500).

    Returns
    -------
    embreex.rtcore.EmbreeDevice
    """
    global _DEVICE
    if _DEVICE is None:
        from embreex import rtcore

        _DEVICE = rtcore.EmbreeDevice()
    return _DEVICE


class EmbreeScene(SceneFrame):
    """Triangles in one Embree scene (``embreex``, one ray per call, robust, float32).

    The :class:`~affordgrasp.rays.RayCaster` backend that casts any rays.

    Parameters
    ----------
    vertices, faces
        As :class:`~affordgrasp.rays.SceneFrame`'s.
    **frame
        ``origin``, ``scale`` and ``face_normals``, as :class:`~affordgrasp.rays.SceneFrame`'s.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray | None = None, **frame) -> None:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        super().__init__(vertices, faces, **frame)
        self._scene = rtcore_scene.EmbreeScene(embree_device())
        if self._faces is None:
            TriangleMesh(scene=self._scene, vertices=self.scene_vertices)
        else:
            TriangleMesh(
                scene=self._scene,
                vertices=self.scene_vertices,
                indices=self._faces.view(np.ndarray).astype(np.int32),
            )

    def first_faces_scene(
        self, origins: np.ndarray, directions: np.ndarray, limits: np.ndarray | None = None
    ) -> np.ndarray:
        """The face each ray hits first.

        Parameters
        ----------
        origins, directions : (n, 3) float32 ndarray
            In Embree's frame (:meth:`to_scene`).
        limits : (n,) float32 ndarray, optional
            Farthest ray parameter searched per ray, in the scene's units (Embree's
            ``tfar``); a hit within it is the same as without it. None: unlimited.

        Returns
        -------
        (n,) int ndarray
            Face index, -1 for a miss.
        """
        if limits is None:
            return self._scene.run(origins, directions)
        return self._scene.run(origins, directions, dists=limits)

    def distances_scene(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Ray parameter of each first hit, in the scene's units, 0 for a miss.

        Parameters
        ----------
        origins, directions : (n, 3) float32 ndarray
            In Embree's frame (:meth:`to_scene`).

        Returns
        -------
        (n,) float32 ndarray
        """
        t = self._scene.run(origins, directions, query="DISTANCE")
        return np.where(t < _EMBREE_MISS, t, 0.0).astype(np.float32)

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
        """First hits of rays (the :class:`~affordgrasp.rays.RayCaster` interface).

        Parameters
        ----------
        origins : (n, 3) float array_like
            m.
        directions : (n, 3) float array_like
            Need not be unit.

        Returns
        -------
        RayHits
        """
        o, d = self.to_scene(origins, directions)
        res = self._scene.run(o, d, output=1)
        uv = np.column_stack([res["u"], res["v"]])
        return ray_hits(
            res["tfar"].astype(np.float64) / self._scale, res["primID"], self.normals, uv
        )
