"""The physical trials of one grasp: squeeze, hold (±x, ±y, ±z), impact and press.

Every trial starts from the same squeezed state (a snapshot), so the six hold directions,
the impact and the press are independent of each other and of their order. MuJoCo is
deterministic: the same scene, grasp and settings give the same outcome bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np

from ..hands.kinematics import joint_poses, kinematic_tree
from . import deps
from .scene import FAR, Scene, rotation_quat, table_friction
from .settings import G

__all__ = [
    "HOLD_DIRECTIONS",
    "GraspOutcome",
    "StartState",
    "back_off",
    "penetration_depth",
    "set_grasp",
    "settled_contacts",
    "validate_grasp",
]

HOLD_DIRECTIONS = ("px", "nx", "py", "ny", "pz", "nz")
_AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
_TOOL_GAP = 2e-4  # m: the press plate starts this far from the use point
_HAND_CONTYPE = 2  # the hand geoms' contype bit (scene._HAND_BITS)
_PUSHES = 8  # pushes of the object off the rigid geoms (each resolves the deepest contact)
_ROUNDS = 3  # push, then open the fingers; again with the fingers that could not open
_BISECTIONS = 14  # opening a finger to first contact: 2^-14 of its opening range
_AT_LIMIT = 1e-6  # rad or m: a coupled joint this close to its closing limit is there
_SETTLED_CONTACT_M = 1e-3  # contacts closer than this after the squeeze count as touching


@dataclass(frozen=True)
class GraspOutcome:
    """What the physics engine saw for one grasp (SI units; NaN: the trial did not apply).

    Attributes
    ----------
    contacts : int
        Hand-object contacts after the squeeze.
    squeeze_shift_m : float
        How far the squeeze moved the object's centre of mass, m.
    settled : bool
        After the squeeze the object touches the hand and is at rest.
    hold_shift_m, hold_angle_rad : (6,) float64 ndarray
        Largest displacement of the centre of mass, m, and largest rotation of the object,
        rad, during the hold test, per load direction (``HOLD_DIRECTIONS``: +x, -x, +y, -y,
        +z, -z of the object frame).
    hold_ok : bool
        The object settled in the hand and every direction held (shift and angle under the
        limits of :class:`~affordgrasp.physics.settings.PhysicsSettings`).
    hold_directions_ok : int
        How many of the six directions held.
    impact_angle_rad : float
        Largest rotation of the object during the impact pulse, rad.
    impact_ok : bool or None
        The rotation stayed under the limit; None without a use point.
    press_force_n : float
        Largest plate force on the use point before it slipped, N (0: not settled).
    press_held : bool or None
        The grasp never slipped up to the largest press force; None without a use point.
    steps : int
        Simulation steps spent.
    initial_penetration_m, start_penetration_m, backoff_shift_m, backoff_open, distal_at_limit
        The start (:class:`StartState`).
    ejected : bool
        No hand-object contact was left after the squeeze.
    settled_points, settled_normals : (k, 3) float64 ndarray
        The hand-object contacts after the squeeze, object frame, m, outward normals.
    settled_mu : (k,) float64 ndarray
        Their friction coefficients.
    settled_epsilon : float
        ε of those contacts (:func:`affordgrasp.metrics.epsilon.epsilon`; 0 without any).
    settled_hold_effort : (6,) float64 ndarray
        E_h of those contacts, N per N, +inf where infeasible.
    """

    contacts: int  # hand-object contacts after the squeeze
    squeeze_shift_m: float  # how far the squeeze moved the object
    settled: bool  # after the squeeze the object touches the hand and is at rest
    hold_shift_m: np.ndarray
    hold_angle_rad: np.ndarray
    hold_ok: bool
    hold_directions_ok: int  # how many of the six directions held
    impact_angle_rad: float
    impact_ok: bool | None  # None: no use point
    press_force_n: float  # largest plate force before the use point slipped (0: not settled)
    press_held: bool | None  # the grasp never slipped up to the largest press force
    steps: int  # simulation steps spent
    initial_penetration_m: float = 0.0
    start_penetration_m: float = 0.0
    backoff_shift_m: float = 0.0
    backoff_open: float = 0.0
    distal_at_limit: int = 0
    ejected: bool = False
    settled_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    settled_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    settled_mu: np.ndarray = field(default_factory=lambda: np.zeros(0))
    settled_epsilon: float = 0.0
    settled_hold_effort: np.ndarray = field(default_factory=lambda: np.full(6, np.inf))

    def to_row(self) -> dict:
        """The outcome as one flat row of the physics table.

        Returns
        -------
        dict
            The scalar attributes, and ``hold_shift_{d}`` / ``hold_angle_{d}`` for each ``d`` of
            ``HOLD_DIRECTIONS`` in place of the two arrays; ``settled_contacts`` (count),
            ``settled_hold_effort_sum`` (Σ E_h, +inf if a direction is infeasible) and
            ``settled_hold_dirs`` (directions with a finite E_h) in place of
            ``settled_hold_effort``; the settled contact arrays flattened to lists.
        """
        row = asdict(self)
        for k, d in enumerate(HOLD_DIRECTIONS):
            row[f"hold_shift_{d}"] = float(self.hold_shift_m[k])
            row[f"hold_angle_{d}"] = float(self.hold_angle_rad[k])
        del row["hold_shift_m"], row["hold_angle_rad"], row["settled_hold_effort"]
        effort = self.settled_hold_effort
        finite = np.isfinite(effort)
        row["settled_contacts"] = len(self.settled_mu)
        row["settled_hold_effort_sum"] = float(effort.sum()) if finite.all() else math.inf
        row["settled_hold_dirs"] = int(finite.sum())
        for name in ("settled_points", "settled_normals", "settled_mu"):
            row[name] = [float(v) for v in np.ravel(row[name])]
        return row


def _frame_quat(z_axis: np.ndarray) -> np.ndarray:
    """A quaternion whose frame has ``z_axis`` as its z."""
    z = z_axis / np.linalg.norm(z_axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return rotation_quat(np.stack([x, y, z], axis=1))


def set_grasp(scene: Scene, hand_pose: np.ndarray, joints: np.ndarray) -> StartState:
    """Put the scene in the grasp's state: hand joints, object pose, servos at rest.

    The links MuJoCo models without a joint (the Barrett spread) are placed with the hand's
    :func:`~affordgrasp.hands.kinematics.joint_poses`; the closing joints get their values.
    With ``settings.backoff`` the fingers and the object are then backed off to first
    contact (:func:`back_off`); the finger servos hold the result, and the couplings start
    from it (a follower that starts at its closing limit is held there).

    Parameters
    ----------
    scene : Scene
        The compiled model (:func:`~affordgrasp.physics.scene.build_scene`).
    hand_pose : (4, 4) float ndarray
        Hand → object transform, m (the dataset's ``hand_pose``).
    joints : (n_dofs,) float ndarray
        DOF values in the hand's order, rad or m (the dataset's ``joints``).

    Returns
    -------
    StartState
        The initial penetration as placed and after the back-off, and what the back-off
        and the couplings did.
    """
    mj = deps.mujoco()
    m, d = scene.model, scene.data
    hand_pose = np.asarray(hand_pose, dtype=np.float64).reshape(4, 4)
    joints = np.asarray(joints, dtype=np.float64)
    mj.mj_resetData(m, d)
    m.jnt_range[:] = scene.joint_range
    local = joint_poses(np.ascontiguousarray(joints), kinematic_tree(scene.hand))
    for li, body in scene.rigid_links.items():
        m.body_pos[body] = local[li][:3, 3]
        m.body_quat[body] = rotation_quat(local[li][:3, :3])
    for li, jid in scene.closing_joints.items():
        j = scene.hand.links[li].joint
        d.qpos[m.jnt_qposadr[jid]] = j.ratio * joints[scene.hand.dof_index(j.dof)]
    obj_in_hand = np.linalg.inv(hand_pose)
    a = scene.object_qpos
    d.qpos[a : a + 7] = [*obj_in_hand[:3, 3], *rotation_quat(obj_in_hand[:3, :3])]
    _park_tools(scene)
    initial = penetration_depth(scene)
    shift = opened = 0.0
    if scene.settings.backoff and initial > scene.settings.backoff_depth_m:
        shift, opened = back_off(scene)
    start = penetration_depth(scene)
    at_limit = 0
    for f in scene.fingers:
        q0 = d.qpos[m.jnt_qposadr[f.joint]]
        d.ctrl[f.servo] = q0
        for c in f.couplings:
            a0 = d.qpos[m.jnt_qposadr[c.joint]] - c.gain * q0
            m.eq_data[c.equality, :5] = [a0, c.gain, 0.0, 0.0, 0.0]
            at_limit += _hold_follower_at_limit(m, d, c.equality, c.joint, f.closing * c.gain)
    mj.mj_forward(m, d)
    return StartState(initial, start, shift, opened, at_limit)


@dataclass(frozen=True)
class StartState:
    """How a grasp started in the engine.

    Attributes
    ----------
    initial_penetration_m : float
        Deepest hand-object penetration as placed from the dataset row, m (0: none).
    start_penetration_m : float
        The same after the back-off, when the squeeze starts, m.
    backoff_shift_m : float
        How far the back-off pushed the object off the palm, m.
    backoff_open : float
        The largest opening of a finger's driven joint by the back-off, rad or m.
    distal_at_limit : int
        Coupled joints that started at their closing limit (held there by the squeeze).
    """

    initial_penetration_m: float
    start_penetration_m: float
    backoff_shift_m: float
    backoff_open: float
    distal_at_limit: int


def _contact_arrays(scene: Scene):
    """(geom pairs (n, 2), dist (n,), normal (n, 3), pos (n, 3)) of the hand-object contacts."""
    mj = deps.mujoco()
    m, d = scene.model, scene.data
    mj.mj_kinematics(m, d)
    mj.mj_collision(m, d)
    n = d.ncon
    if n == 0:
        z = np.zeros((0, 3))
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0), z, z
    con = d.contact
    geom = np.asarray(con.geom[:n]).copy()
    body = m.geom_bodyid[geom]
    obj = body == scene.object_body
    hand = (m.geom_contype[geom] & _HAND_CONTYPE) != 0
    keep = (obj[:, 0] & hand[:, 1]) | (obj[:, 1] & hand[:, 0])
    return (
        geom[keep],
        np.asarray(con.dist[:n])[keep].copy(),
        np.asarray(con.frame[:n, :3])[keep].copy(),
        np.asarray(con.pos[:n])[keep].copy(),
    )


def penetration_depth(scene: Scene, geoms: np.ndarray | None = None) -> float:
    """Deepest penetration of the hand in the object's collision geometry, at the current state.

    Parameters
    ----------
    scene : Scene
    geoms : (k,) int ndarray, optional
        Only contacts of these hand geoms; all hand geoms when None.

    Returns
    -------
    float
        m, >= 0 (0: nothing penetrates).
    """
    pairs, dist, _n, _p = _contact_arrays(scene)
    if geoms is not None:
        sel = np.isin(pairs, geoms).any(axis=1)
        dist = dist[sel]
    return float(max(0.0, -dist.min())) if len(dist) else 0.0


def back_off(scene: Scene) -> tuple[float, float]:
    """Back the grasp off to first contact in the engine's collision geometry.

    The object's convex parts stick out of the mesh that the grasp simulator touched, so a
    grasp at that mesh can start inside a part. First the object is pushed off the palm
    along the deepest palm contact's normal (a few passes), then each finger's driven joint
    is opened by bisection until that finger is at most ``settings.backoff_depth_m`` deep.
    A finger that is still deeper at its opening limit is treated like the palm in the next
    round (the object is pushed off it); at most three rounds. The couplings' offsets are
    set afterwards, from the result.

    Parameters
    ----------
    scene : Scene
        In the placed state of :func:`set_grasp`.

    Returns
    -------
    shift_m : float
        How far the object moved, m.
    opened : float
        The largest opening of a driven joint, rad or m.
    """
    d, s = scene.data, scene.settings
    tol = s.backoff_depth_m
    a = scene.object_qpos
    start = d.qpos[a : a + 3].copy()
    opened = np.zeros(len(scene.fingers))
    rigid = scene.palm_geoms
    for _ in range(_ROUNDS):
        _push_object_off(scene, rigid, tol)
        at_limit = []
        for k, f in enumerate(scene.fingers):
            if penetration_depth(scene, f.geoms) > tol:
                opened[k] += _open_finger(scene, f.joint, f.closing, f.geoms, tol)
            if penetration_depth(scene, f.geoms) > tol:
                at_limit.append(f.geoms)  # open as far as it goes: push the object instead
        if not at_limit and penetration_depth(scene) <= tol:
            break
        rigid = np.concatenate([scene.palm_geoms, *at_limit])
    return float(np.linalg.norm(d.qpos[a : a + 3] - start)), float(opened.max(initial=0.0))


def _push_object_off(scene: Scene, geoms: np.ndarray, tol: float) -> None:
    """Move the object along the deepest contact normal of ``geoms`` until at most ``tol``."""
    m, d = scene.model, scene.data
    a = scene.object_qpos
    for _ in range(_PUSHES):
        pairs, dist, normal, _p = _contact_arrays(scene)
        sel = np.isin(pairs, geoms).any(axis=1)
        if not sel.any() or -dist[sel].min() <= tol:
            return
        k = np.flatnonzero(sel)[np.argmin(dist[sel])]
        # The frame's normal points from geom 0 to geom 1: away from the hand if it is geom 0.
        sign = 1.0 if m.geom_bodyid[pairs[k, 1]] == scene.object_body else -1.0
        d.qpos[a : a + 3] += sign * normal[k] * (-dist[k] - 0.5 * tol)


def _open_finger(scene: Scene, jid: int, direction: float, geoms, tol: float) -> float:
    """Open a finger's driven joint by bisection until it is at most ``tol`` deep; how far."""
    m, d = scene.model, scene.data
    adr = m.jnt_qposadr[jid]
    q0 = float(d.qpos[adr])
    limit = m.jnt_range[jid, 0] if direction > 0 else m.jnt_range[jid, 1]
    lo, hi = 0.0, abs(q0 - limit)  # opening amount: lo penetrates, hi is as open as it gets
    d.qpos[adr] = q0 - direction * hi
    if penetration_depth(scene, geoms) > tol:
        return hi
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        d.qpos[adr] = q0 - direction * mid
        if penetration_depth(scene, geoms) <= tol:
            hi = mid
        else:
            lo = mid
    d.qpos[adr] = q0 - direction * hi
    return hi


def _hold_follower_at_limit(m, d, eq: int, fj: int, closing: float) -> int:
    """Hold a coupled joint at its closing limit once it reaches it; 1 if it did now.

    The coupling ``follower = a0 + a1 · driver`` would otherwise fight the limit and stop
    the driver too (a finger whose distal is at its limit could not squeeze): at the limit
    the follower is held where it is (a1 = 0) and the driver closes alone.
    """
    if m.eq_data[eq, 1] == 0.0:
        return 0
    q = d.qpos[m.jnt_qposadr[fj]]
    lo, hi = m.jnt_range[fj]
    if (closing > 0 and q >= hi - _AT_LIMIT) or (closing < 0 and q <= lo + _AT_LIMIT):
        m.eq_data[eq, :2] = [q, 0.0]
        return 1
    return 0


def _park_tools(scene: Scene) -> None:
    m, d = scene.model, scene.data
    d.mocap_pos[m.body("anvil").mocapid[0]] = [FAR, FAR, FAR]
    m.body("plate").pos = [-FAR, -FAR, -FAR]
    slide = d.joint("plate_slide")
    slide.qpos, slide.qvel = 0.0, 0.0
    d.actuator("plate_push").ctrl = 0.0


class _Snapshot:
    """The integration state of MjData, to start every trial from the squeezed grasp."""

    FIELDS = ("qpos", "qvel", "act", "ctrl", "qacc_warmstart", "mocap_pos", "mocap_quat")

    def __init__(self, d):
        self.time = d.time
        self.arrays = {f: getattr(d, f).copy() for f in self.FIELDS}

    def restore(self, scene: Scene) -> None:
        mj = deps.mujoco()
        d = scene.data
        d.time = self.time
        for f, v in self.arrays.items():
            getattr(d, f)[:] = v
        d.xfrc_applied[:] = 0.0
        _park_tools(scene)
        mj.mj_forward(scene.model, d)


def _angle_between(q0: np.ndarray, q1: np.ndarray) -> float:
    dot = abs(float(np.dot(q0, q1)))
    return 2.0 * math.acos(min(1.0, dot))


def _squeeze(scene: Scene) -> int:
    mj = deps.mujoco()
    m, d, s = scene.model, scene.data, scene.settings
    start = {f.servo: d.ctrl[f.servo] for f in scene.fingers}
    n_ramp = max(1, round(s.squeeze_time / s.timestep))
    n_settle = round(s.settle_time / s.timestep)
    drivers = [(f.joint, f.closing, m.jnt_qposadr[f.joint]) for f in scene.fingers]
    couplings = [(c.equality, c.joint, f.closing) for f in scene.fingers for c in f.couplings]
    for step in range(n_ramp + n_settle):
        frac = min(1.0, (step + 1) / n_ramp)
        for f in scene.fingers:
            kind = m.jnt_type[f.joint]
            over = s.overshoot_rad if kind == mj.mjtJoint.mjJNT_HINGE else s.overshoot_m
            d.ctrl[f.servo] = start[f.servo] + f.closing * over * frac
        mj.mj_step(m, d)
        if not s.backdrivable:
            _ratchet(m, d, drivers)
        for eq, fj, direction in couplings:
            _hold_follower_at_limit(m, d, eq, fj, direction * m.eq_data[eq, 1])
    return n_ramp + n_settle


def _ratchet(m, d, drivers) -> None:
    """A non-backdrivable drive: the opening-side limit follows the finger as it closes."""
    for jid, direction, adr in drivers:
        q = d.qpos[adr]
        if direction > 0:
            m.jnt_range[jid, 0] = min(max(m.jnt_range[jid, 0], q), m.jnt_range[jid, 1])
        else:
            m.jnt_range[jid, 1] = max(min(m.jnt_range[jid, 1], q), m.jnt_range[jid, 0])


def _hand_contacts(scene: Scene) -> int:
    m, d = scene.model, scene.data
    count = 0
    for i in range(d.ncon):
        c = d.contact[i]
        b1, b2 = m.geom_bodyid[c.geom[0]], m.geom_bodyid[c.geom[1]]
        if (b1 == scene.object_body) != (b2 == scene.object_body) and c.dist < 1e-3:
            count += 1
    return count


def _hold(
    scene: Scene, snapshot: _Snapshot, axis: np.ndarray, reference=None
) -> tuple[float, float, int]:
    """Largest (shift, angle) under a load along ``axis`` (object frame); steps used.

    Displacements are measured from ``reference`` = (centre of mass (3,), quaternion (4,))
    in the world, or from the squeezed state when None.
    """
    mj = deps.mujoco()
    m, d, s = scene.model, scene.data, scene.settings
    snapshot.restore(scene)
    body = scene.object_body
    com0 = d.xipos[body].copy() if reference is None else reference[0]
    quat0 = d.xquat[body].copy() if reference is None else reference[1]
    load = s.load_factor * scene.object_mass * G * (d.xmat[body].reshape(3, 3) @ axis)
    n_ramp = max(1, round(s.hold_ramp / s.timestep))
    n = round(s.hold_time / s.timestep)
    shift = angle = 0.0
    for step in range(n):
        d.xfrc_applied[body, :3] = load * min(1.0, (step + 1) / n_ramp)
        mj.mj_step(m, d)
        shift = max(shift, float(np.linalg.norm(d.xipos[body] - com0)))
        angle = max(angle, _angle_between(quat0, d.xquat[body]))
        if shift > 2 * s.max_shift_m or angle > 2 * s.max_angle_rad:
            return shift, angle, step + 1  # failed for good: save the time
    return shift, angle, n


def _use_in_world(scene: Scene, use_point: np.ndarray, use_normal: np.ndarray):
    d = scene.data
    r = d.xmat[scene.object_body].reshape(3, 3)
    p = d.xpos[scene.object_body]
    return r @ use_point + p, r @ use_normal


def place_anvil(scene: Scene, use_point: np.ndarray, use_normal: np.ndarray) -> np.ndarray:
    """Fix the anvil against the use point U, outside the object.

    Parameters
    ----------
    scene : Scene
    use_point : (3,) float ndarray
        U in the object frame, m.
    use_normal : (3,) float ndarray
        Outward unit normal at U, object frame.

    Returns
    -------
    (3,) float64 ndarray
        U in the world frame, m, at the object's current pose.
    """
    mj = deps.mujoco()
    u, n_u = _use_in_world(scene, use_point, use_normal)
    anvil = scene.model.body("anvil").mocapid[0]
    scene.data.mocap_pos[anvil] = u
    # The cube occupies +z of its frame: z along the outward normal puts it beyond U.
    scene.data.mocap_quat[anvil] = _frame_quat(n_u)
    mj.mj_forward(scene.model, scene.data)
    return u


def place_plate(scene: Scene, use_point: np.ndarray, use_normal: np.ndarray) -> np.ndarray:
    """Put the press plate just beyond U (its motor pushes along -z, the inward normal).

    Parameters
    ----------
    scene : Scene
    use_point : (3,) float ndarray
        U in the object frame, m.
    use_normal : (3,) float ndarray
        Outward unit normal at U, object frame.

    Returns
    -------
    (3,) float64 ndarray
        U in the world frame, m, at the object's current pose.
    """
    mj = deps.mujoco()
    u, n_u = _use_in_world(scene, use_point, use_normal)
    plate = scene.model.body("plate")
    plate.pos, plate.quat = u + _TOOL_GAP * n_u, _frame_quat(n_u)
    mj.mj_forward(scene.model, scene.data)
    return u


def _impact(scene: Scene, snapshot: _Snapshot, use_point, use_normal) -> tuple[float, int]:
    """Largest object rotation during a torque pulse about the wrist axis, anvil at U."""
    mj = deps.mujoco()
    m, d, s = scene.model, scene.data, scene.settings
    snapshot.restore(scene)
    u = place_anvil(scene, use_point, use_normal)
    body = scene.object_body
    quat0 = d.xquat[body].copy()
    lever = float(np.hypot(u[0], u[1]))  # distance of U from the wrist axis (the hand's z)
    peak = s.impact_factor * scene.object_mass * G * max(lever, 1e-3)
    n_pulse = max(1, round(s.impact_time / s.timestep))
    n = n_pulse + round(s.impact_settle / s.timestep)
    angle = 0.0
    for step in range(n):
        torque = peak * math.sin(math.pi * (step + 0.5) / n_pulse) if step < n_pulse else 0.0
        d.xfrc_applied[body, 3:] = [0.0, 0.0, torque]
        mj.mj_step(m, d)
        angle = max(angle, _angle_between(quat0, d.xquat[body]))
        if angle > 2 * s.impact_max_angle_rad:
            return angle, step + 1
    return angle, n


def _press(scene: Scene, snapshot: _Snapshot, use_point, use_normal) -> tuple[float, bool, int]:
    """Plate force on U (rising at ``press_rate``) when U first slipped; held if never."""
    mj = deps.mujoco()
    m, d, s = scene.model, scene.data, scene.settings
    snapshot.restore(scene)
    u = place_plate(scene, use_point, use_normal)
    n = max(1, round(s.press_max_force / s.press_rate / s.timestep))
    push = d.actuator("plate_push")
    force = 0.0
    for step in range(n):
        force = s.press_rate * (step + 1) * s.timestep
        push.ctrl = force
        mj.mj_step(m, d)
        now, _ = _use_in_world(scene, use_point, use_normal)
        if np.linalg.norm(now - u) > s.press_slip_m:
            return force, False, step + 1
    return force, True, n


def validate_grasp(
    scene: Scene,
    hand_pose: np.ndarray,
    joints: np.ndarray,
    use_point: np.ndarray | None = None,
    use_normal: np.ndarray | None = None,
    squeezed: Callable[[Scene], None] | None = None,
) -> GraspOutcome:
    """Squeeze the grasp, then run the hold test and (given a use point) impact and press.

    Every trial starts from the same squeezed state, so the results do not depend on the
    order of the trials.

    Parameters
    ----------
    scene : Scene
        The compiled model of the hand and the object.
    hand_pose : (4, 4) float ndarray
        Hand → object transform, m.
    joints : (n_dofs,) float ndarray
        DOF values in the hand's order, rad or m.
    use_point, use_normal : (3,) float ndarray, optional
        U and its outward unit normal in the object frame, m; None or NaN: no use point
        (impact and press are skipped).
    squeezed : callable, optional
        ``squeezed(scene)`` is called once the grasp is squeezed, before any trial (the task
        trials start from that state, :func:`~.task_scene.load_state`); it must not change
        the scene.

    Returns
    -------
    GraspOutcome
    """
    s = scene.settings
    start = set_grasp(scene, hand_pose, joints)
    body = scene.object_body
    com_start = scene.data.xipos[body].copy()
    quat_start = scene.data.xquat[body].copy()
    steps = _squeeze(scene)
    if squeezed is not None:
        squeezed(scene)
    contacts = _hand_contacts(scene)
    squeeze_shift = float(np.linalg.norm(scene.data.xipos[body] - com_start))
    a = scene.object_dof
    speed = float(np.linalg.norm(scene.data.qvel[a : a + 3]))
    spin = float(np.linalg.norm(scene.data.qvel[a + 3 : a + 6]))
    settled = contacts > 0 and speed < s.settled_speed and spin < s.settled_spin
    settled_set = settled_contacts(scene)
    snapshot = _Snapshot(scene.data)
    reference = (com_start, quat_start) if s.displacement_from == "placed" else None
    shifts, angles = np.zeros(6), np.zeros(6)
    for k, axis in enumerate(_AXES):
        shifts[k], angles[k], used = _hold(scene, snapshot, axis, reference)
        steps += used
    ok_dir = (shifts < s.max_shift_m) & (angles < s.max_angle_rad)
    has_use = (
        use_point is not None
        and use_normal is not None
        and np.all(np.isfinite(use_point))
        and np.all(np.isfinite(use_normal))
    )
    impact_angle, impact_ok = math.nan, None
    press_force, press_held = math.nan, None
    if has_use and not settled:
        # Not in the hand after the squeeze: nothing to strike or press with.
        impact_ok, press_force, press_held = False, 0.0, False
    elif has_use:
        up = np.asarray(use_point, dtype=np.float64)
        un = np.asarray(use_normal, dtype=np.float64)
        impact_angle, used = _impact(scene, snapshot, up, un)
        impact_ok = bool(impact_angle < s.impact_max_angle_rad)
        steps += used
        press_force, press_held, used = _press(scene, snapshot, up, un)
        steps += used
    _park_tools(scene)
    return GraspOutcome(
        contacts=contacts,
        squeeze_shift_m=squeeze_shift,
        settled=settled,
        hold_shift_m=shifts,
        hold_angle_rad=angles,
        hold_ok=bool(settled and ok_dir.all()),
        hold_directions_ok=int(ok_dir.sum()),
        impact_angle_rad=float(impact_angle),
        impact_ok=impact_ok,
        press_force_n=float(press_force),
        press_held=press_held,
        steps=steps,
        initial_penetration_m=start.initial_penetration_m,
        start_penetration_m=start.start_penetration_m,
        backoff_shift_m=start.backoff_shift_m,
        backoff_open=start.backoff_open,
        distal_at_limit=start.distal_at_limit,
        ejected=contacts == 0,
        **_settled_metrics(scene, settled_set),
    )


def settled_contacts(scene: Scene):
    """The hand-object contacts of the current state as a contact set in the object frame.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    ContactSet
        Points (k, 3) m and the object's outward normals, object frame; μ of each pair;
        link = the MuJoCo body name of the hand geom. Contacts within 1 mm count.
    """
    from ..metrics.contacts import ContactSet

    mj = deps.mujoco()
    m, d = scene.model, scene.data
    pairs, dist, normal, pos = _contact_arrays(scene)
    keep = dist < _SETTLED_CONTACT_M
    pairs, normal, pos = pairs[keep], normal[keep], pos[keep]
    if len(pairs) == 0:
        return ContactSet.empty()
    body = scene.object_body
    obj_first = m.geom_bodyid[pairs[:, 0]] == body
    # The frame's normal points from geom 0 to geom 1: out of the object when it is geom 0.
    outward = np.where(obj_first[:, None], normal, -normal)
    hand_geom = np.where(obj_first, pairs[:, 1], pairs[:, 0])
    r = d.xmat[body].reshape(3, 3)
    points = (pos - d.xpos[body]) @ r
    normals = outward @ r
    mu = np.maximum(m.geom_friction[pairs[:, 0], 0], m.geom_friction[pairs[:, 1], 0])
    mu = table_friction(scene.settings, mu)  # the metrics' μ, without the engine's margin
    names = np.array(
        [mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[g])) for g in hand_geom],
        dtype=object,
    )
    return ContactSet(points, normals / np.linalg.norm(normals, axis=1, keepdims=True), mu, names)


def _settled_metrics(scene: Scene, contacts) -> dict:
    """ε and E_h of the settled contacts (the analytic metrics where the engine put them)."""
    from ..metrics.effort import hold_effort
    from ..metrics.epsilon import epsilon

    out = {
        "settled_points": contacts.points,
        "settled_normals": contacts.normals,
        "settled_mu": np.asarray(contacts.mu, dtype=np.float64),
        "settled_epsilon": 0.0,
        "settled_hold_effort": np.full(6, np.inf),
    }
    if len(contacts) == 0:
        return out
    center = scene.mass.center_of_mass
    out["settled_epsilon"] = epsilon(contacts, center, scene.mass.r_max, volume=False).epsilon
    out["settled_hold_effort"] = hold_effort(contacts, center)
    return out
