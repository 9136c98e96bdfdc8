"""A robust reader for OFF meshes (the Princeton Shape Benchmark format, conventions: Objects).

OFF files in the wild have n-gon faces, comments anywhere (also right after the counts
line), lower-case headers, header and counts on one line, extra per-vertex columns
(colours, normals, texture coordinates) and per-face colours. trimesh's own OFF loader
crashes on n-gons and silently shifts every vertex when a comment follows the counts line,
so OFF is parsed here, line by line:

* the header is ``[ST][C][N][4][n]OFF`` in any case, optionally followed on the same line
  by the counts (``OFF 8 6 0``, and even ``OFF8 6 0`` as written by some exporters); it may
  also be missing, in which case the first line holds the counts;
* one vertex per line; only the first three numbers are used;
* one face per line, ``k i1 ... ik [colour ...]``; values after the k indices are ignored;
* n-gons are triangulated: a fan when the polygon is proven convex in its best-fit plane,
  otherwise ear clipping (``manifold3d.triangulate``) in that plane.

Every error is a :class:`~affordgrasp.errors.MeshError` naming the file and the line.
"""

from __future__ import annotations

import gc
import logging
import os
import re
from pathlib import Path

import numpy as np

from affordgrasp.errors import MeshError
from affordgrasp.tolerances import FULL_TURN_RAD, STRAIGHT_TURN

__all__ = ["read_off", "triangulate_polygon"]

log = logging.getLogger(__name__)

# [ST][C][N][4][n]OFF; matched on the first token only, so "OFF490" (counts glued to the
# header by a known broken exporter) still parses.
_HEADER = re.compile(r"^(?P<prefix>(?:ST)?C?N?4?N?)OFF(?P<rest>.*)$", re.IGNORECASE)


def read_off(source: str | os.PathLike | bytes) -> tuple[np.ndarray, np.ndarray]:
    """Read an OFF mesh and triangulate its faces.

    Parameters
    ----------
    source : path or text
        A path (``os.PathLike``, or a ``str`` without a newline) to an OFF file, or the
        content of one (``bytes``, or a ``str`` that contains a newline).

    Returns
    -------
    vertices : (n, 3) float64
        Every vertex of the file, in file order (unreferenced ones included).
    faces : (m, 3) int64
        Triangles indexing ``vertices``; the triangles of one polygon keep its winding and
        appear in file order.

    Raises
    ------
    MeshError
        On anything that is not a readable 3-D OFF surface mesh; the message names the
        file, the line and the fix.
    """
    text, name = _read_source(source)
    # Tokenising allocates millions of small lists that the cyclic garbage collector
    # would scan again and again (3x slower on a 300k-face file); none of them can form
    # a cycle, so collection is paused while parsing.
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _parse(text, name)
    finally:
        if collecting:
            gc.enable()


def _parse(text: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    lines = _data_lines(text)
    if not lines:
        raise MeshError(f"{name} is empty: an OFF file needs a header, counts, vertices and faces")

    pos, counts_tokens, counts_line = _parse_header(lines, name)
    if counts_tokens is None:
        if pos >= len(lines):
            raise MeshError(f"{name} ends after the header: the counts line 'nv nf ne' is missing")
        counts_line, counts_tokens = lines[pos]
        pos += 1
    n_vertices, n_faces = _parse_counts(counts_tokens, counts_line, name)

    if n_faces == 0:
        raise MeshError(
            f"{name} has no faces (line {counts_line} says 0); affordgrasp needs a surface "
            "mesh, not a point cloud"
        )
    if n_vertices < 3:
        raise MeshError(
            f"{name} has {n_vertices} vertices (line {counts_line}); a surface needs at least 3"
        )

    vertex_lines = lines[pos : pos + n_vertices]
    if len(vertex_lines) < n_vertices:
        raise MeshError(
            f"{name} ends after {len(vertex_lines)} of {n_vertices} vertices (counts on line "
            f"{counts_line}); the file is truncated or its counts are wrong"
        )
    pos += n_vertices
    vertices = _parse_vertices(vertex_lines, name)

    face_lines = lines[pos : pos + n_faces]
    if len(face_lines) < n_faces:
        raise MeshError(
            f"{name} ends after {len(face_lines)} of {n_faces} faces (counts on line "
            f"{counts_line}); the file is truncated or its counts are wrong"
        )
    if len(lines) > pos + n_faces:
        log.debug("%s: ignoring %d lines after the last face", name, len(lines) - pos - n_faces)
    faces = _parse_faces(face_lines, n_vertices, name)
    return vertices, _triangulate_faces(vertices, faces)


def triangulate_polygon(points: np.ndarray) -> np.ndarray:
    """Triangulate one simple polygon in 3-D, keeping its winding.

    The polygon is projected on its best-fit plane (Newell normal). A polygon proven
    convex there is fanned from its first vertex; any other is ear-clipped.

    Parameters
    ----------
    points : (k, 3) float
        The polygon's corners in order, k >= 3.

    Returns
    -------
    triangles : (k - 2, 3) int64
        Indices into ``points``; each triangle turns the same way as the polygon. Fewer
        rows when the ear clipper drops zero-area ears of a degenerate polygon.
    """
    points = np.asarray(points, dtype=np.float64)
    k = len(points)
    if points.ndim != 2 or points.shape[1] != 3 or k < 3:
        raise ValueError(f"points must be (k >= 3, 3), got shape {points.shape}")
    fan = _fan(k)
    if k == 3:
        return fan
    normal = _newell_normals(points[None])[0]
    if _convex_mask(points[None], normal[None])[0]:
        return fan
    return _ear_clip(points, normal)


def _read_source(source: str | os.PathLike | bytes) -> tuple[str, str]:
    """Return (text, name used in messages) for a path or an OFF text."""
    if isinstance(source, bytes):
        return source.decode("utf-8", errors="replace"), "<OFF text>"
    if isinstance(source, str) and ("\n" in source or "\r" in source):
        return source, "<OFF text>"
    path = Path(source)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise MeshError(f"OFF file {str(path)!r} does not exist; check the path") from None
    except OSError as exc:
        raise MeshError(f"cannot read OFF file {str(path)!r}: {exc}") from exc
    # Comments in old files are often Latin-1; they are discarded, so never fail on them.
    return raw.decode("utf-8", errors="replace"), path.name


def _data_lines(text: str) -> list[tuple[int, list[str]]]:
    """Split into (1-based line number, tokens) for lines that hold data after comments."""
    lines = text.splitlines()
    if "#" in text:
        return [
            (number, tokens)
            for number, line in enumerate(lines, start=1)
            if (tokens := line.partition("#")[0].split())
        ]
    return [
        (number, tokens) for number, line in enumerate(lines, start=1) if (tokens := line.split())
    ]


def _parse_header(
    lines: list[tuple[int, list[str]]], name: str
) -> tuple[int, list[str] | None, int]:
    """Return (index of the next line, counts tokens if on the header line, their line)."""
    line_no, tokens = lines[0]
    first = tokens[0]
    if _is_int(first):
        # Headerless OFF (allowed by the Geomview spec): the first line is the counts.
        return 1, tokens, line_no
    match = _HEADER.match(first)
    if match is None:
        raise MeshError(
            f"{name} line {line_no}: expected an OFF header ('OFF', 'COFF', 'NOFF', ...), "
            f"found {first!r}; is this really an OFF file?"
        )
    prefix = match.group("prefix")
    rest = [match.group("rest")] if match.group("rest") else []
    rest += tokens[1:]
    if any(tok.upper() == "BINARY" for tok in rest):
        raise MeshError(
            f"{name} line {line_no}: binary OFF is not supported; convert it to ASCII OFF, "
            "OBJ or PLY"
        )
    if "4" in prefix:
        raise MeshError(
            f"{name} line {line_no}: this is a 4-D OFF (header {first!r}: vertices have 4 "
            "coordinates); affordgrasp needs a 3-D surface mesh"
        )
    pos = 1
    if prefix[-1:].upper() == "N" and not rest and pos < len(lines) and len(lines[pos][1]) == 1:
        # nOFF: the line after the header is the space dimension (a counts line has >= 2
        # numbers, so a single number can only be a dimension).
        dim_line, (dim_token,) = lines[pos]
        if not _is_int(dim_token):
            raise MeshError(
                f"{name} line {dim_line}: expected the dimension of an nOFF file, "
                f"found {dim_token!r}"
            )
        if int(dim_token) != 3:
            raise MeshError(
                f"{name} line {dim_line}: this is a {int(dim_token)}-D OFF (header {first!r}); "
                "affordgrasp needs a 3-D surface mesh"
            )
        pos += 1
    return pos, (rest or None), line_no


def _parse_counts(tokens: list[str], line_no: int, name: str) -> tuple[int, int]:
    if len(tokens) < 2 or not all(_is_int(t) for t in tokens[:3]):
        raise MeshError(
            f"{name} line {line_no}: expected the counts 'vertices faces [edges]' as "
            f"integers, found {' '.join(tokens)!r}"
        )
    n_vertices, n_faces = int(tokens[0]), int(tokens[1])
    if n_vertices < 0 or n_faces < 0:
        raise MeshError(f"{name} line {line_no}: negative counts {n_vertices} {n_faces}")
    return n_vertices, n_faces


def _parse_vertices(vertex_lines: list[tuple[int, list[str]]], name: str) -> np.ndarray:
    try:
        vertices = np.array([tokens[:3] for _, tokens in vertex_lines], dtype=np.float64)
        if vertices.ndim == 2 and vertices.shape[1] == 3:
            return vertices
    except ValueError:
        pass
    # Slow path, only to name the offending line.
    for line_no, tokens in vertex_lines:
        if len(tokens) < 3:
            raise MeshError(
                f"{name} line {line_no}: a vertex needs 3 coordinates 'x y z', found "
                f"{len(tokens)} value(s) {' '.join(tokens)!r}; the file is truncated or its "
                "vertex count is wrong"
            ) from None
        try:
            [float(t) for t in tokens[:3]]
        except ValueError:
            raise MeshError(
                f"{name} line {line_no}: vertex coordinates must be numbers, found "
                f"{' '.join(tokens[:3])!r}"
            ) from None
    raise AssertionError("unreachable")  # pragma: no cover


def _parse_faces(
    face_lines: list[tuple[int, list[str]]], n_vertices: int, name: str
) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Group the faces by size: {k: (positions in the file (p,), indices (p, k) int64)}."""
    by_count: dict[str, list[int]] = {}
    for position, (_, tokens) in enumerate(face_lines):
        by_count.setdefault(tokens[0], []).append(position)
    groups = {}
    try:
        for count, positions in by_count.items():
            k = int(count)
            if k < 3:
                raise ValueError(count)
            # Tokens after the k indices (a face colour) are dropped before conversion.
            rows = [face_lines[i][1][1 : k + 1] for i in positions]
            polygons = np.array(rows).astype(np.int64)
            if polygons.shape != (len(positions), k):
                raise ValueError(count)
            if polygons.min() < 0 or polygons.max() >= n_vertices:
                raise ValueError(count)
            groups[k] = (np.array(positions, dtype=np.int64), polygons)
    except ValueError:
        # Something is wrong: find the first bad line to name it.
        _validate_face_lines(face_lines, n_vertices, name)
        raise AssertionError("unreachable") from None  # pragma: no cover
    return groups


def _validate_face_lines(face_lines: list[tuple[int, list[str]]], n_vertices: int, name: str):
    """Raise a MeshError naming the first malformed face line."""
    for line_no, tokens in face_lines:
        if not _is_int(tokens[0]):
            raise MeshError(
                f"{name} line {line_no}: a face starts with its vertex count k, found {tokens[0]!r}"
            )
        k = int(tokens[0])
        if k < 3:
            raise MeshError(
                f"{name} line {line_no}: a face has {k} vertices; faces need at least 3 "
                "(points and edges are not surfaces)"
            )
        if len(tokens) < k + 1:
            raise MeshError(
                f"{name} line {line_no}: a face says it has {k} vertices but lists "
                f"{len(tokens) - 1} value(s)"
            )
        if not all(_is_int(t) for t in tokens[1 : k + 1]):
            raise MeshError(
                f"{name} line {line_no}: face vertex indices must be integers, found "
                f"{' '.join(tokens[1 : k + 1])!r}"
            )
        bad = [i for i in map(int, tokens[1 : k + 1]) if i < 0 or i >= n_vertices]
        if bad:
            raise MeshError(
                f"{name} line {line_no}: vertex index {bad[0]} is out of range; the file has "
                f"{n_vertices} vertices (valid indices 0..{n_vertices - 1})"
            )


def _triangulate_faces(
    vertices: np.ndarray, groups: dict[int, tuple[np.ndarray, np.ndarray]]
) -> np.ndarray:
    """Triangulate all polygons; vectorised per polygon size, file order kept."""
    triangles: list[np.ndarray] = []
    owners: list[np.ndarray] = []  # source face of each triangle, to restore file order
    for k, (which, polygons) in sorted(groups.items()):
        if k == 3:
            triangles.append(polygons)
            owners.append(which)
            continue
        points = vertices[polygons]  # (p, k, 3)
        normals = _newell_normals(points)
        convex = _convex_mask(points, normals)
        fan = _fan(k)
        if convex.any():
            triangles.append(polygons[convex][:, fan].reshape(-1, 3))
            owners.append(np.repeat(which[convex], len(fan)))
        # Non-convex polygons are rare in practice; clip them one at a time.
        for j in np.flatnonzero(~convex):
            local = _ear_clip(points[j], normals[j])
            triangles.append(polygons[j][local])
            owners.append(np.full(len(local), which[j], dtype=np.int64))
    tri = np.concatenate(triangles).astype(np.int64, copy=False)
    order = np.argsort(np.concatenate(owners), kind="stable")
    return np.ascontiguousarray(tri[order])


def _fan(k: int) -> np.ndarray:
    j = np.arange(1, k - 1, dtype=np.int64)
    return np.column_stack([np.zeros_like(j), j, j + 1])


def _newell_normals(points: np.ndarray) -> np.ndarray:
    """Unit best-fit normals of polygons, (p, k, 3) -> (p, 3); zero for degenerate ones."""
    nxt = np.roll(points, -1, axis=1)
    normals = np.cross(points, nxt).sum(axis=1)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)


def _convex_mask(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """True where a polygon is convex and simple seen along its normal, (p, k, 3) -> (p,).

    Convex and simple means every corner turns the same way (left about the normal) and
    the turns add up to one full turn; a pentagram turns left everywhere but twice round.
    Degenerate polygons (zero normal) count as convex: any triangulation of them has zero
    area and is dropped later.
    """
    edges = np.roll(points, -1, axis=1) - points
    prev = np.roll(edges, 1, axis=1)
    turn = np.einsum("pkj,pj->pk", np.cross(prev, edges), normals)
    along = np.einsum("pkj,pkj->pk", prev, edges)
    scale = np.linalg.norm(prev, axis=2) * np.linalg.norm(edges, axis=2)
    left = turn >= -STRAIGHT_TURN * scale
    total = np.arctan2(turn, along).sum(axis=1)
    one_turn = np.abs(total - 2.0 * np.pi) < FULL_TURN_RAD
    degenerate = ~normals.any(axis=1)
    return degenerate | (left.all(axis=1) & one_turn)


def _ear_clip(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Ear-clip one polygon in its plane; (k, 3) -> (<= k - 2, 3) local indices."""
    import manifold3d

    if not normal.any():
        return _fan(len(points))
    # An orthonormal (u, v) with u x v = normal makes the polygon counter-clockwise in 2-D.
    helper = np.eye(3)[np.argmin(np.abs(normal))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    flat = np.column_stack([(points - points[0]) @ u, (points - points[0]) @ v])
    tri = np.asarray(manifold3d.triangulate([flat]), dtype=np.int64).reshape(-1, 3)
    if len(tri) == 0:
        log.debug("ear clipping produced no triangles; using a fan")
        return _fan(len(points))
    a, b, c = flat[tri[:, 0]], flat[tri[:, 1]], flat[tri[:, 2]]
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    # Keep the polygon's winding: every triangle counter-clockwise in the plane.
    flip = area2 < 0
    tri[flip] = tri[flip][:, ::-1]
    return tri


def _is_int(token: str) -> bool:
    try:
        int(token)
    except ValueError:
        return False
    return True
