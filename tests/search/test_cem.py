"""The cross-entropy search: restarts that share a budget, a refinement, one run unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from affordgrasp.errors import InputError
from affordgrasp.search.cem import (
    PERIODIC,
    cem_maximize,
    cem_search,
    nearby_inputs,
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


def test_nearby_inputs_move_each_coordinate_by_its_std_and_stay_in_the_box():
    centres = np.array([[0.99, 0.0, -0.99, 0.995, -1.0, 0.0, 0.5, 0.5], TARGET])
    std = np.array([0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.0, 0.0])
    x = nearby_inputs(centres, std, 2000, np.random.default_rng(0))
    assert x.shape == (4000, 8)
    assert (x >= -1).all() and (x <= 1).all() and (x[:, 5] >= 0).all()
    for i, c in enumerate(centres):
        rows = x[i * 2000 : (i + 1) * 2000]
        np.testing.assert_array_equal(rows[:, 6:], np.broadcast_to(c[6:], (2000, 2)))  # std 0
        d = rows - c
        d[:, PERIODIC] = (d[:, PERIODIC] + 1) % 2 - 1  # the angles wrap: 0.99 + 0.05 is -0.96
        assert np.abs(d[:, :6]).max() < 0.05 * 6
    # around the second centre, away from the box's faces: the draws' spread is the std
    d = x[2000:] - TARGET
    d[:, PERIODIC] = (d[:, PERIODIC] + 1) % 2 - 1
    d = d[:, :6]
    np.testing.assert_allclose(d.std(axis=0), 0.05, rtol=0.1)
    assert (x[:2000, 0] < 0).any()  # u1 = 0.99 wrapped past 1 to the other side
    assert (x[:2000, 3] == 1.0).any() and (x[:2000, 4] == -1.0).any()  # clipped
    # the same generator state, the same draws; none asked, none drawn
    again = nearby_inputs(centres, std, 2000, np.random.default_rng(0))
    np.testing.assert_array_equal(x, again)
    assert nearby_inputs(centres, 0.1, 0, np.random.default_rng(0)).shape == (0, 8)
    for bad in ({"centres": np.zeros((2, 6))}, {"std": -0.1}, {"std": np.nan}, {"count": -1}):
        args = {"centres": centres, "std": 0.1, "count": 3} | bad
        with pytest.raises(InputError):
            nearby_inputs(args["centres"], args["std"], args["count"], np.random.default_rng(0))
