"""Validation of the raw inputs of the metric functions (one place, one set of messages)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..grasp.contacts import check_contact_arrays  # its home: the stage that makes contacts
from ..tolerances import UNIT_NORMAL, ZERO_LENGTH

_NOT_A_CONTACT_SET = (
    "contacts must be a ContactSet (build one from raw arrays with "
    "ContactSet.from_arrays(points, normals, mu))"
)


def contact_arrays(contacts) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contiguous float64 arrays of a ContactSet.

    Parameters
    ----------
    contacts : ContactSet
        k contacts.

    Returns
    -------
    points : (k, 3) float64 ndarray
        m.
    normals : (k, 3) float64 ndarray
        Outward unit normals.
    mu : (k,) float64 ndarray
    """
    try:
        points = np.ascontiguousarray(contacts.points, dtype=np.float64).reshape(-1, 3)
        normals = np.ascontiguousarray(contacts.normals, dtype=np.float64).reshape(-1, 3)
        mu = np.ascontiguousarray(contacts.mu, dtype=np.float64).reshape(-1)
    except AttributeError as exc:
        raise InputError(_NOT_A_CONTACT_SET) from exc
    return check_contact_arrays(points, normals, mu)


def stacked_contact_arrays(contacts) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The contacts of many grasps, checked and concatenated (row offsets per grasp).

    The same checks, messages and normalisation as :func:`contact_arrays` on each grasp
    (a grasp's normals are rescaled when one of *its* normals is off), done once on the
    stacked arrays instead of grasp by grasp.

    Parameters
    ----------
    contacts : sequence of ContactSet
        n grasps.

    Returns
    -------
    points : (k, 3) float64 ndarray
        m.
    normals : (k, 3) float64 ndarray
        Outward unit normals.
    mu : (k,) float64 ndarray
    offsets : (n + 1,) int64 ndarray
        Grasp g's contacts are rows offsets[g]:offsets[g + 1].
    """
    try:
        raw = [(c.points, c.normals, c.mu) for c in contacts]
    except AttributeError as exc:
        raise InputError(_NOT_A_CONTACT_SET) from exc
    parts = [
        (
            np.asarray(p, dtype=np.float64).reshape(-1, 3),
            np.asarray(nrm, dtype=np.float64).reshape(-1, 3),
            np.asarray(m, dtype=np.float64).reshape(-1),
        )
        for p, nrm, m in raw
    ]
    for p, nrm, m in parts:
        if not (p.shape == nrm.shape and m.shape[0] == p.shape[0]):
            raise InputError(
                f"inconsistent contact arrays: points {p.shape}, normals {nrm.shape}, mu {m.shape}"
            )
    counts = np.array([p.shape[0] for p, _, _ in parts], dtype=np.int64)
    offsets = np.zeros(len(parts) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    if not counts.sum():
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), offsets
    points = np.ascontiguousarray(np.concatenate([p for p, _, _ in parts]))
    normals = np.ascontiguousarray(np.concatenate([nrm for _, nrm, _ in parts]))
    mu = np.ascontiguousarray(np.concatenate([m for _, _, m in parts]))
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(normals))):
        raise InputError("contact points and normals must be finite (found NaN or inf)")
    bad = ~np.isfinite(mu) | (mu < 0)
    if np.any(bad):
        g = int(np.searchsorted(offsets, np.argmax(bad), side="right")) - 1
        raise InputError(f"friction coefficients must be finite and >= 0, got {parts[g][2]}")
    length = np.linalg.norm(normals, axis=1)
    if np.any(length < ZERO_LENGTH):
        raise InputError("every contact normal must be non-zero")
    off = np.abs(length - 1.0) > UNIT_NORMAL
    if np.any(off):
        owner = np.repeat(np.arange(len(parts)), counts)
        rows = np.isin(owner, owner[off])
        normals[rows] = normals[rows] / length[rows, None]
    return points, normals, mu, offsets


def point3(x, name: str) -> np.ndarray:
    """A finite (3,) float64 vector, or an InputError naming ``name``.

    Parameters
    ----------
    x : array_like of float
        The value given.
    name : str
        The parameter's name, for the :class:`~affordgrasp.errors.InputError` message.

    Returns
    -------
    (3,) float64 ndarray
    """
    x = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    if x.shape != (3,) or not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be 3 finite numbers, got {x}")
    return x


def unit3(v, name: str) -> np.ndarray:
    """A (3,) unit vector from a finite non-zero direction.

    Parameters
    ----------
    v : array_like of float
        The value given.
    name : str
        The parameter's name, for the :class:`~affordgrasp.errors.InputError` message.

    Returns
    -------
    (3,) float64 ndarray
    """
    v = point3(v, name)
    n = float(np.linalg.norm(v))
    if n < ZERO_LENGTH:
        raise InputError(f"{name} must be a non-zero direction, got {v}")
    return v / n


def points_n3(x, name: str) -> np.ndarray:
    """A finite (n, 3) float64 array (a single (3,) vector becomes (1, 3)).

    Parameters
    ----------
    x : array_like of float
        The value given.
    name : str
        The parameter's name, for the :class:`~affordgrasp.errors.InputError` message.

    Returns
    -------
    (n, 3) float64 ndarray
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x.reshape(1, -1)
    if x.ndim != 2 or x.shape[1] != 3 or not np.all(np.isfinite(x)):
        raise InputError(f"{name} must have shape (n, 3) with finite values, got {x.shape}")
    return np.ascontiguousarray(x)


def units_n3(x, name: str) -> np.ndarray:
    """Rows normalised to unit length; zero rows are refused.

    Parameters
    ----------
    x : array_like of float
        The value given.
    name : str
        The parameter's name, for the :class:`~affordgrasp.errors.InputError` message.

    Returns
    -------
    (n, 3) float64 ndarray
    """
    x = points_n3(x, name)
    n = np.linalg.norm(x, axis=1)
    if np.any(n < ZERO_LENGTH):
        raise InputError(f"every row of {name} must be a non-zero direction")
    return x / n[:, None]


def use_normals_n3(use_normal, use_points: np.ndarray) -> np.ndarray:
    """Outward unit normals at the use points, one per point, checked.

    Parameters
    ----------
    use_normal : array_like of float
        The normals given (``use_normal``).
    use_points : (n, 3) float64 ndarray
        The use points they belong to, already checked (:func:`points_n3`).

    Returns
    -------
    (n, 3) float64 ndarray
        Unit rows.
    """
    N = units_n3(use_normal, "use_normal")
    if N.shape[0] != use_points.shape[0]:
        raise InputError(
            f"use_normal has {N.shape[0]} rows, expected one per use point ({use_points.shape[0]})"
        )
    return N


def positive_length(r: float, name: str) -> float:
    """A finite length > 0, in metres, or an InputError naming ``name``.

    Parameters
    ----------
    r : float
        The length, m.
    name : str
        The parameter's name, for the message.

    Returns
    -------
    float
    """
    r = float(r)
    if not (np.isfinite(r) and r > 0):
        raise InputError(f"{name} must be a positive length in metres, got {r}")
    return r
