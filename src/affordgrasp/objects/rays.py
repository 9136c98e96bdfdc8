"""Ray queries on a prepared mesh with Embree, without importing trimesh.

The simulator and the dataset cast rays at objects (use points, the face under a contact).
``trimesh`` casts them through Embree (``trimesh.ray.ray_pyembree``), but importing trimesh
costs about half a second (it imports much of scipy), most of a command's start-up. This
module makes the same Embree calls on the same float32 data, step for step as trimesh 4-5's
``RayMeshIntersector`` (mesh scaled to a 100-unit box, hits advanced along the ray by the
same offsets), so the faces and points hit are the same bits; tests compare the two on
random rays. Without Embree (``embreex`` missing), :class:`EmbreeRays` is not used and the
caller falls back to trimesh's own engine.
"""

from __future__ import annotations

import numpy as np

_EMBREE_DTYPE = np.float32
_RAY_OFFSET_FACTOR = 1e-6
_RAY_OFFSET_FLOOR = 1e-8
_TOL_ZERO = float(np.finfo(np.float64).resolution * 100)  # trimesh.util.TOL_ZERO


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


class EmbreeRays:
    """First and all hits of rays on a triangle mesh (Embree, float32).

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
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        self._vertices = np.asarray(vertices, dtype=np.float64)
        self._faces = np.asarray(faces)
        self._face_normals = np.asarray(face_normals, dtype=np.float64)
        self._mesh_scale = float(scale)
        self._origin = self._vertices.min(axis=0)
        self._scale = float(100.0 / self._mesh_scale)
        scaled = (self._vertices - self._origin) * self._scale
        self._scene = rtcore_scene.EmbreeScene()
        TriangleMesh(
            scene=self._scene,
            vertices=scaled.astype(_EMBREE_DTYPE),
            indices=self._faces.view(np.ndarray).astype(np.int32),
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
                np.array(self._face_normals, dtype=np.float64, order="C"),
            )
        return planes

    @property
    def scene_frame(self) -> tuple[np.ndarray, float]:
        """Embree's frame: a point x is ``(x - origin) * scale`` there, in float32."""
        return self._origin, self._scale

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

    def to_scene(self, origins: np.ndarray, directions: np.ndarray):
        """Rays in Embree's frame.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; unit directions.

        Returns
        -------
        origins, directions : (n, 3) float32 ndarray
        """
        scaled = (np.array(origins, dtype=np.float64) - self._origin) * self._scale
        return scaled.astype(_EMBREE_DTYPE), directions.astype(_EMBREE_DTYPE)

    def first_faces_scene(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """The face each ray hits first.

        Parameters
        ----------
        origins, directions : (n, 3) float32 ndarray
            In Embree's frame (:meth:`to_scene`).

        Returns
        -------
        (n,) int ndarray
            Face index, -1 for a miss.
        """
        return self._scene.run(origins, directions)

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
