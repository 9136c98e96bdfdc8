"""The task trials' model: the grasp scene of :mod:`.scene` plus a wrist, a nail and a workpiece.

The hold, impact and press trials run on the grasp scene as built; the task trials
(:mod:`.task_trials`) run on a second model compiled from the same description with
:func:`add_task_rig`, so nothing of the first changes. What the rig adds, by name:

* ``wrist`` — a free joint on the palm body (``link_0``), at rest where the grasp scene
  fixes the palm. The trials hold the palm still (a large armature on its six dofs) or move
  it at a set velocity (the arm), and let it go (no armature: the hand and the tool move on
  with their own inertia).
* ``nail_rig`` — a mocap body (the strike's frame: +z along the inward use normal, towards
  the tool, the nail head's face at its origin) holding the ``board`` (a box whose face lies
  ``nail_out_m`` beyond the head's) and the ``nail`` body (a head and a shank) on the slide
  ``nail_slide`` (along -z, into the board) whose dry friction (``frictionloss``) is the
  nail's constant resisting force.
* ``cut_rig`` — the ``workpiece`` (a slab whose face is at the body's origin, reaching from
  the origin along +x over the stroke and a margin at either end), a body on two slides:
  ``cut_press`` (along -z, towards the tool, pushed by the force actuator ``cut_push``) and
  ``cut_draw`` (along +x, the edge's direction, moved at a set speed).

The rig's geoms touch the object and the hand (a strike that lands on a finger is seen), not
each other or the grasp scene's anvil and plate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import deps
from .scene import FAR, Scene, build_scene
from .settings import PhysicsSettings, TrialSettings

__all__ = ["TaskScene", "add_task_rig", "build_task_scene", "load_state"]

_RIG_BITS = (4, 1 | 2)  # contype, conaffinity: the rig touches the object (1) and the hand (2)
_PALM = "link_0"
_KINEMATIC = 1e4  # kg: the armature of an axis whose speed the trial sets


def add_task_rig(spec, trials: TrialSettings) -> None:
    """Add the wrist's free joint, the nail rig and the workpiece to a grasp scene's spec.

    Parameters
    ----------
    spec : mujoco.MjSpec
        The grasp scene's model before compilation (its palm body is ``link_0``); changed in
        place.
    trials : TrialSettings
        Sizes, masses, the nail's force and the friction of the rig.
    """
    mj = deps.mujoco()
    t = trials
    slide = mj.mjtJoint.mjJNT_SLIDE
    box = mj.mjtGeom.mjGEOM_BOX
    spec.body(_PALM).add_joint(name="wrist", type=mj.mjtJoint.mjJNT_FREE, armature=0.0, damping=0.0)
    contact = {"contype": _RIG_BITS[0], "conaffinity": _RIG_BITS[1], "condim": 3}
    rig = spec.worldbody.add_body(name="nail_rig", mocap=True, pos=[FAR, -FAR, FAR])
    rig.add_geom(
        name="board",
        type=box,
        size=[t.board_half_m, t.board_half_m, t.board_thickness_m / 2],
        pos=[0, 0, -t.nail_out_m - t.board_thickness_m / 2],
        friction=[t.board_friction, 0, 0],
        **contact,
    )
    nail = rig.add_body(name="nail")
    # Dry friction as a near-hard constraint at the stiffest time constant the strike's step
    # resolves: it holds the nail still under any push below its force and resists with that
    # force while the nail moves (MuJoCo's default impedance lets it creep at 2 m/s under
    # two thirds of it).
    stiff = [2 * t.strike_timestep, 1]
    nail.add_joint(
        name="nail_slide",
        type=slide,
        axis=[0, 0, -1],
        frictionloss=t.nail_force_n,
        solref_friction=stiff,
        solimp_friction=[0.9999, 0.9999, 0.001, 0.5, 2],
        armature=0.0,
        damping=0.0,
        limited=False,
    )
    head, shank = t.nail_head_height_m, t.nail_out_m - t.nail_head_height_m
    for name, radius, half, centre in (
        ("nail_head", t.nail_head_radius_m, head / 2, -head / 2),
        ("nail_shank", t.nail_shank_radius_m, shank / 2, -head - shank / 2),
    ):
        nail.add_geom(
            name=name,
            type=mj.mjtGeom.mjGEOM_CYLINDER,
            size=[radius, half, 0],
            pos=[0, 0, centre],
            mass=t.nail_mass_kg / 2,
            friction=[t.board_friction, 0, 0],
            solref=stiff,
            **contact,
        )
    cut = spec.worldbody.add_body(name="cut_rig", pos=[-FAR, FAR, FAR])
    cut.add_joint(name="cut_press", type=slide, axis=[0, 0, -1], armature=0.0, damping=0.0)
    # The stroke is a set speed: its axis's inertia dwarfs the friction the edge puts on it.
    cut.add_joint(name="cut_draw", type=slide, axis=[1, 0, 0], armature=_KINEMATIC, damping=0.0)
    half_along = t.stroke_m / 2 + t.workpiece_margin_m
    cut.add_geom(
        name="workpiece",
        type=box,
        size=[half_along, t.workpiece_across_m, t.workpiece_thickness_m / 2],
        pos=[t.stroke_m / 2, 0, t.workpiece_thickness_m / 2],
        mass=t.workpiece_mass_kg,
        friction=[t.cut_friction, 0, 0],
        **contact,
    )
    spec.add_actuator(
        name="cut_push",
        target="cut_press",
        trntype=mj.mjtTrn.mjTRN_JOINT,
        gear=[1, 0, 0, 0, 0, 0],
    )


@dataclass
class TaskScene:
    """The task trials' compiled model: a :class:`~.scene.Scene` and the rig's indices.

    Attributes
    ----------
    scene : Scene
        The grasp scene's indices, valid in this model (the trials reuse its grasp set-up
        and squeeze).
    trials : TrialSettings
    mesh : trimesh.Trimesh
        The object's mesh (the cut measures the tool's thickness where it bore).
    palm_body : int
        The palm's body (``link_0``).
    palm_qpos, palm_dof : int
        Addresses of the wrist's free joint: the palm's 7 qpos and 6 dofs.
    nail_mocap : int
        Mocap index of the nail rig.
    nail_qpos, nail_dof : int
        Addresses of the nail's slide.
    press_qpos, press_dof, draw_qpos, draw_dof : int
        Addresses of the workpiece's slides.
    cut_body, cut_actuator : int
        The workpiece's body and its press actuator.
    nail_geoms, board_geoms, cut_geoms : set of int
        Geom ids of the nail (head and shank), the nail board and the workpiece.
    hand_geom : (ngeom,) bool ndarray
        Which geoms belong to the hand.
    """

    scene: Scene
    trials: TrialSettings
    mesh: Any
    palm_body: int
    palm_qpos: int
    palm_dof: int
    nail_mocap: int
    nail_qpos: int
    nail_dof: int
    press_qpos: int
    press_dof: int
    draw_qpos: int
    draw_dof: int
    cut_body: int
    cut_actuator: int
    nail_geoms: Any
    board_geoms: Any
    cut_geoms: Any
    hand_geom: np.ndarray

    @property
    def model(self):
        """The compiled ``mujoco.MjModel``."""
        return self.scene.model

    @property
    def data(self):
        """Its ``mujoco.MjData``."""
        return self.scene.data

    transfer: dict = field(default_factory=dict)  # load_state's index maps, per source model

    def park(self) -> None:
        """Move the rig off stage and stop it (the press force off)."""
        m, d = self.model, self.data
        d.mocap_pos[self.nail_mocap] = [FAR, -FAR, FAR]
        m.body_pos[self.cut_body] = [-FAR, FAR, FAR]
        for adr in (self.nail_qpos, self.press_qpos, self.draw_qpos):
            d.qpos[adr] = 0.0
        for adr in (self.nail_dof, self.press_dof, self.draw_dof):
            d.qvel[adr] = 0.0
        d.ctrl[self.cut_actuator] = 0.0


def build_task_scene(
    hand,
    obj,
    settings: PhysicsSettings | None = None,
    trials: TrialSettings | None = None,
    *,
    parts: list | None = None,
) -> TaskScene:
    """Compile the task trials' model of ``hand`` and ``obj`` (the module docstring).

    Parameters
    ----------
    hand : Hand or str
    obj : GraspObject
    settings : PhysicsSettings, optional
        The grasp scene's protocol; the defaults when None.
    trials : TrialSettings, optional
        The task trials' protocol; the defaults when None.
    parts : list of (vertices, faces), optional
        Convex parts of the object (as for :func:`~.scene.build_scene`).

    Returns
    -------
    TaskScene
    """
    mj = deps.mujoco()
    trials = trials or TrialSettings()
    scene = build_scene(
        hand, obj, settings, parts=parts, extend=lambda spec: add_task_rig(spec, trials)
    )
    m = scene.model
    jid = {n: m.joint(n).id for n in ("wrist", "nail_slide", "cut_press", "cut_draw")}
    hand_geom = (m.geom_contype & 2) != 0
    hand_geom &= m.geom_bodyid != scene.object_body
    return TaskScene(
        scene=scene,
        trials=trials,
        mesh=obj.mesh,
        palm_body=m.body(_PALM).id,
        palm_qpos=int(m.jnt_qposadr[jid["wrist"]]),
        palm_dof=int(m.jnt_dofadr[jid["wrist"]]),
        nail_mocap=int(m.body_mocapid[m.body("nail_rig").id]),
        nail_qpos=int(m.jnt_qposadr[jid["nail_slide"]]),
        nail_dof=int(m.jnt_dofadr[jid["nail_slide"]]),
        press_qpos=int(m.jnt_qposadr[jid["cut_press"]]),
        press_dof=int(m.jnt_dofadr[jid["cut_press"]]),
        draw_qpos=int(m.jnt_qposadr[jid["cut_draw"]]),
        draw_dof=int(m.jnt_dofadr[jid["cut_draw"]]),
        cut_body=m.body("cut_rig").id,
        cut_actuator=mj.mj_name2id(m, mj.mjtObj.mjOBJ_ACTUATOR, "cut_push"),
        nail_geoms={m.geom("nail_head").id, m.geom("nail_shank").id},
        board_geoms={m.geom("board").id},
        cut_geoms={m.geom("workpiece").id},
        hand_geom=hand_geom,
    )


def load_state(ts: TaskScene, scene: Scene) -> None:
    """Put the task scene in the state of a grasp scene (the same hand and object).

    Joint positions and velocities, actuator controls, the joint limits and coupling
    offsets set per grasp (the ratchet, the couplings), and the bodies placed per grasp, are
    copied by name; the palm is at rest where the grasp scene fixes it, the rig parked. The
    task trials then start from the grasp squeezed exactly as for the hold test.

    Parameters
    ----------
    ts : TaskScene
    scene : Scene
        The grasp scene, e.g. just after the squeeze
        (:func:`~affordgrasp.physics.trials.validate_grasp`'s ``squeezed``).
    """
    mj = deps.mujoco()
    src, dst = scene.model, ts.model
    key = id(src)
    maps = ts.transfer.get(key)
    if maps is None:
        maps = ts.transfer[key] = _state_maps(src, dst)
    d, s = ts.data, scene.data
    mj.mj_resetData(dst, d)
    d.time = s.time
    for name, (src_idx, dst_idx) in maps.items():
        if name in ("qpos", "qvel", "ctrl"):
            getattr(d, name)[dst_idx] = getattr(s, name)[src_idx]
        elif name == "jnt_range":
            dst.jnt_range[dst_idx] = src.jnt_range[src_idx]
        elif name == "eq_data":
            dst.eq_data[dst_idx] = src.eq_data[src_idx]
        else:  # body_pos, body_quat
            getattr(dst, name)[dst_idx] = getattr(src, name)[src_idx]
    ts.park()
    mj.mj_forward(dst, d)


def _state_maps(src, dst) -> dict:
    """Index arrays (source, destination) of the state :func:`load_state` copies, by name."""
    mj = deps.mujoco()
    obj = mj.mjtObj
    pairs: dict[str, tuple[list, list]] = {
        k: ([], [])
        for k in ("qpos", "qvel", "ctrl", "jnt_range", "eq_data", "body_pos", "body_quat")
    }
    for j in range(src.njnt):
        jd = mj.mj_name2id(dst, obj.mjOBJ_JOINT, mj.mj_id2name(src, obj.mjOBJ_JOINT, j))
        nq = {0: 7, 1: 4}.get(int(src.jnt_type[j]), 1)
        nv = {0: 6, 1: 3}.get(int(src.jnt_type[j]), 1)
        qa, qb = src.jnt_qposadr[j], dst.jnt_qposadr[jd]
        va, vb = src.jnt_dofadr[j], dst.jnt_dofadr[jd]
        pairs["qpos"][0].extend(range(qa, qa + nq))
        pairs["qpos"][1].extend(range(qb, qb + nq))
        pairs["qvel"][0].extend(range(va, va + nv))
        pairs["qvel"][1].extend(range(vb, vb + nv))
        pairs["jnt_range"][0].append(j)
        pairs["jnt_range"][1].append(jd)
    for kind, src_n, field_names in (
        (obj.mjOBJ_ACTUATOR, src.nu, ("ctrl",)),
        (obj.mjOBJ_EQUALITY, src.neq, ("eq_data",)),
        (obj.mjOBJ_BODY, src.nbody, ("body_pos", "body_quat")),
    ):
        for i in range(1, src_n) if kind == obj.mjOBJ_BODY else range(src_n):
            j = mj.mj_name2id(dst, kind, mj.mj_id2name(src, kind, i))
            for f in field_names:
                pairs[f][0].append(i)
                pairs[f][1].append(j)
    return {
        k: (np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))
        for k, (a, b) in pairs.items()
    }
