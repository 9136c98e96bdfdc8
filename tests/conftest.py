"""Test-wide settings (property tests reproducible in CI) and fixtures shared by several folders."""

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture(scope="session", autouse=True)
def private_cache(tmp_path_factory):
    """The tests write prepared objects (and decompositions) to a per-session cache, never
    to the user's ~/.cache."""
    cache = tmp_path_factory.mktemp("affordgrasp-cache")
    before = os.environ.get("AFFORDGRASP_CACHE_DIR")
    os.environ["AFFORDGRASP_CACHE_DIR"] = str(cache)
    yield cache
    if before is None:
        del os.environ["AFFORDGRASP_CACHE_DIR"]
    else:
        os.environ["AFFORDGRASP_CACHE_DIR"] = before


@pytest.fixture(scope="session")
def box_mesh(tmp_path_factory):
    """A 12 x 4 x 3 cm box as an STL file."""
    import trimesh

    path = tmp_path_factory.mktemp("meshes") / "box.stl"
    trimesh.creation.box([0.12, 0.04, 0.03]).export(path)
    return path
