"""One exception hierarchy; the library names parameters, the CLI names options (errors.py)."""

import pytest

import affordgrasp as ag
from affordgrasp.cli import main
from affordgrasp.errors import DatasetError, InputError, bad_parameter, cli_message


def test_library_names_the_parameter_and_the_cli_the_option():
    err = bad_parameter("shard_size", "must be an integer >= 1, got 0")
    assert str(err) == "shard_size must be an integer >= 1, got 0"
    assert cli_message(err) == "--shard-size must be an integer >= 1, got 0"
    # only the parameter's own name is rewritten, not words that contain it
    err = InputError("size_m 8 makes size_m_test.stl 8 m long", parameter="size_m")
    assert cli_message(err) == "--size-m 8 makes size_m_test.stl 8 m long"
    assert cli_message(DatasetError("no parameter here")) == "no parameter here"


def test_generate_speaks_python_and_the_cli_speaks_flags(tmp_path, capsys):
    with pytest.raises(InputError, match=r"^samples must be an integer >= 1, got 0$"):
        ag.generate(["knife"], 0, tmp_path / "d")
    assert main(["generate", "knife", "--samples", "0", "--out", str(tmp_path / "d")]) == 2
    assert "--samples must be" in capsys.readouterr().err


def test_library_raises_no_bare_runtime_error_and_has_no_assert():
    # Invariants are InternalError (a RuntimeError that says "this is a bug"); bad input is
    # an InputError. Asserts vanish under python -O, so the library has none.
    import ast
    from pathlib import Path

    package = Path(ag.__file__).resolve().parent
    found = []
    for path in sorted(package.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            bare = (
                isinstance(node, ast.Raise)
                and isinstance(node.exc, ast.Call)
                and getattr(node.exc.func, "id", None) == "RuntimeError"
            )
            if bare or isinstance(node, ast.Assert):
                found.append(f"{path.relative_to(package)}:{node.lineno}")
    assert not found, found


@pytest.mark.parametrize(
    "call, parameter",
    [
        (lambda: _physics(shard_size=0), "shard_size"),
        (lambda: _physics(max_per_object=0), "max_per_object"),
        (lambda: _physics(workers=-1), "workers"),
    ],
)
def test_physics_errors_name_the_python_parameter(call, parameter):
    with pytest.raises(InputError) as err:
        call()
    assert str(err.value).startswith(f"{parameter} must be a positive integer")
    flag = "--" + parameter.replace("_", "-")
    assert cli_message(err.value).startswith(f"{flag} must be a positive integer")


def _physics(**kwargs):
    from affordgrasp.physics.run import run_physics

    return run_physics("no-such-dataset", "no-such-out", **kwargs)
