"""The learned scorer: candidates scored from the fused cloud in each hand's frame
(``plan --model learned``).

The views decider (``plan``'s default) simulates every candidate on the surface fused from
the views; this scorer reads the same surface as a point cloud and predicts whether each
candidate's grasp is viable on the true object in a few milliseconds per 64 candidates,
instead of a simulation per candidate. Its inputs per candidate
(:func:`hand_frame_inputs`): the fused surface's points seen from the hand's start pose (the
frame in which the hand approaches along +z), cut to the volume the open hand sweeps and
shifted so that the nearest point in front of the palm lies at z = 0, counted in a grid of
:data:`GRID` cells over that volume; and a few numbers about them and the hand's spread.
The model is a forest of gradient-boosted trees on those counts (a
:class:`~affordgrasp.tasks.probability.TaskModel`, evaluated by the same compiled walk as the
task probabilities) with a calibration map; a PointNet on the points themselves was
measured against it and lost (docs/learning.md).

The shipped model and its card (``pretrained/scorer.json``) are rebuilt by
``tools/fit_scorer.py`` from the rows of ``tools/scorer_data.py``; docs/learning.md gives
the objects, the held-out numbers and the designs compared.
"""

from __future__ import annotations

import json
import os
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import InputError, TaskError
from ..tasks.probability import TaskModel

SCORER_FILE = "scorer.json"
INPUT = "hand-cloud"  # the card's input kind: refuses models of other inputs
CLOUD_POINTS = 2048  # fused-surface samples kept (a seeded subset, in a seeded order)
CLOUD_SEED = 0x5C0E
POINTS = 128  # points per candidate (the first of the cloud's order in its volume)
# The volume the open Barrett hand sweeps, in its start frame: the fingers reach about
# 0.1 m to each side of the approach line at full spread; the closing reaches about
# 0.15 m in front of the first surface met.
LATERAL_M = 0.12
DEPTH_M = 0.15
PALM_M = 0.04  # the first surface met: the nearest point within this of the approach line
POINT_SCALE = 5.0  # points in a network: m × 5 (× the model's own 2: decimetres)
GRID = (8, 8, 6)  # cells across x, y (the lateral box) and z (the depth) of the volume
FEATURES = ("spread", "first_dm", "share", "palm_share", "empty")
N_FEATURES = len(FEATURES)
COLUMNS = tuple(f"cell_{i}" for i in range(int(np.prod(GRID)))) + FEATURES


def fused_cloud(fused) -> np.ndarray:
    """The scorer's cloud of a fused surface: a seeded subset of its simulation samples.

    Parameters
    ----------
    fused : GraspObject
        The surface fused from the views.

    Returns
    -------
    (m, 3) float64 ndarray
        Points in the centred frame of the surface's simulation geometry (the frame of
        :func:`candidate_starts`), m ≤ :data:`CLOUD_POINTS`, in a seeded order.
    """
    from ..grasp.policy import object_geometry

    points = np.asarray(object_geometry(fused).samples.points, dtype=np.float64)
    if len(points) <= CLOUD_POINTS:
        return points[np.random.default_rng(CLOUD_SEED).permutation(len(points))]
    rng = np.random.default_rng(CLOUD_SEED)
    return points[rng.choice(len(points), CLOUD_POINTS, replace=False, shuffle=True)]


def candidate_starts(fused, p0: np.ndarray, hand="barrett") -> np.ndarray:
    """The hand's start poses of pregrasps placed on the fused surface's hull.

    Parameters
    ----------
    fused : GraspObject
    p0 : (n, 6) float ndarray
    hand : Hand or str

    Returns
    -------
    (n, 4, 4) float64 ndarray
        Hand → the centred frame of the surface's geometry, m (the frame of
        :func:`fused_cloud`).
    """
    from ..grasp.policy import hand_arrays, object_geometry, pregrasp_starts
    from ..hands import get_hand

    starts, _ = pregrasp_starts(
        hand_arrays(get_hand(hand)), object_geometry(fused), np.asarray(p0, dtype=np.float64)
    )
    return starts


def hand_frame_inputs(
    cloud: np.ndarray, starts: np.ndarray, spread: np.ndarray, *, with_points: bool = False
) -> tuple[np.ndarray, ...]:
    """The scorer's inputs of each candidate: its grid of counts and its features.

    Parameters
    ----------
    cloud : (m, 3) float ndarray
        :func:`fused_cloud`.
    starts : (n, 4, 4) float ndarray
        :func:`candidate_starts`.
    spread : (n,) float ndarray
        The pregrasp's spread parameter (p0's last entry), in [0, 1].
    with_points : bool
        Also return the points themselves (a network's input).

    Returns
    -------
    grid : (n, prod(GRID)) float32 ndarray
        The cloud in the hand's start frame, cut to |x|, |y| ≤ :data:`LATERAL_M` and to
        :data:`DEPTH_M` beyond the nearest point in front of the palm (z = 0 there), counted
        in :data:`GRID` cells over that volume (x slowest, z fastest), each count a share of
        the cloud's points.
    features : (n, N_FEATURES) float32 ndarray
        :data:`FEATURES`: the spread, the first surface's distance from the start pose
        (dm), the share of the cloud in the volume, the share of those within the palm's
        radius (:data:`PALM_M`) of the approach line, and whether the volume holds none.
    points : (n, POINTS, 3) float32 ndarray
        With ``with_points``: the first :data:`POINTS` of those points in the cloud's
        order (cycled when fewer), × :data:`POINT_SCALE`; zero when there are none.
    """
    cloud = np.asarray(cloud, dtype=np.float64)
    starts = np.asarray(starts, dtype=np.float64)
    n, m = len(starts), len(cloud)
    # local = Rᵀ (x - t), for every candidate and point: (n, m, 3)
    local = (cloud[None, :, :] - starts[:, None, :3, 3]) @ starts[:, :3, :3]
    lateral = (np.abs(local[..., 0]) <= LATERAL_M) & (np.abs(local[..., 1]) <= LATERAL_M)
    lateral &= local[..., 2] > 0.0  # in front of the hand
    radial = local[..., 0] ** 2 + local[..., 1] ** 2
    z = np.where(lateral, local[..., 2], np.inf)
    palm = lateral & (radial <= PALM_M**2)
    first = np.where(palm.any(axis=1), np.where(palm, z, np.inf).min(axis=1), z.min(axis=1))
    empty = ~np.isfinite(first)
    first = np.where(empty, 0.0, first)
    depth = local[..., 2] - first[:, None]
    inside = lateral & (depth <= DEPTH_M)
    count = inside.sum(axis=1)
    gx, gy, gz = GRID
    ix = np.clip(((local[..., 0] + LATERAL_M) * (gx / (2 * LATERAL_M))).astype(np.int64), 0, gx - 1)
    iy = np.clip(((local[..., 1] + LATERAL_M) * (gy / (2 * LATERAL_M))).astype(np.int64), 0, gy - 1)
    iz = np.clip((depth * (gz / DEPTH_M)).astype(np.int64), 0, gz - 1)
    cell = ((np.arange(n)[:, None] * gx + ix) * gy + iy) * gz + iz
    grid = np.bincount(cell[inside], minlength=n * gx * gy * gz).reshape(n, -1) / max(m, 1)
    palm_share = (inside & palm).sum(axis=1) / np.maximum(count, 1)
    features = np.stack(
        [
            np.asarray(spread, dtype=np.float64),
            first * 10.0,
            count / max(m, 1),
            palm_share,
            (count == 0).astype(np.float64),
        ],
        axis=1,
    )
    out = (grid.astype(np.float32), features.astype(np.float32))
    if not with_points:
        return out
    # the first POINTS of each row's points in the volume, in the cloud's (seeded) order,
    # cycled when there are fewer
    slot = np.where(inside, np.cumsum(inside, axis=1) - 1, -1)
    pick = np.zeros((n, POINTS), dtype=np.int64)
    rows, cols = np.nonzero(inside & (slot < POINTS))
    pick[rows, slot[rows, cols]] = cols
    cycled = np.arange(POINTS)[None, :] % np.maximum(np.minimum(count, POINTS), 1)[:, None]
    pick = np.take_along_axis(pick, cycled, axis=1)
    points = np.take_along_axis(local, pick[:, :, None], axis=1)
    points[..., 2] -= first[:, None]
    points[count == 0] = 0.0
    return (*out, (points * POINT_SCALE).astype(np.float32))


def scorer_path() -> Path:
    """The shipped scorer's file (its trees, calibration map and card).

    Returns
    -------
    pathlib.Path
    """
    return Path(str(resources.files("affordgrasp.learning") / "pretrained" / SCORER_FILE))


def load_scorer(path: str | os.PathLike | None = None) -> TaskModel:
    """A scorer (default: the shipped one).

    Parameters
    ----------
    path : path, optional
        A file written by ``tools/fit_scorer.py``.

    Returns
    -------
    TaskModel
        Its columns are :data:`COLUMNS`; its card says what it was fitted on.

    Raises
    ------
    InputError
        When the file is missing or not a scorer of the fused cloud.
    """
    path = scorer_path() if path is None else Path(path)
    try:
        model = TaskModel.from_dict(json.loads(Path(path).read_text()))
    except (OSError, ValueError, KeyError, TaskError) as exc:
        raise InputError(
            f"{str(path)!r} is not a scorer of the fused cloud ({exc}); tools/fit_scorer.py "
            "writes one"
        ) from None
    if model.card.get("input") != INPUT or tuple(model.columns) != COLUMNS:
        raise InputError(
            f"{str(path)!r} is not a scorer of this version's fused-cloud inputs "
            f"(input {model.card.get('input')!r}); tools/fit_scorer.py writes one"
        )
    return model


def score_candidates(model: TaskModel, fused, p0: np.ndarray, hand="barrett") -> np.ndarray:
    """The probability that each candidate's grasp is viable, from the fused cloud.

    Parameters
    ----------
    model : TaskModel
        :func:`load_scorer`'s.
    fused : GraspObject
        The surface fused from the views.
    p0 : (n, 6) float ndarray
        The candidates, placed on the surface's hull as ``plan`` places them.
    hand : Hand or str

    Returns
    -------
    (n,) float64 ndarray
        Calibrated probabilities in [0, 1].
    """
    p0 = np.asarray(p0, dtype=np.float64)
    grid, features = hand_frame_inputs(
        fused_cloud(fused), candidate_starts(fused, p0, hand), p0[:, 5]
    )
    x = np.concatenate([grid, features], axis=1).astype(np.float64)
    return np.interp(model.raw_score(x), model.knots_x, model.knots_y)
