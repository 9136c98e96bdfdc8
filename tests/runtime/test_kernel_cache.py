"""The numba caches of the metric kernels follow every source they inline (kernel_cache.py)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import affordgrasp.metrics  # noqa: F401 - installs the locator
from affordgrasp.metrics.epsilon import epsilon_kernel
from affordgrasp.runtime import kernel_cache


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


def test_a_failing_light_load_falls_back_to_numbas_own_loading(monkeypatch):
    # If an internal of numba the light loading calls breaks, numba's own loading takes
    # over for that kernel (and for the rest of the process): no failed start-up.
    from numba import njit
    from numba.core import caching

    from affordgrasp.metrics.cones import wrench_matrix_kernel

    rng = np.random.default_rng(3)
    points = rng.normal(size=(4, 3))
    normals = rng.normal(size=(4, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    args = (points, normals, np.full(4, 0.4), np.zeros(3), 1.0, False)
    expected = wrench_matrix_kernel(*args)  # loaded or compiled: in the disk cache now

    monkeypatch.setattr(kernel_cache._LightLoading, "enabled", True)
    monkeypatch.setattr(kernel_cache._LightLoading, "failure", None)
    real = caching.Cache._load_overload
    calls = []

    def fails_once(self, sig, target_context):
        calls.append(sig)
        if len(calls) == 1:
            raise RuntimeError("an internal of numba changed")
        return real(self, sig, target_context)

    monkeypatch.setattr(caching.Cache, "_load_overload", fails_once)
    fresh = njit(cache=True)(wrench_matrix_kernel.py_func)  # its first call reads the disk
    got = fresh(*args)
    assert len(calls) == 2  # the light load, then numba's own
    assert sum(fresh.stats.cache_hits.values()) == 1
    assert sum(fresh.stats.cache_misses.values()) == 0  # loaded, not compiled
    np.testing.assert_array_equal(got, expected)
    assert not kernel_cache._LightLoading.enabled
    assert "an internal of numba changed" in kernel_cache._LightLoading.failure

    again = njit(cache=True)(wrench_matrix_kernel.py_func)
    np.testing.assert_array_equal(again(*args), expected)
    assert len(calls) == 3  # numba's own loading only, from now on


@pytest.mark.parametrize("missing", range(4))
def test_light_loading_leaves_numba_alone_without_the_internals_it_needs(monkeypatch, missing):
    from numba.core import caching

    assert hasattr(caching.Cache.load_overload, "__wrapped__")  # installed at import
    monkeypatch.setattr(caching.Cache, "load_overload", caching.Cache.load_overload.__wrapped__)
    (locator_class,) = kernel_cache._installed
    owner, name = kernel_cache._light_loading_needs()[missing]
    for cls in (owner if isinstance(owner, type) else type(owner)).__mro__:
        if name in vars(cls):
            monkeypatch.delattr(cls, name)
    assert not hasattr(owner, name)
    before = caching.Cache.__dict__.get("load_overload")
    assert kernel_cache._install_light_loading(locator_class) is False
    assert caching.Cache.__dict__.get("load_overload") is before


def test_light_loading_installs_with_the_internals_it_needs(monkeypatch):
    from numba.core import caching

    numba_own = caching.Cache.load_overload.__wrapped__
    monkeypatch.setattr(caching.Cache, "load_overload", numba_own)
    (locator_class,) = kernel_cache._installed
    assert kernel_cache._install_light_loading(locator_class) is True
    assert caching.Cache.load_overload.__wrapped__ is numba_own
