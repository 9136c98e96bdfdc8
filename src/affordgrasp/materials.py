"""Materials and the GraspIt! static friction table (conventions: Pregrasp)."""

from __future__ import annotations

from .errors import InputError

MATERIALS = ("glass", "metal", "plastic", "wood", "rubber", "stone")

# GraspIt!'s static Coulomb friction coefficients, symmetric in the pair.
_STATIC_FRICTION = {
    ("glass", "glass"): 0.2,
    ("glass", "metal"): 0.2,
    ("glass", "plastic"): 0.2,
    ("glass", "wood"): 0.3,
    ("glass", "rubber"): 1.0,
    ("glass", "stone"): 0.3,
    ("metal", "metal"): 0.2,
    ("metal", "plastic"): 0.2,
    ("metal", "wood"): 0.3,
    ("metal", "rubber"): 1.0,
    ("metal", "stone"): 0.4,
    ("plastic", "plastic"): 0.3,
    ("plastic", "wood"): 0.4,
    ("plastic", "rubber"): 1.0,
    ("plastic", "stone"): 0.4,
    ("wood", "wood"): 0.4,
    ("wood", "rubber"): 1.0,
    ("wood", "stone"): 0.6,
    ("rubber", "rubber"): 2.0,
    ("rubber", "stone"): 1.5,
    ("stone", "stone"): 0.7,
}

DEFAULT_OBJECT_MATERIAL = "plastic"


def friction_coefficient(a: str, b: str) -> float:
    """Static friction coefficient μ between materials ``a`` and ``b`` (order free).

    Parameters
    ----------
    a, b : str
        Material names (:data:`MATERIALS`); an unknown one raises InputError.

    Returns
    -------
    float
        μ, dimensionless.
    """
    for name in (a, b):
        if name not in MATERIALS:
            raise InputError(f"unknown material {name!r}; known materials: {', '.join(MATERIALS)}")
    key = (a, b) if (a, b) in _STATIC_FRICTION else (b, a)
    return _STATIC_FRICTION[key]


def friction_table() -> dict[str, float]:
    """The whole table as ``{"a-b": mu}``, for dataset cards.

    Returns
    -------
    dict of str to float
    """
    return {f"{a}-{b}": mu for (a, b), mu in _STATIC_FRICTION.items()}
