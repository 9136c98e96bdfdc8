"""Learning data from a generated dataset: inputs (p0, d, depth), targets, splits.

A sample's depth image D(p0, O) is read from the dataset's ``depth_mm`` column when it was
generated with ``--depth``; otherwise it is rendered from the object the dataset resolves
(:meth:`affordgrasp.dataset.handle.Dataset.object`: a pure function of p0 and the mesh, whose
hash is checked), so a dataset without images is as good for learning, only slower to load.

Splits are by object instance (conventions: Vision; :mod:`affordgrasp.dataset.splits`): the
objects of the test (and validation) set never appear in training, and the families
(categories) overlap. A split by family holds out whole families instead.
"""

from __future__ import annotations

import logging
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..columns import HOLD_EFFORT_COLUMNS
from ..dataset.handle import Dataset
from ..errors import DatasetError, InputError
from .targets import (
    Target,
    make_target,
    target_column,
    target_rows,
    target_values,
    threshold_target,
)

log = logging.getLogger(__name__)

INPUT_COLUMNS = ("object", "sample", "p0", "use_dir")
METRIC_INPUTS = ("epsilon", *HOLD_EFFORT_COLUMNS, "impact_effort")


@dataclass
class Samples:
    """Rows chosen for learning: inputs and target, one entry per row.

    Attributes
    ----------
    object : (n,) object ndarray of str
        Object names.
    family : (n,) object ndarray of str
        Their families (categories).
    sample : (n,) int64 ndarray
        Sample numbers in the dataset.
    p0 : (n, 6) float64 ndarray
        Pregrasps, each entry in [0, 1].
    use_dir : (n, 2) float64 ndarray
        Use directions, in [0, 1].
    y : (n,) float64 ndarray
        The target in its own units (NaN when not known, e.g. when predicting).
    depth_mm : (n, size, size) uint16 ndarray or None
        Depth images, mm; None until loaded (:func:`load_depth`).
    meta : dict
        Where the rows come from: the opened ``dataset``.
    """

    object: np.ndarray
    family: np.ndarray
    sample: np.ndarray
    p0: np.ndarray
    use_dir: np.ndarray
    y: np.ndarray
    depth_mm: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.sample)

    def take(self, idx: np.ndarray) -> Samples:
        """The samples at some indices.

        Parameters
        ----------
        idx : (k,) int or (n,) bool ndarray

        Returns
        -------
        Samples
            Copies of the selected entries (``meta`` copied too).
        """
        idx = np.asarray(idx)
        return Samples(
            self.object[idx],
            self.family[idx],
            self.sample[idx],
            self.p0[idx],
            self.use_dir[idx],
            self.y[idx],
            None if self.depth_mm is None else self.depth_mm[idx],
            dict(self.meta),
        )


def read_rows(dataset: Dataset, target: str | Target, *, objects: Sequence[str] | None = None):
    """The rows of a dataset a target is defined on, with their inputs and target values.

    Parameters
    ----------
    dataset : Dataset
        A dataset generated with metrics (opened by the caller: :meth:`Dataset.open`).
    target : str or Target
        ``"viable"``, ``"hold_effort_sum"``, a metric column, ``"COLUMN>=LEVEL"`` or
        ``"task:NAME"``; a Target
        keeps its scale. For a generic column given by name, the scale is set from these rows
        (pass the training rows' Target to the other splits).
    objects : sequence of str, optional
        Read only these objects.

    Returns
    -------
    samples : Samples
        Rows where the target is defined, without depth images.
    target : Target

    Raises
    ------
    DatasetError
        When the dataset was generated with ``--no-metrics``.
    InputError
        When the target is not a column of the dataset.
    """
    directory = dataset.directory
    if not dataset.metrics:
        raise DatasetError(
            f"dataset {str(directory)!r} was generated with --no-metrics; learning needs "
            "the metric columns (generate it without --no-metrics)"
        )
    name = target if isinstance(target, str) else target.name
    column = target_column(name)
    extra = [] if column is None or column in METRIC_INPUTS else [column]
    columns = list(INPUT_COLUMNS) + list(METRIC_INPUTS) + extra
    if name.startswith("task:"):
        columns = None  # a task may read any metric column
    try:
        table = dataset.read(columns=columns, objects=objects)
    except Exception as exc:  # noqa: BLE001 - an unknown column name is bad input
        if "No match for FieldRef" in str(exc) or "not in schema" in str(exc):
            raise InputError(
                f"target {name!r} is not a column of {str(directory)!r}; use 'viable', "
                "'hold_effort_sum', a metric column (e.g. epsilon), COLUMN>=LEVEL (e.g. "
                "robust_viable>=0.5, on a dataset generated with --robust K) or task:NAME"
            ) from None
        raise
    if name.startswith("task:"):
        from ..tasks import get_task

        get_task(name[5:])  # an unknown task: a TaskError naming the known ones
    values = target_values(name, table)
    if isinstance(target, str):
        if name not in ("viable", "hold_effort_sum") and threshold_target(name) is None:
            provisional = Target(name, "regression", "finite")
            mask = target_rows(provisional, table)
            target = make_target(name, values[mask])
        else:
            target = make_target(name)
    mask = target_rows(target, table)
    families = dataset.families
    obj = np.asarray(table.column("object").to_pylist(), dtype=object)[mask]
    samples = Samples(
        object=obj,
        family=np.asarray([families.get(o, o) for o in obj], dtype=object),
        sample=table.column("sample").to_numpy()[mask].astype(np.int64),
        p0=_fixed(table, "p0", 6)[mask],
        use_dir=_fixed(table, "use_dir", 2)[mask],
        y=values[mask],
        meta={"dataset": dataset},
    )
    return samples, target


def _fixed(table, name: str, width: int) -> np.ndarray:
    col = table.column(name).combine_chunks()
    return np.asarray(col.flatten(), dtype=np.float64).reshape(-1, width)


def reads_depth(config: dict) -> bool:
    """Whether a model predicts from the rows' depth images (the pose-only networks and the
    fused views, which render their own, do not).

    Parameters
    ----------
    config : dict
        The model's config.

    Returns
    -------
    bool
    """
    return config["arch"] not in ("pose", "views")


def load_depth(samples: Samples, dataset: Dataset | None = None) -> np.ndarray:
    """The depth images of the samples, read from the dataset or rendered.

    Stored images are read in streamed batches keeping only the chosen rows, so memory is
    that of the result. The images are also stored in ``samples.depth_mm``.

    Parameters
    ----------
    samples : Samples
    dataset : Dataset, optional
        The dataset; default: the one the samples were read from (``samples.meta``).

    Returns
    -------
    (n, 128, 128) uint16 ndarray
        Depth, mm, 0 for no return.
    """
    dataset = samples.meta.get("dataset") if dataset is None else dataset
    if dataset is None:
        raise InputError("samples without a dataset: pass dataset=")
    if dataset.depth:
        images = _read_stored_depth(dataset, samples)
    else:
        images = render_samples_depth(samples, dataset)
    samples.depth_mm = images
    return images


def _read_stored_depth(dataset: Dataset, samples: Samples) -> np.ndarray:
    from ..vision.depth import decode_depth_column, depth_to_mm

    want: dict[tuple[str, int], int] = {
        (o, int(s)): i for i, (o, s) in enumerate(zip(samples.object, samples.sample, strict=True))
    }
    out = None
    found = 0
    objects = sorted(set(samples.object))
    for batch in dataset.batches(
        columns=["object", "sample", "depth_mm"], objects=objects, batch_size=4096
    ):
        names = batch.column(0).to_pylist()
        ids = batch.column(1).to_numpy()
        rows = [(j, want.get((n, int(s)))) for j, (n, s) in enumerate(zip(names, ids, strict=True))]
        rows = [(j, i) for j, i in rows if i is not None]
        if not rows:
            continue
        src = np.array([j for j, _ in rows])
        dst = np.array([i for _, i in rows])
        images = decode_depth_column(batch.column(2).take(src))
        if out is None:
            out = np.zeros((len(samples),) + images.shape[1:], dtype=np.uint16)
        out[dst] = depth_to_mm(images)
        found += len(rows)
    if found != len(samples):
        raise DatasetError(f"{len(samples) - found} chosen rows have no stored depth image")
    return out if out is not None else np.zeros((0, 128, 128), dtype=np.uint16)


def render_samples_depth(samples: Samples, dataset: Dataset) -> np.ndarray:
    """Render D(p0, O) of every sample from its object (as the dataset resolves it).

    Parameters
    ----------
    samples : Samples
    dataset : Dataset
        The dataset the samples come from (:meth:`Dataset.object` finds each object).

    Returns
    -------
    (n, 128, 128) uint16 ndarray
        Depth, mm, 0 for no return.

    Raises
    ------
    DatasetError
        When an object's mesh is gone or is not the one the dataset was made with.
    """
    from ..vision.depth import depth_to_mm, renderer_for

    out = np.zeros((len(samples), 128, 128), dtype=np.uint16)
    by_object: dict[str, list[int]] = defaultdict(list)
    for i, o in enumerate(samples.object):
        by_object[o].append(i)
    for name, rows in by_object.items():
        try:
            renderer = renderer_for(dataset.object(name))
        except DatasetError as exc:
            raise DatasetError(
                f"{exc}; or generate the dataset with --depth to keep its images"
            ) from None
        idx = np.asarray(rows)
        for lo in range(0, len(idx), 1024):
            part = idx[lo : lo + 1024]
            out[part] = depth_to_mm(renderer.render(samples.p0[part]))
    return out


def sensed_depth_mm(samples: Samples, sensor) -> np.ndarray:
    """The samples' depth images as a sensor model returns them.

    Parameters
    ----------
    samples : Samples
        With depth images.
    sensor : SensorModel
        The sensor (:mod:`affordgrasp.vision.sensor`).

    Returns
    -------
    (n, h, w) uint16 ndarray
        Depth, mm; image i's noise keyed by (CRC-32 of its object's name, its sample).
    """
    import zlib

    from ..vision.depth import depth_from_mm, depth_to_mm
    from ..vision.sensor import apply_sensor

    ids = np.array([zlib.crc32(str(o).encode()) for o in samples.object], dtype=np.int64)
    keys = np.c_[ids, samples.sample]
    return depth_to_mm(apply_sensor(depth_from_mm(samples.depth_mm), sensor, keys))


def balanced_indices(labels: np.ndarray, *, seed: int) -> np.ndarray:
    """All positives and as many negatives (fewer when there are not enough), drawn without
    replacement.

    Parameters
    ----------
    labels : (n,) array_like
        Classes; positive when > 0.5.
    seed : int
        Seeds the draw of the negatives.

    Returns
    -------
    (k,) int64 ndarray
        Sorted row indices.
    """
    labels = np.asarray(labels) > 0.5
    pos = np.flatnonzero(labels)
    neg = np.flatnonzero(~labels)
    rng = np.random.default_rng(seed)
    k = min(len(neg), len(pos))
    chosen = rng.choice(neg, k, replace=False) if k else np.zeros(0, dtype=np.int64)
    return np.sort(np.concatenate([pos, chosen]))
