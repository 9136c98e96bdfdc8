"""Model files: safetensors weights with the model's JSON config in the file's metadata.

Nothing is ever unpickled: :func:`load_model` reads the config (``affordgrasp_model``
metadata key) with ``safetensors.safe_open``, rebuilds the network from it and loads the
tensors with ``safetensors.torch.load_file``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..errors import InputError
from .torch_support import require_safetensors, require_torch

METADATA_KEY = "affordgrasp_model"
FORMAT = "affordgrasp-model"
FORMAT_VERSION = 1


def save_model(path: str | os.PathLike, model, config: dict) -> Path:
    """Write ``model``'s weights and ``config`` to ``path`` (a .safetensors file).

    Parameters
    ----------
    path : path
        The model file.
    model : torch.nn.Module
    config : dict
        JSON-ready description that rebuilds the model (stored in the file's metadata).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    st = require_safetensors()
    path = Path(path)
    if path.suffix != ".safetensors":
        raise InputError(f"model file {str(path)!r} must end in .safetensors")
    document = dict(config, format=FORMAT, format_version=FORMAT_VERSION)
    state = {k: v.detach().contiguous().cpu() for k, v in model.state_dict().items()}
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    st.save_file(state, str(tmp), metadata={METADATA_KEY: json.dumps(document, sort_keys=True)})
    os.replace(tmp, path)
    return path


def read_config(path: str | os.PathLike) -> dict:
    """The config stored in a model file (no weights loaded).

    Parameters
    ----------
    path : path
        A file written by :func:`save_model`.

    Returns
    -------
    dict
    """
    require_torch()
    from safetensors import safe_open

    path = Path(path)
    if not path.is_file():
        raise InputError(
            f"model file {str(path)!r} does not exist; train one with "
            "'affordgrasp train DATASET -o model.safetensors' or use 'default'"
        )
    try:
        with safe_open(str(path), framework="pt") as f:
            meta = f.metadata() or {}
    except Exception as exc:  # noqa: BLE001 - anything unreadable is bad input
        raise InputError(f"{str(path)!r} is not a safetensors model file: {exc}") from None
    if METADATA_KEY not in meta:
        raise InputError(f"{str(path)!r} is a safetensors file without an affordgrasp model config")
    config = json.loads(meta[METADATA_KEY])
    if config.get("format") != FORMAT or config.get("format_version", 0) > FORMAT_VERSION:
        raise InputError(f"{str(path)!r} holds an unsupported model format")
    return config


def load_model(path: str | os.PathLike):
    """The model of a model file in eval mode and its config, without unpickling anything.

    Parameters
    ----------
    path : path
        A file written by :func:`save_model`.

    Returns
    -------
    model : torch.nn.Module
    config : dict
    """
    st = require_safetensors()
    from .models import build_model

    config = read_config(path)
    model = build_model(config)
    state = st.load_file(str(path))
    missing, unexpected = model.load_state_dict(state, strict=False)
    if missing or unexpected:
        raise InputError(
            f"{str(path)!r} does not match its config (missing {missing[:3]}, "
            f"unexpected {unexpected[:3]})"
        )
    model.eval()
    return model, config
