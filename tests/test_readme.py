"""The README's Python examples run as written and print what the README says they do."""

import contextlib
import io
import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def run_block(code: str) -> tuple[dict, list[str]]:
    namespace: dict = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), namespace)
    return namespace, out.getvalue().splitlines()


def check_front_door(ns: dict, lines: list[str]) -> None:
    from affordgrasp.grasp.policy import STATUSES

    result, scores = ns["result"], ns["scores"]
    assert result.table.num_rows == 200 and scores.shape == (200,)
    assert np.isfinite(scores).any()  # some grasps of a mug hold it
    status, hold_px, best = lines[-1].split()
    assert status in STATUSES
    assert float(hold_px) >= 0
    # pick = p_pick (ties by minus the total hold effort): the best grasp's column is its score
    row = int(scores.argmax())
    assert float(best) == result.table["p_pick"][row].as_py()
    assert abs(scores.max() - float(best)) <= 1e-6 and 0.0 <= float(best) <= 1.0
    assert float(best) == result.table["p_pick"].to_numpy().max()


def check_contacts(ns: dict, lines: list[str]) -> None:
    # Two opposite point contacts never reach force closure (the GWS is flat): ε = 0.
    assert "epsilon=0.0" in lines[0] and "degenerate" in lines[0]
    # Gravity along ±x: one finger pushes 1 N. Along ±y, ±z: friction μ = 0.5 at each of the
    # two contacts carries 1 N when each presses with 1 N: 2 N in total.
    hold = np.array(lines[1].strip("[]").split(), dtype=float)
    np.testing.assert_allclose(hold, [1, 1, 2, 2, 2, 2], rtol=1e-9)
    # Pressing on the top face: the fingers' friction (≤ 0.5 N each at 1 N) holds 1 N.
    assert float(lines[2]) == pytest.approx(1.0, rel=1e-9)


def check_pairs(ns: dict, lines: list[str]) -> None:
    found = ns["found"]
    candidates, values = lines[-1].split(" ", 1)
    assert int(candidates) == found.candidates >= 1
    values = [float(v) for v in values.strip("[]").split(",")]
    assert 1 <= len(values) <= 3 and values == sorted(values, reverse=True)
    # every top row is a robust grasp whose use point lies on a sharp edge
    assert all(e >= 0.014 for e in found.table["epsilon"].to_pylist())
    assert all(a <= np.radians(45) for a in found.table["use_edge_angle"].to_pylist())


CHECKS = {
    "ag.evaluate(": check_front_door,
    "ContactSet.from_arrays(": check_contacts,
    "best_pairs(": check_pairs,
}


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_readme_python_block_runs_and_prints_what_it_says(code):
    checks = [check for marker, check in CHECKS.items() if marker in code]
    assert len(checks) == 1, "every README Python block needs its check in tests/test_readme.py"
    namespace, lines = run_block(code)
    checks[0](namespace, lines)


def test_the_module_table_names_every_module_of_the_package():
    import affordgrasp

    table = README.read_text().split("## The pipeline", 1)[1].split("\n## ", 1)[0]
    named = set(re.findall(r"`affordgrasp\.(\w+)`", table))
    src = Path(affordgrasp.__file__).resolve().parent
    modules = {p.stem for p in src.glob("*.py") if not p.stem.startswith("_")}
    packages = {p.parent.name for p in src.glob("*/__init__.py")}
    assert modules | packages, src
    assert sorted((modules | packages) - named) == []
    assert sorted(named - (modules | packages)) == []
