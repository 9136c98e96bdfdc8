"""The camera in the hand (conventions: Vision; paper §III-B): intrinsics, pose from the pregrasp.

Conventions (docs/vision.md repeats them with a worked example):

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


@dataclass(frozen=True)
class DepthCamera:
    """Intrinsics of the camera in the hand: ``size`` × ``size`` pixels, ``fov_deg`` wide.

    Attributes
    ----------
    size : int
        Pixels per side, 2 to ``MAX_CAMERA_SIZE``.
    fov_deg : float
        Field of view, degrees.
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
    def pixel_scale(self) -> float:
        """k: tangent of the angle per pixel at the centre, tan(fov/2) / (size/2)."""
        return math.tan(math.radians(self.fov_deg) / 2.0) / (self.size / 2.0)

    @property
    def focal_px(self) -> float:
        """OpenCV fx = fy, pixels."""
        return 1.0 / self.pixel_scale

    @property
    def principal_px(self) -> float:
        """OpenCV cx = cy, pixels (the image centre, between the two middle pixels)."""
        return (self.size - 1) / 2.0

    def intrinsics(self) -> np.ndarray:
        """The OpenCV intrinsic matrix (pixel coordinates of pixel centres are integers).

        Returns
        -------
        (3, 3) float64 ndarray
            K = [[f, 0, c], [0, f, c], [0, 0, 1]], f and c in pixels.
        """
        f, c = self.focal_px, self.principal_px
        return np.array([[f, 0.0, c], [0.0, f, c], [0.0, 0.0, 1.0]])

    def ray_directions(self) -> np.ndarray:
        """The camera-frame ray of every pixel.

        Returns
        -------
        (size, size, 3) float64 ndarray
            Indexed (row, column); z component 1, so a ray's parameter is the depth.
        """
        k = self.pixel_scale
        coord = (np.arange(self.size) + 0.5 - self.size / 2.0) * k
        x, y = np.meshgrid(coord, coord)  # x varies along columns, y along rows
        return np.stack([x, y, np.ones_like(x)], axis=-1)


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
        vertices = np.asarray(mesh.convex_hull.vertices, dtype=np.float64)
        lo, hi = vertices.min(axis=0), vertices.max(axis=0)
        return cls(vertices=vertices, centre=(lo + hi) / 2.0, length=float(np.max(hi - lo)))


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
