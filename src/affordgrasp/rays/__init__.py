"""Ray casting: one interface, several backends, chosen in one place.

Every ray cast in the package goes through :class:`RayCaster`: ``cast(origins, directions)``
returns the first hit of each ray as :class:`RayHits` (distance along the ray, triangle,
unit normal, barycentric coordinates). A mesh's caster (:func:`~.mesh.mesh_caster`, the one
place its backend is chosen) is a :class:`~.mesh.MeshCaster`: it also answers trimesh's
``mesh.ray`` queries (first face, any hit, hit points) and every crossing of many rays.

* :mod:`.embree`: Embree through ``embreex``, one ray per call, robust (watertight) scenes
  in float32 (:class:`~.embree.EmbreeScene`; the viewer and the reference depth engine);
* :mod:`.mesh`: a mesh's caster, Embree in trimesh's frame with trimesh's bits
  (:class:`~.mesh.EmbreeRays`), or trimesh's own engine (:class:`~.mesh.TrimeshRays`);
* :mod:`.crossings`: every crossing of many rays, Embree's hits followed by a compiled loop;
* :mod:`.packets`: the Embree library that ``embreex`` ships, 16 rays per call
  (:class:`~.packets.PacketScene`; the packet depth engine).

``tests/rays/test_backends.py`` checks that every backend, and the depth engines of
:mod:`affordgrasp.vision.engines`, give the same hits on the same rays against a box and a
sphere (analytic distances).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

_TOL_ZERO = float(np.finfo(np.float64).resolution * 100)  # trimesh.util.TOL_ZERO


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


class SceneFrame:
    """A backend's triangles, held in its scene frame ``(x − origin)·scale``.

    Embree is float32 (and the rasteriser projects from the camera): the triangles and the
    rays are moved to the scene's frame before rounding, so an origin near the triangles
    keeps the precision. The base of the backends' scenes (:class:`~.embree.EmbreeScene`,
    :class:`~.packets.PacketScene`, :class:`~affordgrasp.vision.engines.RasterEngine`).

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
        return ((self._vertices - self._origin) * self._scale).astype(np.float32)

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
        """The scene's frame: a point x is ``(x - origin) * scale`` there."""
        return self._origin, self._scale

    def to_scene(self, origins: np.ndarray, directions: np.ndarray):
        """Rays in the scene's frame, in float32 (Embree's).

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            m; directions as given (not made unit).

        Returns
        -------
        origins, directions : (n, 3) float32 ndarray
        """
        scaled = (np.array(origins, dtype=np.float64) - self._origin) * self._scale
        return scaled.astype(np.float32), np.asarray(directions).astype(np.float32)


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


def _unitize(vectors: np.ndarray) -> np.ndarray:
    # trimesh.util.unitize for (n, d) arrays, same operations
    norm = np.sqrt(np.dot(vectors * vectors, [1.0] * vectors.shape[1]))
    valid = norm > _TOL_ZERO
    norm[valid] **= -1
    return vectors * norm.reshape((-1, 1))


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
