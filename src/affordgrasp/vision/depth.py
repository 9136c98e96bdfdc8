"""Depth images D(p0, O) from the camera in the hand (conventions: Vision, paper §III-B).

Depth is the distance along the optical axis (the camera-frame z of the first surface a
pixel's ray meets), metres, float32; a pixel whose ray misses the object is 0 (no return,
as real depth cameras report). See ``camera`` for the conventions and docs/vision.md for a
description precise enough to re-render the pixels. The images are made by one of the
engines of :mod:`affordgrasp.vision.engines` (backends of the package's one ray-casting
interface): by default the triangles are rasterised with a z-buffer (the same pixels up to
rounding); rays cast by Embree (16-ray packets, or ``embreex`` one ray per call) are the
reference and the fallback.

Validated against analytic cases (a plane and a sphere at known distances) in
``tests/vision/test_depth.py``.
"""

from __future__ import annotations

import functools
from collections import OrderedDict

import numpy as np

from ..errors import InputError
from ..grasp.pregrasp import validate_pregrasps
from ..runtime.writing import atomic_write
from .camera import DepthCamera, ObjectFrame, camera_poses
from .engines import EmbreeEngine, PacketEngine, RasterEngine

# Images per Embree call: 64 images = 1 M rays, about 25 MB of ray arrays.
IMAGES_PER_CALL = 64

ENGINES = ("auto", "raster", "packets", "embreex")

# The raster engine leaves to the ray caster an image from a camera nearer to a vertex than
# this fraction of the object's length (projection loses precision there; pregrasp cameras
# are one length before the centre, so at least 0.13 length from every vertex).
NEAR_FRACTION = 0.01

DEPTH_MM_MAX = 65.535  # the largest depth uint16 millimetres can hold, m


class DepthRenderer:
    """Renders D(p0, O) for one object; holds its mesh data (build once, render often).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object in its mesh frame, m.
    camera : DepthCamera, optional
        Intrinsics; the default camera when None.
    engine : {"auto", "raster", "packets", "embreex"}
        How the image is made (:mod:`affordgrasp.vision.engines`): ``"raster"`` (z-buffered
        triangles, see :mod:`affordgrasp.vision.raster`; images it cannot make, from a
        camera almost touching the object, are ray cast), ``"packets"`` (Embree rays in
        16-ray packets from a compiled loop, see :mod:`affordgrasp.rays.packets`),
        ``"embreex"`` (one Embree ray per call, robust scene: the reference) or ``"auto"``
        (``"raster"``, the fastest on every built-in object).
    """

    def __init__(self, mesh, camera: DepthCamera | None = None, *, engine: str = "auto"):
        if engine not in ENGINES:
            raise InputError(f"depth engine must be one of {', '.join(ENGINES)}, got {engine!r}")
        self.camera = camera or DepthCamera()
        self.frame = ObjectFrame.of(mesh)
        self.engine = "raster" if engine == "auto" else engine
        triangles = np.asarray(mesh.triangles, dtype=np.float64)
        centre = self.frame.centre

        def ray_engine():
            # Packets where the library loads (1-2 s, once), else one ray per call.
            from ..rays import packets

            if packets.available():
                return PacketEngine(triangles, centre, self.frame.vertices)
            return EmbreeEngine(triangles, centre)

        self.caster: EmbreeEngine | PacketEngine | RasterEngine
        if self.engine == "raster":
            from .raster import closed_outward

            self.caster = RasterEngine(
                mesh.vertices,
                mesh.faces,
                centre,
                cull=closed_outward(mesh),
                near=NEAR_FRACTION * self.frame.length,
                fallback=ray_engine,
            )
        elif self.engine == "packets":
            self.caster = PacketEngine(triangles, centre, self.frame.vertices)
        else:
            self.caster = EmbreeEngine(triangles, centre)

    def poses(self, p0) -> np.ndarray:
        """Camera poses of pregrasps.

        Parameters
        ----------
        p0 : (n, 6) array_like of float
            Pregrasps, each entry in [0, 1].

        Returns
        -------
        (n, 4, 4) float64 ndarray
            Camera → object transforms, m.
        """
        return camera_poses(self.frame, p0)

    def render(self, p0, *, images_per_call: int = IMAGES_PER_CALL) -> np.ndarray:
        """Depth images of the object seen from pregrasps.

        Parameters
        ----------
        p0 : (n, 6) array_like of float
            Pregrasps, each entry in [0, 1] (checked).
        images_per_call : int
            Images cast per ray-tracing call (memory vs speed).

        Returns
        -------
        (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return.
        """
        p0 = validate_pregrasps(p0)
        return self.render_poses(self.poses(p0), images_per_call=images_per_call)

    def render_poses(self, poses: np.ndarray, *, images_per_call: int = IMAGES_PER_CALL):
        """Depth images from camera poses.

        Parameters
        ----------
        poses : (n, 4, 4) float ndarray
            Camera → object transforms, m.
        images_per_call : int
            Images cast per ray-tracing call.

        Returns
        -------
        (n, size, size) float32 ndarray
            Depth along the optical axis, m; 0 = no return.

        Raises
        ------
        InputError
            When ``poses`` is not (n, 4, 4).
        """
        poses = np.asarray(poses, dtype=np.float64)
        if poses.ndim != 3 or poses.shape[1:] != (4, 4):
            raise InputError(f"camera poses must have shape (n, 4, 4), got {poses.shape}")
        if len(poses) == 0:
            size = self.camera.size
            return np.zeros((0, size, size), dtype=np.float32)
        return self.caster.render(poses, self.camera, images_per_call=images_per_call)


_RENDERERS: OrderedDict = OrderedDict()
_RENDERER_CACHE_SIZE = 8


def renderer_for(obj, camera: DepthCamera | None = None) -> DepthRenderer:
    """A cached renderer of a GraspObject (keyed by mesh hash and camera).

    Parameters
    ----------
    obj : GraspObject
    camera : DepthCamera, optional

    Returns
    -------
    DepthRenderer
    """
    camera = camera or DepthCamera()
    key = (obj.mesh_hash, camera)
    renderer = _RENDERERS.get(key)
    if renderer is None:
        renderer = DepthRenderer(obj.mesh, camera)
        _RENDERERS[key] = renderer
        while len(_RENDERERS) > _RENDERER_CACHE_SIZE:
            _RENDERERS.popitem(last=False)
    else:
        _RENDERERS.move_to_end(key)
    return renderer


def render_depth(obj, p0, camera: DepthCamera | None = None, *, sensor=None, keys=None):
    """D(p0, O): the depth images an in-hand camera sees at each pregrasp.

    Parameters
    ----------
    obj : str, path, GraspObject or trimesh.Trimesh
        ``"knife"``, ``"knife:7"``, a mesh path, an object or a mesh (m).
    p0 : (n, 6) or (6,) array_like of float
        Pregrasps in [-1, 1]^5 × [0, 1].
    camera : DepthCamera, optional
    sensor : SensorModel, optional
        A depth sensor's noise and lost returns (:mod:`affordgrasp.vision.sensor`); None
        (default): the exact image.
    keys : (n,) array_like of int, optional
        With ``sensor``: the key of each image's noise (default 0, 1, ..., n − 1).

    Returns
    -------
    (n, size, size) float32 ndarray
        Depth, m; 0 where the ray hits nothing (no return).
    """
    import trimesh

    if isinstance(obj, trimesh.Trimesh):
        depth = DepthRenderer(obj, camera).render(p0)
    else:
        from ..objects import load_object

        depth = renderer_for(load_object(obj), camera).render(p0)
    if sensor is None:
        return depth
    from .sensor import apply_sensor

    return apply_sensor(depth, sensor, keys, camera)


def depth_to_mm(depth: np.ndarray) -> np.ndarray:
    """Depth in m (float) → uint16 millimetres, rounded to nearest; 0 stays 0 (no return).

    Parameters
    ----------
    depth : float ndarray
        Any shape, m.

    Returns
    -------
    uint16 ndarray
        Same shape, mm.

    Raises
    ------
    InputError
        For depths beyond 65.535 m (what uint16 mm can hold).
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.size and float(np.nanmax(depth)) > DEPTH_MM_MAX:
        raise InputError(
            f"depth {float(np.nanmax(depth)):.3f} m does not fit uint16 millimetres "
            f"(max {DEPTH_MM_MAX} m); scale the object to a real size"
        )
    return np.rint(np.nan_to_num(depth, nan=0.0) * 1000.0).astype(np.uint16)


def depth_from_mm(depth_mm: np.ndarray) -> np.ndarray:
    """uint16 millimetres → float32 metres (0 stays 0).

    Parameters
    ----------
    depth_mm : uint16 ndarray
        Any shape, mm.

    Returns
    -------
    float32 ndarray
        Same shape, m.
    """
    return np.asarray(depth_mm, dtype=np.float32) / np.float32(1000.0)


@functools.lru_cache(maxsize=1)
def _colormap():
    from matplotlib import colormaps

    return colormaps["viridis"]


def depth_to_rgb(depth: np.ndarray) -> np.ndarray:
    """A colour-mapped view of one depth image: near bright, far dark, no return black.

    The range is the image's own min..max depth.

    Parameters
    ----------
    depth : (h, w) float ndarray
        m.

    Returns
    -------
    (h, w, 3) uint8 ndarray
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.ndim != 2:
        raise InputError(f"one depth image (h, w) expected, got shape {depth.shape}")
    hit = depth > 0
    rgb = np.zeros(depth.shape + (3,), dtype=np.uint8)
    if hit.any():
        lo, hi = float(depth[hit].min()), float(depth[hit].max())
        level = 1.0 - (depth - lo) / (hi - lo) if hi > lo else np.ones_like(depth)
        colours = (_colormap()(np.clip(level, 0.0, 1.0))[..., :3] * 255).round()
        rgb[hit] = colours[hit].astype(np.uint8)
    return rgb


def save_depth_png(path, depth: np.ndarray, *, scale: int = 1) -> None:
    """Write the colour-mapped view of one depth image as a PNG (``scale``× nearest).

    Parameters
    ----------
    path : path
        The PNG file.
    depth : (h, w) float ndarray
        m.
    scale : int
        Integer upscaling factor.
    """
    from matplotlib import image as mpimg

    rgb = depth_to_rgb(depth)
    if scale > 1:
        rgb = np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1)
    atomic_write(path, lambda fh: mpimg.imsave(fh, rgb, format="png"))


def depth_manifest(camera: DepthCamera | None = None) -> dict:
    """How a dataset's ``depth_mm`` column was made (recorded in its manifest).

    Parameters
    ----------
    camera : DepthCamera, optional

    Returns
    -------
    dict
        Camera size and field of view, units, encoding.
    """
    camera = camera or DepthCamera()
    return {
        "column": "depth_mm",
        "size": camera.size,
        "fov_deg": camera.fov_deg,
        "encoding": "uint16 millimetres, little-endian, row-major, 0 = no return",
    }


def depth_column(obj, table):
    """The ``depth_mm`` column of a table's pregrasps.

    Parameters
    ----------
    obj : GraspObject
    table : pyarrow.Table
        Rows with a ``p0`` column (n, 6).

    Returns
    -------
    field : pyarrow.Field
    column : pyarrow.Array
        Binary, one uint16 mm image per row.
    """
    import pyarrow as pa

    p0 = np.asarray(table.column("p0").combine_chunks().flatten(), dtype=np.float64)
    images = depth_to_mm(renderer_for(obj).render(p0.reshape(-1, 6)))
    raw = images.astype("<u2").reshape(len(images), -1)
    values = [row.tobytes() for row in raw]
    return pa.field("depth_mm", pa.binary()), pa.array(values, pa.binary())


def decode_depth_column(column) -> np.ndarray:
    """A ``depth_mm`` column (Arrow binary) → depth images in metres.

    Parameters
    ----------
    column : pyarrow.Array or pyarrow.ChunkedArray
        n binary values.

    Returns
    -------
    (n, size, size) float32 ndarray
        m.
    """
    import pyarrow as pa

    if isinstance(column, pa.ChunkedArray):
        column = column.combine_chunks()
    n = len(column)
    if n == 0:
        return np.zeros((0, 128, 128), dtype=np.float32)
    buffers = column.buffers()
    offsets = np.frombuffer(buffers[1], dtype=np.int32, count=n + 1, offset=column.offset * 4)
    data = np.frombuffer(buffers[2], dtype=np.uint8)[offsets[0] : offsets[-1]]
    lengths = np.diff(offsets)
    if np.any(lengths != lengths[0]) or lengths[0] % 2:
        raise InputError("depth_mm column holds images of different sizes")
    side = int(round(np.sqrt(lengths[0] // 2)))
    mm = data.view("<u2").reshape(n, side, side)
    return depth_from_mm(mm)
