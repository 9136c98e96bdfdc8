"""The front door: ``import affordgrasp as ag`` (affordgrasp/__init__.py, pipeline.py)."""

import subprocess
import sys

import numpy as np
import pytest

import affordgrasp as ag
from affordgrasp.errors import InputError


def test_every_front_door_name_resolves():
    for name in ag.__all__:
        assert getattr(ag, name) is not None, name
    assert {"load_object", "get_hand", "get_task", "ContactSet", "evaluate", "generate"} <= set(
        ag.__all__
    )
    assert "read_dataset" in dir(ag)


def test_import_is_light():
    code = (
        "import sys, affordgrasp; print(sorted({'numba', 'pyarrow', 'trimesh'} & set(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_evaluate_samples_and_inputs_agree():
    drawn = ag.evaluate("knife:1", samples=6, seed=5, batch_size=4)
    assert isinstance(drawn, ag.Evaluation) and len(drawn) == 6
    assert set(drawn.timings) == {"simulate", "metrics", "table"}
    p0 = np.array(drawn.table["p0"].to_pylist())
    use_dir = np.array(drawn.table["use_dir"].to_pylist())
    given = ag.evaluate(ag.load_object("knife:1"), p0=p0, use_dir=use_dir)
    for column in ("joints", "epsilon", "hold_effort_px", "use_force"):
        assert given.table[column].to_pylist() == drawn.table[column].to_pylist(), column
    np.testing.assert_array_equal(drawn.scores("pick"), ag.get_task("pick").evaluate(drawn.table))


def test_an_evaluation_does_not_unpack():
    result = ag.Evaluation(ag.evaluate("knife:1", samples=2, seed=0).table, {"simulate": 1.0})
    assert result.seconds == 1.0 and len(result) == 2
    with pytest.raises(TypeError, match=r"does not unpack.*result\.table and result\.timings"):
        table, timings = result
    with pytest.raises(TypeError, match="not subscriptable"):
        result[0]
    with pytest.raises(TypeError, match="does not unpack"):
        list(result)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({}, "give samples"),
        ({"samples": 3, "p0": np.zeros((1, 6))}, "not both"),
        ({"p0": np.zeros((1, 6))}, "give both"),
        ({"samples": 0}, "samples must be a positive integer"),
        ({"samples": 4, "batch_size": -1}, "batch_size must be a positive integer"),
    ],
)
def test_evaluate_names_its_parameters(kwargs, message):
    with pytest.raises(InputError, match=message):
        ag.evaluate("knife", **kwargs)
