"""A depth sensor's imperfections, applied to exact depth images (conventions: Vision).

The renderers make the exact image D(p0, O). A real depth camera adds noise that grows with
distance and returns nothing where the surface is seen at a grazing angle (structured light
and time of flight both lose the reflected signal there) or at random. :func:`apply_sensor`
applies such a model, off by default everywhere (``sensor=None``): models trained on the
noisy images can then face a real camera.

The model (its numbers are :class:`SensorModel`'s defaults, of the order of a
consumer structured-light camera at half a metre, Khoshelham & Elberink 2012):

* depth noise: z + N(0, σ(z)²) with σ(z) = ``sigma_m`` + ``sigma_quadratic`` · z², m;
* grazing returns lost: the surface normal of each pixel is estimated from the image itself
  (the cross product of the differences to its right and lower neighbours, back-projected);
  where the angle between the pixel's ray and the normal exceeds ``grazing_deg`` the return
  is dropped (0);
* random dropout: each remaining return is lost with probability ``dropout``.

Seeded: image i's noise depends only on (``seed``, ``keys[i]``), never on the batch it
came in, so the same pregrasp gives the same noisy image in any batch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .camera import DepthCamera


@dataclass(frozen=True)
class SensorModel:
    """How a depth sensor departs from the exact image.

    Attributes
    ----------
    sigma_m : float
        Depth noise standard deviation at zero distance, m.
    sigma_quadratic : float
        Growth of the standard deviation with the squared depth, 1/m (σ = sigma_m +
        sigma_quadratic · z²).
    grazing_deg : float
        Returns whose ray meets the surface at more than this angle from its normal are
        lost, degrees (90: none lost).
    dropout : float
        Probability that any other return is lost.
    seed : int
        Seeds the noise (with each image's key).
    """

    sigma_m: float = 0.0005
    sigma_quadratic: float = 0.0028
    grazing_deg: float = 75.0
    dropout: float = 0.01
    seed: int = 0

    def __post_init__(self):
        if self.sigma_m < 0 or self.sigma_quadratic < 0:
            raise InputError(
                f"sensor noise must be >= 0, got sigma_m={self.sigma_m}, "
                f"sigma_quadratic={self.sigma_quadratic}"
            )
        if not 0.0 < self.grazing_deg <= 90.0:
            raise InputError(f"grazing_deg must be in (0, 90], got {self.grazing_deg}")
        if not 0.0 <= self.dropout < 1.0:
            raise InputError(f"dropout must be in [0, 1), got {self.dropout}")


def surface_cosines(depth: np.ndarray, camera: DepthCamera | None = None) -> np.ndarray:
    """|cos| of the angle between each pixel's ray and the surface normal seen there.

    The normal is the cross product of the back-projected differences to the right and the
    lower neighbour (the left/upper one at the last column/row); pixels without a return,
    or whose neighbours have none, get 1 (treated as seen head-on).

    Parameters
    ----------
    depth : (n, h, w) float ndarray
        Depth along the optical axis, m; 0 = no return.
    camera : DepthCamera, optional
        The intrinsics the images were made with; the default camera when None.

    Returns
    -------
    (n, h, w) float64 ndarray
        In [0, 1].
    """
    camera = camera or DepthCamera(size=depth.shape[-1])
    rays = camera.ray_directions().astype(np.float64)  # (h, w, 3), z = 1
    z = np.asarray(depth, dtype=np.float64)
    points = z[..., None] * rays[None]  # (n, h, w, 3), camera frame, m
    dx = np.diff(points, axis=2, append=points[:, :, -2:-1])
    dx[:, :, -1] *= -1.0  # the last column looks left: keep the orientation
    dy = np.diff(points, axis=1, append=points[:, -2:-1])
    dy[:, -1] *= -1.0
    normal = np.cross(dx, dy)
    norm = np.linalg.norm(normal, axis=-1)
    ray_norm = np.linalg.norm(rays, axis=-1)[None]
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(np.einsum("nhwk,hwk->nhw", normal, rays)) / (norm * ray_norm)
    valid = z > 0
    right = np.concatenate([valid[:, :, 1:], valid[:, :, -2:-1]], axis=2)
    down = np.concatenate([valid[:, 1:], valid[:, -2:-1]], axis=1)
    ok = valid & right & down & (norm > 0)
    return np.where(ok, np.clip(cos, 0.0, 1.0), 1.0)


def apply_sensor(
    depth: np.ndarray, model: SensorModel, keys=None, camera: DepthCamera | None = None
) -> np.ndarray:
    """Depth images as the sensor model would return them.

    Parameters
    ----------
    depth : (n, h, w) float ndarray
        Exact depth, m; 0 = no return.
    model : SensorModel
        The imperfections.
    keys : (n,) or (n, m) array_like of int, optional
        Non-negative key(s) per image (e.g. its sample index, or an object id and a sample
        index): image i's noise depends only on (model.seed, keys[i]). Default: 0, 1, ...,
        n − 1.
    camera : DepthCamera, optional
        The intrinsics the images were made with.

    Returns
    -------
    (n, h, w) float32 ndarray
        Noisy depth, m; 0 = no return (never negative).
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.ndim != 3:
        raise InputError(f"depth must be (n, h, w) images, got shape {depth.shape}")
    n = len(depth)
    keys = np.arange(n) if keys is None else np.asarray(keys, dtype=np.int64)
    keys = keys.reshape(len(keys), -1) if keys.ndim else keys.reshape(1, 1)
    if len(keys) != n or (keys.size and keys.min() < 0):
        raise InputError(f"keys must be {n} rows of non-negative integers, one per image")
    # one generator per image: its draws do not depend on the batch it came in
    gauss = np.empty_like(depth)
    uniform = np.empty_like(depth)
    for i, key in enumerate(keys):
        rng = np.random.default_rng(np.random.SeedSequence([int(model.seed), *map(int, key)]))
        gauss[i] = rng.standard_normal(depth.shape[1:])
        uniform[i] = rng.random(depth.shape[1:])
    valid = depth > 0
    sigma = model.sigma_m + model.sigma_quadratic * depth**2
    noisy = depth + sigma * gauss
    keep = valid & (noisy > 0) & (uniform >= model.dropout)
    if model.grazing_deg < 90.0:
        keep &= surface_cosines(depth, camera) >= np.cos(np.radians(model.grazing_deg))
    return np.where(keep, noisy, 0.0).astype(np.float32)
