"""Semantic parts of the procedural families: one part label per mesh face.

Each family builds its solid from named pieces (a grip, a blade, a head, ...) and unites
them with exact booleans. manifold3d keeps, for every output triangle, the id of the input
solid it came from, so :func:`tag` records which piece is which part and
:func:`face_parts_of` turns the output's triangle runs into one label per face, with no
change to the geometry (the mesh bytes are the same with and without labels). A family's
refinement then splits a piece into its functional parts from the family's frame (see
:mod:`affordgrasp.objects.families`): the cutting edge of a blade is the band of faces
that touch its sharp edge line (interior dihedral angle below 45°, the only sharp edges of
the families), the striking face of a hammer is the end of its head facing -y, and so on.

Labels are indices into :data:`PART_NAMES`; the vocabulary is shared by every family.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator, Mapping

import manifold3d
import numpy as np
import trimesh
from scipy.spatial import cKDTree

from ...errors import InternalError
from ...rays.mesh import mesh_caster

__all__ = ["PART_NAMES", "part_index", "tag", "recording", "face_parts_of", "refine_parts"]

PART_NAMES: tuple[str, ...] = (
    "body",
    "handle",
    "blade",
    "cutting_edge",
    "spine",
    "tip",
    "guard",
    "pommel",
    "head",
    "striking_face",
    "claw",
    "peen",
    "poll",
    "shaft",
    "edge",
    "rim",
    "base",
    "inside",
    "neck",
    "bowl",
    "stem",
    "foot",
)
_INDEX = {name: i for i, name in enumerate(PART_NAMES)}

# interior dihedral angle below which a convex mesh edge is a sharp (cutting) edge
SHARP_EDGE_RAD = np.radians(45.0)
# widest cutting-edge band: blade bevels are 1.5-7 mm wide, the axe's about 10 mm
EDGE_BAND_M = 0.012

_RECORDER: contextvars.ContextVar[Recorder | None] = contextvars.ContextVar(
    "affordgrasp_part_recorder", default=None
)


def part_index(name: str) -> int:
    """Index of a part name in :data:`PART_NAMES`.

    Parameters
    ----------
    name : str
        A part name.

    Returns
    -------
    int
        The label that stands for it in ``face_parts`` arrays.
    """
    return _INDEX[name]


def tag(solid: manifold3d.Manifold, part: str) -> manifold3d.Manifold:
    """Record that the triangles of ``solid`` belong to ``part``.

    Outside :func:`recording` this does nothing. A triangle keeps the first part recorded
    for its source solid, so tag a piece before uniting it with others.

    Parameters
    ----------
    solid : manifold3d.Manifold
        A piece of a family's object, before the booleans.
    part : str
        One of :data:`PART_NAMES`.

    Returns
    -------
    manifold3d.Manifold
        ``solid`` itself, unchanged.

    Raises
    ------
    ValueError
        When ``part`` is not in :data:`PART_NAMES`.
    """
    if part not in _INDEX:
        raise ValueError(f"unknown part {part!r}; parts: {', '.join(PART_NAMES)}")
    recorder = _RECORDER.get()
    if recorder is not None:
        for run_id in np.asarray(solid.to_mesh64().run_original_id).tolist():
            recorder.setdefault(int(run_id), part)
        recorder.pieces.append((part, solid))
    return solid


class Recorder(dict):
    """Source id -> part name of the tagged triangles, and the tagged solids themselves.

    ``pieces`` lists ``(part, solid)`` in tagging order, in the frame they were tagged in
    (the families tag pieces where they end up, so the pieces give the parts' volumes).
    """

    def __init__(self) -> None:
        super().__init__()
        self.pieces: list[tuple[str, manifold3d.Manifold]] = []


@contextlib.contextmanager
def recording() -> Iterator[Recorder]:
    """Collect the :func:`tag` calls of one family build (a context manager).

    Yields
    ------
    Recorder
        Source solid id (manifold's ``run_original_id``) -> part name, filled by the
        :func:`tag` calls made inside the ``with`` block, and the tagged solids
        (``pieces``).
    """
    recorder = Recorder()
    token = _RECORDER.set(recorder)
    try:
        yield recorder
    finally:
        _RECORDER.reset(token)


def face_parts_of(solid: manifold3d.Manifold, recorder: Mapping[int, str]) -> np.ndarray:
    """The part label of each triangle of ``solid.to_mesh64()``, in its order.

    Parameters
    ----------
    solid : manifold3d.Manifold
        The family's united solid.
    recorder : mapping of int to str
        What :func:`recording` collected.

    Returns
    -------
    (n_faces,) int8 ndarray
        Indices into :data:`PART_NAMES`; triangles whose source solid was not tagged get
        ``"body"``.
    """
    mesh = solid.to_mesh64()
    run_ids = np.asarray(mesh.run_original_id, dtype=np.int64)
    run_index = np.asarray(mesh.run_index, dtype=np.int64)
    counts = np.diff(run_index) // 3
    labels = np.array([_INDEX[recorder.get(int(r), "body")] for r in run_ids], dtype=np.int8)
    out = np.repeat(labels, counts)
    n_tri = len(np.asarray(mesh.tri_verts))
    if len(out) != n_tri:  # pragma: no cover - manifold always covers every triangle
        raise InternalError(f"triangle runs cover {len(out)} of {n_tri} triangles")
    return out


# --------------------------------------------------------------------------------------
# geometric refinement, per family (frame: see affordgrasp.objects.families)
# --------------------------------------------------------------------------------------


def sharp_edge_faces(mesh: trimesh.Trimesh) -> np.ndarray:
    """The band of faces along the sharp edges (the edge's flanks).

    The faces that border a convex edge sharper than 45° are the flanks' first row; the
    band grows from them across smooth edges (dihedral below 3°, so along a flank's plane
    and a gently curved bevel, never over the shoulder onto the blade's flat or round an
    end cap) to the faces whose vertices all lie within ``EDGE_BAND_M`` of the sharp edge
    segments or that touch the edge line: the whole bevel, also where it is meshed in
    several rows or in long slivers.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object's mesh, m.

    Returns
    -------
    (n_faces,) bool ndarray
    """
    angles = np.asarray(mesh.face_adjacency_angles)  # between normals: π - interior angle
    adjacency = np.asarray(mesh.face_adjacency)
    sharp = np.asarray(mesh.face_adjacency_convex) & (np.pi - angles < SHARP_EDGE_RAD)
    faces = np.asarray(mesh.faces)
    band = np.zeros(len(faces), dtype=bool)
    if not sharp.any():
        return band
    V = np.asarray(mesh.vertices)
    seg = V[np.asarray(mesh.face_adjacency_edges)[sharp]]  # (k, 2, 3)
    # distance of every vertex to the nearest sharp segment, by a dense sampling of the
    # segments (spacing 0.5 mm) refined exactly on the nearest few samples
    a, ab = seg[:, 0], seg[:, 1] - seg[:, 0]
    n_s = np.ceil(np.linalg.norm(ab, axis=1) / 5e-4).astype(np.int64) + 1
    owner = np.repeat(np.arange(len(seg)), n_s)
    t = (np.arange(owner.size) - np.repeat(np.cumsum(n_s) - n_s, n_s)) / (n_s[owner] - 1)
    tree = cKDTree(a[owner] + t[:, None] * ab[owner])
    near, _ = tree.query(V, distance_upper_bound=EDGE_BAND_M + 1e-3)
    on_line = np.zeros(len(V), dtype=bool)
    on_line[np.asarray(mesh.face_adjacency_edges)[sharp].ravel()] = True
    # a face of the flank plane that reaches the edge line is on the bevel however far its
    # other corners lie (a long sliver across a double-edged blade's flank)
    inside = (near <= EDGE_BAND_M + 2.5e-4)[faces].all(axis=1) | on_line[faces].any(axis=1)
    band[adjacency[sharp].ravel()] = True
    smooth = (angles < np.radians(3.0)) & ~sharp
    pairs = adjacency[smooth]
    pairs = pairs[inside[pairs].all(axis=1)]
    while True:  # flood fill over smooth edges inside the band
        grow = band[pairs[:, 0]] ^ band[pairs[:, 1]]
        if not grow.any():
            return band
        band[pairs[grow].ravel()] = True


def _set(labels: np.ndarray, mask: np.ndarray, part: str) -> None:
    labels[mask] = _INDEX[part]


def _is(labels: np.ndarray, *parts: str) -> np.ndarray:
    return np.isin(labels, [_INDEX[p] for p in parts])


def _blade(mesh: trimesh.Trimesh, labels: np.ndarray, single_edged: bool) -> np.ndarray:
    """Blade pieces: spine (single-edged), tip (the last 12 mm towards +x), cutting edge."""
    centers = np.asarray(mesh.triangles_center)
    normals = np.asarray(mesh.face_normals)
    blade = _is(labels, "blade")
    if not blade.any():
        return labels
    x_tip = centers[blade, 0].max()
    if single_edged:
        _set(labels, blade & (normals[:, 1] > 0.7), "spine")
    _set(labels, blade & (centers[:, 0] > x_tip - 0.012), "tip")
    _set(labels, _is(labels, "blade", "spine", "tip") & sharp_edge_faces(mesh), "cutting_edge")
    return labels


def _knife(mesh, labels, params):
    return _blade(mesh, labels, single_edged=True)


def _double_edged(mesh, labels, params):
    return _blade(mesh, labels, single_edged=False)


def _hammer(mesh, labels, params):
    centers = np.asarray(mesh.triangles_center)
    normals = np.asarray(mesh.face_normals)
    head = _is(labels, "head")
    y_face = centers[head, 1].min()
    # the flat face and its 1.5 mm chamfer, at the head's -y end
    _set(labels, head & (centers[:, 1] < y_face + 0.002) & (normals[:, 1] < -0.5), "striking_face")
    return labels


def _axe(mesh, labels, params):
    centers = np.asarray(mesh.triangles_center)
    normals = np.asarray(mesh.face_normals)
    head = _is(labels, "head")
    y_back = centers[head, 1].max()
    _set(labels, head & (centers[:, 1] > y_back - 0.004) & (normals[:, 1] > 0.5), "poll")
    _set(labels, head & sharp_edge_faces(mesh), "cutting_edge")
    return labels


def _screwdriver(mesh, labels, params):
    centers = np.asarray(mesh.triangles_center)
    shaft = _is(labels, "shaft")
    x_tip = centers[shaft, 0].max()
    tip_len = float(params.get("tip_length_m", 0.01))
    _set(labels, shaft & (centers[:, 0] > x_tip - tip_len), "tip")
    return labels


def _spatula(mesh, labels, params):
    centers = np.asarray(mesh.triangles_center)
    blade = _is(labels, "blade")
    x_front = centers[blade, 0].max()
    # the chisel-ground front, where it slides under food
    bevel = float(params.get("bevel_length_m", 0.006))
    _set(labels, blade & (centers[:, 0] > x_front - bevel), "edge")
    return labels


def _container(mesh, labels, params, zones: Callable | None = None):
    """Rim (top 3 mm), base (bottom 3 mm), inside (faces that look into the cavity)."""
    centers = np.asarray(mesh.triangles_center)
    normals = np.asarray(mesh.face_normals)
    body = _is(labels, "body")
    zb = centers[body, 2]
    z_lo, z_hi = zb.min(), zb.max()
    axis_xy = 0.5 * (
        mesh.vertices[np.unique(mesh.faces[body])][:, :2].min(axis=0)
        + mesh.vertices[np.unique(mesh.faces[body])][:, :2].max(axis=0)
    )
    radial = centers[:, :2] - axis_xy
    r = np.linalg.norm(radial, axis=1)
    n_radial = np.einsum("ij,ij->i", normals[:, :2], radial) / np.maximum(r, 1e-9)
    # Inner wall faces look towards the axis; the cavity floor looks up from inside it:
    # both see the object again along their outward normal.
    origins = centers + 1e-5 * normals
    hits = mesh_caster(mesh).intersects_any(origins, normals)
    inward = (n_radial < -0.2) | (normals[:, 2] > 0.6)
    _set(labels, body & hits & inward, "inside")
    if zones is not None:
        zones(labels, body & ~hits | body & ~inward, centers, r, z_lo, z_hi)
    _set(labels, body & (centers[:, 2] < z_lo + 0.003) & (normals[:, 2] < -0.3), "base")
    _set(labels, body & (centers[:, 2] > z_hi - 0.003), "rim")
    return labels


def _bottle(mesh, labels, params):
    def zones(lab, outer, centers, r, z_lo, z_hi):
        neck_r = float(params.get("neck_radius_m", 0.013))
        _set(lab, outer & (r < neck_r * 1.25) & (centers[:, 2] > 0.5 * (z_lo + z_hi)), "neck")

    return _container(mesh, labels, params, zones)


def _wine_glass(mesh, labels, params):
    def zones(lab, outer, centers, r, z_lo, z_hi):
        stem_r = float(params.get("stem_radius_m", 0.004))
        low = centers[:, 2] < z_lo + 0.5 * (z_hi - z_lo)
        foot = outer & low & (r > 1.6 * stem_r) & (centers[:, 2] < z_lo + 0.02)
        _set(lab, foot, "foot")
        _set(lab, outer & low & (r <= 1.6 * stem_r), "stem")
        _set(lab, outer & ~low & _is(lab, "body"), "bowl")

    return _container(mesh, labels, params, zones)


def _plain_container(mesh, labels, params):
    return _container(mesh, labels, params)


REFINERS: dict[str, Callable] = {
    "knife": _knife,
    "meat_cleaver": _knife,
    "dagger": _double_edged,
    "sword": _double_edged,
    "hammer": _hammer,
    "axe": _axe,
    "screwdriver": _screwdriver,
    "spatula": _spatula,
    "bottle": _bottle,
    "wine_glass": _wine_glass,
    "tumbler": _plain_container,
    "mug": _plain_container,
    "ice_cream_cone": _plain_container,
}


def refine_parts(family: str, mesh: trimesh.Trimesh, labels: np.ndarray, params) -> np.ndarray:
    """Split a family's tagged pieces into functional parts (see the module docstring).

    Parameters
    ----------
    family : str
        The family's name; a family without a refinement keeps its labels.
    mesh : trimesh.Trimesh
        The object's mesh in the family's frame, m.
    labels : (n_faces,) int8 ndarray
        The labels of :func:`face_parts_of`; not modified.
    params : mapping of str to float
        The object's family parameters (some refinements read sizes from them, e.g.
        ``tip_length_m``).

    Returns
    -------
    (n_faces,) int8 ndarray
        A new label array.
    """
    refine = REFINERS.get(family)
    return refine(mesh, labels.copy(), params) if refine is not None else labels
