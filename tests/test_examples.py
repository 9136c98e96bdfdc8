"""examples/: the README's Python snippets as scripts, run and checked like the README."""

import contextlib
import io
import runpy
from pathlib import Path

import pytest
from test_readme import BLOCKS, CHECKS

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


def test_every_readme_snippet_is_an_example():
    bodies = [p.read_text() for p in EXAMPLES]
    for block in BLOCKS:
        assert any(body.endswith(block) for body in bodies), block.splitlines()[0]


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs_and_prints_what_the_readme_says(path):
    code = path.read_text()
    checks = [check for marker, check in CHECKS.items() if marker in code]
    assert len(checks) == 1, f"{path.name} needs a check in tests/test_readme.py"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        namespace = runpy.run_path(str(path), run_name="__main__")
    checks[0](namespace, out.getvalue().splitlines())
