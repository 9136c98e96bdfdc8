"""Things by name, for the hands and the tasks: register, look up, list, remove.

One small class serves both registries (``affordgrasp.hands.HANDS``,
``affordgrasp.tasks.TASKS``); each says only how it names what it keeps and how it
words an unknown name.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")


class Registry(Generic[T]):
    """Values by name; a value added as a factory is built at its first lookup, then kept.

    Parameters
    ----------
    kind : str
        What a value is (``"hand"``), for the messages.
    value_type : type
        What :meth:`register` accepts; a value's ``name`` is its key.
    error : type of Exception
        What a refusal raises (``HandError``, ``TaskError``).
    factories : mapping of str to callable, optional
        Name -> ``factory() -> value`` of the values there from the start.
    """

    def __init__(self, kind: str, value_type: type, error: type[Exception], factories=None):
        self.kind, self.value_type, self.error = kind, value_type, error
        self._factories: dict[str, Callable[[], T]] = dict(factories or {})
        self._values: dict[str, T] = {}

    def _prepare(self) -> None:
        """Called before every use: a registry that fills itself late does it here."""

    def _unknown_message(self, name: object, *, lookup: bool) -> str:
        """The refusal of an unknown ``name`` (``lookup``: by :meth:`get`, else by
        :meth:`unregister`)."""
        return f"unknown {self.kind} {name!r}; {self.kind}s: {', '.join(self.names())}"

    def _check_free(self, name: str, replace: bool) -> None:
        if name in self._factories and not replace:
            raise self.error(
                f"{self.kind} {name!r} is already registered (pass replace=True to replace it)"
            )

    def _put(self, value: T) -> None:
        self._factories[value.name] = lambda: value
        self._values[value.name] = value

    def register(self, value: T, *, replace: bool = False) -> T:
        """Add ``value`` under ``value.name``.

        Parameters
        ----------
        value : the registry's value type
        replace : bool
            Allow replacing a value registered under that name.

        Returns
        -------
        ``value`` itself.

        Raises
        ------
        error
            For a value of another type, or a taken name without ``replace``.
        """
        if not isinstance(value, self.value_type):
            raise self.error(f"expected a {self.value_type.__name__}, got {type(value).__name__}")
        self._prepare()
        self._check_free(value.name, replace)
        self._put(value)
        return value

    def unregister(self, name: str) -> None:
        """Remove a value (built-in ones included).

        Parameters
        ----------
        name : str

        Raises
        ------
        error
            When no value has that name.
        """
        self._prepare()
        if name not in self._factories:
            raise self.error(self._unknown_message(name, lookup=False))
        del self._factories[name]
        self._values.pop(name, None)

    def get(self, name: str) -> T:
        """The value registered as ``name`` (one added as a factory is built on first use).

        Parameters
        ----------
        name : str

        Returns
        -------
        The value.

        Raises
        ------
        error
            For an unknown name; the message lists the registered ones.
        """
        self._prepare()
        value = self._values.get(name) if isinstance(name, str) else None
        if value is None:
            try:
                factory = self._factories[name]
            except (KeyError, TypeError):
                raise self.error(self._unknown_message(name, lookup=True)) from None
            value = self._values[name] = factory()
        return value

    def names(self) -> list[str]:
        """Names of the registered values, in the order they were added.

        Returns
        -------
        list of str
        """
        self._prepare()
        return list(self._factories)

    def __contains__(self, name: object) -> bool:
        self._prepare()
        return name in self._factories

    def __iter__(self):
        return iter(self.names())

    def __len__(self) -> int:
        self._prepare()
        return len(self._factories)
