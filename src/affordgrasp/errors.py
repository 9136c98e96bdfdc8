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
