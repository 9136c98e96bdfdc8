"""Hands as data: the Barrett BH8-282, a parallel-jaw gripper, and hands you register.

Look a hand up with :func:`get_hand` (a registered name, a ``.json``/``.toml`` hand file, or a
:class:`Hand`, returned as it is); add one with :func:`register_hand`; write and read hand
files with :func:`save_hand` / :func:`load_hand` (:mod:`.files`). Conventions of the hand
frame, joints and fingers: :mod:`.model`.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import HandError
from ..registry import Registry
from .barrett import barrett_bh8_282
from .files import hand_from_dict, hand_to_dict, hand_to_toml, load_hand, save_hand
from .gripper import parallel_jaw
from .model import Dof, Finger, Hand, Joint, Link, Shape


class HandRegistry(Registry[Hand]):
    """Hands by name; built-in hands are built on first lookup, then kept.

    The registry takes no parameters; :data:`HANDS` is the one the package uses. Its
    ``register(hand, *, replace=False)``, ``unregister(name)``, ``get(name)`` and
    ``names()`` (built-in first) are those of :class:`affordgrasp.registry.Registry`.
    """

    def __init__(self) -> None:
        factories = {"barrett": barrett_bh8_282, "parallel_jaw": parallel_jaw}
        super().__init__("hand", Hand, HandError, factories)

    def _unknown_message(self, name: object, *, lookup: bool) -> str:
        hint = " (or a .json/.toml hand file)" if lookup else ""
        return f"unknown hand {name!r}; hands: {', '.join(self.names())}{hint}"


HANDS = HandRegistry()


def get_hand(hand: str | os.PathLike | Hand = "barrett") -> Hand:
    """A hand: a :class:`Hand` as it is, a registered name, or a ``.json``/``.toml`` hand file.

    Parameters
    ----------
    hand : Hand, str or path
        ``"barrett"`` (default), ``"parallel_jaw"``, a name given to :func:`register_hand`,
        or the path of a file written by :func:`save_hand`.

    Returns
    -------
    Hand
        The hand (the same object for the same registered name).

    Raises
    ------
    HandError
        For an unknown name or a bad hand file.
    """
    if isinstance(hand, Hand):
        return hand
    if isinstance(hand, os.PathLike) or (
        isinstance(hand, str) and hand not in HANDS and Path(hand).suffix in (".json", ".toml")
    ):
        return load_hand(hand)
    return HANDS.get(hand)


def register_hand(hand: Hand, *, replace: bool = False) -> Hand:
    """Register ``hand`` under its name (then ``get_hand(name)`` finds it).

    Parameters
    ----------
    hand : Hand
        The hand; its ``name`` is the key.
    replace : bool
        Allow replacing a hand of the same name (built-in ones included).

    Returns
    -------
    Hand
        ``hand`` itself.
    """
    return HANDS.register(hand, replace=replace)


def list_hands() -> list[str]:
    """Names of the registered hands.

    Returns
    -------
    list of str
        The built-in hands (``barrett``, ``parallel_jaw``) and those registered since.
    """
    return HANDS.names()


__all__ = [
    "HANDS",
    "Dof",
    "Finger",
    "Hand",
    "HandRegistry",
    "Joint",
    "Link",
    "Shape",
    "get_hand",
    "hand_from_dict",
    "hand_to_dict",
    "hand_to_toml",
    "list_hands",
    "load_hand",
    "register_hand",
    "save_hand",
]
