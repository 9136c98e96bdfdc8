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
    """Annotated with a type other than None, or, unannotated, returns a value or yields."""
    ret = node.returns
    if ret is not None:
        return not (isinstance(ret, ast.Constant) and ret.value is None)
    stack = list(node.body)
    while stack:
        item = stack.pop()
        if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue  # a nested function's returns are its own
        if isinstance(item, (ast.Yield, ast.YieldFrom)):
            return True
        if isinstance(item, ast.Return) and item.value is not None:
            if not (isinstance(item.value, ast.Constant) and item.value.value is None):
                return True
        stack.extend(ast.iter_child_nodes(item))
    return False


def _is_property(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """A property documents what it is in its summary line, as an attribute does."""
    names = [ast.unparse(d) for d in node.decorator_list]
    return any(n.split(".")[-1] in ("property", "cached_property", "setter") for n in names)


def _function_problems(node: ast.FunctionDef | ast.AsyncFunctionDef, where: str) -> list[str]:
    doc = ast.get_docstring(node) or ""
    if not doc.strip():
        return [f"{where}: no docstring"]
    if _is_property(node):
        return []
    problems = []
    if _parameters(node) and "Parameters\n----------" not in doc:
        problems.append(f"{where}: no Parameters section")
    if _returns_something(node) and not ("Returns\n-------" in doc or "Yields\n------" in doc):
        problems.append(f"{where}: no Returns section")
    return problems


def _inherited_methods(node: ast.ClassDef, classes: dict[str, ast.ClassDef]) -> set[str]:
    """Methods a class gets from its bases defined in the same module (their docs apply)."""
    names: set[str] = set()
    for base in node.bases:
        parent = classes.get(ast.unparse(base))
        if parent is not None and parent is not node:
            names |= {f.name for f in parent.body if isinstance(f, ast.FunctionDef)}
            names |= _inherited_methods(parent, classes)
    return names


def numpydoc_problems(source: str, module: str) -> list[str]:
    """What a module's public functions, classes and their public methods miss of numpydoc.

    A method without a docstring passes when it overrides a method of a base class of the
    same module (it inherits that documentation); a property needs a summary only.
    """
    problems = []
    body = ast.parse(source).body
    classes = {n.name: n for n in body if isinstance(n, ast.ClassDef)}
    for node in body:
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        if node.name.startswith("_"):
            continue
        where = f"{module}:{node.name}"
        if not isinstance(node, ast.ClassDef):
            problems += _function_problems(node, where)
            continue
        doc = ast.get_docstring(node) or ""
        if not doc.strip():
            problems.append(f"{where}: no docstring")
        elif _is_record(node) or _init_parameters(node):
            if "Parameters\n----------" not in doc and "Attributes\n----------" not in doc:
                problems.append(f"{where}: no Parameters or Attributes section")
        inherited = _inherited_methods(node, classes)
        for item in node.body:
            if not isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            if item.name.startswith("_"):
                continue
            if item.name in inherited and not (ast.get_docstring(item) or "").strip():
                continue
            problems += _function_problems(item, f"{where}.{item.name}")
    return problems


MODULES = sorted(
    p
    for p in SRC.rglob("*.py")
    if not any(part.startswith("_") and part != "__init__.py" for part in p.relative_to(SRC).parts)
)


# Editing a module that holds compiled kernels invalidates every kernel's on-disk cache (its
# key hashes all of them): these wait for the next change to their module.
PENDING: set[str] = set()


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_every_public_name_of_every_module_has_numpydoc_sections(path):
    name = str(path.relative_to(SRC))
    problems = numpydoc_problems(path.read_text(encoding="utf-8"), name)
    problems = [p for p in problems if p not in PENDING]
    assert not problems, "\n".join(problems)


def test_pending_problems_are_still_there():
    # a fixed one leaves the list
    found = {
        problem
        for path in MODULES
        for problem in numpydoc_problems(
            path.read_text(encoding="utf-8"), str(path.relative_to(SRC))
        )
    }
    assert PENDING <= found, PENDING - found


def test_the_checker_finds_what_is_missing():
    source = (
        'def f(x: int) -> int:\n    """Summary only."""\n\n\n'
        "def _private(x):\n    pass\n\n\n"
        'class C:\n    """Summary."""\n\n    def __init__(self, a):\n        pass\n\n'
        '    def run(self, n: int) -> int:\n        """Summary only."""\n\n'
        "    def bare(self):\n        pass\n\n"
        "    def _helper(self, n):\n        pass\n\n"
        "    @property\n"
        '    def size(self) -> int:\n        """The size, m."""\n\n\n'
        "class D(C):\n"
        '    """Summary.\n\n    Parameters\n    ----------\n    a : int\n    """\n\n'
        "    def __init__(self, a):\n        pass\n\n"
        "    def run(self, n: int) -> int:\n        return n\n\n\n"
        'class E(Exception):\n    """An error without parameters of its own."""\n\n\n'
        'def g():\n    """Summary only."""\n    return 1\n\n\n'
        'def h():\n    """Summary only."""\n    yield\n\n\n'
        'def k():\n    """Nested returns are not its own."""\n\n'
        "    def inner():\n        return 1\n\n"
        "    return None\n"
    )
    assert numpydoc_problems(source, "m.py") == [
        "m.py:f: no Parameters section",
        "m.py:f: no Returns section",
        "m.py:C: no Parameters or Attributes section",
        "m.py:C.run: no Parameters section",
        "m.py:C.run: no Returns section",
        "m.py:C.bare: no docstring",
        "m.py:g: no Returns section",
        "m.py:h: no Returns section",
    ]


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_every_module_says_what_it_holds(path):
    assert (ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or "").strip()
