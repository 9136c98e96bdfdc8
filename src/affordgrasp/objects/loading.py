"""Load mesh files and turn any mesh into a usable solid (conventions: Objects).

:func:`load_mesh` reads OBJ, STL (ASCII and binary), PLY, GLB/GLTF (every geometry of the
scene, with its transform) and OFF (our own reader, :mod:`affordgrasp.objects.off`).
:func:`prepare_mesh` is the one place where meshes from files and procedural meshes become
what the rest of the pipeline assumes: a closed, outward-oriented volume in metres.

Repair order, cheapest and least invasive first:

1. merge duplicate vertices, drop faces that repeat a vertex and duplicate faces;
2. an open mesh: weld the vertices of its open edges that lie closer than
   ``WELD_RELATIVE`` of its size (a seam written with its two sides apart), before anything
   is capped;
3. a closed mesh made of several bodies: overlapping bodies are unioned (manifold3d) so
   that no volume is counted twice, bodies turned inside out are flipped, a body inside
   another and facing inwards is kept as a cavity; bodies apart from each other are kept
   as one rigid object, with a warning that names them (and one for floating specks);
4. still open: fix the winding, cap each hole with a polygon triangulated in its plane
   (a rim that passes one vertex twice is capped as two holes; a jagged rim whose planar
   triangulation would reuse an edge of the mesh, as a scan cut open at its base has, is
   capped with a fan from its centroid), and close each connected part separately (parts
   touching along an edge are a soup of closed parts: step 3 then unions them);
5. still open: let manifold3d merge nearly coincident vertices along open edges.

Sizes in warnings are in the mesh's own unit (``units``), else in metres or millimetres.

Whatever is still not a closed volume, or encloses no volume, is refused with a
:class:`~affordgrasp.errors.MeshError` that says what to do.
"""

from __future__ import annotations

import logging
import math
import os
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from affordgrasp.errors import InputError, MeshError
from affordgrasp.objects.off import read_off, triangulate_polygon
from affordgrasp.objects.simplify import LARGE_MESH_FACES, SIMPLIFY_TOLERANCE_M
from affordgrasp.tolerances import MIN_RELATIVE_VOLUME, UNION_RTOL, ZERO_AREA

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "SUPPORTED_EXTENSIONS",
    "PLAUSIBLE_SIZE_M",
    "UNITS_TO_M",
    "check_plausible_size",
    "load_mesh",
    "prepare_mesh",
]

log = logging.getLogger(__name__)

# A disjoint body under this share of the largest body's volume is a speck: kept, with a
# warning (a scan's floating noise widens the extent that places the pregrasps).
SPECK_RELATIVE_VOLUME = 1e-3
# Vertices of open edges closer than this share of the mesh's longest extent are one vertex
# written twice (a UV sphere's seam): welded before any hole is capped.
WELD_RELATIVE = 1e-6
# Bodies further apart than this share of the largest body's extent are separate (named in
# a warning); closer, they are parts of one object that touch.
SEPARATE_RELATIVE_GAP = 1e-3

# The warnings of the load in progress, when someone records them (see recording_warnings).
_RECORDED: ContextVar[list[str] | None] = ContextVar("_RECORDED", default=None)


def _warn(message: str, *args: object) -> None:
    """``log.warning``, and the message kept for :func:`recording_warnings`."""
    log.warning(message, *args)
    recorded = _RECORDED.get()
    if recorded is not None:
        recorded.append(message % args if args else message)


@contextmanager
def recording_warnings() -> Iterator[list[str]]:
    """The warnings that loading logs inside the block, as formatted messages.

    They are logged as usual too. The prepared-object cache keeps them with a mesh file's
    entry and logs them again when it loads the entry (:mod:`affordgrasp.objects.prepared`),
    whatever the logging configuration was when they were recorded.

    Yields
    ------
    list of str
        Filled while the block runs.
    """
    recorded: list[str] = []
    token = _RECORDED.set(recorded)
    try:
        yield recorded
    finally:
        _RECORDED.reset(token)


SUPPORTED_EXTENSIONS: tuple[str, ...] = (".glb", ".gltf", ".obj", ".off", ".ply", ".stl")

UNITS_TO_M: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}

# Longest extent of an object a hand can grasp. Outside it, metres are probably not the
# file's unit (a 100 mm cube read as metres is 100 m long), and mesh files are refused.
PLAUSIBLE_SIZE_M: tuple[float, float] = (0.005, 3.0)


def load_mesh(
    path: str | os.PathLike, *, size_m: float | None = None, units: str | None = None
) -> trimesh.Trimesh:
    """Read a mesh file and return it as a closed, outward-oriented solid in metres.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.obj``, ``.stl``, ``.ply``, ``.glb``, ``.gltf`` or ``.off`` file.
    size_m : float, optional
        Rescale uniformly so that the longest bounding-box extent is this many metres.
    units : str, optional
        The file's length unit, one of ``m``, ``cm``, ``mm``, ``in``, ``ft``. Without
        ``size_m`` or ``units`` the file is taken to be in metres.

    Returns
    -------
    mesh : trimesh.Trimesh
        See :func:`prepare_mesh`.
    """
    import trimesh

    _scale_request(size_m, units)  # fail on bad options before a slow read
    file = Path(path).expanduser()
    if not file.exists():
        raise MeshError(f"mesh file {str(file)!r} does not exist; check the path")
    if not file.is_file():
        raise MeshError(f"mesh path {str(file)!r} is not a file; pass a mesh file")
    ext = file.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise MeshError(
            f"unsupported mesh format {ext or '(no extension)'!r} for {file.name!r}; "
            f"supported formats: {', '.join(SUPPORTED_EXTENSIONS)}"
        )
    if ext == ".off":
        vertices, faces = read_off(file)
    else:
        vertices, faces = _read_with_trimesh(file, ext)
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    return prepare_mesh(mesh, size_m=size_m, units=units, source=file.name, check_size=True)


def prepare_mesh(
    mesh: trimesh.Trimesh,
    *,
    size_m: float | None = None,
    units: str | None = None,
    source: str = "mesh",
    check_size: bool = False,
    simplify_above: int | None = LARGE_MESH_FACES,
) -> trimesh.Trimesh:
    """Clean, repair, orient and scale a mesh into a closed solid in metres.

    The input is not modified.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Any triangle mesh: vertices (n, 3) float, faces (m, 3) int.
    size_m : float, optional
        Rescale uniformly (about the origin) so that the longest bounding-box extent is
        this many metres.
    units : str, optional
        The mesh's length unit (``m``, ``cm``, ``mm``, ``in``, ``ft``); coordinates are
        multiplied into metres. Give ``size_m`` or ``units``, not both.
    source : str
        Name of the mesh used in messages (a file name, a family id).
    check_size : bool
        Refuse a mesh whose longest extent in metres is outside ``PLAUSIBLE_SIZE_M`` (what
        a hand can grasp), with a message naming the likely unit. Without it such a mesh
        only logs a warning. :func:`load_mesh` checks.
    simplify_above : int or None
        A mesh with more triangles is first decimated to ``SIMPLIFY_TOLERANCE_M``
        (:func:`~affordgrasp.objects.simplify.simplify_to_tolerance`); a warning gives the
        triangle counts and the measured distance. Quadric decimation can open a closed
        surface (edges collapsed across a thin wall): when the decimated mesh is not closed
        and the original is, the original is kept, with a warning. None: never.

    Returns
    -------
    mesh : trimesh.Trimesh
        A new mesh, watertight with consistent outward winding (positive volume), no
        unreferenced vertices, no duplicate vertices (except where separate bodies only
        touch, each keeps its own); vertices (n, 3) float64 in metres, faces (m, 3) int64.
        ``metadata["source"]`` is ``source``.

    Raises
    ------
    MeshError
        Empty, non-finite, fully degenerate, open beyond repair, or enclosing no volume;
        with ``check_size``, an implausible size.
    InputError
        Bad ``size_m`` / ``units``.
    """
    import trimesh

    scale_kind, scale_value = _scale_request(size_m, units)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    _validate_arrays(vertices, faces, source)
    if check_size:
        # Before the repair: an implausible size is refused however the mesh looks.
        used = vertices[_used_vertices(len(vertices), faces)]
        raw_extent = float(np.ptp(used, axis=0).max())
        check_plausible_size(raw_extent, scale_kind, scale_value, units, source)

    original = None  # the mesh before a decimation that changed it
    if simplify_above is not None and len(faces) > simplify_above:
        factor = scale_value
        if scale_kind == "size_m":
            used = vertices[_used_vertices(len(vertices), faces)]
            factor = scale_value / float(np.ptp(used, axis=0).max())
        v, f = _simplified(vertices, faces, SIMPLIFY_TOLERANCE_M / factor, factor, source)
        if len(f) != len(faces):
            original, (vertices, faces) = (vertices, faces), (v, f)
    simplified = original is not None
    repairs: list[str] = []
    if scale_kind == "units":
        unit = str(units).strip().lower()

        def length(value: float) -> str:
            return f"{value:.3g} {unit}"
    else:
        used = vertices[_used_vertices(len(vertices), faces)]
        to_m = 1.0 if scale_kind is None else scale_value / float(np.ptp(used, axis=0).max())

        def length(value: float) -> str:
            return _length(value * to_m)

    # A decimated mesh is indexed already (_simplified shares a soup's vertices first), and
    # decimation can leave two vertices at one position where it pinched a surface: merging
    # them by position would make faces that repeat a vertex and edges of more than two
    # faces (a closed mug scan of 772,000 triangles, halved: 5,956 such faces dropped).
    work = _clean(vertices, faces.astype(np.int64), source, repairs, merge=not simplified)
    if simplified and not work.is_watertight:
        # The decimation opened it. Repairing a decimated scan can take tens of seconds and
        # fail; the original, when closed, is the better mesh to keep.
        kept: list[str] = []
        whole = _clean(original[0], np.asarray(original[1], dtype=np.int64), source, kept)
        if _is_closed(whole):
            _warn(
                "%s: its simplified mesh is not closed (%d open or non-manifold edges) where "
                "the original is: the original's %d triangles are kept (slower to prepare "
                "and simulate; simplify it in a mesh editor to save time)",
                source,
                _boundary_edge_count(work),
                len(whole.faces),
            )
            work, repairs = whole, kept
    work = _closed_volume(work, source, repairs, length)
    if repairs:
        # One line that says what was done, so that the user can judge the result.
        _warn("%s was repaired: %s", source, "; ".join(repairs))

    extent = float(work.extents.max())
    volume = _signed_volume(work)
    if not volume > MIN_RELATIVE_VOLUME * extent**3:
        raise MeshError(
            f"{source} encloses no volume (volume {volume:.3g} for a longest extent of "
            f"{extent:.3g}): it is a flat or open surface; close it in a mesh editor, or "
            "pass a watertight mesh"
        )

    if scale_kind == "size_m":
        factor = scale_value / extent
    else:
        factor = scale_value
        _warn_if_implausible_size(extent * factor, units or "m", source)
    vertices = np.ascontiguousarray(work.vertices, dtype=np.float64) * factor
    faces = np.ascontiguousarray(work.faces, dtype=np.int64)
    out = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    out.metadata["source"] = source
    return out


def _scale_request(size_m: float | None, units: str | None) -> tuple[str | None, float]:
    """Validate the scaling options; return ('size_m' | 'units' | None, value)."""
    if size_m is not None and units is not None:
        raise InputError(
            f"got both size_m={size_m!r} and units={units!r}; pass one: units converts the "
            "file's coordinates, size_m sets the real size"
        )
    if size_m is not None:
        try:
            value = float(size_m)
        except (TypeError, ValueError):
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"size_m must be a positive number of metres, got {size_m!r}")
        return "size_m", value
    if units is not None:
        key = str(units).strip().lower()
        if key not in UNITS_TO_M:
            raise InputError(f"unknown length unit {units!r}; use one of {', '.join(UNITS_TO_M)}")
        return "units", UNITS_TO_M[key]
    return None, 1.0


def check_plausible_size(
    raw_extent: float, scale_kind: str | None, scale_value: float, units: str | None, source: str
) -> None:
    """Refuse a mesh whose longest extent in metres is not the size of a graspable object.

    The message names the likely unit.

    Parameters
    ----------
    raw_extent : float
        The longest bounding-box extent in the file's coordinates.
    scale_kind : str or None
        How the coordinates are scaled to metres (from :func:`_scale_request`).
    scale_value : float
        The factor or target size of that scaling.
    units : str or None
        The unit the user gave, if any.
    source : str
        The mesh's name for the message.

    Raises
    ------
    MeshError
        When the extent in metres is outside ``PLAUSIBLE_SIZE_M``.
    """
    low, high = PLAUSIBLE_SIZE_M
    extent_m = scale_value if scale_kind == "size_m" else raw_extent * scale_value
    if low <= extent_m <= high:
        return
    plausible = f"an object a hand can grasp is {low * 1000:g} mm to {high:g} m long"
    if scale_kind == "size_m":
        raise MeshError(
            f"size_m {scale_value:g} makes {source} {extent_m:g} m long, but {plausible}; "
            "give its real longest extent in metres",
            parameter="size_m",
        )
    said = f"with units={units!r}" if units else "if its coordinates are metres"
    guesses = [
        (name, raw_extent * factor)
        for name, factor in UNITS_TO_M.items()
        if low <= raw_extent * factor <= high and name != (units or "m")
    ]
    # The likely unit: the first, in the order CAD files use them, that makes a hand-held
    # object (2-60 cm); else the one closest to a 20 cm tool.
    usual = {name: k for k, name in enumerate(("mm", "cm", "in", "m", "ft"))}
    guesses.sort(
        key=lambda g: (
            not 0.02 <= g[1] <= 0.6,
            usual.get(g[0], 9) if 0.02 <= g[1] <= 0.6 else abs(math.log10(g[1] / 0.2)),
        )
    )
    if guesses:
        name, size = guesses[0]
        fix = (
            f"its unit is probably {name} ({size:.3g} m long): pass units={name!r} (--units {name})"
        )
    else:
        fix = "give units= the file's unit (--units)"
    raise MeshError(
        f"{source} is {extent_m:.3g} m long {said}, but {plausible}; {fix}, or size_m= "
        "its real longest extent in metres (--size-m)"
    )


def _warn_if_implausible_size(extent_m: float, units: str, source: str) -> None:
    """Warn (and change nothing) when the size in metres is implausible for an object."""
    low, high = PLAUSIBLE_SIZE_M
    if extent_m > high:
        hint = "did you mean --units mm (or cm, in)?" if units == "m" else "check --units;"
        _warn(
            "%s is %.3g m long with units '%s'; %s Pass --size-m to set its real size.",
            source,
            extent_m,
            units,
            hint,
        )
    elif extent_m < low:
        _warn(
            "%s is only %.3g m long with units '%s'; pass --size-m to set its real size, "
            "or --units with the file's unit.",
            source,
            extent_m,
            units,
        )


def _validate_arrays(vertices: np.ndarray, faces: np.ndarray, source: str) -> None:
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise MeshError(f"{source}: vertices must be (n, 3), got shape {vertices.shape}")
    if len(vertices) == 0 or faces.size == 0:
        raise MeshError(
            f"{source} is empty ({len(vertices)} vertices, {len(faces)} faces); pass a "
            "mesh with triangles"
        )
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise MeshError(f"{source}: faces must be (m, 3) triangles, got shape {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        raise MeshError(f"{source}: faces must be integer indices, got dtype {faces.dtype}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise MeshError(
            f"{source}: a face index ({int(faces.min())}..{int(faces.max())}) is out of "
            f"range for {len(vertices)} vertices"
        )
    finite = np.isfinite(vertices).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise MeshError(
            f"{source} has {len(bad)} vertices with NaN or infinite coordinates (first: "
            f"vertex {int(bad[0])} = {vertices[bad[0]].tolist()}); fix or remove them in "
            "a mesh editor"
        )


def _used_vertices(n_vertices: int, faces: np.ndarray) -> np.ndarray:
    """(n,) bool: the vertices some face uses (a mask: np.unique sorts, 5 s on a scan)."""
    used = np.zeros(n_vertices, dtype=bool)
    used[np.asarray(faces).ravel()] = True
    return used


def _simplified(
    vertices: np.ndarray, faces: np.ndarray, tolerance: float, factor: float, source: str
) -> tuple[np.ndarray, np.ndarray]:
    """A large mesh decimated to ``tolerance`` (its units; ``factor`` converts to metres)."""
    import trimesh

    from .simplify import simplify_to_tolerance

    faces = np.asarray(faces, dtype=np.int64)
    if len(vertices) >= 2 * len(faces):  # a triangle soup (STL): share vertices first
        soup = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        soup.merge_vertices()
        vertices, faces = np.asarray(soup.vertices), np.asarray(soup.faces, dtype=np.int64)
    v, f, report = simplify_to_tolerance(vertices, faces, tolerance)
    if report.faces_after == report.faces_before:
        return vertices, faces
    within = "within" if report.within_tolerance else "NOT within"
    _warn(
        "%s has %d triangles: simplified to %d, %s the %.3g mm tolerance (the original's "
        "surface lies at most %.3g mm from it, measured at %d of its vertices)",
        source,
        report.faces_before,
        report.faces_after,
        within,
        report.tolerance * factor * 1e3,
        report.distance * factor * 1e3,
        report.sampled,
    )
    return v, f


def _clean(
    vertices: np.ndarray, faces: np.ndarray, source: str, repairs: list[str], *, merge: bool = True
) -> trimesh.Trimesh:
    """Merge duplicate vertices (unless ``merge`` is False), drop faces repeating a vertex
    and duplicate faces."""
    import trimesh

    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    if merge:
        mesh.merge_vertices()
    f = mesh.faces
    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    mesh.update_faces(~repeated)
    before = len(mesh.faces)
    if before:
        mesh.update_faces(mesh.unique_faces())
    duplicates = before - len(mesh.faces)
    mesh.remove_unreferenced_vertices()
    extent = float(np.ptp(vertices, axis=0).max())
    # Area is compared with the bounding box so that the test does not depend on units.
    if len(mesh.faces) == 0 or not mesh.area > ZERO_AREA * extent**2:
        raise MeshError(
            f"{source} is degenerate: all {len(faces)} faces have zero area; pass a mesh "
            "that encloses a volume"
        )
    if repeated.any():
        repairs.append(f"dropped {_count(int(repeated.sum()), 'degenerate face')} (a vertex twice)")
    if duplicates:
        repairs.append(f"dropped {_count(duplicates, 'duplicate face')}")
    return mesh


def _count(n: int, thing: str) -> str:
    return f"{n} {thing}" + ("" if n == 1 else "s")


def _is_closed(mesh: trimesh.Trimesh) -> bool:
    return bool(mesh.is_watertight and mesh.is_winding_consistent)


def _closed_volume(
    mesh: trimesh.Trimesh, source: str, repairs: list[str], length
) -> trimesh.Trimesh:
    """Return a closed, outward-oriented mesh equal to ``mesh`` where it was already one.

    Appends to ``repairs`` a phrase for every change (what was done, to how much), sizes
    written by ``length`` (a length in the mesh's coordinates -> text in the user's unit).
    """
    if not _is_closed(mesh):
        mesh = _welded_seams(mesh, repairs, length)
    if _is_closed(mesh):
        if mesh.body_count == 1:
            return _oriented(mesh, repairs)
        bodies = mesh.split(only_watertight=False, repair=False)
        return _combine_bodies(bodies, mesh, source, repairs, length)

    work = mesh.copy()
    zero_area = len(work.faces)
    work.update_faces(work.nondegenerate_faces())
    zero_area -= len(work.faces)
    if zero_area:
        repairs.append(f"dropped {_count(zero_area, 'zero-area face')}")
    work.remove_unreferenced_vertices()
    wound = work.faces.copy()
    _fix_normals(work)
    # _fix_normals reverses rows in place, nothing else: a changed row is a turned face
    turned = int(np.any(work.faces != wound, axis=1).sum())
    scale = float(np.ptp(work.vertices, axis=0).max())
    # The caps of earlier versions first, then manifold3d's merge, and only then the caps
    # for rims those could not close (a rim through one vertex twice, a jagged rim whose
    # planar cap would reuse an edge of the mesh): every mesh repaired before is repaired
    # the same way.
    for careful in (False, True):
        if careful:
            merged = _manifold_repair(mesh)
            if merged is not None:
                repairs.append("closed its open edges by merging nearly coincident vertices")
                return _oriented(merged, repairs)
        capped = _capped_bodies(work, scale, careful)
        if capped is None:
            continue
        bodies, holes, fins, fin_faces = capped
        if turned:
            were = "was" if turned == 1 else "were"
            repairs.append(f"re-wound {_count(turned, 'face')} that {were} wound against the rest")
        if fins:
            repairs.append(
                f"dropped {_count(fins, 'non-manifold fin')} ({_count(fin_faces, 'triangle')} "
                "of open surface enclosing no volume)"
            )
        if holes:
            widest = max(float(np.ptp(h, axis=0).max()) for h in holes)
            edges = sum(len(h) for h in holes)
            repairs.append(
                f"capped {_count(len(holes), 'hole')} ({edges} boundary edges, the widest "
                f"{length(widest)} across) with flat faces"
            )
        return _combine_bodies(bodies, None, source, repairs, length, quiet_flat=fins)

    open_edges = _boundary_edge_count(work)
    raise MeshError(
        f"{source} is not a closed volume: {open_edges} edge(s) are open or shared by more "
        "than two faces after repair; close it in a mesh editor, or pass a watertight mesh"
    )


def _capped_bodies(work: trimesh.Trimesh, scale: float, careful: bool):
    """Each connected part of ``work`` with its holes capped, or None when one stays open.

    Returns (bodies, the holes' rims, open sheets dropped, their faces). Split first: at an
    edge shared by more than two faces (closed parts touching) the face adjacency stops, so
    each part is closed on its own and then unioned.
    """
    bodies = list(work.split(only_watertight=False, repair=False)) or [work.copy()]
    holes: list[np.ndarray] = []
    fins = fin_faces = 0
    for body in bodies:
        if not _is_closed(body):
            open_faces = len(body.faces)
            loops = _fill_holes(body, careful=careful)
            _fix_normals(body)
            if abs(_signed_volume(body)) <= MIN_RELATIVE_VOLUME * scale**3:
                # An open sheet (a fin hanging off an edge, a stray triangle): it encloses
                # nothing and is dropped with the flat parts.
                fins += 1
                fin_faces += open_faces
            else:
                holes += [body.vertices[loop] for loop in loops]
    if not all(_is_closed(body) for body in bodies):
        return None
    return bodies, holes, fins, fin_faces


def _fix_normals(mesh: trimesh.Trimesh) -> None:
    """Consistent, outward winding per body, in place (trimesh's ``fix_normals`` with the
    winding made consistent by :func:`_consistent_winding`)."""
    import trimesh

    wound = _consistent_winding(mesh.faces)
    if wound is not None:
        mesh.faces = wound
    # trimesh divides by the volume on its way; a flat part has none, and is refused later.
    with np.errstate(divide="ignore", invalid="ignore"):
        trimesh.repair.fix_inversion(mesh, multibody=True)


def _consistent_winding(faces: np.ndarray) -> np.ndarray | None:
    """The faces with every connected part wound consistently, or None if they are.

    What ``trimesh.repair.fix_winding`` does (a breadth-first walk over faces sharing an
    edge used by exactly two faces, each face flipped when it runs that edge the same way
    as the face it is reached from), with the walk done by scipy's compiled graph search
    instead of a Python loop per face (trimesh's took 5 s on a 170,000-triangle scan); each
    part keeps the winding of most of its faces.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    faces = np.asarray(faces, dtype=np.int64)
    n = len(faces)
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    _, inverse, counts = np.unique(
        _edge_keys(directed, int(faces.max()) + 1 if n else 0),
        return_inverse=True,
        return_counts=True,
    )
    inverse = inverse.ravel()
    shared = np.flatnonzero(counts[inverse] == 2)
    shared = shared[np.argsort(inverse[shared], kind="stable")]
    a, b = shared[0::2], shared[1::2]  # the two uses of each manifold edge
    fa, fb = a // 3, b // 3
    same = directed[a, 0] == directed[b, 0]  # the edge run the same way: one face is flipped
    if not same.any():
        return None
    # one parity per pair of faces (the first edge they share, as trimesh), by sorted key
    pairs, first = np.unique(np.minimum(fa, fb) * n + np.maximum(fa, fb), return_index=True)
    fa, fb, same = fa[first], fb[first], same[first]
    graph = coo_matrix((np.ones(len(fa)), (fa, fb)), shape=(n, n)).tocsr()
    _, labels = connected_components(graph, directed=False)
    # a root joined to the first face of every part: one walk covers them all
    roots = np.unique(labels, return_index=True)[1]
    rows = np.r_[fa, np.full(len(roots), n)]
    cols = np.r_[fb, roots]
    walk = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    order, parent = breadth_first_order(walk, n, directed=False, return_predecessors=True)
    order = order[1:]  # the root first
    up = parent[order]
    step = np.zeros(len(order), dtype=bool)  # a root's child keeps its winding
    child = up != n
    lo, hi = np.minimum(up[child], order[child]), np.maximum(up[child], order[child])
    step[child] = same[np.searchsorted(pairs, lo * n + hi)]
    flip = np.zeros(n + 1, dtype=bool)
    for face, above, turn in zip(order.tolist(), up.tolist(), step.tolist(), strict=True):
        flip[face] = flip[above] ^ turn
    flip = flip[:n]
    # each part keeps the winding most of its faces have: the fewest faces turned
    turned = np.bincount(labels, weights=flip) > np.bincount(labels) / 2
    flip ^= turned[labels]
    if not flip.any():
        return None
    out = faces.copy()
    out[flip] = out[flip][:, ::-1]
    return out


def _signed_volume(mesh: trimesh.Trimesh) -> float:
    """Enclosed volume, negative for an inside-out mesh (divergence theorem)."""
    # About the box centre: far from the origin the triple products would cancel badly.
    vertices = mesh.vertices - mesh.bounds.mean(axis=0)
    a, b, c = (vertices[mesh.faces[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0)


def _oriented(mesh: trimesh.Trimesh, repairs: list[str] | None = None) -> trimesh.Trimesh:
    if _signed_volume(mesh) < 0:
        mesh = mesh.copy()
        mesh.invert()
        if repairs is not None:
            repairs.append("turned it outside out (every face pointed inwards)")
    return mesh


def _length(metres: float) -> str:
    return f"{metres * 1000:.3g} mm" if metres < 1 else f"{metres:.3g} m"


def _combine_bodies(
    bodies: list[trimesh.Trimesh],
    whole: trimesh.Trimesh | None,
    source: str,
    repairs: list[str],
    length,
    quiet_flat: int = 0,
) -> trimesh.Trimesh:
    """One solid from closed bodies: union overlaps, flip inverted bodies, keep cavities.

    ``whole`` is the unchanged input when the bodies are just its split; it is returned as
    it is when nothing overlaps, so a clean mesh keeps its vertex order.
    """
    import trimesh

    scale = max(float(np.ptp(b.bounds, axis=0).max()) for b in bodies)
    solid_bodies = [b for b in bodies if abs(_signed_volume(b)) > MIN_RELATIVE_VOLUME * scale**3]
    if len(solid_bodies) < len(bodies):
        # Flat parts (a fin, a label) closed onto themselves add nothing to the solid.
        flat = len(bodies) - len(solid_bodies) - quiet_flat  # fins are reported already
        if flat > 0:
            repairs.append(f"dropped {_count(flat, 'flat closed part')} enclosing no volume")
        bodies, whole = solid_bodies or bodies, None
    if len(bodies) == 1:
        return _oriented(bodies[0], repairs)
    volumes = np.array([_signed_volume(b) for b in bodies])
    outer = [b for b, v in zip(bodies, volumes, strict=True) if v > 0]
    cavities = []
    flipped = False
    for body, volume in zip(bodies, volumes, strict=True):
        if volume > 0:
            continue
        point = body.vertices[:1]
        if any(bool(o.contains(point)[0]) for o in outer):
            cavities.append(body)
        else:
            # A body facing inwards but inside nothing is an inverted part, not a hole.
            inverted = body.copy()
            inverted.invert()
            outer.append(inverted)
            flipped = True
    if flipped:
        repairs.append("turned inside-out bodies outside out")

    import manifold3d

    solid = manifold3d.Manifold.batch_boolean([_to_manifold(b) for b in outer], _op("Add"))
    if cavities:
        flipped_cavities = []
        for cavity in cavities:
            c = cavity.copy()
            c.invert()
            flipped_cavities.append(_to_manifold(c))
        holes = manifold3d.Manifold.batch_boolean(flipped_cavities, _op("Add"))
        solid = manifold3d.Manifold.batch_boolean([solid, holes], _op("Subtract"))
    expected = sum(_signed_volume(b) for b in [*outer, *cavities])
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        _warn(
            "%s: could not union its %d bodies (%s); using them as they are, overlaps "
            "would be counted twice in the mass properties",
            source,
            len(bodies),
            solid.status(),
        )
        return _oriented(trimesh.util.concatenate([*outer, *cavities]))
    if abs(solid.volume() - expected) <= UNION_RTOL * abs(expected):
        # Disjoint bodies: keep the input's own vertices and faces.
        _warn_apart(outer, source, length)
        if whole is not None and not flipped:
            return _oriented(whole)
        return _oriented(trimesh.util.concatenate([*outer, *cavities]))
    repairs.append(f"merged {len(bodies)} overlapping bodies into one solid (their union)")
    return _oriented(_from_manifold(solid), repairs)


def _warn_apart(bodies: list[trimesh.Trimesh], source: str, length) -> None:
    """Say so when disjoint bodies are kept as one rigid object: specks (a scan's floating
    noise) widen the extent that places the pregrasps; bodies of some size apart from the
    others are graded as if joined to them."""
    volumes = np.array([abs(_signed_volume(b)) for b in bodies])
    largest = int(np.argmax(volumes))
    is_speck = volumes < SPECK_RELATIVE_VOLUME * volumes[largest]
    specks = int(is_speck.sum())
    if specks:
        low = np.min([b.bounds[0] for b in bodies], axis=0)
        high = np.max([b.bounds[1] for b in bodies], axis=0)
        _warn(
            "%s: %d of its %d disjoint bodies hold%s under %.2g %% of the largest one's volume "
            "(floating specks of a scan?); kept, they widen the object's extent from %s to %s, "
            "which moves where grasps are aimed: remove them in a mesh editor if they are noise",
            source,
            specks,
            len(bodies),
            "s" if specks == 1 else "",
            SPECK_RELATIVE_VOLUME * 100,
            length(float(np.ptp(bodies[largest].bounds, axis=0).max())),
            length(float(np.ptp(np.stack([low, high]), axis=0).max())),
        )
    parts = [b for b, speck in zip(bodies, is_speck, strict=True) if not speck]
    labels, gap = _contact_groups(parts)
    if labels.max() > 0:
        bounds = np.array([p.bounds for p in parts])  # (n, 2, 3)
        sizes = [
            float(np.ptp(bounds[labels == g].reshape(-1, 3), axis=0).max())
            for g in range(labels.max() + 1)
        ]
        _warn(
            "%s holds %d separate bodies (%s long), the closest %s apart: they are graded as "
            "ONE rigid object, as if joined; if they are separate objects, give each its own "
            "mesh file (or join them in a mesh editor)",
            source,
            len(sizes),
            ", ".join(length(x) for x in sorted(sizes, reverse=True)),
            length(gap),
        )


def _contact_groups(bodies: list[trimesh.Trimesh]) -> tuple[np.ndarray, float]:
    """The group of each body, bodies closer than ``SEPARATE_RELATIVE_GAP`` of the largest
    extent sharing one, and the smallest gap between two groups (0 for one group)."""
    from scipy.sparse.csgraph import connected_components

    n = len(bodies)
    scale = max(float(np.ptp(b.bounds, axis=0).max()) for b in bodies)
    solids = [_to_manifold(b) for b in bodies]
    gaps = np.full((n, n), np.inf)
    for i in range(n):
        for j in range(i + 1, n):
            gaps[i, j] = solids[i].min_gap(solids[j], scale)
    _, labels = connected_components(gaps <= SEPARATE_RELATIVE_GAP * scale, directed=False)
    apart = gaps[(labels[:, None] != labels[None, :]) & np.isfinite(gaps)]
    return labels, float(apart.min(initial=scale))


def _welded_seams(mesh: trimesh.Trimesh, repairs: list[str], length) -> trimesh.Trimesh:
    """``mesh`` with the vertices of its open edges closer than ``WELD_RELATIVE`` of its
    longest extent welded into one (a seam written twice); ``mesh`` itself when none are."""
    import trimesh
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    n = len(mesh.vertices)
    edges = mesh.edges_sorted
    _, inverse, counts = np.unique(_edge_keys(edges, n), return_inverse=True, return_counts=True)
    rim = np.unique(edges[counts[inverse.ravel()] == 1])
    tolerance = WELD_RELATIVE * float(np.ptp(mesh.vertices, axis=0).max())
    pairs = cKDTree(mesh.vertices[rim]).query_pairs(tolerance, output_type="ndarray")
    if len(pairs) == 0:
        return mesh
    a, b = rim[pairs[:, 0]], rim[pairs[:, 1]]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    first = np.full(labels.max() + 1, n)
    np.minimum.at(first, labels, np.arange(n))
    faces = first[labels][mesh.faces]
    keep = (
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    )
    welded = trimesh.Trimesh(mesh.vertices, faces[keep], process=False)
    welded.update_faces(welded.unique_faces())
    welded.remove_unreferenced_vertices()
    gap = float(np.linalg.norm(mesh.vertices[a] - mesh.vertices[b], axis=1).max())
    repairs.append(
        f"welded {n - len(welded.vertices)} vertices of its open edges onto others at most "
        f"{length(gap)} away (a seam written with its two sides apart)"
    )
    return welded


def _fill_holes(mesh: trimesh.Trimesh, *, careful: bool = False) -> list[np.ndarray]:
    """Cap every boundary loop of a consistently wound mesh in place; return the loops.

    Each cap is the loop triangulated in its best-fit plane, wound against the boundary
    edges so that the result stays consistently wound. Loops that cannot be traced (a
    vertex where the boundary branches oddly) are left open. With ``careful``, a loop
    through one vertex twice is capped as simple loops, and a cap whose triangulation
    drops an ear or reuses an edge of the mesh off its rim is a fan from the rim's centroid.
    """
    faces = mesh.faces
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    keys = _edge_keys(directed, len(mesh.vertices))
    existing, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    boundary = directed[counts[inverse.ravel()] == 1]
    if len(boundary) == 0:
        return []
    # The cap runs each boundary edge backwards.
    successors: dict[int, list[int]] = defaultdict(list)
    for a, b in boundary[:, ::-1].tolist():
        successors[a].append(b)
    loops = []
    for start in sorted(successors):
        while successors[start]:
            loop = [start]
            current = successors[start].pop()
            while current != start and successors[current] and len(loop) <= len(boundary):
                loop.append(current)
                current = successors[current].pop()
            if current == start and len(loop) >= 3:
                loops += _simple_loops(loop) if careful else [np.array(loop, dtype=np.int64)]
    if not loops:
        return []
    n = len(mesh.vertices)
    caps, centres = [], []
    for loop in loops:
        cap = loop[triangulate_polygon(mesh.vertices[loop])]
        if careful and (
            len(cap) < len(loop) - 2
            or _reuses_an_edge(cap, loop, existing, n)
            or not _wound_with_rim(cap, loop, n)
        ):
            # A jagged rim (a scan cut open at its base) where the planar triangulation
            # drops an ear, draws a diagonal that is already an edge of the mesh (a
            # triangle with two rim edges) or folds over (a noisy rim whose projection
            # crosses itself): a fan from a new vertex at the rim's centroid uses no edge
            # but the rim's, each once, and is wound with it.
            centre = n + len(centres)
            centres.append(mesh.vertices[loop].mean(axis=0))
            cap = np.stack([loop, np.roll(loop, -1), np.full(len(loop), centre)], axis=1)
        caps.append(cap)
    if centres:
        mesh.vertices = np.vstack([mesh.vertices, np.array(centres)])
    mesh.faces = np.vstack([faces, *caps])
    return loops


def _simple_loops(loop: list[int]) -> list[np.ndarray]:
    """A traced boundary loop split where it passes a vertex twice (a rim pinched to one
    vertex: a figure of eight), so that each cap is a simple polygon."""
    out, stack, where = [], [], {}
    for v in loop:
        if v in where:
            i = where[v]
            if len(stack) - i >= 3:
                out.append(np.array(stack[i:], dtype=np.int64))
            for u in stack[i + 1 :]:
                del where[u]
            del stack[i + 1 :]
        else:
            where[v] = len(stack)
            stack.append(v)
    if len(stack) >= 3:
        out.append(np.array(stack, dtype=np.int64))
    return out


def _edge_keys(edges: np.ndarray, n_vertices: int) -> np.ndarray:
    """One int64 per undirected edge (sorting pairs as rows is several times slower)."""
    edges = np.asarray(edges, dtype=np.int64)
    return np.minimum(edges[:, 0], edges[:, 1]) * n_vertices + np.maximum(edges[:, 0], edges[:, 1])


def _reuses_an_edge(cap: np.ndarray, loop: np.ndarray, existing: np.ndarray, n: int) -> bool:
    """Whether a cap's triangles use an edge of the mesh (sorted ``existing`` keys of ``n``
    vertices) that is not on its rim."""
    rim = _edge_keys(np.stack([loop, np.roll(loop, -1)], axis=1), n)
    keys = _edge_keys(cap[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), n)
    return bool(np.any(np.isin(keys, existing) & ~np.isin(keys, rim)))


def _wound_with_rim(cap: np.ndarray, loop: np.ndarray, n: int) -> bool:
    """Whether a cap and the rim's edges as the mesh runs them (against ``loop``) form a
    consistently wound closed surface: every edge run once each way."""
    rim = np.stack([np.roll(loop, -1), loop], axis=1)
    edges = np.vstack([cap[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), rim])
    keys, back = edges @ np.array([n, 1]), edges[:, ::-1] @ np.array([n, 1])
    return len(np.unique(keys)) == len(keys) and bool(np.isin(back, keys).all())


def _boundary_edge_count(mesh: trimesh.Trimesh) -> int:
    _, counts = np.unique(_edge_keys(mesh.edges, len(mesh.vertices)), return_counts=True)
    return int((counts != 2).sum())


def _op(name: str):
    import manifold3d

    return getattr(manifold3d.OpType, name)


def _to_manifold(mesh: trimesh.Trimesh, merge: bool = False):
    """A manifold3d.Manifold of a mesh, in float64 where this manifold3d has it."""
    import manifold3d

    mesh64 = getattr(manifold3d, "Mesh64", None)
    if mesh64 is not None:
        data = mesh64(
            vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint64),
        )
    else:  # pragma: no cover - older manifold3d
        data = manifold3d.Mesh(
            vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint32),
        )
    if merge:
        data.merge()
    return manifold3d.Manifold(data)


def _from_manifold(solid) -> trimesh.Trimesh:
    import trimesh

    data = solid.to_mesh64() if hasattr(solid, "to_mesh64") else solid.to_mesh()
    vertices = np.asarray(data.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(data.tri_verts, dtype=np.int64)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def _manifold_repair(mesh: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """Let manifold3d merge nearly coincident open-edge vertices; None when that fails."""
    import manifold3d

    solid = _to_manifold(mesh, merge=True)
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        return None
    out = _from_manifold(solid)
    return out if _is_closed(out) else None


def _read_with_trimesh(file: Path, ext: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float64 and faces (m, 3) int64 of every mesh in a file's scene."""
    import trimesh

    try:
        scene = trimesh.load_scene(file, file_type=ext[1:], process=False)
    except Exception as exc:  # trimesh raises many types on malformed files
        raise MeshError(
            f"cannot read {file.name!r} as {ext[1:].upper()}: {exc}; check that the file is "
            "complete and really in that format"
        ) from exc
    vertices, faces = [], []
    offset = 0
    for node in scene.graph.nodes_geometry:
        transform, geometry_name = scene.graph[node]
        geometry = scene.geometry.get(geometry_name)
        if not isinstance(geometry, trimesh.Trimesh) or len(geometry.faces) == 0:
            continue
        vertices.append(trimesh.transform_points(geometry.vertices, transform))
        faces.append(np.asarray(geometry.faces, dtype=np.int64) + offset)
        offset += len(geometry.vertices)
    if not faces:
        raise MeshError(
            f"{file.name!r} has no faces; affordgrasp needs a surface mesh (is it a point "
            "cloud or a line drawing?)"
        )
    return np.concatenate(vertices).astype(np.float64), np.concatenate(faces)
