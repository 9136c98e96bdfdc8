"""Linearised friction cones and contact wrench matrices (conventions: Metrics).

Every contact-based metric (ε, E_h, E_i, U_τ) uses the same cones, built exactly as
GraspIt! builds them in the object's mesh frame, so that anyone following conventions: Metrics
reproduces the numbers to 1e-9:

* ``n`` is the *inward* unit normal (minus the object's outward normal);
* ``t1 = normalise(n x (1, 0, 0))``, or ``normalise(n x (0, 0, 1))`` when
  ``|n . (1, 0, 0)| > 1 - 1e-12``; ``t2 = normalise(n x t1)``;
* edge ``j`` (j = 0..7) is ``f_j = n + mu (cos θ_j t1 + sin θ_j t2)``, ``θ_j = 2 π j / 8``.

Each edge has unit normal component, so the sum of an edge combination's weights is the
contact's normal force.

Soft-finger option (off by default): two more edges per contact that carry a pure
torsional moment about the contact normal, ``(n, ±γ n)`` (force, extra torque), with
``γ = (2/3) μ a`` the torsional friction coefficient (metres) of a circular contact patch
of radius ``a`` under uniform pressure (``a`` = :data:`SOFT_PATCH_RADIUS_M`). The cone is
then the convex hull of the tangential and the torsional edges (a linear, conservative
limit surface: tangential and torsional friction share the normal force), and every edge
still has unit normal component.

Wrench layout: the wrench matrix is ``(6, k * E)`` with ``E`` edges per contact
(8, or 10 when soft), contact-major: columns ``i*E .. i*E+E-1`` belong to contact ``i``.
A column is ``(f, (p - c) x f * torque_scale)`` (plus ``±γ n * torque_scale`` in the
torque rows of the torsional edges).

:func:`plane_axes` gives unit normals a plain in-plane frame, for the fits, rings and chords
that need one and not GraspIt!'s convention.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import InputError
from ..runtime.kernel_cache import install_package_stamp
from ..tolerances import CONE_AXIS_SWITCH

# before the first @njit of the metrics: every kernel module imports this one first
install_package_stamp()

N_EDGES = 8  # edges of the linearised Coulomb cone (GraspIt!)
N_SOFT_EDGES = 2  # extra torsional edges of a soft-finger contact
SOFT_PATCH_RADIUS_M = 0.005  # contact patch radius behind the torsional coefficient
_AXIS_TOL = CONE_AXIS_SWITCH  # GraspIt!'s switch from the x axis to the z axis for t1


def edges_per_contact(soft: bool = False) -> int:
    """Number of wrench columns per contact: 8, or 10 with soft-finger torsion.

    Parameters
    ----------
    soft : bool
        Soft-finger contacts (two torsional edges added).

    Returns
    -------
    int
    """
    return N_EDGES + (N_SOFT_EDGES if soft else 0)


@njit(cache=True)
def _tangent_frame(nx, ny, nz):
    """GraspIt!'s tangents (t1, t2) of an inward unit normal (nx, ny, nz)."""
    if abs(nx) > 1.0 - _AXIS_TOL:
        # n x (0, 0, 1)
        ax, ay, az = ny, -nx, 0.0
    else:
        # n x (1, 0, 0)
        ax, ay, az = 0.0, nz, -ny
    s = np.sqrt(ax * ax + ay * ay + az * az)
    ax /= s
    ay /= s
    az /= s
    bx = ny * az - nz * ay
    by = nz * ax - nx * az
    bz = nx * ay - ny * ax
    s = np.sqrt(bx * bx + by * by + bz * bz)
    return ax, ay, az, bx / s, by / s, bz / s


@njit(cache=True)
def wrench_matrix_kernel(points, normals, mu, center, torque_scale, soft):
    """Compiled wrench matrix; see the module docstring for the layout.

    Parameters
    ----------
    points : (k, 3) float64 ndarray
        Contact points, m.
    normals : (k, 3) float64 ndarray
        Outward unit normals.
    mu : (k,) float64 ndarray
        Friction coefficients.
    center : (3,) float64 ndarray
        Reference point of the torques, m.
    torque_scale : float
        Multiplies the torque rows (1 / r_max for ε, 1 for the efforts).
    soft : bool
        Add the two torsional edges per contact.

    Returns
    -------
    (6, k * E) float64 ndarray
        Columns contact-major, E = :func:`edges_per_contact`.
    """
    k = points.shape[0]
    E = N_EDGES + (N_SOFT_EDGES if soft else 0)
    W = np.empty((6, k * E))
    for i in range(k):
        nx = -normals[i, 0]
        ny = -normals[i, 1]
        nz = -normals[i, 2]
        t1x, t1y, t1z, t2x, t2y, t2z = _tangent_frame(nx, ny, nz)
        rx = points[i, 0] - center[0]
        ry = points[i, 1] - center[1]
        rz = points[i, 2] - center[2]
        m = mu[i]
        for j in range(N_EDGES):
            th = 2.0 * np.pi * j / N_EDGES
            c = np.cos(th)
            s = np.sin(th)
            fx = nx + m * (c * t1x + s * t2x)
            fy = ny + m * (c * t1y + s * t2y)
            fz = nz + m * (c * t1z + s * t2z)
            col = i * E + j
            W[0, col] = fx
            W[1, col] = fy
            W[2, col] = fz
            W[3, col] = (ry * fz - rz * fy) * torque_scale
            W[4, col] = (rz * fx - rx * fz) * torque_scale
            W[5, col] = (rx * fy - ry * fx) * torque_scale
        if soft:
            gamma = (2.0 / 3.0) * m * SOFT_PATCH_RADIUS_M
            tx = ry * nz - rz * ny
            ty = rz * nx - rx * nz
            tz = rx * ny - ry * nx
            for j in range(N_SOFT_EDGES):
                sign = 1.0 if j == 0 else -1.0
                col = i * E + N_EDGES + j
                W[0, col] = nx
                W[1, col] = ny
                W[2, col] = nz
                W[3, col] = (tx + sign * gamma * nx) * torque_scale
                W[4, col] = (ty + sign * gamma * ny) * torque_scale
                W[5, col] = (tz + sign * gamma * nz) * torque_scale
    return W


def _as_contact_arrays(points, normals, mu):
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    normals = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 3)
    if normals.shape != points.shape:
        raise InputError(
            f"normals {normals.shape} must have the same shape as points {points.shape}"
        )
    mu = np.ascontiguousarray(np.broadcast_to(np.asarray(mu, dtype=np.float64), (points.shape[0],)))
    return points, normals, mu


def tangent_frames(inward_normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """GraspIt!'s tangent vectors of each contact.

    Parameters
    ----------
    inward_normals : (k, 3) float ndarray
        Unit normals pointing *into* the object.

    Returns
    -------
    t1, t2 : (k, 3) float64 ndarray
        Unit; (t1, t2, n) is a right-handed frame.
    """
    n = np.asarray(inward_normals, dtype=np.float64).reshape(-1, 3)
    t1 = np.empty_like(n)
    t2 = np.empty_like(n)
    for i, (x, y, z) in enumerate(n):
        a = _tangent_frame(x, y, z)
        t1[i] = a[:3]
        t2[i] = a[3:]
    return t1, t2


def plane_axes(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal in-plane axes of unit normals: e1 = n × x̂ (n × ŷ when n is near x̂), e2 = n × e1.

    Parameters
    ----------
    normals : (n, 3) float64 ndarray
        Unit normals.

    Returns
    -------
    e1, e2 : (n, 3) float64 ndarray
        Unit; (e1, e2, n) is a right-handed frame.
    """
    helper = np.zeros_like(normals)
    use_x = np.abs(normals[:, 0]) < 0.9
    helper[use_x, 0] = 1.0
    helper[~use_x, 1] = 1.0
    e1 = np.cross(normals, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(normals, e1)
    return e1, e2


def friction_cone_edges(normals: np.ndarray, mu: np.ndarray | float) -> np.ndarray:
    """Edge forces of the linearised friction cones (conventions: Metrics).

    Parameters
    ----------
    normals : (k, 3) float ndarray
        The object's *outward* unit normals.
    mu : (k,) float ndarray or float
        Friction coefficients.

    Returns
    -------
    (k, 8, 3) float64 ndarray
        ``f_j = n + mu (cos θ_j t1 + sin θ_j t2)`` with n inward (unit normal component).
    """
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    W = contact_wrenches(np.zeros_like(normals), normals, mu, np.zeros(3))
    return W[:3].T.reshape(-1, N_EDGES, 3)


def contact_wrenches(
    points: np.ndarray,
    normals: np.ndarray,
    mu: np.ndarray | float,
    center: np.ndarray,
    *,
    torque_scale: float = 1.0,
    soft: bool = False,
) -> np.ndarray:
    """Wrench matrix of all cone edges of a contact set (conventions: Metrics).

    Parameters
    ----------
    points : (k, 3) float ndarray
        Contact points, m.
    normals : (k, 3) float ndarray
        Outward unit normals.
    mu : (k,) float ndarray or float
        Friction coefficients.
    center : (3,) float ndarray
        The reference point of the torques (centre of mass), m.
    torque_scale : float
        Multiplies the torque rows (ε uses 1 / r_max; efforts use 1).
    soft : bool
        Add the two torsional edges of a soft-finger contact per contact.

    Returns
    -------
    (6, k * E) float64 ndarray
        Forces (N per unit edge) then torques, columns contact-major (module docstring).
    """
    points, normals, mu = _as_contact_arrays(points, normals, mu)
    # a writable copy: one kernel signature whether the caller's array is read-only or not
    center = np.array(center, dtype=np.float64).reshape(3)
    return wrench_matrix_kernel(points, normals, mu, center, float(torque_scale), bool(soft))
