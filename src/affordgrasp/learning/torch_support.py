"""PyTorch and safetensors are optional (``pip install "affordgrasp[learn]"``): import lazily."""

from __future__ import annotations

from ..errors import MissingDependencyError

INSTALL_HINT = 'pip install "affordgrasp[learn]"'


def require_torch():
    """``torch``, or a MissingDependencyError that names the extra to install.

    Returns
    -------
    module
    """
    try:
        import torch
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(
            f"learning needs PyTorch (CPU is enough); install it with: {INSTALL_HINT}"
        ) from exc
    return torch


def require_safetensors():
    """``safetensors.torch``, or a MissingDependencyError that names the extra to install.

    Returns
    -------
    module
    """
    try:
        import safetensors.torch as st
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(
            f"model files need the safetensors package; install it with: {INSTALL_HINT}"
        ) from exc
    return st
