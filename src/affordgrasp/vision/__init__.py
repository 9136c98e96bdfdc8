"""Vision (conventions: Vision, paper §III-B): the camera in the hand, depth images, point clouds.

* ``camera``: the package's one pinhole model (``PinholeCamera``), the depth camera's
  intrinsics (``DepthCamera``) and the camera pose of a pregrasp;
* ``depth``: D(p0, O) (``DepthRenderer``), uint16-millimetre encoding, PNG views;
* ``engines``: the engines that make the images, backends of the ray-casting interface
  (:class:`affordgrasp.rays.RayCaster`): ``RasterEngine``, ``PacketEngine`` (Embree rays in
  16-ray packets), ``EmbreeEngine`` (the reference, one ray per call);
* ``raster``: the default engine's kernel, z-buffer rasterisation of the triangles;
* ``points``: the equivalent fixed-size point clouds;
* ``sensor``: a depth sensor's noise and lost returns (``SensorModel``), off by default.

See docs/vision.md for every convention.
"""

from .camera import DepthCamera, ObjectFrame, PinholeCamera, camera_poses
from .depth import (
    DepthRenderer,
    depth_from_mm,
    depth_to_mm,
    depth_to_rgb,
    render_depth,
    renderer_for,
    save_depth_png,
)
from .points import depth_to_points, point_clouds
from .sensor import SensorModel, apply_sensor

__all__ = [
    "DepthCamera",
    "DepthRenderer",
    "ObjectFrame",
    "PinholeCamera",
    "SensorModel",
    "apply_sensor",
    "camera_poses",
    "depth_from_mm",
    "depth_to_mm",
    "depth_to_points",
    "depth_to_rgb",
    "point_clouds",
    "render_depth",
    "renderer_for",
    "save_depth_png",
]
