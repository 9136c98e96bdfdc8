"""The numba caches of the metric kernels follow every source they inline (kernel_cache.py)."""

import os
import subprocess
import sys
from pathlib import Path

import affordgrasp.metrics  # noqa: F401 - installs the locator
from affordgrasp.metrics import kernel_cache
from affordgrasp.metrics.epsilon import epsilon_kernel


def test_stamp_follows_every_kernel_source(tmp_path):
    (tmp_path / "hull.py").write_text("@njit(cache=True)\ndef f(): pass\n")
    (tmp_path / "epsilon.py").write_text("@njit(cache=True)\ndef g(): pass\n")
    (tmp_path / "plain.py").write_text("def h(): pass\n")
    before = kernel_cache.package_stamp.__wrapped__(tmp_path)
    (tmp_path / "plain.py").write_text("def h(): return 1\n")  # no kernel: same stamp
    assert kernel_cache.package_stamp.__wrapped__(tmp_path) == before
    (tmp_path / "hull.py").write_text("@njit(cache=True)\ndef f(): return 1\n")
    assert kernel_cache.package_stamp.__wrapped__(tmp_path) != before


def test_package_kernels_carry_the_package_stamp():
    (locator_class,) = kernel_cache._installed
    func = epsilon_kernel.py_func
    locator = locator_class.from_function(func, func.__code__.co_filename)
    assert locator is not None
    numba_stamp, package = locator.get_source_stamp()
    assert package == kernel_cache.package_stamp()
    assert locator_class.from_function(test_stamp_follows_every_kernel_source, __file__) is None


def test_import_deletes_no_cache_file(tmp_path):
    # A cache file of a metrics module under NUMBA_CACHE_DIR (numba mirrors the source tree
    # there). Importing the package used to delete such files; now it must leave them.
    package_dir = Path(kernel_cache.__file__).resolve().parent
    mirror = tmp_path / package_dir.relative_to(package_dir.anchor)
    mirror.mkdir(parents=True)
    planted = mirror / "hull.convex_hull_6d-1.py311.nbi"
    planted.write_bytes(b"x")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    src = str(package_dir.parents[1])
    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    subprocess.run([sys.executable, "-c", "import affordgrasp.metrics"], env=env, check=True)
    assert planted.read_bytes() == b"x"
