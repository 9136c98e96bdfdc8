"""Names, aliases and categories of the built-in families, without building anything.

Resolving a spec such as ``knife:7`` needs only these; the builders in
:mod:`affordgrasp.objects.families` (manifold3d, trimesh, scipy) are imported when a family
is actually built, which a warm start with the prepared-object cache never does
(:mod:`affordgrasp.objects.prepared`). ``tests/objects/test_families.py`` checks that this
table and the builders' agree.
"""

from __future__ import annotations

__all__ = ["ALIASES", "CATEGORIES"]

CATEGORIES: dict[str, str] = {
    "hammer": "hammer",
    "knife": "knife",
    "meat_cleaver": "knife",
    "axe": "axe",
    "screwdriver": "screwdriver",
    "spatula": "spatula",
    "sword": "sword",
    "dagger": "knife",
    "bottle": "container",
    "wine_glass": "container",
    "tumbler": "container",
    "mug": "container",
    "ice_cream_cone": "container",
}
"""Canonical family name -> category label, in the families' order."""

ALIASES: dict[str, str] = {
    "cleaver": "meat_cleaver",
    "hatchet": "axe",
    "wineglass": "wine_glass",
    "glass": "tumbler",
    "cone": "ice_cream_cone",
    "ice_cream": "ice_cream_cone",
    "turner": "spatula",
}
"""Other names accepted for a family."""
