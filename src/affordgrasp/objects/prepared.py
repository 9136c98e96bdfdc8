"""Prepared objects kept on disk as arrays, so that a warm start needs neither trimesh nor scipy.

Three kinds of entries live under ``cache_dir()/objects`` (:func:`affordgrasp.caching.cache_dir`):

* a **resolved family** (``family-<name>-<seed>-...npz``): the mesh a built-in family builds
  and repairs (vertices, faces, face parts), its mass properties and labels; keyed by the
  family, seed, materials and density;
* a **resolved mesh file** (``file-<content hash>-...npz``): the mesh that reading and
  repairing a file gives (vertices, faces), its mass properties and the warnings the repair
  logged (logged again on a load); keyed by the SHA-256 of the file's bytes (and of the
  ``.mtl`` or ``.bin`` files it names, which the readers may open), its name and format,
  ``size_m``, ``units`` and density, so that an edited file is read again;
* the **derived geometry of a mesh** (``mesh-<mesh hash>-<stamp>.npz``): what the pipeline computes
  from a mesh with trimesh and scipy: face normals, face adjacency and the bounding-box
  diagonal in the mesh frame (use metrics, rays), and in the simulator's centred frame the
  surface samples, the convex hull's vertices, face normals and diagonal; keyed by the mesh's
  content hash (:func:`~affordgrasp.objects.mesh_hash`), so a mesh file or a family variant
  with the same vertices and faces shares it.

Every key also holds a **stamp**: a format number, a hash of the sources that compute the
entries (``affordgrasp/objects``, ``rays``, ``grasp/policy.py``) and a
fingerprint of the installed numpy, trimesh, scipy and manifold3d. An entry written under
another key, that fails its checksum or that cannot be read is rebuilt and overwritten,
never trusted (:func:`affordgrasp.caching.read_arrays`); a loaded family's vertices and
faces must also hash to the mesh hash stored with them. Values are the ones a fresh build
computes, bit for bit (tests compare them). Set ``AFFORDGRASP_CACHE_DIR`` to move the
cache; deleting it only costs the rebuild.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import logging
import os
import struct
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

import numpy as np

from ..caching import IdentityCache, cache_dir, read_arrays, write_arrays
from .mass import MassProperties
from .surface import SurfaceSample, sample_surface

# The ``source`` of an object made in memory for one use (a surface fused from camera
# views): its derived geometry is not written to the disk cache.
TRANSIENT_SOURCE = "transient"

if TYPE_CHECKING:
    import trimesh


class _ResolvedObject(Protocol):
    """What the cache reads of a GraspObject, described: objects.resolve builds on this module."""

    @property
    def name(self) -> str: ...
    @property
    def category(self) -> str: ...
    @property
    def mesh(self) -> trimesh.Trimesh: ...
    @property
    def mass(self) -> MassProperties: ...
    @property
    def mesh_hash(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def face_parts(self) -> np.ndarray | None: ...
    @property
    def part_names(self) -> tuple[str, ...]: ...
    @property
    def materials(self) -> bool: ...
    @property
    def vertices(self) -> np.ndarray: ...
    @property
    def faces(self) -> np.ndarray: ...


FORMAT = 1
_T = TypeVar("_T")
_PACKAGE_DIR = Path(__file__).resolve().parents[1]  # affordgrasp/
_STAMPED_SOURCES = ("objects", "rays", "grasp/policy.py")
_STAMPED_PACKAGES = ("numpy", "trimesh", "scipy", "manifold3d", "fast_simplification")


@cache
def stamp() -> str:
    """What every entry depends on besides its own key: sources and libraries (hex digest).

    Returns
    -------
    str
    """
    digest = hashlib.sha256(f"format {FORMAT}".encode())
    for name in _STAMPED_SOURCES:
        path = _PACKAGE_DIR / name
        files = sorted(path.rglob("*.py")) if path.is_dir() else [path]
        for file in files:
            digest.update(file.relative_to(_PACKAGE_DIR).as_posix().encode())
            digest.update(hashlib.sha256(file.read_bytes()).digest())
    for package in _STAMPED_PACKAGES:
        # the installed files, not importlib.metadata (importing it costs ~0.1 s)
        spec = importlib.util.find_spec(package)
        origin = spec.origin if spec is not None else None
        if origin:
            st = os.stat(origin)
            digest.update(f"{package}|{origin}|{st.st_size}|{st.st_mtime_ns}".encode())
        else:
            digest.update(f"{package}|missing".encode())
    return digest.hexdigest()


def mesh_hash(mesh: trimesh.Trimesh) -> str:
    """SHA-256 hex digest of a mesh's geometry.

    The bytes hashed are the vertices as little-endian float64 (n, 3), C order, followed by
    the faces as little-endian int64 (m, 3), C order; anyone can recompute it.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Vertices (n, 3) in metres, faces (m, 3).

    Returns
    -------
    str
        64 lowercase hex digits.
    """
    vertices = np.ascontiguousarray(mesh.vertices, dtype="<f8")
    faces = np.ascontiguousarray(mesh.faces, dtype="<i8")
    digest = hashlib.sha256()
    digest.update(vertices.tobytes())
    digest.update(faces.tobytes())
    return digest.hexdigest()


@dataclass(frozen=True, eq=False)
class MeshData:
    """A triangle mesh as arrays, with what trimesh derives from it, without trimesh.

    Duck-types the part of ``trimesh.Trimesh`` the pipeline uses (``vertices``, ``faces``,
    ``face_normals``, ``triangles``, ``face_adjacency*``, ``hash()``); its rays are cast by
    :func:`affordgrasp.rays.mesh.mesh_caster` (Embree, without trimesh).

    Attributes
    ----------
    vertices : (v, 3) float64 ndarray
        m.
    faces : (f, 3) int64 ndarray
    content_hash : str
        :func:`~affordgrasp.objects.mesh_hash` of the vertices and faces.
    face_normals : (f, 3) float64 ndarray or None
        Unit normals as trimesh computes them.
    scale : float or None
        Bounding-box diagonal, m (trimesh's ``mesh.scale``).
    face_adjacency, face_adjacency_edges : (p, 2) int64 ndarray or None
        Pairs of faces sharing an edge, and that edge's vertices (trimesh's).
    face_adjacency_angles : (p,) float64 ndarray or None
        rad.
    face_adjacency_convex : (p,) bool ndarray or None
    """

    vertices: np.ndarray
    faces: np.ndarray
    content_hash: str
    face_normals: np.ndarray | None = None
    scale: float | None = None
    face_adjacency: np.ndarray | None = None
    face_adjacency_edges: np.ndarray | None = None
    face_adjacency_angles: np.ndarray | None = None
    face_adjacency_convex: np.ndarray | None = None

    def __hash__(self) -> int:
        return hash(self.content_hash)

    @property
    def triangles(self) -> np.ndarray:
        """(f, 3, 3) float64 ndarray: the vertices of each face, m."""
        return self.vertices[self.faces]

    def to_trimesh(self) -> trimesh.Trimesh:
        """The mesh as a ``trimesh.Trimesh`` (same vertices and faces, not processed).

        Returns
        -------
        trimesh.Trimesh
        """
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    @classmethod
    def from_trimesh(cls, mesh: trimesh.Trimesh, content_hash: str) -> MeshData:
        """The arrays of ``mesh`` and what trimesh derives from them.

        Parameters
        ----------
        mesh : trimesh.Trimesh
        content_hash : str
            Its mesh hash.

        Returns
        -------
        MeshData
        """
        return cls(
            vertices=np.asarray(mesh.vertices, dtype=np.float64),
            faces=np.asarray(mesh.faces, dtype=np.int64),
            content_hash=content_hash,
            face_normals=np.asarray(mesh.face_normals, dtype=np.float64),
            scale=float(mesh.scale),
            face_adjacency=np.asarray(mesh.face_adjacency, dtype=np.int64),
            face_adjacency_edges=np.asarray(mesh.face_adjacency_edges, dtype=np.int64),
            face_adjacency_angles=np.asarray(mesh.face_adjacency_angles, dtype=np.float64),
            face_adjacency_convex=np.asarray(mesh.face_adjacency_convex, dtype=bool),
        )


_MESH_FIELDS = (
    "face_normals",
    "face_adjacency",
    "face_adjacency_edges",
    "face_adjacency_angles",
    "face_adjacency_convex",
)
_SAMPLE_FIELDS = (
    "points",
    "normals",
    "sharp",
    "cell_start",
    "cell_center",
    "cell_radius",
    "cell_normal",
    "cell_slab",
    "coarse_start",
    "coarse_center",
    "coarse_radius",
    "cell_sub_start",
    "sub_start",
    "sub_points",
    "sub_center",
    "sub_radius",
    "sub_normal",
    "sub_slab",
)


@dataclass(frozen=True, eq=False)
class DerivedGeometry:
    """Everything the pipeline derives from one mesh (see the module docstring).

    Attributes
    ----------
    mesh : MeshData
        Mesh frame, with normals, adjacency and scale.
    origin : (3,) float64 ndarray
        The simulator's centred frame in the mesh frame, m.
    centred : MeshData
        The mesh in the centred frame, with normals and scale (for the use-point rays).
    samples : SurfaceSample
        Surface samples, centred frame.
    hull_vertices : (h, 3) float64 ndarray
        Convex-hull vertices, centred frame, m.
    """

    mesh: MeshData
    origin: np.ndarray
    centred: MeshData
    samples: SurfaceSample
    hull_vertices: np.ndarray


_DERIVED: IdentityCache[DerivedGeometry] = IdentityCache()


def _entry_path(name: str) -> Path:
    return cache_dir() / "objects" / f"{name}.npz"


def derived_geometry(obj: _ResolvedObject) -> DerivedGeometry:
    """The derived geometry of an object's mesh: from memory, from disk, or computed.

    Parameters
    ----------
    obj : GraspObject

    Returns
    -------
    DerivedGeometry
    """
    return _DERIVED.get(obj, lambda: _load_or_build_derived(obj))


def _load_or_build_derived(obj: _ResolvedObject) -> DerivedGeometry:
    if obj.source == TRANSIENT_SOURCE:
        return _build_derived(obj)  # made for one use: the disk cache would only grow
    vertices, faces = obj.vertices, obj.faces
    key = {"kind": "mesh", "mesh_hash": obj.mesh_hash, "stamp": stamp()}
    path = _entry_path(f"mesh-{obj.mesh_hash[:32]}-{key['stamp'][:12]}")
    arrays = read_arrays(path, key)
    if arrays is not None:
        try:
            return _derived_from_arrays(vertices, faces, obj.mesh_hash, arrays)
        except (KeyError, ValueError, IndexError):
            pass  # a malformed entry under the right key: rebuild it
    derived = _build_derived(obj)
    write_arrays(path, key, _derived_to_arrays(derived))
    return derived


def centred_frame_origin(vertices: np.ndarray) -> np.ndarray:
    """Origin of the frame the grasp simulation runs in: the bounding-box centre.

    Parameters
    ----------
    vertices : (n, 3) float ndarray
        m.

    Returns
    -------
    (3,) float64 ndarray
        m.
    """
    return 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))


def _build_derived(obj: _ResolvedObject) -> DerivedGeometry:
    import trimesh

    mesh = obj.mesh
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    origin = centred_frame_origin(vertices)
    # Far from the origin, v - origin is exact (both within a factor 2: Sterbenz).
    centred = trimesh.Trimesh(vertices - origin, np.asarray(mesh.faces), process=False)
    return DerivedGeometry(
        mesh=MeshData.from_trimesh(mesh, obj.mesh_hash),
        origin=origin,
        centred=MeshData(
            vertices=np.asarray(centred.vertices, dtype=np.float64),
            faces=np.asarray(centred.faces, dtype=np.int64),
            content_hash=obj.mesh_hash + ":centred",
            face_normals=np.asarray(centred.face_normals, dtype=np.float64),
            scale=float(centred.scale),
        ),
        samples=sample_surface(centred),
        hull_vertices=_hull_vertices(centred.vertices),
    )


def _hull_vertices(vertices: np.ndarray) -> np.ndarray:
    """(h, 3) float64: the convex hull's vertices (qhull directly, as a point set).

    Only their bounds and farthest distance are used (grasp.pregrasp), which a hull's vertices
    give exactly; trimesh's hull mesh would also orient and repair its faces (2.5 s on a
    200 k-triangle scan, against a tenth of that here).
    """
    from scipy.spatial import ConvexHull, QhullError

    points = np.asarray(vertices, dtype=np.float64)
    try:
        return points[np.sort(ConvexHull(points).vertices)]
    except QhullError:  # a flat or degenerate point set: all of it (same bounds)
        return points


def _derived_to_arrays(d: DerivedGeometry) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {f"mesh_{k}": getattr(d.mesh, k) for k in _MESH_FIELDS}
    out["mesh_scale"] = np.array(d.mesh.scale)
    out["origin"] = d.origin
    out["centred_face_normals"] = d.centred.face_normals
    out["centred_scale"] = np.array(d.centred.scale)
    out["hull_vertices"] = d.hull_vertices
    out.update({f"samples_{k}": getattr(d.samples, k) for k in _SAMPLE_FIELDS})
    out["samples_spacing"] = np.array(d.samples.spacing)
    return out


def _derived_from_arrays(
    vertices: np.ndarray, faces: np.ndarray, content_hash: str, a: dict[str, np.ndarray]
) -> DerivedGeometry:
    origin = a["origin"]
    n_faces = len(faces)
    if a["mesh_face_normals"].shape != (n_faces, 3) or origin.shape != (3,):
        raise ValueError("entry does not match the mesh")
    mesh = MeshData(
        vertices=vertices,
        faces=faces,
        content_hash=content_hash,
        scale=float(a["mesh_scale"]),
        **{k: a[f"mesh_{k}"] for k in _MESH_FIELDS},
    )
    centred = MeshData(
        vertices=vertices - origin,
        faces=faces,
        content_hash=content_hash + ":centred",
        face_normals=a["centred_face_normals"],
        scale=float(a["centred_scale"]),
    )
    samples = SurfaceSample(
        spacing=float(a["samples_spacing"]), **{k: a[f"samples_{k}"] for k in _SAMPLE_FIELDS}
    )
    return DerivedGeometry(mesh, origin, centred, samples, a["hull_vertices"])


# ---------------------------------------------------------------------------------------
# resolved families
# ---------------------------------------------------------------------------------------

_MASS_ARRAYS = ("center_of_mass", "inertia", "bounds")
_MASS_FLOATS = ("density", "volume", "mass", "r_max")


def family_key(family: str, seed: int, materials: bool, density: float) -> dict[str, Any]:
    """The key of a resolved family's entry.

    Parameters
    ----------
    family : str
        Canonical family name.
    seed : int
    materials : bool
    density : float
        kg/m^3.

    Returns
    -------
    dict
    """
    return {
        "kind": "family",
        "family": family,
        "seed": int(seed),
        "materials": bool(materials),
        "density": float(density).hex(),
        "stamp": stamp(),
    }


def _family_path(key: dict[str, Any]) -> Path:
    name = hashlib.sha256(repr(sorted(key.items())).encode()).hexdigest()[:24]
    return _entry_path(f"family-{key['family']}-{key['seed']}-{name}")


def load_family(key: dict[str, Any]) -> dict[str, Any] | None:
    """The resolved family stored under ``key``, or None (missing, stale or corrupt).

    Parameters
    ----------
    key : dict
        :func:`family_key`.

    Returns
    -------
    dict or None
        The keyword arguments of its :class:`~affordgrasp.objects.GraspObject` (which
        :func:`~affordgrasp.objects.load_object` makes); its ``mesh`` is a
        :class:`MeshData`, built into a trimesh only when accessed.
    """

    def build(a: dict[str, np.ndarray], mesh: MeshData, mass: MassProperties) -> dict[str, Any]:
        return {
            "name": str(a["name"]),
            "category": str(a["category"]),
            "mesh": mesh,
            "mass": mass,
            "mesh_hash": mesh.content_hash,
            "source": "family",
            "face_parts": a["face_parts"] if "face_parts" in a else None,
            "part_names": tuple(str(p) for p in a["part_names"]),
            "materials": bool(a["materials"]),
        }

    return _load_object(_family_path(key), key, build)


def _load_object(
    path: Path,
    key: dict[str, Any],
    build: Callable[[dict[str, np.ndarray], MeshData, MassProperties], _T],
) -> _T | None:
    """``build(arrays, mesh, mass)`` of the entry at ``path``, or None (missing, stale,
    corrupt, or its mesh does not hash to its stored hash)."""
    a = read_arrays(path, key)
    if a is None:
        return None
    try:
        mesh = _mesh_from_arrays(a)
        if mesh is None:
            return None
        return build(a, mesh, _mass_from_arrays(a))
    except (KeyError, ValueError, TypeError):
        return None


def store_family(key: dict[str, Any], obj: _ResolvedObject) -> None:
    """Store a freshly resolved family under ``key`` (see :func:`load_family`).

    Parameters
    ----------
    key : dict
        :func:`family_key`.
    obj : GraspObject
    """
    arrays = _mesh_to_arrays(obj)
    arrays["name"] = np.array(obj.name)
    arrays["category"] = np.array(obj.category)
    arrays["part_names"] = np.array(list(obj.part_names), dtype=str)
    arrays["materials"] = np.array(bool(obj.materials))
    if obj.face_parts is not None:
        arrays["face_parts"] = np.asarray(obj.face_parts)
    write_arrays(_family_path(key), key, arrays)


# ---------------------------------------------------------------------------------------
# resolved mesh files
# ---------------------------------------------------------------------------------------


def mesh_file_key(
    path: Path, *, size_m: float | None, units: str | None, density: float
) -> dict[str, Any] | None:
    """The key of a mesh file's entry, or None when the file cannot be cached.

    Not cached (read every time): a path that is not a file, an unsupported format, or a
    glTF whose buffers cannot be told (the reader then reports the problem).

    Parameters
    ----------
    path : pathlib.Path
        The mesh file.
    size_m : float or None
        m; as given to :func:`~affordgrasp.objects.load_mesh` (already validated).
    units : str or None
        As given to :func:`~affordgrasp.objects.load_mesh` (already validated).
    density : float
        kg/m^3.

    Returns
    -------
    dict or None
    """
    from .loading import SUPPORTED_EXTENSIONS

    ext = path.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        return None
    try:
        if not path.is_file():
            return None
        data = path.read_bytes()
        companions = _companion_files(path, data, ext)
        if companions is None:
            return None
        named = {name: _file_digest(path.parent / name) for name in companions}
    except OSError:
        return None
    return {
        "kind": "file",
        "sha256": hashlib.sha256(data).hexdigest(),
        "companions": named,
        "name": path.name,
        "format": ext,
        "size_m": None if size_m is None else float(size_m).hex(),
        "units": None if units is None else str(units),
        "density": float(density).hex(),
        "stamp": stamp(),
    }


def _file_digest(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return "unreadable"  # the reader then goes without it, and so does the entry


def _companion_files(path: Path, data: bytes, ext: str) -> list[str] | None:
    """The files beside ``path`` whose contents its reader may use (relative names).

    An OBJ's material library (trimesh reads the first ``mtllib``, and groups faces by
    material); a glTF's external buffers. None: cannot tell (not cached).
    """
    if ext == ".obj":
        at = data.find(b"mtllib")
        if at < 0:
            return []
        end = data.find(b"\n", at)
        line = data[at + 6 : end if end >= 0 else len(data)]
        return [line.decode("utf-8", "replace").strip()]
    if ext in (".gltf", ".glb"):
        try:
            if ext == ".glb":
                # header (magic, version, length), then the JSON chunk (length, type, data)
                magic, _, _, length, kind = struct.unpack_from("<4sIIII", data)
                if magic != b"glTF" or kind != 0x4E4F534A:
                    return None
                data = data[20 : 20 + length]
            gltf = json.loads(data)
            uris = [b.get("uri") for b in gltf.get("buffers", [])]
        except (ValueError, struct.error, AttributeError, TypeError):
            return None
        return sorted({u for u in uris if isinstance(u, str) and not u.startswith("data:")})
    return []


def _file_path(key: dict[str, Any]) -> Path:
    name = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:24]
    return _entry_path(f"file-{key['sha256'][:16]}-{name}")


def load_mesh_file(key: dict[str, Any], name: str, source: str) -> dict[str, Any] | None:
    """The resolved mesh file stored under ``key``, or None (missing, stale or corrupt).

    Logs again the warnings that resolving it logged.

    Parameters
    ----------
    key : dict
        :func:`mesh_file_key`.
    name : str
        The object's name (the file name).
    source : str
        The file's absolute path.

    Returns
    -------
    dict or None
        The keyword arguments of its :class:`~affordgrasp.objects.GraspObject` (which
        :func:`~affordgrasp.objects.load_object` makes); its ``mesh`` is a
        :class:`MeshData`, built into a trimesh only when accessed.
    """

    def build(
        a: dict[str, np.ndarray], mesh: MeshData, mass: MassProperties
    ) -> tuple[dict[str, Any], list[str]]:
        fields = {
            "name": name,
            "category": "mesh",
            "mesh": mesh,
            "mass": mass,
            "mesh_hash": mesh.content_hash,
            "source": source,
            "load_warnings": tuple(str(w) for w in a["warnings"]),
        }
        return fields, [str(w) for w in a["warnings"]]

    found = _load_object(_file_path(key), key, build)
    if found is None:
        return None
    log = logging.getLogger("affordgrasp.objects.loading")
    for message in found[1]:
        log.warning("%s", message)
    return found[0]


def store_mesh_file(key: dict[str, Any], obj: _ResolvedObject, warnings: list[str]) -> None:
    """Store a freshly resolved mesh file under ``key`` (see :func:`load_mesh_file`).

    Parameters
    ----------
    key : dict
        :func:`mesh_file_key`.
    obj : GraspObject
    warnings : list of str
        What resolving it logged (:func:`~affordgrasp.objects.loading.recording_warnings`).
    """
    arrays = _mesh_to_arrays(obj)
    arrays["warnings"] = np.array(warnings, dtype=str).reshape(-1)
    write_arrays(_file_path(key), key, arrays)


def _mesh_to_arrays(obj: _ResolvedObject) -> dict[str, np.ndarray]:
    arrays: dict[str, np.ndarray] = {
        "vertices": np.asarray(obj.vertices, dtype=np.float64),
        "faces": np.asarray(obj.faces, dtype=np.int64),
        "mesh_hash": np.array(obj.mesh_hash),
    }
    mass: MassProperties = obj.mass
    for k in _MASS_ARRAYS + _MASS_FLOATS:
        arrays[f"mass_{k}"] = np.asarray(getattr(mass, k))
    return arrays


def _mesh_from_arrays(a: dict[str, np.ndarray]) -> MeshData | None:
    """The stored mesh, or None when its vertices and faces do not hash to its hash."""
    mesh = MeshData(a["vertices"], a["faces"], str(a["mesh_hash"]))
    if mesh.vertices.ndim != 2 or mesh.faces.ndim != 2 or mesh_hash(mesh) != mesh.content_hash:
        return None
    return mesh


def _mass_from_arrays(a: dict[str, np.ndarray]) -> MassProperties:
    arrays = {}
    for k in _MASS_ARRAYS:
        arrays[k] = np.array(a[f"mass_{k}"], dtype=np.float64)
        arrays[k].setflags(write=False)
    return MassProperties(**{k: float(a[f"mass_{k}"]) for k in _MASS_FLOATS}, **arrays)
