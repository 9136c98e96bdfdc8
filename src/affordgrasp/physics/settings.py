"""Every number of the physics validation in one frozen record (documented in docs/physics.md).

The defaults are the protocol the reported numbers were measured with; change them through
:class:`PhysicsSettings` (Python) or the options of ``affordgrasp physics``.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, fields

from ..errors import InputError

G = 9.81  # m/s^2
PROTOCOLS = ("affordgrasp", "dgb")
_MAY_BE_ZERO = (
    "seed",
    "settle_time",
    "impact_settle",
    "friction",
    "noslip_iterations",
    "object_mass_kg",
    "friction_margin_deg",
)


# Physical ranges (low, high, unit): what a hand grasping a hand-held object can mean. A value
# outside is a typo or a unit mistake (milliseconds for seconds, grams for kilograms).
PHYSICAL_RANGES: dict[str, tuple[float, float, str]] = {
    "timestep": (1e-5, 0.01, "s"),
    "density": (1.0, 25_000.0, "kg/m^3"),  # aerogel to osmium
    "grip_torque": (1e-3, 100.0, "N·m"),
    "grip_force": (1e-2, 1000.0, "N"),
    "load_factor": (1e-3, 100.0, "(× m·g)"),
    "impact_factor": (1e-3, 100.0, "(× m·g·lever)"),
    "squeeze_time": (1e-3, 10.0, "s"),
    "settle_time": (0.0, 10.0, "s"),
    "hold_ramp": (1e-3, 10.0, "s"),
    "hold_time": (1e-3, 30.0, "s"),
    "impact_time": (1e-3, 10.0, "s"),
    "impact_settle": (0.0, 10.0, "s"),
    "press_rate": (1e-2, 1e4, "N/s"),
    "press_max_force": (1e-2, 1000.0, "N"),
    "contact_timeconst": (1e-4, 0.1, "s"),
    "friction_margin_deg": (0.0, 30.0, "°"),
}
MIN_STEPS_PER_PHASE = 10


@dataclass(frozen=True)
class PhysicsSettings:
    """The validation protocol: simulation, grip, the three trials and their pass limits.

    Units are SI (s, m, rad, N, N·m, kg/m^3). Every value must be finite, and positive except
    ``seed``, ``settle_time`` and ``impact_settle`` (>= 0); ``hold_ramp < hold_time``. A bad
    value raises :class:`~affordgrasp.errors.InputError` naming the setting.

    Attributes
    ----------
    timestep : float
        Simulation step, s.
    density : float
        kg/m^3; the object's mass is density × the volume of the original mesh.
    gravity : bool
        Gravity along -z of the hand frame; off by default (the six hold loads stand in for
        gravity in every direction).
    impratio : float
        MuJoCo's friction-to-normal impedance ratio (stiffer friction, less creep).
    contact_timeconst : float
        Time constant of contacts, joint limits and couplings, s.
    grip_torque : float
        Saturated effort of a revolute closing servo, N·m.
    grip_force : float
        Saturated effort of a prismatic closing servo, N.
    overshoot_rad, overshoot_m : float
        How far past the grasp's joint value the servo target ends, rad (revolute) or m
        (prismatic).
    backdrivable : bool
        False: the load cannot push a finger open (worm drive, lead screw); True: a
        torque-limited servo the load can backdrive.
    squeeze_time, settle_time : float
        The servo target ramps over ``squeeze_time`` s, then is held ``settle_time`` s.
    settled_speed, settled_spin : float
        At rest after the squeeze: linear speed below this, m/s, and angular speed below
        this, rad/s.
    load_factor : float
        k of the hold test: a force k·m·g at the centre of mass along ±x, ±y, ±z of the
        object frame.
    hold_ramp, hold_time : float
        The load rises linearly over ``hold_ramp`` s, then stays; ``hold_time`` s per
        direction, ramp included.
    max_shift_m, max_angle_rad : float
        A direction holds when the object moved less than this, m, and turned less than
        this, rad.
    impact_factor : float
        Peak torque of the impact pulse about the wrist axis = factor · m·g · (distance of the
        use point from the axis).
    impact_time, impact_settle : float
        Half-sine pulse duration and the wait after it, s.
    impact_max_angle_rad : float
        The impact passes when the object turned less than this, rad.
    press_rate : float
        The press plate's force rises at this rate, N/s.
    press_max_force : float
        The press stops here, N (the grasp did not slip).
    press_slip_m : float
        Slip: the use point moved this far relative to the hand, m.
    coacd_threshold, coacd_max_hulls, coacd_resolution : float, int, int
        Convex decomposition (coacd): concavity threshold, most hulls, voxel resolution.
    coacd_mcts_iterations, coacd_mcts_nodes, coacd_mcts_depth : int
        coacd's tree search.
    seed : int
        coacd's random search.
    protocol : str
        The name of the protocol these settings follow (``"affordgrasp"`` or ``"dgb"``,
        see :func:`protocol_settings`); recorded with the outcomes.
    friction : float
        0: every contact gets μ(link material, object material) from the material table;
        > 0: every hand-object contact gets this μ.
    friction_margin_deg : float
        With the material table: the engine's friction cones are this much wider than the
        table's, degrees (μ' = tan(atan μ + δ); see
        :func:`~affordgrasp.physics.scene.engine_friction`); 0: the table's μ.
    torsional_friction : float
        Torsional friction coefficient of the hand geoms, m (used with ``condim`` 4 only).
    condim : int
        MuJoCo contact dimensionality of hand-object contacts: 3 (point contact with
        friction, as the metrics assume) or 4 (plus torsional friction).
    noslip_iterations : int
        MuJoCo's post-solve no-slip iterations (0: off).
    contact_solimp_low : float
        The first value of MuJoCo's contact ``solimp`` (impedance at zero penetration).
    object_mass_kg : float
        0: the object's mass is ``density`` × its volume; > 0: this mass, kg (centre of mass
        and inertia scaled from the mesh's).
    displacement_from : str
        Where the hold test measures displacement from: ``"squeezed"`` (the pose after the
        squeeze) or ``"placed"`` (the pose before the squeeze, as DexGraspBench).
    backoff : bool
        Before the squeeze, open every finger that starts deeper than ``backoff_depth_m``
        in the object's collision geometry, and push the object off the palm, until each
        touches at most that deep (see docs/physics.md).
    backoff_depth_m : float
        The deepest initial penetration the back-off leaves, m.
    """

    # Simulation.
    timestep: float = 0.002
    density: float = 1000.0  # kg/m^3: the object mass is density × the ORIGINAL mesh volume
    gravity: bool = False  # the hold test's six loads stand in for gravity in every direction
    impratio: float = 10.0  # MuJoCo: stiffer friction than normal constraints (less creep)
    # Stiffness of contacts, joint limits and couplings: MuJoCo's constraint time constant
    # (twice the time step, the stiffest it advises). Its default 0.02 s lets a 20 N squeeze
    # sink 3 mm into a 0.1 kg box.
    contact_timeconst: float = 0.004
    # Grip: the first joint of every finger is a position servo with a saturated effort,
    # the others follow it through the finger's closing ratios.
    grip_torque: float = 1.5  # N·m, revolute closing joints (Barrett: about 15 N at the tip)
    grip_force: float = 20.0  # N, prismatic closing joints (a jaw)
    overshoot_rad: float = 0.3  # the servo target ends this far past the grasp's joint value
    overshoot_m: float = 0.015
    # Non-backdrivable fingers (the Barrett's worm drives, a jaw's lead screw): the load can
    # not push a finger open; the servo can still close it. False: a torque-limited servo
    # that the load can backdrive.
    backdrivable: bool = False
    squeeze_time: float = 0.15  # s: the target ramps over this time (a step target tunnels)
    settle_time: float = 0.05  # s: then held still before the trials
    settled_speed: float = 0.02  # m/s: at rest after the squeeze (gravity off: an object
    settled_spin: float = 0.5  # rad/s    pushed out of the hand keeps drifting)
    # Hold test.
    load_factor: float = 1.0  # k
    hold_ramp: float = 0.05  # s: the load rises linearly, then stays
    hold_time: float = 0.25  # s: total duration per direction, ramp included
    max_shift_m: float = 0.01  # pass: the object moved less than this ...
    max_angle_rad: float = math.radians(10.0)  # ... and turned less than this, in every direction
    # Impact test (E_i): a torque pulse about the wrist axis, use point against an anvil.
    impact_factor: float = 1.0  # peak torque = factor · m·g · (distance of U from the axis)
    impact_time: float = 0.05  # s: pulse duration (half-sine)
    impact_settle: float = 0.1  # s: after the pulse, before measuring
    impact_max_angle_rad: float = math.radians(10.0)
    # Press test (U_τ): a plate pushes on the use point with a force rising at this rate.
    press_rate: float = 100.0  # N/s
    press_max_force: float = 30.0  # N: the test stops here (the grasp did not slip)
    press_slip_m: float = 0.005  # slip: the use point moved this far relative to the hand
    # Convex decomposition of the object (coacd); part of the cache key.
    coacd_threshold: float = 0.05
    coacd_max_hulls: int = 24
    coacd_resolution: int = 1000
    coacd_mcts_iterations: int = 60
    coacd_mcts_nodes: int = 10
    coacd_mcts_depth: int = 3
    seed: int = 0  # coacd's random search
    # Protocol variants (docs/physics.md lists both protocols constant by constant).
    protocol: str = "affordgrasp"
    friction: float = 0.0  # 0: the material table; > 0: every hand-object contact
    # The engine's contact normals on the convex parts are off the mesh's by 3.0° (median) and
    # 8.1° (90th percentile) at the grasps' contacts: widen the table's cones by that much.
    friction_margin_deg: float = 8.0
    torsional_friction: float = 0.005  # m: MuJoCo's default, used with condim 4 only
    condim: int = 3  # point contacts with friction, as the metrics assume
    noslip_iterations: int = 0
    contact_solimp_low: float = 0.95
    object_mass_kg: float = 0.0  # 0: density × volume
    displacement_from: str = "squeezed"  # or "placed" (the pose before the squeeze)
    # The start: CoACD parts stick out of the mesh that the grasp simulator used, so a
    # grasp touching the mesh can start inside a part. Open such fingers / push the object
    # off the palm until no hand geom is deeper than this (the simulator's stop distance).
    backoff: bool = True
    backoff_depth_m: float = 5e-5

    def __post_init__(self) -> None:
        if self.protocol not in PROTOCOLS:
            raise InputError(
                f"physics protocol {self.protocol!r} is unknown; choose one of {sorted(PROTOCOLS)}"
            )
        if self.displacement_from not in ("squeezed", "placed"):
            raise InputError(
                f"physics setting displacement_from must be 'squeezed' or 'placed', got "
                f"{self.displacement_from!r}"
            )
        if self.condim not in (1, 3, 4, 6):
            raise InputError(f"physics setting condim must be 1, 3, 4 or 6, got {self.condim!r}")
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or f.name in ("protocol", "displacement_from"):
                continue
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise InputError(f"physics setting {f.name} must be a finite number, got {value!r}")
            if value < 0 or (value == 0 and f.name not in _MAY_BE_ZERO):
                raise InputError(f"physics setting {f.name} must be > 0, got {value!r}")
        for name, (low, high, unit) in PHYSICAL_RANGES.items():
            value = getattr(self, name)
            if not low <= value <= high:
                raise InputError(
                    f"physics setting {name} = {value!r} {unit} is outside its physical range "
                    f"[{low:g}, {high:g}] {unit}"
                )
        # MuJoCo resolves a soft contact only if its time constant spans two steps or more,
        # and a ramp or pulse only if it spans several: a coarser step runs, but reports
        # holds and slips that are artefacts of the integrator.
        shortest = min(self.squeeze_time, self.hold_ramp, self.impact_time)
        limit = min(self.contact_timeconst / 2, shortest / MIN_STEPS_PER_PHASE)
        if self.timestep > limit:
            raise InputError(
                f"physics setting timestep = {self.timestep!r} s is too coarse: at most "
                f"{limit:g} s (half the contact time constant {self.contact_timeconst:g} s, "
                f"and {MIN_STEPS_PER_PHASE} steps in the shortest phase, {shortest:g} s)"
            )
        if self.hold_ramp >= self.hold_time:
            raise InputError(
                f"hold_ramp ({self.hold_ramp} s) must be shorter than hold_time "
                f"({self.hold_time} s)"
            )

    def to_dict(self) -> dict:
        """Every setting by name.

        Returns
        -------
        dict of str to float, int or bool
        """
        return asdict(self)

    def digest(self) -> str:
        """A short stable hash of every setting (outputs record it, resume checks it).

        Returns
        -------
        str
            16 hex digits of the SHA-256 of the sorted settings as JSON.
        """
        text = json.dumps(self.to_dict(), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def decomposition_key(self) -> dict:
        """The settings the convex decomposition depends on (part of its cache key).

        Returns
        -------
        dict of str to float or int
            The ``coacd_*`` settings and ``seed``.
        """
        return {k: v for k, v in self.to_dict().items() if k.startswith("coacd_") or k == "seed"}


# DexGraspBench (its main branch, read from its code; /docs/physics.md): displacement from the
# pose before the squeeze, 2 s per direction, fail past 5 cm or 15°, μ 0.6 with torsional
# friction (condim 4), 2 no-slip iterations, 4 ms steps, contact solref 5 ms / solimp 0.5,
# load 10·m·g on a 0.1 kg object.
_DGB = {
    "protocol": "dgb",
    "timestep": 0.004,
    "contact_timeconst": 0.008,  # MuJoCo clamps a time constant below 2 steps to 2 steps
    "contact_solimp_low": 0.5,
    "friction": 0.6,
    "friction_margin_deg": 0.0,
    "condim": 4,
    "noslip_iterations": 2,
    "object_mass_kg": 0.1,
    "load_factor": 10.0,
    "hold_ramp": 0.05,
    "hold_time": 2.0,
    "max_shift_m": 0.05,
    "max_angle_rad": math.radians(15.0),
    "displacement_from": "placed",
}


TRIALS = ("beat", "cut", "pick")  # the task trials, in the order their columns come


@dataclass(frozen=True)
class TrialSettings:
    """The task trials' protocol (:mod:`~affordgrasp.physics.task_trials`): every number.

    Units are SI (s, m, rad, N, kg). Every value must be finite and positive. docs/physics.md
    says where each default comes from.

    Attributes
    ----------
    swing_speed_rad_s : float
        Beat: the wrist's angular speed at the strike (a hand-held hammer's range).
    strikes : int
        Beat: strikes per trial.
    windback_rad, ramp_rad : float
        Beat: each swing starts at rest this far before the first touch and reaches its
        speed over ``ramp_rad`` (raised-cosine speed profile), then coasts at it.
    strike_timestep, fine_s : float
        Beat: the simulation step of the strike, s, from ``fine_s`` before U would touch the
        nail to the end of the strike (the swing before runs at the physics settings' step).
    strike_time : float
        Beat: how long a strike is followed after its first contact, s.
    miss_rad : float
        Beat: a blow that has touched nothing by the time the swing would have turned this far
        past the nail's head missed.
    relax_s : float
        Beat: the wrist relaxes this long before U would touch the nail (or at any earlier
        contact with the rig): the strike is the hand's and the tool's momentum.
    nail_force_n, nail_mass_kg : float
        Beat: the nail's constant resisting force (dry friction of its slide) and its mass.
    nail_head_radius_m, nail_head_height_m, nail_shank_radius_m, nail_out_m : float
        Beat: the nail head, its shank, and how far the head's face stands out of the board.
    board_half_m, board_thickness_m, board_friction : float
        Beat: the board the nail is set in (a square), and μ of the board and the nail head.
    cut_force_n, cut_ramp_s : float
        Cut: the press force on the edge and the time it ramps up over.
    stroke_m, stroke_speed_m_s : float
        Cut: the stroke's length along the edge and its speed.
    stroke_window_s : float
        Cut: the stroke's contacts are pooled over windows this long (the engine's contact
        between a thin edge and a face flickers from one step to the next).
    cut_friction : float
        Cut: μ of the workpiece.
    crest_radius_m : float
        Cut: the edge line passes through the workpiece's first contact nearest the line
        through U along the edge when that is this close to it (the crest of the edge whose
        bevel U lies on; a cleaver's bevel is 7 mm wide), else through U.
    workpiece_margin_m, workpiece_across_m, workpiece_thickness_m : float
        Cut: the workpiece the edge is pressed onto: it reaches this far beyond the stroke at
        either end, this far on either side of the edge line, and is this thick.
    workpiece_mass_kg : float
        Cut: its mass (it is pushed onto the edge).
    cut_gap_m : float
        Cut: the workpiece starts this far from U.
    edge_radius_m, edge_directions : float, int
        Cut: the ball in which the edge's direction is measured, and its rays (a straight
        edge bears along its length: 2048 rays put its direction within 0.5° median, 1.6°
        at the 90th percentile, on the meat cleaver's edge, 256 within 1.0° / 2.5°).
    beat_max_offset_m : float
        Beat passes: every first contact within this distance of U, ...
    beat_min_advance_m : float
        ... the nail advanced at least this far per strike (the mean), ...
    cut_max_offset_m, cut_on_edge : float
        Cut passes: the workpiece's contacts within ``cut_max_offset_m`` of the edge line
        through U over at least the fraction ``cut_on_edge`` of the stroke, ...
    cut_max_thickness_m, cut_max_angle_rad : float
        ... where the workpiece bore, the tool no thicker than ``cut_max_thickness_m`` (its
        flanks converge: an edge, not a spine) and its wedge no wider than
        ``cut_max_angle_rad`` (not a spine's corner), the full press force reached, ...
    max_turn_rad, max_slip_m : float
        ... and (both trials) the tool turned less than ``max_turn_rad`` and U moved less
        than ``max_slip_m`` in the hand.
    """

    swing_speed_rad_s: float = 10.0
    strikes: int = 3
    windback_rad: float = 1.1
    ramp_rad: float = 1.0
    strike_timestep: float = 0.0005
    fine_s: float = 0.005
    strike_time: float = 0.02
    miss_rad: float = 0.3
    relax_s: float = 0.002
    nail_force_n: float = 150.0
    nail_mass_kg: float = 0.005
    nail_head_radius_m: float = 0.0035
    nail_head_height_m: float = 0.002
    nail_shank_radius_m: float = 0.0015
    nail_out_m: float = 0.025
    board_half_m: float = 0.025
    board_thickness_m: float = 0.02
    board_friction: float = 0.4
    cut_force_n: float = 20.0
    cut_ramp_s: float = 0.1
    stroke_m: float = 0.04
    stroke_speed_m_s: float = 0.1
    stroke_window_s: float = 0.01
    cut_friction: float = 0.4
    workpiece_margin_m: float = 0.01
    workpiece_across_m: float = 0.025
    workpiece_thickness_m: float = 0.01
    workpiece_mass_kg: float = 0.1
    cut_gap_m: float = 2e-4
    edge_radius_m: float = 0.003
    edge_directions: int = 2048
    crest_radius_m: float = 0.01
    beat_max_offset_m: float = 0.01
    beat_min_advance_m: float = 0.0005
    cut_max_offset_m: float = 0.002
    cut_max_thickness_m: float = 0.001
    cut_max_angle_rad: float = math.radians(55.0)
    cut_on_edge: float = 0.9
    max_turn_rad: float = math.radians(10.0)
    max_slip_m: float = 0.005

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            for v in value if isinstance(value, tuple) else (value,):
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise InputError(f"trial setting {f.name} must be a finite number, got {v!r}")
                if v <= 0:
                    raise InputError(f"trial setting {f.name} must be > 0, got {v!r}")
        if self.ramp_rad >= self.windback_rad:
            raise InputError(
                f"trial setting ramp_rad ({self.ramp_rad}) must be below windback_rad "
                f"({self.windback_rad}): the swing must reach its speed before the strike"
            )
        if self.cut_on_edge > 1:
            raise InputError(f"trial setting cut_on_edge is a fraction, got {self.cut_on_edge}")

    def to_dict(self) -> dict:
        """Every setting by name (tuples as lists).

        Returns
        -------
        dict
        """
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def protocol_settings(name: str = "affordgrasp", **overrides) -> PhysicsSettings:
    """The settings of a named protocol, with some values replaced.

    Parameters
    ----------
    name : {"affordgrasp", "dgb"}
        ``"affordgrasp"``: the defaults of :class:`PhysicsSettings`; ``"dgb"``: the
        DexGraspBench-compatible protocol (docs/physics.md lists every constant of both).
    **overrides
        Settings that replace the protocol's.

    Returns
    -------
    PhysicsSettings
    """
    if name not in PROTOCOLS:
        raise InputError(f"physics protocol {name!r} is unknown; choose one of {list(PROTOCOLS)}")
    values = dict(_DGB) if name == "dgb" else {}
    values.update(overrides)
    values["protocol"] = name
    return PhysicsSettings(**values)
