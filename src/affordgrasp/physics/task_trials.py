"""Task trials in MuJoCo (the paper's future work): beat and cut; pick is the hold test.

Both trials run on the task scene (:mod:`.task_scene`), each from the grasp squeezed for
the hold test (copied from the grasp scene, :func:`~.task_scene.load_state`; the palm held
still). The protocols, with their numbers (:class:`~.settings.TrialSettings`),
are the cards of :func:`protocol_cards`; docs/physics.md gives the reasons.

**beat** (version 2). The arm swings the hand about the wrist point w (the row's
``wrist_point``, the palm centre), about the axis through it that drives U straight onto the
nail: a = (U - w) × n, so U moves along its outward normal n (the face leads) as far as its
lever allows (its speed along n is ω |(U - w) × n|: a point near the hand strikes slowly).
The nail's head touches U from outside, its axis along n, and it stands out of a small
board beyond. Each strike: the hand and the tool, at rest, turned back by ``windback_rad``
about that axis, are swung at a speed that rises smoothly to ω over ``ramp_rad`` (the palm's
velocity is set: the grip must carry the tool through the acceleration); ``relax_s`` before
U would touch the nail, or at any earlier contact with the rig, the arm lets go and the hand
and the tool move on as one free body with their own momentum, so the blow delivers what a
swung hammer delivers: all of its energy where the blow lands at the centre of percussion,
less elsewhere, little near the hand. The nail resists with a constant force. Measured per
strike: where the first contact with the rig landed (tool or hand, object frame), how far
the nail went, the impulse on the tool, and the tool's motion in the hand during the blow.
The swing from ``fine_s`` before the touch runs at ``strike_timestep``, the rest at the
physics settings' step. Once the nail is driven home (its head on the board) no blow
follows: the trial is judged on the blows struck.

**cut** (version 1). A workpiece (a slab) is laid against the edge at U (its face square to
the edge's outward direction, from the geometry in a ``edge_radius_m`` ball: the bisector
of a blade's flanks), pressed onto it with a force ramped to ``cut_force_n`` while the palm
is held, then the tool is drawn ``stroke_m`` along the edge's direction at
``stroke_speed_m_s`` (away from the hand, towards the tip: a push stroke) with the press on.
The workpiece starts at first contact: backed off along its normal from wherever the tool or
the hand would lie inside it (the convex parts' overshoot at an edge, a finger below the
edge line). Measured: the workpiece's contacts' distance from the edge line at U over the
stroke (through the first contact near U: the crest of the edge whose bevel U lies on), the
tool's thickness and wedge angle where it bore (an edge, a spine or a spine's corner: a rigid
contact does not tell their pressures apart, so the geometry at the bearing does), the
press force reached before the tool slipped, and the tool's motion in the hand.

The tool's turn and slip are its motion relative to the palm: its rotation, and the motion of
its material point at the palm centre (the tool sliding through the grip). MuJoCo is
deterministic: the same scene and row give the same numbers bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from . import deps
from .scene import Scene
from .settings import TrialSettings
from .task_scene import TaskScene, load_state
from .trials import GraspOutcome, _frame_quat, _Snapshot, validate_grasp

__all__ = [
    "BEAT_VERSION",
    "CUT_VERSION",
    "PICK_VERSION",
    "StrikeOutcome",
    "StrokeOutcome",
    "TaskOutcome",
    "protocol_cards",
    "run_task_trials",
    "strike",
    "stroke",
    "task_row",
    "trial_columns",
]

BEAT_VERSION = 2  # 2: the nail resists with 150 N, no blow after it is driven home (1: 300 N)
CUT_VERSION = 1
PICK_VERSION = 1
_HOLD_ARMATURE = 1e6  # kg, kg·m²: the palm held still (its dofs' inertia dwarfs the hand's)
_MIN_LEVER_M = 1e-4  # U's lever square to n below this: no swing drives U onto the nail
_BACK_OFFS = 8  # passes of the workpiece's back-off to first contact


@dataclass(frozen=True)
class StrikeOutcome:
    """The beat trial of one grasp (SI units; NaN: not measured, the grasp did not settle).

    Attributes
    ----------
    strike_offset_m : float
        The largest distance from U of the first contacts with the rig (per strike, the
        farthest contact of the first step with one), worst strike; +inf when a strike
        missed.
    strike_nail_advance_m : float
        How far the nail went per strike, the mean over the strikes.
    strike_impulse_ns : float
        The rig's normal impulse on the tool per strike, the mean, N·s.
    strike_turn_rad, strike_slip_m : float
        How far the tool turned in the hand, rad, and slid through it (its point at the palm
        centre, relative to the palm), m, from each strike's first contact to its end, summed
        over the strikes (what the blows did to the grip).
    strike_speed_m_s : float
        U's speed along n at the strike (ω × its lever square to n), m/s.
    beat_ok : bool
    """

    strike_offset_m: float
    strike_nail_advance_m: float
    strike_impulse_ns: float
    strike_turn_rad: float
    strike_slip_m: float
    strike_speed_m_s: float
    beat_ok: bool


@dataclass(frozen=True)
class StrokeOutcome:
    """The cut trial of one grasp (SI units; NaN: not measured).

    Attributes
    ----------
    stroke_offset_m : float
        Per window of ``stroke_window_s`` of the stroke the farthest contact of the workpiece
        from the edge line at U (object frame; +inf in a window without one), its
        ``cut_on_edge`` quantile over the stroke. The edge line runs along the edge's
        direction through the workpiece's first contact nearest the line through U, when
        that is within ``crest_radius_m`` of it (the crest of the edge whose bevel U lies
        on), else through U.
    stroke_edge_thickness_m : float
        The tool's thickness where the edge at U bore (the point the edge line passes
        through), from the chords 1 and 3 mm behind it
        (:func:`~affordgrasp.metrics.wedge.use_edge_thickness`): about 0 on an edge,
        the plate's thickness on a spine; NaN when nothing bore.
    stroke_edge_angle_rad : float
        The tool's wedge angle there, in a 3 mm ball
        (:func:`~affordgrasp.metrics.wedge.use_wedge_angle`): 7-51° on the families'
        cutting edges, 90° at a spine's corner, 180° on a flat; NaN when nothing bore.
    stroke_force_n : float
        The press force reached before the tool first slipped or turned past the limits, N.
    stroke_turn_rad, stroke_slip_m : float
        How far the tool turned in the hand, rad, and slid through it (its point at the palm
        centre, relative to the palm), m: the largest over the press and the stroke.
    cut_ok : bool
    """

    stroke_offset_m: float
    stroke_edge_thickness_m: float
    stroke_edge_angle_rad: float
    stroke_force_n: float
    stroke_turn_rad: float
    stroke_slip_m: float
    cut_ok: bool


@dataclass(frozen=True)
class TaskOutcome:
    """The task trials of one grasp; a trial not run (or without a use point) is None.

    Attributes
    ----------
    beat : StrikeOutcome or None
    cut : StrokeOutcome or None
    steps : int
        Simulation steps spent on the task trials (the squeeze is the hold test's).
    """

    beat: StrikeOutcome | None
    cut: StrokeOutcome | None
    steps: int


def protocol_cards(trials: TrialSettings, names=("beat", "cut", "pick")) -> dict:
    """The protocol card of each task trial: its version, what it does, its numbers.

    Parameters
    ----------
    trials : TrialSettings
    names : sequence of str
        Among ``"beat"``, ``"cut"``, ``"pick"``.

    Returns
    -------
    dict of str to dict
        Per trial: ``version``, ``procedure``, ``pass`` (text), ``settings`` (the numbers it
        uses, SI units) and ``columns``.
    """
    t = trials.to_dict()
    both = {k: t[k] for k in ("max_turn_rad", "max_slip_m")}
    cut_keys = ("cut", "stroke", "edge", "workpiece", "crest")
    cards = {
        "beat": {
            "version": BEAT_VERSION,
            "procedure": (
                "the arm swings the hand about the wrist point w, axis (U - w) x n; per "
                "strike from rest windback_rad before the touch, speed ramped (raised "
                "cosine) to swing_speed_rad_s over ramp_rad, step strike_timestep from "
                "fine_s before the touch; relax_s before the touch (or at an earlier "
                "contact) the arm lets go: hand and tool move on as one free body; a nail "
                "(slide, constant resisting force nail_force_n, mass nail_mass_kg) stands "
                "nail_out_m out of a square board (half side board_half_m) at U, along n; "
                "strikes strikes, each followed strike_time after its first contact"
            ),
            "pass": (
                "every strike's first contact within beat_max_offset_m of U, mean nail "
                "advance >= beat_min_advance_m, turn < max_turn_rad and slip < max_slip_m "
                "in the hand over the blows"
            ),
            "settings": {k: v for k, v in t.items() if not k.startswith(cut_keys)} | both,
            "columns": list(StrikeOutcome.__dataclass_fields__),
        },
        "cut": {
            "version": CUT_VERSION,
            "procedure": (
                "a workpiece square to the edge's outward direction at U (edge_radius_m "
                "ball) backed off to first contact, the palm held; press ramped to "
                "cut_force_n over cut_ramp_s, then the tool drawn stroke_m along the edge "
                "at stroke_speed_m_s away from the hand (push stroke); workpiece μ "
                "cut_friction; contacts pooled per stroke_window_s; the edge line along the "
                "edge's direction through the first contact within crest_radius_m of U, or U"
            ),
            "pass": (
                "workpiece contacts within cut_max_offset_m of the edge line through U over "
                ">= cut_on_edge of the stroke, where it bore the tool no thicker than "
                "cut_max_thickness_m and its wedge no wider than cut_max_angle_rad, "
                "cut_force_n reached, turn < max_turn_rad, slip < max_slip_m"
            ),
            "settings": {k: v for k, v in t.items() if k.startswith(cut_keys)} | both,
            "columns": list(StrokeOutcome.__dataclass_fields__),
        },
        "pick": {
            "version": PICK_VERSION,
            "procedure": "the hold test of the physics settings",
            "pass": "hold_ok",
            "settings": {},
            "columns": ["pick_ok"],
        },
    }
    return {n: cards[n] for n in names}


def trial_columns(names) -> list[str]:
    """The outcome columns of the task trials ``names``, in order.

    Parameters
    ----------
    names : sequence of str

    Returns
    -------
    list of str
    """
    out: list[str] = []
    if "beat" in names:
        out += list(StrikeOutcome.__dataclass_fields__)
    if "cut" in names:
        out += list(StrokeOutcome.__dataclass_fields__)
    if "pick" in names:
        out.append("pick_ok")
    return out


def null_row(names) -> dict:
    """The columns of ``names`` for a row without a use point: every value None.

    Parameters
    ----------
    names : sequence of str
        The trials (``pick`` is not included: it needs no use point).

    Returns
    -------
    dict
    """
    return {c: None for c in trial_columns([n for n in names if n != "pick"])}


def _quat_mat(quat: np.ndarray) -> np.ndarray:
    mj = deps.mujoco()
    r = np.zeros(9)
    mj.mju_quat2Mat(r, np.ascontiguousarray(quat, dtype=np.float64))
    return r.reshape(3, 3)


def _rotation(axis: np.ndarray, angle: float) -> tuple[np.ndarray, np.ndarray]:
    mj = deps.mujoco()
    q = np.zeros(4)
    mj.mju_axisAngle2Quat(q, np.ascontiguousarray(axis, dtype=np.float64), angle)
    r = np.zeros(9)
    mj.mju_quat2Mat(r, q)
    return q, r.reshape(3, 3)


class _InHand:
    """The tool's motion relative to the palm since a reference pose: how far it turned, and
    how far its material point at the palm's origin (the wrist point) slid, m."""

    def __init__(self, ts: TaskScene):
        self.ts = ts
        self.reset()

    def _frames(self):
        d, ts = self.ts.data, self.ts
        palm_r = d.xmat[ts.palm_body].reshape(3, 3)
        tool_r = d.xmat[ts.scene.object_body].reshape(3, 3)
        return palm_r, d.xpos[ts.palm_body], tool_r, d.xpos[ts.scene.object_body]

    def reset(self) -> None:
        """Take the current pose as the reference."""
        palm_r, palm_p, tool_r, tool_p = self._frames()
        self.r0 = palm_r.T @ tool_r
        self.point = tool_r.T @ (palm_p - tool_p)  # the tool's point at the palm origin

    def motion(self) -> tuple[float, float]:
        """(turn, rad; slip, m) since the reference."""
        palm_r, palm_p, tool_r, tool_p = self._frames()
        cos = (np.trace(self.r0.T @ (palm_r.T @ tool_r)) - 1.0) / 2.0
        slip = float(np.linalg.norm(tool_r @ self.point + tool_p - palm_p))
        return math.acos(min(1.0, max(-1.0, cos))), slip


def _world(ts: TaskScene, point=None, vector=None):
    d, body = ts.data, ts.scene.object_body
    r = d.xmat[body].reshape(3, 3)
    if point is not None:
        return r @ point + d.xpos[body]
    return r @ vector


def _farthest(ts: TaskScene, points: np.ndarray, use_point: np.ndarray) -> float:
    """The largest distance from U of world points, measured in the object frame, m."""
    return float(np.max(np.linalg.norm(_to_object(ts, points) - use_point, axis=1)))


def _to_object(ts: TaskScene, points: np.ndarray) -> np.ndarray:
    d, body = ts.data, ts.scene.object_body
    return (points - d.xpos[body]) @ d.xmat[body].reshape(3, 3)


def _rig_contacts(ts: TaskScene, rig: np.ndarray):
    """Contacts of the rig geoms flagged in ``rig`` (ngeom,) with the tool or the hand:
    (dist (k,), world points (k, 3), normal force (k,), on the tool (k,) bool)."""
    m, d = ts.model, ts.data
    n = d.ncon
    if n == 0:
        z = np.zeros(0)
        return z, np.zeros((0, 3)), z, np.zeros(0, bool)
    con = d.contact
    geom = np.asarray(con.geom[:n])
    on_rig = rig[geom]
    other = np.where(on_rig[:, 0], geom[:, 1], geom[:, 0])
    tool = m.geom_bodyid[other] == ts.scene.object_body
    keep = (on_rig[:, 0] ^ on_rig[:, 1]) & (tool | ts.hand_geom[other])
    adr = np.asarray(con.efc_address[:n])[keep]
    force = np.where(adr >= 0, d.efc_force[np.maximum(adr, 0)], 0.0)
    return np.asarray(con.dist[:n])[keep], np.asarray(con.pos[:n])[keep], force, tool[keep]


def _hold_palm(ts: TaskScene, held: bool) -> None:
    """Hold the palm still (its dofs' inertia dwarfs the hand's) or let it move freely."""
    a = ts.palm_dof
    ts.model.dof_armature[a : a + 6] = _HOLD_ARMATURE if held else 0.0


def _restore(ts: TaskScene, snapshot: _Snapshot) -> None:
    mj = deps.mujoco()
    snapshot.restore(ts.scene)
    ts.park()
    _hold_palm(ts, True)
    mj.mj_forward(ts.model, ts.data)


def _unsettled_strike() -> StrikeOutcome:
    return StrikeOutcome(math.inf, 0.0, 0.0, math.nan, math.nan, math.nan, False)


def _unsettled_stroke() -> StrokeOutcome:
    return StrokeOutcome(math.inf, math.nan, math.nan, 0.0, math.nan, math.nan, False)


class _Swing:
    """The arm: the palm turned about an axis through the wrist point, at a set speed."""

    def __init__(self, ts: TaskScene, wrist_point: np.ndarray, axis: np.ndarray):
        self.ts, self.w, self.axis = ts, wrist_point, axis
        a = ts.palm_qpos
        self.home = ts.data.qpos[a : a + 7].copy()  # the palm's pose at the touch
        self.angle = 0.0  # about the axis, from that pose

    def wind_back(self, angle: float) -> None:
        """Put the palm at ``-angle`` about the axis from its home pose, the tool where it is
        in the hand; everything at rest."""
        mj = deps.mujoco()
        ts = self.ts
        m, d = ts.model, ts.data
        p, o = ts.palm_qpos, ts.scene.object_qpos
        palm_r, tool_r = _quat_mat(d.qpos[p + 3 : p + 7]), _quat_mat(d.qpos[o + 3 : o + 7])
        rel_r = palm_r.T @ tool_r
        rel_p = palm_r.T @ (d.qpos[o : o + 3] - d.qpos[p : p + 3])
        q, r = _rotation(self.axis, -angle)
        d.qpos[p : p + 3] = self.w + r @ (self.home[:3] - self.w)
        quat = np.zeros(4)
        mj.mju_mulQuat(quat, q, self.home[3:])
        d.qpos[p + 3 : p + 7] = quat
        palm_r = _quat_mat(quat)
        d.qpos[o : o + 3] = d.qpos[p : p + 3] + palm_r @ rel_p
        mj.mju_mat2Quat(quat, np.ascontiguousarray(palm_r @ rel_r).ravel())
        d.qpos[o + 3 : o + 7] = quat
        self.angle = -angle
        d.qvel[:] = 0.0
        _hold_palm(ts, True)
        mj.mj_forward(m, d)

    def drive(self, speed: float, dt: float) -> None:
        """Set the palm's velocity for the next step: turning at ``speed`` about the axis."""
        ts, d = self.ts, self.ts.data
        a = ts.palm_dof
        omega = speed * self.axis
        # a free joint's velocity: its origin's, world frame; its spin, body frame
        d.qvel[a : a + 3] = np.cross(omega, d.xpos[ts.palm_body] - self.w)
        d.qvel[a + 3 : a + 6] = d.xmat[ts.palm_body].reshape(3, 3).T @ omega
        self.angle += speed * dt


def strike(
    ts: TaskScene, snapshot: _Snapshot, use_point, use_normal, wrist_point
) -> tuple[StrikeOutcome, int]:
    """The beat trial from a squeezed state (module docstring).

    Parameters
    ----------
    ts : TaskScene
    snapshot : _Snapshot
        The squeezed grasp.
    use_point, use_normal : (3,) float ndarray
        U and its outward unit normal, object frame.
    wrist_point : (3,) float ndarray
        The wrist point in the hand frame (the world), m.

    Returns
    -------
    StrikeOutcome
    int
        Simulation steps.
    """
    mj = deps.mujoco()
    m, d, t = ts.model, ts.data, ts.trials
    _restore(ts, snapshot)
    use_point = np.asarray(use_point, dtype=np.float64)
    u = _world(ts, point=use_point)
    n = _world(ts, vector=use_normal)
    axis = np.cross(u - wrist_point, n)
    lever = float(np.linalg.norm(axis))
    if lever < _MIN_LEVER_M:  # U on the line through the wrist along n: no swing drives it
        return StrikeOutcome(math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, False), 0
    axis /= lever
    omega = t.swing_speed_rad_s
    d.mocap_pos[ts.nail_mocap] = u
    d.mocap_quat[ts.nail_mocap] = _frame_quat(-n)  # the rig lies along -z of its frame
    in_hand = _InHand(ts)
    swing = _Swing(ts, wrist_point, axis)
    rig = np.zeros(m.ngeom, dtype=bool)
    rig[list(ts.nail_geoms | ts.board_geoms)] = True
    coarse = m.opt.timestep
    ramp_time = 2.0 * t.ramp_rad / omega
    # the swing's time to the touch, and as long again for one that stalls
    give_up = 2.0 * (ramp_time + (t.windback_rad - t.ramp_rad + t.miss_rad) / omega)
    offsets, advances, impulses = [], [], []
    turn = slip = 0.0
    steps = 0
    try:
        for _ in range(t.strikes):
            swing.wind_back(t.windback_rad)
            dist, pos, _f, _tool = _rig_contacts(ts, rig)
            if (dist < 0).any():
                # The hand or the tool lies in the rig where the swing starts: no strike.
                offsets.append(_farthest(ts, pos[dist < 0], use_point))
                advances.append(0.0)
                impulses.append(0.0)
                continue
            nail0 = d.qpos[ts.nail_qpos]
            touch = nail0 / lever  # the angle at which U meets the nail's head, where it is now
            m.opt.timestep = dt = coarse
            relaxed = False
            first = None
            impulse = after = time = 0.0
            while True:
                if not relaxed:
                    ramp = 0.5 * (1.0 - math.cos(math.pi * time / ramp_time))
                    swing.drive(omega * ramp if time < ramp_time else omega, dt)
                mj.mj_step(m, d)
                steps += 1
                time += dt
                dist, pos, force, tool = _rig_contacts(ts, rig)
                active = dist < 0
                if dt == coarse and (swing.angle >= touch - omega * t.fine_s or active.any()):
                    m.opt.timestep = dt = t.strike_timestep
                if not relaxed and (swing.angle >= touch - omega * t.relax_s or active.any()):
                    relaxed = True
                    _hold_palm(ts, False)
                    # let go, the hand and the tool fly on: as far as miss_rad more, at most
                    give_up = min(give_up, time + t.relax_s + t.miss_rad / omega)
                if first is None and active.any():
                    first = _farthest(ts, pos[active], use_point)
                    in_hand.reset()
                if first is not None:
                    impulse += float(force[tool].sum()) * dt
                    after += dt
                    receding = _normal_speed(ts, use_point, n) <= 0 and not active.any()
                    if after >= t.strike_time or receding:
                        break
                elif time > give_up:
                    break
            offsets.append(math.inf if first is None else first)
            advances.append(float(d.qpos[ts.nail_qpos] - nail0))
            impulses.append(impulse)
            if first is not None:
                now_turn, now_slip = in_hand.motion()
                turn, slip = turn + now_turn, slip + now_slip
            if d.qpos[ts.nail_qpos] >= t.nail_out_m - t.nail_head_height_m:
                break  # driven home: the head is on the board, the next blow meets the board
    finally:
        m.opt.timestep = coarse
        _hold_palm(ts, True)
    offset = max(offsets)
    advance = float(np.mean(advances))
    ok = (
        offset <= t.beat_max_offset_m
        and advance >= t.beat_min_advance_m
        and turn < t.max_turn_rad
        and slip < t.max_slip_m
    )
    out = StrikeOutcome(
        offset, advance, float(np.mean(impulses)), turn, slip, omega * lever, bool(ok)
    )
    return out, steps


def _normal_speed(ts: TaskScene, use_point: np.ndarray, normal: np.ndarray) -> float:
    """U's velocity along the world vector ``normal``, m/s (the tool's rigid motion)."""
    d, body = ts.data, ts.scene.object_body
    a = ts.scene.object_dof
    spin = d.xmat[body].reshape(3, 3) @ d.qvel[a + 3 : a + 6]
    lever = d.xmat[body].reshape(3, 3) @ use_point
    return float((d.qvel[a : a + 3] + np.cross(spin, lever)) @ normal)


def stroke(
    ts: TaskScene, snapshot: _Snapshot, use_point, outward, along, wrist_point
) -> tuple[StrokeOutcome, int]:
    """The cut trial from a squeezed state (module docstring).

    Parameters
    ----------
    ts : TaskScene
    snapshot : _Snapshot
    use_point : (3,) float ndarray
        U, object frame, m.
    outward, along : (3,) float ndarray
        The edge's outward direction and its direction at U, object frame, unit
        (:func:`~affordgrasp.metrics.wedge.use_edge_frame`).
    wrist_point : (3,) float ndarray
        The wrist point in the hand frame, m (the stroke pulls the tool towards it).

    Returns
    -------
    StrokeOutcome
    int
        Simulation steps.
    """
    mj = deps.mujoco()
    m, d, t = ts.model, ts.data, ts.trials
    _restore(ts, snapshot)
    use_point = np.asarray(use_point, dtype=np.float64)
    along = np.asarray(along, dtype=np.float64)
    u = _world(ts, point=use_point)
    z = _world(ts, vector=outward)
    x = _world(ts, vector=along)
    x = x - (x @ z) * z
    x /= np.linalg.norm(x)
    if x @ (u - wrist_point) < 0:
        x = -x  # towards the tip, away from the wrist: a push stroke
    frame = np.stack([x, np.cross(z, x), z], axis=1)
    quat = np.zeros(4)
    mj.mju_mat2Quat(quat, np.ascontiguousarray(frame).ravel())
    m.body_pos[ts.cut_body] = u + t.cut_gap_m * z
    m.body_quat[ts.cut_body] = quat
    mj.mj_forward(m, d)
    in_hand = _InHand(ts)
    rig = np.zeros(m.ngeom, dtype=bool)
    rig[list(ts.cut_geoms)] = True
    # The tool's convex parts stick out of its mesh (at a thin edge, tenths of a millimetre),
    # and another part or the hand may stick out farther: back the workpiece off along its
    # normal until it touches nothing, so the press starts at the first contact.
    for _ in range(_BACK_OFFS):
        dist, _p, _f, _t = _rig_contacts(ts, rig)
        if not (dist < 0).any():
            break
        d.qpos[ts.press_qpos] += float(dist.min()) - t.cut_gap_m
        mj.mj_forward(m, d)
    dt = m.opt.timestep
    n_ramp = max(1, round(t.cut_ramp_s / dt))
    n_draw = max(1, round(t.stroke_m / t.stroke_speed_m_s / dt))
    per_window = max(1, round(t.stroke_window_s / dt))
    turn = slip = 0.0
    reached = None
    offsets = np.full(-(-n_draw // per_window), -np.inf)
    touched = np.zeros(len(offsets), dtype=bool)
    crest = None  # where the edge line passes: the tool's first contact near U
    force = 0.0
    for step in range(n_ramp + n_draw):
        force = t.cut_force_n * min(1.0, (step + 1) / n_ramp)
        d.ctrl[ts.cut_actuator] = force
        drawing = step >= n_ramp
        d.qvel[ts.draw_dof] = -t.stroke_speed_m_s if drawing else 0.0
        mj.mj_step(m, d)
        now_turn, now_slip = in_hand.motion()
        turn, slip = max(turn, now_turn), max(slip, now_slip)
        if reached is None and (turn >= t.max_turn_rad or slip >= t.max_slip_m):
            reached = force
        dist, pos, _force, _tool = _rig_contacts(ts, rig)
        touching = dist < 0
        if crest is None and touching.any():
            crest = _crest(_to_object(ts, pos[touching]), use_point, along, t.crest_radius_m)
        if drawing:
            if touching.any():
                points = _to_object(ts, pos[touching])
                rel = points - crest
                off = rel - np.outer(rel @ along, along)
                w = (step - n_ramp) // per_window
                offsets[w] = max(offsets[w], float(np.linalg.norm(off, axis=1).max()))
                touched[w] = True
    d.ctrl[ts.cut_actuator] = 0.0
    offsets[~touched] = np.inf  # a window without a contact: the edge left the workpiece
    offset = float(np.quantile(offsets, t.cut_on_edge, method="higher"))
    reached = force if reached is None else reached
    thickness, angle = _bearing_wedge(ts, crest, outward)
    ok = (
        offset <= t.cut_max_offset_m
        and thickness <= t.cut_max_thickness_m
        and angle <= t.cut_max_angle_rad
        and reached >= t.cut_force_n
        and turn < t.max_turn_rad
        and slip < t.max_slip_m
    )
    out = StrokeOutcome(offset, thickness, angle, float(reached), turn, slip, bool(ok))
    return out, n_ramp + n_draw


def _crest(points: np.ndarray, use_point: np.ndarray, along: np.ndarray, radius: float):
    """The point the edge line passes through: of the workpiece's first contacts, the one
    nearest the line through U along the edge, when within ``radius`` of it (the crest of
    the edge whose bevel U lies on), else U."""
    rel = points - use_point
    across = np.linalg.norm(rel - np.outer(rel @ along, along), axis=1)
    k = int(np.argmin(across))
    return points[k] if across[k] <= radius else use_point


def _bearing_wedge(ts: TaskScene, crest, outward: np.ndarray) -> tuple[float, float]:
    """The tool's thickness (m) and wedge angle (rad) where the edge at U bore (the crest
    point, on the mesh): :func:`~affordgrasp.metrics.wedge.use_wedge_shape` with the
    workpiece's normal; NaN when nothing bore."""
    from ..metrics.wedge import use_wedge_shape

    if crest is None:
        return math.nan, math.nan
    point = ts.mesh.nearest.on_surface(np.asarray(crest, dtype=np.float64)[None])[0]
    shape = use_wedge_shape(ts.mesh, point, np.asarray(outward, dtype=np.float64)[None])
    return float(shape.edge_thickness[0]), float(shape.angle[0])


def run_task_trials(
    scene: Scene,
    ts: TaskScene,
    hand_pose,
    joints,
    names,
    use_point=None,
    use_normal=None,
    wrist_point=None,
    edge_frame=None,
) -> tuple[GraspOutcome, TaskOutcome]:
    """Validate a grasp (hold, impact, press) and run the task trials ``names`` on it.

    The grasp is squeezed once, in the grasp scene (:func:`~.trials.validate_grasp`); the
    task trials start from that squeezed state, copied into the task scene
    (:func:`~.task_scene.load_state`), so they see the grasp the hold test saw.

    Parameters
    ----------
    scene : Scene
        The grasp scene (:func:`~.scene.build_scene`).
    ts : TaskScene
        The task scene of the same hand and object (:func:`~.task_scene.build_task_scene`).
    hand_pose : (4, 4) float ndarray
        Hand → object transform, m.
    joints : (n_dofs,) float ndarray
    names : sequence of str
        Trials among ``"beat"`` and ``"cut"`` (others are ignored; ``pick`` is the hold
        test's ``hold_ok``).
    use_point, use_normal : (3,) float ndarray, optional
        U and its outward normal, object frame; None or NaN: no use point, no trial.
    wrist_point : (3,) float ndarray, optional
        The wrist point (the palm centre), object frame, m (the dataset's ``wrist_point``).
    edge_frame : tuple of two (3,) float ndarray, optional
        The edge's outward direction and direction at U, object frame
        (:func:`~affordgrasp.metrics.wedge.use_edge_frame`); needed for cut.

    Returns
    -------
    GraspOutcome
        The hold, impact and press trials, as :func:`~.trials.validate_grasp` gives them.
    TaskOutcome
    """
    wanted = [n for n in names if n in ("beat", "cut")]
    has_use = (
        use_point is not None
        and use_normal is not None
        and wrist_point is not None
        and np.all(np.isfinite(use_point))
        and np.all(np.isfinite(use_normal))
        and np.all(np.isfinite(wrist_point))
    )
    held: list[_Snapshot] = []

    def capture(squeezed: Scene) -> None:
        load_state(ts, squeezed)
        _hold_palm(ts, True)
        held.append(_Snapshot(ts.data))

    grasp = validate_grasp(
        scene,
        hand_pose,
        joints,
        use_point,
        use_normal,
        squeezed=capture if wanted and has_use else None,
    )
    if not wanted or not has_use:
        return grasp, TaskOutcome(None, None, 0)
    hand_pose = np.asarray(hand_pose, dtype=np.float64).reshape(4, 4)
    use_point = np.asarray(use_point, dtype=np.float64)
    use_normal = np.asarray(use_normal, dtype=np.float64)
    inverse = np.linalg.inv(hand_pose)
    wrist = inverse[:3, :3] @ np.asarray(wrist_point, dtype=np.float64) + inverse[:3, 3]
    snapshot = held[0] if grasp.settled else None  # not in the hand: nothing to do a task with
    beat = cut = None
    steps = 0
    if "beat" in wanted:
        if snapshot is None:
            beat = _unsettled_strike()
        else:
            beat, used = strike(ts, snapshot, use_point, use_normal, wrist)
            steps += used
    if "cut" in wanted:
        if snapshot is None:
            cut = _unsettled_stroke()
        else:
            outward, along = edge_frame
            cut, used = stroke(ts, snapshot, use_point, outward, along, wrist)
            steps += used
    ts.park()
    return grasp, TaskOutcome(beat, cut, steps)


def task_row(outcome: TaskOutcome, names, hold_ok: bool) -> dict:
    """The task trials' columns of one row (:func:`trial_columns`).

    Parameters
    ----------
    outcome : TaskOutcome
    names : sequence of str
    hold_ok : bool
        The hold test's outcome (``pick_ok``).

    Returns
    -------
    dict
    """
    row = null_row(names)
    for part in (outcome.beat, outcome.cut):
        if part is not None:
            row.update(asdict(part))
    if "pick" in names:
        row["pick_ok"] = bool(hold_ok)
    return row
