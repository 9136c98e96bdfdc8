"""Convex hull of a wrench set in 6D, compiled (the hull behind ε and the GWS volume).

A quickhull (beneath-beyond with outside sets) specialised to dimension 6 and to the tens
to hundreds of points of a grasp wrench space. Why not scipy/qhull: qhull costs 1-20 ms
per hull here, most of it in facet merging that precision-robust general-purpose hulls
need; this kernel builds the same simplicial facets in a fraction of that and is called
from compiled code without Python overhead.

Precision handling (the reason qhull merges facets): a point counts as *beyond* a facet
only when it is more than ``tol = 1e-12 * max|coordinate|`` above the facet's hyperplane,
so points that are coplanar with a facet (the eight edges of one friction cone lie on a
common 2-flat, symmetric grasps have many coplanar wrenches) are never added as thin
slivers. Facet orientation is fixed by an interior point (the centroid of the initial
simplex), not by adjacency, so round-off cannot flip a facet. Nearly coplanar wrenches
(equal normals with 1e-10 of noise, a palm flat on a round foot: dozens of contacts a
hair off one plane) put an apex barely above some facets: a facet the apex is at most
``COPLANAR_TOL`` (relative) above is treated as coplanar with it, not visible, so the new
facet on that ridge makes a fold of at most that height instead of a sliver whose
hyperplane is round-off; an apex that is only that little above every facet is dropped.
A hull built with such a rule is verified at the end (every point beneath every facet to
``VERIFY_TOL``, and the same volume from two interior points: a surface folded over itself
by round-off slivers passes the first test but not the second), and ε's own facet test
stays exact (see :mod:`affordgrasp.metrics.epsilon`). Combinatorial consistency (each ridge
in exactly two facets) is maintained and checked; any violation returns ``HULL_FAILED`` and
the caller falls back to qhull. The result has been checked against qhull (options ``Qt Qx``) on
random, symmetric and nearly coplanar wrench sets: ``tests/metrics/test_hull.py``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..runtime.kernel_cache import install_package_stamp

install_package_stamp()  # before the first @njit (see kernel_cache)

HULL_OK = 0
HULL_DEGENERATE = 1  # fewer than 7 affinely independent points: no 6D hull
HULL_FAILED = 2  # a numerical or topological inconsistency: use qhull instead

DIM = 6
HULL_TOL = 1e-12  # beyond-test tolerance, relative to the largest |coordinate|
COPLANAR_TOL = 1e-9  # an apex at most this far above a facet (relative) is coplanar with it
VERIFY_TOL = 1e-8  # after a coplanar apex: every point within this (relative) beneath every facet
VOLUME_CHECK_TOL = 1e-9  # ... and its volume the same from two interior points (relative)
RANK_TOL = 1e-10  # affine independence tolerance of the initial simplex, relative


@njit(cache=True)
def _hyperplane(P, verts, q0, out_n, scratch, perm, y):
    """Unit normal ``out_n`` and offset d of the hyperplane through ``P[verts]``.

    Oriented so that the interior point ``q0`` is beneath (``n . q0 < d``). Returns
    ``(d, ok)``; ok is False for an (affinely) degenerate vertex set.
    """
    M = scratch
    p0 = verts[0]
    for r in range(DIM - 1):
        vr = verts[r + 1]
        for c in range(DIM):
            M[r, c] = P[vr, c] - P[p0, c]
    for c in range(DIM):
        perm[c] = c
    scale = 0.0
    for r in range(DIM - 1):
        for c in range(DIM):
            v = abs(M[r, c])
            if v > scale:
                scale = v
    if scale == 0.0:
        return 0.0, False
    # Gaussian elimination with full pivoting on the 5 x 6 difference matrix; the
    # column left without a pivot carries the free component of the null vector.
    for r in range(DIM - 1):
        best = 0.0
        bi = r
        bj = r
        for i in range(r, DIM - 1):
            for j in range(r, DIM):
                v = abs(M[i, j])
                if v > best:
                    best = v
                    bi = i
                    bj = j
        if best <= 1e-14 * scale:
            return 0.0, False
        if bi != r:
            for j in range(DIM):
                t = M[r, j]
                M[r, j] = M[bi, j]
                M[bi, j] = t
        if bj != r:
            for i in range(DIM - 1):
                t = M[i, r]
                M[i, r] = M[i, bj]
                M[i, bj] = t
            t = perm[r]
            perm[r] = perm[bj]
            perm[bj] = t
        piv = M[r, r]
        for i in range(r + 1, DIM - 1):
            f = M[i, r] / piv
            if f != 0.0:
                for j in range(r, DIM):
                    M[i, j] -= f * M[r, j]
    y[DIM - 1] = 1.0
    for r in range(DIM - 2, -1, -1):
        acc = M[r, DIM - 1]
        for c in range(r + 1, DIM - 1):
            acc += M[r, c] * y[c]
        y[r] = -acc / M[r, r]
    norm = 0.0
    for c in range(DIM):
        norm += y[c] * y[c]
    norm = np.sqrt(norm)
    for c in range(DIM):
        out_n[perm[c]] = y[c] / norm
    d = 0.0
    for r in range(DIM):
        v = verts[r]
        for c in range(DIM):
            d += out_n[c] * P[v, c]
    d /= DIM
    dq = 0.0
    for c in range(DIM):
        dq += out_n[c] * q0[c]
    if dq > d:
        for c in range(DIM):
            out_n[c] = -out_n[c]
        d = -d
    return d, True


@njit(cache=True, inline="always")
def _pencil_plane(normal, offset, v, g, dist_v, dist_g, P, vertices, nf, out_n, chk_tol):
    """Hyperplane through the ridge shared by facets v, g and the apex p (dist_v > 0 above
    v, dist_g <= tol above g): ``-dist_g * (n_v, d_v) + dist_v * (n_g, d_g)``, normalised.

    Takes the facet store's ``normal``, ``offset`` and ``vertices`` arrays, not the store
    (one call per new facet: passing ten arrays costs ten reference counts each way).
    The interior point stays beneath (both weights are >= 0 up to tol). Returns
    ``(d, ok)``; ok is False when the result does not pass through ``P[vertices[nf]]``.
    """
    a = -dist_g
    b = dist_v
    norm = 0.0
    for c in range(DIM):
        x = a * normal[v, c] + b * normal[g, c]
        out_n[c] = x
        norm += x * x
    if norm <= 0.0:
        return 0.0, False
    norm = np.sqrt(norm)
    d = (a * offset[v] + b * offset[g]) / norm
    for c in range(DIM):
        out_n[c] /= norm
    for r in range(DIM):
        x = vertices[nf, r]
        s = 0.0
        for c in range(DIM):
            s += out_n[c] * P[x, c]
        if abs(s - d) > chk_tol:
            return 0.0, False
    return d, True


@njit(cache=True)
def _remove_components(r, E, step):
    """r -= its components along the orthonormal rows E[:step] (one Gram-Schmidt pass)."""
    for e in range(step):
        dot = 0.0
        for c in range(DIM):
            dot += r[c] * E[e, c]
        for c in range(DIM):
            r[c] -= dot * E[e, c]


@njit(cache=True)
def _initial_simplex(P, out, rank_tol):
    """Greedy large-volume simplex of DIM + 1 points; False when affinely degenerate."""
    N = P.shape[0]
    centroid = np.zeros(DIM)
    for i in range(N):
        for c in range(DIM):
            centroid[c] += P[i, c]
    for c in range(DIM):
        centroid[c] /= N
    best = -1.0
    i0 = 0
    for i in range(N):
        s = 0.0
        for c in range(DIM):
            d = P[i, c] - centroid[c]
            s += d * d
        if s > best:
            best = s
            i0 = i
    out[0] = i0
    E = np.zeros((DIM, DIM))
    r = np.empty(DIM)
    for step in range(DIM):
        best = -1.0
        bi = -1
        for i in range(N):
            for c in range(DIM):
                r[c] = P[i, c] - P[i0, c]
            _remove_components(r, E, step)
            s = 0.0
            for c in range(DIM):
                s += r[c] * r[c]
            if s > best:
                best = s
                bi = i
        if best <= rank_tol * rank_tol:
            return False
        for c in range(DIM):
            r[c] = P[bi, c] - P[i0, c]
        # two Gram-Schmidt passes keep the basis orthogonal to round-off
        for _ in range(2):
            _remove_components(r, E, step)
        s = 0.0
        for c in range(DIM):
            s += r[c] * r[c]
        s = np.sqrt(s)
        for c in range(DIM):
            E[step, c] = r[c] / s
        out[step + 1] = bi
    return True


class FacetStore(NamedTuple):
    """Every facet the hull has built, alive or retired, one row each (the one facet store).

    Attributes
    ----------
    vertices : (cap, 6) int64 ndarray
        Point indices.
    neighbours : (cap, 6) int64 ndarray
        The facet across the ridge opposite each vertex.
    normal : (cap, 6) float64 ndarray
        Outward unit normal.
    offset : (cap,) float64 ndarray
        Points beneath satisfy ``normal @ p <= offset``.
    alive : (cap,) bool ndarray
    outside : (cap,) int64 ndarray
        Head of the facet's outside-point list (-1: none).
    far_point, far_dist : (cap,) ndarray
        Its farthest outside point and that point's distance.
    mark : (cap,) ndarray
        Visit stamp of the visibility search (sign: visible + / not -).
    apex_dist : (cap,) float64 ndarray
        Height of the current apex above each visited facet.
    """

    vertices: np.ndarray
    neighbours: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    alive: np.ndarray
    outside: np.ndarray
    far_point: np.ndarray
    far_dist: np.ndarray
    mark: np.ndarray
    apex_dist: np.ndarray


@njit(cache=True)
def _facet_store(cap):
    return FacetStore(
        np.empty((cap, DIM), dtype=np.int64),
        np.empty((cap, DIM), dtype=np.int64),
        np.empty((cap, DIM)),
        np.zeros(cap),
        np.zeros(cap, dtype=np.bool_),
        np.full(cap, -1, dtype=np.int64),
        np.full(cap, -1, dtype=np.int64),
        np.zeros(cap),
        np.zeros(cap, dtype=np.int64),
        np.zeros(cap),
    )


@njit(cache=True)
def _grown(F, n, cap):
    """A store of capacity ``cap`` holding the first ``n`` facets of ``F``."""
    G = _facet_store(cap)
    G.vertices[:n] = F.vertices[:n]
    G.neighbours[:n] = F.neighbours[:n]
    G.normal[:n] = F.normal[:n]
    G.offset[:n] = F.offset[:n]
    G.alive[:n] = F.alive[:n]
    G.outside[:n] = F.outside[:n]
    G.far_point[:n] = F.far_point[:n]
    G.far_dist[:n] = F.far_dist[:n]
    G.mark[:n] = F.mark[:n]
    G.apex_dist[:n] = F.apex_dist[:n]
    return G


@njit(cache=True)
def _grow_1(a, cap, fill):
    b = np.empty(cap, dtype=a.dtype)
    b[: a.shape[0]] = a
    b[a.shape[0] :] = fill
    return b


@njit(cache=True)
def _dist(F, f, P, p):
    s = 0.0
    for c in range(DIM):
        s += F.normal[f, c] * P[p, c]
    return s - F.offset[f]


@njit(cache=True)
def _dist_nd(normal, offset, f, P, p):
    s = 0.0
    for c in range(DIM):
        s += normal[f, c] * P[p, c]
    return s - offset[f]


@njit(cache=True, inline="always")
def _det_lu(A, n):
    """Determinant of the leading n x n block of A (Gaussian elimination, partial pivoting).

    A is overwritten. Inlined into :func:`_det5` and :func:`_det6`, where ``n`` is a
    constant.
    """
    det = 1.0
    for r in range(n):
        bi = r
        best = abs(A[r, r])
        for i in range(r + 1, n):
            if abs(A[i, r]) > best:
                best = abs(A[i, r])
                bi = i
        if best == 0.0:
            return 0.0
        if bi != r:
            for j in range(n):
                t = A[r, j]
                A[r, j] = A[bi, j]
                A[bi, j] = t
            det = -det
        piv = A[r, r]
        det *= piv
        for i in range(r + 1, n):
            f = A[i, r] / piv
            for j in range(r + 1, n):
                A[i, j] -= f * A[r, j]
    return det


@njit(cache=True)
def _det6(A):
    """Determinant of a 6 x 6 matrix (Gaussian elimination, partial pivoting); A is overwritten."""
    return _det_lu(A, DIM)


@njit(cache=True)
def _det5(A):
    """Determinant of a 5 x 5 matrix (Gaussian elimination, partial pivoting); A is overwritten."""
    return _det_lu(A, DIM - 1)


@njit(cache=True)
def facet_spread(P, vertices):
    """Smallest Gram-Schmidt residual of the five edge vectors of a facet simplex.

    Its "thinness": 0 when the six vertices lie in a 4-flat.

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Wrenches.
    vertices : (6,) int64 ndarray
        Row indices into ``P`` of the facet's vertices.

    Returns
    -------
    float
    """
    E = np.empty((5, 6))
    for r in range(5):
        for c in range(6):
            E[r, c] = P[vertices[r + 1], c] - P[vertices[0], c]
    smallest = np.inf
    for r in range(5):
        for _ in range(2):
            for q in range(r):
                d = 0.0
                for c in range(6):
                    d += E[r, c] * E[q, c]
                for c in range(6):
                    E[r, c] -= d * E[q, c]
        nrm = 0.0
        for c in range(6):
            nrm += E[r, c] * E[r, c]
        nrm = np.sqrt(nrm)
        smallest = min(smallest, nrm)
        if nrm == 0.0:
            return 0.0
        for c in range(6):
            E[r, c] /= nrm
    return smallest


@njit(cache=True)
def _visible(F, f0, p, P, thr, stamp, vis, hv, hk, hg):
    """Facets more than ``thr`` below apex ``p``, breadth-first from ``f0``, and the horizon.

    Marks visited facets (``stamp``: visible, ``-stamp``: not) and stores the apex's height
    above each in ``F.apex_dist``. Returns ``(nvis, nh)``: the visible facets ``vis[:nvis]``
    and the horizon ridges (visible facet ``hv``, the vertex slot opposite the ridge ``hk``,
    the neighbour across it ``hg``, ``[:nh]``). The arrays are never grown here (an array
    reassigned inside the loop costs reference counts on every pass): ``nvis = -1`` says
    they were too short; the caller grows them and searches again with a fresh stamp.
    """
    # the store's fields as locals: the loop touches them tens of thousands of times
    neighbours = F.neighbours
    mark = F.mark
    apex_dist = F.apex_dist
    normal = F.normal
    offset = F.offset
    nvis_cap = vis.shape[0]
    nh_cap = hv.shape[0]
    nvis = 1
    vis[0] = f0
    mark[f0] = stamp
    nh = 0
    i = 0
    while i < nvis:
        v = vis[i]
        i += 1
        for k in range(DIM):
            g = neighbours[v, k]
            if mark[g] == stamp:
                continue
            if mark[g] != -stamp:
                dg = _dist_nd(normal, offset, g, P, p)
                apex_dist[g] = dg
                if dg > thr:
                    mark[g] = stamp
                    if nvis == nvis_cap:
                        return -1, nh
                    vis[nvis] = g
                    nvis += 1
                    continue
                mark[g] = -stamp
            if nh == nh_cap:
                return -1, nh
            hv[nh] = v
            hk[nh] = k
            hg[nh] = g
            nh += 1
    return nvis, nh


@njit(cache=True)
def _unlink(F, nxt, f, p, P):
    """Remove point ``p`` from facet ``f``'s outside set and refresh its farthest point."""
    prev = -1
    pt = F.outside[f]
    F.far_point[f] = -1
    F.far_dist[f] = 0.0
    while pt >= 0:
        pn = nxt[pt]
        if pt == p:
            if prev < 0:
                F.outside[f] = pn
            else:
                nxt[prev] = pn
        else:
            dist = _dist(F, f, P, pt)
            if F.far_point[f] < 0 or dist > F.far_dist[f]:
                F.far_dist[f] = dist
                F.far_point[f] = pt
            prev = pt
        pt = pn


@njit(cache=True)
def _build(P, nearest_only, F):
    """Build the hull of ``P`` in the facet store ``F`` (reused, grown as needed).

    :func:`convex_hull_6d` (``nearest_only`` False) or :func:`nearest_facet_hull` (True).
    Returns ``(status, nF, interior, F)``: the facets are the live rows ``f < nF`` of the
    returned store (it is a new one when ``F`` had to grow).
    """
    N = P.shape[0]
    scale = 0.0
    for i in range(N):
        for c in range(DIM):
            v = abs(P[i, c])
            if v > scale:
                scale = v
    q0 = np.zeros(DIM)
    # Fewer than DIM + 1 points or all at the origin: no 6-D hull (HULL_DEGENERATE). 32768
    # points or more: HULL_FAILED, so the caller uses qhull. Nothing below needs that cap
    # any more (it bounded a packed ridge key that the adjacency no longer uses); it stays
    # as a size limit of this kernel, far above the hundreds of wrenches of a grasp.
    if N < DIM + 1 or scale == 0.0 or N >= 32768:
        status = HULL_DEGENERATE if N < DIM + 1 or scale == 0.0 else HULL_FAILED
        return status, 0, q0, F
    tol = HULL_TOL * scale
    chk_tol = 1e-14 * scale
    vis_tol = COPLANAR_TOL * scale
    verify_tol = VERIFY_TOL * scale
    simplex = np.empty(DIM + 1, dtype=np.int64)
    if not _initial_simplex(P, simplex, RANK_TOL * scale):
        return HULL_DEGENERATE, 0, q0, F
    for i in range(DIM + 1):
        for c in range(DIM):
            q0[c] += P[simplex[i], c]
    for c in range(DIM):
        q0[c] /= DIM + 1

    cap = F.offset.shape[0]
    if cap < 2 * (DIM + 1):
        cap = 512
        F = _facet_store(cap)
    F_vertices = F.vertices
    F_neighbours = F.neighbours
    F_normal = F.normal
    F_offset = F.offset
    F_alive = F.alive
    F_outside = F.outside
    F_far_point = F.far_point
    F_far_dist = F.far_dist
    F_mark = F.mark
    F_apex_dist = F.apex_dist
    nxt = np.full(N, -1, dtype=np.int64)
    scratch = np.empty((DIM - 1, DIM))
    nvec = np.empty(DIM)
    perm = np.empty(DIM, dtype=np.int64)
    yvec = np.empty(DIM)

    for i in range(DIM + 1):
        s = 0
        for j in range(DIM + 1):
            if j != i:
                F_vertices[i, s] = simplex[j]
                F_neighbours[i, s] = j
                s += 1
        d, ok = _hyperplane(P, F_vertices[i], q0, nvec, scratch, perm, yvec)
        if not ok:
            return HULL_FAILED, 0, q0, F
        F_normal[i] = nvec
        F_offset[i] = d
        F_alive[i] = True
        F_outside[i] = -1
        F_far_point[i] = -1
        F_far_dist[i] = 0.0
        F_mark[i] = 0
    nF = DIM + 1

    in_simplex = np.zeros(N, dtype=np.bool_)
    for i in range(DIM + 1):
        in_simplex[simplex[i]] = True
    stack = np.empty(64, dtype=np.int64)
    nstack = 0
    for p in range(N):
        if in_simplex[p]:
            continue
        for f in range(nF):
            dist = _dist_nd(F_normal, F_offset, f, P, p)
            if dist > tol:
                if F_outside[f] < 0:
                    stack[nstack] = f  # at most DIM + 1 of them: no growth
                    nstack += 1
                nxt[p] = F_outside[f]
                F_outside[f] = p
                if dist > F_far_dist[f]:
                    F_far_dist[f] = dist
                    F_far_point[f] = p
                break

    vis = np.empty(64, dtype=np.int64)
    hv = np.empty(64, dtype=np.int64)
    hk = np.empty(64, dtype=np.int64)
    hg = np.empty(64, dtype=np.int64)
    stamp = 0
    thick = False  # a nearly coplanar apex was met: verify the finished hull
    free = np.empty(64, dtype=np.int64)  # retired facet slots, reused by new facets
    nfree = 0
    newf = np.empty(64, dtype=np.int64)
    rounds = 0
    while nstack > 0 or nearest_only:
        rounds += 1
        if nearest_only and rounds > N:
            # every round adds a point as an apex: more rounds than points is an
            # inconsistent partial hull (e.g. a pinched horizon): give up to qhull
            return HULL_FAILED, nF, q0, F
        if nearest_only:
            # Best first: the facet nearest the origin. If no point is above it, it is a
            # facet of the full hull, and no facet is nearer: the partial hull lies inside
            # the full one, so the origin's distance to the full boundary is at least its
            # distance to the partial boundary, the nearest facet's offset.
            fm = -1
            for f in range(nF):
                if F_alive[f] and (fm < 0 or F_offset[f] < F_offset[fm]):
                    fm = f
            p = -1
            far = tol
            for q in range(N):
                dq = _dist_nd(F_normal, F_offset, fm, P, q)
                if dq > far:
                    far = dq
                    p = q
            if p < 0:
                break
            f0 = fm
            F_far_dist[f0] = far
        else:
            # the farthest outside point of all first: fewer facets built and retired
            # (stale entries: retired slots, emptied outside sets, are dropped on the way)
            bi = -1
            j = 0
            while j < nstack:
                fj = stack[j]
                if not F_alive[fj] or F_outside[fj] < 0:
                    nstack -= 1
                    stack[j] = stack[nstack]
                    continue
                if bi < 0 or F_far_dist[fj] > F_far_dist[stack[bi]]:
                    bi = j
                j += 1
            if bi < 0:
                break
            f0 = stack[bi]
            nstack -= 1
            stack[bi] = stack[nstack]
            p = F_far_point[f0]
        if F_far_dist[f0] <= vis_tol:
            # p is barely above f0: start from the facet it is farthest above, if that one
            # is clearly below p; otherwise p is coplanar with the hull (within vis_tol)
            # and is dropped, to be checked against the finished hull.
            thick = True
            stamp += 1
            F_apex_dist[f0] = F_far_dist[f0]
            nvis, nh = _visible(F, f0, p, P, tol, stamp, vis, hv, hk, hg)
            while nvis < 0:  # the search ran out of room: grow, search again
                vis = np.empty(2 * vis.shape[0], dtype=np.int64)
                hv = np.empty(2 * hv.shape[0], dtype=np.int64)
                hk = np.empty(hv.shape[0], dtype=np.int64)
                hg = np.empty(hv.shape[0], dtype=np.int64)
                stamp += 1
                nvis, nh = _visible(F, f0, p, P, tol, stamp, vis, hv, hk, hg)
            best = f0
            for i in range(nvis):
                if F_apex_dist[vis[i]] > F_apex_dist[best]:
                    best = vis[i]
            _unlink(F, nxt, f0, p, P)
            if F_outside[f0] >= 0:
                if nstack == stack.shape[0]:
                    stack = _grow_1(stack, 2 * nstack, -1)
                stack[nstack] = f0
                nstack += 1
            if F_apex_dist[best] <= vis_tol:
                if nearest_only:  # the same apex would come back
                    return HULL_FAILED, nF, q0, F
                continue
            f0 = best
            F_far_dist[f0] = F_apex_dist[best]
        stamp += 1
        # Visible facets: breadth-first from f0 over the facet adjacency. A facet that p is
        # barely above (<= vis_tol: nearly coplanar wrenches, e.g. equal normals with 1e-10
        # of noise) is not visible: the new facet on that ridge makes a fold of at most
        # vis_tol instead of a sliver whose hyperplane is round-off.
        F_apex_dist[f0] = F_far_dist[f0]
        nvis, nh = _visible(F, f0, p, P, vis_tol, stamp, vis, hv, hk, hg)
        while nvis < 0:
            vis = np.empty(2 * vis.shape[0], dtype=np.int64)
            hv = np.empty(2 * hv.shape[0], dtype=np.int64)
            hk = np.empty(hv.shape[0], dtype=np.int64)
            hg = np.empty(hv.shape[0], dtype=np.int64)
            stamp += 1
            nvis, nh = _visible(F, f0, p, P, vis_tol, stamp, vis, hv, hk, hg)
        for h in range(nh):
            if F_apex_dist[hg[h]] > tol:
                thick = True
                break
        if nh > newf.shape[0]:
            newf = np.empty(2 * nh, dtype=np.int64)
        # retired slots first, then fresh rows; the store grows here, before the loop (an
        # array reassigned inside a loop costs reference counts on every pass)
        if nF + nh - nfree > cap:
            cap = max(2 * cap, nF + nh - nfree + 64)
            F = _grown(F, nF, cap)
            F_vertices = F.vertices
            F_neighbours = F.neighbours
            F_normal = F.normal
            F_offset = F.offset
            F_alive = F.alive
            F_outside = F.outside
            F_far_point = F.far_point
            F_far_dist = F.far_dist
            F_mark = F.mark
            F_apex_dist = F.apex_dist
        for h in range(nh):
            if nfree > 0:
                nfree -= 1
                newf[h] = free[nfree]
            else:
                newf[h] = nF
                nF += 1
        # cone of new facets from p over the horizon ridges
        for h in range(nh):
            v = hv[h]
            k = hk[h]
            g = hg[h]
            nf = newf[h]
            for c in range(DIM):
                F_vertices[nf, c] = F_vertices[v, c]
                F_neighbours[nf, c] = -1
            F_vertices[nf, k] = p
            F_neighbours[nf, k] = g
            found = False
            for kk in range(DIM):
                if F_neighbours[g, kk] == v:
                    F_neighbours[g, kk] = nf
                    found = True
                    break
            if not found:
                return HULL_FAILED, nF, q0, F
            F_neighbours[v, k] = -2 - nf  # v retires: its horizon slot names nf
            # The new hyperplane contains the ridge, so it lies in the pencil of the two
            # hyperplanes through that ridge (v's and g's): the combination through p is
            # exact in exact arithmetic and costs O(DIM). Near-coplanar v and g make it
            # ill-conditioned, so it is accepted only if it passes through all six
            # vertices to 1e-14 of the data scale; otherwise the plane is solved afresh.
            d, ok = _pencil_plane(
                F_normal,
                F_offset,
                v,
                g,
                F_apex_dist[v],
                F_apex_dist[g],
                P,
                F_vertices,
                nf,
                nvec,
                chk_tol,
            )
            if ok:
                # p barely above g (a coplanar neighbour) makes one pencil weight positive:
                # keep the interior point beneath
                s = -d
                for c in range(DIM):
                    s += nvec[c] * q0[c]
                ok = s < 0.0
            if not ok:
                d, ok = _hyperplane(P, F_vertices[nf], q0, nvec, scratch, perm, yvec)
                if not ok:
                    return HULL_FAILED, nF, q0, F
            for c in range(DIM):
                F_normal[nf, c] = nvec[c]
            F_offset[nf] = d
            F_alive[nf] = True
            F_outside[nf] = -1
            F_far_point[nf] = -1
            F_far_dist[nf] = 0.0
            F_mark[nf] = 0
        # neighbours among the new facets. The new facet on horizon ridge (v, k) and the one
        # across its ridge opposite slot j share p and the 4-face Q = v's vertices but those
        # of slots j and k. The facets around Q form a cycle (the link of a 3-face of a
        # simplicial 5-sphere); turning about Q from v through visible facets, away from g,
        # reaches the other horizon ridge that holds Q, whose new facet is the neighbour.
        npaired = 0
        for h in range(nh):
            nf = newf[h]
            v = hv[h]
            k = hk[h]
            for j in range(DIM):
                if j == k or F_neighbours[nf, j] >= 0:
                    continue
                c = v  # a visible facet holding Q
                se = j  # cross c's ridge opposite its vertex in slot se ...
                so = k  # ... keeping its vertex in slot so
                steps = 0
                while True:
                    x = F_neighbours[c, se]
                    if x <= -2:  # a horizon ridge: x names its new facet
                        break
                    if F_mark[x] != stamp or steps > nvis:
                        return HULL_FAILED, nF, q0, F
                    t = -1
                    s2 = -1
                    o = F_vertices[c, so]
                    for r in range(DIM):
                        if F_neighbours[x, r] == c:
                            t = r
                        if F_vertices[x, r] == o:
                            s2 = r
                    if t < 0 or s2 < 0:
                        return HULL_FAILED, nF, q0, F
                    c = x
                    se = s2
                    so = t
                    steps += 1
                nf2 = -2 - x
                if nf2 == nf or F_neighbours[nf2, so] != -1:
                    return HULL_FAILED, nF, q0, F
                F_neighbours[nf, j] = nf2
                F_neighbours[nf2, so] = nf
                npaired += 1
        if 2 * npaired != nh * (DIM - 1):
            return HULL_FAILED, nF, q0, F
        # retire the visible facets and hand their outside points to the new facets
        for i in range(nvis):
            F_alive[vis[i]] = False
        for i in range(nvis):
            v = vis[i]
            pt = F_outside[v]
            F_outside[v] = -1
            while pt >= 0:
                pn = nxt[pt]
                if pt != p:
                    for h in range(nh):
                        nf = newf[h]
                        dist = _dist_nd(F_normal, F_offset, nf, P, pt)
                        if dist > tol:
                            nxt[pt] = F_outside[nf]
                            F_outside[nf] = pt
                            if dist > F_far_dist[nf]:
                                F_far_dist[nf] = dist
                                F_far_point[nf] = pt
                            break
                pt = pn
        if nstack + nh > stack.shape[0]:
            stack = _grow_1(stack, 2 * (nstack + nh), -1)
        for h in range(nh):
            nf = newf[h]
            if F_outside[nf] >= 0:
                stack[nstack] = nf
                nstack += 1
        if nfree + nvis > free.shape[0]:
            free = _grow_1(free, 2 * (nfree + nvis), -1)
        for i in range(nvis):
            free[nfree] = vis[i]
            nfree += 1

    if thick and not nearest_only:
        # Coplanar apexes were met (folds of <= vis_tol, dropped points): the surface is the
        # hull only if every point is beneath every facet, to verify_tol, and the volume is
        # the same from two interior points. The boundary of a convex body gives the same
        # sum of |cone volumes| from any interior point; a surface folded over itself
        # (slivers whose hyperplanes are round-off) does not. Checked from the initial
        # simplex's centroid and from the centroid of all points.
        for f in range(nF):
            if F_alive[f]:
                for p in range(N):
                    if _dist_nd(F_normal, F_offset, f, P, p) > verify_tol:
                        return HULL_FAILED, nF, q0, F
        centroid = np.zeros(DIM)
        for i in range(N):
            for c in range(DIM):
                centroid[c] += P[i, c] / N
        v1 = _store_volume_det6(P, F, nF, q0)
        v2 = _store_volume_det6(P, F, nF, centroid)
        if abs(v1 - v2) > VOLUME_CHECK_TOL * v1:
            return HULL_FAILED, nF, q0, F
    return HULL_OK, nF, q0, F


@njit(cache=True)
def _hull(P, nearest_only):
    """The hull's facets as arrays: ``(status, vertices, normals, offsets, interior)``."""
    status, nF, q0, F = _build(P, nearest_only, _facet_store(512))
    if status != HULL_OK:
        return status, np.zeros((0, DIM), dtype=np.int64), np.zeros((0, DIM)), np.zeros(0), q0
    count = 0
    for f in range(nF):
        if F.alive[f]:
            count += 1
    out_v = np.empty((count, DIM), dtype=np.int64)
    out_n = np.empty((count, DIM))
    out_d = np.empty(count)
    j = 0
    for f in range(nF):
        if F.alive[f]:
            out_v[j] = F.vertices[f]
            out_n[j] = F.normal[f]
            out_d[j] = F.offset[f]
            j += 1
    return HULL_OK, out_v, out_n, out_d, q0


@njit(cache=True)
def hull_workspace():
    """An empty facet store for :func:`build_hull` to reuse from one hull to the next.

    Returns
    -------
    FacetStore
        Room for 512 facets; :func:`build_hull` grows it when a hull needs more.
    """
    return _facet_store(512)


@njit(cache=True)
def build_hull(P, nearest_only, store):
    """The hull of ``P`` built in a reusable facet store (no per-hull allocation).

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Points.
    nearest_only : bool
        Stop when the facet nearest the origin is final (as :func:`nearest_facet_hull`).
    store : FacetStore
        From :func:`hull_workspace` or a previous call.

    Returns
    -------
    status : int
        HULL_OK, HULL_DEGENERATE or HULL_FAILED.
    n : int
        The facets are the rows ``f < n`` of the returned store with ``store.alive[f]``.
    interior : (6,) float64 ndarray
        A point inside the hull.
    store : FacetStore
        The store holding the facets (a larger one when ``store`` had to grow): pass it to
        the next call.
    """
    return _build(P, nearest_only, store)


@njit(cache=True)
def store_volume(P, F, n, interior):
    """6-volume of the hull whose facets are the live rows ``f < n`` of the store ``F``.

    Each facet's cone from the interior point has volume ``|c| h / 6!``: ``h`` the
    point's distance to the facet's hyperplane, ``c`` the generalised cross product of the
    facet's five edge vectors, which is parallel to the facet's unit normal ``n``, so
    ``|c| = |c_a| / |n_a|`` for the normal's largest component ``a``, and ``c_a`` is a 5 x 5
    determinant (the edges without coordinate ``a``): the same volume as
    :func:`hull_volume`'s 6 x 6 determinants, at about half their cost.

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Points.
    F : FacetStore
        As returned by :func:`build_hull`.
    n : int
        Rows in use.
    interior : (6,) float64 ndarray
        A point inside the hull.

    Returns
    -------
    float
    """
    A = np.empty((DIM - 1, DIM - 1))
    vertices = F.vertices
    normal = F.normal
    offset = F.offset
    alive = F.alive
    vol = 0.0
    for f in range(n):
        if not alive[f]:
            continue
        a = 0
        big = abs(normal[f, 0])
        h = offset[f] - normal[f, 0] * interior[0]
        for c in range(1, DIM):
            h -= normal[f, c] * interior[c]
            if abs(normal[f, c]) > big:
                big = abs(normal[f, c])
                a = c
        v0 = vertices[f, 0]
        for r in range(DIM - 1):
            v = vertices[f, r + 1]
            j = 0
            for c in range(DIM):
                if c != a:
                    A[r, j] = P[v, c] - P[v0, c]
                    j += 1
        vol += abs(_det5(A) * h) / big
    return vol / 720.0  # 6!


@njit(cache=True)
def _store_volume_det6(P, F, n, interior):
    """:func:`store_volume` from the 6 x 6 determinants (no use of the facet normals)."""
    A = np.empty((DIM, DIM))
    vertices = F.vertices
    alive = F.alive
    vol = 0.0
    for f in range(n):
        if not alive[f]:
            continue
        for r in range(DIM):
            v = vertices[f, r]
            for c in range(DIM):
                A[r, c] = P[v, c] - interior[c]
        vol += abs(_det6(A))
    return vol / 720.0  # 6!


@njit(cache=True)
def convex_hull_6d(P):
    """Facets of the convex hull of a 6-D point set.

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Points.

    Returns
    -------
    status : int
        HULL_OK, HULL_DEGENERATE (affine rank < 6) or HULL_FAILED.
    vertices : (F, 6) int64 ndarray
    normals : (F, 6) float64 ndarray
        Outward unit normals: every point satisfies ``normals @ p <= offsets + tol``.
    offsets : (F,) float64 ndarray
    interior : (6,) float64 ndarray
        A point inside the hull.
    """
    return _hull(P, False)


@njit(cache=True)
def nearest_facet_hull(P):
    """The hull grown only until its facet nearest the origin is final (ε without volume).

    Best first: the facet with the smallest offset takes the point farthest above it, until
    no point is above it; that facet is then a facet of the full hull with the smallest
    offset of all (the partial hull lies inside the full one). Exact like
    :func:`convex_hull_6d`, with a fraction of the facets when the origin is inside.

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Points.

    Returns
    -------
    status, vertices, normals, offsets, interior
        As for :func:`convex_hull_6d`, but the facets are those of a partial hull: the one
        with the smallest offset is a facet of the full hull, and no full-hull facet has a
        smaller offset (when that offset is > 0, it is ε). Not for the volume.
    """
    return _hull(P, True)


@njit(cache=True)
def hull_volume(P, vertices, interior):
    """6-volume of a hull given by simplicial facets and an interior point.

    Parameters
    ----------
    P : (N, 6) float64 ndarray
        Points.
    vertices : (F, 6) int64 ndarray
        Facets as row indices into ``P``.
    interior : (6,) float64 ndarray
        A point inside the hull.

    Returns
    -------
    float
    """
    A = np.empty((DIM, DIM))
    vol = 0.0
    for f in range(vertices.shape[0]):
        for r in range(DIM):
            v = vertices[f, r]
            for c in range(DIM):
                A[r, c] = P[v, c] - interior[c]
        vol += abs(_det6(A))
    return vol / 720.0  # 6!
