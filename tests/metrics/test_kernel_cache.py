"""Stale numba caches of the metric kernels are dropped when a source changes (kernel_cache.py)."""

import json

from affordgrasp.metrics import kernel_cache


def test_cache_files_are_dropped_only_when_sources_change(tmp_path, monkeypatch):
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    files = ["hull.convex_hull_6d-1.py311.nbi", "hull.convex_hull_6d-1.py311.1.nbc"]
    other = cache / "somewhere_else.f-1.py311.nbi"  # not a metrics module: kept
    for name in files:
        (cache / name).write_bytes(b"x")
    other.write_bytes(b"x")
    sources = {"hull.py": [1, 10], "epsilon.py": [2, 20]}
    monkeypatch.setattr(kernel_cache, "_cache_dirs", lambda: [cache])
    monkeypatch.setattr(kernel_cache, "_fingerprint", lambda: dict(sources))

    kernel_cache.invalidate_stale_kernel_caches()  # no stamp yet: drop everything
    assert not any((cache / n).exists() for n in files) and other.exists()
    assert json.loads((cache / kernel_cache._STAMP_NAME).read_text()) == sources

    for name in files:
        (cache / name).write_bytes(b"x")
    kernel_cache.invalidate_stale_kernel_caches()  # unchanged sources: keep
    assert all((cache / n).exists() for n in files)

    sources["hull.py"] = [3, 11]
    kernel_cache.invalidate_stale_kernel_caches()  # an edit: drop again
    assert not any((cache / n).exists() for n in files)
