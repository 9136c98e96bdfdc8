"""Mass properties of a closed mesh at a uniform density, or of parts (conventions: Objects).

Validated against known geometries: boxes, cylinders and spheres against their closed
forms, and the rigid-motion laws (translation moves the centre of mass only, a rotation R
maps the inertia to R I R^T), in ``tests/objects/test_mass.py``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from affordgrasp.errors import InputError, MeshError

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "MassProperties",
    "mass_properties",
    "mass_properties_parts",
    "material_mass_properties",
    "plane_regions",
    "regions_on_mesh",
]


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of an object in its mesh frame, SI units.

    Attributes
    ----------
    density : float
        kg/m^3 (1.0 by default, as in the paper).
    volume : float
        m^3.
    mass : float
        kg.
    center_of_mass : (3,) float ndarray
        m.
    inertia : (3, 3) float ndarray
        kg m^2, about the centre of mass, mesh-frame axes.
    r_max : float
        m, largest distance from the centre of mass to a mesh vertex.
    bounds : (2, 3) float ndarray
        m, axis-aligned bounding box (min row, max row).
    """

    density: float
    volume: float
    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    r_max: float
    bounds: np.ndarray


def mass_properties(mesh: trimesh.Trimesh, density: float = 1.0) -> MassProperties:
    """Mass properties of a closed, outward-oriented mesh at a uniform density.

    Integrals over the tetrahedra spanned by each triangle and the bounding-box centre
    (``trimesh.triangles.mass_properties``, validated against known geometries; the tests
    check boxes, cylinders and spheres against closed forms).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed and outward-oriented (as :func:`affordgrasp.objects.prepare_mesh` returns);
        vertices (n, 3) float in metres.
    density : float
        kg/m^3, finite and > 0.

    Returns
    -------
    MassProperties
        Inertia about the centre of mass in the mesh axes, products of inertia with their
        sign (I_xy = -∫ x y dm); arrays are read-only.
    """
    density = _check_density(density)
    volume, com, inertia_per_density = _unit_density_integrals(mesh, "mesh")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    return _make(
        density=density,
        volume=volume,
        mass=density * volume,
        center_of_mass=com,
        inertia=density * inertia_per_density,
        vertices=vertices,
    )


def mass_properties_parts(
    meshes: Sequence[trimesh.Trimesh], densities: Sequence[float]
) -> MassProperties:
    """Mass properties of an object made of parts of different densities.

    Each part is integrated on its own and the parts are combined with the parallel-axis
    theorem; the parts must not overlap (overlapping volume would be counted twice).

    Parameters
    ----------
    meshes : sequence of trimesh.Trimesh, length p >= 1
        Closed, outward-oriented parts in one common frame, metres.
    densities : sequence of float, length p
        kg/m^3 per part, each finite and > 0.

    Returns
    -------
    MassProperties
        ``density`` is the mean density, total mass / total volume; ``r_max`` and
        ``bounds`` cover the vertices of every part.
    """
    meshes = list(meshes)
    densities = list(densities)
    if not meshes:
        raise InputError("mass_properties_parts needs at least one part; got no meshes")
    if len(meshes) != len(densities):
        raise InputError(
            f"got {len(meshes)} meshes but {len(densities)} densities; pass one density per part"
        )
    masses, coms, inertias, volumes = [], [], [], []
    for i, (mesh, density) in enumerate(zip(meshes, densities, strict=True)):
        density = _check_density(density, f"densities[{i}]")
        volume, com, inertia_per_density = _unit_density_integrals(mesh, f"part {i}")
        volumes.append(volume)
        masses.append(density * volume)
        coms.append(com)
        inertias.append(density * inertia_per_density)
    mass_each = np.array(masses)
    com_each = np.array(coms)  # (p, 3)
    mass = float(mass_each.sum())
    com = (mass_each[:, None] * com_each).sum(axis=0) / mass
    # Parallel axis: I_c = I_i + m_i (|d|^2 E - d d^T), d from the common COM to part i's.
    d = com_each - com
    shift = np.einsum("p,pj,pj->p", mass_each, d, d)[:, None, None] * np.eye(3) - np.einsum(
        "p,pi,pj->pij", mass_each, d, d
    )
    inertia = (np.array(inertias) + shift).sum(axis=0)
    volume = float(sum(volumes))
    vertices = np.concatenate([np.asarray(m.vertices, dtype=np.float64) for m in meshes])
    return _make(
        density=mass / volume,
        volume=volume,
        mass=mass,
        center_of_mass=com,
        inertia=inertia,
        vertices=vertices,
    )


def material_mass_properties(
    mesh: trimesh.Trimesh, regions: Sequence[tuple[str, float, trimesh.Trimesh]]
) -> MassProperties:
    """Mass properties of an object whose volume is split into regions of materials.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The whole object (gives ``r_max`` and ``bounds``), m.
    regions : sequence of (material, density, trimesh.Trimesh)
        Disjoint closed regions whose union is ``mesh``, density in kg/m^3 (a built-in
        family's ``metadata["materials"]``).

    Returns
    -------
    MassProperties
        Combined as :func:`mass_properties_parts`; ``density`` is the mean density.

    Raises
    ------
    MeshError
        When the regions' volumes do not add up to the object's (within 0.5 %).
    """
    parts = mass_properties_parts([r[2] for r in regions], [r[1] for r in regions])
    volume, _, _ = _unit_density_integrals(mesh, "mesh")
    if abs(parts.volume - volume) > 5e-3 * volume:
        raise MeshError(
            f"material regions hold {parts.volume:.6g} m^3 of an object of {volume:.6g} m^3; "
            "they must split the object exactly"
        )
    return _make(
        density=parts.mass / volume,
        volume=volume,
        mass=parts.mass,
        center_of_mass=parts.center_of_mass,
        inertia=0.5 * (parts.inertia + parts.inertia.T),  # symmetric bit for bit
        vertices=np.asarray(mesh.vertices, dtype=np.float64),
    )


def _check_density(density: float, name: str = "density") -> float:
    try:
        value = float(density)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a finite number > 0 (kg/m^3), got {density!r}")
    return value


def _unit_density_integrals(
    mesh: trimesh.Trimesh, what: str
) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume, centre of mass (3,), inertia at unit density (3, 3)) of a closed mesh."""
    import trimesh

    if len(mesh.faces) == 0:
        raise MeshError(f"{what} has no faces; mass properties need a closed mesh")
    if not mesh.is_watertight:
        raise MeshError(
            f"{what} is not watertight, so it has no well-defined volume; pass it through "
            "affordgrasp.objects.prepare_mesh first"
        )
    # Integrate about the bounding-box centre: the inertia about the centre of mass does not
    # depend on the origin, and an object far from its mesh origin would otherwise lose
    # digits to cancellation (a 1.5 cm cube 5 m away: 1e-8 relative error).
    centre = np.asarray(mesh.bounds, dtype=np.float64).mean(axis=0)
    props = trimesh.triangles.mass_properties(
        np.asarray(mesh.triangles, dtype=np.float64) - centre, density=1.0
    )
    volume = float(props.volume)
    if not volume > 0:
        raise MeshError(
            f"{what} has volume {volume:.3g} m^3; it must be closed and outward-oriented "
            "(pass it through affordgrasp.objects.prepare_mesh first)"
        )
    com = np.asarray(props.center_mass, dtype=np.float64) + centre
    inertia = np.asarray(props.inertia, dtype=np.float64)
    # The integral is symmetric in exact arithmetic; make it symmetric bit for bit.
    return volume, com, 0.5 * (inertia + inertia.T)


def _make(
    *,
    density: float,
    volume: float,
    mass: float,
    center_of_mass: np.ndarray,
    inertia: np.ndarray,
    vertices: np.ndarray,
) -> MassProperties:
    center_of_mass = np.array(center_of_mass, dtype=np.float64)
    inertia = np.array(inertia, dtype=np.float64)
    bounds = np.array([vertices.min(axis=0), vertices.max(axis=0)])
    r_max = float(np.linalg.norm(vertices - center_of_mass, axis=1).max())
    for array in (center_of_mass, inertia, bounds):
        array.setflags(write=False)
    return MassProperties(
        density=float(density),
        volume=float(volume),
        mass=float(mass),
        center_of_mass=center_of_mass,
        inertia=inertia,
        r_max=r_max,
        bounds=bounds,
    )


def regions_on_mesh(
    mesh: trimesh.Trimesh, regions: Sequence[tuple[str, float, trimesh.Trimesh]]
) -> list[tuple[str, float, trimesh.Trimesh]]:
    """Material regions of a nearby geometry carried onto ``mesh`` (exact booleans).

    Each region but the largest becomes ``mesh`` ∩ region; the largest takes the rest of
    ``mesh``, so the regions split ``mesh`` exactly even where ``mesh`` bulges out of the
    regions' union (a scan-like copy's noise, 0.1-0.3 mm). Used to give a scan-like variant
    of a family its materials (:mod:`affordgrasp.objects.scan`).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed, outward-oriented, m.
    regions : sequence of (material, density, trimesh.Trimesh)
        Disjoint closed regions close to ``mesh`` (a family's ``metadata["materials"]``).

    Returns
    -------
    list of (material, density kg/m^3, trimesh.Trimesh)
        Disjoint, union ``mesh``; empty pieces are dropped.
    """
    import manifold3d

    from affordgrasp.objects.loading import _from_manifold, _op, _to_manifold

    regions = list(regions)
    if not regions:
        raise InputError("regions_on_mesh needs at least one region; got none")
    whole = _to_manifold(mesh)
    solids = [_to_manifold(r[2]) for r in regions]
    largest = int(np.argmax([s.volume() for s in solids]))
    out: list[tuple[str, float, trimesh.Trimesh]] = []
    taken = []
    for i, (name, density, _) in enumerate(regions):
        if i == largest:
            continue
        piece = manifold3d.Manifold.batch_boolean([whole, solids[i]], _op("Intersect"))
        if piece.volume() > 0:
            out.append((name, density, _from_manifold(piece)))
            taken.append(piece)
    rest = whole
    if taken:
        union = manifold3d.Manifold.batch_boolean(taken, _op("Add"))
        rest = manifold3d.Manifold.batch_boolean([whole, union], _op("Subtract"))
    out.append((regions[largest][0], regions[largest][1], _from_manifold(rest)))
    return out


def plane_regions(
    mesh: trimesh.Trimesh, density: float, planes: Sequence[tuple[str, float, object, object]]
) -> list[tuple[str, float, trimesh.Trimesh]]:
    """Split a closed mesh into regions of densities by cutting planes (exact booleans).

    Region i is the part of ``mesh`` on the side its plane's normal points to, less what
    the regions before it took; what no region takes has ``density``. How a user gives a
    mesh file a steel head and a wooden handle (``<mesh file>.materials.toml``,
    :func:`affordgrasp.objects.resolve.load_object`).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed, outward-oriented, m.
    density : float
        kg/m^3 of the rest.
    planes : sequence of (name, density kg/m^3, point (3,) m, normal (3,))
        The regions, in order of precedence.

    Returns
    -------
    list of (material, density kg/m^3, trimesh.Trimesh)
        Disjoint, union ``mesh``; empty pieces are dropped (argument to
        :func:`material_mass_properties`).
    """
    from affordgrasp.objects.loading import _from_manifold, _to_manifold

    rest = _to_manifold(mesh)
    out: list[tuple[str, float, trimesh.Trimesh]] = []
    for name, rho, point, normal in planes:
        rho = _check_density(rho, f"region {name!r}")
        n = np.asarray(normal, dtype=np.float64).reshape(3)
        p = np.asarray(point, dtype=np.float64).reshape(3)
        if not (np.all(np.isfinite(n)) and np.linalg.norm(n) > 0 and np.all(np.isfinite(p))):
            raise InputError(
                f"region {name!r} needs a finite plane point and a non-zero normal, got "
                f"point {p.tolist()} normal {n.tolist()}"
            )
        n = n / np.linalg.norm(n)
        piece, rest = rest.split_by_plane(n.tolist(), float(n @ p))
        if piece.volume() > 0:
            out.append((str(name), rho, _from_manifold(piece)))
    if rest.volume() > 0:
        out.append(("rest", _check_density(density), _from_manifold(rest)))
    return out
