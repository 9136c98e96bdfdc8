"""Embree through ``embreex``, one ray per call: the scenes of the one-ray backends.

* :class:`EmbreeScene`: triangles in a robust (watertight) float32 scene, relative to a
  chosen origin and scale; casts any rays (:class:`~affordgrasp.rays.RayCaster`);
* :class:`EmbreeRays`: a mesh's scene in trimesh's frame, answering trimesh's ray queries
  (:class:`~affordgrasp.rays.MeshCaster`) without importing trimesh (about half a second, most
  of a command's start-up: it imports much of scipy).

:class:`EmbreeRays` makes the same Embree calls on the same float32 data as trimesh 4-5's
``RayMeshIntersector`` (mesh scaled to a 100-unit box, hits advanced along the ray by the
same offsets, :mod:`affordgrasp.rays.crossings`), so the faces and points hit are the same
bits; ``tests/rays/test_embree.py`` compares the two on random rays.
"""

from __future__ import annotations

import numpy as np

from . import MeshCaster, RayHits, ray_hits, unit_face_normals

_EMBREE_DTYPE = np.float32
_RAY_OFFSET_FACTOR = 1e-6
_RAY_OFFSET_FLOOR = 1e-8
_TOL_ZERO = float(np.finfo(np.float64).resolution * 100)  # trimesh.util.TOL_ZERO
_EMBREE_MISS = 1e30  # Embree reports a miss as tfar = 1e37


def _unitize(vectors: np.ndarray) -> np.ndarray:
    # trimesh.util.unitize for (n, d) arrays, same operations
    norm = np.sqrt(np.dot(vectors * vectors, [1.0] * vectors.shape[1]))
    valid = norm > _TOL_ZERO
    norm[valid] **= -1
    return vectors * norm.reshape((-1, 1))


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


class SceneFrame:
    """Triangles as an Embree scene holds them: float32, in the frame ``(x − origin)·scale``.

    Embree is float32: the triangles and the rays are moved to the scene's frame before
    rounding, so an origin near the triangles keeps the precision. The base of the scenes
    of every Embree backend (:class:`EmbreeScene`, :class:`~.packets.PacketScene`).

    Parameters
    ----------
    vertices : (v, 3) or (t, 3, 3) float ndarray
        The vertices (with ``faces``) or the triangles (without), m.
    faces : (t, 3) int ndarray, optional
        Vertex indices of each triangle.
    origin : (3,) float ndarray, optional
        The scene frame's origin, m (default 0).
    scale : float
        Scene units per metre.
    face_normals : (t, 3) float ndarray, optional
        Unit normal of each triangle (default: from the winding, :func:`unit_face_normals`).
    """

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray | None = None,
        *,
        origin: np.ndarray | None = None,
        scale: float = 1.0,
        face_normals: np.ndarray | None = None,
    ) -> None:
        self._vertices = np.asarray(vertices, dtype=np.float64)
        self._faces = None if faces is None else np.asarray(faces)
        self._origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=np.float64)
        self._scale = float(scale)
        self._face_normals = None if face_normals is None else np.asarray(face_normals)

    @property
    def scene_vertices(self) -> np.ndarray:
        """(v, 3) or (t, 3, 3) float32 ndarray: the vertices in the scene's frame."""
        return ((self._vertices - self._origin) * self._scale).astype(_EMBREE_DTYPE)

    @property
    def triangles(self) -> np.ndarray:
        """(t, 3, 3) float64 ndarray: the triangles, m."""
        if self._faces is None:
            return self._vertices
        return self._vertices[self._faces]

    @property
    def normals(self) -> np.ndarray:
        """(t, 3) float64 ndarray: unit normal of every triangle."""
        if self._face_normals is None:
            self._face_normals = unit_face_normals(self.triangles)
        return self._face_normals

    @property
    def scene_frame(self) -> tuple[np.ndarray, float]:
        """Embree's frame: a point x is ``(x - origin) * scale`` there, in float32."""
        return self._origin, self._scale

    def to_scene(self, origins: np.ndarray, directions: np.ndarray):
        """Rays in Embree's frame.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; directions as given (not made unit).

        Returns
        -------
        origins, directions : (n, 3) float32 ndarray
        """
        scaled = (np.array(origins, dtype=np.float64) - self._origin) * self._scale
        return scaled.astype(_EMBREE_DTYPE), np.asarray(directions).astype(_EMBREE_DTYPE)


class EmbreeScene(SceneFrame):
    """Triangles in one Embree scene (``embreex``, one ray per call, robust, float32).

    The :class:`~affordgrasp.rays.RayCaster` backend that casts any rays.

    Parameters
    ----------
    vertices, faces
        As :class:`SceneFrame`'s.
    **frame
        ``origin``, ``scale`` and ``face_normals``, as :class:`SceneFrame`'s.
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


class EmbreeRays(EmbreeScene, MeshCaster):
    """A mesh's :class:`EmbreeScene` in trimesh's frame (its lowest corner at 0, scaled to a
    100-unit box), answering trimesh's ray queries (:class:`~affordgrasp.rays.MeshCaster`).

    Parameters
    ----------
    vertices : (v, 3) float64 ndarray
        m.
    faces : (f, 3) int ndarray
    face_normals : (f, 3) float64 ndarray
        Unit normals, as trimesh computes them (the hit points are on these planes).
    scale : float
        The mesh's bounding-box diagonal, m (trimesh's ``mesh.scale``).
    """

    def __init__(
        self, vertices: np.ndarray, faces: np.ndarray, face_normals: np.ndarray, scale: float
    ) -> None:
        vertices = np.asarray(vertices, dtype=np.float64)
        self._mesh_scale = float(scale)
        super().__init__(
            vertices,
            faces,
            origin=vertices.min(axis=0),
            scale=float(100.0 / self._mesh_scale),
            face_normals=np.asarray(face_normals, dtype=np.float64),
        )

    # The pieces of trimesh's multiple-hit loop, which :mod:`affordgrasp.rays.crossings`
    # runs compiled.

    @property
    def ray_offset(self) -> float:
        """How far a ray restarts past a hit, m (doubled for a repeated face)."""
        return max(_RAY_OFFSET_FLOOR, self._mesh_scale * _RAY_OFFSET_FACTOR)

    @property
    def face_planes(self) -> tuple[np.ndarray, np.ndarray]:
        """(f, 3) float64 first vertex and (f, 3) unit normal of every face."""
        planes = getattr(self, "_planes", None)
        if planes is None:
            # writable C-contiguous copies: one signature of the compiled loop, whether the
            # mesh's arrays are read-only (a cached object) or not
            planes = self._planes = (
                np.array(self._vertices[self._faces][:, 0, :], order="C"),
                np.array(self.normals, dtype=np.float64, order="C"),
            )
        return planes

    def unit_directions(self, directions: np.ndarray) -> np.ndarray:
        """Directions made unit as the ray loop makes them.

        Parameters
        ----------
        directions : (n, 3) float64 ndarray

        Returns
        -------
        (n, 3) float64 ndarray
        """
        return _unitize(directions)

    def crossings(self, origins, directions, reach: float | None = None):
        """Every crossing of each ray (:meth:`~affordgrasp.rays.MeshCaster.crossings`), by
        :func:`~.crossings.all_crossings`, or :func:`~.crossings.near_crossings` with ``reach``.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; directions need not be unit.
        reach : float, optional
            m.

        Returns
        -------
        index_tri, index_ray : (m,) int64 ndarray
        locations : (m, 3) float64 ndarray
        """
        from .crossings import all_crossings, near_crossings

        if reach is None:
            return all_crossings(self, origins, directions)
        return near_crossings(self, origins, directions, reach)

    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True):
        """Hit points, rays and faces (trimesh's ``mesh.ray.intersects_location``).

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m.
        multiple_hits : bool
            Every hit along each ray, else the first.

        Returns
        -------
        locations : (m, 3) float64 ndarray
        index_ray, index_tri : (m,) int64 ndarray
        """
        from .crossings import all_crossings, first_crossings

        crossings = all_crossings if multiple_hits else first_crossings
        index_tri, index_ray, locations = crossings(self, ray_origins, ray_directions)
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins, ray_directions) -> np.ndarray:
        """Index of the first face each ray hits, -1 for a miss.

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m.

        Returns
        -------
        (n,) int ndarray
        """
        ray_origins = np.array(ray_origins, dtype=_EMBREE_DTYPE)
        ray_directions = np.array(ray_directions, dtype=_EMBREE_DTYPE)
        if ray_origins.shape != ray_directions.shape:
            raise ValueError("Ray origin and direction don't match!")
        return self.first_faces_scene(*self.to_scene(ray_origins, _unitize(ray_directions)))
