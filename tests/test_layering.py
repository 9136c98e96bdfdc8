"""The layering contract holds, and library code never switches matplotlib's backend."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "src" / "affordgrasp"


def test_the_import_contract_is_kept():
    pytest.importorskip("importlinter")
    run = (
        "import sys; sys.argv = ['lint-imports', '--no-cache']; "
        "from importlinter.cli import lint_imports_command; lint_imports_command()"
    )
    done = subprocess.run(
        [sys.executable, "-c", run],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(ROOT / "src"), "PATH": ""},
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "0 broken" in done.stdout


def test_no_library_module_switches_the_backend_or_uses_pyplot():
    pattern = re.compile(
        r"matplotlib\.use\(|import matplotlib\.pyplot|from matplotlib import pyplot"
    )
    offenders = [
        f"{path.relative_to(SOURCE)}:{i}"
        for path in sorted(SOURCE.rglob("*.py"))
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line)
    ]
    assert offenders == []


def test_tests_import_nothing_from_the_script_folders():
    # benchmarks/ (timings), studies/ (research) and tools/ (maintenance) are scripts: what
    # a test needs of them belongs in the package. A test that loads code by path (or puts
    # a folder on sys.path) and names one of those folders is one that imports a script.
    here = Path(__file__).resolve().parent
    loads = re.compile(r"spec_from_file_location|run_path|sys\.path\.(insert|append)")
    names = re.compile(r"[\"'/](benchmarks|studies|tools)[\"'/]")
    imports = re.compile(r"^\s*(from|import)\s+(benchmarks|studies|tools)\b", re.MULTILINE)
    offenders = []
    for path in sorted(here.rglob("*.py")):
        if path == Path(__file__).resolve():
            continue
        text = path.read_text(encoding="utf-8")
        if (loads.search(text) and names.search(text)) or imports.search(text):
            offenders.append(str(path.relative_to(ROOT)))
    assert not offenders, offenders
