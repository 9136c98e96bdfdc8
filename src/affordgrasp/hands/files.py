"""Hands as documents: a :class:`Hand` to and from a dict, JSON or TOML (round trip exact).

The document mirrors the dataclasses (lengths in m, angles in rad, poses as 4x4 nested
lists, row-major)::

    name = "my_gripper"
    description = "..."
    pregrasp_dof = "spread"            # omitted when the hand has none
    [[dofs]]
    name = "spread"; lower = 0.0; upper = 3.14159; role = "pregrasp"
    [[links]]
    name = "palm"; material = "plastic"            # the root: no parent, no joint
    [[links.shapes]]
    kind = "cylinder"; half_extents = [0.04, 0.04, 0.01]; radius = 0.0045
    pose = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -0.01], [0, 0, 0, 1]]
    [[links]]
    name = "f1_proximal"; parent = "palm"; material = "wood"
    [links.joint]
    kind = "revolute"; origin = [[...]]; axis = [0, 1, 0]; dof = "f1"; ratio = 1.0
    [[fingers]]
    name = "f1"; dofs = ["f1"]; speeds = [1.0]

:func:`save_hand` writes ``.json`` or ``.toml``; :func:`load_hand` reads either, and also a
dataset's ``_manifest.json`` (the hand it records under ``hand_spec``), so that a dataset
is resumed with ``--hand DIR/_manifest.json``.
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HandError
from ..runtime.writing import atomic_write
from .model import Dof, Finger, Hand, Joint, Link, Shape

FORMATS = (".json", ".toml")


def _matrix(m: Any) -> list:
    return np.asarray(m, dtype=np.float64).tolist()


def hand_to_dict(hand: Hand) -> dict:
    """The hand as plain data (str, float, lists, dicts): JSON- and TOML-ready.

    Parameters
    ----------
    hand : Hand
        The hand.

    Returns
    -------
    dict
        Links (poses as 4 x 4 nested lists, lengths in m), DOFs (limits in rad or m),
        fingers and the pregrasp DOF; :func:`hand_from_dict` rebuilds the hand exactly.
    """
    links = []
    for link in hand.links:
        doc: dict[str, Any] = {"name": link.name, "material": link.material}
        if link.parent is not None:
            doc["parent"] = link.parent
        if link.joint is not None:
            j = link.joint
            doc["joint"] = {
                "kind": j.kind,
                "origin": _matrix(j.origin),
                "axis": _matrix(j.axis),
                "dof": j.dof,
                "ratio": float(j.ratio),
            }
        doc["shapes"] = [
            {
                "kind": s.kind,
                "half_extents": [float(x) for x in s.half_extents],
                "radius": float(s.radius),
                "pose": _matrix(s.pose),
            }
            for s in link.shapes
        ]
        links.append(doc)
    out: dict[str, Any] = {"name": hand.name, "description": hand.description}
    if hand.pregrasp_dof is not None:
        out["pregrasp_dof"] = hand.pregrasp_dof
    out["dofs"] = [
        {"name": d.name, "lower": float(d.lower), "upper": float(d.upper), "role": d.role}
        for d in hand.dofs
    ]
    out["links"] = links
    out["fingers"] = [
        {"name": f.name, "dofs": list(f.dofs), "speeds": [float(s) for s in f.speeds]}
        for f in hand.fingers
    ]
    return out


def _need(doc: Any, key: str, where: str) -> Any:
    if not isinstance(doc, dict) or key not in doc:
        raise HandError(f"{where}: missing key {key!r}")
    return doc[key]


def _array(value: Any, shape: tuple[int, ...], where: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != shape:
        raise HandError(f"{where} must be numbers of shape {shape}, got {value!r}")
    return arr


def _half_extents(a: np.ndarray) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))


def hand_from_dict(doc: dict) -> Hand:
    """The :class:`Hand` of a document made by :func:`hand_to_dict` (validated).

    Parameters
    ----------
    doc : dict
        The document (from JSON or TOML).

    Returns
    -------
    Hand
        Validated; a bad document raises :class:`~affordgrasp.errors.HandError`.
    """
    name = str(_need(doc, "name", "hand"))
    where = f"hand {name!r}"
    try:
        dofs = tuple(
            Dof(
                str(_need(d, "name", f"{where} dof")),
                float(_need(d, "lower", f"{where} dof")),
                float(_need(d, "upper", f"{where} dof")),
                str(_need(d, "role", f"{where} dof")),
            )
            for d in _need(doc, "dofs", where)
        )
        links = []
        for raw in _need(doc, "links", where):
            lname = str(_need(raw, "name", f"{where} link"))
            lw = f"{where} link {lname!r}"
            joint = None
            if "joint" in raw:
                j = raw["joint"]
                joint = Joint(
                    str(_need(j, "kind", lw)),
                    _array(_need(j, "origin", lw), (4, 4), f"{lw} joint origin"),
                    _array(_need(j, "axis", lw), (3,), f"{lw} joint axis"),
                    str(_need(j, "dof", lw)),
                    float(j.get("ratio", 1.0)),
                )
            shapes = tuple(
                Shape(
                    str(_need(s, "kind", lw)),
                    _half_extents(_array(_need(s, "half_extents", lw), (3,), lw)),
                    float(_need(s, "radius", lw)),
                    _array(s.get("pose", np.eye(4)), (4, 4), f"{lw} shape pose"),
                )
                for s in raw.get("shapes", [])
            )
            links.append(
                Link(lname, raw.get("parent"), joint, shapes, str(_need(raw, "material", lw)))
            )
        fingers = tuple(
            Finger(
                str(_need(f, "name", f"{where} finger")),
                tuple(str(x) for x in _need(f, "dofs", f"{where} finger")),
                tuple(float(x) for x in _need(f, "speeds", f"{where} finger")),
            )
            for f in doc.get("fingers", [])
        )
    except (TypeError, AttributeError, ValueError) as exc:
        raise HandError(f"{where}: malformed hand document ({exc})") from None
    return Hand(
        name=name,
        links=tuple(links),
        dofs=dofs,
        fingers=fingers,
        pregrasp_dof=doc.get("pregrasp_dof"),
        description=str(doc.get("description", "")),
    )


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a valid TOML basic string
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise HandError(f"cannot write {type(v).__name__} to TOML")


def _toml_table(doc: dict, path: str, lines: list[str]) -> None:
    def is_tables(v: Any) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    for key, value in doc.items():
        if not isinstance(value, dict) and not is_tables(value):
            lines.append(f"{key} = {_toml_value(value)}")
    for key, value in doc.items():
        sub = f"{path}.{key}" if path else key
        if isinstance(value, dict):
            lines.append(f"\n[{sub}]")
            _toml_table(value, sub, lines)
        elif is_tables(value):
            for item in value:
                lines.append(f"\n[[{sub}]]")
                _toml_table(item, sub, lines)


def hand_to_toml(hand: Hand) -> str:
    """The hand as a TOML document.

    Parameters
    ----------
    hand : Hand
        The hand.

    Returns
    -------
    str
        TOML text of :func:`hand_to_dict` (floats written exactly).
    """
    lines: list[str] = []
    _toml_table(hand_to_dict(hand), "", lines)
    return "\n".join(lines) + "\n"


def save_hand(hand: Hand, path: str | os.PathLike) -> Path:
    """Write ``hand`` to a file that :func:`load_hand` reads back exactly.

    Parameters
    ----------
    hand : Hand
        The hand.
    path : path
        A ``.json`` or ``.toml`` file name (the suffix picks the format).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    if path.suffix not in FORMATS:
        raise HandError(f"a hand file must end in .json or .toml, got {str(path)!r}")
    if path.suffix == ".json":
        text = json.dumps(hand_to_dict(hand), indent=1)
    else:
        text = hand_to_toml(hand)
    return atomic_write(path, text.encode("utf-8"))


def load_hand(path: str | os.PathLike) -> Hand:
    """Read a hand from a ``.json`` or ``.toml`` file (format: the module docstring).

    Parameters
    ----------
    path : path
        A file written by :func:`save_hand` (or by hand, in the same form), or a dataset's
        ``_manifest.json``: the hand recorded under its ``hand_spec`` key.

    Returns
    -------
    Hand
        Validated; a bad document raises :class:`~affordgrasp.errors.HandError`.
    """
    path = Path(path)
    if path.suffix not in FORMATS:
        raise HandError(f"a hand file must end in .json or .toml, got {str(path)!r}")
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise HandError(f"hand file {str(path)!r} does not exist") from None
    try:
        doc = json.loads(raw) if path.suffix == ".json" else tomllib.loads(raw.decode("utf-8"))
    except (ValueError, tomllib.TOMLDecodeError) as exc:
        raise HandError(f"hand file {str(path)!r} is not valid {path.suffix[1:]}: {exc}") from None
    if isinstance(doc, dict) and isinstance(doc.get("hand_spec"), dict):
        doc = doc["hand_spec"]  # a dataset manifest: the hand it was generated with
    elif isinstance(doc, dict) and doc.get("format") == "affordgrasp-dataset":
        raise HandError(
            f"dataset manifest {str(path)!r} records its hand by name only "
            f"({doc.get('hand')!r}, written before hands were recorded whole); "
            "pass that name or the hand's own file"
        )
    try:
        return hand_from_dict(doc)
    except HandError as exc:
        raise HandError(f"hand file {str(path)!r}: {exc}") from None
