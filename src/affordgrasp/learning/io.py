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
from ..runtime.writing import atomic_write
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
    data = st.save(state, metadata={METADATA_KEY: json.dumps(document, sort_keys=True)})
    atomic_write(path, data)
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
    try:
        config = json.loads(meta[METADATA_KEY])
    except ValueError as exc:
        raise InputError(f"{str(path)!r}: its model config is not valid JSON ({exc})") from None
    check_config(config, path)
    return config


def check_config(config, path: str | os.PathLike) -> None:
    """Refuse a model config this version cannot rebuild: format, version, architecture, inputs.

    Parameters
    ----------
    config : object
        The decoded ``affordgrasp_model`` metadata.
    path : path
        The file, for the message.

    Raises
    ------
    InputError
        Naming what differs from what this version reads.
    """
    from .models import ARCHITECTURES

    where = repr(str(path))
    if not isinstance(config, dict) or config.get("format") != FORMAT:
        raise InputError(f"{where} holds an unsupported model format (not {FORMAT!r})")
    version = config.get("format_version", 0)
    if not isinstance(version, int) or not 1 <= version <= FORMAT_VERSION:
        raise InputError(
            f"{where} has model format version {version!r}; this affordgrasp reads versions "
            f"1 to {FORMAT_VERSION} (made by affordgrasp {config.get('affordgrasp_version', '?')})"
        )
    arch = config.get("arch")
    if arch not in ARCHITECTURES:
        raise InputError(
            f"{where} has architecture {arch!r}; this affordgrasp knows {', '.join(ARCHITECTURES)}"
        )
    target = config.get("target")
    if not isinstance(target, dict) or "kind" not in target or "name" not in target:
        raise InputError(f"{where} has no target (kind and name) in its config")
    camera = config.get("camera", {"size": 128})
    size = camera.get("size") if isinstance(camera, dict) else None
    if not isinstance(size, int) or not 8 <= size <= 1024:
        raise InputError(f"{where} has input image size {size!r}; expected a size of 8-1024 px")
    view = config.get("view")
    if view not in (None, "hand") or (view == "hand" and arch != "cnn"):
        raise InputError(
            f"{where} has input view {view!r} for architecture {arch!r}; this affordgrasp knows "
            "the camera image (no view) and the hand view of a cnn"
        )
    for key in ("width", "n_points", "members"):
        value = config.get(key, 1)
        if not isinstance(value, int) or value < 1:
            raise InputError(f"{where} has {key} = {value!r}; expected a positive integer")


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
    try:
        state = st.load_file(str(path))
    except Exception as exc:  # noqa: BLE001 - a truncated or corrupt file is bad input
        raise InputError(f"{str(path)!r}: cannot read its weights ({exc})") from None
    _check_tensors(state, model.state_dict(), config, path)
    missing, unexpected = model.load_state_dict(state, strict=False)
    if missing or unexpected:
        raise InputError(
            f"{str(path)!r} does not match its config (missing {missing[:3]}, "
            f"unexpected {unexpected[:3]})"
        )
    model.eval()
    return model, config


def _check_tensors(state: dict, expected: dict, config: dict, path) -> None:
    """Shapes as the config's architecture builds them, and finite values, before loading."""
    torch = require_torch()
    described = (
        f"architecture {config['arch']!r}, image {config.get('camera', {}).get('size')} px, "
        f"width {config.get('width')}"
    )
    for name, tensor in state.items():
        want = expected.get(name)
        if want is not None and tuple(tensor.shape) != tuple(want.shape):
            raise InputError(
                f"{str(path)!r}: tensor {name!r} has shape {tuple(tensor.shape)}, but its config "
                f"({described}) builds {tuple(want.shape)}; the weights are of another model"
            )
        if tensor.is_floating_point():
            bad = int((~torch.isfinite(tensor)).sum())
            if bad:
                raise InputError(
                    f"{str(path)!r}: tensor {name!r} holds {bad} non-finite values (NaN or "
                    "inf); the file is corrupt or its training diverged: retrain it"
                )
