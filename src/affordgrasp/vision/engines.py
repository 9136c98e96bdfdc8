"""The depth engines: three backends of the ray-casting interface that also make images.

Each engine holds one object's triangles in the scene frame of the depth images (the
object's bounding-box centre at the origin, m: float32 keeps its precision there) and
answers both

* ``cast(origins, directions)``: the first hit of any rays, as every
  :class:`~affordgrasp.rays.RayCaster` does (:class:`~affordgrasp.rays.RayHits`);
* ``render(poses, camera)``: depth images of a pinhole camera (conventions:
  :mod:`affordgrasp.vision.camera`), the fastest way each engine has.

The engines:

* :class:`EmbreeEngine`: Embree through ``embreex``, one ray per call
  (:class:`~affordgrasp.rays.embree.EmbreeScene`): the reference;
* :class:`PacketEngine`: the Embree library that ``embreex`` ships, 16 rays per call
  (:class:`~affordgrasp.rays.packets.PacketScene`): images from a compiled loop over 4 × 4
  pixel tiles, any rays from packets filled with numpy;
* :class:`RasterEngine`: z-buffered triangles (:mod:`affordgrasp.vision.raster`), the
  default for images. It answers a ray as a one-pixel image looking along it; a ray (or an
  image) from which a vertex lies nearer than ``near`` along the view, or behind it, is left
  to a ray engine, as projection cannot handle it.

``tests/rays/test_backends.py`` checks that all of them give the same hits on the same rays
(a box and a sphere, analytic distances); ``tests/vision/test_depth.py`` and
``tests/vision/test_raster.py`` compare their images.
"""

from __future__ import annotations

import functools

import numpy as np

from ..errors import InputError
from ..rays import RayHits, SceneFrame, ray_hits
from ..rays.embree import EmbreeScene
from .camera import DepthCamera

_F32 = np.float32


@functools.lru_cache(maxsize=8)
def camera_rays(camera: DepthCamera) -> np.ndarray:
    """The camera-frame ray of every pixel, as the engines cast them (cached, read-only).

    Parameters
    ----------
    camera : DepthCamera

    Returns
    -------
    (size*size, 3) float32 ndarray
        Row-major, z = 1.
    """
    rays = camera.ray_directions().reshape(-1, 3).astype(_F32)
    rays.flags.writeable = False
    return rays


class EmbreeEngine(EmbreeScene):
    """Embree through ``embreex``, one ray per call (the reference engine): the object's
    :class:`~affordgrasp.rays.embree.EmbreeScene`, which also makes depth images.

    Parameters
    ----------
    triangles : (t, 3, 3) float ndarray
        The object's triangles, m.
    centre : (3,) float ndarray
        The scene frame's origin, m.
    """

    name = "embreex"

    def __init__(self, triangles: np.ndarray, centre: np.ndarray) -> None:
        self.centre = np.asarray(centre, dtype=np.float64)
        super().__init__(triangles, origin=self.centre)

    def render(
        self, poses: np.ndarray, camera: DepthCamera, *, images_per_call: int = 64
    ) -> np.ndarray:
        """Depth images (camera-frame rays with z = 1: Embree's t is the depth).

        Parameters
        ----------
        poses : (n, 4, 4) float64 ndarray
            Camera → mesh frame, m.
        camera : DepthCamera
        images_per_call : int
            Images cast per Embree call (memory vs speed).

        Returns
        -------
        (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return.
        """
        n, size = len(poses), camera.size
        out = np.zeros((n, size, size), dtype=_F32)
        rays_cam = camera_rays(camera)
        per_image = rays_cam.shape[0]
        for lo in range(0, n, images_per_call):
            hi = min(n, lo + images_per_call)
            rot = poses[lo:hi, :3, :3]
            origin = poses[lo:hi, :3, 3] - self.centre
            # (b, pixels, 3): each camera ray turned into the mesh frame (a batched matmul;
            # einsum is 20x slower here).
            dirs = np.matmul(rays_cam[None], rot.transpose(0, 2, 1).astype(_F32))
            origins = np.repeat(origin.astype(_F32), per_image, axis=0)
            t = self.distances_scene(origins, dirs.reshape(-1, 3))
            out[lo:hi] = t.reshape(hi - lo, size, size)
        return out


class PacketEngine:
    """The Embree library of ``embreex`` called with 16 rays at a time.

    Parameters
    ----------
    triangles : (t, 3, 3) float ndarray
        The object's triangles, m.
    centre : (3,) float ndarray
        The scene frame's origin, m.
    hull : (h, 3) float ndarray, optional
        Convex-hull vertices, m: images cast only the tiles that meet its projection
        (default: the triangles' vertices).

    Raises
    ------
    InputError
        When the Embree 4 library cannot be loaded
        (:func:`affordgrasp.rays.packets.available` is False).
    """

    name = "packets"

    def __init__(
        self, triangles: np.ndarray, centre: np.ndarray, hull: np.ndarray | None = None
    ) -> None:
        from ..rays.packets import PacketScene

        triangles = np.asarray(triangles, dtype=np.float64)
        self.centre = np.asarray(centre, dtype=np.float64)
        self.scene = PacketScene(triangles, origin=self.centre)
        points = triangles.reshape(-1, 3) if hull is None else np.asarray(hull, dtype=np.float64)
        self._hull = np.ascontiguousarray(points - self.centre)

    def render(self, poses: np.ndarray, camera: DepthCamera, **_: object) -> np.ndarray:
        """Depth images, cast tile by tile from a compiled loop.

        Parameters
        ----------
        poses : (n, 4, 4) float64 ndarray
            Camera → mesh frame, m.
        camera : DepthCamera

        Returns
        -------
        (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return.
        """
        from ..rays.packets import render_tiles

        size = camera.size
        out = np.zeros((len(poses), size, size), dtype=_F32)
        render_tiles(
            self.scene.handle,
            camera_rays(camera),
            np.ascontiguousarray(poses[:, :3, :3], dtype=_F32),
            np.ascontiguousarray(poses[:, :3, 3] - self.centre, dtype=_F32),
            self._hull,
            camera.focal_px,
            camera.principal_px,
            size,
            out,
        )
        return out

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
        """First hits of rays, 16 per Embree call (:class:`~affordgrasp.rays.RayCaster`).

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            Mesh frame, m; directions need not be unit.

        Returns
        -------
        RayHits
        """
        return self.scene.cast(origins, directions)


class RasterEngine(SceneFrame):
    """Z-buffered triangles (:func:`affordgrasp.vision.raster.rasterise`).

    Parameters
    ----------
    vertices : (v, 3) float ndarray
        m.
    faces : (t, 3) int ndarray
    centre : (3,) float ndarray
        The scene frame's origin, m.
    cull : bool
        Skip back faces (a closed, outward-oriented mesh seen from outside).
    near : float
        Views with a vertex nearer than this along the optical axis are not rasterised, m.
    fallback : callable, optional
        Makes the ray engine for those views (called once, when first needed).
    """

    name = "raster"

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray,
        centre: np.ndarray,
        *,
        cull: bool,
        near: float,
        fallback=None,
    ) -> None:
        self.centre = np.asarray(centre, dtype=np.float64)
        super().__init__(vertices, np.ascontiguousarray(faces, dtype=np.int64), origin=centre)
        self._centred = np.ascontiguousarray(self._vertices - self.centre)
        self.cull = bool(cull)
        self.near = float(near)
        self._fallback_factory = fallback
        self._fallback = None

    def fallback(self):
        """The ray engine for the views the rasteriser leaves (built once).

        Returns
        -------
        EmbreeEngine or PacketEngine
        """
        if self._fallback is None:
            if self._fallback_factory is None:
                raise InputError("this raster engine has no ray engine for near views")
            self._fallback = self._fallback_factory()
        return self._fallback

    def rasterise(
        self, rot: np.ndarray, origin: np.ndarray, focal: float, centre: float, size: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Depth images of square pinhole views, without the fallback.

        Parameters
        ----------
        rot : (n, 3, 3) float64 ndarray
            Camera → mesh frame rotations.
        origin : (n, 3) float64 ndarray
            Camera positions, mesh frame, m.
        focal, centre : float
            OpenCV fx = fy and cx = cy, pixels.
        size : int
            Pixels per side.

        Returns
        -------
        images : (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return (and for the views not done).
        done : (n,) bool ndarray
            False for the views left to a ray engine.
        """
        from .raster import rasterise

        n = len(rot)
        out = np.zeros((n, size, size), dtype=_F32)
        done = np.ones(n, dtype=np.bool_)
        rasterise(
            self._centred,
            self._faces,
            np.ascontiguousarray(rot, dtype=np.float64),
            np.ascontiguousarray(np.asarray(origin, dtype=np.float64) - self.centre),
            focal,
            centre,
            size,
            self.near,
            self.cull,
            out,
            done,
        )
        return out, done

    def render(self, poses: np.ndarray, camera: DepthCamera, **kwargs: object) -> np.ndarray:
        """Depth images; views too near the object are cast by the fallback engine.

        Parameters
        ----------
        poses : (n, 4, 4) float64 ndarray
            Camera → mesh frame, m.
        camera : DepthCamera
        **kwargs
            Passed to the fallback's ``render``.

        Returns
        -------
        (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return.
        """
        out, done = self.rasterise(
            poses[:, :3, :3], poses[:, :3, 3], camera.focal_px, camera.principal_px, camera.size
        )
        if not done.all():
            out[~done] = self.fallback().render(poses[~done], camera, **kwargs)
        return out

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> RayHits:
        """First hits of rays, each a one-pixel view along it (slow: a pass over every
        triangle per ray; for checks, not for volume).

        The distance is the rasteriser's; the triangle hit is the one the ray crosses at
        that distance. Rays from which a vertex is nearer than ``near`` (or behind) are
        cast by the fallback engine.

        Parameters
        ----------
        origins, directions : (n, 3) float array_like
            Mesh frame, m; directions need not be unit.

        Returns
        -------
        RayHits
        """
        origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        length = np.linalg.norm(directions, axis=1)
        rot = view_rotations(directions / length[:, None])
        depth, done = self.rasterise(rot, origins, 1.0, 0.0, 1)
        distance = depth.reshape(-1).astype(np.float64) / length
        triangle = np.full(len(origins), -1, dtype=np.int64)
        uv = np.full((len(origins), 2), np.nan)
        hit = done & (distance > 0)
        if hit.any():
            triangle[hit], uv[hit] = _triangle_at(
                self.triangles, origins[hit], directions[hit], distance[hit]
            )
        hits = ray_hits(distance, triangle, self.normals, uv)
        if not done.all():
            rest = self.fallback().cast(origins[~done], directions[~done])
            for name in ("distance", "triangle", "normal", "barycentric"):
                getattr(hits, name)[~done] = getattr(rest, name)
        return hits


def view_rotations(axes: np.ndarray) -> np.ndarray:
    """Camera → mesh rotations whose optical axis (third column) is each unit axis.

    Parameters
    ----------
    axes : (n, 3) float ndarray
        Unit.

    Returns
    -------
    (n, 3, 3) float64 ndarray
        Right-handed, orthonormal.
    """
    axes = np.asarray(axes, dtype=np.float64)
    helper = np.where(
        (np.abs(axes[:, 0]) < 0.9)[:, None], np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    )
    y = np.cross(axes, helper)
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    x = np.cross(y, axes)
    return np.stack([x, y, axes], axis=2)


def _triangle_at(
    triangles: np.ndarray, origins: np.ndarray, directions: np.ndarray, distance: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The triangle each ray crosses nearest to its given distance, and the (u, v) there.

    Möller–Trumbore against every triangle, in chunks of rays (memory: chunk × triangles).
    """
    a = triangles[:, 0]
    e1 = triangles[:, 1] - a
    e2 = triangles[:, 2] - a
    chunk = max(1, 2_000_000 // max(1, len(triangles)))
    found = np.empty(len(origins), dtype=np.int64)
    uv = np.empty((len(origins), 2))
    for lo in range(0, len(origins), chunk):
        o, d = origins[lo : lo + chunk, None], directions[lo : lo + chunk, None]
        p = np.cross(d, e2)
        det = np.einsum("tk,ntk->nt", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - a
            u = np.einsum("ntk,ntk->nt", s, p) * inv
            q = np.cross(s, e1)
            v = np.einsum("nk,ntk->nt", d[:, 0], q) * inv
            t = np.einsum("tk,ntk->nt", e2, q) * inv
            tol = 1e-6
            inside = (u >= -tol) & (v >= -tol) & (u + v <= 1 + tol) & np.isfinite(t)
        miss = np.where(inside, np.abs(t - distance[lo : lo + chunk, None]), np.inf)
        best = np.argmin(miss, axis=1)
        rows = np.arange(len(best))
        found[lo : lo + chunk] = best
        uv[lo : lo + chunk] = np.column_stack([u[rows, best], v[rows, best]])
    return found, uv
