"""Every package affordgrasp needs at run time is declared in pyproject.toml.

A package that happens to be installed (pulled in by a test tool, or left on the machine)
hides a missing declaration until a user installs into a fresh environment. Two checks:

* statically, every third-party top-level import in ``src/`` maps to a distribution declared
  in ``[project] dependencies``; an optional extra is allowed only for imports made lazily
  (inside a function), which is how optional features are written;
* dynamically, the pipeline runs on awkward meshes in a subprocess that can import only the
  standard library and the declared dependencies with their own required dependencies,
  as a fresh ``pip install .`` would have them. Packages that a library imports on its own
  (trimesh uses networkx to fix the winding of a flipped face) are caught here.
"""

from __future__ import annotations

import ast
import functools
import importlib.metadata as md
import json
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

import affordgrasp

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "affordgrasp"


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def _names(requirements: list[str]) -> set[str]:
    return {canonicalize_name(Requirement(r).name) for r in requirements}


def _imports(path: Path) -> list[tuple[str, bool]]:
    """(top-level module, imported at module level) of every absolute import of a file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []

    def visit(node, lazy: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = lazy or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
            if isinstance(child, ast.Import):
                found.extend((a.name.split(".")[0], not lazy) for a in child.names)
            elif isinstance(child, ast.ImportFrom) and child.level == 0 and child.module:
                found.append((child.module.split(".")[0], not lazy))
            visit(child, inner)

    visit(tree, False)
    return found


@functools.cache
def _owners() -> dict[str, list[str]]:
    # Scans every installed distribution: once per session, not once per import.
    return md.packages_distributions()


def _distributions(module: str) -> set[str]:
    dists = set(_owners().get(module, []))
    if not dists:
        # A distribution that installs a bare extension module (manifold3d) is not always
        # listed by packages_distributions(); its name is the module's.
        try:
            dists = {md.distribution(module).metadata["Name"]}
        except md.PackageNotFoundError:
            pass
    return {canonicalize_name(d) for d in dists}


def test_every_third_party_import_is_declared():
    project = _project()
    core = _names(project["dependencies"])
    extras = {k: _names(v) for k, v in project.get("optional-dependencies", {}).items()}
    optional = set().union(*extras.values()) if extras else set()
    stdlib = set(sys.stdlib_module_names)
    problems = []
    for path in sorted(SRC.rglob("*.py")):
        for module, eager in _imports(path):
            if module in stdlib or module in ("affordgrasp", "__future__"):
                continue
            dists = _distributions(module)
            where = path.relative_to(ROOT)
            if not dists:
                problems.append(f"{where}: {module} is not installed, so it cannot be checked")
            elif dists & core:
                continue
            elif dists & optional and not eager:
                continue
            elif dists & optional:
                problems.append(f"{where}: optional {module} imported at module level")
            else:
                problems.append(f"{where}: {module} ({', '.join(sorted(dists))}) not declared")
    assert not problems, "\n".join(sorted(set(problems)))


def test_optional_dependencies_named_in_require_calls_are_extras():
    """``require("ray", "cluster")`` must name an extra that installs that package."""
    extras = {k: _names(v) for k, v in _project().get("optional-dependencies", {}).items()}
    calls = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (
                isinstance(node, ast.Call)
                and getattr(node.func, "id", getattr(node.func, "attr", None)) == "require"
                and len(node.args) == 2
                and all(isinstance(a, ast.Constant) for a in node.args)
            ):
                calls.append((path.name, node.args[0].value, node.args[1].value))
    assert calls, "the scan found no require() call; the test no longer sees them"
    for where, module, extra in calls:
        assert extra in extras, f"{where}: require({module!r}, {extra!r}): no such extra"
        dists = _distributions(module.split(".")[0]) or {canonicalize_name(module)}
        assert dists & extras[extra], f"{where}: extra {extra!r} does not install {module}"


# Runs in a subprocess: only the standard library, affordgrasp and the declared dependencies
# (with what they require, extras excluded) may be imported.
_FRESH_ENV_SCRIPT = textwrap.dedent(
    """
    import importlib.abc, importlib.metadata as md, json, sys
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    declared = json.loads(sys.argv[1])
    allowed, todo = set(), list(declared)
    while todo:
        name = canonicalize_name(todo.pop())
        if name in allowed:
            continue
        allowed.add(name)
        try:
            requires = md.requires(name) or []
        except md.PackageNotFoundError:
            continue
        for text in requires:
            req = Requirement(text)
            if req.marker is None or req.marker.evaluate({"extra": ""}):
                todo.append(req.name)
    owners = md.packages_distributions()
    blocked = set()

    class Fresh(importlib.abc.MetaPathFinder):
        def find_spec(self, fullname, path=None, target=None):
            top = fullname.split(".")[0]
            dists = {canonicalize_name(d) for d in owners.get(top, [])}
            if dists and top != "affordgrasp" and not dists & allowed:
                blocked.add(top)
                raise ModuleNotFoundError(f"No module named {top!r}", name=top)
            return None

    for name in [m for m in sys.modules if m.split(".")[0] not in sys.stdlib_module_names]:
        if name.split(".")[0] not in ("packaging",):
            del sys.modules[name]
    sys.meta_path.insert(0, Fresh())

    import numpy as np
    import trimesh
    from affordgrasp.objects.loading import prepare_mesh
    from affordgrasp.pipeline import evaluate_samples

    box = trimesh.creation.box((0.05, 0.04, 0.03))
    flipped = box.faces.copy()
    flipped[0] = flipped[0][::-1]
    prepare_mesh(trimesh.Trimesh(box.vertices, flipped, process=False), source="flipped")
    prepare_mesh(trimesh.Trimesh(box.vertices, box.faces[1:], process=False), source="open")
    other = box.copy()
    other.apply_translation((0.02, 0, 0))
    soup = trimesh.util.concatenate([box, other])
    prepare_mesh(soup, source="overlapping")
    table = evaluate_samples("mug", 16, seed=0).table
    assert table.num_rows == 16
    print(json.dumps(sorted(blocked)))
    """
)

# The folder the tests import affordgrasp from (the installed package in CI, src/ in a
# checkout): the subprocess runs the same build, with the same compiled kernels.
PACKAGE_ROOT = Path(affordgrasp.__file__).resolve().parents[1]


def test_pipeline_runs_with_only_the_declared_dependencies():
    declared = sorted(_names(_project()["dependencies"]))
    proc = subprocess.run(
        [sys.executable, "-c", _FRESH_ENV_SCRIPT, json.dumps(declared)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**__import__("os").environ, "PYTHONPATH": str(PACKAGE_ROOT)},
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
