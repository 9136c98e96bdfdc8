"""The task trials on analytic cases: a block's blow drives the nail by its kinetic energy over
the nail's force, a hammer's face strikes where its handle does not, a blade's edge cuts where
its flat does not, and the same row gives the same numbers twice."""

from __future__ import annotations

import math

import numpy as np
import pytest
from physics_support import jaw_grasp

from affordgrasp.physics.scene import build_scene
from affordgrasp.physics.settings import TrialSettings
from affordgrasp.physics.task_scene import build_task_scene
from affordgrasp.physics.task_trials import run_task_trials

TOUCH = 0.0225 - 5e-5  # jaw travel that leaves a 0.05 mm gap to a 40 mm wide part
HEIGHT = 0.035  # the part's centre above the palm (physics_support.jaw_grasp)
WRIST = np.array([0.0, 0.0, -HEIGHT])  # the palm centre in the object frame


def tool(name, meshes):
    """An object made of closed convex meshes, and those meshes as its convex parts (no
    decomposition)."""
    import trimesh

    from affordgrasp.objects import GraspObject, mass_properties, mesh_hash

    mesh = trimesh.util.concatenate(meshes)
    obj = GraspObject(name, "mesh", mesh, mass_properties(mesh), mesh_hash(mesh), "test")
    return obj, [(np.asarray(m.vertices), np.asarray(m.faces)) for m in meshes]


@pytest.fixture(scope="module")
def hammer():
    """A T-shaped hammer: a 40 x 300 x 30 mm handle along y from -100 mm (the jaws close on
    its 40 mm along x at y = 0), and a head at its +y end standing 20 mm proud of the handle
    along +z, its striking face the head's top (z = 35 mm, normal +z)."""
    import trimesh

    move = trimesh.transformations.translation_matrix
    handle = trimesh.creation.box((0.04, 0.3, 0.03), move((0.0, 0.05, 0.0)))
    head = trimesh.creation.box((0.04, 0.03, 0.05), move((0.0, 0.215, 0.01)))
    return tool("hammer", [handle, head])


@pytest.fixture(scope="module")
def blade():
    """A knife-like blade: a 40 x 120 x 30 mm handle along y, and a 2 mm thin blade beyond
    it whose lower edge (z = -40 mm) is a 30° wedge."""
    import trimesh

    handle = trimesh.creation.box((0.04, 0.12, 0.03))
    # the blade: a prism along y, its cross-section a 2 mm plate ending in a 30° wedge
    t, depth = 0.001, 0.001 / math.tan(math.radians(15))
    section = [(-t, 0.0), (t, 0.0), (t, -0.04 + depth), (0.0, -0.04), (-t, -0.04 + depth)]
    ys = (0.06, 0.18)
    vertices = [(x, y, z + 0.015) for y in ys for x, z in section]
    n = len(section)
    faces = [
        (0, 1, 2),
        (0, 2, 3),
        (0, 3, 4),
        (n, n + 2, n + 1),
        (n, n + 3, n + 2),
        (n, n + 4, n + 3),
    ]
    for k in range(n):
        a, b = k, (k + 1) % n
        faces += [(a, b + n, b), (a, a + n, b + n)]
    prism = trimesh.Trimesh(vertices, faces, process=True)
    prism.fix_normals()
    return tool("blade", [handle, prism])


def scenes(obj, parts, trials=None, hand="parallel_jaw"):
    task_scene = build_task_scene(hand, obj, trials=trials, parts=parts)
    return build_scene(hand, obj, parts=parts), task_scene


def beat(obj_parts, use_point, use_normal, trials=None):
    obj, parts = obj_parts
    scene, ts = scenes(obj, parts, trials)
    pose, joints = jaw_grasp(TOUCH, TOUCH, HEIGHT)
    grasp, task = run_task_trials(
        scene, ts, pose, joints, ["beat"], np.array(use_point), np.array(use_normal), WRIST
    )
    assert grasp.hold_ok
    return task.beat


def test_a_blow_drives_the_nail_by_its_energy(hammer):
    # Let go of by the arm, the hand and the hammer move on freely; U's normal speed at the
    # touch is ω times its lever square to n, and the work of the nail's constant force F
    # over its advance is the kinetic energy the blow gives up at U, 1/2 m_eff v_n^2 of the
    # body that strikes.
    from affordgrasp.physics.task_scene import load_state
    from affordgrasp.physics.trials import _squeeze, set_grasp

    obj, parts = hammer
    force = 20.0  # N: low enough for the jaws to carry the tool through the blow
    trials = TrialSettings(nail_force_n=force, strikes=1)
    scene, ts = scenes(obj, parts, trials)
    pose, joints = jaw_grasp(TOUCH, TOUCH, HEIGHT)
    u, n = np.array([0.0, 0.215, 0.035]), np.array([0.0, 0.0, 1.0])
    _grasp, task = run_task_trials(scene, ts, pose, joints, ["beat"], u, n, WRIST)
    # the composite body at the touch: the squeezed grasp the trial started from
    set_grasp(scene, pose, joints)
    _squeeze(scene)
    load_state(ts, scene)
    m, d = ts.model, ts.data
    hand = [b for b in range(m.nbody) if _in_hand(m, b, ts.palm_body)]
    body = ts.scene.object_body
    u_world = d.xmat[body].reshape(3, 3) @ u + d.xpos[body]
    n_world = d.xmat[body].reshape(3, 3) @ n
    v_n = trials.swing_speed_rad_s * np.linalg.norm(np.cross(u_world, n_world))  # wrist at 0
    energy = {
        name: 0.5 * _effective_mass(m, d, bodies, u_world, n_world) * v_n**2
        for name, bodies in (("tool", [body]), ("hand and tool", [*hand, body]))
    }
    assert task.beat.strike_speed_m_s == pytest.approx(v_n, rel=1e-6)
    assert task.beat.strike_offset_m < 0.005
    # The blow gives up at most the energy of the hand and the tool as one body (a grip that
    # gives way, the soft contacts, the 5 g nail struck inelastically all lose some), and at
    # least the tool's own (the hand can only add to it).
    advance = task.beat.strike_nail_advance_m
    assert energy["tool"] / force < advance < energy["hand and tool"] / force
    assert energy["tool"] < 0.9 * energy["hand and tool"]  # the bracket is not trivial


def _effective_mass(m, d, bodies, point, normal) -> float:
    """m_eff of the rigid composite of ``bodies`` for a push along ``normal`` at ``point``:
    1/m_eff = 1/M + k' I_c^-1 k, k = (point - c) x normal."""
    mass, x = m.body_mass[bodies], d.xipos[bodies]
    c = mass @ x / mass.sum()
    inertia = np.zeros((3, 3))
    for b, mb, xb in zip(bodies, mass, x, strict=True):
        r, dx = d.ximat[b].reshape(3, 3), xb - c
        inertia += r @ np.diag(m.body_inertia[b]) @ r.T
        inertia += mb * (dx @ dx * np.eye(3) - np.outer(dx, dx))
    k = np.cross(point - c, normal)
    return 1.0 / (1.0 / mass.sum() + k @ np.linalg.solve(inertia, k))


def _in_hand(m, body: int, palm: int) -> bool:
    while body > 0:
        if body == palm:
            return True
        body = m.body_parentid[body]
    return False


def test_the_face_drives_the_nail_and_the_handle_by_the_hand_does_not(hammer):
    # a blow the jaws' 20 N grip can carry three times: a light nail, a slower swing
    trials = TrialSettings(nail_force_n=20.0, swing_speed_rad_s=4.0)
    face = beat(hammer, (0.0, 0.215, 0.035), (0.0, 0.0, 1.0), trials)
    assert face.beat_ok
    assert face.strike_offset_m < 0.006  # the nail's head is 3.5 mm in radius
    # the handle's top next to the jaws: slow (the lever is short) and the jaws meet the rig
    near = beat(hammer, (0.0, 0.025, 0.015), (0.0, 0.0, 1.0), trials)
    assert not near.beat_ok
    assert near.strike_speed_m_s < 0.3 * face.strike_speed_m_s
    assert near.strike_nail_advance_m < 0.5 * face.strike_nail_advance_m or (
        near.strike_offset_m > trials.beat_max_offset_m
    )


def test_a_use_point_on_the_line_through_the_wrist_cannot_be_struck(hammer):
    # U straight above the palm centre, n along that line: no wrist turn moves U along n
    out = beat(hammer, (0.0, 0.0, 0.015), (0.0, 0.0, 1.0))
    assert not out.beat_ok and out.strike_speed_m_s == 0.0 and math.isinf(out.strike_offset_m)


def cut(blade_parts, use_point, use_normal):
    from affordgrasp.metrics.wedge import use_edge_frame

    obj, parts = blade_parts
    # a press the jaws' 20 N grip can carry 90 mm out along the blade
    scene, ts = scenes(obj, parts, TrialSettings(cut_force_n=2.0))
    pose, joints = jaw_grasp(TOUCH, TOUCH, HEIGHT)
    outward, along = use_edge_frame(obj.mesh, use_point, use_normal, directions=2048)
    edge = (outward[0], along[0])
    u, n = np.array(use_point), np.array(use_normal)
    grasp, task = run_task_trials(scene, ts, pose, joints, ["cut"], u, n, WRIST, edge)
    assert grasp.hold_ok
    return task.cut


def test_the_edge_cuts_and_the_flat_does_not(blade):
    # on the edge's +x flank 0.5 mm above its crest (z = -25 mm), with the flank's normal
    # (what a sampled use point on a mesh edge gets)
    half = math.radians(15.0)
    flank = (0.0005 * math.tan(half), 0.09, -0.025 + 0.0005)
    edge = cut(blade, flank, (math.cos(half), 0.0, -math.sin(half)))
    assert edge.cut_ok, edge
    assert edge.stroke_offset_m < 0.002 and edge.stroke_edge_thickness_m < 0.0005
    assert math.degrees(edge.stroke_edge_angle_rad) == pytest.approx(30.0, abs=6.0)
    flat = cut(blade, (0.001, 0.09, -0.01), (1.0, 0.0, 0.0))
    assert not flat.cut_ok
    assert flat.stroke_offset_m > 0.005


def test_rows_without_a_use_point_get_no_task_outcome(hammer):
    obj, parts = hammer
    scene, ts = scenes(obj, parts)
    pose, joints = jaw_grasp(TOUCH, TOUCH, HEIGHT)
    grasp, task = run_task_trials(scene, ts, pose, joints, ["beat", "cut"], None, None, WRIST)
    assert task.beat is None and task.cut is None
    nan = np.full(3, np.nan)
    _, task = run_task_trials(scene, ts, pose, joints, ["beat"], nan, nan, WRIST)
    assert task.beat is None
    from affordgrasp.physics.task_trials import task_row

    row = task_row(task, ("beat", "cut", "pick"), grasp.hold_ok)
    assert row["beat_ok"] is None and row["cut_ok"] is None and row["pick_ok"] is True


def test_the_same_row_gives_the_same_numbers(hammer):
    obj, parts = hammer
    rows = []
    for _ in range(2):
        scene, ts = scenes(obj, parts)
        pose, joints = jaw_grasp(TOUCH, TOUCH * 0.999, HEIGHT)
        u, n = np.array([0.0, 0.215, 0.035]), np.array([0.0, 0.0, 1.0])
        grasp, task = run_task_trials(scene, ts, pose, joints, ["beat"], u, n, WRIST)
        rows.append((grasp.to_row(), task))
    assert rows[0] == rows[1]


def test_the_hold_outcomes_do_not_depend_on_the_task_trials(hammer):
    from affordgrasp.physics.trials import validate_grasp

    obj, parts = hammer
    scene, ts = scenes(obj, parts)
    pose, joints = jaw_grasp(TOUCH, TOUCH, HEIGHT)
    u, n = np.array([0.0, 0.215, 0.035]), np.array([0.0, 0.0, 1.0])
    alone = validate_grasp(scene, pose, joints, u, n).to_row()
    with_trials, _ = run_task_trials(scene, ts, pose, joints, ["beat"], u, n, WRIST)
    assert with_trials.to_row() == alone


def test_the_nail_holds_below_its_force_and_yields_above(hammer):
    import mujoco

    obj, parts = hammer
    _scene, ts = scenes(obj, parts)
    m, d = ts.model, ts.data
    m.opt.timestep = ts.trials.strike_timestep
    moved = {}
    for push in (0.7, 1.3):  # × the nail's force, along its slide
        mujoco.mj_resetData(m, d)
        for _ in range(100):  # 50 ms
            d.qfrc_applied[ts.nail_dof] = push * ts.trials.nail_force_n
            mujoco.mj_step(m, d)
        moved[push] = d.qpos[ts.nail_qpos]
    # a creep of 2 mm/s, a few hundredths of a millimetre over a blow (MuJoCo's default
    # impedance: 2 m/s)
    assert abs(moved[0.7]) < 2e-4
    # above it, the net 0.3 F accelerates the 5 g nail
    expected = 0.5 * 0.3 * ts.trials.nail_force_n / ts.trials.nail_mass_kg * 0.05**2
    assert moved[1.3] == pytest.approx(expected, rel=0.05)
