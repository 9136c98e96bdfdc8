"""The one exception hierarchy of affordgrasp.

Every error raised on bad user input is an :class:`InputError`; its message names the
bad value and says what to do. The CLI maps ``InputError`` to exit code 2 and any other
exception to exit code 1.
"""

from __future__ import annotations


class AffordgraspError(Exception):
    """Base class of every error affordgrasp raises on purpose."""


class InputError(AffordgraspError, ValueError):
    """Bad input from the user: a file, an argument, an option value."""


class MeshError(InputError):
    """A mesh that cannot be read or used (empty, non-finite, open, degenerate...)."""


class HandError(InputError):
    """A hand description that is inconsistent or incomplete."""


class TaskError(InputError):
    """An unknown task, a bad threshold mode or a malformed task definition."""


class DatasetError(InputError):
    """A dataset directory that is missing, foreign or inconsistent with the request."""


class MissingDependencyError(AffordgraspError, ImportError):
    """An optional dependency is needed for this feature and is not installed."""


def require(module: str, extra: str):
    """Import an optional dependency, or raise a message that says how to install it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(
            f"this feature needs the optional package '{module}'; "
            f"install it with: pip install 'affordgrasp[{extra}]'"
        ) from exc


def did_you_mean(name: object, choices) -> str:
    """`` (did you mean 'hammer'?)`` when ``name`` is close to one of ``choices``, else ``""``.

    For messages about unknown names: a typo gets the intended name back.
    """
    import difflib

    if not isinstance(name, str) or not name:
        return ""
    by_key = {str(c).lower(): str(c) for c in choices}
    close = difflib.get_close_matches(name.strip().lower(), list(by_key), n=2, cutoff=0.6)
    if not close:
        return ""
    return " (did you mean " + " or ".join(repr(by_key[c]) for c in close) + "?)"
