"""Contact sets: the struct of arrays that crosses from the simulator to the metrics."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError


@dataclass(frozen=True)
class ContactSet:
    """Contacts of one grasp, in the object's mesh frame.

    points : (k, 3) float64, contact points on the object surface, m
    normals : (k, 3) float64, the object's *outward* unit normal at each point
    mu : (k,) float64, Coulomb friction coefficient of each contact
    link : (k,) str (object array), name of the hand link that makes the contact
    """

    points: np.ndarray
    normals: np.ndarray
    mu: np.ndarray
    link: np.ndarray

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @classmethod
    def empty(cls) -> ContactSet:
        return cls(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=object))

    @classmethod
    def from_arrays(cls, points, normals, mu, link=None) -> ContactSet:
        """Validate raw arrays (e.g. from another simulator or a robot) into a ContactSet.

        ``mu`` may be a scalar (same coefficient for every contact); ``link`` defaults to
        ``"c0", "c1", ...``. Normals are normalised; zero or non-finite ones are refused.
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
        if not (np.all(np.isfinite(points)) and np.all(np.isfinite(normals))):
            raise InputError("contact points and normals must be finite (found NaN or inf)")
        if np.any(~np.isfinite(mu)) or np.any(mu < 0):
            raise InputError(f"friction coefficients must be finite and >= 0, got {mu}")
        lengths = np.linalg.norm(normals, axis=1)
        if np.any(lengths < 1e-12):
            raise InputError("every contact normal must be non-zero")
        normals = normals / lengths[:, None]
        if link is None:
            link = np.array([f"c{i}" for i in range(k)], dtype=object)
        else:
            link = np.asarray(link, dtype=object).reshape(-1)
            if link.shape[0] != k:
                raise InputError(f"need one link name per contact ({k}), got {link.shape[0]}")
        return cls(points, normals, mu, link)
