"""Seeded parameter draws for the procedural families."""

from __future__ import annotations

from typing import Any

import numpy as np


class ParameterDraw:
    """Draws one family instance's parameters from ``numpy.random.default_rng(seed)``.

    Seed 0 is the family's typical instance: every parameter takes its typical value and
    the generator is not consumed.  Every other seed draws each parameter uniformly from its
    range, in the order the family asks for them, so the same seed gives the same object.
    The values drawn are kept in :attr:`values` (name -> value) for the mesh metadata.

    Parameters
    ----------
    seed : int
        Non-negative; 0 for the typical instance.
    """

    def __init__(self, seed: int) -> None:
        self.typical = seed == 0
        self.rng = np.random.default_rng(seed)
        self.values: dict[str, Any] = {}

    def uniform(self, name: str, low: float, high: float, typical: float) -> float:
        """A real parameter in [low, high]; ``typical`` for seed 0.

        Parameters
        ----------
        name : str
            Recorded in :attr:`values`.
        low, high : float
            The range (m, rad or a ratio, as the family states).
        typical : float
            The value of the typical instance.

        Returns
        -------
        float
        """
        value = typical if self.typical else float(self.rng.uniform(low, high))
        self.values[name] = value
        return value

    def choice(self, name: str, options: tuple[str, ...], typical: str) -> str:
        """One of ``options``; ``typical`` for seed 0.

        Parameters
        ----------
        name : str
            Recorded in :attr:`values`.
        options : tuple of str
            Drawn with equal probability.
        typical : str
            The value of the typical instance.

        Returns
        -------
        str
        """
        value = typical if self.typical else str(options[int(self.rng.integers(len(options)))])
        self.values[name] = value
        return value

    def integer(self, name: str, low: int, high: int, typical: int) -> int:
        """An integer in [low, high] inclusive; ``typical`` for seed 0.

        Parameters
        ----------
        name : str
            Recorded in :attr:`values`.
        low, high : int
            The range, both ends included.
        typical : int
            The value of the typical instance.

        Returns
        -------
        int
        """
        value = typical if self.typical else int(self.rng.integers(low, high + 1))
        self.values[name] = value
        return value
