"""Turn an object spec into a ready object: mesh, mass properties, identity (conventions: Objects).

Spec grammar, as on the command line:

* ``knife`` — a built-in family, seed 0 (the same as ``knife:0``);
* ``knife:7`` — a family variant, the seed a non-negative integer;
* ``path/to/mesh.off`` — a mesh file (see :func:`affordgrasp.objects.load_mesh`);
* a mesh file may have region densities beside it, ``<file>.materials.toml`` (a steel head
  cut off by a plane; see :func:`_with_region_densities`);
* any of these followed by ``~scan`` or ``~scan:K`` — its scan-like variant
  (:mod:`affordgrasp.objects.scan`), degraded with seed K (default: the family's seed, 0
  for a file).

Family names win over a file of the same name in the working directory; write
``./knife`` for the file.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from affordgrasp.errors import InputError, did_you_mean
from affordgrasp.objects import family_names
from affordgrasp.objects.loading import (
    SUPPORTED_EXTENSIONS,
    _scale_request,
    load_mesh,
    prepare_mesh,
    recording_warnings,
)
from affordgrasp.objects.mass import (
    MassProperties,
    _check_density,
    mass_properties,
    material_mass_properties,
    plane_regions,
    regions_on_mesh,
)
from affordgrasp.objects.prepared import TRANSIENT_SOURCE, MeshData, mesh_hash
from affordgrasp.objects.scan import SCAN_SUFFIX, scan_like, split_scan_spec
from affordgrasp.objects.simplify import LARGE_MESH_FACES
from affordgrasp.rays.mesh import mesh_caster

if TYPE_CHECKING:
    import trimesh

__all__ = ["GraspObject", "is_family_spec", "list_families", "load_object", "mesh_hash"]

# Family objects are cached: building and repairing one can take a while, and the pipeline
# asks for the same object again and again.
_FAMILY_CACHE_SIZE = 64


class _MeshField:
    """The ``mesh`` of a GraspObject: a ``trimesh.Trimesh``, made on first access when the
    object was given its mesh as arrays (a prepared object loaded from the cache, a worker's
    copy), so that a run that never needs trimesh does not import it."""

    def __set_name__(self, owner: type, name: str) -> None:
        self._slot = f"_{name}"

    def __get__(self, obj: Any, objtype: type | None = None) -> Any:
        if obj is None:
            raise AttributeError("mesh has no default")  # a required dataclass field
        value = obj.__dict__[self._slot]
        if not _is_trimesh(value):
            value = value.to_trimesh()
            obj.__dict__[self._slot] = value
        return value

    def __set__(self, obj: Any, value: Any) -> None:
        obj.__dict__[self._slot] = value


def _is_trimesh(value: Any) -> bool:
    import sys

    module = sys.modules.get("trimesh")
    return module is not None and isinstance(value, module.Trimesh)


@dataclass(frozen=True, eq=False)
class GraspObject:
    """An object ready to be grasped (:func:`load_object` makes one).

    Attributes
    ----------
    name : str
        Canonical id: ``"knife:3"`` for a family variant, the file name for a mesh file.
    category : str
        The family's category label, or ``"mesh"`` for a file.
    mesh : trimesh.Trimesh
        Watertight, outward-oriented, metres, in the object's mesh frame. Shared between
        callers (family objects are cached): treat it as read-only, ``copy()`` it to edit.
        An object made from arrays (:class:`~affordgrasp.objects.prepared.MeshData`, as the
        cache and the workers make them) builds it on first access.
    mass : MassProperties
        At the density the object was resolved with (unit density by default), or from
        its per-part materials when resolved with ``materials=True``.
    mesh_hash : str
        :func:`mesh_hash` of ``mesh``: stable across runs and machines.
    source : str
        ``"family"``, or the absolute path of the mesh file.
    face_parts : (n_faces,) int8 ndarray or None
        Semantic part of each face of ``mesh``, an index into ``part_names`` (built-in
        families; None for mesh files, which carry no labels).
    part_names : tuple of str
        Names of the parts (``"handle"``, ``"blade"``, ``"cutting_edge"``, ...); empty
        without labels.
    materials : bool
        Whether ``mass`` follows the family's per-part materials (``materials=True``)
        rather than one uniform density.
    load_warnings : tuple of str
        What loading a mesh file warned about (repairs, a simplification with its
        measured distance); the dataset card lists them.
    """

    name: str
    category: str
    mesh: trimesh.Trimesh = _MeshField()  # type: ignore[assignment]
    mass: MassProperties
    mesh_hash: str
    source: str
    face_parts: np.ndarray | None = None
    part_names: tuple[str, ...] = ()
    materials: bool = False
    load_warnings: tuple[str, ...] = ()

    @property
    def vertices(self) -> np.ndarray:
        """(v, 3) float64 ndarray: the mesh's vertices, m (without building ``mesh``)."""
        return np.asarray(self.__dict__["_mesh"].vertices, dtype=np.float64)

    @property
    def faces(self) -> np.ndarray:
        """(f, 3) int64 ndarray: the mesh's faces (without building ``mesh``)."""
        return np.asarray(self.__dict__["_mesh"].faces, dtype=np.int64)

    @property
    def mesh_data(self) -> MeshData:
        """The mesh as arrays with its normals, adjacency and ray queries, without trimesh.

        Loaded from the on-disk cache of prepared objects, or computed (with trimesh) and
        stored there (:mod:`affordgrasp.objects.prepared`).
        """
        from affordgrasp.objects.prepared import derived_geometry

        return derived_geometry(self).mesh

    def parts_of_faces(self, faces) -> np.ndarray:
        """Part name of each face index.

        Parameters
        ----------
        faces : (n,) array_like of int
            Face indices of ``mesh`` (-1: none).

        Returns
        -------
        (n,) object ndarray of str
            ``""`` for -1 or an object without part labels.
        """
        faces = np.asarray(faces, dtype=np.int64).reshape(-1)
        out = np.full(len(faces), "", dtype=object)
        if self.face_parts is None:
            return out
        ok = (faces >= 0) & (faces < len(self.face_parts))
        names = np.asarray(self.part_names, dtype=object)
        out[ok] = names[self.face_parts[faces[ok]]]
        return out

    def faces_at(self, points, normals) -> np.ndarray:
        """Face under each surface point.

        The first face hit by a ray that starts 0.5 mm outside the point along its outward
        normal and looks back at it. A ray that misses (a contact on a sharp edge, whose normal
        is the edge's) takes the closest face instead.

        Parameters
        ----------
        points : (n, 3) array_like of float
            Surface points, m, in the object frame.
        normals : (n, 3) array_like of float
            Outward unit normals there.

        Returns
        -------
        (n,) int64 ndarray
            Face indices of ``mesh``.
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
        if len(points) == 0:
            return np.zeros(0, dtype=np.int64)
        mesh = self.mesh_data
        faces = np.asarray(
            mesh_caster(mesh).intersects_first(points + 5e-4 * normals, -normals), dtype=np.int64
        )
        missed = faces < 0
        if missed.any():
            # trimesh's closest_point, without importing trimesh (~0.5 s) mid-run
            from affordgrasp.objects.proximity import closest_faces

            faces[missed] = closest_faces(mesh, points[missed])
        return faces


def list_families() -> list[str]:
    """Names of the built-in procedural families, sorted (the one listing verb of families).

    Returns
    -------
    list of str
        Canonical names (``axe``, ``bottle``, ...); aliases such as ``cleaver`` are not listed.
    """
    return sorted(family_names.CATEGORIES)


def load_object(
    spec: str | os.PathLike | GraspObject,
    *,
    size_m: float | None = None,
    units: str | None = None,
    density: float | None = None,
    materials: bool = False,
) -> GraspObject:
    """Resolve a family name, ``family:seed`` or mesh path into a :class:`GraspObject`.

    Parameters
    ----------
    spec : str, os.PathLike or GraspObject
        See the module docstring for the grammar. A GraspObject is returned as it is, or
        with its mass recomputed when another ``density`` (or ``materials=True``) is
        asked for.
    size_m : float, optional
        Rescale so that the longest bounding-box extent is this many metres.
    units : str, optional
        Length unit of a mesh file (``m``, ``cm``, ``mm``, ``in``, ``ft``).
    density : float, optional
        kg/m^3, one uniform density for the mass properties; default 1.0 (uniform unit
        density, as in the paper), for families and mesh files alike.
    materials : bool
        A built-in family's mass properties from its per-part materials instead (steel
        head, wooden handle, ...: :mod:`affordgrasp.objects.families.materials`), so that
        the centre of mass and the mass lie where they do in the real tool. Not with
        ``density``, and not for a mesh file (it has no parts to give materials to).

    Returns
    -------
    GraspObject
        Family objects are cached: the same spec and options give the same object.

    Raises
    ------
    InputError
        Unknown family or missing file (the message lists the families), a bad seed, or
        bad options; :class:`~affordgrasp.errors.MeshError` for an unusable mesh.
    """
    materials = _check_materials(materials, density)
    if isinstance(spec, GraspObject):
        return _reuse(spec, size_m=size_m, units=units, density=density, materials=materials)
    density = 1.0 if density is None else _check_density(density)
    if isinstance(spec, os.PathLike):
        _refuse_materials_for_file(str(spec), materials)
        return _resolve_file(Path(spec), size_m=size_m, units=units, density=density)
    if not isinstance(spec, str):
        raise InputError(
            f"an object spec must be a family name, 'family:seed' or a mesh path, got "
            f"{type(spec).__name__} {spec!r}"
        )
    text = spec.strip()
    if not text:
        raise InputError(
            "the object spec is empty; give a family name (e.g. 'knife', 'knife:7') or a mesh path"
        )
    # an existing file is a file, whatever its name holds ("mug~scan_v2.ply"), and a name
    # ending in a mesh format's extension names a file ("knife~scan.stl"), missing or not
    path = Path(text).expanduser()
    named_file = path.exists() or path.suffix.lower() in SUPPORTED_EXTENSIONS
    scan = None if named_file else split_scan_spec(text)
    if scan is not None:
        return _resolve_scan(
            scan[0], scan[1], size_m=size_m, units=units, density=density, materials=materials
        )
    family, seed_text = _split_family(text)
    if family is not None:
        if size_m is not None or units is not None:
            # A rescaled family would keep the family's name with other geometry.
            raise InputError(
                f"{text!r} is a built-in family, made at its real size in metres; size and "
                "units options apply to mesh files only (export it with 'affordgrasp objects "
                "export' and rescale the file if you need another size)"
            )
        seed = _parse_seed(seed_text, family, text)
        return _resolve_family(family, seed, density, materials, size_m, units)
    if path.exists():
        _refuse_materials_for_file(text, materials)
        return _resolve_file(path, size_m=size_m, units=units, density=density)
    raise InputError(_unknown_spec_message(text))


def object_from_mesh(
    mesh: trimesh.Trimesh,
    name: str,
    *,
    source: str = TRANSIENT_SOURCE,
    density: float = 1.0,
    simplify_above: int | None = LARGE_MESH_FACES,
) -> GraspObject:
    """An object from a mesh held in memory (cleaned, repaired and oriented as a file's).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object in metres, in its mesh frame (not modified).
    name : str
        The object's name.
    source : str
        Where the mesh came from. With the default, :data:`TRANSIENT_SOURCE`, its derived
        geometry is kept in memory only, never written to the on-disk cache (a surface
        fused from camera views is made for one decision).
    density : float
        kg/m^3, uniform.
    simplify_above : int or None
        A mesh with more triangles is simplified as a file's is
        (:func:`~affordgrasp.objects.loading.prepare_mesh`); None: never (a surface fused
        from views, whose voxels are coarser than the simplification's tolerance).

    Returns
    -------
    GraspObject
        Category ``"mesh"``.

    Raises
    ------
    InputError
        For a bad density; :class:`~affordgrasp.errors.MeshError` for an unusable mesh.
    """
    if not _is_trimesh(mesh):
        raise InputError(f"mesh must be a trimesh.Trimesh, got {type(mesh).__name__}")
    density = _check_density(density)
    with recording_warnings() as warnings:
        prepared_mesh = prepare_mesh(mesh, source=name, simplify_above=simplify_above)
    return _build(name, "mesh", prepared_mesh, density, source, load_warnings=tuple(warnings))


def is_family_spec(spec: object) -> bool:
    """Whether ``spec`` names a built-in family (``knife``, ``knife:7``), not a mesh file.

    Parameters
    ----------
    spec : object
        An object spec; anything but a str is not a family spec.

    Returns
    -------
    bool
    """
    return isinstance(spec, str) and _split_family(spec.strip())[0] is not None


def _check_materials(materials: object, density: float | None) -> bool:
    if not isinstance(materials, (bool, np.bool_)):
        raise InputError(f"materials must be True or False, got {materials!r}")
    if materials and density is not None:
        raise InputError(
            f"materials=True gives each part its material's density, and density={density!r} "
            "gives the whole object one density; pass one of the two"
        )
    return bool(materials)


def _refuse_materials_for_file(spec: str, materials: bool) -> None:
    if materials:
        raise InputError(
            f"{spec!r} is a mesh file, which has no parts to give materials to; per-part "
            "materials (materials=True, --materials) apply to the built-in families only. "
            "Drop the option (a mesh file has uniform density, 1.0 by default, or density=...)"
        )


def _families():
    from affordgrasp.objects import families

    return families


def _families_installed() -> bool:
    import importlib.util

    return importlib.util.find_spec("affordgrasp.objects.families") is not None


def _available_families() -> dict[str, str] | None:
    # Names only: the builders are imported when a family is built. Without the procedural
    # families every spec is a path.
    return family_names.CATEGORIES if _families_installed() else None


def _normalise(name: str) -> str:
    return name.strip().lower().replace("-", "_").replace(" ", "_")


def _split_family(text: str) -> tuple[str | None, str | None]:
    """(family name, seed text or None) when ``text`` names a family, else (None, None)."""
    families = _available_families()
    if not families:
        return None, None
    by_key = {_normalise(name): name for name in families}
    aliases = family_names.ALIASES
    by_key.update({_normalise(alias): name for alias, name in aliases.items() if name in families})
    head, sep, tail = text.partition(":")
    name = by_key.get(_normalise(head))
    if name is None:
        return None, None
    return name, (tail if sep else None)


def _parse_seed(seed_text: str | None, family: str, spec: str) -> int:
    if seed_text is None:
        return 0
    seed_text = seed_text.strip()
    if not (seed_text.isascii() and seed_text.isdigit()):
        raise InputError(
            f"bad object spec {spec!r}: the seed after ':' must be a non-negative integer "
            f"(e.g. '{family}:7'), got {seed_text!r}"
        )
    return int(seed_text)


def _unknown_spec_message(text: str) -> str:
    families = _available_families()
    listed = ", ".join(sorted(families)) if families else "(none installed)"
    head = text.partition(":")[0]
    hint = did_you_mean(head, families or ()) if not Path(text).suffix else ""
    return (
        f"unknown object {text!r}{hint}: it is not a built-in family and no file exists at that "
        f"path. Families: {listed}. Use 'family' or 'family:seed', or the path of an "
        "existing mesh file (.obj, .stl, .ply, .glb, .gltf, .off)"
    )


def _resolve_file(
    path: Path, *, size_m: float | None, units: str | None, density: float
) -> GraspObject:
    from affordgrasp.objects import prepared

    if not path.exists():
        raise InputError(_unknown_spec_message(str(path)))
    _scale_request(size_m, units)  # bad options fail before the file is read
    # Read and repaired once per file content: later processes load the arrays (see
    # objects/prepared.py).
    key = prepared.mesh_file_key(path, size_m=size_m, units=units, density=density)
    source = str(path.resolve())
    if key is not None:
        fields = prepared.load_mesh_file(key, path.name, source)
        if fields is not None:
            return _with_region_densities(GraspObject(**fields), path)
    with recording_warnings() as warnings:
        mesh = load_mesh(path, size_m=size_m, units=units)
    obj = _build(path.name, "mesh", mesh, density, source, load_warnings=tuple(warnings))
    obj = _with_region_densities(obj, path)
    # not if the file changed while it was read: the mesh may be of other bytes than the key's
    if key is not None and key == prepared.mesh_file_key(
        path, size_m=size_m, units=units, density=density
    ):
        prepared.store_mesh_file(key, obj, warnings)
    return obj


@functools.lru_cache(maxsize=_FAMILY_CACHE_SIZE)
def _resolve_family(
    family: str, seed: int, density: float, materials: bool, size_m: float | None, units: str | None
) -> GraspObject:
    from affordgrasp.objects import prepared

    if size_m is not None or units is not None:
        return _build_family(family, seed, density, materials, size_m, units)
    # Built once per machine: later processes load the arrays (see objects/prepared.py).
    key = prepared.family_key(family, seed, materials, density)
    fields = prepared.load_family(key)
    if fields is not None:
        return GraspObject(**fields)
    obj = _build_family(family, seed, density, materials, size_m, units)
    prepared.store_family(key, obj)
    return obj


def _build_family(
    family: str, seed: int, density: float, materials: bool, size_m: float | None, units: str | None
) -> GraspObject:
    families = _families()
    name = f"{family}:{seed}"
    raw = families.make_family(family, seed=seed, materials=materials)
    mesh = prepare_mesh(raw, size_m=size_m, units=units, source=name)
    face_parts = raw.metadata.get("face_parts")
    if face_parts is not None and not np.array_equal(raw.faces, mesh.faces):
        import trimesh

        # preparing changed the triangles: each keeps the part of the raw face under it
        _, _, under = trimesh.proximity.closest_point(raw, mesh.triangles_center)
        face_parts = np.asarray(face_parts)[under]
    regions = raw.metadata.get("materials") if materials else None
    return _build(
        name,
        families.FAMILIES[family].category,
        mesh,
        density,
        "family",
        face_parts=face_parts,
        part_names=tuple(raw.metadata.get("part_names", ())) if face_parts is not None else (),
        regions=regions,
    )


MATERIALS_SUFFIX = ".materials.toml"


def _with_region_densities(obj: GraspObject, path: Path) -> GraspObject:
    """``obj`` with the region densities of ``<path>.materials.toml`` when that file exists.

    The file (TOML; lengths in metres in the loaded object's frame, densities kg/m^3)::

        density = 700.0            # what no region below takes (a wooden handle)
        [[region]]                 # in order of precedence
        name = "head"
        density = 7850.0           # steel
        plane_point = [0.10, 0.0, 0.0]
        plane_normal = [1.0, 0.0, 0.0]   # the region is the side the normal points to

    Each region is the part of the mesh beyond its cutting plane
    (:func:`~affordgrasp.objects.mass.plane_regions`): a hammer's head, an axe's head.
    """
    side = path.with_name(path.name + MATERIALS_SUFFIX)
    if not side.exists():
        return obj
    import tomllib

    try:
        doc = tomllib.loads(side.read_text(encoding="utf-8"))
        planes = [
            (r.get("name", f"region {i}"), r["density"], r["plane_point"], r["plane_normal"])
            for i, r in enumerate(doc.get("region", []))
        ]
        rest = doc.get("density", obj.mass.density)
    except (tomllib.TOMLDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise InputError(
            f"{side}: cannot read the region densities ({exc}); write 'density = ...' and "
            "[[region]] tables with name, density, plane_point and plane_normal"
        ) from None
    regions = plane_regions(obj.mesh, rest, planes)
    return replace(obj, mass=material_mass_properties(obj.mesh, regions), materials=True)


def _resolve_scan(
    base: str,
    scan_seed: int | None,
    *,
    size_m: float | None,
    units: str | None,
    density: float,
    materials: bool,
) -> GraspObject:
    """The scan-like variant of ``base`` (a family spec or a mesh path)."""
    family, seed_text = _split_family(base)
    if family is None:
        _refuse_materials_for_file(base, materials)
        path = Path(base).expanduser()
        if not path.exists():
            raise InputError(_unknown_spec_message(base))
        crisp = _resolve_file(path, size_m=size_m, units=units, density=density)
        seed = 0 if scan_seed is None else scan_seed
        with recording_warnings():
            mesh, _ = scan_like(crisp.mesh, seed=seed)
        name = f"{crisp.name}{SCAN_SUFFIX}:{seed}"
        return _with_region_densities(_build(name, "mesh", mesh, density, crisp.source), path)
    if size_m is not None or units is not None:
        raise InputError(
            f"{base!r} is a built-in family, made at its real size in metres; size and units "
            "options apply to mesh files only"
        )
    seed = _parse_seed(seed_text, family, base)
    return _resolve_family_scan(
        family, seed, seed if scan_seed is None else scan_seed, density, materials
    )


@functools.lru_cache(maxsize=_FAMILY_CACHE_SIZE)
def _resolve_family_scan(
    family: str, seed: int, scan_seed: int, density: float, materials: bool
) -> GraspObject:
    from affordgrasp.objects import prepared

    key = prepared.family_key(family, seed, materials, density)
    key["scan_seed"] = int(scan_seed)
    fields = prepared.load_family(key)
    if fields is not None:
        return GraspObject(**fields)
    crisp = _resolve_family(family, seed, density, False, None, None)
    with recording_warnings():
        mesh, face_parts = scan_like(crisp.mesh, crisp.face_parts, seed=scan_seed)
    regions = None
    if materials:
        raw = _families().make_family(family, seed=seed, materials=True)
        regions = regions_on_mesh(mesh, raw.metadata["materials"])
    suffix = SCAN_SUFFIX if scan_seed == seed else f"{SCAN_SUFFIX}:{scan_seed}"
    obj = _build(
        f"{family}:{seed}{suffix}",
        _families().FAMILIES[family].category,
        mesh,
        density,
        "family",
        face_parts=face_parts,
        part_names=crisp.part_names if face_parts is not None else (),
        regions=regions,
    )
    prepared.store_family(key, obj)
    return obj


def _build(
    name: str,
    category: str,
    mesh: trimesh.Trimesh,
    density: float,
    source: str,
    *,
    face_parts: np.ndarray | None = None,
    part_names: tuple[str, ...] = (),
    regions: list | None = None,
    load_warnings: tuple[str, ...] = (),
) -> GraspObject:
    if regions:
        mass = material_mass_properties(mesh, regions)
    else:
        mass = mass_properties(mesh, density=density)
    return GraspObject(
        name=name,
        category=category,
        mesh=mesh,
        mass=mass,
        mesh_hash=mesh_hash(mesh),
        source=source,
        face_parts=face_parts,
        part_names=part_names,
        materials=bool(regions),
        load_warnings=tuple(load_warnings),
    )


def _reuse(
    obj: GraspObject,
    *,
    size_m: float | None,
    units: str | None,
    density: float | None,
    materials: bool,
) -> GraspObject:
    if size_m is not None or units is not None:
        raise InputError(
            f"object {obj.name!r} is already resolved, so size_m/units cannot apply; pass "
            "its spec (family or path) with size_m/units instead"
        )
    if materials:
        if obj.materials:
            return obj
        if obj.source != "family":
            _refuse_materials_for_file(obj.name, materials)
        if split_scan_spec(obj.name) is not None:
            return load_object(obj.name, materials=True)
        family, seed_text = _split_family(obj.name)
        if family is None:
            raise InputError(
                f"object {obj.name!r} is not a built-in family, so it has no materials; drop "
                "materials=True"
            )
        return _resolve_family(
            family, _parse_seed(seed_text, family, obj.name), 1.0, True, None, None
        )
    if density is None or (not obj.materials and _check_density(density) == obj.mass.density):
        return obj
    return replace(obj, mass=mass_properties(obj.mesh, density=density), materials=False)
