"""Objects: load, repair and scale meshes, mass properties, families (conventions: Objects).

The entry point is :func:`load_object`, which turns ``"knife"``, ``"knife:7"`` or a
mesh path into a :class:`GraspObject`. The procedural families (:func:`make_family`,
``FAMILIES``) are imported on first use. Rays are cast by :mod:`affordgrasp.rays`.
"""

from __future__ import annotations

from typing import Any

from affordgrasp.objects.loading import load_mesh, prepare_mesh
from affordgrasp.objects.mass import MassProperties, mass_properties, mass_properties_parts
from affordgrasp.objects.off import read_off
from affordgrasp.objects.resolve import (
    GraspObject,
    list_families,
    load_object,
    mesh_hash,
    object_from_mesh,
)

__all__ = [
    "FAMILIES",
    "GraspObject",
    "MassProperties",
    "list_families",
    "load_object",
    "load_mesh",
    "make_family",
    "mass_properties",
    "mass_properties_parts",
    "mesh_hash",
    "object_from_mesh",
    "prepare_mesh",
    "read_off",
]

# Served from objects.families on first access: building the family table is not needed
# to load a mesh file.
_FROM_FAMILIES = ("FAMILIES", "make_family")


def __getattr__(name: str) -> Any:
    if name in _FROM_FAMILIES:
        from affordgrasp.objects import families

        return getattr(families, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
