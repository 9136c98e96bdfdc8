import pytest
import trimesh
from grasp_support import as_object


@pytest.fixture(scope="session")
def box_object():
    return as_object(trimesh.creation.box((0.05, 0.05, 0.2)), "box")
