"""Ray casting a grasp scene: shaded colours, depth, parts.

The object and the posed hand are cast in one scene (the package's ray-casting
interface, :class:`affordgrasp.rays.RayCaster`, with its Embree backend); each
pixel is shaded by its normal (Lambert, two lights fixed to the camera, a flat colour per
part: the object grey, the palm and fingers blue) and silhouettes are outlined so the
picture reads at thumbnail size. The result depends only on the inputs (no randomness, no
GL). A scene's caster is built once
(:func:`caster_of`): the default camera, the image and the visibility tests of the overlays
all cast into the same one. The default camera (:func:`auto_camera`) is the fixed
direction whose rays see the most of the object and the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from ..caching import IdentityCache
from ..rays import RayHits
from ..rays.embree import EmbreeScene
from .camera import Camera, _fibonacci_sphere, _image_up, framed_camera, unit
from .scene import GraspScene, scene_bounds

BACKGROUND = np.array([1.0, 1.0, 1.0])
OBJECT_COLOR = np.array([0.74, 0.74, 0.72])
PALM_COLOR = np.array([0.24, 0.36, 0.62])
FINGER_COLOR = np.array([0.40, 0.56, 0.86])
OUTLINE_COLOR = np.array([0.12, 0.12, 0.14])

# Parts in the part buffer of a render.
BACKGROUND_PART = 0
OBJECT_PART = 1
HAND_PART = 2

# Shading normals are averaged over faces within this angle of each other; sharper edges
# stay sharp (a blade's edge, a box's corner).
SMOOTH_ANGLE_DEG = 35.0


@dataclass(frozen=True)
class Render:
    """A ray-cast image.

    Attributes
    ----------
    rgb : (h, w, 3) uint8 ndarray
    depth : (h, w) float ndarray
        Distance from the eye to the surface, m; inf on the background.
    part : (h, w) int8 ndarray
        BACKGROUND_PART / OBJECT_PART / HAND_PART.
    camera : Camera
        The camera, at the image's size.
    """

    rgb: np.ndarray
    depth: np.ndarray
    part: np.ndarray
    camera: Camera


@dataclass(frozen=True)
class SceneCaster:
    """The scene's triangles behind the ray-casting interface, with shading data per face.

    Rays are cast in float32 relative to the scene's centre to keep precision. Get a scene's
    with :func:`caster_of` (built once per scene).

    Attributes
    ----------
    rays : EmbreeScene
        The object's and the hand's triangles (object first), origin at the scene's centre.
    corner_normals : (f, 3, 3) float ndarray
        Shading normals per face corner.
    face_color : (f, 3) float ndarray
        RGB per face.
    face_part : (f,) int8 ndarray
        OBJECT_PART / HAND_PART per face.
    """

    rays: EmbreeScene
    corner_normals: np.ndarray  # (f, 3, 3)
    face_color: np.ndarray  # (f, 3)
    face_part: np.ndarray  # (f,) int8

    def cast(self, origins: np.ndarray, dirs: np.ndarray) -> RayHits:
        """First hits of rays (the :class:`~affordgrasp.rays.RayCaster` interface).

        Parameters
        ----------
        origins : (n, 3) array_like of float
            World frame, m.
        dirs : (n, 3) array_like of float
            Directions (unit length for distances in m).

        Returns
        -------
        RayHits
        """
        return self.rays.cast(origins, dirs)

    def render(self, camera: Camera, *, supersample: int = 2) -> Render:
        """Shaded colours, depth and part per pixel, seen by ``camera``.

        Parameters
        ----------
        camera : Camera
        supersample : int
            Rays per pixel along each axis (anti-aliasing).

        Returns
        -------
        Render
        """
        return _render(self, camera, supersample=supersample)


def corner_normals(mesh: trimesh.Trimesh) -> np.ndarray:
    """Shading normals at each face corner.

    The area-weighted mean of the normals of the faces around the corner's vertex that are
    within ``SMOOTH_ANGLE_DEG`` of the face.

    Parameters
    ----------
    mesh : trimesh.Trimesh

    Returns
    -------
    (f, 3, 3) float64 ndarray
    """
    faces = np.asarray(mesh.faces)
    fn = np.asarray(mesh.face_normals)
    weighted = fn * np.asarray(mesh.area_faces)[:, None]
    vf = np.asarray(mesh.vertex_faces)  # (v, max degree), -1 padded
    around = vf[faces]  # (f, 3, d)
    valid = around >= 0
    idx = np.where(valid, around, 0)
    near = np.einsum("fk,fcdk->fcd", fn, fn[idx]) >= np.cos(np.deg2rad(SMOOTH_ANGLE_DEG))
    w = np.where((valid & near)[..., None], weighted[idx], 0.0)
    n = w.sum(axis=2)
    norm = np.linalg.norm(n, axis=2, keepdims=True)
    fallback = np.broadcast_to(fn[:, None, :], n.shape)
    return np.where(norm > 1e-20, n / np.maximum(norm, 1e-20), fallback)


_OBJECT_CORNER_NORMALS: IdentityCache[np.ndarray] = IdentityCache()
_CASTERS: IdentityCache[SceneCaster] = IdentityCache()


def caster_of(scene: GraspScene) -> SceneCaster:
    """The scene's triangles in one ray-casting scene, built once per scene.

    Parameters
    ----------
    scene : GraspScene

    Returns
    -------
    SceneCaster
        The same one for every call with this scene (held as long as the scene).
    """
    return _CASTERS.get(scene, lambda: _build_caster(scene))


def _object_corner_normals(mesh: trimesh.Trimesh) -> np.ndarray:
    # Objects are shared and reused across grasps (hand meshes are new for every grasp).
    return _OBJECT_CORNER_NORMALS.get(mesh, lambda: corner_normals(mesh), version=hash(mesh))


def _build_caster(scene: GraspScene) -> SceneCaster:
    meshes = [scene.object_mesh]
    normals = [_object_corner_normals(scene.object_mesh)]
    colors = [np.broadcast_to(OBJECT_COLOR, (len(scene.object_mesh.faces), 3))]
    parts = [np.full(len(scene.object_mesh.faces), OBJECT_PART, dtype=np.int8)]
    if scene.hand is not None:
        hm = scene.hand.mesh
        meshes.append(hm)
        normals.append(corner_normals(hm))
        is_palm = scene.hand.face_link == 0
        colors.append(np.where(is_palm[:, None], PALM_COLOR, FINGER_COLOR))
        parts.append(np.full(len(hm.faces), HAND_PART, dtype=np.int8))
    lo, hi = scene_bounds(scene)
    origin = 0.5 * (lo + hi)
    triangles = np.concatenate([np.asarray(m.triangles) for m in meshes])
    return SceneCaster(
        EmbreeScene(triangles, origin=origin),
        np.concatenate(normals),
        np.concatenate(colors),
        np.concatenate(parts),
    )


def render_image(scene: GraspScene, camera: Camera, *, supersample: int = 2) -> Render:
    """Ray-cast the object and the hand: shaded colours, depth and part per pixel.

    Parameters
    ----------
    scene : GraspScene
    camera : Camera
    supersample : int
        Rays per pixel side (antialiasing).

    Returns
    -------
    Render
    """
    return caster_of(scene).render(camera, supersample=supersample)


def _render(caster: SceneCaster, camera: Camera, *, supersample: int = 2) -> Render:
    s = max(1, int(supersample))
    big = camera.with_size(camera.width * s, camera.height * s)
    origins, dirs = big.rays()
    hits = caster.cast(origins, dirs)
    h, w = big.height, big.width
    hit = hits.hit
    t = hits.triangle[hit]
    u, v = hits.barycentric[hit].T
    bary = np.column_stack([1.0 - u - v, u, v])
    n = np.einsum("nc,nck->nk", bary, caster.corner_normals[t])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    d = dirs[hit]
    n = np.where((np.sum(n * d, axis=1) > 0)[:, None], -n, n)  # two-sided: face the camera
    right, up, forward = big.basis()
    key = unit(-forward + 0.6 * up - 0.5 * right)  # upper left, in front
    fill = unit(-forward - 0.3 * up + 0.7 * right)
    lambert = 0.42 + 0.50 * np.clip(n @ key, 0, None) + 0.20 * np.clip(n @ fill, 0, None)
    colors = np.tile(BACKGROUND, (h * w, 1))
    colors[hit] = np.clip(caster.face_color[t] * lambert[:, None], 0.0, 1.0)
    depth = np.full(h * w, np.inf)
    depth[hit] = hits.distance[hit]
    part = np.zeros(h * w, dtype=np.int8)
    part[hit] = caster.face_part[t]
    colors = colors.reshape(h, w, 3)
    depth = depth.reshape(h, w)
    part = part.reshape(h, w)
    edge = _outline(depth, part, tol=0.01 * _finite_range(depth))
    colors[edge] = OUTLINE_COLOR
    if s > 1:
        colors = colors.reshape(camera.height, s, camera.width, s, 3).mean(axis=(1, 3))
        # A pixel's depth and part are those of its nearest sample: anything seen at all
        # in a pixel counts (background only where every sample missed).
        blocks = depth.reshape(camera.height, s, camera.width, s).transpose(0, 2, 1, 3)
        blocks = blocks.reshape(camera.height, camera.width, s * s)
        nearest = np.argmin(blocks, axis=2)[..., None]
        depth = np.take_along_axis(blocks, nearest, axis=2)[..., 0]
        part_blocks = part.reshape(camera.height, s, camera.width, s).transpose(0, 2, 1, 3)
        part_blocks = part_blocks.reshape(camera.height, camera.width, s * s)
        part = np.take_along_axis(part_blocks, nearest, axis=2)[..., 0]
    rgb = np.round(np.clip(colors, 0, 1) * 255).astype(np.uint8)
    return Render(rgb, depth, part, camera)


def _finite_range(depth: np.ndarray) -> float:
    finite = depth[np.isfinite(depth)]
    return float(finite.max() - finite.min()) if finite.size else 0.0


def _outline(depth: np.ndarray, part: np.ndarray, tol: float) -> np.ndarray:
    """Pixels on a silhouette: the part changes, or the depth jumps, to a neighbour."""
    edge = np.zeros(part.shape, dtype=bool)
    dz = np.where(np.isfinite(depth), depth, 1e9)
    for a, b in ((np.s_[1:, :], np.s_[:-1, :]), (np.s_[:, 1:], np.s_[:, :-1])):
        jump = (part[a] != part[b]) | (np.abs(dz[a] - dz[b]) > max(tol, 1e-6))
        # Mark the nearer pixel of the pair: outlines hug the foreground.
        nearer_a = dz[a] <= dz[b]
        edge[a] |= jump & nearer_a
        edge[b] |= jump & ~nearer_a
    return edge


def visible(caster: SceneCaster, camera: Camera, points: np.ndarray) -> np.ndarray:
    """Whether each point is seen by the camera (nothing nearer along its ray, 2 mm slack).

    Parameters
    ----------
    caster : SceneCaster
    camera : Camera
    points : (n, 3) float ndarray
        m.

    Returns
    -------
    (n,) bool ndarray
    """
    points = np.asarray(points, dtype=np.float64)
    return visible_from(caster, np.broadcast_to(camera.eye, points.shape), points, 2e-3)


def visible_from(
    caster: SceneCaster, eyes: np.ndarray, points: np.ndarray, tol: float = 2e-3
) -> np.ndarray:
    """Whether each point is seen from its eye.

    Parameters
    ----------
    caster : SceneCaster
    eyes : (n, 3) float ndarray
        m.
    points : (n, 3) float ndarray
        m.
    tol : float
        m.

    Returns
    -------
    (n,) bool ndarray
    """
    d = np.asarray(points, dtype=np.float64) - eyes
    dist = np.linalg.norm(d, axis=1)
    d = d / dist[:, None]
    return caster.cast(eyes, d).distance >= dist - tol


def auto_camera(
    scene: GraspScene,
    *,
    width: int = 512,
    height: int = 512,
    fov_deg: float = 30.0,
    candidates: int = 64,
) -> Camera:
    """The default camera: the fixed direction that sees the most of the object and the hand.

    Of ``candidates`` fixed directions, the one that sees the most of both the object and the
    hand (and the use point), framed; image up is ``-wrist_axis``.

    Parameters
    ----------
    scene : GraspScene
    width, height : int
        Pixels.
    fov_deg : float
        Vertical field of view, degrees.
    candidates : int
        Directions tried.

    Returns
    -------
    Camera
    """
    caster = caster_of(scene)
    dirs = _fibonacci_sphere(candidates)
    a = scene.wrist_axis
    if np.all(np.isfinite(a)) and np.linalg.norm(a) > 0:
        # Straight along the approach, the palm hides the object or the object the hand.
        dirs = dirs[np.abs(dirs @ unit(a)) < 0.85]
    probe = 40
    # One framed low-resolution camera per candidate (cheap numpy), then all their rays and
    # the use-point sight lines in one embree call.
    cams = [framed_camera(scene, v, fov_deg=fov_deg, width=probe, height=probe) for v in dirs]
    if not cams:
        return framed_camera(
            scene, np.array([0.3, -1.0, 0.5]), fov_deg=fov_deg, width=width, height=height
        )
    origins, rays = zip(*(c.rays() for c in cams), strict=True)
    tri = caster.cast(np.concatenate(origins), np.concatenate(rays)).triangle
    part = np.where(tri >= 0, caster.face_part[np.maximum(tri, 0)], BACKGROUND_PART)
    part = part.reshape(len(cams), probe * probe)
    obj_px = np.count_nonzero(part == OBJECT_PART, axis=1) / part.shape[1]
    hand_px = np.count_nonzero(part == HAND_PART, axis=1) / part.shape[1]
    score = np.sqrt(obj_px * hand_px) if scene.hand is not None else obj_px
    if np.all(np.isfinite(scene.use_point)):
        eyes = np.array([c.eye for c in cams])
        seen = visible_from(caster, eyes, np.broadcast_to(scene.use_point, eyes.shape))
        score = np.where(seen, 1.15 * score, score)
    # Prefer a camera above the grasp: a tiny, deterministic tie-breaker between mirror views.
    score = score + 1e-3 * (dirs @ _image_up(scene))
    best = dirs[int(np.argmax(score))]
    return framed_camera(scene, best, fov_deg=fov_deg, width=width, height=height)
