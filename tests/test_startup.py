"""Start-up: what a fresh command's warm path imports and loads (benchmarks/bench_startup.py).

Timing a process start is flaky under load, so these tests check the mechanism instead: the
modules that made start-up slow are not imported on the warm path of the main job form.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = str(Path(__file__).resolve().parents[1] / "src")


def fresh_process_modules(code: str, **env: str) -> set[str]:
    # the session's private cache (tests/conftest.py), never the user's
    cache = {"AFFORDGRASP_CACHE_DIR": os.environ["AFFORDGRASP_CACHE_DIR"]}
    proc = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys, json; print(json.dumps(sorted(sys.modules)))"],
        capture_output=True,
        text=True,
        check=False,
        env={"PYTHONPATH": SRC, "PATH": "/usr/bin:/bin", **cache, **env},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return set(json.loads(proc.stdout.strip().splitlines()[-1]))


def test_generate_imports_neither_pandas_nor_scipy_stats(tmp_path):
    modules = fresh_process_modules(
        "from affordgrasp.cli import main\n"
        f"assert main(['generate', 'hammer', '--samples', '1', '--workers', '1', '--out', "
        f"{str(tmp_path / 'out')!r}]) == 0"
    )
    assert "pandas" not in modules
    assert "scipy.stats" not in modules


def test_kernels_load_from_the_cache_without_numba_compiler_registries():
    # numba's own cache loading first imports every typing and lowering registry (~0.2 s);
    # the package's kernels load without them and give the same results.
    modules = fresh_process_modules(
        "from affordgrasp import compiled\n"
        "load = compiled.warm_up()\n"
        "import sys\n"
        "if load.compiled:\n"
        "    sys.modules['numba.np.arraymath'] = None  # compiled here: nothing to check\n"
        "    sys.modules['compiled-in-test'] = None\n"
    )
    if "compiled-in-test" in modules:
        pytest.skip("the kernel cache was stale and this process compiled the kernels")
    assert "numba.np.arraymath" not in modules


def test_a_warm_generate_imports_neither_trimesh_nor_scipy_spatial(tmp_path):
    # The first process builds the family and its derived geometry into the cache; the
    # second loads them as arrays and casts its rays with Embree directly.
    generate = (
        "from affordgrasp.cli import main\n"
        "assert main(['generate', 'mug', '--samples', '2', '--workers', '1', '--out', {!r}]) == 0"
    )
    cache = {"AFFORDGRASP_CACHE_DIR": str(tmp_path / "cache")}
    cold = fresh_process_modules(generate.format(str(tmp_path / "a")), **cache)
    assert "trimesh" in cold
    warm = fresh_process_modules(generate.format(str(tmp_path / "b")), **cache)
    for name in ("trimesh", "scipy.spatial", "scipy.sparse", "pandas", "manifold3d"):
        assert name not in warm, name
