"""Ray casting: one interface, several backends, chosen in one place.

Every ray cast in the package goes through :class:`RayCaster`: ``cast(origins, directions)``
returns the first hit of each ray as :class:`RayHits` (distance along the ray, triangle,
unit normal, barycentric coordinates). A mesh's caster (:func:`mesh_caster`, the one place a
backend is chosen) is a :class:`MeshCaster`: it also answers the queries of trimesh's
``mesh.ray`` (first face, any hit, hit points) and every crossing of many rays. Backends:

* :class:`~.embree.EmbreeScene`: Embree through ``embreex``, one ray per call, robust
  (watertight) scene in float32; the viewer (:mod:`affordgrasp.viz.raycast`) and the
  reference depth engine use it;
* :class:`~.embree.EmbreeRays`: an :class:`~.embree.EmbreeScene` in trimesh's frame that
  answers trimesh's queries with the same bits as trimesh's own Embree engine, without
  importing trimesh; every crossing by a compiled loop (:mod:`.crossings`);
* :class:`~.packets.PacketScene`: the Embree library that ``embreex`` ships, called with 16
  rays at a time (the packet depth engine);
* :class:`TrimeshRays`: trimesh's own engine (``mesh.ray``), for a ``trimesh.Trimesh`` and
  wherever ``embreex`` is missing (trimesh's ray-triangle test).

``tests/rays/test_backends.py`` checks that every backend, and the depth engines of
:mod:`affordgrasp.vision.engines`, give the same hits on the same rays against a box and a
sphere (analytic distances).
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..caching import IdentityCache


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
    """Whether ``embreex`` can be imported (then the Embree backends work).

    Returns
    -------
    bool
    """
    try:
        import embreex.rtcore_scene  # noqa: F401
    except ImportError:
        return False
    return True


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

    def intersects_any(self, ray_origins, ray_directions) -> np.ndarray:
        return self.mesh.ray.intersects_any(ray_origins, ray_directions)

    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True):
        return self.mesh.ray.intersects_location(
            ray_origins, ray_directions, multiple_hits=multiple_hits
        )

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
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


_MESH_CASTERS: IdentityCache[MeshCaster] = IdentityCache()


def mesh_caster(mesh) -> MeshCaster:
    """The ray caster of a mesh: where the backend is chosen.

    A ``trimesh.Trimesh`` keeps its own engine (``mesh.ray``, :class:`TrimeshRays`). A
    prepared mesh (arrays with trimesh's face normals and scale, such as
    :class:`~affordgrasp.objects.prepared.MeshData`) is cast by :class:`~.embree.EmbreeRays`
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
            from .embree import EmbreeRays

            return EmbreeRays(mesh.vertices, mesh.faces, mesh.face_normals, mesh.scale)
        return TrimeshRays(mesh.to_trimesh())

    return _MESH_CASTERS.get(mesh, build)
