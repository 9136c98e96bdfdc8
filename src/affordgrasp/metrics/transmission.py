"""Force transmitted to use U_τ (conventions: Metrics).

The largest force ``F >= 0`` the object can press on the environment at the use point
``U`` along its outward normal, in static equilibrium, with every contact force inside
its (linearised) friction cone and every contact's normal force at most 1 N. The
environment pushes back with ``F n_in`` (inward normal), so::

    max F  s.t.  W λ + F (n_in, (U - c) x n_in) = 0,  λ >= 0,
                 Σ_j λ_ij <= 1 for every contact i        (normal force <= 1 N)

with real torques about the centre of mass ``c``. ``λ = 0, F = 0`` is always feasible,
and F is bounded (the force rows of ``W λ`` are bounded and ``n_in`` is a unit vector), so
the program always has an optimum; U_τ = 0 when no force can be transmitted (also with
no contact). Units: N. Scale invariant.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import InternalError
from ..runtime.kernel_cache import install_package_stamp
from .cones import wrench_matrix_kernel
from .effort import use_wrench
from .lp import OPTIMAL, HighsStandardLP, LPStatus, check_backend, simplex_standard
from .validation import contact_arrays, point3, unit3

install_package_stamp()  # before the first @njit (see kernel_cache)


@njit(cache=True)
def use_force_lp(W, w_use, n_contacts):
    """Standard-form data ``(A, b, c)`` of the U_τ program.

    Variables: λ (N = k * E), F, then one slack per contact. Rows: 6 equilibrium rows,
    then one normal-force bound per contact (edges are contact-major in ``W``).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force.
    n_contacts : int
        k.

    Returns
    -------
    A : (6 + k, N + 1 + k) float64 ndarray
    b : (6 + k,) float64 ndarray
    c : (N + 1 + k,) float64 ndarray
    """
    n = W.shape[1]
    k = n_contacts
    E = n // k
    A = np.zeros((6 + k, n + 1 + k))
    A[:6, :n] = W
    A[:6, n] = w_use
    b = np.zeros(6 + k)
    for i in range(k):
        for j in range(E):
            A[6 + i, i * E + j] = 1.0
        A[6 + i, n + 1 + i] = 1.0
        b[6 + i] = 1.0
    c = np.zeros(n + 1 + k)
    c[n] = -1.0
    return A, b, c


@njit(cache=True)
def use_force_kernel(W, w_use, n_contacts):
    """U_τ of a wrench matrix, compiled.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force.
    n_contacts : int
        k.

    Returns
    -------
    status : int
        OPTIMAL, or the simplex status when it could not certify an optimum (the caller
        then uses HiGHS).
    value : float
        N.
    """
    if n_contacts == 0:
        return OPTIMAL, 0.0
    A, b, c = use_force_lp(W, w_use, n_contacts)
    x = np.empty(A.shape[1])
    status, obj = simplex_standard(A, b, c, x)
    if status != OPTIMAL:
        return status, np.nan
    return OPTIMAL, max(0.0, -obj)


def use_force(
    contacts, center, use_point, use_normal, *, soft: bool = False, backend: str = "simplex"
) -> float:
    """Force transmitted to use U_τ (conventions: Metrics), N.

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
    soft : bool
        Soft-finger cones (torsional friction).
    backend : {"simplex", "highs"}
        The LP solver (:mod:`.lp`); both give the same optimum.

    Returns
    -------
    float
        The largest force at U along the outward normal with every contact's normal force
        <= 1 N and inside its cone; 0 when none.
    """
    check_backend(backend)
    points, normals, mu = contact_arrays(contacts)
    center = point3(center, "center")
    use_point = point3(use_point, "use_point")
    use_normal = unit3(use_normal, "use_normal")
    W = wrench_matrix_kernel(points, normals, mu, center, 1.0, bool(soft))
    w_use = use_wrench(use_point, use_normal, center)
    k = points.shape[0]
    if backend == "simplex":
        status, value = use_force_kernel(W, w_use, k)
        if status == OPTIMAL:
            return float(value)
    return use_force_highs(W, w_use, k)


def use_force_highs(W: np.ndarray, w_use: np.ndarray, n_contacts: int) -> float:
    """U_τ with HiGHS (same program as :func:`use_force_kernel`).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix of the cone edges (:func:`affordgrasp.metrics.cones.contact_wrenches`),
        N = k * E columns, contact-major.
    w_use : (6,) float64 ndarray
        Wrench of the unit use force.
    n_contacts : int
        k.

    Returns
    -------
    float
        N; 0 when no force can be transmitted.
    """
    if n_contacts == 0:
        return 0.0
    if W.shape[1] % n_contacts:
        raise InternalError(f"{W.shape[1]} wrench columns do not split over {n_contacts} contacts")
    A, b, c = use_force_lp(np.ascontiguousarray(W), w_use, n_contacts)
    res = HighsStandardLP(A, c).solve(b)
    # F = 0, λ = 0 is feasible and F is bounded: anything but an optimum (or a program no
    # solver could decide numerically, reported as NaN) is a bug
    if res.status is LPStatus.UNDECIDED:
        return float("nan")
    if res.status is not LPStatus.OPTIMAL:
        raise InternalError(f"the U_τ program must have an optimum, HiGHS says {res.status}")
    return max(0.0, -float(res.objective))
