"""A MuJoCo model of one hand and one object, built from our own data (no third-party meshes).

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


def _fmt(values) -> str:
    return " ".join(f"{v:.9g}" for v in np.asarray(values, dtype=np.float64).ravel())


def _quat(rotation: np.ndarray) -> np.ndarray:
    mj = deps.mujoco()
    q = np.zeros(4)
    mj.mju_mat2Quat(q, np.ascontiguousarray(rotation, dtype=np.float64).ravel())
    return q


@dataclass
class Scene:
    """A compiled model with the indices the trials need. Not thread-safe (one per process).

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
    fixed_links : list of (int, int)
        (body id, link index) of every link MuJoCo models without a joint (its DOF does
        not close, e.g. the Barrett spread), placed per grasp by
        :func:`~affordgrasp.physics.trials.set_grasp`.
    fingers : list of tuple
        (actuator id, joint id, closing direction ±1, [(equality id, follower joint id,
        speed ratio), ...]) per finger: the servo on its first joint and the couplings.
    closing_joints : list of (int, int, float)
        (MuJoCo joint id, DOF index, ratio) of every closing joint.
    joint_range : (njnt, 2) float64 ndarray
        The joint limits as built (the non-backdrivable ratchet moves the model's).
    finger_geoms : list of (k,) int ndarray
        Per finger (the order of ``fingers``): the hand geoms its driven joint moves.
    palm_geoms : (k,) int ndarray
        The hand geoms no finger moves (the palm and the rigidly placed links).
    anvil_mocap : int
        Mocap index of the anvil.
    plate_body, plate_joint, plate_actuator : int
        Body, slide joint and force actuator of the press plate.
    """

    model: Any  # mujoco.MjModel (the extra is optional: no import at type-check time)
    data: Any  # mujoco.MjData
    hand: Hand
    settings: PhysicsSettings
    mass: MassProperties
    object_name: str
    n_parts: int
    object_body: int
    object_qpos: int  # address of the free joint's 7 qpos
    object_dof: int  # address of its 6 dofs
    fixed_links: list  # (body id, link index) of every link MuJoCo models without a joint
    fingers: list  # (actuator id, joint id, direction, [(eq id, joint id, ratio), ...])
    closing_joints: list  # (MuJoCo joint id, DOF index, ratio) of every closing joint
    joint_range: np.ndarray  # (njnt, 2) the model's joint limits as built (the ratchet moves them)
    anvil_mocap: int
    plate_body: int
    plate_joint: int
    plate_actuator: int
    finger_geoms: list
    palm_geoms: np.ndarray

    @property
    def object_mass(self) -> float:
        """The object's mass, kg."""
        return self.mass.mass


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
    if getattr(obj, "materials", False) and settings.object_mass_kg <= 0:
        # Per-part materials (a dataset made with --materials, a region densities file): the
        # object's own mass, centre of mass and inertia, as its rows were scored with.
        mass = obj.mass
    else:
        mass = mass_properties(obj.mesh, density=settings.density)
        if settings.object_mass_kg > 0:
            # A fixed mass (the DexGraspBench protocol): the same density everywhere, scaled.
            mass = mass_properties(obj.mesh, density=settings.object_mass_kg / mass.volume)
    xml, info = _mjcf(hand, obj.name, parts, mass, settings, object_material)
    try:
        if extend is None:
            model = mj.MjModel.from_xml_string(xml)
        else:
            spec = mj.MjSpec.from_string(xml)
            extend(spec)
            model = spec.compile()
    except ValueError as exc:  # pragma: no cover - a bug in the builder, not user input
        raise InternalError(f"MuJoCo rejected the generated model: {exc}") from exc
    data = mj.MjData(model)

    def body(name):
        return mj.mj_name2id(model, mj.mjtObj.mjOBJ_BODY, name)

    def joint(name):
        return mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, name)

    obj_body = body("object")
    obj_joint = model.body_jntadr[obj_body]
    fixed = [(body(f"link_{li}"), li) for li in info["fixed"]]
    fingers = []
    for act_name, jname, direction, followers in info["fingers"]:
        act = mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, act_name)
        fl = [
            (mj.mj_name2id(model, mj.mjtObj.mjOBJ_EQUALITY, e), joint(j), r)
            for e, j, r in followers
        ]
        fingers.append((act, joint(jname), direction, fl))
    plate = body("plate")
    finger_geoms, palm_geoms = _hand_geoms(model, [f[1] for f in fingers], obj_body)
    return Scene(
        model=model,
        data=data,
        hand=hand,
        settings=settings,
        mass=mass,
        object_name=obj.name,
        n_parts=len(parts),
        object_body=obj_body,
        object_qpos=int(model.jnt_qposadr[obj_joint]),
        object_dof=int(model.jnt_dofadr[obj_joint]),
        fixed_links=fixed,
        fingers=fingers,
        closing_joints=[(joint(f"j_{li}"), di, r) for li, di, r in info["closing_links"]],
        joint_range=model.jnt_range.copy(),
        anvil_mocap=int(model.body_mocapid[body("anvil")]),
        plate_body=plate,
        plate_joint=joint("plate_slide"),
        plate_actuator=mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, "plate_push"),
        finger_geoms=finger_geoms,
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


def _mjcf(hand, name, parts, mass, settings, object_material):
    """The model as MJCF text, and what the Scene needs to know about it."""
    s = settings
    assets: list[str] = []
    finger_of_dof: dict[str, tuple] = {}
    for f in hand.fingers:
        for k, d in enumerate(f.dofs):
            finger_of_dof[d] = (f, k)
    closing_dofs = set(finger_of_dof)
    info: dict[str, list] = {"fixed": [], "fingers": [], "closing_links": []}
    children: dict[str, list[int]] = {}
    for i, link in enumerate(hand.links):
        if link.parent is not None:
            children.setdefault(link.parent, []).append(i)
    joint_name_of_dof: dict[str, tuple[str, float]] = {}
    # MuJoCo takes the larger friction of a pair (object geoms carry 0): torsional friction
    # only with condim 4, rolling never.
    tors = f"{s.torsional_friction:.6g} 0" if s.condim >= 4 else "0 0"

    def link_xml(i: int, indent: str) -> str:
        link = hand.links[i]
        mu = engine_friction(s, friction_coefficient(link.material, object_material))
        lines = []
        j = link.joint
        attrs = ""
        joint_xml = ""
        if j is not None:
            r, t = j.origin[:3, :3], j.origin[:3, 3]
            attrs = f' pos="{_fmt(t)}" quat="{_fmt(_quat(r))}"'
            if j.dof in closing_dofs:
                dof = hand.dofs[hand.dof_index(j.dof)]
                lo, hi = sorted((j.ratio * dof.lower, j.ratio * dof.upper))
                kind = "hinge" if j.kind == "revolute" else "slide"
                joint_xml = (
                    f'{indent}  <joint name="j_{i}" type="{kind}" axis="{_fmt(j.axis)}" '
                    f'range="{lo:.9g} {hi:.9g}" limited="true"/>\n'
                )
                joint_name_of_dof[j.dof] = (f"j_{i}", j.ratio)
                info["closing_links"].append((i, hand.dof_index(j.dof), j.ratio))
            else:
                info["fixed"].append(i)
        lines.append(f'{indent}<body name="link_{i}"{attrs}>\n')
        lines.append(joint_xml)
        for k, shape in enumerate(link.shapes):
            pts = rounded_shape_points(shape.kind, shape.half_extents, shape.radius)
            pts = pts @ shape.pose[:3, :3].T + shape.pose[:3, 3]
            mesh_name = f"hand_{i}_{k}"
            assets.append(f'    <mesh name="{mesh_name}" vertex="{_fmt(pts)}"/>\n')
            lines.append(
                f'{indent}  <geom type="mesh" mesh="{mesh_name}" friction="{mu:.6g} {tors}" '
                f'contype="{_HAND_BITS[0]}" conaffinity="{_HAND_BITS[1]}" condim="{s.condim}" '
                f'density="1000" rgba="0.6 0.6 0.65 1"/>\n'
            )
        if not link.shapes and j is not None:
            # A massless joint carrier (the Barrett spread base): give it a small inertia.
            lines.append(
                f'{indent}  <inertial pos="0 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>\n'
            )
        for c in children.get(link.name, []):
            lines.append(link_xml(c, indent + "  "))
        lines.append(f"{indent}</body>\n")
        return "".join(lines)

    palm_geoms = []
    palm = hand.links[0]
    mu_palm = engine_friction(s, friction_coefficient(palm.material, object_material))
    for k, shape in enumerate(palm.shapes):
        pts = rounded_shape_points(shape.kind, shape.half_extents, shape.radius)
        pts = pts @ shape.pose[:3, :3].T + shape.pose[:3, 3]
        assets.append(f'    <mesh name="palm_{k}" vertex="{_fmt(pts)}"/>\n')
        palm_geoms.append(
            f'      <geom type="mesh" mesh="palm_{k}" friction="{mu_palm:.6g} {tors}" '
            f'contype="{_HAND_BITS[0]}" conaffinity="{_HAND_BITS[1]}" condim="{s.condim}"/>\n'
        )
    finger_xml = "".join(link_xml(c, "      ") for c in children.get(palm.name, []))

    object_geoms = []
    for k, (v, _f) in enumerate(parts):
        assets.append(f'    <mesh name="part_{k}" vertex="{_fmt(v)}"/>\n')
        object_geoms.append(
            f'      <geom type="mesh" mesh="part_{k}" friction="0 0 0" condim="{s.condim}" '
            f'contype="{_OBJECT_BITS[0]}" conaffinity="{_OBJECT_BITS[1]}" mass="0" '
            'rgba="0.8 0.5 0.2 1"/>\n'
        )
    inertia = mass.inertia
    full = [
        inertia[0, 0],
        inertia[1, 1],
        inertia[2, 2],
        inertia[0, 1],
        inertia[0, 2],
        inertia[1, 2],
    ]

    actuators, equalities = [], []
    for f in hand.fingers:
        first = f.dofs[0]
        jname, ratio0 = joint_name_of_dof[first]
        kind = hand.links[int(jname[2:])].joint.kind
        effort = s.grip_torque if kind == "revolute" else s.grip_force
        overshoot = s.overshoot_rad if kind == "revolute" else s.overshoot_m
        # Gain: the servo saturates once the joint lags its target by a fifth of the overshoot.
        kp = 5.0 * effort / overshoot
        act = f"servo_{f.name}"
        actuators.append(
            f'    <position name="{act}" joint="{jname}" kp="{kp:.9g}" kv="{0.1 * kp:.9g}" '
            f'forcerange="{-effort:.9g} {effort:.9g}" forcelimited="true"/>\n'
        )
        followers = []
        for k, d in enumerate(f.dofs[1:], start=1):
            fj, _ratio = joint_name_of_dof[d]
            eq = f"couple_{f.name}_{k}"
            # joint fj = a0 + a1 * joint jname; a0, a1 are set per grasp (Scene.set_grasp).
            equalities.append(
                f'    <joint name="{eq}" joint1="{fj}" joint2="{jname}" polycoef="0 1 0 0 0"/>\n'
            )
            followers.append((eq, fj, f.speeds[k] / f.speeds[0]))
        direction = 1.0 if ratio0 > 0 else -1.0
        info["fingers"].append((act, jname, direction, followers))

    xml = f"""<mujoco model="affordgrasp-{hand.name}">
  <compiler angle="radian" inertiafromgeom="true" boundmass="1e-4" boundinertia="1e-9"/>
  <option timestep="{s.timestep:.9g}" gravity="0 0 {-G if s.gravity else 0.0:.9g}"
          integrator="implicitfast" cone="elliptic" impratio="{s.impratio:.9g}"
          noslip_iterations="{int(s.noslip_iterations)}"/>
  <default>
    <joint armature="0.01" damping="0.05" solreflimit="{s.contact_timeconst:.9g} 1"
           solimplimit="0.95 0.99 0.001"/>
    <geom solref="{s.contact_timeconst:.9g} 1" solimp="{s.contact_solimp_low:.9g} 0.99 0.001"/>
    <equality solref="{s.contact_timeconst:.9g} 1" solimp="0.95 0.99 0.001"/>
  </default>
  <asset>
{"".join(assets)}  </asset>
  <worldbody>
    <body name="link_0">
{"".join(palm_geoms)}{finger_xml}    </body>
    <body name="object" pos="0 0 0.5">
      <freejoint name="object_free"/>
      <inertial pos="{_fmt(mass.center_of_mass)}" mass="{mass.mass:.9g}"
                fullinertia="{_fmt(full)}"/>
{"".join(object_geoms)}    </body>
    <body name="anvil" mocap="true" pos="{FAR} {FAR} {FAR}">
      <geom type="box" size="{TOOL_HALF} {TOOL_HALF} {TOOL_HALF}" pos="0 0 {TOOL_HALF}"
            friction="0 0 0" condim="3" contype="{_TOOL_BITS[0]}" conaffinity="{_TOOL_BITS[1]}"/>
    </body>
    <body name="plate" pos="{-FAR} {-FAR} {-FAR}">
      <joint name="plate_slide" type="slide" axis="0 0 1" armature="0" damping="0"
             limited="false"/>
      <geom type="box" size="{TOOL_HALF} {TOOL_HALF} {TOOL_HALF}" pos="0 0 {TOOL_HALF}"
            friction="0 0 0" condim="3" mass="0.02"
            contype="{_TOOL_BITS[0]}" conaffinity="{_TOOL_BITS[1]}"/>
    </body>
  </worldbody>
  <actuator>
{"".join(actuators)}    <motor name="plate_push" joint="plate_slide" gear="-1"/>
  </actuator>
  <equality>
{"".join(equalities)}  </equality>
</mujoco>
"""
    if not parts:
        raise InputError(f"object {name!r} has no convex parts to simulate")
    return xml, info
