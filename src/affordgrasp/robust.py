"""Robust quality (docs/robust.md): metrics and task scores under hand-pose, friction and
centre-of-mass uncertainty, by K perturbed re-simulations per grasp.

For each grasp the policy is run again K times from a perturbed pregrasp and the metric
vector Φ recomputed on each copy; the copies are summarised per grasp in ``robust_*``
columns. The k-th perturbation depends only on ``(seed, k)`` (common random numbers:
``numpy.random.Generator(PCG64(SeedSequence([seed, k])))``), so every grasp of every object
is judged under the same K draws, and a grasp's robust columns do not depend on the batch,
chunk, shard or worker it was evaluated in.

Perturbation k, all of it expressed in the grasp's hand frame (x, y, z = approach):

* **hand pose**: a rotation ``R_k = exp([ω_k]×)``, ``ω_k ~ N(0, σ_r² I)`` about the point
  where the unperturbed grasp stopped (the palm at first contact; for a grasp that missed,
  the point of the approach line nearest the object's centre), then a translation
  ``t_k ~ N(0, σ_t² I)``. The perturbed hand then backs off along its own approach
  direction by a bound on how far the move brought any point of the open hand forward,
  ``b = (2 sin(θ/2) (D + ρ) + max(t_z, 0)) / cos θ + clearance_m`` (θ the rotation angle,
  D the pivot's depth in front of the palm, ρ the open hand's radius about the palm), so
  that it starts outside the object as the unperturbed hand did, and approaches until
  contact and closes as usual. The component of ``t_k`` along the approach is absorbed by
  the approach.
* **friction**: every contact's μ becomes ``max(μ + σ_μ z_k, μ_min)``, ``z_k`` a standard
  normal truncated to ``[-2, 2]``: the hand/material μ shifted by one draw per copy (a
  robot's pads are all too slippery or all too sticky together).
* **centre of mass**: shifted by ``c_k ~ N(0, σ_c² I)``: the point the wrenches' torques
  are taken about, where gravity acts (E_h) and the axis distance of the inertia. The
  use point stays on the surface where the use ray met it; U_g and the edge angle are the
  unperturbed grasp's.

Defaults (Dex-Net-like anchors: gripper 5 mm, μ = 0.5 ± 0.1, 25 samples; Mahler et al.
2017): σ_t = 5 mm, σ_r = 3°, σ_μ = 0.1 (truncated at ±2σ, floor 0.05), σ_c = 2.5 mm,
K = 25, q = 0.2. With every σ = 0 each copy is the unperturbed grasp, bit for bit, and
every ``robust_*`` column equals its plain metric (``tests/test_robust.py``).

Columns per grasp (:func:`robust_column_names`):

==========================  ================================================================
``robust_fc``               fraction of copies in force closure (ε > 0)
``robust_epsilon``          mean ε over the copies
``robust_viable``           fraction of copies viable (the ``viable`` task, default mode)
``robust_hold_dirs``        mean number of the 6 load directions with finite E_h
``robust_hold``             graded hold (pick's robust ranking score, see below)
``robust_p_<task>``         fraction of copies with F_T > −∞
``robust_<task>``           the q-quantile of F_T over the copies, −∞ counted: the
                            ⌊q (K − 1)⌋-th smallest value (0-based), an order statistic
                            (no interpolation with −∞)
==========================  ================================================================

**Graded hold.** Plain pick, −ΣE_h, is −∞ for every grasp that cannot hold against one of
the six loads, and most grasps tie there. The physics replay measured that the number of
load directions with finite E_h, averaged over noisy copies, predicts holding better (AUC
0.83) than the noise-free count (0.78) or pick (0.73). So pick's robust score orders grasps
by ``robust_hold_dirs`` first and, among equal counts, by the lower mean effort over the
finite directions::

    robust_hold = robust_hold_dirs − (1 / K) · s / (s + 1 N),
    s = mean over copies of Σ E_h over that copy's finite directions (N)

The second term lies in [0, 1/K) and ``robust_hold_dirs`` moves in steps of 1/K, so the
order is exactly lexicographic (counts first, efforts second), and the value reads as "load
directions held, on average". :func:`ranking_column` names the column a task ranks by in
robust mode (``robust_hold`` for pick, ``robust_<task>`` otherwise); :func:`task_scores` is
the score every search, summary and plot ranks rows by, plain or robust.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np

from . import columns
from .columns import HOLD_EFFORT_COLUMNS, USE_METRICS
from .errors import InputError

__all__ = [
    "DEFAULT_TASKS",
    "Perturbations",
    "RobustSettings",
    "hold_dirs",
    "manifest_robust",
    "perturbations",
    "ranking_column",
    "ranking_values",
    "robust_column_names",
    "robust_columns",
    "robust_settings",
    "task_scores",
]

# Tasks summarised by default: the built-in formula tasks (``viable`` has its own
# ``robust_viable``; a task probability has a robust model of its own, which reads the
# copies' robust_fc, robust_epsilon, robust_hold and robust_hold_dirs).
DEFAULT_TASKS: tuple[str, ...] = ("beat-rules", "cut-rules", "cut-ug", "pick-paper")
HOLD_SCALE_N = 1.0  # N: the effort at which the graded hold's second term is half its range
FRICTION_TRUNCATION = 2.0  # σ: the friction draw is a normal truncated to ±2σ


@dataclass(frozen=True)
class RobustSettings:
    """Parameters of robust evaluation (recorded in a dataset's manifest and card).

    Attributes
    ----------
    copies : int
        K, perturbed re-simulations per grasp (0: plain evaluation only).
    translation_m : float
        σ_t, standard deviation of the hand translation per hand axis, m.
    rotation_rad : float
        σ_r, standard deviation of the hand rotation vector per hand axis, rad.
    friction_sd : float
        σ_μ, standard deviation of the friction shift (truncated at ±2σ).
    friction_min : float
        Lowest friction coefficient after the shift.
    com_m : float
        σ_c, standard deviation of the centre-of-mass shift per hand axis, m.
    quantile : float
        q of the conservative task score ``robust_<task>``, in [0, 1].
    seed : int
        Seed of the perturbations (the k-th depends on (seed, k) only).
    clearance_m : float
        Margin added to a perturbed hand's back-off, m (see the module docstring).
    tasks : tuple of str
        Tasks with ``robust_p_<task>`` and ``robust_<task>`` columns.
    mode : str
        Threshold mode of the tasks' scores (``robust_viable`` uses the ``viable`` task's
        default thresholds).
    """

    copies: int = 25
    translation_m: float = 0.005
    rotation_rad: float = math.radians(3.0)
    friction_sd: float = 0.1
    friction_min: float = 0.05
    com_m: float = 0.0025
    quantile: float = 0.2
    seed: int = 0
    clearance_m: float = 0.002
    tasks: tuple[str, ...] = field(default=DEFAULT_TASKS)
    mode: str = "default"

    def __post_init__(self) -> None:
        k = self.copies
        if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 0:
            raise InputError(f"robust copies K must be an integer >= 0, got {k!r}")
        for name in ("translation_m", "rotation_rad", "friction_sd", "com_m", "clearance_m"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise InputError(f"robust {name} must be a finite number >= 0, got {v!r}")
        if not (isinstance(self.friction_min, int | float) and self.friction_min > 0):
            raise InputError(f"robust friction_min must be > 0, got {self.friction_min!r}")
        if not (isinstance(self.quantile, int | float) and 0.0 <= self.quantile <= 1.0):
            raise InputError(f"robust quantile q must lie in [0, 1], got {self.quantile!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer):
            raise InputError(f"robust seed must be an integer >= 0, got {self.seed!r}")
        if self.seed < 0:
            raise InputError(f"robust seed must be an integer >= 0, got {self.seed!r}")
        object.__setattr__(self, "tasks", tuple(str(t) for t in self.tasks))

    def scores(self, task) -> bool:
        """Whether robust evaluation gives ``task`` a robust score: its copies summarise
        the task (``tasks``), or the task is a probability with a robust model of its own.

        Parameters
        ----------
        task : Task

        Returns
        -------
        bool
        """
        return task.probability or task.name in self.tasks

    @property
    def enabled(self) -> bool:
        """True when K > 0.

        Returns
        -------
        bool
        """
        return self.copies > 0

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values (for manifests and cards).

        Returns
        -------
        dict
            Every attribute; ``tasks`` as a list.
        """
        out = asdict(self)
        out["tasks"] = list(self.tasks)
        out["copies"] = int(self.copies)
        out["seed"] = int(self.seed)
        return out

    @classmethod
    def from_dict(cls, values: dict[str, Any] | None) -> RobustSettings:
        """Settings from :meth:`to_dict` output (None or K = 0: disabled).

        Parameters
        ----------
        values : dict or None

        Returns
        -------
        RobustSettings
        """
        if not values:
            return cls(copies=0)
        values = dict(values)
        unknown = sorted(set(values) - {f.name for f in fields(cls)})
        if unknown:
            raise InputError(
                f"robust settings {', '.join(unknown)} are unknown to this version of "
                "affordgrasp; read the dataset with the version that wrote it"
            )
        if "tasks" in values:
            values["tasks"] = tuple(values["tasks"])
        return cls(**values)


@dataclass(frozen=True)
class Perturbations:
    """K perturbations, in the hand frame of whatever grasp they are applied to.

    Attributes
    ----------
    rotation : (K, 3, 3) float64 ndarray
        Hand rotations (about the grasp's pivot).
    translation : (K, 3) float64 ndarray
        Hand translations, m.
    friction : (K,) float64 ndarray
        Friction shifts (added to every contact's μ).
    com : (K, 3) float64 ndarray
        Centre-of-mass shifts, m.
    """

    rotation: np.ndarray
    translation: np.ndarray
    friction: np.ndarray
    com: np.ndarray

    def __len__(self) -> int:
        return len(self.friction)


def manifest_robust(manifest: dict) -> RobustSettings | None:
    """The robust settings a dataset manifest records (None for a plain dataset).

    Parameters
    ----------
    manifest : dict
        A dataset's ``_manifest.json``.

    Returns
    -------
    RobustSettings or None
    """
    return robust_settings(RobustSettings.from_dict(manifest.get("robust")))


def robust_settings(value: RobustSettings | int | None) -> RobustSettings | None:
    """Settings from an option value: K (the default perturbations), settings, or None.

    Parameters
    ----------
    value : RobustSettings, int or None
        ``--robust K``; 0 or None: plain evaluation.

    Returns
    -------
    RobustSettings or None
        None when robust evaluation is off.
    """
    if value is None:
        return None
    if isinstance(value, RobustSettings):
        return value if value.enabled else None
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise InputError(f"--robust K must be an integer >= 0 (copies per grasp), got {value!r}")
    return RobustSettings(copies=int(value)) if value > 0 else None


def _rotation_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rodrigues' formula for one rotation vector (3,): (3, 3)."""
    theta = float(np.sqrt(rotvec @ rotvec))
    if theta == 0.0:
        return np.eye(3)
    k = rotvec / theta
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(theta) * kx + (1.0 - math.cos(theta)) * (kx @ kx)


def perturbations(settings: RobustSettings) -> Perturbations:
    """The K perturbations of ``settings``; the k-th depends on ``(settings.seed, k)`` only.

    Parameters
    ----------
    settings : RobustSettings

    Returns
    -------
    Perturbations
        Standard draws scaled by the settings' σ (zero σ: the identity, exactly).
    """
    from scipy.special import ndtr, ndtri

    k_count = int(settings.copies)
    rotation = np.empty((k_count, 3, 3))
    translation = np.empty((k_count, 3))
    friction = np.empty(k_count)
    com = np.empty((k_count, 3))
    lo = float(ndtr(-FRICTION_TRUNCATION))
    hi = float(ndtr(FRICTION_TRUNCATION))
    for k in range(k_count):
        rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(settings.seed), k])))
        normal = rng.standard_normal(9)
        u = float(rng.random())
        rotation[k] = _rotation_matrix(settings.rotation_rad * normal[0:3])
        translation[k] = settings.translation_m * normal[3:6]
        com[k] = settings.com_m * normal[6:9]
        friction[k] = settings.friction_sd * float(ndtri(lo + u * (hi - lo)))
    return Perturbations(rotation, translation, friction, com)


def _matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Batched a @ b summed term by term in a fixed order (BLAS rounds a batch and a single
    product differently; a grasp's result must not depend on its batch)."""
    out = a[..., :, 0, None] * b[..., None, 0, :]
    for j in range(1, a.shape[-1]):
        out = out + a[..., :, j, None] * b[..., None, j, :]
    return out


def _matvec(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Batched a @ v term by term: a (..., 3, 3), v (..., 3) → (..., 3)."""
    return (
        a[..., :, 0] * v[..., 0, None]
        + a[..., :, 1] * v[..., 1, None]
        + a[..., :, 2] * v[..., 2, None]
    )


def hold_dirs(metrics: Any) -> np.ndarray:
    """Number of the six load directions with finite E_h, per row.

    Parameters
    ----------
    metrics : mapping of str to (n,) array, or pyarrow.Table
        Rows with the six ``hold_effort_*`` columns (N).

    Returns
    -------
    (n,) float64 ndarray
        0 to 6 (NaN efforts count as infinite).
    """
    from .columns import hold_dirs_count
    from .tasks.metric_columns import MetricColumns

    cols = metrics if isinstance(metrics, MetricColumns) else MetricColumns(metrics)
    return hold_dirs_count({c: cols[c] for c in HOLD_EFFORT_COLUMNS})


def robust_column_names(tasks: Sequence[str] = DEFAULT_TASKS) -> tuple[str, ...]:
    """:func:`affordgrasp.columns.robust_column_names` (their one owner, so that the sample
    schema names them without importing this module), of the default tasks unless told.

    Parameters
    ----------
    tasks : sequence of str

    Returns
    -------
    tuple of str
    """
    return columns.robust_column_names(tasks)


def ranking_column(task: str) -> str:
    """The column a task's grasps are ranked by in robust mode.

    Parameters
    ----------
    task : str
        A task name.

    Returns
    -------
    str
        ``robust_hold`` for pick-paper (graded hold), else ``robust_<task>``.
    """
    return "robust_hold" if task == "pick-paper" else f"robust_{task}"


def _backoff(
    pivot_depth: np.ndarray, draws: Perturbations, hand_radius: float, clearance: float
) -> np.ndarray:
    """How far each copy backs off, (n, K), m: a bound on the forward move of any point of
    the open hand (within ``hand_radius`` of the palm) under copy k's rotation about the
    pivot and translation, plus ``clearance``."""
    cos_t = np.clip((np.trace(draws.rotation, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    half_chord = np.sqrt(np.maximum(0.0, (1.0 - cos_t) / 2.0))  # sin(θ / 2)
    lever = np.abs(pivot_depth)[:, None] + hand_radius
    forward = 2.0 * half_chord[None] * lever + np.maximum(draws.translation[None, :, 2], 0.0)
    return forward / np.maximum(cos_t, 0.1)[None] + clearance


def _perturbed_starts(
    starts: np.ndarray, pivot_depth: np.ndarray, draws: Perturbations, backoff: np.ndarray
) -> np.ndarray:
    """Start poses of every copy, (n K, 4, 4), grasp-major (row i K + k); ``backoff``
    (n, K), m."""
    n, k_count = len(starts), len(draws)
    # hand-frame transform of copy k about the pivot p = (0, 0, depth):
    # x' = R (x - p) + p + t - b R e_z
    rot = np.broadcast_to(draws.rotation[None], (n, k_count, 3, 3))
    p = np.zeros((n, k_count, 3))
    p[..., 2] = pivot_depth[:, None]
    rz = rot[..., :, 2]
    offset = p - _matvec(rot, p) + draws.translation[None] - backoff[..., None] * rz
    local = np.zeros((n, k_count, 4, 4))
    local[..., :3, :3] = rot
    local[..., :3, 3] = offset
    local[..., 3, 3] = 1.0
    out = _matmul(np.broadcast_to(starts[:, None], (n, k_count, 4, 4)), local)
    return np.ascontiguousarray(out.reshape(n * k_count, 4, 4))


def robust_columns(
    obj,
    batch,
    settings: RobustSettings,
    *,
    hand,
    phi: dict | None = None,
    soft: bool = False,
    timings: dict | None = None,
    frame=None,
) -> dict[str, np.ndarray]:
    """The ``robust_*`` columns (and ``hold_dirs``) of simulated grasps.

    Parameters
    ----------
    obj : GraspObject
        The object the batch was simulated on.
    batch : SimulationBatch
        n grasps from :func:`affordgrasp.grasp.policy.simulate` (their pregrasps, poses
        and use points).
    settings : RobustSettings
        K > 0 and the perturbation scales.
    hand : Hand
        The hand simulated.
    phi : dict of str to (n,) ndarray, optional
        The batch's plain Φ (``use_edge``, ``use_edge_angle`` and ``hold_dirs`` are taken
        from it); computed when None.
    soft : bool
        Soft-finger contacts.
    timings : dict, optional
        Filled with the seconds spent simulating the copies (``simulate``), on their
        metrics (``metrics``) and summarising them (``summary``).
    frame : GraspObject, optional
        The object whose geometry placed the batch's pregrasps (``simulate(..., frame=)``):
        the copies start from the same poses, perturbed; None: ``obj`` itself.

    Returns
    -------
    dict of str to (n,) float64 ndarray
        :func:`robust_column_names` of ``settings.tasks``.
    """
    import time

    from .metrics.phi_batch import phi_of_batch

    if not settings.enabled:
        raise InputError("robust evaluation needs K >= 1 copies (K = 0 is plain evaluation)")
    n, k_count = len(batch), settings.copies
    if phi is None:
        phi = phi_of_batch(obj, batch, soft=soft, volume=False)
    out: dict[str, np.ndarray] = {"hold_dirs": hold_dirs(phi)}
    if n == 0:
        for name in robust_column_names(settings.tasks)[1:]:
            out[name] = np.zeros(0)
        return out
    steps: dict[str, float] = {}
    phi_k = copy_metrics(
        obj, batch, settings, hand=hand, phi=phi, soft=soft, frame=frame, timings=steps
    )
    t2 = time.perf_counter()
    _summarise(out, phi_k, n, k_count, settings)
    if timings is not None:
        timings.update(steps, summary=time.perf_counter() - t2)
    return out


def copy_metrics(
    obj,
    batch,
    settings: RobustSettings,
    *,
    hand,
    phi: dict | None = None,
    soft: bool = False,
    frame=None,
    timings: dict | None = None,
) -> dict[str, np.ndarray]:
    """Φ of every perturbed copy of simulated grasps, before they are summarised.

    What :func:`robust_columns` summarises, for a caller that judges the copies its own way
    (``plan``'s robust check takes a quantile of their ε).

    Parameters
    ----------
    obj : GraspObject
        The object the batch was simulated on.
    batch : SimulationBatch
        n grasps from :func:`affordgrasp.grasp.policy.simulate`.
    settings : RobustSettings
        K > 0 and the perturbation scales (its tasks are not used).
    hand : Hand or str
        The hand simulated (a name is resolved here, with the hand's arrays, once).
    phi : dict of str to (n,) ndarray, optional
        The batch's plain Φ; computed when None.
    soft : bool
        Soft-finger contacts.
    frame : GraspObject, optional
        The object whose geometry placed the batch's pregrasps; None: ``obj`` itself.
    timings : dict, optional
        Filled with the seconds spent simulating the copies (``simulate``) and on their
        metrics (``metrics``).

    Returns
    -------
    dict of str to (n K,) ndarray
        The Φ columns of the copies, grasp-major (copy k of grasp i in row i K + k).

    Raises
    ------
    InputError
        For K = 0 or an empty batch.
    """
    import time

    from .grasp.policy import hand_arrays, object_geometry, pregrasp_starts, simulate_starts
    from .grasp.pregrasp import dot3
    from .hands import get_hand
    from .metrics.phi_batch import phi_of_batch

    if not settings.enabled:
        raise InputError("robust evaluation needs K >= 1 copies (K = 0 is plain evaluation)")
    arrays = hand_arrays(get_hand(hand))
    n, k_count = len(batch), settings.copies
    if n == 0:
        raise InputError("no grasps to copy: the batch is empty")
    if phi is None:
        phi = phi_of_batch(obj, batch, soft=soft, volume=False)
    geom = object_geometry(obj)
    draws = perturbations(settings)
    placing = None if frame is None else object_geometry(frame)
    starts, travel = pregrasp_starts(arrays, geom, batch.p0, placing)
    # pivot: where the unperturbed palm stopped, along the approach (centred frame)
    z = starts[:, :3, 2]
    start_origin = starts[:, :3, 3]
    stop = batch.hand_pose[:, :3, 3] - geom.origin
    depth = dot3(stop - start_origin, z)  # term by term: the same whatever the batch
    missed = np.asarray(batch.status == "missed")
    centre = 0.5 * (geom.hull_vertices.min(axis=0) + geom.hull_vertices.max(axis=0))
    depth = np.where(missed, dot3(centre[None] - start_origin, z), depth)
    if settings.translation_m == 0.0 and settings.rotation_rad == 0.0:
        backoff = np.zeros((n, k_count))  # every copy is the unperturbed grasp
    else:
        backoff = _backoff(depth, draws, arrays.open_radius, settings.clearance_m)
    t0 = time.perf_counter()
    copies = _perturbed_starts(starts, depth, draws, backoff)
    flat = simulate_starts(
        arrays,
        geom,
        copies,
        (travel[:, None] + backoff).reshape(n * k_count),
        np.repeat(batch.p0[:, 5], k_count),
    )
    # centre-of-mass shift of copy k in the object frame: the grasp's hand axes times c_k
    hand_rot = batch.hand_pose[:, :3, :3]
    shift = _matvec(hand_rot[:, None], draws.com[None]).reshape(n * k_count, 3)
    per_contact_copy = np.repeat(np.arange(n * k_count), np.diff(flat.offsets))
    mu = np.maximum(flat.mu + draws.friction[per_contact_copy % k_count], settings.friction_min)
    if settings.friction_sd == 0.0:
        mu = flat.mu
    t1 = time.perf_counter()
    phi_k = _copy_metrics(obj, batch, phi, flat, shift, mu, k_count, soft)
    if timings is not None:
        timings.update(simulate=t1 - t0, metrics=time.perf_counter() - t1)
    return phi_k


def _copy_metrics(obj, batch, phi, flat, shift, mu, k_count, soft) -> dict[str, np.ndarray]:
    """Φ of every copy (n K rows): the contact metrics in one compiled call, geometry moved
    by minus the centre-of-mass shift (the same as moving the centre of mass by it)."""
    from .metrics.contacts import ContactSet
    from .metrics.discharge import discharge
    from .metrics.effort import hold_effort, impact_effort
    from .metrics.epsilon import epsilon
    from .metrics.epsilon_hand import epsilon_hand
    from .metrics.hand_placement import (
        contact_reach,
        contact_thickness,
        contact_width,
        long_axis,
        use_clearance,
    )
    from .metrics.inertia import rotational_inertia
    from .metrics.phi import contact_metrics_batch
    from .metrics.striking import use_lever_ratio, use_swing_cosine
    from .metrics.transmission import use_force
    from .metrics.validation import units_n3

    mass = obj.mass
    # a writable copy: one kernel signature in process and in workers (see metrics.phi)
    center = np.array(mass.center_of_mass, dtype=np.float64).reshape(3)
    m = len(flat.poses)
    no_use = np.repeat(batch.use_triangle < 0, k_count)
    use_point = np.where(no_use[:, None], center, np.repeat(batch.use_point, k_count, axis=0))
    use_normal = np.where(
        no_use[:, None], [1.0, 0.0, 0.0], np.repeat(batch.use_normal, k_count, axis=0)
    )
    counts = np.diff(flat.offsets)
    points = np.ascontiguousarray(flat.points - np.repeat(shift, counts, axis=0))
    normals = np.ascontiguousarray(flat.normals)
    mu = np.ascontiguousarray(mu, dtype=np.float64)
    # normalised as compute_phi_batch does, so that an unperturbed copy matches it bit for bit
    use_normal = units_n3(use_normal, "use_normal")
    wrist_point = flat.poses[:, :3, 3]
    wrist_axis = units_n3(flat.poses[:, :3, 2], "wrist_axis")
    shifted_use = np.ascontiguousarray(use_point - shift)
    _code, eps, _vol, hold, impact, force, redo = contact_metrics_batch(
        points,
        normals,
        mu,
        np.ascontiguousarray(flat.offsets, dtype=np.int64),
        center,
        float(mass.r_max),
        shifted_use,
        np.ascontiguousarray(use_normal),
        wrist_axis,
        bool(soft),
        False,
    )
    for i in np.flatnonzero(redo):
        # rare: a compiled solver could not certify its answer (as in compute_phi_batch)
        a, b = flat.offsets[i], flat.offsets[i + 1]
        cs = ContactSet(points[a:b], normals[a:b], mu[a:b], np.full(b - a, "", dtype=object))
        eps[i] = epsilon(cs, center, mass.r_max, soft=soft, volume=False).epsilon
        hold[i] = hold_effort(cs, center, soft=soft, backend="highs")
        impact[i] = impact_effort(
            cs, center, shifted_use[i], use_normal[i], wrist_axis[i], soft=soft, backend="highs"
        )
        force[i] = use_force(cs, center, shifted_use[i], use_normal[i], soft=soft, backend="highs")
    cols: dict[str, np.ndarray] = {
        "epsilon": eps,
        "inertia": np.asarray(
            rotational_inertia(mass, wrist_point - shift, wrist_axis), dtype=float
        ).reshape(m),
        "impact_effort": impact,
        "discharge": np.asarray(
            discharge(use_point, use_normal, wrist_point, wrist_axis), dtype=float
        ).reshape(m),
        "use_force": force,
        "use_edge": np.repeat(phi["use_edge"], k_count),
        "use_edge_angle": np.repeat(phi["use_edge_angle"], k_count),
        # the use point is not perturbed: its local shape is the grasp's own
        "use_wedge_angle": np.repeat(phi["use_wedge_angle"], k_count),
        "use_wedge_angle_fine": np.repeat(phi["use_wedge_angle_fine"], k_count),
        "use_edge_span": np.repeat(phi["use_edge_span"], k_count),
        "use_edge_thickness": np.repeat(phi["use_edge_thickness"], k_count),
        "use_depth": np.repeat(phi["use_depth"], k_count),
        "use_relief": np.repeat(phi["use_relief"], k_count),
        "use_swing_cosine": np.asarray(
            use_swing_cosine(shifted_use, use_normal, wrist_point - shift, wrist_axis), dtype=float
        ).reshape(m),
        # distances between the copy's contacts, its wrist and U: the shift moves all alike
        "use_clearance": use_clearance(points, flat.offsets, shifted_use),
        "contact_reach": contact_reach(
            points, flat.offsets, shifted_use, center, long_axis(mass.inertia)
        ),
        "use_lever_ratio": np.asarray(
            use_lever_ratio(shifted_use, center, wrist_point - shift, wrist_axis), dtype=float
        ).reshape(m),
        # the chord under each contact, on the object where the copy touched it
        "contact_thickness": contact_thickness(obj.mesh_data, flat.points, normals, flat.offsets),
        "contact_width": contact_width(obj.mesh_data, flat.points, normals, flat.offsets),
        "epsilon_hand": epsilon_hand(
            points, normals, mu, flat.offsets, center, float(mass.r_max), eps, soft=bool(soft)
        ),
    }
    for j, name in enumerate(HOLD_EFFORT_COLUMNS):
        cols[name] = np.ascontiguousarray(hold[:, j])
    for name in USE_METRICS:
        cols[name] = np.where(no_use, np.nan, cols[name])
    return cols


def _summarise(
    out: dict[str, np.ndarray],
    phi_k: dict[str, np.ndarray],
    n: int,
    k_count: int,
    settings: RobustSettings,
) -> None:
    """Per-grasp summaries of the copies' metrics (n K rows, grasp-major) into ``out``."""
    from .tasks import get_task, is_viable
    from .tasks.metric_columns import MetricColumns

    cols = MetricColumns(phi_k)

    def per_grasp(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=np.float64).reshape(n, k_count)

    def mean(values: np.ndarray) -> np.ndarray:
        return per_grasp(values).sum(axis=1) / k_count

    eps = cols["epsilon"]
    out["robust_fc"] = mean(eps > 0)
    out["robust_epsilon"] = mean(eps)
    out["robust_viable"] = mean(is_viable(cols))
    hold = np.stack([cols[c] for c in HOLD_EFFORT_COLUMNS], axis=1)
    finite = np.isfinite(hold)
    dirs = finite.sum(axis=1).astype(np.float64)
    out["robust_hold_dirs"] = mean(dirs)
    s = mean(np.where(finite, hold, 0.0).sum(axis=1))
    out["robust_hold"] = out["robust_hold_dirs"] - (s / (s + HOLD_SCALE_N)) / k_count
    index = int(math.floor(settings.quantile * (k_count - 1)))
    for name in settings.tasks:
        with np.errstate(invalid="ignore"):
            f = np.asarray(get_task(name).evaluate(cols, settings.mode), dtype=np.float64)
        f = np.where(np.isnan(f), -np.inf, f)
        ok = f > -np.inf
        out[f"robust_p_{name}"] = mean(ok)
        out[f"robust_{name}"] = np.sort(per_grasp(f), axis=1)[:, index]


def ranking_values(columns: Any, task: str) -> np.ndarray:
    """The robust ranking score of ``task`` for every row (:func:`ranking_column`).

    Parameters
    ----------
    columns : pyarrow.Table or mapping of str to (n,) ndarray
        Rows evaluated with robust evaluation (``--robust K``).
    task : str
        The task name.

    Returns
    -------
    (n,) float64 ndarray
        −∞ where the robust score fails; NaN never ranks.

    Raises
    ------
    InputError
        When the rows have no robust column for the task.
    """
    name = ranking_column(task)
    names = columns.column_names if hasattr(columns, "column_names") else list(columns)
    if name not in names:
        present = sorted(n for n in names if n.startswith("robust_") and n.count("_") == 1)
        raise InputError(
            f"no column {name!r} for task {task!r} in robust mode: evaluate or generate with "
            f"--robust K (robust columns here: {', '.join(present) or 'none'}); tasks other "
            "than the built-in ones need RobustSettings(tasks=...)"
        )
    col = columns.column(name) if hasattr(columns, "column") else columns[name]
    if hasattr(col, "to_numpy"):
        col = col.to_numpy()
    return np.asarray(col, dtype=np.float64).reshape(-1)


def task_scores(
    task: Any,
    columns: Any,
    mode: str = "default",
    thresholds: Mapping[str, float] | None = None,
    *,
    robust: bool = False,
) -> np.ndarray:
    """The score rows are ranked by: F_T of ``task``, or with ``robust`` its robust score.

    Parameters
    ----------
    task : str or Task
        A registered name or a :class:`~affordgrasp.tasks.Task`.
    columns : pyarrow.Table, MetricColumns or mapping of str to (n,) ndarray
        The rows' columns (only those the task reads are converted).
    mode : str
        Threshold mode.
    thresholds : mapping of str to float, optional
        Threshold values that replace the mode's.
    robust : bool
        The robust ranking score (:func:`ranking_values`: rows evaluated with ``--robust K``);
        ``mode`` and ``thresholds`` are then those the rows were evaluated with.

    Returns
    -------
    (n,) float64 ndarray
        −∞ where a requirement fails; NaN never ranks.
    """
    from .tasks import get_task

    task = get_task(task) if isinstance(task, str) else task
    # a task probability reads the robust columns itself (its robust model) when present
    if robust and not task.probability:
        return ranking_values(columns, task.name)
    return np.asarray(task.evaluate(columns, mode, **dict(thresholds or {})), dtype=np.float64)
