"""A dataset's manifest: the plan a run writes first and a resume must match.

``DIR/_manifest.json`` records what the command asked for (conventions: Datasets): the objects
with their mesh hashes, the seed, the samples and shard size, the hand, the metrics. It is
written before any shard (:func:`prepare_directory`); a run into a directory that holds one
resumes it only when every key of ``PLAN_KEYS`` agrees, and otherwise names what differs.
The rest of the directory: :mod:`.shards` (the rows) and :mod:`.checksums`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..errors import DatasetError
from ..runtime import writing

FORMAT = "affordgrasp-dataset"
# 2: shard checksums in _checksums.jsonl.
FORMAT_VERSION = 2
MANIFEST_NAME = "_manifest.json"
CARD_JSON_NAME = "_card.json"
CARD_MD_NAME = "_card.md"

# Manifest keys that define the content of the dataset; a resume must match all of them.
PLAN_KEYS = (
    "robust",
    "format_version",
    "affordgrasp_version",
    "seed",
    "samples",
    "shard_size",
    "hand",
    "hand_spec",
    "metrics",
    "volume",
    "soft",
    "depth",
    "materials",
    "sample_streams",
    "objects",
    "probability_models",
)
# Yes/no plan keys: what they say, and what each value means (an absent "materials", in a
# manifest written before it was recorded, is unit density).
_FLAGS = {
    "volume": ("GWS volume", "computed (--metrics +volume)", "not computed"),
    "materials": ("mass properties from", "per-part materials (--materials)", "unit density"),
}


def write_json_atomic(path: Path, document: dict) -> None:
    """Write a JSON file atomically (:func:`~affordgrasp.runtime.writing.atomic_write`).

    Parameters
    ----------
    path : pathlib.Path
    document : dict
        JSON-ready; written indented, keys in their order.
    """
    writing.atomic_write(path, (json.dumps(document, indent=2) + "\n").encode("utf-8"))


def check_writable(directory: Path) -> None:
    """Refuse an output directory that cannot be written, before any work is done.

    The directory is created (with its parents) and a probe file written and removed.

    Parameters
    ----------
    directory : pathlib.Path

    Raises
    ------
    InputError
        From :func:`~affordgrasp.runtime.writing.write_error`.
    """
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise writing.write_error(directory, exc) from exc
    probe = directory / f".write-test-{os.getpid()}"
    try:
        writing.write_file(probe, b"")
    except OSError as exc:
        raise writing.write_error(directory, exc) from exc
    finally:
        try:
            probe.unlink(missing_ok=True)
        except OSError:
            pass


def read_manifest(directory: str | os.PathLike) -> dict:
    """The manifest of a dataset directory.

    Parameters
    ----------
    directory : path

    Returns
    -------
    dict
        The parsed ``_manifest.json``.

    Raises
    ------
    DatasetError
        Saying why there is none: no directory, no manifest, unreadable or foreign JSON.
    """
    directory = Path(directory)
    path = directory / MANIFEST_NAME
    if not directory.is_dir():
        raise DatasetError(
            f"dataset directory {str(directory)!r} does not exist; create one with "
            "'affordgrasp generate OBJECT... --samples N --out DIR'"
        )
    if not path.is_file():
        raise DatasetError(
            f"{str(directory)!r} is not an affordgrasp dataset (no {MANIFEST_NAME}); give the "
            "directory that 'affordgrasp generate --out' wrote"
        )
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise DatasetError(f"cannot read {str(path)!r}: {exc}") from exc
    if manifest.get("format") != FORMAT:
        raise DatasetError(f"{str(path)!r} is not an affordgrasp dataset manifest")
    return manifest


def manifest_volume(manifest: dict) -> bool:
    """Whether a dataset's ``gws_volume`` column holds computed volumes.

    Parameters
    ----------
    manifest : dict
        A dataset manifest.

    Returns
    -------
    bool
        Its ``volume`` entry; a manifest written before the volume became optional has
        none, and computed the volume whenever it computed metrics.
    """
    if "volume" in manifest:
        return bool(manifest["volume"])
    return bool(manifest.get("metrics"))


def manifest_streams(manifest: dict) -> str:
    """How a dataset's objects drew their samples: ``"per-object"`` or ``"shared"``.

    Parameters
    ----------
    manifest : dict

    Returns
    -------
    str
        Its ``sample_streams`` entry; a manifest written before it was recorded has none,
        and every object of it drew the run's samples (``"shared"``).
    """
    return str(manifest.get("sample_streams", "shared"))


def manifest_differences(existing: dict, requested: dict) -> list[str]:
    """Readable differences between two manifests' plans (``PLAN_KEYS``).

    Parameters
    ----------
    existing : dict
        The manifest on disk.
    requested : dict
        The manifest of the run asked for.

    Returns
    -------
    list of str
        One phrase per difference, e.g. ``"seed 0 there vs 1 here"``; empty when they agree.
    """
    diffs, both = [], (existing, requested)
    for key in PLAN_KEYS:
        a, b = existing.get(key), requested.get(key)
        if key == "hand_spec":
            changed = hand_spec_differences(a, b)
            if changed and existing.get("hand") == requested.get("hand"):
                diffs.append(
                    f"hand {existing.get('hand')!r}: same name, different {', '.join(changed)}"
                )
        elif key == "objects":
            a = [(o.get("name"), o.get("mesh_hash")) for o in a or []]
            b = [(o.get("name"), o.get("mesh_hash")) for o in b or []]
            if a != b:
                diffs.append(
                    f"objects {[n for n, _ in a]} there vs {[n for n, _ in b]} here"
                    + (
                        " (same names, different meshes)"
                        if [n for n, _ in a] == [n for n, _ in b]
                        else ""
                    )
                )
        elif key in _FLAGS:
            what, yes, no = _FLAGS[key]
            a, b = (manifest_volume(m) if key == "volume" else bool(m.get(key)) for m in both)
            if a != b:
                diffs.append(f"{what} {yes if a else no} there vs {yes if b else no} here")
        elif key == "sample_streams":
            a, b = manifest_streams(existing), manifest_streams(requested)
            if a != b:
                diffs.append(f"samples drawn with {a} streams there vs {b} here (--streams)")
        elif key == "probability_models":
            # recorded since the task probabilities: a dataset written before resumes as is
            from ..tasks.probability import recorded_digests

            if a is not None and recorded_digests(a) != recorded_digests(b):
                diffs.append(
                    "task probability models (p_beat, p_cut, p_pick) of another version "
                    "there; resume it with that version, or generate a new dataset"
                )
        elif key in ("depth", "robust") and a != b:  # tables of settings: in words
            diffs.append(f"{_plan_text(key, a)} there vs {_plan_text(key, b)} here")
        elif a != b:
            diffs.append(f"{key} {a!r} there vs {b!r} here")
    return diffs


def _plan_text(key: str, value: dict | None) -> str:
    """The ``depth`` or ``robust`` settings of a manifest in words, with their option."""
    if not value:
        return f"no {'depth images' if key == 'depth' else 'robust columns'} (--{key})"
    if key == "depth":
        return f"depth images of {value.get('size')} px at {value.get('fov_deg')}° (--depth)"
    return f"robust columns of {value.get('copies')} copies (--robust {value.get('copies')})"


def hand_spec_differences(there: dict | None, here: dict | None) -> list[str]:
    """The parts of two recorded hands that differ (``links``, ``dofs``, ...).

    A manifest written before hands were recorded whole (no ``hand_spec``) is compared by
    the hand's name alone, so it yields no difference here; the description is not compared
    (it does not change a single row).

    Parameters
    ----------
    there, here : dict or None
        ``hand_spec`` of two manifests (:func:`~affordgrasp.hands.hand_to_dict`).

    Returns
    -------
    list of str
        Sorted top-level keys whose values differ.
    """
    if there is None or here is None:
        return []
    there, here = json.loads(json.dumps(there)), json.loads(json.dumps(here))
    keys = sorted((set(there) | set(here)) - {"description"})
    return [k for k in keys if there.get(k) != here.get(k)]


def prepare_directory(directory: Path, manifest: dict) -> dict:
    """Create the dataset directory with its manifest, or check it matches for a resume.

    Parameters
    ----------
    directory : pathlib.Path
    manifest : dict
        The manifest of the run asked for.

    Returns
    -------
    dict
        The manifest in force (the existing one when resuming).

    Raises
    ------
    DatasetError
        When the directory holds a dataset of another plan (what differs is named; a
        different hand of the same name with ``parameter="hand"``), or is not empty and not
        a dataset.
    """
    check_writable(directory)
    path = directory / MANIFEST_NAME
    if path.exists():
        existing = read_manifest(directory)
        diffs = manifest_differences(existing, manifest)
        changed = hand_spec_differences(existing.get("hand_spec"), manifest.get("hand_spec"))
        if existing.get("hand") == manifest.get("hand") and changed:
            raise DatasetError(
                f"hand {manifest.get('hand')!r} is not the hand the dataset in "
                f"{str(directory)!r} was generated with (same name, different "
                + ", ".join(changed)
                + f"); resume it with that hand, {str(directory / MANIFEST_NAME)!r} "
                "records it and reads as a hand file, or write to a new output directory",
                parameter="hand",
            )
        if diffs:
            raise DatasetError(
                f"{str(directory)!r} holds a dataset made by a different command ("
                + "; ".join(diffs)
                + "). Resume it with its original options (see its _manifest.json) or "
                "write to a new --out directory"
            )
        return existing
    foreign = [
        p.name
        for p in directory.iterdir()
        if not p.name.startswith(".") and p.name not in (CARD_JSON_NAME, CARD_MD_NAME)
    ]
    if foreign:
        raise DatasetError(
            f"{str(directory)!r} is not empty and is not an affordgrasp dataset (it holds "
            f"{', '.join(sorted(foreign)[:3])}{', ...' if len(foreign) > 3 else ''}); give a "
            "new or empty --out directory"
        )
    write_json_atomic(path, manifest)
    return manifest
