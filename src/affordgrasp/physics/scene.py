"""A MuJoCo model of one hand and one object, built as a ``mujoco.MjSpec`` from our own data.

No third-party meshes, no MJCF text: bodies, joints, geoms and actuators are spec objects,
named (``link_{i}``, ``j_{i}``, ``object``, ``servo_{finger}``, ``anvil``, ``plate``...), and
the scene looks their ids up by name in the compiled model.

* The hand frame is the world frame: the palm is fixed at the origin, and the object, a free
  body, is placed at the inverse of the grasp's hand → object transform. With gravity off
  (the default) this is the hand's view of any grasp.
* Each link shape (a sphere-swept box or cylinder, see :mod:`affordgrasp.hands.model`) becomes
  a convex mesh geom through support points of the rounded shape, so the engine sees the
  same rounded links as the grasp simulator.
* Joints: a closing DOF's joint becomes a MuJoCo hinge/slide joint with its limits. In every
  finger, the first DOF is driven by a position servo with a saturated effort; the later
  DOFs follow it through the finger's closing ratios (equality constraints, e.g. the
  Barrett distal at 1/3 of the proximal, offset so that the grasp's joint values hold).
  Links moved by a pregrasp DOF (the Barrett spread) are placed rigidly per grasp.
* The object collides as its convex parts (:mod:`.decompose`); its mass, centre of mass and
  inertia are those of the ORIGINAL mesh at ``settings.density``, or its per-part
  materials' when it has them (a dataset made with ``--materials``).
* Friction: every hand geom carries μ(link material, object material) from the material
  table (or ``settings.friction`` when set), object geoms μ = 0; MuJoCo takes the larger
  of a pair, so each contact gets that μ. Contacts are point contacts with friction
  (condim 3), as the metrics assume, unless ``settings.condim`` says otherwise (the
  DexGraspBench protocol: 4, with torsional friction).
* Two tools for the use tests, off stage during the hold test: a fixed anvil (mocap body)
  and a plate on a slide joint pushed by a force actuator; both are frictionless 10 mm
  cubes (a local obstacle at the use point that pushes only along its normal).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, InternalError
from ..hands import Hand, get_hand
from ..materials import DEFAULT_OBJECT_MATERIAL, friction_coefficient
from ..objects.mass import MassProperties, mass_properties
from ..tolerances import ZERO_LENGTH
from . import deps
from .decompose import convex_parts
from .settings import G, PhysicsSettings

__all__ = ["Scene", "build_scene", "engine_friction", "rounded_shape_points"]

FAR = 10.0  # m: where the tools wait, well away from anything
TOOL_HALF = 0.005  # m: the anvil and the plate are 10 mm cubes (a local obstacle at U)
_OBJECT_BITS = (1, 2 | 4)  # contype, conaffinity: the object touches the hand and the tools
_HAND_BITS = (2, 1)
_TOOL_BITS = (4, 1)


def _fibonacci_directions(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5**0.5) * i
    r = np.sqrt(1.0 - z * z)
    dirs = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    # The 26 face, edge and corner directions too, so that flat faces stay flat.
    grid = np.array(list(np.ndindex(3, 3, 3)), dtype=np.float64) - 1.0
    grid = grid[np.any(grid != 0, axis=1)]
    return np.concatenate([dirs, grid / np.linalg.norm(grid, axis=1, keepdims=True)])


# 600 directions: the hull of the support points stays within 1.5 % of the rounding radius
# of the true rounded shape (0.11 mm for the Barrett's 8 mm), under the grasp simulator's
# contact tolerance (0.2 mm). 96 directions left gaps of 0.6 mm at the rounded corners.
_DIRECTIONS = _fibonacci_directions(600)


def rounded_shape_points(kind: str, half_extents, radius: float) -> np.ndarray:
    """Support points of a sphere-swept box or cylinder, in the shape frame.

    Their convex hull is inscribed in the rounded shape and touches it in every sampled
    direction (flat faces exactly, rounded parts within 1.5 % of the radius).

    Parameters
    ----------
    kind : str
        ``"box"`` or ``"cylinder"`` (axis z).
    half_extents : (3,) array_like of float
        Half extents of the core, m (a cylinder uses the first as its radius and the third
        as its half height).
    radius : float
        Rounding radius, m.

    Returns
    -------
    (n, 3) float64 ndarray
        Distinct points, m (n <= 626).
    """
    h = np.asarray(half_extents, dtype=np.float64)
    d = _DIRECTIONS
    if kind == "box":
        core = np.sign(d) * h
    else:  # cylinder: core radius h[0], half height h[2], axis z
        xy = d[:, :2]
        norm = np.linalg.norm(xy, axis=1, keepdims=True)
        rim = np.where(norm > ZERO_LENGTH, xy / np.maximum(norm, ZERO_LENGTH), 0.0) * h[0]
        core = np.concatenate([rim, np.sign(d[:, 2:]) * h[2]], axis=1)
    return np.unique(np.round(core + radius * d, 12), axis=0)


def engine_friction(settings: PhysicsSettings, mu: float) -> float:
    """The friction coefficient the engine gives a hand-object pair whose table μ is ``mu``.

    ``settings.friction`` (> 0) replaces the table. Otherwise the friction cone is widened by
    ``settings.friction_margin_deg``: μ' = tan(atan μ + δ). A force inside the cone of
    half-angle atan μ about the mesh's normal is inside the cone of half-angle atan μ + δ
    about any normal within δ of it, so a grasp in force closure on the mesh stays in force
    closure on collision geometry whose normals are off by at most δ.

    Parameters
    ----------
    settings : PhysicsSettings
    mu : float
        μ of the material table, > 0.

    Returns
    -------
    float
    """
    import math

    if settings.friction:
        return float(settings.friction)
    if not settings.friction_margin_deg:
        return float(mu)
    return math.tan(math.atan(mu) + math.radians(settings.friction_margin_deg))


def table_friction(settings: PhysicsSettings, mu_engine: np.ndarray) -> np.ndarray:
    """Invert :func:`engine_friction` for table friction: the table μ of engine coefficients.

    Parameters
    ----------
    settings : PhysicsSettings
    mu_engine : (k,) float ndarray

    Returns
    -------
    (k,) float64 ndarray
        Unchanged when ``settings.friction`` is set or there is no margin.
    """
    mu_engine = np.asarray(mu_engine, dtype=np.float64)
    if settings.friction or not settings.friction_margin_deg:
        return mu_engine
    return np.tan(np.arctan(mu_engine) - np.radians(settings.friction_margin_deg))


def _written(values, digits: int = 9):
    """``values`` to ``digits`` significant digits, as the model's numbers have always been.

    The model was first written as MJCF text with 9 significant digits (6 for friction);
    keeping that precision keeps every replay bit for bit what it was.
    """
    out = np.array([float(f"{v:.{digits}g}") for v in np.ravel(values)])
    return float(out[0]) if np.ndim(values) == 0 else out


def rotation_quat(rotation: np.ndarray) -> np.ndarray:
    """The unit quaternion of a rotation matrix.

    Parameters
    ----------
    rotation : (3, 3) float ndarray

    Returns
    -------
    (4,) float64 ndarray
        (w, x, y, z), MuJoCo's order.
    """
    mj = deps.mujoco()
    q = np.zeros(4)
    mj.mju_mat2Quat(q, np.ascontiguousarray(rotation, dtype=np.float64).ravel())
    return q


@dataclass(frozen=True)
class Coupling:
    """A joint that follows its finger's driven joint: ``joint = a0 + gain · driven``.

    Attributes
    ----------
    equality : int
        MuJoCo id of the joint equality (a0 and gain are set per grasp).
    joint : int
        MuJoCo id of the following joint.
    gain : float
        Its motion per unit of the driven joint's (the closing speeds' and the joint
        ratios' quotient: the Barrett distal's is 1/3).
    """

    equality: int
    joint: int
    gain: float


@dataclass(frozen=True)
class FingerDrive:
    """A finger's position servo on its first closing joint, and the joints coupled to it.

    Attributes
    ----------
    servo : int
        MuJoCo id of the position actuator.
    joint : int
        MuJoCo id of the driven joint.
    closing : float
        +1 or -1: the direction the driven joint closes in.
    couplings : tuple of Coupling
    geoms : (k,) int ndarray
        The hand geoms the driven joint moves.
    """

    servo: int
    joint: int
    closing: float
    couplings: tuple[Coupling, ...]
    geoms: np.ndarray


@dataclass
class Scene:
    """A compiled model and the MuJoCo ids the trials need. Not thread-safe (one per process).

    The tools are found by name: bodies ``anvil`` (mocap) and ``plate``, the plate's joint
    ``plate_slide`` and actuator ``plate_push`` (``model.body("plate")``).

    Attributes
    ----------
    model : mujoco.MjModel
    data : mujoco.MjData
    hand : Hand
        The hand modelled.
    settings : PhysicsSettings
    mass : MassProperties
        Of the original mesh at ``settings.density`` (or of its per-part materials).
    object_name : str
    n_parts : int
        Convex parts the object collides as.
    object_body : int
        MuJoCo body id of the object.
    object_qpos, object_dof : int
        Addresses of the object's free joint: its 7 qpos (position, quaternion) and its 6
        dofs.
    rigid_links : dict of int to int
        Hand link index → MuJoCo body id of every link MuJoCo models without a joint (its
        DOF does not close, e.g. the Barrett spread), placed per grasp by
        :func:`~affordgrasp.physics.trials.set_grasp`.
    closing_joints : dict of int to int
        Hand link index → MuJoCo joint id of every closing joint.
    fingers : list of FingerDrive
        Per finger of the hand.
    joint_range : (njnt, 2) float64 ndarray
        The joint limits as built (the non-backdrivable ratchet moves the model's).
    palm_geoms : (k,) int ndarray
        The hand geoms no finger moves (the palm and the rigidly placed links).
    """

    model: Any  # mujoco.MjModel (the extra is optional: no import at type-check time)
    data: Any  # mujoco.MjData
    hand: Hand
    settings: PhysicsSettings
    mass: MassProperties
    object_name: str
    n_parts: int
    object_body: int
    object_qpos: int
    object_dof: int
    rigid_links: dict[int, int]
    closing_joints: dict[int, int]
    fingers: list[FingerDrive]
    joint_range: np.ndarray
    palm_geoms: np.ndarray

    @property
    def object_mass(self) -> float:
        """The object's mass, kg."""
        return self.mass.mass

    @property
    def finger_geoms(self) -> list[np.ndarray]:
        """Per finger (the order of ``fingers``): the hand geoms its driven joint moves."""
        return [f.geoms for f in self.fingers]


def build_scene(
    hand: Hand | str,
    obj,
    settings: PhysicsSettings | None = None,
    *,
    object_material: str = DEFAULT_OBJECT_MATERIAL,
    parts: list | None = None,
    extend: Callable[[Any], None] | None = None,
) -> Scene:
    """Compile the MuJoCo model of ``hand`` and ``obj`` (see the module docstring).

    Parameters
    ----------
    hand : Hand or str
        A Hand, a registered name or a hand file.
    obj : GraspObject
        The object, in its own frame. Its mass properties are used when they follow
        per-part materials (``obj.materials``); otherwise the object weighs
        ``settings.density`` × its volume (or ``settings.object_mass_kg``).
    settings : PhysicsSettings, optional
        The protocol; the defaults when None.
    object_material : str
        The object's material in the friction table.
    parts : list of (vertices, faces), optional
        Convex parts of the object, m; default: the cached CoACD decomposition of
        ``obj.mesh``.
    extend : callable, optional
        ``extend(spec)`` adds to the model's ``mujoco.MjSpec`` before it is compiled (the
        task trials' rig, :mod:`.task_scene`); None: the model as described above.

    Returns
    -------
    Scene
    """
    mj = deps.mujoco()
    settings = settings or PhysicsSettings()
    hand = get_hand(hand)
    if parts is None:
        parts = convex_parts(obj.mesh, obj.mesh_hash, settings)
    if not parts:
        raise InputError(f"object {obj.name!r} has no convex parts to simulate")
    if getattr(obj, "materials", False) and settings.object_mass_kg <= 0:
        # Per-part materials (a dataset made with --materials, a region densities file): the
        # object's own mass, centre of mass and inertia, as its rows were scored with.
        mass = obj.mass
    else:
        mass = mass_properties(obj.mesh, density=settings.density)
        if settings.object_mass_kg > 0:
            # A fixed mass (the DexGraspBench protocol): the same density everywhere, scaled.
            mass = mass_properties(obj.mesh, density=settings.object_mass_kg / mass.volume)
    try:
        spec = _model_spec(hand, parts, mass, settings, object_material)
        if extend is not None:
            extend(spec)
        model = spec.compile()
    except ValueError as exc:  # pragma: no cover - a bug in the builder, not user input
        raise InternalError(f"MuJoCo rejected the model: {exc}") from exc
    links = _closing_links(hand)
    drivers = [model.joint(f"j_{links[f.dofs[0]]}").id for f in hand.fingers]
    obj_body = model.body("object").id
    geoms, palm_geoms = _hand_geoms(model, drivers, obj_body)
    fingers = []
    for f, jid, finger_geoms in zip(hand.fingers, drivers, geoms, strict=True):
        ratio = hand.links[links[f.dofs[0]]].joint.ratio
        couplings = tuple(
            Coupling(
                model.equality(f"couple_{f.name}_{k}").id,
                model.joint(f"j_{links[d]}").id,
                hand.links[links[d]].joint.ratio * (f.speeds[k] / f.speeds[0]) / ratio,
            )
            for k, d in enumerate(f.dofs[1:], start=1)
        )
        servo = model.actuator(f"servo_{f.name}").id
        closing = 1.0 if ratio > 0 else -1.0
        fingers.append(FingerDrive(servo, jid, closing, couplings, finger_geoms))
    free = model.joint("object_free")
    jointed = [i for i, link in enumerate(hand.links) if link.joint is not None]
    return Scene(
        model=model,
        data=mj.MjData(model),
        hand=hand,
        settings=settings,
        mass=mass,
        object_name=obj.name,
        n_parts=len(parts),
        object_body=obj_body,
        object_qpos=int(free.qposadr[0]),
        object_dof=int(free.dofadr[0]),
        rigid_links={
            i: model.body(f"link_{i}").id for i in jointed if hand.links[i].joint.dof not in links
        },
        closing_joints={
            i: model.joint(f"j_{i}").id for i in jointed if hand.links[i].joint.dof in links
        },
        fingers=fingers,
        joint_range=model.jnt_range.copy(),
        palm_geoms=palm_geoms,
    )


def _hand_geoms(model, driver_joints: list[int], object_body: int):
    """The geoms each finger's driven joint moves, and the hand's other geoms (the palm's)."""
    n_body = model.nbody
    parent = model.body_parentid
    driver_body = [int(model.jnt_bodyid[j]) for j in driver_joints]
    owner = np.full(n_body, -1)
    for b in range(1, n_body):
        a = b
        while a > 0:
            if a in driver_body:
                owner[b] = driver_body.index(a)
                break
            a = parent[a]
    geom_body = model.geom_bodyid
    hand = (model.geom_contype & _HAND_BITS[0]) != 0
    hand &= geom_body != object_body
    fingers = [np.flatnonzero(hand & (owner[geom_body] == k)) for k in range(len(driver_body))]
    palm = np.flatnonzero(hand & (owner[geom_body] < 0))
    return fingers, palm


def _closing_links(hand: Hand) -> dict[str, int]:
    """Closing DOF → the index of the link whose joint it drives (the last one, if several)."""
    closing = {d for f in hand.fingers for d in f.dofs}
    return {
        link.joint.dof: i
        for i, link in enumerate(hand.links)
        if link.joint is not None and link.joint.dof in closing
    }


def _model_spec(hand: Hand, parts, mass: MassProperties, settings, object_material: str):
    """The model as a ``mujoco.MjSpec`` (see the module docstring), not yet compiled."""
    mj = deps.mujoco()
    s = settings
    spec = mj.MjSpec()
    spec.modelname = f"affordgrasp-{hand.name}"
    spec.compiler.degree = False
    spec.compiler.inertiafromgeom = mj.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE
    spec.compiler.boundmass, spec.compiler.boundinertia = 1e-4, 1e-9
    opt = spec.option
    opt.timestep, opt.impratio = _written([s.timestep, s.impratio])
    opt.gravity = [0.0, 0.0, _written(-G if s.gravity else 0.0)]
    opt.integrator, opt.cone = mj.mjtIntegrator.mjINT_IMPLICITFAST, mj.mjtCone.mjCONE_ELLIPTIC
    opt.noslip_iterations = int(s.noslip_iterations)
    solref = [_written(s.contact_timeconst), 1.0]
    solimp = [0.95, 0.99, 0.001, 0.5, 2.0]  # MuJoCo's defaults but the first
    main = spec.default
    main.joint.armature, main.joint.damping = 0.01, [0.05, 0.0, 0.0]
    main.joint.solref_limit, main.joint.solimp_limit = solref, solimp
    main.geom.solref = solref
    main.geom.solimp = [_written(s.contact_solimp_low), *solimp[1:]]
    main.geom.type, main.geom.condim = mj.mjtGeom.mjGEOM_MESH, s.condim
    main.equality.solref, main.equality.solimp = solref, solimp
    # Geom classes: the object touches the hand and the tools; the tools are frictionless
    # cubes occupying +z of their frames (a local obstacle at U).
    hand_class = spec.add_default("hand", main)
    hand_class.geom.contype, hand_class.geom.conaffinity = _HAND_BITS
    hand_class.geom.rgba = [0.6, 0.6, 0.65, 1.0]
    object_class = spec.add_default("object", main)
    part = object_class.geom
    part.contype, part.conaffinity = _OBJECT_BITS
    part.friction, part.mass, part.rgba = [0.0] * 3, 0.0, [0.8, 0.5, 0.2, 1.0]
    tool_class = spec.add_default("tool", main)
    tool = tool_class.geom
    tool.contype, tool.conaffinity, tool.condim = *_TOOL_BITS, 3
    tool.type, tool.size, tool.pos = mj.mjtGeom.mjGEOM_BOX, [TOOL_HALF] * 3, [0, 0, TOOL_HALF]
    tool.friction = [0.0] * 3
    # MuJoCo takes the larger friction of a pair (object geoms carry 0): torsional friction
    # only with condim 4, rolling never.
    torsional = _written(s.torsional_friction, 6) if s.condim >= 4 else 0.0
    links = _closing_links(hand)
    children: dict[str, list[int]] = {}
    for i, link in enumerate(hand.links[1:], start=1):
        children.setdefault(link.parent, []).append(i)

    def add_link(parent, i: int) -> None:
        link, j = hand.links[i], hand.links[i].joint
        body = parent.add_body(name=f"link_{i}")
        if j is not None:
            body.pos = _written(j.origin[:3, 3])
            body.quat = _written(rotation_quat(j.origin[:3, :3]))
        if j is not None and j.dof in links:
            dof = hand.dofs[hand.dof_index(j.dof)]
            body.add_joint(
                name=f"j_{i}",
                type=mj.mjtJoint.mjJNT_HINGE if j.kind == "revolute" else mj.mjtJoint.mjJNT_SLIDE,
                axis=_written(j.axis),
                range=_written(sorted((j.ratio * dof.lower, j.ratio * dof.upper))),
                limited=mj.mjtLimited.mjLIMITED_TRUE,
            )
        mu = engine_friction(s, friction_coefficient(link.material, object_material))
        for k, shape in enumerate(link.shapes):
            pts = rounded_shape_points(shape.kind, shape.half_extents, shape.radius)
            pts = pts @ shape.pose[:3, :3].T + shape.pose[:3, 3]
            spec.add_mesh(name=f"hand_{i}_{k}", uservert=_written(pts))
            friction = [_written(mu, 6), torsional, 0.0]
            body.add_geom(hand_class, meshname=f"hand_{i}_{k}", friction=friction)
        if not link.shapes and j is not None:
            # A massless joint carrier (the Barrett spread base): give it a small inertia.
            body.explicitinertial, body.mass, body.inertia = True, 0.01, [1e-6] * 3
            body.ipos = [0.0, 0.0, 0.0]
        for c in children.get(link.name, []):
            add_link(body, c)

    add_link(spec.worldbody, 0)
    obj = spec.worldbody.add_body(name="object", pos=[0.0, 0.0, 0.5])
    obj.add_freejoint(name="object_free")
    obj.explicitinertial, obj.mass = True, _written(mass.mass)
    obj.ipos = _written(mass.center_of_mass)
    i = mass.inertia
    obj.fullinertia = _written([i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]])
    for k, (vertices, _faces) in enumerate(parts):
        spec.add_mesh(name=f"part_{k}", uservert=_written(vertices))
        obj.add_geom(object_class, meshname=f"part_{k}")
    spec.worldbody.add_body(name="anvil", mocap=True, pos=[FAR] * 3).add_geom(tool_class)
    plate = spec.worldbody.add_body(name="plate", pos=[-FAR] * 3)
    plate.add_joint(
        name="plate_slide",
        type=mj.mjtJoint.mjJNT_SLIDE,
        axis=[0.0, 0.0, 1.0],
        armature=0.0,
        damping=[0.0, 0.0, 0.0],
        limited=mj.mjtLimited.mjLIMITED_FALSE,
    )
    plate.add_geom(tool_class, mass=0.02)
    joint_trn = mj.mjtTrn.mjTRN_JOINT
    for f in hand.fingers:
        driven = f"j_{links[f.dofs[0]]}"
        revolute = hand.links[links[f.dofs[0]]].joint.kind == "revolute"
        effort = s.grip_torque if revolute else s.grip_force
        overshoot = s.overshoot_rad if revolute else s.overshoot_m
        # Gain: the servo saturates once the joint lags its target by a fifth of the overshoot.
        kp = _written(5.0 * effort / overshoot)
        servo = spec.add_actuator(name=f"servo_{f.name}", target=driven, trntype=joint_trn)
        servo.forcerange, servo.forcelimited = _written([-effort, effort]), True
        servo.set_to_position(kp=kp, kv=_written(0.1 * kp))
        for k, d in enumerate(f.dofs[1:], start=1):
            # joint of d = a0 + a1 · driven joint; a0, a1 are set per grasp (set_grasp).
            spec.add_equality(
                name=f"couple_{f.name}_{k}",
                type=mj.mjtEq.mjEQ_JOINT,
                name1=f"j_{links[d]}",
                name2=driven,
            )
    push = spec.add_actuator(name="plate_push", target="plate_slide", trntype=joint_trn)
    push.gear[0] = -1.0
    push.set_to_motor()
    return spec
