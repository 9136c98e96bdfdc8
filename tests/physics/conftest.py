"""Fixtures of the physics tests: small objects (the private cache is tests/conftest.py's)."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("coacd")


def make_object(mesh, name="box"):
    from affordgrasp.objects import GraspObject, mass_properties, mesh_hash

    return GraspObject(name, "mesh", mesh, mass_properties(mesh), mesh_hash(mesh), "test")


@pytest.fixture(scope="session")
def box_object():
    """A 40 x 40 x 60 mm box centred at its origin, long side along z."""
    import trimesh

    return make_object(trimesh.creation.box([0.04, 0.04, 0.06]))
