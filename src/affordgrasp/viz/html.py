"""A self-contained HTML page with an interactive 3D view of grasps (rotate, zoom, toggles).

Everything the page needs is inside the one file: three.js (vendored, see
``viz/static/build-three.sh``), the viewer script, the meshes and the grasps as JSON with
base64 arrays. Nothing is fetched from the network, so it opens offline from disk.

Meshes are sent once: each object, and each hand as its link meshes in the link frames; a
grasp is then the link poses (row-major 4x4, link → object), contacts, use point, wrist axis,
centre of mass and the camera of its PNG (same conventions as :mod:`affordgrasp.viz.camera`).
Vertices are float32 metres, normals int8 (normalised), indices uint16 or uint32.
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
import trimesh

from .._version import __version__
from ..hands import Hand
from ..hands.meshes import link_meshes
from ..runtime.writing import atomic_write
from .camera import Camera
from .raycast import corner_normals
from .scene import GraspScene


@dataclass(frozen=True)
class ViewerEntry:
    """One grasp in the viewer.

    Attributes
    ----------
    scene : GraspScene
        What to draw (needs ``hand_model`` and ``link_poses``, as ``grasp_scene`` sets).
    camera : Camera
        The initial view (e.g. the camera of the grasp's PNG).
    title : str
        Its caption.
    group : str
        The heading it is listed under (e.g. "knife:0 · cut").
    facts : list of (str, str)
        (name, value) pairs shown beside the view.
    thumbnail : bytes or None
        PNG bytes of the rendered grasp (listed, and shown when WebGL is missing).
    """

    scene: GraspScene
    camera: Camera
    title: str = ""
    group: str = ""
    facts: list[tuple[str, str]] = field(default_factory=list)
    thumbnail: bytes | None = None


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def mesh_payload(mesh: trimesh.Trimesh) -> dict:
    """A mesh for the viewer: vertices split at sharp edges so normals shade like the PNGs.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        m.

    Returns
    -------
    dict
        Positions (float32), quantised normals (int8) and triangle indices (uint16 or
        uint32), each little-endian and base64-encoded (JSON-ready).
    """
    faces = np.asarray(mesh.faces, dtype=np.int64)
    normals = np.clip(np.round(corner_normals(mesh) * 127.0), -127, 127).astype(np.int8)
    # One viewer vertex per distinct (vertex, quantised normal) pair.
    keys = np.concatenate([faces.reshape(-1, 1), normals.reshape(-1, 3).astype(np.int64)], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    positions = np.asarray(mesh.vertices, dtype=np.float32)[unique[:, 0]]
    index = inverse.reshape(-1)
    index_type = "uint16" if len(unique) < 65536 else "uint32"
    return {
        "positions": _b64(positions.astype("<f4")),
        "normals": _b64(unique[:, 1:].astype(np.int8)),
        "index": _b64(index.astype("<u2" if index_type == "uint16" else "<u4")),
        "index_type": index_type,
    }


def _finite_list(v) -> list | None:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if not np.all(np.isfinite(a)):
        return None
    return [float(x) for x in a]


def _points(a: np.ndarray) -> list:
    return [[float(x) for x in p] for p in np.asarray(a, dtype=np.float64).reshape(-1, 3)]


def viewer_document(entries: list[ViewerEntry]) -> dict:
    """The JSON document the page embeds (objects, hands, grasps).

    Parameters
    ----------
    entries : list of ViewerEntry

    Returns
    -------
    dict
    """
    if not entries:
        raise ValueError("the viewer needs at least one grasp")
    objects: list[dict] = []
    object_index: dict[int, int] = {}
    hands: dict[str, dict] = {}
    grasps = []
    for e in entries:
        s = e.scene
        key = id(s.object_mesh)
        if key not in object_index:
            object_index[key] = len(objects)
            objects.append({"mesh": mesh_payload(s.object_mesh)})
        hand: Hand | None = s.hand_model
        if hand is None or s.link_poses is None:
            raise ValueError("viewer entries need scenes with hand_model and link_poses")
        if hand.name not in hands:
            hands[hand.name] = {
                "links": [
                    None if m is None else {"mesh": mesh_payload(m), "palm": i == 0}
                    for i, m in enumerate(link_meshes(hand))
                ]
            }
        thumb = None
        if e.thumbnail:
            thumb = "data:image/png;base64," + base64.b64encode(e.thumbnail).decode("ascii")
        grasps.append(
            {
                "title": e.title or s.title,
                "group": e.group,
                "object": object_index[key],
                "hand": hand.name,
                "link_poses": [[float(x) for x in p.reshape(-1)] for p in np.asarray(s.link_poses)],
                "contacts": {
                    "points": _points(s.contact_points),
                    "normals": _points(s.contact_normals),
                    "mu": [float(m) for m in np.asarray(s.contact_mu).reshape(-1)],
                    "link": [str(x) for x in np.asarray(s.contact_link).reshape(-1)],
                },
                "use_point": _finite_list(s.use_point),
                "use_normal": _finite_list(s.use_normal),
                "wrist_point": _finite_list(s.wrist_point),
                "wrist_axis": _finite_list(s.wrist_axis),
                "com": _finite_list(s.center_of_mass),
                "size": s.size,
                "camera": {
                    "eye": _finite_list(e.camera.eye),
                    "target": _finite_list(e.camera.target),
                    "up": _finite_list(e.camera.basis()[1]),
                    "fov": float(e.camera.fov_deg),
                },
                "facts": [[str(k), str(v)] for k, v in e.facts],
                "thumbnail": thumb,
            }
        )
    return {"version": __version__, "objects": objects, "hands": hands, "grasps": grasps}


def _static(name: str) -> str:
    return resources.files("affordgrasp.viz").joinpath("static", name).read_text("utf-8")


def _json_in_script(data: str) -> str:
    # Inside <script>, "</script" and "<!--" could end or derail the element: JSON may write
    # every "<" as its escape, which parses to the same document.
    return data.replace("<", "\\u003c")


def _code_in_script(code: str, name: str) -> str:
    if re.search(r"</script|<!--|<script", code, flags=re.IGNORECASE):
        raise ValueError(f"{name} cannot be inlined in a <script> element as it is")
    return code


def viewer_html(
    entries: list[ViewerEntry], *, title: str = "affordgrasp", subtitle: str = ""
) -> str:
    """The page as a string.

    Parameters
    ----------
    entries : list of ViewerEntry
    title, subtitle : str
        The page's heading.

    Returns
    -------
    str
        Self-contained HTML (scripts and data inline; no network).
    """
    document = viewer_document(entries)
    data = json.dumps(document, separators=(",", ":"), allow_nan=False)
    parts = {
        "TITLE": html.escape(title),
        "SUBTITLE": html.escape(subtitle),
        "VERSION": html.escape(__version__),
        "DATA": _json_in_script(data),
        "THREE": _code_in_script(_static("three.bundle.min.js"), "three.bundle.min.js"),
        "VIEWER": _code_in_script(_static("viewer.js"), "viewer.js"),
    }
    # One pass, so nothing inserted is read as a placeholder.
    return re.sub(r"\{\{([A-Z]+)\}\}", lambda m: parts[m.group(1)], _static("viewer.html"))


def write_viewer(
    path: str | os.PathLike,
    entries: list[ViewerEntry],
    *,
    title: str = "affordgrasp",
    subtitle: str = "",
) -> Path:
    """Write the self-contained viewer page.

    Parameters
    ----------
    path : path
        The HTML file.
    entries : list of ViewerEntry
    title, subtitle : str
        The page's heading.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write(path, viewer_html(entries, title=title, subtitle=subtitle).encode("utf-8"))


def fmt_value(value) -> str:
    """A metric value as the viewer lists it.

    Parameters
    ----------
    value : object
        A number (finite, ±inf or NaN: shown as ∞, −∞, —) or anything else.

    Returns
    -------
    str
    """
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "—"
        if math.isinf(v):
            return "∞" if v > 0 else "−∞"
        return f"{v:.4g}"
    return str(value)
