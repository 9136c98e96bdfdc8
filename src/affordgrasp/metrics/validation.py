"""Validation of the raw inputs of the metric functions (one place, one set of messages)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..tolerances import UNIT_NORMAL, ZERO_LENGTH


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
        raise InputError(
            "contacts must be a ContactSet (build one from raw arrays with "
            "ContactSet.from_arrays(points, normals, mu))"
        ) from exc
    return check_contact_arrays(points, normals, mu)


def check_contact_arrays(
    points: np.ndarray, normals: np.ndarray, mu: np.ndarray, *, normalise: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The one check of contact arrays (shapes, finiteness, ``mu >= 0``, non-zero normals).

    Normals are rescaled to unit length when ``normalise`` is set or when one of them is
    off by more than 1e-12 (the cones assume unit normals; a ContactSet built directly,
    without :meth:`ContactSet.from_arrays`, may not have them).

    Parameters
    ----------
    points : (k, 3) float64 ndarray
        m.
    normals : (k, 3) float64 ndarray
        Outward normals.
    mu : (k,) float64 ndarray
        Friction coefficients, >= 0.
    normalise : bool
        Always rescale the normals.

    Returns
    -------
    points, normals, mu
        The same shapes, float64; normals unit.
    """
    if not (points.shape == normals.shape and mu.shape[0] == points.shape[0]):
        raise InputError(
            f"inconsistent contact arrays: points {points.shape}, normals {normals.shape}, "
            f"mu {mu.shape}"
        )
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(normals))):
        raise InputError("contact points and normals must be finite (found NaN or inf)")
    if np.any(~np.isfinite(mu)) or np.any(mu < 0):
        raise InputError(f"friction coefficients must be finite and >= 0, got {mu}")
    length = np.linalg.norm(normals, axis=1)
    if np.any(length < ZERO_LENGTH):
        raise InputError("every contact normal must be non-zero")
    if normalise or np.any(np.abs(length - 1.0) > UNIT_NORMAL):
        normals = np.ascontiguousarray(normals / length[:, None])
    return points, normals, mu


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
