"""The cross-entropy search: restarts that share a budget, a refinement, one run unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.search.cem import (
    PERIODIC,
    cem_maximize,
    cem_search,
    plan_runs,
    uniform_inputs,
)

TARGET = np.array([0.9, -0.3, 0.2, 0.1, -0.5, 0.4, 0.5, -0.4])


def peak(x: np.ndarray) -> np.ndarray:
    d = x - TARGET
    d[:, PERIODIC] = (d[:, PERIODIC] + 1) % 2 - 1
    r2 = (d**2).sum(axis=1)
    return np.where(r2 < 1.0, -r2, -np.inf)


def first_generation(start: int, stop: int) -> np.ndarray:
    return uniform_inputs(np.random.default_rng([7, start]), stop - start)


def test_one_run_is_cem_maximize():
    one = cem_search(peak, budget=300, seed=4, population=30, first_generation=first_generation)
    plain = cem_maximize(peak, budget=300, seed=4, population=30, initial=first_generation(0, 30))
    np.testing.assert_array_equal(one.x, plain.x)
    np.testing.assert_array_equal(one.values, plain.values)
    assert one.generations == plain.generations


def test_restarts_and_refinement_share_the_budget():
    calls = []

    def counted(x):
        calls.append(x.copy())
        return peak(x)

    trace = cem_search(
        counted, budget=301, seed=0, restarts=3, refine=0.2, first_generation=first_generation
    )
    runs, refine = plan_runs(301, 3, 0.2)
    assert refine == 60 and [b for b, _ in runs] == [81, 80, 80]
    assert len(trace.values) == sum(len(c) for c in calls) == 301
    np.testing.assert_array_equal(trace.x, np.concatenate(calls))
    # each restart starts with the next block of the first generations
    pop = runs[0][1]
    np.testing.assert_array_equal(calls[0], first_generation(0, pop))
    assert [g["run"] for g in trace.generations][-1] == 3  # the refinement
    assert trace.generations[-1]["evaluations"] == 301
    assert trace.state.best == pytest.approx(trace.values.max())
    again = cem_search(
        peak, budget=301, seed=0, restarts=3, refine=0.2, first_generation=first_generation
    )
    np.testing.assert_array_equal(again.values, trace.values)


@pytest.mark.parametrize(
    "budget, restarts, refine, name",
    [
        (10, 0, 0.0, "restarts"),
        (10, 2, 1.0, "refine"),
        (2, 3, 0.0, "budget"),
        (96, 2, 1e-3, "refine"),
    ],
)
def test_splits_that_cannot_work_are_refused(budget, restarts, refine, name):
    with pytest.raises(InputError, match=name):
        plan_runs(budget, restarts, refine)
