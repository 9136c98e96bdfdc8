"""PyTorch and safetensors are optional (``pip install "affordgrasp[learn]"``): import lazily."""

from __future__ import annotations

import importlib

from ..errors import MissingDependencyError

INSTALL_HINT = 'pip install "affordgrasp[learn]"'


def _require(module: str, need: str):
    try:
        return importlib.import_module(module)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(f"{need}; install it with: {INSTALL_HINT}") from exc


def require_torch():
    """``torch``, or a MissingDependencyError that names the extra to install.

    Returns
    -------
    module
    """
    return _require("torch", "learning needs PyTorch (CPU is enough)")


def require_safetensors():
    """``safetensors.torch``, or a MissingDependencyError that names the extra to install.

    Returns
    -------
    module
    """
    return _require("safetensors.torch", "model files need the safetensors package")
