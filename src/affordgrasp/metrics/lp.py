"""Linear programs of the metrics, solved to optimality (conventions: Metrics).

Every LP of the metric vector is small (6 to ~20 rows, tens to a few hundred columns) and
is written in standard form::

    minimise  c @ x   subject to   A @ x = b,  x >= 0.

Two interchangeable solvers answer it:

* ``"simplex"`` (default): a dense two-phase tableau simplex compiled with numba. Rows are
  scaled, entering columns follow Dantzig's rule with a switch to Bland's rule after a run
  of degenerate pivots (no cycling), leaving rows follow a Harris-style ratio test (largest
  pivot among the near-ties). The final basis is *re-solved* with an LU factorisation and
  checked for primal and dual feasibility, so the returned optimum is accurate to ~1e-12
  and not a product of accumulated tableau round-off. A problem the check does not accept
  is handed to HiGHS (logged), so the answer is always a certified optimum.
* ``"highs"``: HiGHS through highspy, the reference. ``tests/metrics/test_lp.py`` checks
  that both agree to 1e-9 on hundreds of random feasible, infeasible, rank-deficient and
  degenerate problems.

The status of a solve is explicit (:class:`LPStatus`); no sentinel value is ever returned
for an infeasible problem.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import InputError
from ..runtime.kernel_cache import install_package_stamp

install_package_stamp()  # before the first @njit (see kernel_cache)

log = logging.getLogger(__name__)

# Status codes shared by the compiled kernels (plain ints cross the numba boundary).
OPTIMAL = 0
INFEASIBLE = 1
UNBOUNDED = 2
FAILED = 3  # numerical trouble or iteration limit: the caller must use another solver

_PIVOT_TOL = 1e-9  # smallest usable pivot element on a row-scaled tableau
_COST_TOL = 1e-9  # reduced costs above -_COST_TOL * max(1, |c|) are treated as >= 0
_FEAS_TOL = 1e-9  # phase-1 residual (relative to max(1, |b|)) that still counts as feasible
_REFINE_TOL = 1e-8  # acceptance of the re-solved basis (primal/dual infeasibility allowed)
_DEGENERATE_RUN = 25  # consecutive degenerate pivots before switching to Bland's rule


class LPStatus(enum.Enum):
    """Outcome of a linear program."""

    OPTIMAL = "optimal"
    INFEASIBLE = "infeasible"
    UNBOUNDED = "unbounded"
    # Neither the simplex nor the interior-point method could decide (numerical trouble on
    # a nearly degenerate program). The metrics report NaN for it, never a guess.
    UNDECIDED = "undecided"


@dataclass(frozen=True)
class LPResult:
    """Solution of ``min c @ x, A @ x = b, x >= 0``.

    Attributes
    ----------
    status : LPStatus
    objective : float
        The optimum (``nan`` unless optimal).
    x : (n,) float64 ndarray
        An optimal point (``nan`` unless optimal).
    """

    status: LPStatus
    objective: float
    x: np.ndarray

    @property
    def optimal(self) -> bool:
        """The program was solved to optimality (``objective`` and ``x`` are finite)."""
        return self.status is LPStatus.OPTIMAL


# --------------------------------------------------------------------------------------
# compiled dense simplex
# --------------------------------------------------------------------------------------


@njit(cache=True)
def _pivot(T, r, s):
    """Gauss-Jordan pivot of tableau ``T`` on row ``r``, column ``s``."""
    n1 = T.shape[1]
    inv = 1.0 / T[r, s]
    for j in range(n1):
        T[r, j] *= inv
    T[r, s] = 1.0
    for i in range(T.shape[0]):
        if i != r:
            f = T[i, s]
            if f != 0.0:
                for j in range(n1):
                    T[i, j] -= f * T[r, j]
                T[i, s] = 0.0


@njit(cache=True)
def _iterate(T, basis, n_enter, cost_tol, max_iter):
    """Run simplex pivots on ``T`` until optimal; columns ``>= n_enter`` never enter.

    Returns OPTIMAL, UNBOUNDED or FAILED (iteration limit).
    """
    m = T.shape[0] - 1
    rhs = T.shape[1] - 1
    bland = False
    degenerate_run = 0
    for _ in range(max_iter):
        s = -1
        best = -cost_tol
        for j in range(n_enter):
            rj = T[m, j]
            if rj < -cost_tol:
                if bland:
                    s = j
                    break
                if rj < best:
                    best = rj
                    s = j
        if s < 0:
            return OPTIMAL
        # Harris ratio test: a relaxed bound first, then the largest pivot under it, so
        # tiny pivots (the usual source of blow-up) are avoided. In Bland mode exact
        # ties go to the smallest basic index, which guarantees termination.
        theta = np.inf
        for i in range(m):
            a = T[i, s]
            if a > _PIVOT_TOL:
                xi = T[i, rhs]
                if xi < 0.0:
                    xi = 0.0
                t = (xi + 1e-12) / a
                if t < theta:
                    theta = t
        if theta == np.inf:
            return UNBOUNDED
        r = -1
        best_a = 0.0
        best_ratio = np.inf
        for i in range(m):
            a = T[i, s]
            if a > _PIVOT_TOL:
                xi = T[i, rhs]
                if xi < 0.0:
                    xi = 0.0
                ratio = xi / a
                if ratio <= theta:
                    if bland:
                        if (
                            r < 0
                            or ratio < best_ratio - 1e-15
                            or (ratio <= best_ratio + 1e-15 and basis[i] < basis[r])
                        ):
                            r = i
                            best_ratio = ratio
                    elif a > best_a:
                        r = i
                        best_a = a
                        best_ratio = ratio
        if best_ratio <= 1e-14:
            degenerate_run += 1
            if degenerate_run > _DEGENERATE_RUN:
                bland = True
        else:
            degenerate_run = 0
        _pivot(T, r, s)
        basis[r] = s
    return FAILED


@njit(cache=True)
def simplex_standard(A, b, c, x_out):
    """Solve ``min c @ x, A @ x = b, x >= 0``, compiled.

    Parameters
    ----------
    A : (m, n) float64 ndarray
    b : (m,) float64 ndarray
    c : (n,) float64 ndarray
    x_out : (n,) float64 ndarray
        Written with an optimal point.

    Returns
    -------
    status : int
        OPTIMAL / INFEASIBLE / UNBOUNDED / FAILED (FAILED: use another solver).
    objective : float
    """
    m, n = A.shape
    for j in range(n):
        x_out[j] = 0.0
    # Scaled copy of the constraints: each row divided by its largest entry and signed so
    # that b >= 0 (artificial variables start feasible).
    As = np.empty((m, n))
    bs = np.empty(m)
    for i in range(m):
        s = 0.0
        for j in range(n):
            v = abs(A[i, j])
            if v > s:
                s = v
        if s == 0.0:
            s = 1.0
        if b[i] < 0.0:
            s = -s
        for j in range(n):
            As[i, j] = A[i, j] / s
        bs[i] = b[i] / s
    bmax = 1.0
    for i in range(m):
        if bs[i] > bmax:
            bmax = bs[i]
    cmax = 1.0
    for j in range(n):
        if abs(c[j]) > cmax:
            cmax = abs(c[j])
    cost_tol = _COST_TOL * cmax

    T = np.zeros((m + 1, n + m + 1))
    basis = np.empty(m, dtype=np.int64)
    for i in range(m):
        for j in range(n):
            T[i, j] = As[i, j]
        T[i, n + i] = 1.0
        T[i, n + m] = bs[i]
        basis[i] = n + i
    # phase 1: minimise the sum of the artificials
    for i in range(m):
        for j in range(n):
            T[m, j] -= T[i, j]
        T[m, n + m] -= T[i, n + m]
    max_iter = 50 * (m + n) + 100
    st = _iterate(T, basis, n, 1e-11, max_iter)
    if st != OPTIMAL:
        return FAILED, np.nan
    if -T[m, n + m] > _FEAS_TOL * bmax:
        return INFEASIBLE, np.nan
    # drive the artificials that are still basic (at zero) out of the basis; a row with
    # no usable entry is redundant (rank-deficient A) and keeps its artificial at zero.
    for i in range(m):
        if basis[i] >= n:
            best = 0.0
            jb = -1
            for j in range(n):
                v = abs(T[i, j])
                if v > best:
                    best = v
                    jb = j
            if best > 1e-7:
                _pivot(T, i, jb)
                basis[i] = jb
    # phase 2
    for j in range(n + m + 1):
        T[m, j] = 0.0
    for j in range(n):
        T[m, j] = c[j]
    for i in range(m):
        k = basis[i]
        if k < n:
            cb = c[k]
            if cb != 0.0:
                for j in range(n + m + 1):
                    T[m, j] -= cb * T[i, j]
    st = _iterate(T, basis, n, cost_tol, max_iter)
    if st != OPTIMAL:
        return st, np.nan

    # Re-solve the final basis from the original (scaled) data: B x_B = b, B^T y = c_B.
    B = np.zeros((m, m))
    cB = np.zeros(m)
    for i in range(m):
        k = basis[i]
        if k < n:
            for r in range(m):
                B[r, i] = As[r, k]
            cB[i] = c[k]
        else:
            B[k - n, i] = 1.0
    if m > 0:
        if abs(np.linalg.det(B)) < 1e-300:
            return FAILED, np.nan
        # Round-off in the tableau can end on a basis that is singular to machine precision
        # while its determinant is not tiny (7e-19 with a condition number of 3e17 on a hold
        # effort LP): LAPACK then meets an exact zero pivot in B or B^T. No certificate can
        # come from such a basis; the caller hands the LP to HiGHS.
        try:
            xB = np.linalg.solve(B, bs)
            y = np.linalg.solve(B.T, cB)
        except Exception:  # numba catches only Exception: here np.linalg.LinAlgError
            return FAILED, np.nan
    else:
        xB = np.zeros(0)
        y = np.zeros(0)
    xscale = 1.0
    for i in range(m):
        if abs(xB[i]) > xscale:
            xscale = abs(xB[i])
    for i in range(m):
        if xB[i] < -_REFINE_TOL * xscale:
            return FAILED, np.nan
        if basis[i] >= n and abs(xB[i]) > _REFINE_TOL * xscale:
            return FAILED, np.nan
    for j in range(n):
        rj = c[j]
        for r in range(m):
            rj -= As[r, j] * y[r]
        if rj < -_REFINE_TOL * cmax * max(1.0, np.sqrt(m)):
            return FAILED, np.nan
    obj = 0.0
    for i in range(m):
        k = basis[i]
        if k < n:
            v = xB[i]
            if v < 0.0:
                v = 0.0
            x_out[k] = v
            obj += c[k] * v
    return OPTIMAL, obj


# --------------------------------------------------------------------------------------
# HiGHS reference
# --------------------------------------------------------------------------------------


def _new_highs():
    """A HiGHS solver with its output off before it has printed anything.

    HiGHS prints its banner on the first call that may log unless ``output_flag`` is already
    false, and highspy's ``Highs`` wrapper (1.8 and later) makes such a call in its own
    constructor (it enables callbacks), so the banner reached stdout, where it corrupted the
    JSON summary of ``generate --json`` after a LP fell back to HiGHS. The wrapper adds
    only callbacks and Ctrl-C handling of ``solve``, which this module does not use, so the
    solver is built from the class it wraps and silenced first. Older highspy (no wrapper)
    exports that class as ``Highs`` and prints nothing before the option is set.
    """
    try:
        from highspy._core import _Highs as highs_class
    except ImportError:
        from highspy import Highs as highs_class
    highs = highs_class()
    highs.setOptionValue("output_flag", False)
    return highs


class HighsStandardLP:
    """A HiGHS model of ``min c @ x, A @ x = b, x >= 0`` whose right-hand side can change.

    Building the model once and changing only ``b`` between solves (e.g. the six gravity
    directions of the hold effort) costs about a third of a fresh build.

    Parameters
    ----------
    A : (m, n) float ndarray
    c : (n,) float ndarray
    """

    def __init__(self, A: np.ndarray, c: np.ndarray):
        import highspy

        A = np.ascontiguousarray(A, dtype=np.float64)
        c = np.ascontiguousarray(c, dtype=np.float64)
        m, n = A.shape
        self._m, self._n = m, n
        self._A = A
        self._highs = _new_highs()
        lp = highspy.HighsLp()
        lp.num_col_ = n
        lp.num_row_ = m
        lp.col_cost_ = c
        lp.col_lower_ = np.zeros(n)
        lp.col_upper_ = np.full(n, highspy.kHighsInf)
        lp.row_lower_ = np.zeros(m)
        lp.row_upper_ = np.zeros(m)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        col_idx, row_idx = np.nonzero(A.T)  # sorted by column, then row
        lp.a_matrix_.start_ = np.searchsorted(col_idx, np.arange(n + 1)).astype(np.int32)
        lp.a_matrix_.index_ = row_idx.astype(np.int32)
        lp.a_matrix_.value_ = A[row_idx, col_idx]
        self._highs.passModel(lp)
        self._status_enum = highspy.HighsModelStatus

    def solve(self, b: np.ndarray) -> LPResult:
        """Solve the program for one right-hand side.

        A program the simplex method cannot decide (numerical trouble on a nearly degenerate
        program) is solved again by the interior-point method; "unbounded or infeasible" is
        decided by a phase-1 solve.

        Parameters
        ----------
        b : (m,) float ndarray
            The right-hand side.

        Returns
        -------
        LPResult
            ``UNDECIDED`` (with a warning) when HiGHS cannot decide it.
        """
        b = np.ascontiguousarray(b, dtype=np.float64)
        idx = np.arange(self._m, dtype=np.int32)
        self._highs.changeRowsBounds(self._m, idx, b, b)
        self._highs.run()
        status = self._highs.getModelStatus()
        S = self._status_enum
        if status not in (S.kOptimal, S.kInfeasible, S.kUnbounded, S.kUnboundedOrInfeasible):
            # Numerical trouble in the simplex on a nearly degenerate program: the
            # interior-point method, from scratch, usually decides it.
            self._highs.clearSolver()
            self._highs.setOptionValue("solver", "ipm")
            self._highs.run()
            status = self._highs.getModelStatus()
            self._highs.setOptionValue("solver", "choose")
            self._highs.clearSolver()
        if status == S.kOptimal:
            x = np.asarray(self._highs.getSolution().col_value, dtype=np.float64)
            objective = float(self._highs.getInfo().objective_function_value)
            return LPResult(LPStatus.OPTIMAL, objective, x)
        if status == S.kInfeasible:
            return _not_optimal(LPStatus.INFEASIBLE, self._n)
        if status in (S.kUnbounded, S.kUnboundedOrInfeasible):
            # min c@x with x >= 0: "unbounded or infeasible" is resolved by a phase-1 solve
            return self._resolve_unbounded_or_infeasible(b)
        log.warning(
            "HiGHS could not decide a nearly degenerate LP (status %s): its metric is NaN",
            self._highs.modelStatusToString(status),
        )
        return _not_optimal(LPStatus.UNDECIDED, self._n)

    def _resolve_unbounded_or_infeasible(self, b: np.ndarray) -> LPResult:
        feasibility = HighsStandardLP(self._A, np.zeros(self._n)).solve(b)
        if feasibility.status is LPStatus.INFEASIBLE:
            return _not_optimal(LPStatus.INFEASIBLE, self._n)
        return _not_optimal(LPStatus.UNBOUNDED, self._n)


def _not_optimal(status: LPStatus, n: int) -> LPResult:
    return LPResult(status, float("nan"), np.full(n, np.nan))


_STATUS = {
    OPTIMAL: LPStatus.OPTIMAL,
    INFEASIBLE: LPStatus.INFEASIBLE,
    UNBOUNDED: LPStatus.UNBOUNDED,
}

BACKENDS = ("simplex", "highs")


def check_backend(backend: str) -> None:
    """Refuse an unknown solver name with the list of valid ones.

    Parameters
    ----------
    backend : str
        ``"simplex"`` or ``"highs"``; anything else raises InputError.
    """
    if backend not in BACKENDS:
        raise InputError(f"unknown LP backend {backend!r}; use one of {', '.join(BACKENDS)}")


def solve_standard_lp(
    c: np.ndarray, A: np.ndarray, b: np.ndarray, *, backend: str = "simplex"
) -> LPResult:
    """Solve ``min c @ x  s.t.  A @ x = b,  x >= 0`` exactly (to optimality).

    Parameters
    ----------
    c : (n,) float ndarray
    A : (m, n) float ndarray
    b : (m,) float ndarray
    backend : {"simplex", "highs"}
        Compiled dense simplex with HiGHS fallback, or HiGHS.

    Returns
    -------
    LPResult
        Infeasibility and unboundedness are statuses, not values.
    """
    check_backend(backend)
    A = np.ascontiguousarray(A, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64).reshape(-1)
    c = np.ascontiguousarray(c, dtype=np.float64).reshape(-1)
    if A.ndim != 2 or A.shape != (b.shape[0], c.shape[0]):
        raise InputError(
            f"inconsistent LP shapes: A {A.shape}, b {b.shape}, c {c.shape}; "
            "expected A (m, n), b (m,), c (n,)"
        )
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b)) and np.all(np.isfinite(c))):
        raise InputError("LP data must be finite")
    if backend == "simplex":
        x = np.zeros(A.shape[1])
        status, obj = simplex_standard(A, b, c, x)
        if status != FAILED:
            if status == OPTIMAL:
                return LPResult(LPStatus.OPTIMAL, float(obj), x)
            return _not_optimal(_STATUS[status], A.shape[1])
        log.debug("dense simplex could not certify an LP of shape %s; using HiGHS", A.shape)
    return HighsStandardLP(A, c).solve(b)
