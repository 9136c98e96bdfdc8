"""Procedural tool and object families (conventions: Objects): seeded, watertight, in metres.

The benchmark meshes of the paper cannot be redistributed, so these families give an
unlimited supply of train/validation/test objects, split by instance (seed).  Each family is
parametric: ``make_family(name, seed)`` draws the family's parameters (lengths, widths,
proportions, handle shape, ...) with ``numpy.random.default_rng(seed)`` within realistic
ranges; seed 0 is the typical instance, with every parameter at its typical value.  The same
seed always gives the same vertex and face bytes.

Every mesh is a single closed, consistently outward-oriented volume built with exact
booleans (manifold3d) and has between 1k and 30k triangles.  Thin parts are really thin:
blades are swept wedge sections whose cutting edge is a line of mesh edges with an
inclusive angle of 14-26 degrees; containers are hollow with 1.5-4 mm walls and open tops.

Mesh frame, shared by every family (metres):

* the origin is the centre of the axis-aligned bounding box;
* elongated tools lie along x, handle towards -x, working end (head, blade tip, screwdriver
  tip, spatula blade) towards +x;
* blades lie in the x-y plane with thickness along z (symmetric about z = 0 for knives,
  cleavers, daggers, swords, axes); a single cutting edge faces -y (knife, meat cleaver,
  axe); double-edged blades (dagger, sword) have edges facing -y and +y; the spatula's
  chisel edge is its front, facing +x;
* hammer and axe heads extend along y with the working side towards -y (hammer striking
  face, axe edge) and the back towards +y (claw or peen, poll);
* containers stand upright: axis along +z, opening at +z; the mug's handle points to +x.

Category labels (``FamilyInfo.category``), semantic classes shared across families so that
splits by instance still have overlapping categories: ``"knife"`` (knife, meat_cleaver,
dagger), ``"sword"``, ``"axe"``, ``"hammer"``, ``"screwdriver"``, ``"spatula"`` and
``"container"`` (bottle, wine_glass, tumbler, mug, ice_cream_cone).

Validated against known geometries: the construction primitives are checked against the
closed-form volumes of swept boxes and lathed cylinders in ``tests/objects/test_families.py``,
which also proves every family's size ranges, watertightness, edge angles and hollowness.
"""

from __future__ import annotations

import logging
import numbers
from collections.abc import Callable
from dataclasses import dataclass

import manifold3d
import numpy as np
import trimesh

from affordgrasp.errors import InputError
from affordgrasp.objects import family_names
from affordgrasp.objects.families import blades, containers, handtools, materials, parts, striking
from affordgrasp.objects.families.geometry import to_trimesh
from affordgrasp.objects.families.parameters import ParameterDraw

__all__ = ["FamilyInfo", "FAMILIES", "CATEGORIES", "ALIASES", "make_family"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class FamilyInfo:
    """What a procedural family is.

    Attributes
    ----------
    name : str
        Canonical family name, e.g. ``"knife"``.
    category : str
        Semantic label, one of :data:`CATEGORIES`.
    description : str
        One line, with the typical real size.
    """

    name: str
    category: str
    description: str


CATEGORIES: tuple[str, ...] = (
    "knife",
    "sword",
    "axe",
    "hammer",
    "screwdriver",
    "spatula",
    "container",
)

_BUILDERS: dict[str, tuple[str, str, Callable[[ParameterDraw], manifold3d.Manifold]]] = {
    "hammer": (
        "hammer",
        "claw or ball-peen hammer, 0.26-0.34 m long, head 0.09-0.13 m",
        striking.hammer,
    ),
    "knife": (
        "knife",
        "kitchen knife (chef's to utility), 0.20-0.33 m long, 1.5-2.5 mm spine",
        blades.knife,
    ),
    "meat_cleaver": (
        "knife",
        "meat cleaver, 0.27-0.35 m long, blade 75-110 mm tall, 3-5 mm spine",
        blades.meat_cleaver,
    ),
    "axe": ("axe", "hatchet to camp axe, 0.36-0.70 m long, bearded head 0.11-0.16 m", striking.axe),
    "screwdriver": (
        "screwdriver",
        "slotted or Phillips screwdriver, 0.15-0.30 m long, fluted handle",
        handtools.screwdriver,
    ),
    "spatula": (
        "spatula",
        "slotted kitchen turner, 0.25-0.35 m long, blade 64-88 mm wide",
        handtools.spatula,
    ),
    "sword": ("sword", "double-edged arming sword, 0.70-1.00 m long", blades.sword),
    "dagger": ("knife", "double-edged dagger, 0.22-0.35 m long", blades.dagger),
    "bottle": (
        "container",
        "glass bottle with punt, 0.20-0.32 m tall, 60-84 mm across",
        containers.bottle,
    ),
    "wine_glass": (
        "container",
        "stemmed wine glass, 0.15-0.22 m tall, bowl 70-96 mm across",
        containers.wine_glass,
    ),
    "tumbler": (
        "container",
        "straight-sided drinking glass, 0.08-0.15 m tall, 66-86 mm across",
        containers.tumbler,
    ),
    "mug": (
        "container",
        "coffee mug with loop handle, 90-110 mm tall, 75-90 mm across",
        containers.mug,
    ),
    "ice_cream_cone": (
        "container",
        "hollow wafer cone, 0.10-0.15 m tall, 45-64 mm across",
        containers.ice_cream_cone,
    ),
}

FAMILIES: dict[str, FamilyInfo] = {
    name: FamilyInfo(name=name, category=category, description=description)
    for name, (category, description, _) in _BUILDERS.items()
}

ALIASES: dict[str, str] = dict(family_names.ALIASES)

# Boolean seams leave a few sub-micrometre sliver triangles; simplifying at 1 um removes
# them while moving no surface by more than that.
_CLEAN_TOLERANCE_M = 1e-6


def _canonical(name: object) -> str:
    if not isinstance(name, str):
        raise InputError(
            f"family name must be a string, got {type(name).__name__} {name!r}; "
            f"available families: {', '.join(FAMILIES)}"
        )
    key = name.strip().lower().replace("-", "_").replace(" ", "_")
    key = ALIASES.get(key, key)
    if key not in FAMILIES:
        raise InputError(
            f"unknown object family {name!r}; available families: {', '.join(FAMILIES)}"
            f" (aliases: {', '.join(sorted(ALIASES))})"
        )
    return key


def _check_seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise InputError(
            f"family seed must be a non-negative integer, got {type(seed).__name__} {seed!r}"
        )
    if seed < 0:
        raise InputError(f"family seed must be a non-negative integer, got {seed}")
    return int(seed)


def make_family(name: str, seed: int = 0, *, materials: bool = False) -> trimesh.Trimesh:
    """Build one instance of a procedural family.

    Parameters
    ----------
    name : str
        A family name from :func:`affordgrasp.list_families` (or an alias, ``"cleaver"``).
    seed : int
        Non-negative; 0 is the family's typical instance.
    materials : bool
        Also split the solid into its material regions (exact booleans, about a third of
        the build time): only needed for per-part mass properties.

    Returns
    -------
    trimesh.Trimesh
        Watertight, in metres, in the frame described in this module's docstring, with
        ``metadata`` keys ``family``, ``category``, ``seed``, ``params`` (the parameter
        values drawn, SI units as their names say), ``face_parts`` ((n_faces,) int8, each
        face's semantic part), ``part_names`` (the names those indices refer to,
        :data:`~affordgrasp.objects.families.parts.PART_NAMES`) and, with ``materials=True``,
        ``materials`` (a list of ``(material, density kg/m³, closed trimesh)``: disjoint
        regions whose union is the mesh, :mod:`~affordgrasp.objects.families.materials`).

    Raises
    ------
    InputError
        For an unknown name or a bad seed.
    """
    key = _canonical(name)
    seed = _check_seed(seed)
    category, _, build = _BUILDERS[key]
    draw = ParameterDraw(seed)
    with parts.recording() as recorder:
        solid = build(draw).simplify(_CLEAN_TOLERANCE_M)
    mesh = to_trimesh(solid)
    face_parts = parts.refine_parts(
        key, mesh, parts.face_parts_of(solid, recorder), dict(draw.values)
    )
    mesh.metadata.update(
        {
            "family": key,
            "category": category,
            "seed": seed,
            "params": dict(draw.values),
            "face_parts": face_parts,
            "part_names": parts.PART_NAMES,
        }
    )
    if materials:
        mesh.metadata["materials"] = _material_regions(key, solid, recorder.pieces)
    logger.debug("built %s:%d with %d triangles", key, seed, len(mesh.faces))
    return mesh


def _material_regions(key: str, solid, pieces) -> list:
    """``(material, density kg/m³, closed trimesh)`` regions in the mesh frame."""
    # the mesh frame's origin is the bounding-box centre: move the regions with it
    offset = np.asarray(to_trimesh(solid, center=False).bounds).mean(axis=0)
    regions = []
    for material, region in materials.material_regions(key, solid, pieces):
        region_mesh = to_trimesh(region, center=False)
        region_mesh.apply_translation(-offset)
        regions.append((material, materials.DENSITY_KG_M3[material], region_mesh))
    return regions
