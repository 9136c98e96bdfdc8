"""Pinhole cameras and how the default view of a grasp is framed.

Conventions (see ``docs/viewing.md``):

* :class:`Camera` is a pinhole camera (the package's one pinhole geometry,
  :class:`affordgrasp.vision.camera.PinholeCamera`) posed by ``eye`` looking at ``target``,
  ``up`` up in the image; ``fov_deg`` is the vertical field of view. Pixel coordinates (0, 0)
  are the top-left corner of the image; x grows to the right, y downwards; a pixel's centre
  is at (i + 0.5, j + 0.5).
* The default camera (:func:`affordgrasp.viz.raycast.auto_camera`, chosen by casting rays)
  keeps the hand at the top of the image (image up is the direction the hand came from,
  ``-wrist_axis``), looks at the grasp from the direction among 64 fixed candidates where the
  most of both the object and the hand are visible, and frames them together
  (:func:`framed_camera`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..vision.camera import PinholeCamera
from .scene import GraspScene, scene_bounds, scene_points


@dataclass(frozen=True)
class Camera(PinholeCamera):
    """A pinhole camera looking from ``eye`` at ``target``.

    Pixel coordinates put the image's top-left corner at (0, 0) (pixel centres at
    (i + 0.5, j + 0.5)); the geometry is :class:`~affordgrasp.vision.camera.PinholeCamera`'s.

    Attributes
    ----------
    eye, target, up : (3,) float ndarray
        Metres (``up`` need not be orthogonal to the view).
    fov_deg : float
        Vertical field of view, degrees.
    width, height : int
        Image size, pixels.
    """

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov_deg: float = 30.0
    width: int = 512
    height: int = 512
    PIXEL_CENTRE = 0.5

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
        """The camera's axes in the world frame.

        Returns
        -------
        right, up, forward : (3,) float64 ndarray
            Orthonormal; ``forward`` points from the eye to the target, ``up`` is the given up
            made perpendicular to it (any perpendicular when they are parallel).
        """
        forward = self.target - self.eye
        forward = forward / np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        if np.linalg.norm(right) < 1e-9:  # up parallel to the view: any perpendicular will do
            right = np.cross(forward, any_perpendicular(forward))
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        return right, up, forward

    def rotation(self) -> np.ndarray:
        """Camera → world rotation (columns: right, down, forward; OpenCV's camera frame).

        Returns
        -------
        (3, 3) float64 ndarray
        """
        right, up, forward = self.basis()
        return np.column_stack([right, -up, forward])

    def with_size(self, width: int, height: int) -> Camera:
        """The same camera at another image size (same field of view).

        Parameters
        ----------
        width, height : int
            Pixels.

        Returns
        -------
        Camera
        """
        return replace(self, width=int(width), height=int(height))

    def rays(self) -> tuple[np.ndarray, np.ndarray]:
        """The ray through every pixel centre, row-major.

        Returns
        -------
        origins : (h*w, 3) float64 ndarray
            The eye, m.
        directions : (h*w, 3) float64 ndarray
            Unit directions in the world frame.
        """
        d = self.world_rays(self.rotation())
        return np.broadcast_to(self.eye, d.shape).copy(), d

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates of points and their distance from the eye.

        Parameters
        ----------
        points : (n, 3) array_like of float
            World frame, m.

        Returns
        -------
        uv : (n, 2) float64 ndarray
            Pixel coordinates (x right, y down); NaN for points behind the camera.
        distance : (n,) float64 ndarray
            From the eye, m.
        """
        uv, _ = self.project_world(points, self.rotation(), self.eye)
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.eye
        return uv, np.linalg.norm(p, axis=1)


def unit(v: np.ndarray) -> np.ndarray:
    """``v`` scaled to unit length.

    Parameters
    ----------
    v : (3,) float ndarray
        Non-zero.

    Returns
    -------
    (3,) float64 ndarray
    """
    return v / np.linalg.norm(v)


def any_perpendicular(v: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``v``.

    Parameters
    ----------
    v : (3,) float ndarray
        Unit.

    Returns
    -------
    (3,) float64 ndarray
    """
    a = np.array([1.0, 0.0, 0.0]) if abs(v[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    return unit(np.cross(v, a))


def _fibonacci_sphere(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _image_up(scene: GraspScene) -> np.ndarray:
    a = scene.wrist_axis
    if np.all(np.isfinite(a)) and np.linalg.norm(a) > 0:
        return -unit(a)  # the hand came from there: keep it at the top
    return np.array([0.0, 0.0, 1.0])


def framed_camera(
    scene: GraspScene,
    view_dir: np.ndarray,
    *,
    fov_deg: float = 30.0,
    width: int = 512,
    height: int = 512,
) -> Camera:
    """A camera on the side ``view_dir`` that frames the object and the hand, 6 % of the image
    left free on each side.

    Parameters
    ----------
    scene : GraspScene
    view_dir : (3,) float ndarray
        From the scene towards the eye.
    fov_deg : float
        Vertical field of view, degrees.
    width, height : int
        Pixels.

    Returns
    -------
    Camera
    """
    v = unit(np.asarray(view_dir, dtype=np.float64))
    up = _image_up(scene)
    if np.linalg.norm(np.cross(v, up)) < 1e-3:
        up = any_perpendicular(v)
    pts = scene_points(scene)
    lo, hi = scene_bounds(scene)
    t0 = 0.5 * (lo + hi)
    right, cam_up, forward = Camera(t0 + v, t0, up, fov_deg, width, height).basis()
    # Exact fit for a fixed view direction: a point p is inside the image when
    # |(p - t)·right| <= kx ((p - t)·forward + D) (and the same with up, ky), with t the target
    # and D the eye's distance; the smallest D over lateral shifts of t has a closed form.
    q = pts - t0
    depth = q @ forward
    ky = np.tan(np.deg2rad(fov_deg) / 2.0) * (1.0 - 2.0 * 0.06)
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
