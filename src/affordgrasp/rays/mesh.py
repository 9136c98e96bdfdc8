"""A mesh's ray caster: trimesh's ray queries (``mesh.ray``) behind one interface.

:class:`MeshCaster` answers what the objects, the metrics and the grasp policy ask of a
mesh: the face each ray hits first, whether it hits, the hit points, and every crossing of
many rays. Its backends, chosen by :func:`mesh_caster`:

* :class:`EmbreeRays`: a prepared mesh's Embree scene, making the same Embree calls on the
  same float32 data as trimesh 4-5's ``RayMeshIntersector`` (:mod:`.crossings`), so the
  faces and points hit are the same bits (``tests/rays/test_embree.py`` compares them),
  without importing trimesh (half a second, most of a command's start-up);
* :class:`TrimeshRays`: trimesh's own engine on a ``trimesh.Trimesh`` (Embree through
  ``embreex``, else trimesh's ray-triangle test in numpy).
"""

from __future__ import annotations

import functools
from abc import abstractmethod

import numpy as np

from ..caching import IdentityCache
from . import RayCaster, RayHits, _unitize, embree_available, ray_hits
from .embree import EmbreeScene

_RAY_OFFSET_FACTOR = 1e-6
_RAY_OFFSET_FLOOR = 1e-8


class MeshCaster(RayCaster):
    """The ray queries of one mesh, by trimesh's names (``mesh.ray``); get a mesh's with
    :func:`mesh_caster`.

    Hit points are computed in float64 on the plane of the face hit.

    Attributes
    ----------
    normals : (f, 3) float64 ndarray
        Unit normal of every face (trimesh's).
    """

    normals: np.ndarray

    @abstractmethod
    def intersects_first(self, ray_origins, ray_directions) -> np.ndarray:
        """The face each ray hits first.

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m; directions need not be unit.

        Returns
        -------
        (n,) int ndarray
            -1 for a miss.
        """

    @abstractmethod
    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True):
        """Hit points, their rays and faces.

        Parameters
        ----------
        ray_origins, ray_directions : (n, 3) float array_like
            m; directions need not be unit.
        multiple_hits : bool
            Every hit along each ray, else the first.

        Returns
        -------
        locations : (m, 3) float64 ndarray
        index_ray, index_tri : (m,) int ndarray
        """

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

    def crossings(self, origins, directions, reach: float | None = None):
        """Every crossing of each ray with the surface, in the order the ray meets them.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; directions need not be unit.
        reach : float, optional
            m: at least every crossing within it of the ray's origin, and each ray's first
            (None: every crossing).

        Returns
        -------
        index_tri, index_ray : (m,) int64 ndarray
        locations : (m, 3) float64 ndarray
        """
        locations, ray, tri = self.intersects_location(origins, directions, multiple_hits=True)
        return (
            np.asarray(tri, dtype=np.int64),
            np.asarray(ray, dtype=np.int64),
            np.asarray(locations, dtype=np.float64),
        )


class TrimeshRays(MeshCaster):
    """trimesh's own engine on a ``trimesh.Trimesh`` (``mesh.ray``: Embree through ``embreex``
    when installed, else trimesh's ray-triangle test in numpy).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        m.
    """

    def __init__(self, mesh) -> None:
        self.mesh = mesh
        self.normals = np.asarray(mesh.face_normals, dtype=np.float64)

    def intersects_first(self, ray_origins, ray_directions) -> np.ndarray:
        return self.mesh.ray.intersects_first(ray_origins, ray_directions)

    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True):
        return self.mesh.ray.intersects_location(
            ray_origins, ray_directions, multiple_hits=multiple_hits
        )

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
        """First hits of rays (:class:`~affordgrasp.rays.RayCaster`), from trimesh's points.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; directions need not be unit.

        Returns
        -------
        RayHits
        """
        from trimesh.triangles import points_to_barycentric

        origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        locations, ray, tri = self.intersects_location(origins, directions, multiple_hits=False)
        ray, n = np.asarray(ray, dtype=np.int64), len(origins)
        distance, triangle, uv = np.zeros(n), np.full(n, -1), np.zeros((n, 2))
        # |hit − origin| in units of the direction's length
        distance[ray] = np.linalg.norm(locations - origins[ray], axis=1) / np.linalg.norm(
            directions[ray], axis=1
        )
        triangle[ray] = tri
        if len(ray):
            uv[ray] = points_to_barycentric(self.mesh.triangles[tri], locations)[:, 1:]
        return ray_hits(distance, triangle, self.normals, uv)


class EmbreeRays(EmbreeScene, MeshCaster):
    """A mesh's :class:`~.embree.EmbreeScene` in trimesh's frame (its lowest corner at 0,
    scaled to a 100-unit box), answering trimesh's ray queries with trimesh's bits.

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

    # The pieces of trimesh's multiple-hit loop, which :mod:`.crossings` runs compiled.

    @property
    def ray_offset(self) -> float:
        """How far a ray restarts past a hit, m (doubled for a repeated face)."""
        return max(_RAY_OFFSET_FLOOR, self._mesh_scale * _RAY_OFFSET_FACTOR)

    @functools.cached_property
    def face_planes(self) -> tuple[np.ndarray, np.ndarray]:
        """(f, 3) float64 first vertex and (f, 3) unit normal of every face."""
        # writable C-contiguous copies: one signature of the compiled loop, whether the
        # mesh's arrays are read-only (a cached object) or not
        return (
            np.array(self._vertices[self._faces][:, 0, :], order="C"),
            np.array(self.normals, dtype=np.float64, order="C"),
        )

    def crossings(self, origins, directions, reach: float | None = None):
        # the compiled loop: the same bits as trimesh's loop, twice as fast
        from .crossings import crossings

        return crossings(self, origins, directions, reach)

    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True):
        from .crossings import crossings

        rounds = {} if multiple_hits else {"max_hits": 1}  # one round: the first hits
        index_tri, index_ray, locations = crossings(self, ray_origins, ray_directions, **rounds)
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins, ray_directions) -> np.ndarray:
        ray_origins = np.array(ray_origins, dtype=np.float32)
        ray_directions = np.array(ray_directions, dtype=np.float32)
        if ray_origins.shape != ray_directions.shape:
            raise ValueError("Ray origin and direction don't match!")
        return self.first_faces_scene(*self.to_scene(ray_origins, _unitize(ray_directions)))


_MESH_CASTERS: IdentityCache[MeshCaster] = IdentityCache()


def mesh_caster(mesh) -> MeshCaster:
    """The ray caster of a mesh: where the backend is chosen.

    A ``trimesh.Trimesh`` keeps its own engine (``mesh.ray``, :class:`TrimeshRays`). A
    prepared mesh (arrays with trimesh's face normals and scale, such as
    :class:`~affordgrasp.objects.prepared.MeshData`) is cast by :class:`EmbreeRays`
    (the same bits, without importing trimesh), or where ``embreex`` is missing by trimesh's
    engine on ``mesh.to_trimesh()``; built once per mesh.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        m.

    Returns
    -------
    MeshCaster
    """
    if hasattr(mesh, "ray"):
        return TrimeshRays(mesh)

    def build() -> MeshCaster:
        if embree_available() and mesh.face_normals is not None and mesh.scale is not None:
            return EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale)
        return TrimeshRays(mesh.to_trimesh())

    return _MESH_CASTERS.get(mesh, build)
