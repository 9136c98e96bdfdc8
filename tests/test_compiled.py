"""Kernels ready up front, caches valid after an install (compiled.py, kernel_cache.py)."""

import os
import shutil

from affordgrasp import compiled
from affordgrasp.grasp import kernels
from affordgrasp.metrics import kernel_cache
from affordgrasp.vision import render_depth


def test_warm_up_runs_every_pipeline_kernel_and_reports_what_it_cost():
    compiled.warm_up()
    again = compiled.warm_up()  # everything is in memory now: nothing compiles
    assert not again.compiled
    assert again.seconds < 30
    assert "loaded from cache" in again.describe()
    for dispatcher in compiled._dispatchers():
        assert dispatcher.signatures, dispatcher.py_func.__name__


def test_warm_up_with_vision_also_makes_the_rasteriser_ready():
    compiled.warm_up(vision=True)
    again = compiled.warm_up(vision=True)
    assert not again.compiled
    for dispatcher in compiled._vision_dispatchers():
        assert dispatcher.signatures, dispatcher.py_func.__name__
    # the signature warmed up is the one a depth render calls: rendering compiles nothing
    (rasterise,) = compiled._vision_dispatchers()
    misses = sum(rasterise.stats.cache_misses.values())
    signatures = list(rasterise.signatures)
    render_depth("knife", [[0.3, 0.1, -0.4, 0.2, -0.5, 0.7]])
    assert sum(rasterise.stats.cache_misses.values()) == misses
    assert list(rasterise.signatures) == signatures


def test_building_the_package_warms_the_vision_kernels_up(monkeypatch):
    calls = []
    monkeypatch.setattr(compiled, "warm_up", lambda **kw: calls.append(kw) or LOADED)
    compiled.main()
    assert calls == [{"vision": True}]


LOADED = compiled.KernelLoad(0.5, False)


def test_cache_stamp_depends_on_contents_not_modification_times(tmp_path):
    # An install copies the sources with new modification times; caches built with the
    # wheel must stay valid, and an edited kernel must invalidate them.
    a = tmp_path / "a" / "grasp"
    a.mkdir(parents=True)
    shutil.copy(kernels.__file__, a / "kernels.py")
    stamp = kernel_cache.package_stamp.__wrapped__(tmp_path / "a")
    os.utime(a / "kernels.py", (1, 1))
    assert kernel_cache.package_stamp.__wrapped__(tmp_path / "a") == stamp
    (a / "kernels.py").write_text((a / "kernels.py").read_text() + "\n# edited\n")
    assert kernel_cache.package_stamp.__wrapped__(tmp_path / "a") != stamp


def test_every_kernel_of_the_package_uses_the_content_stamp():
    (locator_class,) = kernel_cache._installed
    func = kernels.approach_until_contact.py_func
    locator = locator_class.from_function(func, func.__code__.co_filename)
    assert locator is not None
    assert locator.get_source_stamp() == ("affordgrasp-kernels", kernel_cache.package_stamp())
