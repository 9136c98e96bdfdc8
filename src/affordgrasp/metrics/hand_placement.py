"""Where the hand holds relative to the working part: off it, on a handle, for real tools.

The tasks keep the hand off the part that does the work (a blade, a hammer's head): every
contact far from the use point U (:func:`use_clearance`), none reaching past the centre of
mass towards U (:func:`contact_reach`, along :func:`long_axis`), on a part thick and wide
enough to be a handle (:func:`contact_thickness`, :func:`contact_width`: chords through
the solid under the contacts). Validated in ``tests/metrics/test_hand_placement.py``.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..grasp.pregrasp import dot3
from ..rays.mesh import mesh_caster
from .cones import plane_axes


def _use_point_groups(group, n_uses: int, n_grasps: int) -> np.ndarray:
    """(n,) int64: the grasp of each use point (default: use point i is grasp i), checked."""
    group = np.arange(n_uses) if group is None else np.asarray(group, dtype=np.int64).reshape(-1)
    if group.shape[0] != n_uses:
        raise InputError(f"group has {group.shape[0]} rows, expected one per use point ({n_uses})")
    if n_uses and (group.min() < 0 or group.max() >= n_grasps):
        raise InputError(
            f"group indices must lie in [0, {n_grasps}), got {group.min()}..{group.max()}"
        )
    return group


def use_clearance(contact_points, offsets, use_point, group=None) -> np.ndarray:
    """Smallest distance from a grasp's contacts to its use point (``use_clearance``), m.

    A hand that touches the working part near U (fingers on a blade) has a small clearance;
    tasks whose use point is a working part ask for at least a hand's width.

    Parameters
    ----------
    contact_points : (k, 3) float
        Contacts of all grasps, stacked, m.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.
    use_point : (n, 3) float
        Use points, m.
    group : (n,) int, optional
        The grasp of each use point (default: use point i belongs to grasp i, n = g).

    Returns
    -------
    (n,) float64 ndarray
        m; +inf for a grasp without contacts, NaN for a NaN use point.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    g = len(offsets) - 1
    group = _use_point_groups(group, len(U), g)
    counts = np.diff(offsets)
    kmax = int(counts.max()) if g else 0
    out = np.full(len(U), np.inf)
    if kmax == 0 or len(U) == 0:
        return np.where(np.isnan(U).any(axis=1), np.nan, out)
    padded = np.full((g, kmax, 3), np.nan)
    owner = np.repeat(np.arange(g), counts)
    padded[owner, np.arange(len(C)) - offsets[owner]] = C
    for first in range(0, len(U), 65536):
        sl = slice(first, first + 65536)
        d = np.linalg.norm(padded[group[sl]] - U[sl, None, :], axis=2)
        has = ~np.isnan(d)
        out[sl] = np.where(has.any(axis=1), np.min(np.where(has, d, np.inf), axis=1), np.inf)
    return np.where(np.isnan(U).any(axis=1), np.nan, out)


def long_axis(inertia) -> np.ndarray:
    """The object's long axis: the principal axis of least moment of inertia.

    Parameters
    ----------
    inertia : (3, 3) float
        Inertia tensor about the centre of mass, kg·m² (any density scale).

    Returns
    -------
    (3,) float64 ndarray
        Unit vector (its sign is arbitrary; :func:`contact_reach` does not depend on it).
    """
    inertia = np.asarray(inertia, dtype=np.float64).reshape(3, 3)
    _, vectors = np.linalg.eigh(0.5 * (inertia + inertia.T))
    return vectors[:, 0]


def contact_reach(
    contact_points, offsets, use_point, center_of_mass, axis, group=None
) -> np.ndarray:
    """How far the hand reaches past the centre of mass towards U (``contact_reach``).

    Along the object's long axis e (:func:`long_axis`), with u = (U - c) · e the use point's
    offset from the centre of mass c, the largest (p - c) · e · sign(u) over a grasp's
    contacts p, divided by |u|: 0 when no contact lies past the centre of mass on U's side,
    1 when one reaches as far as U does, negative when every contact lies behind the centre
    of mass. A knife held by its handle and cutting with its blade, or a hammer with a steel
    head held by its handle and striking with its head, reads small or negative; a finger on
    an axe's head or a knife's blade reads near 1. It needs no part labels, so it holds on a
    scanned mesh.

    Parameters
    ----------
    contact_points, offsets, use_point, group
        As for :func:`use_clearance`.
    center_of_mass : (3,) float
        m.
    axis : (3,) float
        The long axis (any sign).

    Returns
    -------
    (n,) float64 ndarray
        Dimensionless; -inf for a grasp without contacts, ±inf when U lies level with the
        centre of mass (u = 0) and a contact lies past it (+) or none does (-), NaN for a
        NaN use point.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    U = np.asarray(use_point, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(center_of_mass, dtype=np.float64).reshape(3)
    e = np.asarray(axis, dtype=np.float64).reshape(3)
    norm = float(np.linalg.norm(e))
    if not (np.isfinite(norm) and norm > 0):
        raise InputError(f"axis must be a non-zero finite vector, got {e.tolist()}")
    e = e / norm
    g = len(offsets) - 1
    if g < 0 or offsets[-1] != len(C):
        raise InputError(
            f"offsets must end at the number of contacts ({len(C)}), got {offsets.tolist()}"
        )
    group = _use_point_groups(group, len(U), g)
    counts = np.diff(offsets)
    hi = np.full(g, -np.inf)
    lo = np.full(g, np.inf)
    if len(C):
        owner = np.repeat(np.arange(g), counts)
        along = dot3(C - c, e)
        np.maximum.at(hi, owner, along)
        np.minimum.at(lo, owner, along)
    u = dot3(U - c, e)
    reach = np.where(u >= 0, hi[group], -lo[group])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(u != 0, reach / np.abs(u), np.where(reach > 0, np.inf, -np.inf))
    return np.where(np.isnan(U).any(axis=1), np.nan, out)


_THICKNESS_START_M = 1e-4  # the rays start this far inside, along -n


def contact_thickness(mesh, contact_points, contact_normals, offsets) -> np.ndarray:
    """Thinnest part a grasp touches (``contact_thickness``), m.

    At each contact, the length of the chord through the solid along the inward normal (the
    first exit of a ray from just inside, along -n); per grasp the smallest. A blade, 1-5 mm
    thick, is thin everywhere; a handle or a hammer's head is not: tasks whose working part
    is a blade keep the hand off it with a minimum thickness.

    Parameters
    ----------
    mesh : trimesh.Trimesh or MeshData
        The object, m (its rays: :func:`affordgrasp.rays.mesh.mesh_caster`).
    contact_points, contact_normals : (k, 3) float
        Contacts of all grasps, stacked, m; the object's outward unit normals.
    offsets : (g + 1,) int
        Grasp j owns rows ``offsets[j]:offsets[j + 1]``.

    Returns
    -------
    (g,) float64 ndarray
        m; +inf for a grasp without contacts; a contact whose ray finds no exit (grazing an
        edge) counts as 0.
    """
    return contact_thickness_and_width(
        mesh, contact_points, contact_normals, offsets, directions=0
    )[0]


WIDTH_DIRECTIONS = 6  # directions across the part, per contact, of contact_width


def _first_exit(mesh, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(k,) distance from each origin to the first surface along its direction, m; inf if none."""
    out = np.full(len(origins), np.inf)
    if len(origins) == 0:
        return out
    locations, ray, _ = mesh_caster(mesh).intersects_location(origins, dirs, multiple_hits=False)
    ray = np.asarray(ray, dtype=np.int64)
    if len(ray):
        out[ray] = np.linalg.norm(np.asarray(locations, dtype=np.float64) - origins[ray], axis=1)
    return out


def contact_width(
    mesh, contact_points, contact_normals, offsets, directions: int = WIDTH_DIRECTIONS
) -> np.ndarray:
    """Narrowest part a grasp touches, measured across the part (``contact_width``), m.

    At each contact, the chord through the solid along the inward normal (as
    :func:`contact_thickness`), then from that chord's midpoint, the chords across the part
    along ``directions`` directions perpendicular to the normal (half-turn evenly spaced);
    the contact's width is the smallest of them, and a grasp's the smallest over its
    contacts. A finger on a handle reads the handle's section (12 mm and more); a finger on
    a blade's spine reads the blade's thickness (2-5 mm), though its chord along the normal
    runs down the blade's height: the thickness test alone lets a hand hold a cleaver by its
    spine.

    Parameters
    ----------
    mesh, contact_points, contact_normals, offsets
        As for :func:`contact_thickness` (the mesh closed).
    directions : int
        Directions across the part per contact (default :data:`WIDTH_DIRECTIONS`).

    Returns
    -------
    (g,) float64 ndarray
        m; +inf for a grasp without contacts; a contact whose normal ray finds no exit
        (grazing an edge) counts as 0.
    """
    if int(directions) < 1:
        raise InputError(f"directions must be a positive integer, got {directions}")
    return contact_thickness_and_width(
        mesh, contact_points, contact_normals, offsets, directions=directions
    )[1]


def contact_thickness_and_width(
    mesh, contact_points, contact_normals, offsets, directions: int = WIDTH_DIRECTIONS
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`contact_thickness` and :func:`contact_width` from one set of rays.

    The chord along the inward normal is both the thickness and the width's first chord;
    the chords across the part, both halves of every direction for every contact, are cast
    in one call.

    Parameters
    ----------
    mesh, contact_points, contact_normals, offsets
        As for :func:`contact_thickness`.
    directions : int
        Directions across the part per contact (0: the thickness alone; the width is then
        the chord along the normal).

    Returns
    -------
    thickness, width : (g,) float64 ndarray
        m.
    """
    C = np.asarray(contact_points, dtype=np.float64).reshape(-1, 3)
    N = np.asarray(contact_normals, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64).reshape(-1)
    k = int(directions)
    if k < 0:
        raise InputError(f"directions must be a non-negative integer, got {directions}")
    g = len(offsets) - 1
    thickness = np.full(g, np.inf)
    out = np.full(g, np.inf)
    if len(C) == 0:
        return thickness, out
    origins = C - _THICKNESS_START_M * N
    along = _first_exit(mesh, origins, -N)
    chord_n = np.where(np.isfinite(along), along + _THICKNESS_START_M, 0.0)
    width = chord_n.copy()
    inside = np.isfinite(along)
    m = int(inside.sum())
    if m and k:
        centre = origins[inside] - 0.5 * along[inside, None] * N[inside]
        e1, e2 = plane_axes(N[inside])
        # rows: direction a's + half, then its - half, each over the m contacts
        d = np.stack(
            [np.cos(angle) * e1 + np.sin(angle) * e2 for angle in np.arange(k) * np.pi / k]
        )
        dirs = np.stack([d, -d], axis=1).reshape(-1, 3)
        exits = _first_exit(mesh, np.tile(centre, (2 * k, 1)), dirs).reshape(k, 2, m)
        for a in range(k):
            width[inside] = np.minimum(width[inside], exits[a, 0] + exits[a, 1])
    counts = np.diff(offsets)
    owner = np.repeat(np.arange(g), counts)
    np.minimum.at(thickness, owner, chord_n)
    np.minimum.at(out, owner, width)
    return thickness, out
