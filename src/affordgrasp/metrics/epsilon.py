"""ε, the grasp robustness of GraspIt! (L1 epsilon), and the GWS volume (conventions: Metrics).

Wrenches ``w = (f, (p - c) x f / r_max)`` of every friction-cone edge (see
:mod:`affordgrasp.metrics.cones`); the grasp wrench space is their convex hull (the
origin is *not* added); ε is the distance from the origin to the nearest hull facet when
the origin is strictly inside (force closure), else 0.

The computation is exact and ordered so that grasps that cannot be force closure never
build a hull:

1. no contact -> ε = 0, reason ``"no contact"``;
2. rank of the wrench matrix below 6 (flat wrench set, e.g. two antipodal contacts
   through the centre of mass) -> ε = 0, reason ``"degenerate"``;
3. an LP decides whether the origin is strictly interior to the hull:
   ``max t  s.t.  Σ λ_i w_i = 0, Σ λ_i = 1, λ_i >= t``; with rank 6 the origin is
   interior iff ``t* > 0`` (otherwise reason ``"not force closure"``);
4. only then the exact 6D hull (:mod:`affordgrasp.metrics.hull`, qhull as fallback);
   ε = min over facets of the facet offset, volume = hull volume.

GWS volume convention: reported for force-closure grasps (where it is a quality
measure) and 0 otherwise. GraspIt! also reports a volume for non-closure hulls; use
:func:`gws_volume` for that number.

GraspIt! takes torques about the area-weighted surface centroid and normalises them by
its own ``maxRadius``: pass those as ``center`` and ``r_max`` to reproduce its ε.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..runtime.kernel_cache import install_package_stamp
from .cones import contact_wrenches, wrench_matrix_kernel
from .hull import (
    HULL_DEGENERATE,
    HULL_OK,
    build_hull,
    convex_hull_6d,
    facet_spread,
    hull_volume,
    hull_workspace,
    store_volume,
)
from .lp import FAILED, OPTIMAL, simplex_standard
from .validation import contact_arrays, point3, positive_length

install_package_stamp()  # before the first @njit (see kernel_cache)

log = logging.getLogger(__name__)

# reason codes shared with the compiled kernels
CLOSURE = 0
NO_CONTACT = 1
NOT_FORCE_CLOSURE = 2
DEGENERATE = 3
HULL_FALLBACK = 4  # the compiled hull gave up; the caller recomputes with qhull
LP_FALLBACK = 5  # the compiled LP gave up; the caller recomputes with HiGHS

REASONS = {
    CLOSURE: "",
    NO_CONTACT: "no contact",
    NOT_FORCE_CLOSURE: "not force closure",
    DEGENERATE: "degenerate",
}

RANK_TOL = 1e-10  # singular-value-like tolerance of the rank test, relative
CLOSURE_TOL = 1e-12  # the LP margin t* must exceed this to call the origin interior
SUPPORT_TOL = 1e-10  # a facet supports the wrench set if no wrench is higher above it
SLIVER_TOL = 1e-8  # a facet simplex thinner than this (relative) is a sliver


@dataclass(frozen=True)
class EpsilonResult:
    """ε and the GWS volume of one grasp.

    Attributes
    ----------
    epsilon : float
        >= 0, distance from the origin to the nearest GWS facet (units of a normalised
        wrench: N, with torques divided by r_max).
    volume : float
        >= 0, 6-volume of the GWS for force-closure grasps, else 0.
    reason : str
        ``""`` when ε > 0, else ``"no contact"``, ``"not force closure"`` or ``"degenerate"``.
    """

    epsilon: float
    volume: float
    reason: str


@njit(cache=True)
def wrench_rank(W, rel_tol):
    """Numerical rank of a wrench matrix: column-pivoted Gram-Schmidt, relative tolerance.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix.
    rel_tol : float
        Tolerance relative to the largest column norm.

    Returns
    -------
    int
        0 to 6.
    """
    m, n = W.shape
    R = W.copy()
    big = 0.0
    for j in range(n):
        s = 0.0
        for i in range(m):
            s += R[i, j] * R[i, j]
        if s > big:
            big = s
    if big == 0.0:
        return 0
    tol2 = rel_tol * rel_tol * big
    rank = 0
    q = np.empty(m)
    for _ in range(m):
        best = 0.0
        bj = -1
        for j in range(n):
            s = 0.0
            for i in range(m):
                s += R[i, j] * R[i, j]
            if s > best:
                best = s
                bj = j
        if best <= tol2:
            break
        nrm = np.sqrt(best)
        for i in range(m):
            q[i] = R[i, bj] / nrm
        for j in range(n):
            d = 0.0
            for i in range(m):
                d += q[i] * R[i, j]
            for i in range(m):
                R[i, j] -= d * q[i]
        rank += 1
    return rank


@njit(cache=True)
def closure_margin(W):
    """LP margin ``t*`` of the origin inside conv(columns of W).

    ``max t  s.t.  Σ λ_i w_i = 0, Σ λ_i = 1, λ_i >= t`` with λ_i = μ_i + t, μ, t >= 0.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix.

    Returns
    -------
    status : int
        An LP status; INFEASIBLE means the origin is outside the hull.
    margin : float
        t*.
    """
    m, n = W.shape
    A = np.zeros((m + 1, n + 1))
    for i in range(m):
        s = 0.0
        for j in range(n):
            A[i, j] = W[i, j]
            s += W[i, j]
        A[i, n] = s
    for j in range(n):
        A[m, j] = 1.0
    A[m, n] = float(n)
    b = np.zeros(m + 1)
    b[m] = 1.0
    c = np.zeros(n + 1)
    c[n] = -1.0
    x = np.empty(n + 1)
    status, obj = simplex_standard(A, b, c, x)
    if status == OPTIMAL:
        return status, -obj
    return status, 0.0


@njit(cache=True)
def epsilon_kernel(W):
    """ε and the GWS volume of a normalised wrench matrix, compiled.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix, torques divided by r_max.

    Returns
    -------
    code, epsilon, volume
        As for :func:`epsilon_volume_kernel` with ``volume=True``.
    """
    return epsilon_volume_kernel(W, True)


@njit(cache=True)
def epsilon_volume_kernel(W, volume):
    """ε of a normalised wrench matrix, and the GWS volume if asked, compiled.

    The volume needs the full hull; ε alone needs only the facets that the best-first
    :func:`~affordgrasp.metrics.hull.nearest_facet_hull` builds (a fraction of them).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix, torques divided by r_max.
    volume : bool
        Compute the volume (else it is NaN for force-closure grasps).

    Returns
    -------
    code : int
        CLOSURE, NO_CONTACT, NOT_FORCE_CLOSURE, DEGENERATE, HULL_FALLBACK or LP_FALLBACK
        (the last two ask the caller to recompute with qhull / HiGHS).
    epsilon : float
        >= 0.
    gws_volume : float
        6-volume of the GWS, >= 0 (NaN for force closure when not asked).
    """
    code, eps, vol, _ = epsilon_volume_store(W, volume, hull_workspace())
    return code, eps, vol


@njit(cache=True)
def epsilon_volume_store(W, volume, store):
    """:func:`epsilon_volume_kernel` building its hull in a reusable facet store.

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix, torques divided by r_max.
    volume : bool
        Compute the volume (else it is NaN for force-closure grasps).
    store : FacetStore
        From :func:`~affordgrasp.metrics.hull.hull_workspace` or a previous call.

    Returns
    -------
    code, epsilon, gws_volume
        As for :func:`epsilon_volume_kernel`.
    store : FacetStore
        The store to pass to the next call (a larger one when it had to grow).
    """
    n = W.shape[1]
    if n == 0:
        return NO_CONTACT, 0.0, 0.0, store
    if wrench_rank(W, RANK_TOL) < 6:
        return DEGENERATE, 0.0, 0.0, store
    status, t = closure_margin(W)
    if status == FAILED:
        return LP_FALLBACK, 0.0, 0.0, store
    if status != OPTIMAL or t <= CLOSURE_TOL:
        return NOT_FORCE_CLOSURE, 0.0, 0.0, store
    P = np.ascontiguousarray(W.T)
    hs, nf, interior, store = build_hull(P, not volume, store)
    if hs != HULL_OK:
        # The LP proved the origin strictly inside a full-rank hull: never "degenerate".
        return HULL_FALLBACK, 0.0, 0.0, store
    f = -1
    for g in range(nf):
        if store.alive[g] and (f < 0 or store.offset[g] < store.offset[f]):
            f = g
    if (
        f < 0
        or not facet_supports(P, store.normal[f], store.offset[f], store.vertices[f])
        or store.offset[f] <= 0.0
    ):
        # A facet that some wrench lies above (a sliver built from nearly coplanar
        # wrenches) cannot give ε: recompute exactly.
        return HULL_FALLBACK, 0.0, 0.0, store
    if not volume:
        return CLOSURE, store.offset[f], np.nan, store
    return CLOSURE, store.offset[f], store_volume(P, store, nf, interior), store


@njit(cache=True)
def facet_supports(P, normal, offset, vertices):
    """Whether the hyperplane ``normal . x = offset`` supports the wrench set ``P``.

    Every wrench beneath it and its facet's six vertices on it, to ``SUPPORT_TOL`` of the data
    scale, and the six vertices spanning a 5-flat (not a zero-volume sliver).

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Wrenches.
    normal : (6,) float64 ndarray
        Unit normal.
    offset : float
        Hyperplane offset.
    vertices : (6,) int64 ndarray
        Row indices into ``P`` of the facet's vertices.

    Returns
    -------
    bool
    """
    scale = 0.0
    for i in range(P.shape[0]):
        for c in range(6):
            scale = max(scale, abs(P[i, c]))
    tol = SUPPORT_TOL * scale
    for i in range(P.shape[0]):
        s = 0.0
        for c in range(6):
            s += normal[c] * P[i, c]
        if s - offset > tol:
            return False
    for r in range(6):
        s = 0.0
        for c in range(6):
            s += normal[c] * P[vertices[r], c]
        if abs(s - offset) > tol:
            return False
    return facet_spread(P, vertices) > SLIVER_TOL * scale


def epsilon_from_wrenches_qhull(W: np.ndarray) -> tuple[int, float, float]:
    """ε and volume of a wrench matrix with scipy's qhull (the slow reference).

    Parameters
    ----------
    W : (6, N) float64 ndarray
        Wrench matrix, torques divided by r_max.

    Returns
    -------
    code, epsilon, volume
        As for :func:`epsilon_kernel`.
    """
    from scipy.spatial import ConvexHull, QhullError

    W = np.asarray(W, dtype=np.float64)
    if W.shape[1] == 0:
        return NO_CONTACT, 0.0, 0.0
    if wrench_rank(np.ascontiguousarray(W), RANK_TOL) < 6:
        return DEGENERATE, 0.0, 0.0
    try:
        hull = ConvexHull(W.T, qhull_options="Qt Qx")
    except QhullError:
        # Full rank, so qhull's trouble is precision on nearly flat input. Joggling moves
        # the points by ~1e-11 of their scale: ε within that, never a made-up "degenerate".
        try:
            hull = ConvexHull(W.T, qhull_options="QJ")
        except QhullError:
            return DEGENERATE, 0.0, 0.0
        log.warning("qhull needed joggled input (QJ) for a nearly flat wrench set")
    # qhull's equations are n . x + offset <= 0 inside: the origin's distance is -offset
    eps = float(np.min(-hull.equations[:, -1]))
    if eps <= 0.0:
        return NOT_FORCE_CLOSURE, 0.0, 0.0
    return CLOSURE, eps, float(hull.volume)


def epsilon(
    contacts, center, r_max: float, *, soft: bool = False, volume: bool = True
) -> EpsilonResult:
    """GraspIt!'s L1 epsilon and the GWS volume of a contact set (conventions: Metrics).

    Parameters
    ----------
    contacts : ContactSet
        Points (k, 3) m, outward normals (k, 3), mu (k,).
    center : (3,) float
        Reference point of the torques (the centre of mass), m.
    r_max : float
        Torque normalisation length (largest COM-to-vertex distance), m.
    soft : bool
        Use soft-finger cones (see :mod:`affordgrasp.metrics.cones`).
    volume : bool
        Also compute the GWS volume (the full hull). False: ε only, from the facets
        nearest the origin (the same ε, often tens of times faster); the volume of a
        force-closure grasp is then NaN.

    Returns
    -------
    EpsilonResult
        ε >= 0, volume >= 0 (NaN when not asked, for force closure), reason.
    """
    points, normals, mu = contact_arrays(contacts)
    center = point3(center, "center")
    r_max = positive_length(r_max, "r_max")
    W = wrench_matrix_kernel(points, normals, mu, center, 1.0 / r_max, bool(soft))
    code, eps, vol = epsilon_volume_kernel(W, bool(volume))
    if code in (HULL_FALLBACK, LP_FALLBACK):
        log.debug("compiled ε path gave up (code %d); using qhull", code)
        code, eps, vol = epsilon_from_wrenches_qhull(W)
        if code == CLOSURE and not volume:
            vol = np.nan
    return EpsilonResult(float(eps), float(vol), REASONS[code])


def gws_volume(contacts, center, r_max: float, *, soft: bool = False) -> float:
    """6-volume of the grasp wrench space whether or not the grasp is force closure.

    This is GraspIt!'s "volume" quality; 0 when the wrench set is flat (affine rank < 6).

    Parameters
    ----------
    contacts, center, r_max, soft
        As for :func:`epsilon`.

    Returns
    -------
    float
        >= 0, in normalised wrench units to the sixth power.
    """
    points, normals, mu = contact_arrays(contacts)
    center = point3(center, "center")
    r_max = positive_length(r_max, "r_max")
    W = contact_wrenches(points, normals, mu, center, torque_scale=1.0 / r_max, soft=soft)
    if W.shape[1] < 7:
        return 0.0
    P = np.ascontiguousarray(W.T)
    status, verts, _, _, interior = convex_hull_6d(P)
    if status == HULL_OK:
        return float(hull_volume(P, verts, interior))
    if status == HULL_DEGENERATE:
        return 0.0
    from scipy.spatial import ConvexHull, QhullError

    try:
        return float(ConvexHull(P, qhull_options="Qt Qx").volume)
    except QhullError:
        return 0.0
