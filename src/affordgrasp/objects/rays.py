"""One ray-casting interface (:class:`RayCaster`) and its Embree backend.

Every ray cast in the package goes through one interface: ``cast(origins, directions)``
returns the first hit of each ray as :class:`RayHits` (distance along the ray, triangle,
unit normal, barycentric coordinates). Its backends:

* :class:`EmbreeScene` (here): Embree through ``embreex``, one ray per call, robust
  (watertight) scene in float32, relative to a chosen origin and scale. The objects' ray
  queries (:class:`EmbreeRays`), the viewer (:mod:`affordgrasp.viz.raycast`) and the
  reference depth engine use it;
* the Embree library that ``embreex`` ships, called in 16-ray packets, and the z-buffer
  rasteriser (:mod:`affordgrasp.vision.engines`; they sit with the depth images they make
  fastest).

``tests/vision/test_engines.py`` checks that every backend gives the same hits on the same
rays against a box and a sphere (analytic distances).

:class:`EmbreeRays` answers trimesh's ray queries without importing trimesh: importing
trimesh costs about half a second (it imports much of scipy), most of a command's start-up.
It makes the same Embree calls on the same float32 data, step for step as trimesh 4-5's
``RayMeshIntersector`` (mesh scaled to a 100-unit box, hits advanced along the ray by the
same offsets), so the faces and points hit are the same bits; tests compare the two on
random rays. Without Embree (``embreex`` missing), :class:`EmbreeRays` is not used and the
caller falls back to trimesh's own engine.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

_EMBREE_DTYPE = np.float32
_RAY_OFFSET_FACTOR = 1e-6
_RAY_OFFSET_FLOOR = 1e-8
_TOL_ZERO = float(np.finfo(np.float64).resolution * 100)  # trimesh.util.TOL_ZERO
_EMBREE_MISS = 1e30  # Embree reports a miss as tfar = 1e37


@dataclass(frozen=True)
class RayHits:
    """The first hit of each of n rays.

    Attributes
    ----------
    distance : (n,) float64 ndarray
        Ray parameter t of the hit: the point is ``origin + t * direction`` (m along the ray
        when the direction is unit; the depth along the optical axis for camera rays with
        z = 1); +inf for a miss.
    triangle : (n,) int64 ndarray
        Index of the triangle hit, -1 for a miss.
    normal : (n, 3) float64 ndarray
        Unit normal of the triangle hit, as wound (outward on an outward-oriented mesh);
        0 for a miss.
    barycentric : (n, 2) float64 ndarray
        (u, v) of the hit in its triangle (a, b, c): the point is
        ``(1 − u − v)·a + u·b + v·c``; NaN for a miss.
    """

    distance: np.ndarray
    triangle: np.ndarray
    normal: np.ndarray
    barycentric: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        """(n,) bool ndarray: whether each ray hit."""
        return self.triangle >= 0


@runtime_checkable
class RayCaster(Protocol):
    """What every ray-casting backend does: the first hit of each ray on its triangles."""

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
        """First hits of rays.

        Parameters
        ----------
        origins : (n, 3) float array_like
            In the frame of the triangles, m.
        directions : (n, 3) float array_like
            Need not be unit (the distance is then in units of the direction's length).

        Returns
        -------
        RayHits
        """
        ...


def unit_face_normals(triangles: np.ndarray) -> np.ndarray:
    """Unit normals of triangles as wound, ``(b − a) × (c − a)``; 0 for a degenerate one.

    Parameters
    ----------
    triangles : (t, 3, 3) float ndarray
        m.

    Returns
    -------
    (t, 3) float64 ndarray
    """
    tri = np.asarray(triangles, dtype=np.float64)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(normal, axis=1, keepdims=True)
    return np.divide(normal, norm, out=np.zeros_like(normal), where=norm > 0)


def ray_hits(
    distance: np.ndarray, triangle: np.ndarray, face_normals: np.ndarray, uv: np.ndarray
) -> RayHits:
    """:class:`RayHits` from a backend's raw answer (misses: triangle < 0).

    Parameters
    ----------
    distance : (n,) float ndarray
        Ray parameter of each hit (any value for a miss).
    triangle : (n,) int ndarray
        -1 for a miss.
    face_normals : (t, 3) float ndarray
        Unit normal of every triangle.
    uv : (n, 2) float ndarray
        Barycentric (u, v) of each hit.

    Returns
    -------
    RayHits
    """
    triangle = np.asarray(triangle).astype(np.int64)
    hit = triangle >= 0
    distance = np.where(hit, np.asarray(distance, dtype=np.float64), np.inf)
    normal = np.zeros((len(triangle), 3))
    normal[hit] = face_normals[triangle[hit]]
    barycentric = np.where(hit[:, None], np.asarray(uv, dtype=np.float64), np.nan)
    return RayHits(distance, triangle, normal, barycentric)


def embree_available() -> bool:
    """Whether ``embreex`` can be imported (then :class:`EmbreeRays` works).

    Returns
    -------
    bool
    """
    try:
        import embreex.rtcore_scene  # noqa: F401
    except ImportError:
        return False
    return True


def _unitize(vectors: np.ndarray) -> np.ndarray:
    # trimesh.util.unitize for (n, d) arrays, same operations
    norm = np.sqrt(np.dot(vectors * vectors, [1.0] * vectors.shape[1]))
    valid = norm > _TOL_ZERO
    norm[valid] **= -1
    return vectors * norm.reshape((-1, 1))


def _diagonal_dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.dot(a * b, [1.0] * a.shape[1])


def _planes_lines(plane_origins, plane_normals, line_origins, line_directions):
    # trimesh.intersections.planes_lines, same operations
    plane_origins = np.asanyarray(plane_origins, dtype=np.float64)
    plane_normals = np.asanyarray(plane_normals, dtype=np.float64)
    line_origins = np.asanyarray(line_origins, dtype=np.float64)
    line_directions = np.asanyarray(line_directions, dtype=np.float64)
    origin_vectors = plane_origins - line_origins
    projection_ori = _diagonal_dot(origin_vectors, plane_normals)
    projection_dir = _diagonal_dot(line_directions, plane_normals)
    valid = np.abs(projection_dir) > 1e-5
    distance = np.divide(projection_ori[valid], projection_dir[valid])
    on_plane = line_directions[valid] * distance.reshape((-1, 1))
    on_plane += line_origins[valid]
    return on_plane, valid


_DEVICE = None


def embree_device():
    """The process's one Embree device, shared by every :class:`EmbreeScene`.

    ``embreex`` makes a new device for each scene it is not given one for, and does not
    check that the device was made: with about a thousand scenes alive in one process (a
    ``generate`` run of 500 objects keeps two per object) Embree's device creation fails
    and the next scene segfaults inside Embree. Scenes of one device are independent, and
    tracing them from several threads is safe; one device makes the number of scenes
    limited by memory only (``tests/objects/test_rays.py`` builds 1500).

    Returns
    -------
    embreex.rtcore.EmbreeDevice
    """
    global _DEVICE
    if _DEVICE is None:
        from embreex import rtcore

        _DEVICE = rtcore.EmbreeDevice()
    return _DEVICE


class EmbreeScene:
    """Triangles in one Embree scene (``embreex``, one ray per call, robust, float32).

    The :class:`RayCaster` backend that casts any rays. Embree is float32: the triangles
    and the rays are moved to the scene's frame, ``(x − origin)·scale``, before rounding,
    so an origin near the triangles keeps the precision.

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
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        self._vertices = np.asarray(vertices, dtype=np.float64)
        self._faces = None if faces is None else np.asarray(faces)
        self._origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=np.float64)
        self._scale = float(scale)
        self._face_normals = None if face_normals is None else np.asarray(face_normals)
        scaled = (self._vertices - self._origin) * self._scale
        self._scene = rtcore_scene.EmbreeScene(embree_device())
        if self._faces is None:
            TriangleMesh(scene=self._scene, vertices=scaled.astype(_EMBREE_DTYPE))
        else:
            TriangleMesh(
                scene=self._scene,
                vertices=scaled.astype(_EMBREE_DTYPE),
                indices=self._faces.view(np.ndarray).astype(np.int32),
            )

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
        """First hits of rays (the :class:`RayCaster` interface).

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


class EmbreeRays(EmbreeScene):
    """First and all hits of rays on a triangle mesh (Embree, float32), as trimesh casts them.

    An :class:`EmbreeScene` in trimesh's frame (the mesh moved to its lowest corner and
    scaled to a 100-unit box), with trimesh's ray queries.

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

    def _run(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        return self.first_faces_scene(*self.to_scene(origins, directions))

    # The pieces of the multiple-hit loop, for a caller that runs the loop itself
    # (``affordgrasp.metrics.ray_crossings``, compiled) on the same rays.

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

    def intersects_id(
        self,
        ray_origins,
        ray_directions,
        multiple_hits: bool = True,
        max_hits: int = 100,
        return_locations: bool = False,
    ):
        """Faces hit by each ray (every hit along it with ``multiple_hits``).

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m; directions need not be unit.
        multiple_hits : bool
            Every hit along each ray, else the first.
        max_hits : int
            Most hits per ray.
        return_locations : bool
            Also return the hit points.

        Returns
        -------
        index_tri, index_ray : (m,) int64 ndarray
            Face and ray of each hit.
        locations : (m, 3) float64 ndarray
            With ``return_locations``.
        """
        ray_origins = np.array(ray_origins, dtype=np.float64)
        ray_directions = np.array(ray_directions, dtype=np.float64)
        if ray_origins.shape != ray_directions.shape:
            raise ValueError("Ray origin and direction don't match!")
        ray_directions = _unitize(ray_directions)
        result_triangle = [np.zeros(0, dtype=np.int64)]
        result_ray_idx = [np.zeros(0, dtype=np.int64)]
        result_locations = [np.zeros((0, 3), dtype=np.float64)]
        if multiple_hits or return_locations:
            base_offset = max(_RAY_OFFSET_FLOOR, self._mesh_scale * _RAY_OFFSET_FACTOR)
            ray_offsets = ray_directions * base_offset
            plane_origins, plane_normals = self.face_planes
        last_hit = np.full(len(ray_origins), -1, dtype=np.int64)
        live = np.arange(len(ray_origins))
        for _depth in range(max_hits):
            query = self._run(ray_origins[live], ray_directions[live])
            hit = query != -1
            if not hit.any():
                break
            hit_rays = live[hit]
            hit_tris = query[hit]
            if not multiple_hits and not return_locations:
                result_triangle.append(hit_tris)
                result_ray_idx.append(hit_rays)
                break
            dupe = last_hit[hit_rays] == hit_tris
            last_hit[hit_rays] = hit_tris
            ok_rays = hit_rays[~dupe]
            ok_tris = hit_tris[~dupe]
            dupe_rays = hit_rays[dupe]
            new_origins, valid = _planes_lines(
                plane_origins[ok_tris],
                plane_normals[ok_tris],
                ray_origins[ok_rays],
                ray_directions[ok_rays],
            )
            ok_rays, ok_tris = ok_rays[valid], ok_tris[valid]
            result_locations.append(new_origins)
            result_triangle.append(ok_tris)
            result_ray_idx.append(ok_rays)
            if not multiple_hits:
                break
            ray_origins[ok_rays] = new_origins + ray_offsets[ok_rays]
            ray_offsets[ok_rays] = ray_directions[ok_rays] * base_offset
            ray_offsets[dupe_rays] *= 2.0
            ray_origins[dupe_rays] += ray_offsets[dupe_rays]
            live = np.concatenate([ok_rays, dupe_rays])
        index_tri = np.concatenate(result_triangle)
        index_ray = np.concatenate(result_ray_idx)
        if return_locations:
            return index_tri, index_ray, np.concatenate(result_locations)
        return index_tri, index_ray

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
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
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
        return self._run(ray_origins, _unitize(ray_directions))

    def intersects_any(self, ray_origins, ray_directions) -> np.ndarray:
        """Whether each ray hits the mesh.

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m.

        Returns
        -------
        (n,) bool ndarray
        """
        return self.intersects_first(ray_origins, ray_directions) != -1
