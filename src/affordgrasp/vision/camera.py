"""Cameras (conventions: Vision; paper §III-B): the pinhole model, the camera in the hand.

:class:`PinholeCamera` is the one camera geometry of the package (pixel rays, projection,
intrinsics); the depth camera (:class:`DepthCamera`) and the viewer's camera
(:class:`affordgrasp.viz.camera.Camera`) are both pinhole cameras.

Conventions of the camera in the hand (docs/vision.md repeats them with a worked example):

* Pinhole camera, square image of ``size`` × ``size`` pixels (default 128), field of view
  ``fov_deg`` (default 60°) across the full width and the full height.
* Camera frame = the hand frame of the pregrasp (``affordgrasp.grasp.pregrasp.hand_rotations``):
  +z is the optical axis (the approach direction), +x is the hand's x (image columns grow
  along it), +y is the hand's y (image rows grow along it); the roll π·u3 is included. This is
  the OpenCV convention (x right, y down, z forward) with the hand's axes.
* Pixel (row r, column c) looks along the camera-frame ray
  ``((c + 0.5 − size/2)·k, (r + 0.5 − size/2)·k, 1)`` with ``k = tan(fov/2) / (size/2)``,
  i.e. OpenCV intrinsics fx = fy = (size/2)/tan(fov/2), cx = cy = (size − 1)/2.
* Camera position: on the pregrasp's approach line (through the offset point (u4, u5) of
  ``start_poses``), at an *object-length* distance before the object's centre measured along
  the optical axis: ``z_cam·a = (centre·a) − length`` where ``centre`` is the centre of the
  object's axis-aligned bounding box and ``length`` its largest extent (both in the mesh
  frame). As length ≥ the bounding-sphere radius, the camera is always outside the object.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..grasp.pregrasp import hand_rotations, validate_pregrasps

# Pixels per side at most: a 4096 x 4096 float64 image is 128 MB (and each render holds a few).
MAX_CAMERA_SIZE = 4096


class PinholeCamera:
    """The pinhole geometry every camera of the package shares (written once, here).

    A subclass provides ``width`` and ``height`` (pixels) and ``fov_deg`` (the vertical
    field of view, degrees; square pixels). Camera frame: +x right in the image (columns
    grow along it), +y down (rows grow along it), +z forward along the optical axis (the
    OpenCV convention). The pixel in row r, column c looks along
    ``((c + 0.5 − width/2)·k, (r + 0.5 − height/2)·k, 1)`` with
    ``k = tan(fov/2) / (height/2)`` (:attr:`pixel_scale`).

    Pixel coordinates (u along the columns, v along the rows) put the centre of pixel
    (r, c) at ``(c + PIXEL_CENTRE, r + PIXEL_CENTRE)``: 0 (OpenCV, the depth camera) or 0.5
    (the corner of the image at 0, the viewer's camera).
    """

    width: int
    height: int
    fov_deg: float
    PIXEL_CENTRE = 0.0

    @property
    def pixel_scale(self) -> float:
        """k: tangent of the angle per pixel at the centre, tan(fov/2) / (height/2)."""
        return math.tan(math.radians(self.fov_deg) / 2.0) / (self.height / 2.0)

    @property
    def focal_px(self) -> float:
        """The focal length fx = fy, pixels (1 / :attr:`pixel_scale`)."""
        return 1.0 / self.pixel_scale

    @property
    def principal_point(self) -> tuple[float, float]:
        """(cx, cy): the pixel coordinates of the optical axis (the image centre)."""
        offset = self.PIXEL_CENTRE - 0.5
        return self.width / 2.0 + offset, self.height / 2.0 + offset

    def intrinsics(self) -> np.ndarray:
        """The intrinsic matrix in this camera's pixel coordinates.

        Returns
        -------
        (3, 3) float64 ndarray
            K = [[f, 0, cx], [0, f, cy], [0, 0, 1]], pixels.
        """
        f = self.focal_px
        cx, cy = self.principal_point
        return np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])

    def ray_directions(self) -> np.ndarray:
        """The camera-frame ray through every pixel centre.

        Returns
        -------
        (height, width, 3) float64 ndarray
            Indexed (row, column); z component 1, so a ray's parameter is the depth.
        """
        k = self.pixel_scale
        x = (np.arange(self.width) + 0.5 - self.width / 2.0) * k
        y = (np.arange(self.height) + 0.5 - self.height / 2.0) * k
        xx, yy = np.meshgrid(x, y)  # x varies along columns, y along rows
        return np.stack([xx, yy, np.ones_like(xx)], axis=-1)

    def pixel_rays(self, uv: np.ndarray) -> np.ndarray:
        """Camera-frame rays through pixel coordinates.

        Parameters
        ----------
        uv : (n, 2) float array_like
            Pixel coordinates (u along the columns, v along the rows).

        Returns
        -------
        (n, 3) float64 ndarray
            z component 1: the point at depth d along the optical axis is ``d * ray``.
        """
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        cx, cy = self.principal_point
        k = self.pixel_scale
        return np.column_stack([(uv[:, 0] - cx) * k, (uv[:, 1] - cy) * k, np.ones(len(uv))])

    def project_camera(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates of camera-frame points, and their depth.

        Parameters
        ----------
        points : (n, 3) float array_like
            Camera frame, m.

        Returns
        -------
        uv : (n, 2) float64 ndarray
            Pixel coordinates; NaN for points not in front of the camera (z <= 1e-9 m).
        depth : (n,) float64 ndarray
            z, m.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return self._project(p[:, 0], p[:, 1], p[:, 2])

    def _project(self, x: np.ndarray, y: np.ndarray, z: np.ndarray):
        f = self.focal_px
        cx, cy = self.principal_point
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = np.column_stack([cx + f * x / z, cy + f * y / z])
        uv[z <= 1e-9] = np.nan
        return uv, z

    def world_rays(self, rotation: np.ndarray) -> np.ndarray:
        """The ray through every pixel centre in the world frame, unit length, row-major.

        Parameters
        ----------
        rotation : (3, 3) float ndarray
            Camera → world: its columns are the camera's x (right), y (down) and z
            (forward) axes in the world frame.

        Returns
        -------
        (height*width, 3) float64 ndarray
        """
        rays = self.ray_directions().reshape(-1, 3)
        d = rotation[:, 2] + rays[:, :1] * rotation[:, 0] + rays[:, 1:2] * rotation[:, 1]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return d

    def project_world(
        self, points: np.ndarray, rotation: np.ndarray, position: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates of world points seen from a pose, and their depth.

        Parameters
        ----------
        points : (n, 3) float array_like
            World frame, m.
        rotation : (3, 3) float ndarray
            Camera → world (see :meth:`world_rays`).
        position : (3,) float ndarray
            The camera's centre, world frame, m.

        Returns
        -------
        uv : (n, 2) float64 ndarray
            NaN for points not in front of the camera.
        depth : (n,) float64 ndarray
            Along the optical axis, m.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) - position
        return self._project(p @ rotation[:, 0], p @ rotation[:, 1], p @ rotation[:, 2])


@dataclass(frozen=True)
class DepthCamera(PinholeCamera):
    """Intrinsics of the camera in the hand: ``size`` × ``size`` pixels, ``fov_deg`` wide.

    The geometry is :class:`PinholeCamera`'s, with OpenCV pixel coordinates (pixel centres
    at integers).

    Attributes
    ----------
    size : int
        Pixels per side, 2 to ``MAX_CAMERA_SIZE``.
    fov_deg : float
        Field of view, degrees (across the full width and the full height).
    """

    size: int = 128
    fov_deg: float = 60.0

    def __post_init__(self):
        if not isinstance(self.size, int) or isinstance(self.size, bool) or self.size < 2:
            raise InputError(f"camera size must be an integer >= 2, got {self.size!r}")
        if self.size > MAX_CAMERA_SIZE:
            raise InputError(
                f"camera size {self.size} is too large: at most {MAX_CAMERA_SIZE} pixels per "
                f"side (a {self.size} x {self.size} image would need "
                f"{self.size**2 * 8 / 2**30:.3g} GiB per copy)"
            )
        if not 0.0 < float(self.fov_deg) < 180.0:
            raise InputError(
                f"camera field of view must be in (0, 180) degrees, got {self.fov_deg}"
            )

    @property
    def width(self) -> int:  # type: ignore[override]
        """Pixels (= ``size``)."""
        return self.size

    @property
    def height(self) -> int:  # type: ignore[override]
        """Pixels (= ``size``)."""
        return self.size

    @property
    def principal_px(self) -> float:
        """OpenCV cx = cy, pixels (the image centre, between the two middle pixels)."""
        return (self.size - 1) / 2.0


@dataclass(frozen=True)
class ObjectFrame:
    """What the camera pose needs from an object: its vertices, box centre and length.

    Attributes
    ----------
    vertices : (v, 3) float64 ndarray
        m (convex-hull vertices suffice: only extents are used).
    centre : (3,) float64 ndarray
        Bounding-box centre, m.
    length : float
        m.
    """

    vertices: np.ndarray
    centre: np.ndarray
    length: float

    @classmethod
    def of(cls, mesh) -> ObjectFrame:
        """The frame of a mesh.

        Parameters
        ----------
        mesh : trimesh.Trimesh
            The object, m.

        Returns
        -------
        ObjectFrame
            From the vertices of its convex hull.
        """
        return cls.from_vertices(mesh.convex_hull.vertices)

    @classmethod
    def from_vertices(cls, vertices) -> ObjectFrame:
        """The frame of some points (an object's hull vertices).

        Parameters
        ----------
        vertices : (v, 3) array_like of float
            m.

        Returns
        -------
        ObjectFrame
        """
        vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        lo, hi = vertices.min(axis=0), vertices.max(axis=0)
        return cls(vertices=vertices, centre=(lo + hi) / 2.0, length=float(np.max(hi - lo)))

    def moved(self, transform) -> ObjectFrame:
        """The frame of the same object moved by a rigid transform.

        Parameters
        ----------
        transform : (4, 4) array_like of float
            Rigid transform, m.

        Returns
        -------
        ObjectFrame
            Of the moved vertices (the box is recomputed, the length too).
        """
        t = np.asarray(transform, dtype=np.float64)
        return ObjectFrame.from_vertices(self.vertices @ t[:3, :3].T + t[:3, 3])


def camera_poses(frame: ObjectFrame, p0) -> np.ndarray:
    """Camera → object transforms for pregrasps.

    Columns of the rotation: the hand's x, y and approach z (see the module docstring).

    Parameters
    ----------
    frame : ObjectFrame
    p0 : (n, 6) array_like of float
        Pregrasps.

    Returns
    -------
    (n, 4, 4) float64 ndarray
        Translations in m.
    """
    p0 = validate_pregrasps(p0)
    rot = hand_rotations(p0)
    verts = frame.vertices
    # The offset point of the approach line, exactly as the grasp policy's start pose.
    px = verts @ rot[:, :, 0].T
    py = verts @ rot[:, :, 1].T
    xlo, xhi = px.min(axis=0), px.max(axis=0)
    ylo, yhi = py.min(axis=0), py.max(axis=0)
    x = (xlo + xhi) / 2 + p0[:, 3] * (xhi - xlo) / 2
    y = (ylo + yhi) / 2 + p0[:, 4] * (yhi - ylo) / 2
    z = rot[:, :, 2] @ frame.centre - frame.length
    origin = rot[:, :, 0] * x[:, None] + rot[:, :, 1] * y[:, None] + rot[:, :, 2] * z[:, None]
    poses = np.zeros((len(p0), 4, 4))
    poses[:, :3, :3] = rot
    poses[:, :3, 3] = origin
    poses[:, 3, 3] = 1.0
    return poses


POSE_STREAM = 0x9E5E  # the pose error's draws: SeedSequence([seed, POSE_STREAM])


def pose_error_transform(centre, error_m: float, error_deg: float, seed: int) -> np.ndarray:
    """A rigid error of a pose estimate: the believed object = this transform of the true one.

    A rotation by exactly ``error_deg`` about an axis drawn uniformly on the sphere, through
    ``centre``, then a translation of exactly ``error_m`` along a direction drawn
    uniformly: the sizes are fixed, the directions drawn (keyed by ``seed``).

    Parameters
    ----------
    centre : (3,) array_like of float
        The point the rotation turns about (the object's box centre), m.
    error_m : float
        Translation error, m (>= 0).
    error_deg : float
        Rotation error, degrees (>= 0).
    seed : int
        Same seed, same error.

    Returns
    -------
    (4, 4) float64 ndarray
        True object frame → believed object frame.
    """
    if not (np.isfinite(error_m) and np.isfinite(error_deg)) or error_m < 0 or error_deg < 0:
        raise InputError(
            f"a pose error is a distance >= 0 (m) and an angle >= 0 (degrees), got "
            f"{error_m!r} and {error_deg!r}"
        )
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), POSE_STREAM]))
    axis, direction = rng.normal(size=(2, 3))
    axis /= np.linalg.norm(axis)
    direction /= np.linalg.norm(direction)
    a = math.radians(float(error_deg))
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + math.sin(a) * k + (1.0 - math.cos(a)) * (k @ k)  # Rodrigues
    c = np.asarray(centre, dtype=np.float64).reshape(3)
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = c - rot @ c + float(error_m) * direction
    return out
