"""The physics extra's optional dependencies, imported on first use."""

from __future__ import annotations

from ..errors import MissingDependencyError

INSTALL_HINT = 'pip install "affordgrasp[physics]"'


def _require(name: str):
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise MissingDependencyError(
            f"physics validation needs the optional package {name!r}; install it with: "
            f"{INSTALL_HINT}"
        ) from exc


def mujoco():
    """The ``mujoco`` module (MuJoCo's official Python bindings).

    Returns
    -------
    module
        ``mujoco``, imported.

    Raises
    ------
    MissingDependencyError
        When it is not installed, naming the extra that installs it.
    """
    return _require("mujoco")


def coacd():
    """The ``coacd`` module (approximate convex decomposition).

    Returns
    -------
    module
        ``coacd``, imported.

    Raises
    ------
    MissingDependencyError
        When it is not installed, naming the extra that installs it.
    """
    return _require("coacd")
