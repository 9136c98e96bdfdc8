"""Learning targets (learning/targets.py): scaling to [0, 1] and back."""

import numpy as np
import pytest

from affordgrasp.learning.targets import make_target


@pytest.mark.parametrize("log", [False, True])
def test_an_effort_is_never_predicted_negative(log):
    effort = make_target("hold_effort_sum", log=log)
    scores = np.array([-0.05, 0.0, 0.5, 1.2, np.nan])
    values = effort.denormalise(scores)
    assert values[0] == 0.0 and np.all(values[:4] >= 0.0) and np.isnan(values[4])
    np.testing.assert_allclose(effort.normalise(values[1:4]), scores[1:4], rtol=1e-6)
    # a target that may be negative keeps its negative predictions
    task = make_target("task:pick", np.array([-300.0, -20.0, -1.0]))
    assert task.denormalise(np.array([-0.1]))[0] < task.low < 0.0
