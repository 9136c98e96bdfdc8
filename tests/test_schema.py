"""The row table is built from numpy buffers: the same arrays as pa.array, without pandas."""

import subprocess
import sys

import numpy as np
import pyarrow as pa
import pytest

from affordgrasp import schema


@pytest.mark.parametrize(
    ("values", "typ"),
    [
        (np.array([0.5, -1e300, np.nan, np.inf, 0.0]), pa.float64()),
        (np.arange(7, dtype=np.int64) - 3, pa.int64()),
        (np.array([0, 3, 3, 9], dtype=np.int32), pa.int32()),
        (np.zeros(0), pa.float64()),
        (np.arange(12.0).reshape(3, 4)[:, ::2], pa.float64()),  # not contiguous
        ([1, 2, 3], pa.int32()),
    ],
)
def test_numbers_are_what_pa_array_makes(values, typ):
    got = schema._numbers(values, typ)
    got.validate(full=True)
    want = pa.array(np.ascontiguousarray(values).reshape(-1).astype(typ.to_pandas_dtype()), typ)
    assert got.type == typ and got.null_count == want.null_count == 0
    np.testing.assert_array_equal(got.to_numpy(), want.to_numpy())  # NaN == NaN here


@pytest.mark.parametrize(
    "values",
    [["grasped", "touched", "missed"], ["", "ünïcödé ✓", None, "x", None], [], [None], ["a"] * 5],
)
def test_strings_are_what_pa_array_makes(values):
    got = schema._strings(values)
    got.validate(full=True)
    assert got.equals(pa.array(values, pa.string()))
    assert got.to_pylist() == values


def test_evaluating_and_writing_rows_does_not_import_pandas(tmp_path):
    code = (
        "import sys; import pyarrow.parquet as pq; import affordgrasp as ag; "
        "t = ag.evaluate('knife:1', samples=3, seed=2).table; "
        f"pq.write_table(t, r'{tmp_path}/r.parquet'); print('pandas' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
