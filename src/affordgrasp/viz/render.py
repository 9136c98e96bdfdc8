"""Render one grasp to an image, headless: ray casting, no OpenGL, no display.

The object and the posed hand are cast in one scene with a pinhole camera; each pixel is
shaded by its normal (Lambert, two lights fixed to the camera, a flat colour per part: the
object grey, the palm and fingers blue) and silhouettes are outlined so the picture reads at
thumbnail size. Contacts, normals, friction cones, the use point and the wrist axis are then
drawn over the image by projecting their 3D points with the same camera; markers hidden behind
a surface are drawn hollow. The result depends only on the inputs (no randomness, no GL).

Camera conventions (see ``docs/viewing.md``):

* :class:`Camera` is a pinhole camera: ``eye`` looks at ``target``, ``up`` is up in the image,
  ``fov_deg`` is the vertical field of view. Pixel (0, 0) is the top-left corner of the image;
  x grows to the right, y downwards; a pixel's centre is at (i + 0.5, j + 0.5).
* The default camera (:func:`auto_camera`) keeps the hand at the top of the image (image up is
  the direction the hand came from, ``-wrist_axis``), looks at the grasp from the direction
  among 64 fixed candidates where the most of both the object and the hand are visible, and
  frames the object and the hand together.

Everything is in the object frame (metres), as the rows of a simulation store it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import trimesh

from ..errors import InputError
from ..hands import Hand, get_hand
from ..hands.meshes import HandMesh, posed_hand_mesh

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
class Camera:
    """A pinhole camera.

    eye, target, up : (3,) float, metres (``up`` need not be orthogonal to the view)
    fov_deg : vertical field of view, degrees
    width, height : image size, pixels
    """

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov_deg: float = 30.0
    width: int = 512
    height: int = 512

    def __post_init__(self) -> None:
        for name in ("eye", "target", "up"):
            v = np.asarray(getattr(self, name), dtype=np.float64).reshape(3)
            if not np.all(np.isfinite(v)):
                raise InputError(f"camera {name} must be 3 finite numbers, got {v}")
            object.__setattr__(self, name, v)
        if not 1.0 <= float(self.fov_deg) <= 170.0:
            raise InputError(f"camera fov_deg must be in [1, 170] degrees, got {self.fov_deg}")
        if int(self.width) < 2 or int(self.height) < 2:
            raise InputError(
                f"camera image must be at least 2x2 pixels, got {self.width}x{self.height}"
            )
        if np.linalg.norm(self.eye - self.target) <= 0:
            raise InputError("camera eye and target must differ")

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward), orthonormal, in the world frame."""
        forward = self.target - self.eye
        forward = forward / np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        if np.linalg.norm(right) < 1e-9:  # up parallel to the view: any perpendicular will do
            right = np.cross(forward, _any_perpendicular(forward))
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        return right, up, forward

    @property
    def focal_px(self) -> float:
        return 0.5 * self.height / np.tan(np.deg2rad(self.fov_deg) / 2.0)

    def with_size(self, width: int, height: int) -> Camera:
        return replace(self, width=int(width), height=int(height))

    def rays(self) -> tuple[np.ndarray, np.ndarray]:
        """Origins (h*w, 3) and unit directions (h*w, 3) through pixel centres, row-major."""
        right, up, forward = self.basis()
        x = (np.arange(self.width) + 0.5 - 0.5 * self.width) / self.focal_px
        y = (np.arange(self.height) + 0.5 - 0.5 * self.height) / self.focal_px
        xx, yy = np.meshgrid(x, y)
        d = forward + xx.reshape(-1, 1) * right - yy.reshape(-1, 1) * up
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return np.broadcast_to(self.eye, d.shape).copy(), d

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (n, 2) (x right, y down) and distance from the eye (n,).

        Points behind the camera get NaN pixel coordinates.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.eye
        right, up, forward = self.basis()
        z = p @ forward
        with np.errstate(divide="ignore", invalid="ignore"):
            u = 0.5 * self.width + self.focal_px * (p @ right) / z
            v = 0.5 * self.height - self.focal_px * (p @ up) / z
        uv = np.column_stack([u, v])
        uv[z <= 1e-9] = np.nan
        return uv, np.linalg.norm(p, axis=1)


@dataclass(frozen=True)
class GraspScene:
    """Everything drawn for one grasp, in the object frame (metres).

    object_mesh : the object
    hand : the posed hand mesh, or None to draw the object alone
    contact_points, contact_normals : (k, 3) float (normals: the object's outward normal)
    contact_mu : (k,) float; contact_link : (k,) str
    use_point, use_normal : (3,) float, NaN when the sample has no use point
    wrist_point, wrist_axis : (3,) float (the axis is the approach direction), NaN if unknown
    center_of_mass : (3,) float
    title : a short caption
    hand_model, link_poses : the hand and its link poses (n_links, 4, 4) in the object frame,
        for the interactive viewer (which draws the links, not the merged mesh)
    """

    object_mesh: trimesh.Trimesh
    hand: HandMesh | None
    contact_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_mu: np.ndarray = field(default_factory=lambda: np.zeros(0))
    contact_link: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))
    use_point: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    use_normal: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    wrist_point: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    wrist_axis: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    center_of_mass: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    title: str = ""
    hand_model: Hand | None = None
    link_poses: np.ndarray | None = None  # (n_links, 4, 4) link -> object

    @property
    def size(self) -> float:
        """Diagonal of the bounding box of the object and the hand, metres."""
        lo, hi = _scene_bounds(self)
        return float(np.linalg.norm(hi - lo))


@dataclass(frozen=True)
class Render:
    """A ray-cast image.

    rgb : (h, w, 3) uint8
    depth : (h, w) float, distance from the eye to the surface, inf on the background
    part : (h, w) int8, BACKGROUND_PART / OBJECT_PART / HAND_PART
    camera : the camera, at the image's size
    """

    rgb: np.ndarray
    depth: np.ndarray
    part: np.ndarray
    camera: Camera


def _vec(row: Mapping, name: str, width: int) -> np.ndarray:
    value = row.get(name)
    if value is None:
        return np.full(width, np.nan)
    return np.asarray(value, dtype=np.float64).reshape(width)


def _points(row: Mapping, name: str) -> np.ndarray:
    value = row.get(name)
    if value is None or len(value) == 0:
        return np.zeros((0, 3))
    # Arrow gives lists of lists, pandas an object array of arrays: stack either way.
    return np.array([np.asarray(p, dtype=np.float64).reshape(3) for p in value])


def grasp_scene(
    obj, row: Mapping, *, hand: Hand | str | None = None, title: str = ""
) -> GraspScene:
    """The scene of one sample row (a mapping with the SPEC §2.9 columns, e.g. a dict from
    ``table.slice(i, 1).to_pylist()[0]``).

    obj : GraspObject (its mesh and centre of mass are drawn)
    hand : the hand that made the grasp; by default the row's ``hand`` column, else "barrett"
    """
    for name in ("hand_pose", "joints"):
        if row.get(name) is None:
            raise InputError(f"a grasp row needs the column {name!r} (SPEC §2.9) to be drawn")
    if hand is None:
        hand = row.get("hand")
        hand = hand if isinstance(hand, str) and hand else "barrett"
    hand = get_hand(hand) if isinstance(hand, str) else hand
    joints = np.asarray(row["joints"], dtype=np.float64)
    if joints.shape != (len(hand.dofs),):
        raise InputError(
            f"the row has {joints.size} joint values but hand {hand.name!r} has "
            f"{len(hand.dofs)} DOFs; pass the hand that made the dataset"
        )
    pose = np.asarray(row["hand_pose"], dtype=np.float64).reshape(4, 4)
    points = _points(row, "contact_points")
    normals = _points(row, "contact_normals")
    mu = row.get("contact_mu")
    mu = np.zeros(len(points)) if mu is None else np.asarray(mu, dtype=np.float64).reshape(-1)
    links = row.get("contact_link")
    links = np.asarray([""] * len(points) if links is None else list(links), dtype=object)
    return GraspScene(
        object_mesh=obj.mesh,
        hand=posed_hand_mesh(hand, joints, pose),
        hand_model=hand,
        link_poses=pose[None] @ hand.forward_kinematics(joints),
        contact_points=points,
        contact_normals=normals,
        contact_mu=mu,
        contact_link=links,
        use_point=_vec(row, "use_point", 3),
        use_normal=_vec(row, "use_normal", 3),
        wrist_point=_vec(row, "wrist_point", 3),
        wrist_axis=_vec(row, "wrist_axis", 3),
        center_of_mass=np.asarray(obj.mass.center_of_mass, dtype=np.float64),
        title=title,
    )


# --------------------------------------------------------------------------- ray casting


@dataclass(frozen=True)
class _Caster:
    """The scene's triangles in one embree scene, with shading data per face corner.

    Rays are cast in float32 relative to ``origin`` (the scene's centre) to keep precision.
    """

    scene: object
    origin: np.ndarray  # (3,)
    corner_normals: np.ndarray  # (f, 3, 3)
    face_color: np.ndarray  # (f, 3)
    face_part: np.ndarray  # (f,) int8

    def cast(self, origins: np.ndarray, dirs: np.ndarray) -> dict:
        """First hits: primID (n,) (-1: miss), tfar (n,) distance, u, v barycentrics."""
        o = (np.asarray(origins, dtype=np.float64) - self.origin).astype(np.float32)
        return self.scene.run(o, np.asarray(dirs, dtype=np.float32), output=1)


_CORNER_NORMAL_CACHE: dict[int, tuple[trimesh.Trimesh, np.ndarray]] = {}


def corner_normals(mesh: trimesh.Trimesh, angle_deg: float = SMOOTH_ANGLE_DEG) -> np.ndarray:
    """Shading normals at each face corner, (f, 3, 3): the area-weighted mean of the normals
    of the faces around the corner's vertex that are within ``angle_deg`` of the face."""
    faces = np.asarray(mesh.faces)
    fn = np.asarray(mesh.face_normals)
    weighted = fn * np.asarray(mesh.area_faces)[:, None]
    vf = np.asarray(mesh.vertex_faces)  # (v, max degree), -1 padded
    around = vf[faces]  # (f, 3, d)
    valid = around >= 0
    idx = np.where(valid, around, 0)
    near = np.einsum("fk,fcdk->fcd", fn, fn[idx]) >= np.cos(np.deg2rad(angle_deg))
    w = np.where((valid & near)[..., None], weighted[idx], 0.0)
    n = w.sum(axis=2)
    norm = np.linalg.norm(n, axis=2, keepdims=True)
    fallback = np.broadcast_to(fn[:, None, :], n.shape)
    return np.where(norm > 1e-20, n / np.maximum(norm, 1e-20), fallback)


def _object_corner_normals(mesh: trimesh.Trimesh) -> np.ndarray:
    # Objects are shared and reused across grasps: cache by identity, keeping the mesh alive.
    cached = _CORNER_NORMAL_CACHE.get(id(mesh))
    if cached is None or cached[0] is not mesh:
        if len(_CORNER_NORMAL_CACHE) > 32:
            _CORNER_NORMAL_CACHE.clear()
        cached = (mesh, corner_normals(mesh))
        _CORNER_NORMAL_CACHE[id(mesh)] = cached
    return cached[1]


def _caster(scene: GraspScene) -> _Caster:
    from embreex import mesh_construction, rtcore_scene

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
    lo, hi = _scene_bounds(scene)
    origin = 0.5 * (lo + hi)
    triangles = np.concatenate([np.asarray(m.triangles) for m in meshes]) - origin
    ray_scene = rtcore_scene.EmbreeScene()
    mesh_construction.TriangleMesh(scene=ray_scene, vertices=triangles.astype(np.float32))
    return _Caster(
        ray_scene,
        origin,
        np.concatenate(normals),
        np.concatenate(colors),
        np.concatenate(parts),
    )


def render_image(scene: GraspScene, camera: Camera, *, supersample: int = 2) -> Render:
    """Ray-cast the object and the hand: shaded colours, depth and part per pixel."""
    return _render(_caster(scene), camera, supersample=supersample)


def _render(caster: _Caster, camera: Camera, *, supersample: int = 2) -> Render:
    s = max(1, int(supersample))
    big = camera.with_size(camera.width * s, camera.height * s)
    origins, dirs = big.rays()
    res = caster.cast(origins, dirs)
    h, w = big.height, big.width
    tri = res["primID"].astype(np.int64)
    hit = tri >= 0
    t = tri[hit]
    u = res["u"][hit].astype(np.float64)
    v = res["v"][hit].astype(np.float64)
    bary = np.column_stack([1.0 - u - v, u, v])
    n = np.einsum("nc,nck->nk", bary, caster.corner_normals[t])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    d = dirs[hit]
    n = np.where((np.sum(n * d, axis=1) > 0)[:, None], -n, n)  # two-sided: face the camera
    right, up, forward = big.basis()
    key = _unit(-forward + 0.6 * up - 0.5 * right)  # upper left, in front
    fill = _unit(-forward - 0.3 * up + 0.7 * right)
    lambert = 0.42 + 0.50 * np.clip(n @ key, 0, None) + 0.20 * np.clip(n @ fill, 0, None)
    colors = np.tile(BACKGROUND, (h * w, 1))
    colors[hit] = np.clip(caster.face_color[t] * lambert[:, None], 0.0, 1.0)
    depth = np.full(h * w, np.inf)
    depth[hit] = res["tfar"][hit]
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


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _any_perpendicular(v: np.ndarray) -> np.ndarray:
    a = np.array([1.0, 0.0, 0.0]) if abs(v[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    return _unit(np.cross(v, a))


# --------------------------------------------------------------------------- default camera


def _scene_points(scene: GraspScene) -> np.ndarray:
    """Points whose projection bounds the scene's: the object's hull and the hand's vertices."""
    pts = [np.asarray(scene.object_mesh.convex_hull.vertices)]
    if scene.hand is not None:
        pts.append(np.asarray(scene.hand.mesh.vertices))
    return np.concatenate(pts)


def _scene_bounds(scene: GraspScene) -> tuple[np.ndarray, np.ndarray]:
    lo = np.asarray(scene.object_mesh.bounds[0], dtype=np.float64)
    hi = np.asarray(scene.object_mesh.bounds[1], dtype=np.float64)
    if scene.hand is not None:
        lo = np.minimum(lo, scene.hand.mesh.bounds[0])
        hi = np.maximum(hi, scene.hand.mesh.bounds[1])
    return lo, hi


def _fibonacci_sphere(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _image_up(scene: GraspScene) -> np.ndarray:
    a = scene.wrist_axis
    if np.all(np.isfinite(a)) and np.linalg.norm(a) > 0:
        return -_unit(a)  # the hand came from there: keep it at the top
    return np.array([0.0, 0.0, 1.0])


def framed_camera(
    scene: GraspScene,
    view_dir: np.ndarray,
    *,
    up: np.ndarray | None = None,
    fov_deg: float = 30.0,
    width: int = 512,
    height: int = 512,
    margin: float = 0.06,
) -> Camera:
    """A camera on the side ``view_dir`` (from the scene towards the eye) that frames the
    object and the hand with ``margin`` (a fraction of the image) free on each side."""
    v = _unit(np.asarray(view_dir, dtype=np.float64))
    up = _image_up(scene) if up is None else np.asarray(up, dtype=np.float64)
    if np.linalg.norm(np.cross(v, up)) < 1e-3:
        up = _any_perpendicular(v)
    pts = _scene_points(scene)
    lo, hi = _scene_bounds(scene)
    t0 = 0.5 * (lo + hi)
    right, cam_up, forward = Camera(t0 + v, t0, up, fov_deg, width, height).basis()
    # Exact fit for a fixed view direction: a point p is inside the image when
    # |(p - t)·right| <= kx ((p - t)·forward + D) (and the same with up, ky), with t the target
    # and D the eye's distance; the smallest D over lateral shifts of t has a closed form.
    q = pts - t0
    depth = q @ forward
    ky = np.tan(np.deg2rad(fov_deg) / 2.0) * (1.0 - 2.0 * margin)
    kx = ky * width / height
    shift = np.zeros(3)
    distance = 0.0
    for axis, k in ((right, kx), (cam_up, ky)):
        a = q @ axis
        hi_a = float(np.max(a - k * depth))
        lo_a = float(np.min(a + k * depth))
        shift += 0.5 * (hi_a + lo_a) * axis
        distance = max(distance, (hi_a - lo_a) / (2.0 * k))
    # Keep every point in front of the eye, with some room.
    distance = max(distance, float(-depth.min()) + 0.05 * float(np.linalg.norm(hi - lo)), 1e-3)
    target = t0 + shift
    return Camera(target + v * distance, target, up, fov_deg, width, height)


def auto_camera(
    scene: GraspScene,
    *,
    width: int = 512,
    height: int = 512,
    fov_deg: float = 30.0,
    candidates: int = 64,
) -> Camera:
    """The default camera: the one of ``candidates`` fixed directions that sees the most of
    both the object and the hand (and the use point), framed; image up is ``-wrist_axis``."""
    return _auto_camera(_caster(scene), scene, width, height, fov_deg, candidates)


def _auto_camera(caster, scene, width, height, fov_deg, candidates) -> Camera:
    dirs = _fibonacci_sphere(candidates)
    a = scene.wrist_axis
    if np.all(np.isfinite(a)) and np.linalg.norm(a) > 0:
        # Straight along the approach, the palm hides the object or the object the hand.
        dirs = dirs[np.abs(dirs @ _unit(a)) < 0.85]
    probe = 40
    # One framed low-resolution camera per candidate (cheap numpy), then all their rays and
    # the use-point sight lines in one embree call.
    cams = [framed_camera(scene, v, fov_deg=fov_deg, width=probe, height=probe) for v in dirs]
    if not cams:
        return framed_camera(
            scene, np.array([0.3, -1.0, 0.5]), fov_deg=fov_deg, width=width, height=height
        )
    origins, rays = zip(*(c.rays() for c in cams), strict=True)
    tri = caster.cast(np.concatenate(origins), np.concatenate(rays))["primID"]
    part = np.where(tri >= 0, caster.face_part[np.maximum(tri, 0)], BACKGROUND_PART)
    part = part.reshape(len(cams), probe * probe)
    obj_px = np.count_nonzero(part == OBJECT_PART, axis=1) / part.shape[1]
    hand_px = np.count_nonzero(part == HAND_PART, axis=1) / part.shape[1]
    score = np.sqrt(obj_px * hand_px) if scene.hand is not None else obj_px
    if np.all(np.isfinite(scene.use_point)):
        eyes = np.array([c.eye for c in cams])
        seen = _visible_from(caster, eyes, np.broadcast_to(scene.use_point, eyes.shape))
        score = np.where(seen, 1.15 * score, score)
    # Prefer a camera above the grasp: a tiny, deterministic tie-breaker between mirror views.
    score = score + 1e-3 * (dirs @ _image_up(scene))
    best = dirs[int(np.argmax(score))]
    return framed_camera(scene, best, fov_deg=fov_deg, width=width, height=height)


def _visible(caster: _Caster, camera: Camera, points: np.ndarray, tol: float = 2e-3) -> np.ndarray:
    """Whether each point (n, 3) is seen by the camera (nothing nearer along its ray)."""
    points = np.asarray(points, dtype=np.float64)
    return _visible_from(caster, np.broadcast_to(camera.eye, points.shape), points, tol)


def _visible_from(
    caster: _Caster, eyes: np.ndarray, points: np.ndarray, tol: float = 2e-3
) -> np.ndarray:
    """Whether each point (n, 3) is seen from its eye (n, 3)."""
    d = np.asarray(points, dtype=np.float64) - eyes
    dist = np.linalg.norm(d, axis=1)
    d = d / dist[:, None]
    res = caster.cast(eyes, d)
    first = np.where(res["primID"] >= 0, res["tfar"], np.inf)
    return first >= dist - tol


# --------------------------------------------------------------------------- overlays


@dataclass(frozen=True)
class OverlayStyle:
    """What is drawn over the image, and how big (sizes in points at 100 dpi)."""

    contacts: bool = True
    normals: bool = True
    cones: bool = False
    use_point: bool = True
    wrist_axis: bool = True
    center_of_mass: bool = True
    marker_size: float = 6.0
    line_width: float = 1.8
    normal_length: float = 0.10  # fraction of the scene size


CONTACT_COLOR = "#ff8c00"
CONE_COLOR = "#e0a030"
USE_COLOR = "#d62728"
WRIST_COLOR = "#2ca02c"
COM_COLOR = "#111111"


def draw_grasp(
    ax,
    scene: GraspScene,
    *,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    width: int = 512,
    height: int = 512,
    supersample: int = 2,
) -> Render:
    """Render ``scene`` into the matplotlib axes ``ax`` (image + overlays); returns the render."""
    caster = _caster(scene)
    if camera is None:
        camera = _auto_camera(caster, scene, width, height, 30.0, 64)
    render = _render(caster, camera, supersample=supersample)
    ax.imshow(render.rgb, interpolation="antialiased")
    ax.set_xlim(0, camera.width)
    ax.set_ylim(camera.height, 0)
    ax.set_axis_off()
    draw_overlays(ax, scene, render, caster=caster, style=style)
    return render


def draw_overlays(
    ax, scene: GraspScene, render: Render, *, caster=None, style: OverlayStyle = OverlayStyle()
) -> None:
    """Draw contacts, normals, cones, use point, wrist axis and centre of mass over ``render``."""
    camera = render.camera
    caster = _caster(scene) if caster is None else caster
    length = style.normal_length * scene.size
    lw = style.line_width
    ms = style.marker_size

    def seg(p, q, **kw):
        uv, _ = camera.project(np.array([p, q]))
        if np.all(np.isfinite(uv)):
            ax.plot(uv[:, 0], uv[:, 1], solid_capstyle="round", **kw)

    def arrow(p, n, color, z):
        uv, _ = camera.project(np.array([p, p + length * n]))
        if np.all(np.isfinite(uv)):
            ax.annotate(
                "",
                xy=tuple(uv[1]),
                xytext=tuple(uv[0]),
                arrowprops=dict(
                    arrowstyle="-|>",
                    color=color,
                    lw=lw,
                    mutation_scale=8 + 2 * lw,
                    shrinkA=0,
                    shrinkB=0,
                ),
                zorder=z,
            )

    if (
        style.wrist_axis
        and np.all(np.isfinite(scene.wrist_point))
        and np.all(np.isfinite(scene.wrist_axis))
    ):
        a = _unit(scene.wrist_axis)
        seg(
            scene.wrist_point - 0.3 * scene.size * a,
            scene.wrist_point + 0.4 * scene.size * a,
            color=WRIST_COLOR,
            lw=lw,
            ls=(0, (4, 2)),
            zorder=3,
        )
        _marker(ax, camera, caster, scene.wrist_point[None], WRIST_COLOR, "s", ms * 0.9, z=4)

    k = len(scene.contact_points)
    if style.cones and k:
        ring = np.linspace(0, 2 * np.pi, 25)
        for p, n, mu in zip(
            scene.contact_points, scene.contact_normals, scene.contact_mu, strict=False
        ):
            n = _unit(n)
            t1 = _any_perpendicular(n)
            t2 = np.cross(n, t1)
            h = 0.8 * length
            r = h * float(mu)
            circle = p + h * n + r * (np.cos(ring)[:, None] * t1 + np.sin(ring)[:, None] * t2)
            uv, _ = camera.project(circle)
            if np.all(np.isfinite(uv)):
                ax.plot(uv[:, 0], uv[:, 1], color=CONE_COLOR, lw=0.8 * lw, alpha=0.9, zorder=5)
            for j in range(0, 24, 6):
                seg(p, circle[j], color=CONE_COLOR, lw=0.8 * lw, alpha=0.9, zorder=5)
    if style.normals and k:
        for p, n in zip(scene.contact_points, scene.contact_normals, strict=False):
            arrow(p, _unit(n), CONTACT_COLOR, 6)
    if style.contacts and k:
        _marker(ax, camera, caster, scene.contact_points, CONTACT_COLOR, "o", ms, z=7)

    if style.center_of_mass and np.all(np.isfinite(scene.center_of_mass)):
        uv, _ = camera.project(scene.center_of_mass[None])
        if np.all(np.isfinite(uv)):
            ax.plot(
                uv[:, 0],
                uv[:, 1],
                marker="P",
                ms=ms * 1.1,
                color="white",
                mec=COM_COLOR,
                mew=1.2,
                zorder=8,
                ls="none",
            )

    if style.use_point and np.all(np.isfinite(scene.use_point)):
        if np.all(np.isfinite(scene.use_normal)):
            arrow(scene.use_point, _unit(scene.use_normal), USE_COLOR, 8)
        _marker(ax, camera, caster, scene.use_point[None], USE_COLOR, "o", ms * 1.2, z=9)


def _marker(ax, camera, caster, points, color, marker, size, z) -> None:
    """Markers at ``points``: filled where seen, hollow where hidden behind a surface."""
    uv, _ = camera.project(points)
    ok = np.all(np.isfinite(uv), axis=1)
    if not np.any(ok):
        return
    seen = _visible(caster, camera, points[ok])
    uv = uv[ok]
    if np.any(seen):
        ax.plot(
            uv[seen, 0],
            uv[seen, 1],
            ls="none",
            marker=marker,
            ms=size,
            color=color,
            mec="black",
            mew=0.8,
            zorder=z,
        )
    if np.any(~seen):
        ax.plot(
            uv[~seen, 0],
            uv[~seen, 1],
            ls="none",
            marker=marker,
            ms=size,
            mfc="none",
            mec=color,
            mew=1.6,
            zorder=z,
        )


def grasp_image(
    scene: GraspScene,
    *,
    size_px: int = 512,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    caption: str | None = None,
) -> tuple[np.ndarray, Camera]:
    """One grasp drawn in a square image: (rgb (size, size, 3) uint8, the camera used).

    ``caption`` (default: the scene's title) is written in the top-left corner.
    """
    from .figure import figure_pixels, new_figure

    caption = scene.title if caption is None else caption
    if camera is not None and (camera.width, camera.height) != (size_px, size_px):
        camera = camera.with_size(size_px, size_px)
    fig, ax = new_figure(size_px, size_px)
    scale = size_px / 512.0
    style = replace(
        style,
        marker_size=style.marker_size * max(scale, 0.6),
        line_width=style.line_width * max(scale, 0.6),
    )
    render = draw_grasp(ax, scene, camera=camera, style=style, width=size_px, height=size_px)
    if caption:
        ax.text(
            0.02,
            0.98,
            caption,
            transform=ax.transAxes,
            va="top",
            ha="left",
            fontsize=max(6.5, 9.0 * scale),
            zorder=20,
            bbox=dict(boxstyle="round,pad=0.25", fc="white", ec="none", alpha=0.8),
        )
    return figure_pixels(fig), render.camera


def save_grasp_png(
    scene: GraspScene,
    path,
    *,
    size_px: int = 512,
    camera: Camera | None = None,
    style: OverlayStyle = OverlayStyle(),
    caption: str | None = None,
) -> Camera:
    """Render one grasp (image, overlays, caption) to a square PNG; returns the camera used."""
    from .figure import save_image

    rgb, camera = grasp_image(scene, size_px=size_px, camera=camera, style=style, caption=caption)
    save_image(rgb, path)
    return camera
