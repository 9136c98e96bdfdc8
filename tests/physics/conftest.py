"""Fixtures of the physics tests: a private decomposition cache and small objects."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("coacd")


@pytest.fixture(scope="session", autouse=True)
def private_cache(tmp_path_factory):
    """Every test writes decompositions to a per-session temporary cache, never ~/.cache."""
    import os

    cache = tmp_path_factory.mktemp("affordgrasp-cache")
    before = os.environ.get("AFFORDGRASP_CACHE_DIR")
    os.environ["AFFORDGRASP_CACHE_DIR"] = str(cache)
    yield cache
    if before is None:
        del os.environ["AFFORDGRASP_CACHE_DIR"]
    else:
        os.environ["AFFORDGRASP_CACHE_DIR"] = before


def make_object(mesh, name="box"):
    from affordgrasp.objects import GraspObject, mass_properties, mesh_hash

    return GraspObject(name, "mesh", mesh, mass_properties(mesh), mesh_hash(mesh), "test")


@pytest.fixture(scope="session")
def box_object():
    """A 40 x 40 x 60 mm box centred at its origin, long side along z."""
    import trimesh

    return make_object(trimesh.creation.box([0.04, 0.04, 0.06]))
