"""The per-sample table: column types and conversion to Arrow (names: :mod:`.columns`).

Every simulated sample is one row, stable or not. Points and normals are in the object's
mesh frame, metres; the outward normal of the object is stored. +inf is stored as IEEE inf.
Rows without a use point (a use ray that leaves a hollow object through its opening without
a hit) have NaN use point/normal and NaN use metrics.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from ._version import __version__
from .columns import METRIC_COLUMNS, PROBABILITY_COLUMNS

_f64 = pa.float64()
_vec3 = pa.list_(_f64, 3)
_NUMPY_TYPES = {_f64: np.float64, pa.int64(): np.int64, pa.int32(): np.int32}

SAMPLE_FIELDS = [
    pa.field("object", pa.string()),
    pa.field("object_hash", pa.string()),
    pa.field("hand", pa.string()),
    pa.field("sample", pa.int64()),
    pa.field("seed", pa.int64()),
    pa.field("p0", pa.list_(_f64, 6)),
    pa.field("use_dir", pa.list_(_f64, 2)),
    pa.field("status", pa.string()),
    pa.field("hand_pose", pa.list_(_f64, 16)),
    pa.field("joints", pa.list_(_f64)),
    pa.field("contact_points", pa.list_(_vec3)),
    pa.field("contact_normals", pa.list_(_vec3)),
    pa.field("contact_mu", pa.list_(_f64)),
    pa.field("contact_link", pa.list_(pa.string())),
    pa.field("contact_parts", pa.list_(pa.string())),
    pa.field("n_contacts", pa.int32()),
    pa.field("use_point", _vec3),
    pa.field("use_normal", _vec3),
    pa.field("use_triangle", pa.int64()),
    pa.field("use_part", pa.string()),
    pa.field("wrist_point", _vec3),
    pa.field("wrist_axis", _vec3),
]
METRIC_FIELDS = [
    pa.field(name, pa.string() if name == "epsilon_reason" else _f64) for name in METRIC_COLUMNS
]
# p_beat, p_cut, p_pick: after the metric columns, or after the robust columns when present
PROBABILITY_FIELDS = [pa.field(name, _f64) for name in PROBABILITY_COLUMNS]
SCHEMA = pa.schema(SAMPLE_FIELDS + METRIC_FIELDS, metadata={"affordgrasp_version": __version__})
SIMULATION_SCHEMA = pa.schema(SAMPLE_FIELDS, metadata={"affordgrasp_version": __version__})

# ``generate --depth``: D(p0, O) per row, uint16 millimetres, little-endian, row-major,
# 0 = no return (affordgrasp.vision; docs/vision.md). Parquet's zstd compresses the column.
DEPTH_COLUMN = "depth_mm"
DEPTH_FIELD = pa.field(DEPTH_COLUMN, pa.binary())


def robust_fields(tasks) -> list[pa.Field]:
    """The float64 fields of robust evaluation (:func:`affordgrasp.columns.robust_column_names`).

    Parameters
    ----------
    tasks : sequence of str
        Tasks with ``robust_p_<task>`` and ``robust_<task>`` columns.

    Returns
    -------
    list of pyarrow.Field
    """
    from .columns import robust_column_names

    return [pa.field(name, _f64) for name in robust_column_names(tuple(tasks))]


def append_float_columns(table: pa.Table, fields: list[pa.Field], values: dict) -> pa.Table:
    """``table`` with float64 columns appended.

    Parameters
    ----------
    table : pyarrow.Table
        n rows.
    fields : list of pyarrow.Field
        float64 fields, in order.
    values : dict of str to (n,) float ndarray
        The values of each field by name.

    Returns
    -------
    pyarrow.Table
    """
    for f in fields:
        table = table.append_column(f, _numbers(values[f.name]))
    return table


def dataset_schema(metrics: bool = True, depth: bool = False, robust=None) -> pa.Schema:
    """The schema of a dataset's shards.

    Parameters
    ----------
    metrics : bool
        Include the metric columns (:data:`affordgrasp.columns.METRIC_COLUMNS`).
    depth : bool
        Include the depth image column (uint16 millimetres).
    robust : RobustSettings, optional
        Include the robust columns of these settings (with the metric columns, K > 0).

    Returns
    -------
    pyarrow.Schema
        Key, grasp state and (optionally) metric, robust, task probability and depth
        fields, in shard order.
    """
    schema = SCHEMA if metrics else SIMULATION_SCHEMA
    if metrics and robust is not None and robust.enabled:
        for f in robust_fields(robust.tasks):
            schema = schema.append(f)
    if metrics:
        for f in PROBABILITY_FIELDS:
            schema = schema.append(f)
    return schema.append(DEPTH_FIELD) if depth else schema


# The columns are built from numpy buffers, not with pa.array: pyarrow imports pandas on the
# first pa.array call (about half a second of a worker's start-up) and nothing here needs it.


def _numbers(values, typ: pa.DataType = _f64) -> pa.Array:
    """A primitive Arrow array (float64, int64 or int32) over a numpy array's buffer."""
    v = np.ascontiguousarray(values, dtype=_NUMPY_TYPES[typ]).reshape(-1)
    return pa.Array.from_buffers(typ, len(v), [None, pa.py_buffer(v)])


def column_numbers(column) -> np.ndarray:
    """A numeric Arrow column as a numpy array, read from its buffers.

    ``to_numpy`` would import pandas (a quarter of a second of a command's start-up); an
    integer column with nulls or a column of another type still goes through it.

    Parameters
    ----------
    column : pyarrow.ChunkedArray or pyarrow.Array
        float64, int64 or int32 values.

    Returns
    -------
    (n,) ndarray
        A copy, of the column's numpy dtype; NaN where a float64 column is null.
    """
    chunks = column.chunks if isinstance(column, pa.ChunkedArray) else [column]
    dtype = _NUMPY_TYPES.get(column.type)
    nulls = any(c.null_count for c in chunks)
    if dtype is None or (nulls and dtype is not np.float64):
        return column.to_numpy(zero_copy_only=False)
    parts = [_chunk_numbers(c, dtype) for c in chunks]
    return np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)


def _chunk_numbers(chunk: pa.Array, dtype) -> np.ndarray:
    """One primitive chunk's values (a copy); null float64 entries become NaN."""
    n = len(chunk)
    if chunk.null_count == n:
        return np.full(n, np.nan, dtype=dtype)
    validity, data = chunk.buffers()[:2]
    values = np.frombuffer(data, dtype=dtype)[chunk.offset : chunk.offset + n].copy()
    if chunk.null_count:
        bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
        values[~bits[chunk.offset : chunk.offset + n].astype(bool)] = np.nan
    return values


def _strings(values) -> pa.Array:
    """A string Arrow array of str values (None: null)."""
    items = list(values)
    encoded = [b"" if v is None else str(v).encode() for v in items]
    offsets = np.zeros(len(items) + 1, dtype=np.int32)
    np.cumsum([len(e) for e in encoded], out=offsets[1:])
    valid = np.array([v is not None for v in items], dtype=bool)
    bitmap = None if valid.all() else pa.py_buffer(np.packbits(valid, bitorder="little"))
    return pa.Array.from_buffers(
        pa.string(),
        len(items),
        [bitmap, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))],
        null_count=int(len(items) - valid.sum()),
    )


def _fixed(values: np.ndarray, width: int) -> pa.Array:
    return pa.FixedSizeListArray.from_arrays(_numbers(values), width)


def _ragged_vec3(chunks: list[np.ndarray]) -> pa.Array:
    counts = np.array([len(c) for c in chunks], dtype=np.int32)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    flat = np.concatenate(
        [np.zeros((0, 3))] + [np.asarray(c, dtype=np.float64).reshape(-1, 3) for c in chunks]
    )
    inner = pa.FixedSizeListArray.from_arrays(_numbers(flat), 3)
    return pa.ListArray.from_arrays(_numbers(offsets, pa.int32()), inner)


def _ragged(chunks: list[np.ndarray], typ: pa.DataType) -> pa.Array:
    counts = np.array([len(c) for c in chunks], dtype=np.int32)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    flat: list | np.ndarray = (
        np.concatenate([np.asarray(c).reshape(-1) for c in chunks]) if chunks else []
    )
    values = _strings(flat) if typ == pa.string() else _numbers(np.asarray(flat), typ)
    return pa.ListArray.from_arrays(_numbers(offsets, pa.int32()), values)


def _parts_of(obj, faces: np.ndarray) -> np.ndarray:
    """Part names of faces ("" without labels); objects without the method have none."""
    if getattr(obj, "face_parts", None) is None:
        return np.full(len(faces), "", dtype=object)
    return obj.parts_of_faces(faces)


def _contact_parts(obj, contacts) -> list[np.ndarray]:
    """Part under each contact of each grasp (one ray cast for the whole batch)."""
    counts = [len(c) for c in contacts]
    if getattr(obj, "face_parts", None) is None or not sum(counts):
        return [np.full(k, "", dtype=object) for k in counts]
    points = np.concatenate([c.points for c in contacts if len(c)])
    normals = np.concatenate([c.normals for c in contacts if len(c)])
    names = obj.parts_of_faces(obj.faces_at(points, normals))
    return np.split(names, np.cumsum(counts)[:-1])


def batch_to_table(
    obj, batch, *, hand: str, seed: int, sample_start: int = 0, metrics: dict | None = None
) -> pa.Table:
    """Rows of a simulated batch (and their metrics) as an Arrow table.

    Parameters
    ----------
    obj : GraspObject
        The object grasped (its name, hash and face parts label the rows).
    batch : SimulationBatch
        n simulated grasps: pregrasps p0 (n, 7), use directions (n, 2), hand poses, joint
        angles (rad), contacts (ragged, m) and use points (n, 3) m.
    hand : str
        The hand's name.
    seed : int
        The dataset seed recorded in each row.
    sample_start : int
        Sample index of the first row.
    metrics : dict of str to ndarray, optional
        Column name to an (n,) array (float64; ``epsilon_reason`` str) or None for a metric
        not computed (a null column: ``gws_volume`` unless asked for); None leaves the
        metric columns out.

    Returns
    -------
    pyarrow.Table
        n rows with the fields of :func:`dataset_schema`; positions in metres, directions
        unit vectors, joint angles in radians.
    """
    n = len(batch)
    contacts = batch.contacts
    cols = {
        "object": _strings([obj.name] * n),
        "object_hash": _strings([obj.mesh_hash] * n),
        "hand": _strings([hand] * n),
        "sample": _numbers(np.arange(sample_start, sample_start + n), pa.int64()),
        "seed": _numbers(np.full(n, seed), pa.int64()),
        "p0": _fixed(batch.p0, 6),
        "use_dir": _fixed(batch.use_dir, 2),
        "status": _strings(batch.status),
        "hand_pose": _fixed(batch.hand_pose.reshape(n, 16), 16),
        "joints": pa.ListArray.from_arrays(
            _numbers(np.arange(0, n + 1) * batch.joints.shape[1], pa.int32()),
            _numbers(batch.joints),
        ),
        "contact_points": _ragged_vec3([c.points for c in contacts]),
        "contact_normals": _ragged_vec3([c.normals for c in contacts]),
        "contact_mu": _ragged([c.mu for c in contacts], _f64),
        "contact_link": _ragged([c.link for c in contacts], pa.string()),
        "contact_parts": _ragged(_contact_parts(obj, contacts), pa.string()),
        "n_contacts": _numbers([len(c) for c in contacts], pa.int32()),
        "use_point": _fixed(batch.use_point, 3),
        "use_normal": _fixed(batch.use_normal, 3),
        "use_triangle": _numbers(batch.use_triangle, pa.int64()),
        "use_part": _strings(_parts_of(obj, batch.use_triangle)),
        "wrist_point": _fixed(batch.wrist_point, 3),
        "wrist_axis": _fixed(batch.wrist_axis, 3),
    }
    schema = SIMULATION_SCHEMA
    if metrics is not None:
        for name in METRIC_COLUMNS:
            values = metrics[name]
            if name == "epsilon_reason":
                cols[name] = _strings([str(v) for v in values])
            elif values is None:  # not computed (gws_volume unless asked for): null
                cols[name] = pa.nulls(n, _f64)
            else:
                cols[name] = _numbers(values)
        schema = SCHEMA
    return pa.Table.from_pydict(cols, schema=schema)


def metric_arrays(table: pa.Table) -> dict[str, np.ndarray]:
    """The metric columns of a table as numpy arrays (for tasks and summaries).

    Parameters
    ----------
    table : pyarrow.Table
        Rows with some or all of the metric columns.

    Returns
    -------
    dict of str to ndarray
        Column name to an (n,) array: float64 for the numeric metrics (NaN where null,
        e.g. ``gws_volume`` when it was not computed), object (str) for
        ``epsilon_reason``; columns absent from ``table`` are left out.
    """
    out = {}
    for name in METRIC_COLUMNS:
        if name in table.column_names:
            col = table.column(name)
            out[name] = (
                np.array(col.to_pylist(), dtype=object)
                if name == "epsilon_reason"
                else column_numbers(col).astype(np.float64)
            )
    return out
