"""Contact sets: the struct of arrays that crosses from the simulator to the metrics.

The grasp stage produces them (:func:`affordgrasp.grasp.policy.simulate`); the metrics take
them from any source (``affordgrasp.ContactSet``, also importable from
:mod:`affordgrasp.metrics.contacts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..tolerances import UNIT_NORMAL, ZERO_LENGTH

__all__ = ["ContactSet", "check_contact_arrays"]


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


@dataclass(frozen=True)
class ContactSet:
    """Contacts of one grasp, in the object's mesh frame.

    Attributes
    ----------
    points : (k, 3) float64
        Contact points on the object surface, m.
    normals : (k, 3) float64
        The object's *outward* unit normal at each point.
    mu : (k,) float64
        Coulomb friction coefficient of each contact.
    link : (k,) object array of str
        Name of the hand link that makes each contact.
    """

    points: np.ndarray
    normals: np.ndarray
    mu: np.ndarray
    link: np.ndarray

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @classmethod
    def empty(cls) -> ContactSet:
        """A set with no contacts.

        Returns
        -------
        ContactSet
            k = 0.
        """
        return cls(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=object))

    @classmethod
    def from_arrays(cls, points, normals, mu, link=None) -> ContactSet:
        """Validate raw arrays (e.g. from another simulator or a robot) into a ContactSet.

        Parameters
        ----------
        points, normals : (k, 3) array_like
            Contact points (m) and the object's outward normals there (any non-zero length;
            they are normalised).
        mu : float or (k,) array_like
            Friction coefficients (a scalar: the same for every contact).
        link : (k,) sequence of str, optional
            Link names; default ``"c0", "c1", ...``.

        Returns
        -------
        ContactSet
            Unit normals, float64 arrays.

        Raises
        ------
        InputError
            On a wrong shape, a non-finite value, a negative ``mu`` or a zero normal.
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim == 1 and points.size == 0:
            points = points.reshape(0, 3)
        normals = np.asarray(normals, dtype=np.float64)
        if normals.ndim == 1 and normals.size == 0:
            normals = normals.reshape(0, 3)
        if points.ndim != 2 or points.shape[1] != 3:
            raise InputError(f"contact points must have shape (k, 3), got {points.shape}")
        if normals.shape != points.shape:
            raise InputError(
                f"contact normals must have the same shape as the points {points.shape}, "
                f"got {normals.shape}"
            )
        k = points.shape[0]
        mu = np.broadcast_to(np.asarray(mu, dtype=np.float64), (k,)).copy()
        points, normals, mu = check_contact_arrays(points, normals, mu, normalise=True)
        if link is None:
            link = np.array([f"c{i}" for i in range(k)], dtype=object)
        else:
            link = np.asarray(link, dtype=object).reshape(-1)
            if link.shape[0] != k:
                raise InputError(f"need one link name per contact ({k}), got {link.shape[0]}")
        return cls(points, normals, mu, link)
