"""Test-wide settings (property tests reproducible in CI) and fixtures shared by several folders."""

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture(scope="session")
def box_mesh(tmp_path_factory):
    """A 12 x 4 x 3 cm box as an STL file."""
    import trimesh

    path = tmp_path_factory.mktemp("meshes") / "box.stl"
    trimesh.creation.box([0.12, 0.04, 0.03]).export(path)
    return path
