"""Scan-like objects: a seeded degradation of a crisp mesh into what a 3D scanner returns.

Real scans of tools differ from the procedural families in four ways that matter to the
tasks: the triangles are small and of one size, sharp edges are rounded (a 2 mm blade's
cutting edge shows dihedral angles of 30-90° instead of 14-26°), the surface is noisy
(σ ≈ 0.1-0.3 mm) and small holes have been closed by a repair. :func:`scan_like` applies
the four to any closed mesh, in this order, each with a documented parameter
(:class:`ScanSettings`):

1. **Remeshing** to a scanner-like triangle size: every edge split to at most
   ``triangle_m`` (manifold3d's ``refine_to_length``), so a blade's long edge becomes a
   line of millimetre triangles.
2. **Edge rounding** limited to a radius: the vertices within ``round_radius_m`` of a crease
   (adjacent faces more than 20° apart) are moved by ``round_iterations`` damped uniform
   Laplacian steps (λ = 0.5) while every other vertex stays fixed. The fixed band boundary confines
   the rounding to a strip of about twice the radius: a wedge's crest retracts into a
   round, flats, handles and the overall size are untouched.
3. **Surface noise**: each vertex moves along its normal by a spatially correlated
   Gaussian field (white noise averaged over its 1-ring twice, then scaled to standard
   deviation ``noise_m``), as a scanner's depth noise after its own light smoothing.
4. **Small holes closed by the loader**: ``holes`` patches (a face and its 1-ring, about
   two triangle sizes wide) are cut out and capped by
   :func:`affordgrasp.objects.loading.prepare_mesh`, as a mesh file's holes are.

Part labels (``face_parts``) follow each face: remeshing keeps the label of the face it
came from, caps take the label of the nearest face. Randomness (noise, holes) comes from
``numpy.random.default_rng(seed)`` only: the same mesh, settings and seed give the same
bytes.

On the command line a scan-like variant is named by appending ``~scan`` to an object spec
(``knife:3~scan``: seed 3 for the degradation too; ``knife:3~scan:5``: degradation seed 5;
``tool.obj~scan``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from affordgrasp.errors import InputError

if TYPE_CHECKING:
    import trimesh

__all__ = ["SCAN_SUFFIX", "ScanSettings", "scan_like", "split_scan_spec"]

SCAN_SUFFIX = "~scan"
_CREASE_RAD = np.radians(20.0)  # adjacent faces further apart than this form a crease


@dataclass(frozen=True)
class ScanSettings:
    """Parameters of :func:`scan_like` (defaults: a hand-held structured-light scanner).

    Attributes
    ----------
    triangle_m : float
        Longest edge after remeshing, m (1 mm).
    round_radius_m : float
        Half-width of the band around creases that is smoothed, m (0.5 mm).
    round_iterations : int
        Laplacian steps inside the band (20: enough for the band to relax).
    noise_m : float
        Standard deviation of the normal displacement, m (0.15 mm).
    holes : int
        Small holes cut and capped (2).
    """

    triangle_m: float = 1.0e-3
    round_radius_m: float = 0.5e-3
    round_iterations: int = 20
    noise_m: float = 0.15e-3
    holes: int = 2

    def __post_init__(self) -> None:
        for name in ("triangle_m", "round_radius_m", "noise_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InputError(
                    f"ScanSettings.{name} must be a length >= 0 in metres, got {value}"
                )
        if not self.triangle_m > 0:
            raise InputError(f"ScanSettings.triangle_m must be > 0 m, got {self.triangle_m}")
        for name in ("round_iterations", "holes"):
            value = getattr(self, name)
            if int(value) != value or value < 0:
                raise InputError(f"ScanSettings.{name} must be an integer >= 0, got {value}")


def split_scan_spec(text: str) -> tuple[str, int | None] | None:
    """``("knife:3", seed)`` for ``"knife:3~scan[:seed]"``, None for a spec without ``~scan``.

    Parameters
    ----------
    text : str
        An object spec.

    Returns
    -------
    tuple of (str, int or None) or None
        The base spec and the degradation seed (None: not given).

    Raises
    ------
    InputError
        A malformed suffix (``~scan:x``, ``~scanner``).
    """
    base, sep, tail = text.rpartition(SCAN_SUFFIX)
    if not sep or not base:
        return None
    if tail == "":
        return base, None
    if tail.startswith(":") and tail[1:].isascii() and tail[1:].isdigit():
        return base, int(tail[1:])
    raise InputError(
        f"bad scan-like spec {text!r}: write '{base}{SCAN_SUFFIX}' or '{base}{SCAN_SUFFIX}:SEED' "
        "with a non-negative integer seed"
    )


def _laplacian_parts(faces: np.ndarray, n_vertices: int):
    import scipy.sparse as sp

    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = np.unique(np.sort(edges, axis=1), axis=0)
    rows = np.concatenate([edges[:, 0], edges[:, 1]])
    cols = np.concatenate([edges[:, 1], edges[:, 0]])
    adjacency = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n_vertices, n_vertices))
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return adjacency, np.maximum(degree, 1.0)


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = vertices[faces]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # area weighted
    vn = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(vn, faces[:, k], fn)
    return vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)


def _refine(vertices: np.ndarray, faces: np.ndarray, length: float):
    import manifold3d

    mesh = manifold3d.Mesh(
        vert_properties=np.ascontiguousarray(vertices, dtype=np.float32),
        tri_verts=np.ascontiguousarray(faces, dtype=np.uint32),
        face_id=np.arange(len(faces), dtype=np.uint32),
    )
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError:
        raise InputError(
            f"scan_like needs a closed manifold mesh; manifold3d says {solid.status()}"
        )
    out = solid.refine_to_length(float(length)).to_mesh()
    V = np.asarray(out.vert_properties, dtype=np.float64)[:, :3]
    F = np.asarray(out.tri_verts, dtype=np.int64)
    origin = np.asarray(out.face_id, dtype=np.int64)
    return V, F, origin


def scan_like(
    mesh: trimesh.Trimesh,
    face_parts: np.ndarray | None = None,
    *,
    seed: int = 0,
    settings: ScanSettings | None = None,
) -> tuple[trimesh.Trimesh, np.ndarray | None]:
    """A scan-like copy of a closed mesh (module docstring).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed, outward-oriented, metres. Not modified.
    face_parts : (n_faces,) int ndarray, optional
        Part label of each face of ``mesh``.
    seed : int
        Seed of the noise and of the holes.
    settings : ScanSettings, optional
        Defaults: :class:`ScanSettings` ().

    Returns
    -------
    mesh : trimesh.Trimesh
        Watertight, outward-oriented, metres (repaired by
        :func:`~affordgrasp.objects.loading.prepare_mesh`).
    face_parts : (n_faces,) int8 ndarray or None
        Labels of the new faces, None when none were given.
    """
    import trimesh
    from scipy.spatial import cKDTree

    from affordgrasp.objects.loading import prepare_mesh

    s = settings or ScanSettings()
    seed = int(seed)
    if seed < 0:
        raise InputError(f"scan_like seed must be a non-negative integer, got {seed}")
    rng = np.random.default_rng(seed)
    V, F, origin = _refine(np.asarray(mesh.vertices), np.asarray(mesh.faces), s.triangle_m)
    adjacency, degree = _laplacian_parts(F, len(V))

    # 2. rounding: Laplacian steps on the band around creases, everything else fixed
    if s.round_radius_m > 0 and s.round_iterations > 0:
        work = trimesh.Trimesh(V, F, process=False)
        angles = np.asarray(work.face_adjacency_angles)
        crease_v = np.unique(work.face_adjacency_edges[angles > _CREASE_RAD])
        if crease_v.size:
            tree = cKDTree(V[crease_v])
            dist, _ = tree.query(V, distance_upper_bound=s.round_radius_m)
            band = np.isfinite(dist)
            for _ in range(int(s.round_iterations)):
                step = adjacency @ V / degree[:, None] - V
                V = V + 0.5 * np.where(band[:, None], step, 0.0)

    # 3. correlated noise along the vertex normals
    if s.noise_m > 0:
        field = rng.standard_normal(len(V))
        for _ in range(2):
            field = 0.5 * field + 0.5 * (adjacency @ field) / degree
        field *= s.noise_m / max(float(field.std()), 1e-300)
        V = V + field[:, None] * _vertex_normals(V, F)
    else:
        rng.standard_normal(len(V))  # the holes draw the same faces with or without noise

    # 4. small holes, capped by the loader
    keep = np.ones(len(F), dtype=bool)
    if s.holes:
        centers = rng.choice(len(F), size=min(int(s.holes), len(F)), replace=False)
        ring = np.isin(F, np.unique(F[centers])).any(axis=1)
        keep &= ~ring
    labels_before = None if face_parts is None else np.asarray(face_parts)[origin]
    raw = trimesh.Trimesh(V, F[keep], process=False)
    # the caps are part of the degradation: the loader's "repaired" warning is not news here
    loading_log = logging.getLogger("affordgrasp.objects.loading")
    was_disabled, loading_log.disabled = loading_log.disabled, True
    try:
        out = prepare_mesh(raw, source="scan-like mesh")
    finally:
        loading_log.disabled = was_disabled
    if labels_before is None:
        return out, None
    # each face of the result takes the label of the nearest face before the holes
    tree = cKDTree(V[F].mean(axis=1))
    _, nearest = tree.query(np.asarray(out.triangles_center))
    return out, labels_before[nearest].astype(np.int8)
