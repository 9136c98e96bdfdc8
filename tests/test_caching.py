"""One caching idiom: values derived from an object, keyed by identity (caching.py)."""

import gc

from affordgrasp.caching import IdentityCache


class Thing:
    def __init__(self, n):
        self.n = n


def test_built_once_per_object_and_version_and_dropped_with_it():
    cache = IdentityCache()
    builds = []
    things = {"a": Thing(1), "b": Thing(1)}

    def get(name, **kw):
        t = things[name]

        def build():
            builds.append(t.n)
            return t.n * 10

        return cache.get(t, build, **kw)

    assert get("a") == 10 and get("a") == 10
    assert builds == [1]  # cached
    assert get("b") == 10 and builds == [1, 1]  # an equal but other object
    things["a"].n = 2
    assert get("a", version=2) == 20 and builds == [1, 1, 2]  # a new version
    assert len(cache) == 2
    del things["a"]
    gc.collect()
    assert len(cache) == 1  # the entry went with its object
