"""Hand effort on hold E_h and on impact E_i (conventions: Metrics).

Both are linear programs over the cone-edge weights ``λ >= 0`` of all contacts (see
:mod:`affordgrasp.metrics.cones`): each edge has unit normal component, so ``Σ λ`` is
the sum of the contact normal forces, in newtons. Wrenches are taken about the centre of
mass ``c`` with real torques (N·m, no r_max scaling).

* E_h ∈ R^6: for a 1 N gravity force ``g`` along +x, −x, +y, −y, +z, −z of the mesh
  frame applied at ``c``: ``min Σ λ  s.t.  W λ + (g, 0) = 0``.
* E_i: the hand swings positively about the wrist axis ``+a``; at impact a unit inertial
  couple ``(0, a)`` (1 N·m) is balanced by the contacts plus a free force ``s >= 0`` at
  the use point ``U`` along the inward normal ``n_in`` (its magnitude costs nothing):
  ``min Σ λ  s.t.  W λ + s (n_in, (U - c) x n_in) + (0, a) = 0``.

Both are +inf when infeasible (and with no contact). E_i is per unit torque: it scales as
1/length under a uniform scaling of the scene; E_h is scale invariant.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import InternalError
from ..runtime.kernel_cache import install_package_stamp
from .cones import wrench_matrix_kernel
from .lp import INFEASIBLE, OPTIMAL, HighsStandardLP, LPStatus, check_backend, simplex_standard
from .validation import contact_arrays, point3, unit3

install_package_stamp()  # before the first @njit (see kernel_cache)

# Order of the six gravity directions of E_h (column suffixes: columns.HOLD_EFFORT_SUFFIXES).
GRAVITY_DIRECTIONS = np.array(
    [[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]]
)


@njit(cache=True)
def use_wrench(use_point, use_normal, center):
    """Wrench of a unit force at the use point along the *inward* normal, about ``center``.

    Parameters
    ----------
    use_point : (3,) float64 ndarray
        The use point U, m.
    use_normal : (3,) float64 ndarray
        Outward unit normal at U.
    center : (3,) float64 ndarray
        Reference point of the torques, m.

    Returns
    -------
    (6,) float64 ndarray
        Force (N) then torque (N·m) of 1 N.
    """
    w = np.empty(6)
    nx = -use_normal[0]
    ny = -use_normal[1]
    nz = -use_normal[2]
    rx = use_point[0] - center[0]
    ry = use_point[1] - center[1]
    rz = use_point[2] - center[2]
    w[0] = nx
    w[1] = ny
    w[2] = nz
    w[3] = ry * nz - rz * ny
    w[4] = rz * nx - rx * nz
    w[5] = rx * ny - ry * nx
    return w


@njit(cache=True)
def _status_value(status, obj):
    if status == OPTIMAL:
        return True, obj
    if status == INFEASIBLE:
        return True, np.inf
    return False, np.nan  # FAILED (or an impossible UNBOUNDED): recompute with HiGHS


@njit(cache=True)
def hold_effort_kernel(W, out):
    """E_h of a wrench matrix, compiled.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    out : (6,) float64 ndarray
        Written with E_h along +x, −x, +y, −y, +z, −z, N (+inf where infeasible).

    Returns
    -------
    bool
        False when an LP could not be certified and HiGHS must recompute it.
    """
    n = W.shape[1]
    if n == 0:
        for d in range(6):
            out[d] = np.inf
        return True
    c = np.ones(n)
    x = np.empty(n)
    b = np.zeros(6)
    all_ok = True
    for d in range(6):
        for i in range(6):
            b[i] = 0.0
        b[d // 2] = -1.0 if d % 2 == 0 else 1.0  # W λ = -g
        status, obj = simplex_standard(W, b, c, x)
        ok, out[d] = _status_value(status, obj)
        all_ok = all_ok and ok
    return all_ok


@njit(cache=True)
def impact_lp(W, w_use, axis):
    """Standard-form data of the E_i program (variables λ, then s).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force (:func:`use_wrench`).
    axis : (3,) float64 ndarray
        Unit wrist axis a.

    Returns
    -------
    A : (6, N + 1) float64 ndarray
    b : (6,) float64 ndarray
    c : (N + 1,) float64 ndarray
        min c·x subject to A x = b, x >= 0.
    """
    n = W.shape[1]
    A = np.empty((6, n + 1))
    A[:, :n] = W
    A[:, n] = w_use
    b = np.zeros(6)
    b[3] = -axis[0]
    b[4] = -axis[1]
    b[5] = -axis[2]
    c = np.ones(n + 1)
    c[n] = 0.0
    return A, b, c


@njit(cache=True)
def impact_effort_kernel(W, w_use, axis):
    """E_i of a wrench matrix, compiled.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force.
    axis : (3,) float64 ndarray
        Unit wrist axis a.

    Returns
    -------
    ok : bool
        False: use HiGHS (:func:`impact_effort_highs`).
    value : float
        N per N·m, +inf if infeasible.
    """
    if W.shape[1] == 0:
        return True, np.inf
    A, b, c = impact_lp(W, w_use, axis)
    x = np.empty(A.shape[1])
    status, obj = simplex_standard(A, b, c, x)
    return _status_value(status, obj)


def hold_effort(contacts, center, *, soft: bool = False, backend: str = "simplex") -> np.ndarray:
    """Hand effort on hold E_h (conventions: Metrics).

    Parameters
    ----------
    contacts : ContactSet
        Points (k, 3) m, outward normals (k, 3), mu (k,), in the object's mesh frame.
    center : (3,) float
        Centre of mass, m (the reference point of the torques).
    soft : bool
        Soft-finger cones (torsional friction).
    backend : {"simplex", "highs"}
        The LP solver (:mod:`.lp`); both give the same optimum.

    Returns
    -------
    (6,) float64 ndarray
        N: the minimum sum of contact normal forces that balances 1 N of gravity along +x,
        −x, +y, −y, +z, −z (:data:`affordgrasp.columns.HOLD_EFFORT_SUFFIXES`); +inf where
        no contact forces can.
    """
    check_backend(backend)
    points, normals, mu = contact_arrays(contacts)
    center = point3(center, "center")
    W = wrench_matrix_kernel(points, normals, mu, center, 1.0, bool(soft))
    out = np.empty(6)
    if backend == "simplex" and hold_effort_kernel(W, out):
        return out
    return hold_effort_highs(W)


def hold_effort_highs(W: np.ndarray) -> np.ndarray:
    """E_h of a wrench matrix with HiGHS: one model, six right-hand sides.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.

    Returns
    -------
    (6,) float64 ndarray
        N, +inf where infeasible.
    """
    if W.shape[1] == 0:
        return np.full(6, np.inf)
    model = HighsStandardLP(W, np.ones(W.shape[1]))
    out = np.empty(6)
    for d, g in enumerate(GRAVITY_DIRECTIONS):
        res = model.solve(-np.concatenate([g, np.zeros(3)]))
        out[d] = _lp_value(res)
    return out


def _lp_value(res) -> float:
    if res.status is LPStatus.OPTIMAL:
        return float(res.objective)
    if res.status is LPStatus.INFEASIBLE:
        return float("inf")
    if res.status is LPStatus.UNDECIDED:
        return float("nan")
    raise InternalError("a minimum-effort LP reported unbounded; its costs are >= 0")


def impact_effort(
    contacts,
    center,
    use_point,
    use_normal,
    wrist_axis,
    *,
    soft: bool = False,
    backend: str = "simplex",
) -> float:
    """Hand effort on impact E_i (conventions: Metrics), N per N·m of inertial torque.

    Parameters
    ----------
    contacts : ContactSet
        Points (k, 3) m, outward normals (k, 3), mu (k,), in the object's mesh frame.
    center : (3,) float
        Centre of mass, m (the reference point of the torques).
    use_point : (3,) float
        The use point U, m.
    use_normal : (3,) float
        Outward unit normal at U.
    wrist_axis : (3,) float
        Direction a of the wrist axis (normalised here); the swing is positive about +a.
    soft : bool
        Soft-finger cones (torsional friction).
    backend : {"simplex", "highs"}
        The LP solver (:mod:`.lp`); both give the same optimum.

    Returns
    -------
    float
        The minimum sum of contact normal forces; +inf if infeasible.
    """
    check_backend(backend)
    points, normals, mu = contact_arrays(contacts)
    center = point3(center, "center")
    use_point = point3(use_point, "use_point")
    use_normal = unit3(use_normal, "use_normal")
    axis = unit3(wrist_axis, "wrist_axis")
    W = wrench_matrix_kernel(points, normals, mu, center, 1.0, bool(soft))
    w_use = use_wrench(use_point, use_normal, center)
    if backend == "simplex":
        ok, value = impact_effort_kernel(W, w_use, axis)
        if ok:
            return float(value)
    return impact_effort_highs(W, w_use, axis)


def impact_effort_highs(W: np.ndarray, w_use: np.ndarray, axis: np.ndarray) -> float:
    """E_i with HiGHS (same program as :func:`impact_effort_kernel`).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force.
    axis : (3,) float64 ndarray
        Unit wrist axis a.

    Returns
    -------
    float
        N per N·m, +inf if infeasible.
    """
    if W.shape[1] == 0:
        return float("inf")
    A, b, c = impact_lp(np.ascontiguousarray(W), w_use, axis)
    return _lp_value(HighsStandardLP(A, c).solve(b))
