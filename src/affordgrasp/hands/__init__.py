"""Hands as data: the Barrett BH8-282, a parallel-jaw gripper, and hands you register.

Look a hand up with :func:`get_hand` (a registered name, a ``.json``/``.toml`` hand file, or a
:class:`Hand`, returned as it is); add one with :func:`register_hand`; write and read hand
files with :func:`save_hand` / :func:`load_hand` (:mod:`.files`). Conventions of the hand
frame, joints and fingers: :mod:`.model`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from ..errors import HandError
from .barrett import barrett_bh8_282
from .files import hand_from_dict, hand_to_dict, hand_to_toml, load_hand, save_hand
from .gripper import parallel_jaw
from .model import Dof, Finger, Hand, Joint, Link, Shape


class HandRegistry:
    """Hands by name; built-in hands are built on first lookup, then kept.

    The registry takes no parameters; :data:`HANDS` is the one the package uses.

    Attributes
    ----------
    register : method
        ``register(hand, *, replace=False)``: add a hand under its name.
    unregister : method
        ``unregister(name)``: remove one.
    get : method
        ``get(name)``: the hand of that name (:class:`HandError` if unknown).
    """

    def __init__(self) -> None:
        self._factories: dict[str, Callable[[], Hand]] = {
            "barrett": barrett_bh8_282,
            "parallel_jaw": parallel_jaw,
        }
        self._hands: dict[str, Hand] = {}

    def register(self, hand: Hand, *, replace: bool = False) -> Hand:
        """Add ``hand`` under ``hand.name``.

        Parameters
        ----------
        hand : Hand
        replace : bool
            Allow replacing a hand registered under that name.

        Returns
        -------
        Hand
            ``hand`` itself.

        Raises
        ------
        HandError
            For something other than a Hand, or a taken name without ``replace``.
        """
        if not isinstance(hand, Hand):
            raise HandError(f"expected a Hand, got {type(hand).__name__}")
        if hand.name in self._factories and not replace:
            raise HandError(
                f"hand {hand.name!r} is already registered (pass replace=True to replace it)"
            )
        self._factories[hand.name] = lambda: hand
        self._hands[hand.name] = hand
        return hand

    def unregister(self, name: str) -> None:
        """Remove a hand (built-in ones included).

        Parameters
        ----------
        name : str

        Raises
        ------
        HandError
            When no hand has that name.
        """
        if name not in self._factories:
            raise HandError(f"unknown hand {name!r}; hands: {', '.join(self._factories)}")
        del self._factories[name]
        self._hands.pop(name, None)

    def get(self, name: str) -> Hand:
        """The hand registered as ``name`` (a built-in one is built on first use).

        Parameters
        ----------
        name : str

        Returns
        -------
        Hand

        Raises
        ------
        HandError
            For an unknown name; the message lists the registered hands.
        """
        hand = self._hands.get(name) if isinstance(name, str) else None
        if hand is None:
            try:
                factory = self._factories[name]
            except (KeyError, TypeError):
                raise HandError(
                    f"unknown hand {name!r}; hands: {', '.join(self._factories)} "
                    "(or a .json/.toml hand file)"
                ) from None
            hand = self._hands[name] = factory()
        return hand

    def names(self) -> list[str]:
        """Names of the registered hands, built-in first.

        Returns
        -------
        list of str
        """
        return list(self._factories)

    def __contains__(self, name: object) -> bool:
        return name in self._factories


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
