"""What each part of a procedural family is made of, and the densities of those materials.

With ``load_object(spec, materials=True)`` (``--materials`` on the command line) a
family's mass properties (centre of mass, inertia) follow its materials: a hammer is a
steel head on a wooden handle, so its centre of mass lies near the head, as in the real
tool. The default stays the paper's uniform unit density. Densities are typical
handbook values at room temperature, kg/m³:

==========  ======  ==============================================================
material    ρ       what
==========  ======  ==============================================================
steel       7850    carbon and stainless tool steel (7750-8050)
wood        650     handle hardwoods, ash and hickory, air-dry (600-800)
plastic     1200    handle plastics: polypropylene 900 to POM 1410, ABS 1050
glass       2500    soda-lime glass
ceramic     2400    stoneware and porcelain mugs (2300-2500)
wafer       500     baked wafer of an ice-cream cone (a 12 g cone of about 25 cm³)
==========  ======  ==============================================================

Each family names a material per tagged piece (:data:`FAMILY_MATERIALS`); a piece the
table does not name, and volume no tagged piece covers, is the family's ``"*"`` material.
Where pieces of different materials overlap (a blade's tang inside its handle), the denser
material takes the volume.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import manifold3d

__all__ = ["DENSITY_KG_M3", "FAMILY_MATERIALS", "material_of", "material_regions"]

DENSITY_KG_M3: dict[str, float] = {
    "steel": 7850.0,
    "wood": 650.0,
    "plastic": 1200.0,
    "glass": 2500.0,
    "ceramic": 2400.0,
    "wafer": 500.0,
}

_MIN_VOLUME_M3 = 1e-10  # 0.1 mm³: smaller regions are boolean round-off, not parts

_STEEL_TOOL = {"blade": "steel", "head": "steel", "claw": "steel", "peen": "steel"}
_HILTED_BLADE = {
    "blade": "steel",
    "guard": "steel",
    "pommel": "steel",
    "handle": "wood",
    "*": "steel",
}

# family -> {tagged piece: material}; "*" is the material of everything else
FAMILY_MATERIALS: dict[str, Mapping[str, str]] = {
    "hammer": {**_STEEL_TOOL, "handle": "wood", "*": "steel"},
    "axe": {**_STEEL_TOOL, "handle": "wood", "*": "steel"},
    "knife": {"blade": "steel", "handle": "plastic", "*": "steel"},
    "meat_cleaver": {"blade": "steel", "handle": "wood", "*": "steel"},
    "sword": _HILTED_BLADE,
    "dagger": _HILTED_BLADE,
    "screwdriver": {"shaft": "steel", "handle": "plastic", "*": "steel"},
    "spatula": {"blade": "steel", "shaft": "steel", "handle": "plastic", "*": "steel"},
    "bottle": {"*": "glass"},
    "wine_glass": {"*": "glass"},
    "tumbler": {"*": "glass"},
    "mug": {"*": "ceramic"},
    "ice_cream_cone": {"*": "wafer"},
}


def material_of(family: str, piece: str) -> str:
    """Material of a tagged piece of a family (the family's ``"*"`` material by default).

    Parameters
    ----------
    family : str
        Canonical family name.
    piece : str
        A part name the family's builder tagged (:data:`~.parts.PART_NAMES`).

    Returns
    -------
    str
        A key of :data:`DENSITY_KG_M3`.
    """
    table = FAMILY_MATERIALS[family]
    return table.get(piece, table["*"])


def material_regions(
    family: str, solid: manifold3d.Manifold, pieces: Sequence[tuple[str, manifold3d.Manifold]]
) -> list[tuple[str, manifold3d.Manifold]]:
    """Split a family's solid into one region per material (exact booleans).

    Parameters
    ----------
    family : str
        Canonical family name.
    solid : manifold3d.Manifold
        The finished object.
    pieces : sequence of (part, Manifold)
        The tagged pieces (:class:`~.parts.Recorder`), in the solid's frame.

    Returns
    -------
    list of (material, Manifold)
        Non-empty, disjoint regions whose union is ``solid``: denser materials first, each
        the union of its pieces within the solid minus the denser regions; the family's
        ``"*"`` material also takes what no piece covers.
    """
    by_material: dict[str, list[manifold3d.Manifold]] = {}
    for part, piece in pieces:
        by_material.setdefault(material_of(family, part), []).append(piece)
    default = FAMILY_MATERIALS[family]["*"]
    by_material.setdefault(default, [])
    order = sorted(by_material, key=lambda m: -DENSITY_KG_M3[m])
    regions: list[tuple[str, manifold3d.Manifold]] = []
    taken: manifold3d.Manifold | None = None
    for material in order:
        if material == default:
            continue
        region = (
            manifold3d.Manifold.batch_boolean(by_material[material], manifold3d.OpType.Add) ^ solid
        )
        if taken is not None:
            region = region - taken
        if region.volume() > _MIN_VOLUME_M3:
            regions.append((material, region))
            taken = region if taken is None else taken + region
    rest = solid if taken is None else solid - taken
    if rest.volume() > _MIN_VOLUME_M3:
        regions.append((default, rest))
    return regions
