"""A generated dataset opened once: its plan, card, hand, objects and rows (conventions: Datasets).

:class:`Dataset` is the one handle every consumer of a dataset takes (training, prediction,
physics replay, drawing, argmax), in the way ``pyarrow.dataset`` hands out one object per
stored thing: the manifest is read once, the hand rebuilt once, the shards checked once, and
the object that made each row is resolved by one rule (:meth:`Dataset.object`)::

    ds = Dataset.open("data/tools")
    ds.objects                  # ['knife:0', 'mug:0']
    knife = ds.object("knife")  # the GraspObject of its rows, mass properties included
    table = ds.read(columns=["object", "epsilon"])

The on-disk format is that of :mod:`affordgrasp.dataset.shards`; every dataset that format
ever wrote opens (keys added later have their documented defaults when absent).
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import re
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import DatasetError, InputError

if TYPE_CHECKING:
    import pyarrow as pa
    import pyarrow.dataset as pads

    from ..hands.model import Hand
    from ..objects.resolve import GraspObject
    from ..robust import RobustSettings
    from .splits import Split

log = logging.getLogger(__name__)

__all__ = [
    "REQUIRED_COLUMNS",
    "Dataset",
    "DatasetLike",
    "find_object",
    "manifest_hand",
    "match_objects",
    "object_filter",
    "object_specs",
    "open_dataset",
    "read_errors",
]

# Columns without which Parquet files are not affordgrasp samples (see docs/conventions.md).
REQUIRED_COLUMNS = ("object", "sample", "seed", "hand_pose", "joints")


class Dataset:
    """A dataset directory written by :func:`affordgrasp.generate`, opened once.

    Build it with :meth:`open`; the constructor only stores what it is given.

    Parameters
    ----------
    directory : path
        The dataset directory.
    manifest : dict
        Its parsed ``_manifest.json``.

    Attributes
    ----------
    directory : pathlib.Path
    manifest : dict
        The plan as written (read it through the properties below where one exists).
    """

    def __init__(self, directory: str | os.PathLike, manifest: dict) -> None:
        self.directory = Path(directory)
        self.manifest = manifest
        self._arrow: pads.Dataset | None = None
        self._objects: dict[tuple, GraspObject] = {}

    # ------------------------------------------------------------------ opening

    @classmethod
    def open(cls, source: DatasetLike) -> Dataset:
        """Open a dataset directory (a Dataset is returned as it is).

        Parameters
        ----------
        source : path or Dataset
            A directory written by ``affordgrasp generate``.

        Returns
        -------
        Dataset

        Raises
        ------
        DatasetError
            When the directory does not exist or holds no affordgrasp manifest (the message
            says which, and the command that makes one).
        """
        if isinstance(source, Dataset):
            return source
        from .manifest import read_manifest

        return cls(source, read_manifest(source))

    def __repr__(self) -> str:
        return f"Dataset({str(self.directory)!r}, objects={len(self.entries)})"

    def __str__(self) -> str:
        return str(self.directory)

    def __fspath__(self) -> str:
        # A Dataset goes wherever a dataset path went (os.fspath, Path(ds), open_dataset(ds)).
        return str(self.directory)

    # ------------------------------------------------------------------ the plan

    @property
    def seed(self) -> int:
        """The run's seed."""
        return int(self.manifest["seed"])

    @property
    def samples(self) -> int:
        """Samples per object."""
        return int(self.manifest["samples"])

    @property
    def shard_size(self) -> int:
        """Rows per shard."""
        return int(self.manifest["shard_size"])

    @property
    def metrics(self) -> bool:
        """Whether the rows have the metric columns (False: ``--no-metrics``)."""
        return bool(self.manifest.get("metrics", True))

    @property
    def soft(self) -> bool:
        """Whether contacts were soft-finger."""
        return bool(self.manifest.get("soft", False))

    @property
    def depth(self) -> bool:
        """Whether the rows store their depth images (column ``depth_mm``)."""
        return bool(self.manifest.get("depth"))

    @property
    def materials(self) -> bool:
        """Whether the families' mass properties follow their per-part materials.

        Absent from manifests written before it was recorded: unit density (False).
        """
        return bool(self.manifest.get("materials", False))

    @property
    def volume(self) -> bool:
        """Whether ``gws_volume`` holds computed volumes (see ``manifest.manifest_volume``)."""
        from .manifest import manifest_volume

        return manifest_volume(self.manifest)

    @property
    def robust(self) -> RobustSettings | None:
        """Robust evaluation's settings (None for a plain dataset)."""
        from ..robust import manifest_robust

        return manifest_robust(self.manifest)

    @property
    def command(self) -> list[str] | None:
        """The command line that made it, when recorded."""
        command = self.manifest.get("command")
        return list(command) if command else None

    @functools.cached_property
    def hand(self) -> Hand:
        """The hand the rows were simulated with, rebuilt from the manifest (custom ones too)."""
        return manifest_hand(self.manifest)

    @property
    def card(self) -> dict | None:
        """The dataset card (``_card.json``): what the run made and how; None when absent."""
        from .card import read_card

        return read_card(self.directory)

    # ------------------------------------------------------------------ objects

    @functools.cached_property
    def entries(self) -> dict[str, dict]:
        """Object name -> its manifest entry (``index``, ``category``, ``mesh_hash``...)."""
        return {o["name"]: o for o in self.manifest["objects"]}

    @property
    def objects(self) -> list[str]:
        """Names of the objects, in the order they were given."""
        return list(self.entries)

    @functools.cached_property
    def families(self) -> dict[str, str]:
        """Object name -> its family (category; for splits by object or family)."""
        return {name: e.get("category") or name.split(":")[0] for name, e in self.entries.items()}

    def split(
        self, kind: str = "object", *, seed: int = 0, test_families: Sequence[str] | None = None
    ) -> Split:
        """Its objects split for learning (:mod:`affordgrasp.dataset.splits`).

        Parameters
        ----------
        kind : {"object", "family"}
            Hold out object instances (families shared), or whole families.
        seed : int
            Seeds the draw.
        test_families : sequence of str, optional
            The held-out families of a split by family.

        Returns
        -------
        Split

        Raises
        ------
        InputError
            For another kind, a split by family without ``test_families``, or too few
            objects to split.
        """
        from .splits import split_by_family, split_by_object

        names = self.objects
        families = [self.families[n] for n in names]
        if kind == "object":
            return split_by_object(names, families, seed=seed)
        if kind == "family":
            if not test_families:
                raise InputError(
                    "a split by family needs test_families, the families to hold out "
                    "(e.g. ['axe', 'mug'])"
                )
            return split_by_family(names, families, test_families, seed=seed)
        raise InputError(f"unknown split {kind!r}; choose object or family")

    def select(self, wanted: Sequence[str] | None) -> list[str] | None:
        """Object names of the dataset matching ``wanted`` (``knife`` matches ``knife:0``).

        Parameters
        ----------
        wanted : sequence of str or None
            Names, families or mesh paths; None or empty selects every object.

        Returns
        -------
        list of str or None
            None when every object is selected.

        Raises
        ------
        DatasetError
            For a name that matches nothing (the message names the objects available).
        """
        if not wanted:
            return None
        return match_objects(self.objects, wanted, self.directory)

    def scale_options(self) -> dict:
        """``size_m`` / ``units`` the mesh files were loaded with, read from the recorded command.

        Returns
        -------
        dict
            ``size_m`` (float or None) and ``units`` (str or None): None where the command
            gave none, or was not recorded.
        """
        command = self.command or []
        found: dict = {"size_m": None, "units": None}
        for flag, key, kind in (("--size-m", "size_m", float), ("--units", "units", str)):
            for i, word in enumerate(command):
                value = None
                if word == flag and i + 1 < len(command):
                    value = command[i + 1]
                elif word.startswith(flag + "="):
                    value = word.split("=", 1)[1]
                if value is not None:
                    try:
                        found[key] = kind(value)
                    except ValueError:
                        pass  # not this run's option (a mesh file of that name...)
        return found

    def object(
        self,
        name: str,
        *,
        meshes: Sequence[str] = (),
        size_m: float | None = None,
        units: str | None = None,
        changed_family: str = "error",
    ) -> GraspObject:
        """The object whose rows these are (:func:`find_object` with the manifest's facts).

        A family is rebuilt from its name (scan-like variants included) with the dataset's
        mass properties (per-part materials when it was made with ``--materials``); a mesh
        file is looked for where :func:`object_specs` says, at the scale it was made at
        (default: the recorded command's ``--size-m`` / ``--units``). Resolved once per
        handle.

        Parameters
        ----------
        name : str
            An object of the dataset (``knife`` matches ``knife:0``).
        meshes : sequence of str
            Mesh files to try first (``--mesh``).
        size_m : float, optional
            Rescale a mesh file to this longest extent, m.
        units : str, optional
            Length unit of a mesh file.
        changed_family : {"error", "accept"}
            See :func:`find_object`.

        Returns
        -------
        GraspObject

        Raises
        ------
        DatasetError
            When the object is not in the dataset, or no candidate loads with its mesh.
        """
        name = self._name(name)
        scale = self.scale_options()
        size_m = scale["size_m"] if size_m is None else size_m
        units = scale["units"] if units is None else units
        key = (name, tuple(meshes), size_m, units, changed_family)
        if key not in self._objects:
            entry = self._entry(name)
            self._objects[key] = find_object(
                name,
                source=entry.get("source", "family"),
                mesh_hash=entry.get("mesh_hash"),
                meshes=meshes,
                directory=self.directory,
                materials=self.materials,
                size_m=size_m,
                units=units,
                changed_family=changed_family,
            )
        return self._objects[key]

    def mesh_hash(self, name: str) -> str | None:
        """The hash of the mesh an object's rows were simulated on.

        Parameters
        ----------
        name : str
            An object of the dataset.

        Returns
        -------
        str or None
            None when the manifest does not record it.
        """
        return self._entry(self._name(name)).get("mesh_hash") or None

    def _name(self, name: str) -> str:
        return match_objects(self.objects, [name], self.directory)[0]

    def _entry(self, name: str) -> dict:
        entry = self.entries.get(name)
        if entry is None:
            raise DatasetError(
                f"object {name!r} is not in dataset {str(self.directory)!r}; it holds: "
                f"{', '.join(self.objects)}"
            )
        return entry

    # ------------------------------------------------------------------ rows

    def shards(self) -> list[Path]:
        """The shard files on disk, in plan order.

        Returns
        -------
        list of pathlib.Path
        """
        from .shards import shard_paths

        return shard_paths(self.directory)

    def arrow(self) -> pads.Dataset:
        """The shards as one ``pyarrow.dataset.Dataset``, checked once against the plan.

        Every reader of the rows comes through here: the shards on disk must be the plan's
        (none missing, none extra) and each the file written for it
        (:func:`~affordgrasp.dataset.shards.check_shards`).

        Returns
        -------
        pyarrow.dataset.Dataset

        Raises
        ------
        DatasetError
            When there are no shards yet, or one is missing, extra, damaged or another
            dataset's (the message names it and what to do).
        """
        if self._arrow is None:
            self._arrow = open_dataset(self.directory, manifest=self.manifest)
        return self._arrow

    def read(
        self, *, columns: Sequence[str] | None = None, objects: Sequence[str] | None = None
    ) -> pa.Table:
        """Rows as one Arrow table (for small datasets; :meth:`batches` streams).

        Parameters
        ----------
        columns : sequence of str, optional
            Columns to read; all when None.
        objects : sequence of str, optional
            Objects to read (as for :meth:`select`); all when None.

        Returns
        -------
        pyarrow.Table
            One row per sample, in plan order.
        """
        arrow = self.arrow()
        with read_errors(self.directory):
            return arrow.to_table(
                columns=list(columns) if columns is not None else None,
                filter=object_filter(self.select(objects)),
            )

    def batches(
        self,
        *,
        columns: Sequence[str] | None = None,
        objects: Sequence[str] | None = None,
        batch_size: int = 65536,
    ) -> Iterator[pa.RecordBatch]:
        """Stream rows in batches (memory-bounded).

        Parameters
        ----------
        columns : sequence of str, optional
        objects : sequence of str, optional
        batch_size : int
            Rows per batch at most.

        Yields
        ------
        pyarrow.RecordBatch
        """
        with read_errors(self.directory):
            yield from scan_files(
                self.arrow(),
                columns=columns,
                filter=object_filter(self.select(objects)),
                batch_size=batch_size,
            )

    def count_rows(self, objects: Sequence[str] | None = None) -> int:
        """The number of rows of some objects.

        Parameters
        ----------
        objects : sequence of str, optional
            As for :meth:`select`; all when None.

        Returns
        -------
        int
        """
        from .shards import plan_shards

        self.arrow()  # the shards on disk are the plan's (checked), so the plan counts them
        chosen = self.select(objects)
        names = [o["name"] for o in self.manifest["objects"]]
        planned = {s.name: s for s in plan_shards(len(names), self.samples, self.shard_size)}
        return sum(
            planned[p.name].rows
            for p in self.shards()
            if p.name in planned
            and (chosen is None or names[planned[p.name].object_index] in chosen)
        )


DatasetLike = str | os.PathLike | Dataset
"""What a consumer of a dataset accepts: a directory, or an opened :class:`Dataset`."""


def object_specs(
    name: str,
    source: str | None,
    *,
    meshes: Sequence[str] = (),
    directory: str | os.PathLike | None = None,
) -> list[str]:
    """Where the mesh of a dataset's object may be found, in the order to try them.

    Parameters
    ----------
    name : str
        The object's name in the rows (``knife:3``, ``knife:3~scan``, ``part.stl``,
        ``part.stl~scan:2``).
    source : str or None
        Its manifest's ``source``: ``"family"``, the mesh file's path, or None when not
        known (loose Parquet files without a manifest).
    meshes : sequence of str
        Mesh files offered by the caller (``--mesh``): those of the object's file name
        come first.
    directory : path, optional
        The dataset directory: files of the object's file name under it are tried last.

    Returns
    -------
    list of str
        Object specs (:func:`~affordgrasp.objects.load_object` grammar), without repeats.
        A family: its name. A mesh file: the offered files, the recorded path, files under
        the directory, then (source unknown) the name itself; a scan-like variant's specs
        carry its ``~scan:K`` suffix, so that the file is degraded again.
    """
    from ..objects.scan import SCAN_SUFFIX, split_scan_spec

    if source == "family":
        return [name]
    try:  # a file's own name may hold "~scan" (knife~scan.stl): a file, not a variant
        scan = None if name == Path(str(source)).name else split_scan_spec(name)
    except InputError:
        scan = None
    suffix = ""
    if scan is not None:
        suffix = SCAN_SUFFIX + ("" if scan[1] is None else f":{scan[1]}")
    file_name = scan[0] if scan is not None else name
    specs = [
        m + suffix
        for m in meshes
        if os.path.basename(m) == file_name or Path(m).stem == Path(file_name).stem
    ]
    if source is not None:
        specs.append(str(source) + suffix)
    if directory is not None and Path(directory).is_dir():
        specs.extend(
            str(p) + suffix for p in sorted(Path(directory).rglob(file_name)) if p.is_file()
        )
    if source is None:
        specs.append(name)
    return list(dict.fromkeys(specs))


def find_object(
    name: str,
    *,
    source: str | None = "family",
    mesh_hash: str | None = None,
    meshes: Sequence[str] = (),
    directory: str | os.PathLike | None = None,
    materials: bool = False,
    size_m: float | None = None,
    units: str | None = None,
    changed_family: str = "error",
) -> GraspObject:
    """The object a dataset's rows were simulated on: the one rule every consumer uses.

    The candidates of :func:`object_specs` are loaded in turn; the first whose mesh is the
    rows' (``mesh_hash``) is returned. Families get the dataset's mass properties
    (``materials``), mesh files its scale (``size_m`` / ``units``) and their region
    densities file when they have one.

    Parameters
    ----------
    name : str
        The object's name in the rows.
    source : str or None
        The manifest's ``source`` (``"family"`` or a path); None when not known.
    mesh_hash : str, optional
        The rows' ``object_hash``; None accepts the first candidate that loads.
    meshes : sequence of str
        Mesh files offered by the caller (``--mesh``).
    directory : path, optional
        The dataset directory (searched for mesh files of the object's name).
    materials : bool
        Per-part materials for a family (the dataset's ``--materials``).
    size_m, units : optional
        The scale mesh files were loaded at.
    changed_family : {"error", "accept"}
        When a family now builds another mesh than the rows' (another affordgrasp
        version): refuse, or return it anyway (for drawing; compare ``obj.mesh_hash`` with
        ``mesh_hash`` to warn).

    Returns
    -------
    GraspObject

    Raises
    ------
    DatasetError
        When no candidate loads with the rows' mesh (the message says what to pass).
    """
    from ..objects import load_object
    from ..objects.resolve import is_family_spec

    if changed_family not in ("error", "accept"):
        raise InputError(f"changed_family must be 'error' or 'accept', got {changed_family!r}")
    last_error: Exception | None = None
    mismatch: Exception | None = None  # a file of the right name with another mesh says most
    for spec in object_specs(name, source, meshes=meshes, directory=directory):
        family = source == "family" or is_family_spec(spec)
        options = {"materials": materials} if family else {"size_m": size_m, "units": units}
        try:
            obj = load_object(spec, **options)
        except InputError as exc:
            last_error = exc
            continue
        if mesh_hash and obj.mesh_hash != mesh_hash:
            if family and changed_family == "accept":
                return obj
            mismatch = mismatch or DatasetError(
                f"{spec!r} resolves to another mesh than the rows' "
                f"(hash {obj.mesh_hash[:12]} here vs {mesh_hash[:12]} there)"
            )
            continue
        return obj
    fix = (
        "use the affordgrasp version that generated it"
        if source == "family"
        else "restore the mesh file or pass it with --mesh PATH (with the --size-m / --units "
        "it was generated with)"
    )
    raise DatasetError(
        f"cannot find the mesh that dataset object {name!r} was generated on "
        f"({mismatch or last_error}); {fix}"
    )


# ------------------------------------------------------------------ the shards


def open_dataset(
    directory: str | os.PathLike,
    *,
    loose: bool = False,
    verify: bool = True,
    manifest: dict | None = None,
) -> pads.Dataset:
    """The shards of a dataset directory as one ``pyarrow.dataset.Dataset`` (plan order).

    Parameters
    ----------
    directory : path
        A directory written by ``affordgrasp generate``.
    loose : bool
        Also accept a directory without a (valid) manifest: every ``*.parquet`` file under it
        (not in hidden folders) whose columns are those of sample rows, e.g. files written
        by ``affordgrasp evaluate --out``. Their footers are checked, not checksums.
    verify : bool
        Check every shard against the checksum recorded when it was written and against
        the plan's object, seed, samples and columns (reads each file once per process; see
        docs/dataset.md for the cost). Missing and extra shards are refused either way
        (:func:`~affordgrasp.dataset.shards.check_shards`).
    manifest : dict, optional
        The directory's manifest when already read (:class:`~affordgrasp.dataset.handle.Dataset`
        passes its own); read here otherwise.

    Returns
    -------
    pyarrow.dataset.Dataset

    Raises
    ------
    DatasetError
        When the directory is missing, not a dataset, empty or unreadable, or a shard is
        missing, extra, damaged or another dataset's (the message names it and what to do).
    """
    import pyarrow.dataset as pads

    from ..schema import dataset_schema
    from .manifest import read_manifest
    from .shards import check_shards, shard_paths

    try:
        manifest = read_manifest(directory) if manifest is None else manifest
    except DatasetError:
        if not loose:
            raise
        return _open_loose_files(Path(directory))
    paths = shard_paths(directory)
    if not paths:
        raise DatasetError(
            f"dataset {str(directory)!r} has no shards yet; run the command in its "
            "_manifest.json to generate them"
        )
    from ..robust import manifest_robust

    schema = dataset_schema(
        manifest.get("metrics", True), bool(manifest.get("depth")), manifest_robust(manifest)
    )
    check_shards(Path(directory), paths, manifest, schema, content=verify)
    _warn_missing_metrics(directory, paths, schema)
    return pads.dataset([str(p) for p in paths], format="parquet", schema=schema)


def _warn_missing_metrics(directory, paths: list, schema) -> None:
    """Say so when the shards lack metric columns this version writes (an earlier version
    wrote them): they read as null, and a task that needs one scores every row −∞."""
    import pyarrow.parquet as pq

    from ..columns import METRIC_COLUMNS

    wanted = [c for c in METRIC_COLUMNS if c in schema.names]
    if not wanted:
        return
    missing: set[str] = set()
    for path in {paths[0], paths[-1]}:  # a dataset's shards come from one version, or two
        with read_errors(path):
            have = set(pq.read_schema(path).names)
        missing |= {c for c in wanted if c not in have}
    if missing:
        log.warning(
            "dataset %s was written by an earlier version of affordgrasp: its rows have no "
            "%s (read as null), so a task that needs them scores those rows as unusable; "
            "generate it again to compute them",
            directory,
            ", ".join(c for c in METRIC_COLUMNS if c in missing),
        )


@contextlib.contextmanager
def read_errors(where: str | os.PathLike):
    """Turn an Arrow or OS error while reading into a DatasetError naming the damaged file.

    A context manager.

    Parameters
    ----------
    where : path
        Named in the message when the error does not name a file.

    Yields
    ------
    None
        The block runs inside; an Arrow or OS error it raises leaves as a DatasetError.
    """
    import pyarrow as pa

    try:
        yield
    except (pa.ArrowException, OSError) as exc:
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        match = re.search(r"[\w./\\:-]*\.parquet", text)
        culprit = match.group(0) if match else str(where)
        raise DatasetError(
            f"cannot read {culprit!r}: {text}; the file is damaged or not Parquet: delete it "
            "(and, for a dataset, run its generate command again to rewrite it)"
        ) from exc


def _open_loose_files(directory: Path) -> pads.Dataset:
    import pyarrow as pa
    import pyarrow.dataset as pads
    import pyarrow.parquet as pq

    if not directory.is_dir():
        raise DatasetError(f"{str(directory)!r} is not a directory")
    files = sorted(
        str(p)
        for p in directory.rglob("*.parquet")
        if p.is_file() and not any(part.startswith(".") for part in p.relative_to(directory).parts)
    )
    if not files:
        raise DatasetError(
            f"no Parquet files under {str(directory)!r}; give a dataset directory "
            "written by 'affordgrasp generate', or an object (family, family:seed or mesh path)"
        )
    for file in files:
        # Footers only: a truncated or foreign file is named before any scan.
        with read_errors(file):
            try:
                pq.read_metadata(file)
            except (pa.ArrowException, OSError) as exc:
                raise pa.ArrowInvalid(f"{file}: {exc}") from exc
    with read_errors(directory):
        dataset = pads.dataset(files, format="parquet")
    missing = set(REQUIRED_COLUMNS) - set(dataset.schema.names)
    if missing:
        raise DatasetError(
            f"the Parquet files under {str(directory)!r} lack the columns {sorted(missing)}; "
            "they do not look like an affordgrasp dataset (see docs/conventions.md)"
        )
    return dataset


def manifest_hand(manifest: dict) -> Hand:
    """The hand a dataset was generated with, rebuilt from its manifest.

    Parameters
    ----------
    manifest : dict
        A dataset's ``_manifest.json`` (:func:`~affordgrasp.dataset.manifest.read_manifest`).

    Returns
    -------
    Hand
        The hand recorded whole under ``hand_spec``; for a manifest written before hands
        were recorded whole (``hand`` holds only a name), the registered hand of that name.
    """
    from ..hands import get_hand, hand_from_dict

    spec = manifest.get("hand_spec")
    if isinstance(spec, dict):
        return hand_from_dict(spec)
    return get_hand(str(manifest.get("hand") or "barrett"))


def match_objects(
    names: Sequence[str], wanted: Sequence[str], where: str | os.PathLike
) -> list[str]:
    """The names among a dataset's objects that ``wanted`` means (``knife`` is ``knife:0``).

    Parameters
    ----------
    names : sequence of str
        The dataset's objects.
    wanted : sequence of str
        Names, families or mesh paths.
    where : path
        The dataset, named in the error.

    Returns
    -------
    list of str

    Raises
    ------
    DatasetError
        For a name that matches nothing (the message names the objects available).
    """
    names = list(names)
    chosen = []
    for w in wanted:
        w = w.strip()
        if w in names:
            chosen.append(w)
        elif f"{w}:0" in names:
            chosen.append(f"{w}:0")
        elif os.path.basename(w) in names:
            chosen.append(os.path.basename(w))
        else:
            raise DatasetError(
                f"object {w!r} is not in dataset {str(where)!r}; it holds: {', '.join(names)}"
            )
    return chosen


def object_filter(objects: Sequence[str] | None) -> pads.Expression | None:
    """An Arrow filter keeping the rows of some objects.

    Parameters
    ----------
    objects : sequence of str or None
        Object names; None or empty keeps every row.

    Returns
    -------
    pyarrow.dataset.Expression or None
    """
    if not objects:
        return None
    import pyarrow.dataset as pads

    return pads.field("object").isin(list(objects))


# Files read ahead of the one being consumed (threads: Parquet reads release the GIL)
READ_AHEAD = 4


def scan_files(
    dataset: pads.Dataset,
    columns: Sequence[str] | None = None,
    filter: pads.Expression | None = None,
    batch_size: int = 65536,
) -> Iterator[pa.RecordBatch]:
    """A dataset's rows in batches, read one file at a time (memory independent of rows).

    A pyarrow scanner over the whole dataset keeps the Parquet footer of every file it has
    read until it is done (10⁷ rows in 2,500 shards: about 500 MB more than 10⁵ rows); here
    each file is opened, read and released in turn, the next :data:`READ_AHEAD` read ahead
    in threads.
    Files lacking some of the dataset's columns read them as null, as the dataset does.

    Parameters
    ----------
    dataset : pyarrow.dataset.Dataset
        A file dataset (``Dataset.arrow()``, or loose Parquet files).
    columns : sequence of str, optional
        Columns to read; all when None.
    filter : pyarrow.dataset.Expression, optional
        Rows to keep (row-group statistics skip files without any).
    batch_size : int
        Rows per batch at most.

    Yields
    ------
    pyarrow.RecordBatch
        In the dataset's file order.
    """
    from concurrent.futures import ThreadPoolExecutor

    import pyarrow.dataset as pads

    files = list(getattr(dataset, "files", None) or [])
    if not files:  # not a file dataset: its own scanner
        yield from dataset.scanner(
            columns=None if columns is None else list(columns), filter=filter, batch_size=batch_size
        ).to_batches()
        return
    schema = dataset.schema
    wanted = None if columns is None else list(columns)
    fmt = pads.ParquetFileFormat()

    def read(path: str) -> pa.Table:
        part = pads.dataset(path, schema=schema, format=fmt)
        return part.to_table(columns=wanted, filter=filter)

    from collections import deque

    with ThreadPoolExecutor(max_workers=READ_AHEAD) as pool:
        ahead: deque = deque()
        rest = iter(files)
        for path in rest:
            ahead.append(pool.submit(read, path))
            if len(ahead) == READ_AHEAD:
                break
        while ahead:
            table = ahead.popleft().result()
            nxt = next(rest, None)
            if nxt is not None:
                ahead.append(pool.submit(read, nxt))
            yield from table.to_batches(max_chunksize=batch_size)
