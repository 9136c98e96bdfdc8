"""The public API is documented in numpydoc: sections that say what goes in and comes out."""

import ast
import inspect
from pathlib import Path

import pytest

import affordgrasp as ag


@pytest.mark.parametrize("name", ag.__all__)
def test_front_door_names_have_numpydoc_sections(name):
    obj = getattr(ag, name)
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"ag.{name} has no docstring"
    if inspect.isclass(obj):
        assert "Attributes\n----------" in doc or "Parameters\n----------" in doc, name
        return
    params = [p for p in inspect.signature(obj).parameters.values() if p.name != "self"]
    if params:
        assert "Parameters\n----------" in doc, f"ag.{name} documents no Parameters section"


# ------------------------------------------------------------------ every module of the package

SRC = Path(ag.__file__).resolve().parent


def _is_record(node: ast.ClassDef) -> bool:
    """A dataclass or NamedTuple: its fields are its constructor's parameters."""
    decorated = any("dataclass" in ast.unparse(d) for d in node.decorator_list)
    named_tuple = any("NamedTuple" in ast.unparse(b) for b in node.bases)
    has_fields = any(isinstance(s, ast.AnnAssign) for s in node.body)
    return (decorated or named_tuple) and has_fields


def _init_parameters(node: ast.ClassDef) -> list[str]:
    for item in node.body:
        if isinstance(item, ast.FunctionDef) and item.name == "__init__":
            return _parameters(item)
    return []


def _parameters(node: ast.FunctionDef | ast.AsyncFunctionDef) -> list[str]:
    args = node.args
    names = [a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs]]
    names += [a.arg for a in (args.vararg, args.kwarg) if a is not None]
    return [n for n in names if n not in ("self", "cls")]


def _returns_something(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    ret = node.returns
    return ret is not None and not (isinstance(ret, ast.Constant) and ret.value is None)


def numpydoc_problems(source: str, module: str) -> list[str]:
    """What a module's public functions and classes miss of numpydoc."""
    problems = []
    for node in ast.parse(source).body:
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        if node.name.startswith("_"):
            continue
        doc = ast.get_docstring(node) or ""
        where = f"{module}:{node.name}"
        if not doc.strip():
            problems.append(f"{where}: no docstring")
            continue
        sections = "Parameters\n----------" in doc or "Attributes\n----------" in doc
        if isinstance(node, ast.ClassDef):
            if (_is_record(node) or _init_parameters(node)) and not sections:
                problems.append(f"{where}: no Parameters or Attributes section")
            continue
        if _parameters(node) and "Parameters\n----------" not in doc:
            problems.append(f"{where}: no Parameters section")
        if _returns_something(node) and not ("Returns\n-------" in doc or "Yields\n------" in doc):
            problems.append(f"{where}: no Returns section")
    return problems


MODULES = sorted(
    p
    for p in SRC.rglob("*.py")
    if not any(part.startswith("_") and part != "__init__.py" for part in p.relative_to(SRC).parts)
)


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_every_public_name_of_every_module_has_numpydoc_sections(path):
    name = str(path.relative_to(SRC))
    problems = numpydoc_problems(path.read_text(encoding="utf-8"), name)
    assert not problems, "\n".join(problems)


def test_the_checker_finds_what_is_missing():
    source = (
        'def f(x: int) -> int:\n    """Summary only."""\n\n\n'
        "def _private(x):\n    pass\n\n\n"
        'class C:\n    """Summary."""\n\n    def __init__(self, a):\n        pass\n\n\n'
        'class E(Exception):\n    """An error without parameters of its own."""\n'
    )
    assert numpydoc_problems(source, "m.py") == [
        "m.py:f: no Parameters section",
        "m.py:f: no Returns section",
        "m.py:C: no Parameters or Attributes section",
    ]
