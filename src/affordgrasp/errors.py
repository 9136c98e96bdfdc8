"""The one exception hierarchy of affordgrasp.

Every error raised on bad user input is an :class:`InputError`; its message names the
bad value and says what to do. The CLI maps ``InputError`` to exit code 2 and any other
exception to exit code 1.
"""

from __future__ import annotations


class AffordgraspError(Exception):
    """Base class of every error affordgrasp raises on purpose."""


class InputError(AffordgraspError, ValueError):
    """Bad input from the user: a file, an argument, an option value.

    Parameters
    ----------
    message : str
        What is wrong and how to fix it, naming the Python parameter (``samples must be a
        positive integer, got 0``).
    parameter : str, optional
        The name of the bad parameter. The CLI shows it as its option (``--samples``): see
        :func:`cli_message`.
    """

    def __init__(self, message: str = "", *, parameter: str | None = None):
        super().__init__(message)
        self.parameter = parameter


def bad_parameter(parameter: str, problem: str, error: type[InputError] = InputError):
    """An error about one parameter: ``bad_parameter("samples", "must be >= 1, got 0")``.

    The message starts with the parameter's Python name; the CLI rewrites it to the option.

    Parameters
    ----------
    parameter : str
        The Python name of the bad parameter.
    problem : str
        What is wrong with it, starting with a verb (``"must be >= 1, got 0"``).
    error : type
        The :class:`InputError` subclass to build.

    Returns
    -------
    InputError
        The error (not raised), with ``parameter`` set.
    """
    return error(f"{parameter} {problem}", parameter=parameter)


def cli_message(exc: BaseException) -> str:
    """The message of an error as the CLI says it: the parameter named as its option.

    Parameters
    ----------
    exc : BaseException
        The error; when it has a ``parameter`` attribute, the first mention of that name
        becomes its option (``samples`` -> ``--samples``).

    Returns
    -------
    str
        The one-line message.
    """
    import re

    text = str(exc)
    parameter = getattr(exc, "parameter", None)
    if parameter:
        flag = "--" + parameter.replace("_", "-")
        text = re.sub(rf"(?<![\w-]){re.escape(parameter)}(?![\w])", flag, text, count=1)
    return text


class MeshError(InputError):
    """A mesh that cannot be read or used (empty, non-finite, open, degenerate...)."""


class HandError(InputError):
    """A hand description that is inconsistent or incomplete."""


class TaskError(InputError):
    """An unknown task, a bad threshold mode or a malformed task definition."""


class DatasetError(InputError):
    """A dataset directory that is missing, foreign or inconsistent with the request."""


class InternalError(AffordgraspError, RuntimeError):
    """A broken invariant inside affordgrasp: a bug, not bad input (please report it)."""


class MissingDependencyError(AffordgraspError, ImportError):
    """An optional dependency is needed for this feature and is not installed."""


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal (SIGTERM, SIGHUP) and handled like Ctrl-C.

    Workers are stopped and finished work is kept; the CLI exits with 128 + signum.

    Parameters
    ----------
    signum : int
        The signal number.
    """

    def __init__(self, signum: int):
        import signal

        self.signum = int(signum)
        super().__init__(f"stopped by {signal.Signals(self.signum).name}")


def require(module: str, extra: str):
    """Import an optional dependency, or raise a message that says how to install it.

    Parameters
    ----------
    module : str
        The module to import (``"torch"``, ``"mujoco"``).
    extra : str
        The optional extra of affordgrasp that installs it (``"learn"``, ``"physics"``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    MissingDependencyError
        When it is not installed; the message gives the ``pip install`` line.
    """
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

    Parameters
    ----------
    name : object
        The unknown name (anything that is not a non-empty str gives ``""``).
    choices : iterable
        The known names (compared case-insensitively).

    Returns
    -------
    str
        The suggestion with its leading space, or ``""``.
    """
    import difflib

    if not isinstance(name, str) or not name:
        return ""
    by_key = {str(c).lower(): str(c) for c in choices}
    close = difflib.get_close_matches(name.strip().lower(), list(by_key), n=2, cutoff=0.6)
    if not close:
        return ""
    return " (did you mean " + " or ".join(repr(by_key[c]) for c in close) + "?)"
