"""Hands as data (SPEC §2.2): the Barrett BH8-282 and a parallel-jaw gripper."""

from __future__ import annotations

from functools import cache

from ..errors import HandError
from .barrett import barrett_bh8_282
from .gripper import parallel_jaw
from .model import Dof, Finger, Hand, Joint, Link, Shape

_HANDS = {"barrett": barrett_bh8_282, "parallel_jaw": parallel_jaw}


def hand_names() -> list[str]:
    return list(_HANDS)


def get_hand(name: str | Hand = "barrett") -> Hand:
    """A built-in hand by name ("barrett" or "parallel_jaw"); a Hand is returned as it is."""
    if isinstance(name, Hand):
        return name
    return _builtin_hand(name)


@cache
def _builtin_hand(name: str) -> Hand:
    try:
        return _HANDS[name]()
    except (KeyError, TypeError):
        raise HandError(f"unknown hand {name!r}; built-in hands: {', '.join(_HANDS)}") from None


__all__ = ["Dof", "Finger", "Hand", "Joint", "Link", "Shape", "get_hand", "hand_names"]
