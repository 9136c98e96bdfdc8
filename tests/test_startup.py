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

import affordgrasp

# The folder that holds the package under test (site-packages for an installed copy, whose
# kernels ship compiled; src/ in a checkout), so that a fresh process imports the same copy.
SRC = str(Path(affordgrasp.__file__).resolve().parents[1])


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


LOAD_AND_RUN_THE_KERNELS = """
import hashlib, json
from affordgrasp import kernels as compiled
from affordgrasp.runtime import kernel_cache
from affordgrasp.objects import load_object
from affordgrasp.pipeline import evaluate_samples
kernel_cache._LightLoading.enabled = {light}
load = compiled.warm_up()  # loads every kernel of the pipeline and runs it
rows = evaluate_samples(load_object("tumbler"), 6, seed=0).table.to_pylist()
print(json.dumps({{
    "compiled": load.compiled,
    "light_loads": kernel_cache._LightLoading.loads,
    "failure": kernel_cache._LightLoading.failure,
    "hits": {{
        d.py_func.__name__: sum(d.stats.cache_hits.values()) for d in compiled._dispatchers()
    }},
    "rows": hashlib.sha256(json.dumps(rows, sort_keys=True, default=str).encode()).hexdigest(),
    "n": len(rows),
}}))
"""


def run_fresh(code: str) -> list[str]:
    """Lines a fresh interpreter prints running ``code`` (the session's private cache)."""
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=False,
        env={
            "PYTHONPATH": SRC,
            "PATH": "/usr/bin:/bin",
            "AFFORDGRASP_CACHE_DIR": os.environ["AFFORDGRASP_CACHE_DIR"],
        },
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip().splitlines()


def load_and_run_the_kernels(light: bool) -> tuple[dict, set[str]]:
    code = LOAD_AND_RUN_THE_KERNELS.format(light=light)
    lines = run_fresh(code + "\nimport sys; print(json.dumps(sorted(sys.modules)))")
    report, modules = lines[-2:]
    return json.loads(report), set(json.loads(modules))


def test_kernels_load_from_the_cache_without_numba_compiler_registries_and_run_right():
    # numba's own cache loading first imports every typing and lowering registry (~0.2 s);
    # the package's kernels load without them, and every kernel of the pipeline then runs
    # and gives what the same kernels give when numba loads them its own way.
    light, modules = load_and_run_the_kernels(light=True)
    if light["compiled"]:  # a stale kernel cache: this process compiled and saved it
        light, modules = load_and_run_the_kernels(light=True)
    if light["compiled"]:
        pytest.skip("the kernel cache could not be written: nothing loads from it")
    assert light["failure"] is None
    for name, hits in light["hits"].items():
        assert hits > 0, name  # loaded from the cache...
    assert light["light_loads"] >= len(light["hits"])  # ...the light way
    assert "numba.np.arraymath" not in modules
    numba_own, modules = load_and_run_the_kernels(light=False)
    assert numba_own["light_loads"] == 0
    assert "numba.np.arraymath" in modules  # numba's loading does import its registries
    assert light["n"] == numba_own["n"] == 6
    assert light["rows"] == numba_own["rows"]


LINK_AGAINST_A_LIGHT_LOADED_KERNEL = """
import json, numba, numpy as np
from affordgrasp import kernels as compiled
from affordgrasp.hands.kinematics import shape_poses
from affordgrasp.runtime import kernel_cache
load = compiled.warm_up()
(overload,) = shape_poses.overloads.values()
parsed_before = overload.library._shared_module is not None

@numba.njit
def user_function(links, shape_link, shape_local):  # compiled now, against the cached kernel
    return shape_poses(links, shape_link, shape_local)

rng = np.random.default_rng(0)
links = rng.normal(size=(3, 4, 4))
shape_link = np.array([2, 0, 0, 1])
shape_local = rng.normal(size=(4, 4, 4))
print(json.dumps({{
    "compiled": load.compiled,
    "light_loads": kernel_cache._LightLoading.loads,
    "failure": kernel_cache._LightLoading.failure,
    "parsed_before": parsed_before,
    "error": float(np.abs(
        user_function(links, shape_link, shape_local) - links[shape_link] @ shape_local
    ).max()),
    "overloads": len(shape_poses.overloads),
    "parsed_after": overload.library._shared_module is not None,
}}))
"""


def test_a_function_compiled_later_links_against_a_kernel_loaded_without_its_bitcode():
    # The light loading parses a kernel's LLVM bitcode only when a new function is compiled
    # against it: a user's njit function calling a package kernel compiles, links and agrees.
    report = json.loads(run_fresh(LINK_AGAINST_A_LIGHT_LOADED_KERNEL.format())[-1])
    if report["compiled"]:  # a stale kernel cache: this process compiled and saved it
        report = json.loads(run_fresh(LINK_AGAINST_A_LIGHT_LOADED_KERNEL.format())[-1])
    if report["compiled"]:
        pytest.skip("the kernel cache could not be written: nothing loads from it")
    assert report["failure"] is None and report["light_loads"] > 0
    assert not report["parsed_before"]  # loaded without its bitcode...
    assert report["overloads"] == 1  # ...the user's function used that same overload...
    assert report["parsed_after"]  # ...whose bitcode was parsed to link it...
    assert report["error"] < 1e-12  # ...and gives the right poses


# Never on generate's path, cold or warm (pandas and scipy.stats cost a second of imports).
NEVER_IMPORTED = ("pandas", "scipy.stats")
# Not on a warm generate's path (the object and its derived geometry come from the cache).
NOT_WHEN_WARM = ("trimesh", "scipy.spatial", "scipy.sparse", "manifold3d", *NEVER_IMPORTED)


def test_a_warm_generate_imports_neither_trimesh_nor_scipy_spatial(tmp_path):
    # The first process builds the family and its derived geometry into the cache; the
    # second loads them as arrays and casts its rays with Embree directly. Neither imports
    # pandas or scipy.stats.
    generate = (
        "from affordgrasp.cli import main\n"
        "assert main(['generate', 'mug', '--samples', '2', '--workers', '1', '--out', {!r}]) == 0"
    )
    cache = {"AFFORDGRASP_CACHE_DIR": str(tmp_path / "cache")}
    cold = fresh_process_modules(generate.format(str(tmp_path / "a")), **cache)
    assert "trimesh" in cold
    for name in NEVER_IMPORTED:
        assert name not in cold, name
    warm = fresh_process_modules(generate.format(str(tmp_path / "b")), **cache)
    for name in NOT_WHEN_WARM:
        assert name not in warm, name


@pytest.mark.parametrize("suffix", [".stl"])  # .obj, .ply: the same path after the read
def test_a_warm_generate_on_a_mesh_file_imports_neither_trimesh_nor_scipy_spatial(tmp_path, suffix):
    # The first process reads and repairs the file into the cache (keyed by its bytes); the
    # second loads the arrays as it does for a built-in family.
    import trimesh

    path = tmp_path / f"block{suffix}"
    trimesh.creation.box((0.03, 0.05, 0.11)).export(path)
    generate = (
        "from affordgrasp.cli import main\n"
        f"assert main(['generate', {str(path)!r}, '--samples', '2', '--workers', '1', "
        "'--out', {!r}]) == 0"
    )
    cache = {"AFFORDGRASP_CACHE_DIR": str(tmp_path / "cache")}
    cold = fresh_process_modules(generate.format(str(tmp_path / "a")), **cache)
    assert "trimesh" in cold
    warm = fresh_process_modules(generate.format(str(tmp_path / "b")), **cache)
    for name in NOT_WHEN_WARM:
        assert name not in warm, name
