"""Mass properties of a closed mesh at a uniform density (SPEC §2.1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of an object in its mesh frame, SI units.

    density : float, kg/m^3 (1.0 by default, as in the paper)
    volume : float, m^3
    mass : float, kg
    center_of_mass : (3,) float, m
    inertia : (3, 3) float, kg m^2, about the centre of mass, mesh-frame axes
    r_max : float, m, largest distance from the centre of mass to a mesh vertex
    bounds : (2, 3) float, m, axis-aligned bounding box (min row, max row)
    """

    density: float
    volume: float
    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    r_max: float
    bounds: np.ndarray
