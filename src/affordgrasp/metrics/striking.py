"""A blunt striking surface and the swing that strikes with it, without part labels, for real tools.

A hammer's striking face (an axe's poll) is the flat end of a long, massive head: behind it,
along the inward normal, lies the head's whole length (60-170 mm), and around it the surface
stays in U's tangent plane for several millimetres. The other blunt surfaces of the same head
fail one or the other: its side faces (cheeks) have only the head's width behind them (22-32
mm), a claw's tines a few millimetres, and a ball peen, as deep as the face, curves away from
its tangent plane (1-1.5 mm at 5 mm from U on a ball of 11-15 mm radius, 0-0.3 mm on a flat
face with a scanner's noise).

* ``use_depth`` (m): the chord through the solid behind U along -n (one ray from just inside
  U to the first exit).
* ``use_relief`` (m): how far U and the surface on a ring of radius :data:`RELIEF_RADIUS_M`
  around it (:data:`RELIEF_RAYS` rays cast along -n from :data:`RELIEF_HEIGHT_M` above U's
  tangent plane) lie from their best-fit plane: the largest residual; +inf where a ray misses
  (the ring leaves the part: a claw's tine, an edge).

* ``use_swing_cosine``: per grasp, the cosine between U's outward normal and the velocity
  a swing about the wrist axis gives U: 1 when the face meets its target square.
* ``use_lever_ratio``: per grasp, whether that swing strikes with the massive end: U's
  distance from the wrist axis over the centre of mass's, projected on U's side.

The first two depend on the solid, not on its triangles (rays on a closed mesh), so a scan-like
variant reads what its crisp family does (tests/metrics/test_striking.py: a box's faces, a
sphere's sag, a thin plate). Calibrated with ``studies/calibrate_striking.py``.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..rays.mesh import mesh_caster
from .cones import plane_axes
from .validation import points_n3, positive_length, use_normals_n3

RELIEF_RADIUS_M = 0.005  # ring radius of use_relief
RELIEF_RAYS = 8  # rays on the ring
RELIEF_HEIGHT_M = 0.01  # the ring's rays start this far above U's tangent plane
_DEPTH_START_M = 2e-5  # the depth ray starts this far inside U, along -n


def _first_hits(mesh, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Distance to the first hit of each ray ((n,) float64, +inf for a miss), m."""
    return mesh_caster(mesh).cast(origins, directions).distance


def _checked(use_point, use_normal) -> tuple[np.ndarray, np.ndarray]:
    P = points_n3(use_point, "use_point")
    return P, use_normals_n3(use_normal, P)


def use_depth(mesh, use_point, use_normal) -> float | np.ndarray:
    """The solid's depth behind U along its inward normal (``use_depth``), m.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m, closed (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    use_point : (3,) or (n, 3) float
        Use points on the surface, m.
    use_normal : (3,) or (n, 3) float
        Outward unit normals there.

    Returns
    -------
    float or (n,) float64 ndarray
        m; 0 where the ray finds no exit (U off the surface); a float for a single point.
    """
    single = np.ndim(use_point) == 1
    P, N = _checked(use_point, use_normal)
    if len(P) == 0:
        return np.zeros(0)
    t = _first_hits(mesh, P - _DEPTH_START_M * N, -N)
    out = np.where(np.isfinite(t), t + _DEPTH_START_M, 0.0)
    return float(out[0]) if single else out


def use_relief(
    mesh, use_point, use_normal, *, radius: float = RELIEF_RADIUS_M, rays: int = RELIEF_RAYS
) -> float | np.ndarray:
    """How far U and the surface around it leave their best-fit plane (``use_relief``), m.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    use_point : (3,) or (n, 3) float
        Use points on the surface, m.
    use_normal : (3,) or (n, 3) float
        Outward unit normals there.
    radius : float
        Ring radius, m (default 5 mm).
    rays : int
        Rays on the ring (>= 3).

    Returns
    -------
    float or (n,) float64 ndarray
        m, >= 0: the largest distance of U and of the ring's points (the first surface met
        coming down along -n from 10 mm above U's tangent plane) from the plane fitted to
        them by least squares; +inf where a ray misses; a float for a single point. 0 on a
        plane, whatever U's normal; 8/9 (R - sqrt(R² - r²)) on a sphere of radius R.
    """
    single = np.ndim(use_point) == 1
    P, N = _checked(use_point, use_normal)
    radius = positive_length(radius, "radius")
    k = int(rays)
    if k < 3:
        raise InputError(f"rays must be an integer >= 3, got {rays}")
    n = len(P)
    if n == 0:
        return np.zeros(0)
    e1, e2 = plane_axes(N)
    angle = 2.0 * np.pi * np.arange(k) / k
    ring = (
        np.cos(angle)[None, :, None] * e1[:, None, :]
        + np.sin(angle)[None, :, None] * e2[:, None, :]
    )  # (n, k, 3)
    origins = P[:, None, :] + radius * ring + RELIEF_HEIGHT_M * N[:, None, :]
    directions = np.broadcast_to(-N[:, None, :], origins.shape)
    t = _first_hits(mesh, origins.reshape(-1, 3), np.ascontiguousarray(directions.reshape(-1, 3)))
    # heights of U (0) and of the ring's hits over U's tangent plane, and their best-fit plane
    # z = a x + b y + c (the ring is symmetric about U, so the normal equations are
    # diagonal): the residual does not depend on the tilt of U's own normal, which a
    # scanner's noise turns by several degrees
    z = np.concatenate([np.zeros((n, 1)), RELIEF_HEIGHT_M - t.reshape(n, k)], axis=1)
    x = np.concatenate([[0.0], radius * np.cos(angle)])
    y = np.concatenate([[0.0], radius * np.sin(angle)])
    with np.errstate(invalid="ignore"):
        # einsum's own loop, not a BLAS product: a row's sums must not depend on how many
        # rows the batch has (a dataset's rows are the same in any batch)
        a = np.einsum("ij,j->i", z, x) / np.einsum("j,j->", x, x)
        b = np.einsum("ij,j->i", z, y) / np.einsum("j,j->", y, y)
        c = z.mean(axis=1)
        residual = np.abs(z - a[:, None] * x - b[:, None] * y - c[:, None])
    out = np.where(np.isfinite(t.reshape(n, k)).all(axis=1), residual.max(axis=1), np.inf)
    return float(out[0]) if single else out


def use_swing_cosine(use_point, use_normal, wrist_point, wrist_axis) -> float | np.ndarray:
    """Cosine between U's outward normal and its swing velocity (``use_swing_cosine``).

    The hand swings positively about the wrist axis (unit a through the palm centre w); U
    moves along v = a × r, r the part of U - w perpendicular to a. The strike's impulse
    acts wholly against the swing when the face U strikes with leads it, n along v (1);
    a face whose normal runs along the lever (the top of a hammer's head, struck with the
    palm a few centimetres off the handle) reads about the palm's offset over the lever,
    though its moment may still point along -a (δ, which reads the moment's direction only,
    is then 1).

    Parameters
    ----------
    use_point : (n, 3) float
        m.
    use_normal : (n, 3) float
        Outward unit normals at U.
    wrist_point : (n, 3) float
        Palm centres, m.
    wrist_axis : (n, 3) float
        Unit approach directions.

    Returns
    -------
    (n,) float64 ndarray
        In [-1, 1]; 0 where U lies on the axis; NaN where U is NaN.
    """
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    N = np.asarray(use_normal, dtype=np.float64).reshape(-1, 3)
    W = np.asarray(wrist_point, dtype=np.float64).reshape(-1, 3)
    A = np.asarray(wrist_axis, dtype=np.float64).reshape(-1, 3)
    A = A / np.linalg.norm(A, axis=1, keepdims=True)
    v = np.cross(A, _off_axis(U, W, A))
    speed = np.linalg.norm(v, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.einsum("ij,ij->i", N, v) / speed
    cosine = np.where(speed > 1e-12, cosine, np.where(np.isnan(speed), np.nan, 0.0))
    return np.clip(cosine, -1.0, 1.0)


def _off_axis(P: np.ndarray, W: np.ndarray, A: np.ndarray) -> np.ndarray:
    """(n, 3) offsets of the points P from the axes through W along A, square to A."""
    d = P - W
    return d - np.einsum("ij,ij->i", d, A)[:, None] * A


def use_lever_ratio(use_point, center_of_mass, wrist_point, wrist_axis) -> np.ndarray:
    """How far U is from the wrist axis, relative to the centre of mass (``use_lever_ratio``).

    With r_U and r_C the offsets of U and of the centre of mass from the wrist axis (the line
    through the palm centre along the approach direction; the parts perpendicular to it), the
    ratio is |r_U|² / (r_C · r_U): U's lever over the centre of mass's lever projected on U's
    side. A swing about that axis strikes with its massive end when the ratio is at least 1
    (the mass lies between the axis and U) and small (the mass near U: at most 2 puts it in
    the outer half of the lever). A hammer held by its handle, whose steel head holds the
    centre of mass, strikes with the head (ratio a little over 1); striking with the handle's
    end beyond the hand puts the mass on the other side of the axis (negative), and holding
    the head to strike with the handle puts the mass near the axis (large).

    Parameters
    ----------
    use_point, wrist_point, wrist_axis
        As for :func:`use_swing_cosine`.
    center_of_mass : (3,) float
        m.

    Returns
    -------
    (n,) float64 ndarray
        Dimensionless; -inf when the centre of mass is on the axis or on the other side of it
        from U (r_C · r_U <= 0); NaN where U is NaN (no use point).
    """
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    W = np.asarray(wrist_point, dtype=np.float64).reshape(-1, 3)
    A = np.asarray(wrist_axis, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(center_of_mass, dtype=np.float64).reshape(1, 3)
    r_u = _off_axis(U, W, A)
    r_c = _off_axis(np.broadcast_to(c, U.shape), W, A)
    along = np.einsum("ij,ij->i", r_c, r_u)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.einsum("ij,ij->i", r_u, r_u) / along
    return np.where(along > 0, ratio, np.where(np.isnan(along), np.nan, -np.inf))
