"""The compiled simplex against HiGHS (scipy's linprog) on random LPs (lp.py)."""

import numpy as np
import pytest
from scipy.optimize import linprog

from affordgrasp.errors import InputError
from affordgrasp.metrics.lp import LPStatus, solve_standard_lp

_STATUS = {0: LPStatus.OPTIMAL, 2: LPStatus.INFEASIBLE, 3: LPStatus.UNBOUNDED}


def _random_problem(rng, kind):
    m = int(rng.integers(1, 13))
    n = int(rng.integers(1, 90))
    A = rng.normal(size=(m, n))
    if kind == "rank-deficient":
        r = int(rng.integers(1, m + 1))
        A = rng.normal(size=(m, r)) @ rng.normal(size=(r, n))
    elif kind == "degenerate":  # small integers: ties in ratio tests, degenerate vertices
        A = rng.integers(-2, 3, size=(m, n)).astype(float)
    x0 = np.abs(rng.normal(size=n)) * (rng.random(n) < 0.3)
    u = rng.random()
    b = A @ x0 if u < 0.6 else rng.normal(size=m)  # the latter is often infeasible
    if u > 0.85:  # certainly infeasible: row 0 of A x is > 0 for every x >= 0, x != 0
        A[0] = np.abs(A[0]) + 0.1
        b[0] = -1.0
    c = np.abs(rng.normal(size=n)) if kind != "signed-cost" else rng.normal(size=n)
    if kind == "unit-cost":
        c = np.ones(n)
    return A, b, c


@pytest.mark.parametrize(
    "kind", ["dense", "rank-deficient", "degenerate", "signed-cost", "unit-cost"]
)
def test_simplex_matches_highs(kind):
    rng = np.random.default_rng(
        {"dense": 1, "rank-deficient": 2, "degenerate": 3, "signed-cost": 4, "unit-cost": 5}[kind]
    )
    seen = set()
    for _ in range(120):
        A, b, c = _random_problem(rng, kind)
        ours = solve_standard_lp(c, A, b)
        ref = linprog(c, A_eq=A, b_eq=b, bounds=(0, None), method="highs")
        assert ours.status is _STATUS[ref.status]
        seen.add(ours.status)
        if ref.status == 0:
            assert ours.objective == pytest.approx(ref.fun, rel=1e-9, abs=1e-9)
            assert np.all(ours.x >= 0)
            np.testing.assert_allclose(A @ ours.x, b, atol=1e-9 * max(1, np.abs(b).max()))
            assert c @ ours.x == pytest.approx(ours.objective, rel=1e-12, abs=1e-12)
    assert LPStatus.OPTIMAL in seen and LPStatus.INFEASIBLE in seen


def test_highs_backend_agrees_with_simplex():
    rng = np.random.default_rng(7)
    for _ in range(100):
        A, b, c = _random_problem(rng, "dense")
        a = solve_standard_lp(c, A, b)
        h = solve_standard_lp(c, A, b, backend="highs")
        assert a.status is h.status
        if a.optimal:
            assert a.objective == pytest.approx(h.objective, rel=1e-9, abs=1e-9)


def test_status_is_explicit_never_a_sentinel():
    infeasible = solve_standard_lp([1.0], [[1.0]], [-1.0])
    assert infeasible.status is LPStatus.INFEASIBLE and not infeasible.optimal
    unbounded = solve_standard_lp([-1.0, 0.0], [[1.0, -1.0]], [0.0])
    assert unbounded.status is LPStatus.UNBOUNDED
    redundant = solve_standard_lp([1.0, 1.0], [[1.0, 1.0], [2.0, 2.0]], [1.0, 2.0])
    assert redundant.optimal and redundant.objective == pytest.approx(1.0)


def test_bad_input_is_refused():
    with pytest.raises(InputError):
        solve_standard_lp([1.0], [[1.0, 2.0]], [1.0])
    with pytest.raises(InputError):
        solve_standard_lp([1.0], [[np.nan]], [1.0])
    with pytest.raises(InputError):
        solve_standard_lp([1.0], [[1.0]], [1.0], backend="cplex")


def test_highs_prints_nothing_on_stdout():
    """HiGHS's banner (C printf, first instance of a process) must not reach stdout.

    ``generate --json`` writes its summary on stdout; a LP handed to HiGHS mid-run once
    put the banner in front of it and the JSON could not be read.
    """
    import subprocess
    import sys

    script = (
        "import numpy as np\n"
        "from affordgrasp.metrics.lp import HighsStandardLP\n"
        "lp = HighsStandardLP(np.array([[1.0, 1.0]]), np.array([1.0, 2.0]))\n"
        "r = lp.solve(np.array([1.0]))\n"
        "print(r.status.name, round(r.objective, 9))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True
    )
    assert out.stdout == "OPTIMAL 1.0\n", out.stdout
